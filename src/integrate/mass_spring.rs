//! Explicit mass-spring integrators: symplectic Euler and leapfrog.
//!
//! The cloth model is the one XPBD solves, read as forces: each distance constraint of
//! compliance `α` is a spring of stiffness `k = 1/α`, and a constraint of zero compliance (rigid
//! in XPBD) gets the solver's [`stiffness`](crate::SolverParams::stiffness) (scene key
//! `solver.stiffness`, default 1e4 N/m). Forces are `F = Σ springs + wind`, accelerations
//! `a = g + w F` (`w` the inverse mass; pinned particles, `w = 0`, get no acceleration, and they
//! keep their velocity, zero unless a program set one, exactly as in XPBD). Tethers are XPBD
//! position limits and have no force counterpart: these methods ignore them.
//!
//! Per substep of length `h`:
//!
//! ```text
//! symplectic Euler:  v <- v + h a(x_n);            x_{n+1} = x_n + h v_{n+1}
//! leapfrog (KDK):    v <- v + h/2 a(x_n);  x_{n+1} = x_n + h v;  v <- v + h/2 a(x_{n+1})
//! ```
//!
//! followed in both by drag `v <- v / (1 + h w c_drag)` and fabric damping `v <- v / (1 + c h)`
//! (the same factors as the XPBD update). Symplectic Euler is first order. The leapfrog update
//! of Landovskaya, Landovsky & Frolovsky, `v_{n+1} = v_n + h M⁻¹F(r_n, v_n)`, `r_{n+1} = r_n + h v_{n+1}`,
//! is symplectic Euler when read with whole-step velocities; it is leapfrog, and second order,
//! when `v` is read as the velocity half a step later — which is what kick-drift-kick computes
//! while still reporting velocities at whole steps. Its force at the end of a substep is the
//! force at the start of the next, so a step of `s` substeps costs `s + 1` force evaluations.
//!
//! Both are conditionally stable: with the stiffest spring `k` between particles of mass `m`,
//! `h` must stay below about `2 / ω`, `ω = 2 √(k/m)`. Past that the state grows without bound
//! and the step's guard reports [`WeftError::Diverged`](crate::WeftError::Diverged).

use crate::data::lanes::{load, F32s, Vec3x8, LANES};
use crate::data::particles::ParticleChunk;
use crate::integrate::springs::{add_spring_forces_scalar, add_spring_forces_simd};
use crate::model::effects::Effects;
use crate::model::params::{Backend, Method};
use crate::world::World;

/// Scratch of the force-based methods, kept by the world between steps.
#[derive(Default)]
pub struct MassSpringState {
    /// Force arrays, N (padded length).
    pub f: [Vec<f32>; 3],
    /// The implicit solver's factorisation and layout, built on first use.
    pub implicit: Option<crate::integrate::implicit::ImplicitState>,
    /// The predictions before the collision stages moved them (see
    /// [`crate::integrate::contacts`]).
    pub predicted: [Vec<f32>; 3],
    /// Velocities before the self-collision speed clamp (see [`crate::integrate::contacts`]).
    pub before_clamp: [Vec<f32>; 3],
}

/// What one kick/drift pass does to a chunk of particles.
#[derive(Clone, Copy)]
pub struct KickParams<'a> {
    /// Length of the kick, s (`h`, or `h/2` for a leapfrog half kick).
    pub hk: f32,
    /// Gravity, m/s², if named.
    pub gravity: Option<[f32; 3]>,
    /// Per-particle force (global index), N.
    pub force: [&'a [f32]; 3],
    /// `h · c_drag` when drag is named and this pass closes the substep.
    pub drag_h: Option<f32>,
    /// Fabric damping factors `1 / (1 + c h)` (global index) when this pass closes the substep.
    pub damp: Option<&'a [f32]>,
    /// Drift `x += h v` after the kick, with this `h`.
    pub drift: Option<f32>,
    /// The drift writes only the prediction `p = x + h v` and leaves `x` for the collision
    /// stages (see [`crate::integrate::contacts`]); otherwise it writes both.
    pub keep_x: bool,
}

/// Kick (and optionally drag, damping, drift) on one chunk: SIMD when `simd`, else the twin.
pub fn kick(c: ParticleChunk<'_>, p: &KickParams<'_>, simd: bool) {
    if simd {
        kick_simd(c, p)
    } else {
        kick_scalar(c, p)
    }
}

