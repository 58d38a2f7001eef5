//! The world: particles, constraints and effects, and the step that advances them.
//!
//! One step of length `dt` runs `substeps` substeps of `h = dt / substeps`; each substep:
//! wind forces (if named) → predict (gravity, drag, forces) → `iterations` sweeps of the
//! coloured distance constraints and the tethers → update velocities and positions (with
//! fabric damping if any). See the crate README's Architecture section for the file of each
//! stage and its scalar twin.

mod access;
pub mod checkpoint;
pub(crate) mod contacts;
pub(crate) mod describe;
pub(crate) mod forces;
pub mod metrics;
pub(crate) mod obstacles;
pub(crate) mod self_collision;
pub mod stage_clock;
pub mod step;
pub mod strands;
pub mod threads;

use std::sync::Arc;

use crate::constraints::distance::DistanceInput;
use crate::constraints::grid::{GridSpec, GRID_MIN};
use crate::constraints::{DistanceSet, TetherSet};
use crate::data::particles::Particles;
use crate::error::{Result, WeftError};
use crate::integrate::wind::WindState;
use crate::model::cloth::{ClothDesc, ConstraintKind};
use crate::model::effects::Effects;
use crate::model::layout::ClothInfo;
use crate::model::params::SolverParams;

/// A simulated world.
pub struct World {
    pub(crate) particles: Particles,
    pub(crate) distance: DistanceSet,
    pub(crate) distance_inputs: Vec<DistanceInput>,
    pub(crate) stretch: Vec<(u32, u32, f32)>,
    pub(crate) tethers: TetherSet,
    pub(crate) tether_inputs: Vec<crate::model::cloth::Tether>,
    pub(crate) triangles: Vec<[u32; 3]>,
    pub(crate) cloths: Vec<ClothInfo>,
    /// For each cloth, the range of `distance_inputs` that holds its constraints.
    pub(crate) cloth_inputs: Vec<std::ops::Range<usize>>,
    pub(crate) damping_rate: Vec<f32>,
    pub(crate) has_damping: bool,
    /// Whether a substep's update pass also runs the next substep's predict, chunk by chunk
    /// (`src/world/step/`; off only in tests that hold the fused path to the separate passes).
    pub(crate) fuse_predict: bool,
    pub(crate) damp_factor: Vec<f32>,
    pub(crate) damp_h: f32,
    pub(crate) params: SolverParams,
    pub(crate) effects: Effects,
    pub(crate) wind: Option<WindState>,
    pub(crate) pool: Option<Arc<rayon::ThreadPool>>,
    pub(crate) backup: [Vec<f32>; 6],
    pub(crate) time: f64,
    pub(crate) steps: u64,
    pub(crate) last_h: f32,
    pub(crate) obstacles: crate::obstacles::ObstacleSet,
    pub(crate) embed: crate::embed::EmbedState,
    pub(crate) strands: Vec<crate::model::layout::StrandInfo>,
    pub(crate) scalps: crate::strands::scalp::ScalpSet,
    pub(crate) strand_area: Vec<f32>,
    pub(crate) selfcol: crate::self_collision::SelfCollisionData,
    /// Scratch of the force-based integrators (force arrays, implicit factorisation).
    pub(crate) ms: crate::integrate::mass_spring::MassSpringState,
    /// Per-stage wall time of the step, when on.
    pub(crate) clock: crate::world::stage_clock::StageClock,
    /// The measured thread choice of `threads = 0` ([`threads`]).
    pub(crate) thread_choice: threads::ThreadChoice,
}

impl World {
    /// An empty world.
    pub fn new(params: SolverParams, effects: Effects) -> Result<World> {
        params.validate()?;
        effects.validate()?;
        let pool = make_pool(params.threads)?;
        Ok(World {
            particles: Particles::new(),
            distance: DistanceSet::default(),
            distance_inputs: Vec::new(),
            stretch: Vec::new(),
            tethers: TetherSet::default(),
            tether_inputs: Vec::new(),
            triangles: Vec::new(),
            cloths: Vec::new(),
            cloth_inputs: Vec::new(),
            damping_rate: Vec::new(),
            has_damping: false,
            fuse_predict: true,
            damp_factor: Vec::new(),
            damp_h: f32::NAN,
            params,
            effects,
            wind: None,
            pool,
            backup: Default::default(),
            time: 0.0,
            steps: 0,
            last_h: 0.0,
            obstacles: Default::default(),
            embed: Default::default(),
            strands: Vec::new(),
            scalps: Default::default(),
            strand_area: Vec::new(),
            selfcol: Default::default(),
            ms: Default::default(),
            clock: Default::default(),
            thread_choice: Default::default(),
        })
    }

