//! Particle storage in structure-of-arrays form.
//!
//! Every attribute is its own `Vec<f32>`: positions `x, y, z`, predicted positions
//! `px, py, pz`, velocities `vx, vy, vz` and inverse masses `w` (0 = pinned or kinematic).
//! The length is padded to a multiple of [`LANES`](crate::data::lanes::LANES) with inert particles
//! (`w = 0`, at the origin, at rest), and there is always at least one such padding slot: the
//! last one, [`Particles::sink`], is where padded (dummy) constraints point so that SIMD loops
//! never need a tail.
//!
//! Element-wise kernels run over chunks of about [`CHUNK`] particles, as many for each of two threads ([`Particles::for_chunks`]). The
//! step's divergence guard rides on two such passes instead of passes of its own
//! ([`Particles::for_chunks_saving`] copies the state at the start of the step chunk by chunk
//! inside the first predict, [`chunk_finite_simd`] checks the end state chunk by chunk inside
//! the last update, while the chunk is still in cache).

mod chunks;
mod raw;

pub use chunks::*;
pub use raw::*;

use crate::data::lanes::round_up;

/// Particle arrays (SoA), padded to the lane width.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Particles {
    count: usize,
    /// Positions.
    pub x: Vec<f32>,
    /// Positions.
    pub y: Vec<f32>,
    /// Positions.
    pub z: Vec<f32>,
    /// Predicted positions (scratch of the solver; equal to `x` between steps).
    pub px: Vec<f32>,
    /// Predicted positions.
    pub py: Vec<f32>,
    /// Predicted positions.
    pub pz: Vec<f32>,
    /// Velocities.
    pub vx: Vec<f32>,
    /// Velocities.
    pub vy: Vec<f32>,
    /// Velocities.
    pub vz: Vec<f32>,
    /// Inverse masses (1/kg); 0 means the particle is pinned (infinite mass).
    pub w: Vec<f32>,
}

impl Particles {
    /// An empty set with the single padding block.
    pub fn new() -> Self {
        let mut p = Self::default();
        p.repad();
        p
    }

    /// Number of real (non-padding) particles.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Padded length of every array (a multiple of the lane width, > `count`).
    pub fn padded_len(&self) -> usize {
        self.x.len()
    }

    /// Index of the inert padding particle that dummy constraints point at.
    pub fn sink(&self) -> u32 {
        (self.padded_len() - 1) as u32
    }

    /// Appends a particle and returns its index.
    pub fn push(&mut self, pos: [f32; 3], vel: [f32; 3], inv_mass: f32) -> u32 {
        self.truncate_padding();
        let i = self.count;
        self.x.push(pos[0]);
        self.y.push(pos[1]);
        self.z.push(pos[2]);
        self.vx.push(vel[0]);
        self.vy.push(vel[1]);
        self.vz.push(vel[2]);
        self.w.push(inv_mass);
        self.count += 1;
        self.repad();
        i as u32
    }

    /// Appends many particles at once (faster than repeated [`push`](Self::push)).
    pub fn extend(&mut self, pos: &[[f32; 3]], inv_mass: &[f32]) -> u32 {
        debug_assert_eq!(pos.len(), inv_mass.len());
        self.truncate_padding();
        let first = self.count;
        for (p, &w) in pos.iter().zip(inv_mass) {
            self.x.push(p[0]);
            self.y.push(p[1]);
            self.z.push(p[2]);
            self.vx.push(0.0);
            self.vy.push(0.0);
            self.vz.push(0.0);
            self.w.push(w);
        }
        self.count += pos.len();
        self.repad();
        first as u32
    }

    /// The arrays that hold state between steps (the predictions are derived from `x`).
    fn stored_arrays(&mut self) -> [&mut Vec<f32>; 7] {
        [
            &mut self.x,
            &mut self.y,
            &mut self.z,
            &mut self.vx,
            &mut self.vy,
            &mut self.vz,
            &mut self.w,
        ]
    }

    fn truncate_padding(&mut self) {
        let n = self.count;
        for v in self.stored_arrays() {
            v.truncate(n);
        }
    }

    fn repad(&mut self) {
        let len = round_up(self.count + 1);
        for v in self.stored_arrays() {
            v.resize(len, 0.0);
        }
        self.px = self.x.clone();
        self.py = self.y.clone();
        self.pz = self.z.clone();
    }

    /// Position of particle `i`.
    pub fn position(&self, i: usize) -> [f32; 3] {
        [self.x[i], self.y[i], self.z[i]]
    }

    /// Velocity of particle `i`.
    pub fn velocity(&self, i: usize) -> [f32; 3] {
        [self.vx[i], self.vy[i], self.vz[i]]
    }

    /// Index of the first real particle whose position or velocity is not finite.
    pub fn first_non_finite(&self) -> Option<usize> {
        (0..self.count).find(|&i| {
            !(self.x[i].is_finite()
                && self.y[i].is_finite()
                && self.z[i].is_finite()
                && self.vx[i].is_finite()
                && self.vy[i].is_finite()
                && self.vz[i].is_finite())
        })
    }
}

#[cfg(test)]
mod tests;
