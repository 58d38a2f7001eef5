//! The force-based step (symplectic Euler, leapfrog, implicit Euler): the world's glue that
//! gathers forces, runs the method's kick and drift kernels (`integrate::mass_spring`,
//! `integrate::implicit`) over the substeps, and hands the drift to the collision stages
//! (`world::contacts`) when the world has any.

use crate::data::exec::Exec;
use crate::integrate::implicit::{ImplicitState, ImplicitSubstep};
use crate::integrate::mass_spring::{kick, kick_params};
use crate::integrate::springs::{add_spring_forces_scalar, add_spring_forces_simd};
use crate::model::params::{Backend, Method};
use crate::world::World;

impl World {
    /// Forces at the current positions (and velocities, for wind) into the scratch arrays.
    fn compute_forces(&mut self, t: f64) {
        let len = self.particles.padded_len();
        let simd = self.params.backend == Backend::Simd;
        for a in &mut self.ms.f {
            a.clear();
            a.resize(len, 0.0);
        }
        let p = &self.particles;
        let x = [&p.x[..], &p.y[..], &p.z[..]];
        if let (Some(w), Some(state)) = (&self.effects.wind, &mut self.wind) {
            state.compute(w, t, &self.triangles, x, [&p.vx, &p.vy, &p.vz], Exec::new(simd, simd));
            self.ms.f[0].copy_from_slice(&state.fx);
            self.ms.f[1].copy_from_slice(&state.fy);
            self.ms.f[2].copy_from_slice(&state.fz);
        }
        let [fx, fy, fz] = &mut self.ms.f;
        if simd {
            add_spring_forces_simd(&self.distance, x, [fx, fy, fz], self.params.stiffness, true);
        } else {
            add_spring_forces_scalar(&self.distance, x, [fx, fy, fz], self.params.stiffness);
        }
    }

    /// Damping factors for substep length `h` (recomputed only when `h` changes).
    pub(crate) fn damping_for(&mut self, h: f32) {
        if self.has_damping && self.damp_h != h {
            self.damp_factor = self.damping_rate.iter().map(|&c| 1.0 / (1.0 + c * h)).collect();
            self.damp_factor.resize(self.particles.padded_len(), 1.0);
            self.damp_h = h;
        }
    }

    /// One step of a force-based method (`substeps` substeps; `iterations` is not used), with
    /// the collision stages after every drift when the world has obstacles or self-collision.
    pub(crate) fn run_mass_spring(&mut self, dt: f32, method: Method) -> crate::Result<()> {
        let n_sub = self.params.substeps;
        let h = dt / n_sub as f32;
        let exec = self.exec();
        let (simd, parallel) = (exec.simd(), exec.parallel());
        self.damping_for(h);
        self.last_h = h;
        let contacts = self.begin_force_contacts(dt, parallel);
        let keep_x = contacts.any();
        let leap = method == Method::Leapfrog;
        if leap {
            self.compute_forces(self.time);
        }
        for s in 0..n_sub {
            let t = self.time + s as f64 * h as f64;
            if method == Method::ImplicitEuler {
                self.implicit_substep(h, t, keep_x)?;
            } else if leap {
                // Half kick + drift with F(x_n), contacts, then the half kick with F(x_{n+1})
                // closing the substep.
                let mut first = kick_params(
                    &self.ms.f,
                    self.has_damping.then_some(&self.damp_factor[..]),
                    &self.effects,
                    0.5 * h,
                    h,
                    false,
                    Some(h),
                );
                first.keep_x = keep_x;
                self.particles.for_chunks(parallel, |c| kick(c, &first, simd));
                if keep_x {
                    self.force_contact_stages(contacts, s, h, exec);
                }
                self.compute_forces(t + h as f64);
                let close = kick_params(
                    &self.ms.f,
                    self.has_damping.then_some(&self.damp_factor[..]),
                    &self.effects,
                    0.5 * h,
                    h,
                    true,
                    None,
                );
                self.particles.for_chunks(parallel, |c| kick(c, &close, simd));
                continue;
            } else {
                // Symplectic Euler: one whole kick + drift closing the substep.
                self.compute_forces(t);
                let mut close = kick_params(
                    &self.ms.f,
                    self.has_damping.then_some(&self.damp_factor[..]),
                    &self.effects,
                    h,
                    h,
                    true,
                    Some(h),
                );
                close.keep_x = keep_x;
                self.particles.for_chunks(parallel, |c| kick(c, &close, simd));
            }
            if keep_x {
                self.force_contact_stages(contacts, s, h, exec);
            }
        }
        Ok(())
    }
}

impl World {
    /// One implicit Euler substep of length `h` at time `t`. With `keep_x` the drift writes only
    /// the prediction `p` for the collision stages ([`crate::world::contacts`]).
    pub(crate) fn implicit_substep(&mut self, h: f32, t: f64, keep_x: bool) -> crate::Result<()> {
        let p = &self.particles;
        let exec = Exec::new(self.params.backend == Backend::Simd, false);
        let wind = match (&self.effects.wind, &mut self.wind) {
            (Some(w), Some(state)) => {
                state.compute(w, t, &self.triangles, [&p.x, &p.y, &p.z], [&p.vx, &p.vy, &p.vz], exec);
                Some([&state.fx[..], &state.fy[..], &state.fz[..]])
            }
            _ => None,
        };
        let sub = ImplicitSubstep {
            h,
            stiffness: self.params.stiffness,
            gravity: self.effects.gravity,
            wind,
            drag: self.effects.drag,
            damp: self.has_damping.then_some(&self.damp_factor[..]),
            keep_x,
        };
        ImplicitState::substep(&mut self.ms.implicit, &mut self.particles, &self.distance, &sub)
    }
}
