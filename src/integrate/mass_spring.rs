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
use crate::model::effects::Effects;

/// Scratch of the force-based methods, kept by the world between steps.
#[derive(Default)]
pub struct MassSpringState {
    /// Force arrays, N (padded length).
    pub f: [Vec<f32>; 3],
    /// The implicit solver's factorisation and layout, built on first use.
    pub implicit: Option<crate::integrate::implicit::ImplicitState>,
    /// The predictions before the collision stages moved them (see
    /// `world::contacts`).
    pub predicted: [Vec<f32>; 3],
    /// Velocities before the self-collision speed clamp (see `world::contacts`).
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
    /// stages (see `world::contacts`); otherwise it writes both.
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
pub(crate) fn kick_params<'a>(
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

#[cfg(test)]
#[path = "mass_spring_tests.rs"]
mod tests;
