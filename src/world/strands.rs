//! Adding strands to a world: particles, constraints in the shared colouring, scalp collision
//! and the wind's strand drag.
//!
//! [`World::add_strands`] appends a [`StrandsDesc`]'s particles after those already present,
//! puts its stretch and bending constraints into the world's one
//! [`DistanceSet`](crate::constraints::DistanceSet) (so strands and cloth are coloured and solved
//! together), registers the particle range with the scalp stage, and records a [`StrandInfo`]
//! for rendering.

use crate::error::{Result, WeftError};
use crate::model::layout::StrandInfo;
use crate::strands::hair::StrandsDesc;
use crate::world::World;

impl World {
    /// Grows a group of strands (AHS) and adds it; returns its index in
    /// [`strands`](Self::strands).
    pub fn add_strands(&mut self, desc: &StrandsDesc) -> Result<usize> {
        self.memory_counts().plus(&desc.memory_counts()).check()?;
        let b = desc.build()?;
        self.check_room_for(b.positions.len())?;
        let first = self.particles.extend(&b.positions, &b.inv_mass);
        // Strand groups count down from the top of the group ids, clear of the cloths'.
        self.selfcol.add_group(&b.positions, u32::MAX - self.strands.len() as u32);
        self.push_edges(first, &b.edges);
        let n = self.particles.count();
        self.damping_rate.resize(n, desc.damping);
        self.has_damping |= desc.damping > 0.0;
        let area = desc.thickness * desc.segment_length;
        self.strand_area.resize(first as usize, 0.0);
        self.strand_area
            .extend(b.inv_mass.iter().map(|&w| if w > 0.0 { area } else { 0.0 }));
        self.scalps.push(first as usize, n, &desc.scalp, 0.5 * desc.thickness);
        self.strands.push(StrandInfo {
            first,
            count: desc.count,
            points: desc.points,
            scalp: desc.scalp,
            thickness: desc.thickness,
        });
        self.rebuild_topology();
        Ok(self.strands.len() - 1)
    }

    /// Moves strand group `group`'s scalp so its centre is at `center`: the roots (kinematic,
    /// `w = 0`) are translated with it, so the strands follow through their constraints, and
    /// the scalp stage collides against the moved shape from the next step on. Checkpoints
    /// do not record a moved scalp (they rebuild the world from its scene).
    pub fn set_scalp_center(&mut self, group: usize, center: [f32; 3]) -> Result<()> {
        let len = self.strands.len();
        let info = self.strands.get_mut(group).ok_or(WeftError::IndexOutOfRange {
            name: "strand group",
            index: group,
            len,
        })?;
        crate::error::finite3("scalp center", center)?;
        let d = [0, 1, 2].map(|k| center[k] - info.scalp.center[k]);
        if !d.iter().all(|c| c.is_finite()) {
            return Err(WeftError::param("scalp center", format!("{center:?}"), "the move is too large"));
        }
        info.scalp.center = center;
        let p = &mut self.particles;
        for s in 0..info.count {
            let r = info.strand_range(s).start;
            if p.w[r] == 0.0 {
                p.x[r] += d[0];
                p.y[r] += d[1];
                p.z[r] += d[2];
                (p.px[r], p.py[r], p.pz[r]) = (p.x[r], p.y[r], p.z[r]);
            }
        }
        // Strand groups and their scalp ranges are pushed together, so indices agree.
        self.scalps.ranges[group].center = center;
        Ok(())
    }

    /// The strand groups added so far.
    pub fn strands(&self) -> &[StrandInfo] {
        &self.strands
    }

    /// Number of strand particles kept outside a scalp by the scalp stage.
    pub fn scalp_particle_count(&self) -> usize {
        self.scalps.ranges.iter().map(|r| r.end - r.start).sum()
    }
}