    /// Builds a cloth and adds it; returns its index in [`cloths`](Self::cloths).
    ///
    /// Refuses a cloth whose world would exceed the memory limit (`budget`) before building it.
    pub fn add_cloth(&mut self, desc: &ClothDesc) -> Result<usize> {
        self.memory_counts().plus(&desc.memory_counts()).check()?;
        let b = desc.build()?;
        self.check_room_for(b.positions.len())?;
        let first = self.particles.extend(&b.positions, &b.inv_mass);
        let first_triangle = self.triangles.len() as u32;
        let inputs = self.distance_inputs.len();
        self.push_edges(first, &b.edges);
        self.cloth_inputs.push(inputs..self.distance_inputs.len());
        for t in &b.tethers {
            self.tether_inputs.push(crate::model::cloth::Tether {
                particle: first + t.particle,
                anchor: first + t.anchor,
                max_len: t.max_len,
            });
        }
        self.triangles
            .extend(b.triangles.iter().map(|t| [first + t[0], first + t[1], first + t[2]]));
        self.damping_rate.resize(self.particles.count(), desc.fabric.damping);
        self.has_damping |= desc.fabric.damping > 0.0;
        let cloth_index = self.cloths.len() as u32;
        self.selfcol
            .add_cloth(&b.positions, cloth_index, desc.spacing, desc.fabric.thickness);
        self.cloths.push(ClothInfo {
            first,
            rows: desc.rows,
            cols: desc.cols,
            first_triangle,
            triangle_count: b.triangles.len() as u32,
            thickness: desc.fabric.thickness,
        });
        self.rebuild_topology();
        Ok(self.cloths.len() - 1)
    }

    /// The counts the memory estimate (`budget::MemoryCounts::bytes`) is computed from.
    pub fn memory_counts(&self) -> crate::model::budget::MemoryCounts {
        crate::model::budget::MemoryCounts {
            particles: self.particles.count() as u64,
            constraints: self.distance_inputs.len() as u64,
            tethers: self.tether_inputs.len() as u64,
            triangles: self.triangles.len() as u64,
            obstacles: self.obstacles.list().len() as u64,
            wind: self.effects.wind.is_some(),
            self_collision: self.selfcol.config.is_some(),
            force_method: self.params.method != crate::model::params::Method::Xpbd,
            implicit: self.params.method == crate::model::params::Method::ImplicitEuler,
        }
    }

    /// Refuses a piece that would overflow the `u32` particle indices (before anything changes).
    pub(crate) fn check_room_for(&self, more: usize) -> Result<()> {
        let total = self.particles.count() as u64 + more as u64 + 16;
        if total >= u32::MAX as u64 {
            return Err(WeftError::param("particles", total, "too many particles for u32 indices"));
        }
        Ok(())
    }

    /// Adds a piece's distance constraints (local indices offset by `first`); stretch ones also
    /// feed the strain metric.
    pub(crate) fn push_edges(&mut self, first: u32, edges: &[crate::model::cloth::Edge]) {
        for e in edges {
            let (a, bb) = (first + e.a, first + e.b);
            self.distance_inputs.push(DistanceInput {
                a,
                b: bb,
                rest: e.rest,
                compliance: e.compliance,
            });
            if e.kind == ConstraintKind::Stretch {
                self.stretch.push((a, bb, e.rest));
            }
        }
    }

    /// Re-lays out constraints and scratch after the particle count changed.
    pub(crate) fn rebuild_topology(&mut self) {
        let sink = self.particles.sink();
        let len = self.particles.padded_len();
        let grids: Vec<_> = (self.cloths.iter().zip(&self.cloth_inputs))
            .filter(|(c, _)| c.rows as u64 * c.cols as u64 >= GRID_MIN as u64)
            .map(|(c, r)| {
                let spec = GridSpec {
                    first: c.first,
                    rows: c.rows,
                    cols: c.cols,
                };
                (spec, r.clone())
            })
            .collect();
        self.distance = DistanceSet::with_grids(&self.distance_inputs, len, sink, &grids);
        self.tethers = TetherSet::new(&self.tether_inputs, sink);
        self.wind = self.new_wind_state();
        self.damp_h = f32::NAN;
        self.obstacles.invalidate();
        self.ms = Default::default();
        for b in &mut self.backup {
            b.resize(len, 0.0);
        }
        self.embed_topology_changed();
    }

    /// Wind scratch when wind is named: triangle adjacency plus the strand drag areas.
    fn new_wind_state(&self) -> Option<WindState> {
        let len = self.particles.padded_len();
        self.effects.wind.as_ref().map(|_| {
            let mut w = WindState::new(&self.triangles, len);
            if !self.strand_area.is_empty() {
                w.strand_area = self.strand_area.clone();
                w.strand_area.resize(len, 0.0);
            }
            w
        })
    }
}

#[cfg(test)]
impl World {
    /// Bit patterns of every position and velocity: what the unit tests compare when two runs
    /// must agree bit for bit (`tests/common::state_bits` is the integration tests' twin).
    pub(crate) fn state_bits(&self) -> Vec<u32> {
        let (p, v) = (self.positions(), self.velocities());
        p.iter().chain(v.iter()).flat_map(|a| a.iter().map(|f| f.to_bits())).collect()
    }
}

/// The world's own pool for `threads` workers: none for 0 (the global pool) and for 1 (the
/// caller's thread, see [`threads`]).
pub(super) fn make_pool(threads: usize) -> Result<Option<Arc<rayon::ThreadPool>>> {
    if threads <= 1 {
        return Ok(None);
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map(|p| Some(Arc::new(p)))
        .map_err(|e| WeftError::param("solver.threads", threads, format!("cannot start the thread pool: {e}")))
}