fn kick_simd(c: ParticleChunk<'_>, p: &KickParams<'_>) {
    if p.gravity.is_some() {
        crate::model::effects::probe::enter(crate::model::effects::probe::GRAVITY);
    }
    if p.drag_h.is_some() {
        crate::model::effects::probe::enter(crate::model::effects::probe::DRAG);
    }
    let hk = F32s::splat(p.hk);
    let zero = F32s::ZERO;
    let one = F32s::ONE;
    let g = Vec3x8::splat(p.gravity.unwrap_or([0.0; 3]));
    let hc = F32s::splat(p.drag_h.unwrap_or(0.0));
    let hd = F32s::splat(p.drift.unwrap_or(0.0));
    for i in (0..c.x.len()).step_by(LANES) {
        let j = c.start + i;
        let w = load(c.w, i);
        let mut v = Vec3x8::load(c.vx, c.vy, c.vz, i);
        if p.gravity.is_some() {
            let free = w.simd_gt(zero);
            v = v + Vec3x8::select(free, g, Vec3x8::splat([0.0; 3])).scale(hk);
        }
        let f = Vec3x8::load(p.force[0], p.force[1], p.force[2], j);
        v = v + f.scale(w * hk);
        if p.drag_h.is_some() {
            v = v.scale(one / (one + hc * w));
        }
        if let Some(d) = p.damp {
            v = v.scale(load(d, j));
        }
        v.store(c.vx, c.vy, c.vz, i);
        if p.drift.is_some() {
            let x = Vec3x8::load(c.x, c.y, c.z, i) + v.scale(hd);
            if !p.keep_x {
                x.store(c.x, c.y, c.z, i);
            }
            x.store(c.px, c.py, c.pz, i);
        }
    }
}

/// Scalar twin of the kick kernel.
fn kick_scalar(c: ParticleChunk<'_>, p: &KickParams<'_>) {
    if p.gravity.is_some() {
        crate::model::effects::probe::enter(crate::model::effects::probe::GRAVITY);
    }
    if p.drag_h.is_some() {
        crate::model::effects::probe::enter(crate::model::effects::probe::DRAG);
    }
    let hk = p.hk;
    let g = p.gravity.unwrap_or([0.0; 3]);
    let hc = p.drag_h.unwrap_or(0.0);
    let hd = p.drift.unwrap_or(0.0);
    for i in 0..c.x.len() {
        let j = c.start + i;
        let w = c.w[i];
        let mut v = [c.vx[i], c.vy[i], c.vz[i]];
        if p.gravity.is_some() {
            let gm = if w > 0.0 { g } else { [0.0; 3] };
            for (vk, gk) in v.iter_mut().zip(gm) {
                *vk += gk * hk;
            }
        }
        let wh = w * hk;
        for (vk, f) in v.iter_mut().zip(p.force) {
            *vk += f[j] * wh;
        }
        if p.drag_h.is_some() {
            let s = 1.0 / (1.0 + hc * w);
            v = v.map(|e| e * s);
        }
        if let Some(d) = p.damp {
            v = v.map(|e| e * d[j]);
        }
        (c.vx[i], c.vy[i], c.vz[i]) = (v[0], v[1], v[2]);
        if p.drift.is_some() {
            let x = [c.x[i] + v[0] * hd, c.y[i] + v[1] * hd, c.z[i] + v[2] * hd];
            if !p.keep_x {
                (c.x[i], c.y[i], c.z[i]) = (x[0], x[1], x[2]);
            }
            (c.px[i], c.py[i], c.pz[i]) = (x[0], x[1], x[2]);
        }
    }
}

/// Kick parameters over the force scratch `f`; `close` adds drag and damping.
fn kick_params<'a>(
    f: &'a [Vec<f32>; 3],
    damp: Option<&'a [f32]>,
    effects: &Effects,
    hk: f32,
    h: f32,
    close: bool,
    drift: Option<f32>,
) -> KickParams<'a> {
    KickParams {
        hk,
        gravity: effects.gravity,
        force: [&f[0], &f[1], &f[2]],
        drag_h: effects.drag.filter(|_| close).map(|c| c * h),
        damp: damp.filter(|_| close),
        drift,
        keep_x: false,
    }
}

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
            state.compute(w, t, &self.triangles, x, [&p.vx, &p.vy, &p.vz], simd);
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
        let simd = self.params.backend == Backend::Simd;
        let parallel = simd && !self.embed.caller_thread_only;
        self.damping_for(h);
        self.last_h = h;
        let contacts = self.begin_force_contacts(parallel);
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
                    self.force_contact_stages(contacts, s, h, parallel, simd);
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
                self.force_contact_stages(contacts, s, h, parallel, simd);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
#[path = "mass_spring_tests.rs"]
mod tests;
