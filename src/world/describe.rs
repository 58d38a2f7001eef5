//! `World::describe`: the world as plain data ([`WorldDescription`]).

use crate::model::description::{DistanceDesc, ObstacleDesc, WorldDescription};
use crate::obstacles::Geometry;
use crate::world::World;

impl World {
    /// The world's state, topology and settings as plain data (constraints in the solver's
    /// colour order). The f64 reference step is built from this.
    pub fn describe(&self) -> WorldDescription {
        let p = &self.particles;
        let n = p.count();
        let colours = self
            .distance
            .colours
            .iter()
            .map(|c| {
                (0..c.real)
                    .map(|k| DistanceDesc {
                        a: c.a[k],
                        b: c.b[k],
                        rest: c.rest[k],
                        compliance: c.compliance[k],
                    })
                    .collect()
            })
            .collect();
        let obstacles = self
            .obstacles()
            .iter()
            .map(|o| ObstacleDesc {
                shape: match o.geometry() {
                    Geometry::Shape(s) => Some(*s),
                    Geometry::Mesh(_) => None,
                },
                velocity: o.velocity(),
                friction: o.friction(),
            })
            .collect();
        WorldDescription {
            positions: (0..n).map(|i| p.position(i)).collect(),
            velocities: (0..n).map(|i| p.velocity(i)).collect(),
            inv_mass: p.w[..n].to_vec(),
            damping: self.damping_rate.clone(),
            colours,
            tethers: self.tether_inputs.clone(),
            triangles: self.triangles.clone(),
            strand_area: self.strand_area.clone(),
            scalps: self.scalps.ranges.clone(),
            cloths: self.cloths.clone(),
            strands: self.strands.clone(),
            effects: self.effects.clone(),
            obstacles,
            friction: self.friction(),
            self_collision: self.self_collision().cloned(),
            self_collision_distance: self.self_collision_distance(),
            substeps: self.params.substeps,
            iterations: self.params.iterations,
            method: self.params.method,
            time: self.time,
        }
    }
}
