//! The world's obstacle API: adding obstacles, friction, contact counts, timing and the
//! penetration measure. The obstacle stages themselves are `crate::obstacles`.

use crate::error::Result;
use crate::model::shapes::Shape;
use crate::obstacles::penetration::mesh_signed_distance;
use crate::obstacles::{Geometry, Obstacle};
use crate::world::World;

impl World {
    /// Adds an obstacle; returns its index in [`obstacles`](Self::obstacles).
    pub fn add_obstacle(&mut self, obstacle: Obstacle) -> Result<usize> {
        self.obstacles.add(obstacle)
    }

    /// The obstacles, in the order they were added.
    pub fn obstacles(&self) -> &[Obstacle] {
        self.obstacles.list()
    }

    /// Sets the Coulomb friction coefficient of obstacles that have none of their own
    /// (default 0).
    pub fn set_friction(&mut self, mu: f32) -> Result<()> {
        self.obstacles.set_friction(mu)
    }

    /// Wall time spent in the obstacle stages of all steps so far (contacts, responses,
    /// projections, velocity passes).
    pub fn obstacle_time(&self) -> std::time::Duration {
        self.obstacles.busy()
    }

    /// The default obstacle friction coefficient.
    pub fn friction(&self) -> f32 {
        self.obstacles.friction()
    }

    /// How many particles hold a contact with at least one obstacle after the last substep
    /// (0 before the first step).
    pub fn obstacle_contacts(&self) -> usize {
        self.obstacles.contact_count(self.particles.count())
    }
}

impl World {
    /// The deepest any particle sits inside any obstacle, m (0 when none does); pinned
    /// particles included.
    pub fn max_penetration(&self) -> f32 {
        let [x, y, z] = self.positions();
        let mut worst = 0.0f32;
        let mut scratch = Vec::new();
        for o in self.obstacles() {
            let shape: Option<Shape> = o.shape_at(self.time());
            for i in 0..x.len() {
                let q = [x[i], y[i], z[i]];
                let d = match (&shape, o.geometry()) {
                    (Some(s), _) => Some(s.signed_distance(q)),
                    (None, Geometry::Mesh(m)) => mesh_signed_distance(m.mesh(), m.broadphase(), q, &mut scratch),
                    _ => None,
                };
                worst = worst.max(-d.unwrap_or(0.0));
            }
        }
        worst
    }
}
