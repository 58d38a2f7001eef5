//! Reading and setting a world's state: its parameters and effects (validated), counts, the
//! particle arrays, positions, velocities and inverse masses from caller buffers (checked).

use crate::constraints::DistanceSet;
use crate::data::particles::Particles;
use crate::error::{Result, WeftError};
use crate::model::effects::Effects;
use crate::model::layout::ClothInfo;
use crate::model::params::SolverParams;
use crate::world::{make_pool, World};

impl World {
    /// The solver parameters.
    pub fn params(&self) -> &SolverParams {
        &self.params
    }

    /// Replaces the solver parameters (takes effect at the next step).
    pub fn set_params(&mut self, params: SolverParams) -> Result<()> {
        params.validate()?;
        if params.threads != self.params.threads {
            self.pool = make_pool(params.threads)?;
            self.thread_choice = Default::default();
        }
        self.params = params;
        Ok(())
    }

    /// The effects.
    pub fn effects(&self) -> &Effects {
        &self.effects
    }

    /// Replaces the effects (takes effect at the next step).
    pub fn set_effects(&mut self, effects: Effects) -> Result<()> {
        effects.validate()?;
        self.effects = effects;
        self.wind = self.new_wind_state();
        Ok(())
    }

    /// Number of real particles.
    pub fn particle_count(&self) -> usize {
        self.particles.count()
    }

    /// Number of distance constraints.
    pub fn constraint_count(&self) -> usize {
        self.distance.len()
    }

    /// Number of tethers.
    pub fn tether_count(&self) -> usize {
        self.tethers.len()
    }

    /// The coloured distance constraints.
    pub fn distance_set(&self) -> &DistanceSet {
        &self.distance
    }

    /// Number of constraint colours.
    pub fn colour_count(&self) -> usize {
        self.distance.colours.len()
    }

    /// The particle arrays (padded; only the first [`particle_count`](Self::particle_count)
    /// entries are real).
    pub fn particles(&self) -> &Particles {
        &self.particles
    }

    /// Positions as three slices of length `particle_count`.
    pub fn positions(&self) -> [&[f32]; 3] {
        let n = self.particles.count();
        [&self.particles.x[..n], &self.particles.y[..n], &self.particles.z[..n]]
    }

    /// Velocities as three slices of length `particle_count`.
    pub fn velocities(&self) -> [&[f32]; 3] {
        let n = self.particles.count();
        [&self.particles.vx[..n], &self.particles.vy[..n], &self.particles.vz[..n]]
    }

    /// Position of one particle as a `mint` point.
    pub fn position(&self, i: usize) -> Result<mint::Point3<f32>> {
        if i >= self.particles.count() {
            return Err(WeftError::IndexOutOfRange {
                name: "particle",
                index: i,
                len: self.particles.count(),
            });
        }
        Ok(self.particles.position(i).into())
    }

    /// Writes interleaved positions into `out` (resized to `particle_count`).
    pub fn positions_interleaved(&self, out: &mut Vec<[f32; 3]>) {
        let n = self.particles.count();
        out.clear();
        out.extend((0..n).map(|i| self.particles.position(i)));
    }

    /// Render/collision triangles (global particle indices).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The cloths added so far.
    pub fn cloths(&self) -> &[ClothInfo] {
        &self.cloths
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Sets the inverse mass of every real particle (0 pins a particle). Tethers keep the
    /// anchors they were built with.
    pub fn set_inverse_masses(&mut self, w: &[f32]) -> Result<()> {
        let n = self.particles.count();
        if w.len() != n {
            return Err(WeftError::BufferLength {
                name: "inverse masses",
                got: w.len(),
                expected: n,
            });
        }
        if let Some(bad) = w.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(WeftError::param("inverse mass", bad, "must be finite and zero or greater"));
        }
        self.particles.w[..n].copy_from_slice(w);
        self.damp_h = f32::NAN;
        Ok(())
    }

    /// Sets the position of every real particle (predictions follow).
    pub fn set_positions(&mut self, x: [&[f32]; 3]) -> Result<()> {
        check_vec3_buffers(["x", "y", "z"], x, self.particles.count(), "positions must be finite")?;
        let n = self.particles.count();
        let p = &mut self.particles;
        p.x[..n].copy_from_slice(x[0]);
        p.y[..n].copy_from_slice(x[1]);
        p.z[..n].copy_from_slice(x[2]);
        p.px.copy_from_slice(&p.x);
        p.py.copy_from_slice(&p.y);
        p.pz.copy_from_slice(&p.z);
        Ok(())
    }

    /// Sets the velocity of every real particle (e.g. initial conditions in tests).
    pub fn set_velocities(&mut self, v: [&[f32]; 3]) -> Result<()> {
        check_vec3_buffers(["vx", "vy", "vz"], v, self.particles.count(), "velocities must be finite")?;
        let n = self.particles.count();
        self.particles.vx[..n].copy_from_slice(v[0]);
        self.particles.vy[..n].copy_from_slice(v[1]);
        self.particles.vz[..n].copy_from_slice(v[2]);
        Ok(())
    }
}

/// Checks three caller buffers: length `n` each, every value finite.
fn check_vec3_buffers(names: [&'static str; 3], b: [&[f32]; 3], n: usize, reason: &str) -> Result<()> {
    for (name, s) in names.into_iter().zip(b) {
        if s.len() != n {
            return Err(WeftError::BufferLength {
                name,
                got: s.len(),
                expected: n,
            });
        }
        if let Some(bad) = s.iter().find(|f| !f.is_finite()) {
            return Err(WeftError::param(name, bad, reason));
        }
    }
    Ok(())
}
