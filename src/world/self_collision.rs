//! The world's self-collision API: settings, the collision distance, the pair lists and the
//! statistics. The stages themselves are `crate::self_collision`.

use crate::data::exec::Exec;
use crate::error::Result;
use crate::self_collision::Active;
use crate::self_collision::{SelfCollision, SelfCollisionStats};
use crate::world::World;

impl World {
    /// A step's self-collision start: each particle's travel from the velocities for a step
    /// of `dt`, then the pair lists from the positions. The settings the substeps need, or
    /// `None` when off or when the lists failed (the step then runs without; the statistics
    /// count it).
    pub(crate) fn begin_self_collision(&mut self, dt: f32, exec: Exec) -> Option<Active> {
        let n = self.particles.count();
        let p = &self.particles;
        self.selfcol.adapt_travel([&p.vx, &p.vy, &p.vz], &p.w, n, dt, exec);
        let on = self.selfcol.begin_step([&p.x, &p.y, &p.z], n, &self.damping_rate, exec);
        on.unwrap_or(false).then(|| self.selfcol.active()).flatten()
    }

    /// Turns self-collision on (`Some`) or off (`None`). Off costs nothing in the step.
    pub fn set_self_collision(&mut self, config: Option<SelfCollision>) -> Result<()> {
        if let Some(c) = &config {
            crate::self_collision::validate(c)?;
        }
        self.selfcol.config = config;
        Ok(())
    }

    /// The self-collision settings, if on.
    pub fn self_collision(&self) -> Option<&SelfCollision> {
        self.selfcol.config.as_ref()
    }

    /// The collision distance in use (configured or `min(thickness, spacing)`), m.
    pub fn self_collision_distance(&self) -> f32 {
        self.selfcol.distance()
    }

    /// The pair lists of the last step: pairs within `d + (t_i + t_j) d` at the step's start
    /// (`t_i` the particles' travels, [`World::self_collision_travels`]), the cloths' rest neighbours left out, each pair once in the list of its smaller id (see
    /// [`crate::self_collision`]), if self-collision has run.
    pub fn self_collision_pairs(&self) -> Option<&crate::self_collision::neighbours::Neighbours> {
        self.selfcol.lists()
    }

    /// The largest travel over the collision distance of the last step with self-collision:
    /// what its fastest particle called for, at most
    /// [`crate::self_collision::SelfCollision::travel`] (see [`crate::self_collision`]);
    /// `None` before the first.
    pub fn self_collision_travel(&self) -> Option<f32> {
        self.selfcol.step_travel()
    }

    /// Each particle's travel over the collision distance in the last step with
    /// self-collision (the pair `(i, j)` was listed within `d + (t_i + t_j) d`); empty before
    /// the first.
    pub fn self_collision_travels(&self) -> &[f32] {
        self.selfcol.step_travels(self.particles.count())
    }

    /// Number of pairs in the last step's pair list (the pairs the substeps test).
    pub fn self_collision_pair_count(&self) -> usize {
        self.selfcol.pair_count()
    }

    /// Average-collision statistics and self-collision time so far.
    pub fn self_collision_stats(&self) -> &SelfCollisionStats {
        &self.selfcol.stats
    }

    /// Measures the current state's penetration percentage and records it in the statistics
    /// (once per step count; the step measures the state it starts from, so calling this after
    /// the last step completes the average). Returns the percentage; 0 when off.
    pub fn measure_self_collision(&mut self) -> Result<f64> {
        let n = self.particles.count();
        let steps = self.steps;
        let p = &self.particles;
        let x = [&p.x[..], &p.y[..], &p.z[..]];
        let parallel = self.params.backend == crate::model::params::Backend::Simd;
        self.selfcol.measure(x, n, steps, parallel)
    }
}
