//! The speed clamp of self-collision (Müller's "Ten Minute Physics" self-collision), SIMD
//! (`f32x8`) with a scalar twin that the tests hold to it bit for bit (same operations in the
//! same order, no FMA).
//!
//! After predict, a free particle's velocity relative to the mean velocity `m` of the free
//! particles is limited so that it moves at most `limit` relative to the cloth in one substep:
//!
//! ```text
//! u = v - m;   v' = m + u limit / (|u| h);
//! if |u| h > limit and |v'| <= |v|:  v = v';   p = x + h v
//! ```
//!
//! The clamp only ever slows a particle down. A particle slower than the cloth around it (one
//! an obstacle has stopped, or one resting on the layers below) keeps its velocity: pulled up
//! to the mean, the resting part of a pile would be driven into the ground every substep at
//! the speed of the part still falling, and the contact pass, which splits each correction
//! between the two particles, cannot undo that: the pile is pressed through itself. The cost
//! is the bound: a falling particle and a stopped one close in faster than `2 T` a step, and
//! such a pair is caught only once the list holds it.
//!
//! The mean is summed in fixed chunks (module `mean`); when the step has no obstacles (which
//! change velocities between predict and the clamp), its predict pass (or the update pass
//! that runs the next predict) adds each chunk's sums while the chunk is in cache, and the
//! clamp only reads them: one pass over the particles and one parallel region fewer a
//! substep, the same bits (`step::fusion_tests`).

use crate::data::lanes::{load, F32s, Vec3x8, LANES};
use crate::model::shapes::dot;

/// Inputs of [`clamp_speed`].
#[derive(Clone, Copy, Debug)]
pub struct ClampParams<'a> {
    /// Mean velocity of the free particles, m/s.
    pub mean: [f32; 3],
    /// Largest move relative to the mean in one substep, m (times the particle's `travel`).
    pub limit: f32,
    /// Substep length, s.
    pub h: f32,
    /// Each particle's factor on `limit` (indexed like the whole particle arrays, padding
    /// included), or empty (or shorter than a chunk's particles) for `limit` itself.
    pub travel: &'a [f32],
}

/// The speed clamp on one chunk (`x`, `v`, `p`, `w` chunk-local, lengths a multiple of
/// [`LANES`]): SIMD when `simd`, else the scalar twin.
pub fn clamp_speed(c: crate::data::particles::ParticleChunk<'_>, cp: &ClampParams<'_>, simd: bool) {
    if simd {
        clamp_simd(c, cp)
    } else {
        clamp_scalar(c, cp)
    }
}

/// The clamp's lanes. The loads keep their bounds checks: the pass waits on memory, and
/// unchecked loads saved instructions but no time.
fn clamp_simd(c: crate::data::particles::ParticleChunk<'_>, cp: &ClampParams<'_>) {
    let m = Vec3x8::splat(cp.mean);
    let h = F32s::splat(cp.h);
    let uniform = F32s::splat(cp.limit / cp.h);
    let per = cp.travel.len() >= c.start + c.x.len();
    for i in (0..c.x.len()).step_by(LANES) {
        let lim = if per {
            load(cp.travel, c.start + i) * F32s::splat(cp.limit) / h
        } else {
            uniform
        };
        let lim2 = lim * lim;
        let v = Vec3x8::load(c.vx, c.vy, c.vz, i);
        let u = v - m;
        let u2 = u.length_sq();
        let fast = u2.simd_gt(lim2) & load(c.w, i).simd_gt(F32s::ZERO);
        if !fast.any() {
            // Nothing to clamp: the pass only reads (the stores below would write the same bits).
            continue;
        }
        let scaled = m + u.scale(lim / u2.sqrt());
        // Never faster than before (see the module docs).
        let fast = fast & scaled.length_sq().simd_le(v.length_sq());
        let v = Vec3x8::select(fast, scaled, v);
        let x = Vec3x8::load(c.x, c.y, c.z, i);
        let p = x + v.scale(h);
        let p = Vec3x8::select(fast, p, Vec3x8::load(c.px, c.py, c.pz, i));
        v.store(c.vx, c.vy, c.vz, i);
        p.store(c.px, c.py, c.pz, i);
    }
}

/// Scalar twin of the speed clamp.
fn clamp_scalar(c: crate::data::particles::ParticleChunk<'_>, cp: &ClampParams<'_>) {
    let h = cp.h;
    let per = cp.travel.len() >= c.start + c.x.len();
    for i in 0..c.x.len() {
        let lim = if per {
            cp.travel[c.start + i] * cp.limit / cp.h
        } else {
            cp.limit / cp.h
        };
        let lim2 = lim * lim;
        let u = [c.vx[i] - cp.mean[0], c.vy[i] - cp.mean[1], c.vz[i] - cp.mean[2]];
        let u2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
        if !(u2 > lim2 && c.w[i] > 0.0) {
            continue;
        }
        let s = lim / u2.sqrt();
        let v = [cp.mean[0] + u[0] * s, cp.mean[1] + u[1] * s, cp.mean[2] + u[2] * s];
        let old = [c.vx[i], c.vy[i], c.vz[i]];
        let slower = dot(v, v) <= dot(old, old);
        if !slower {
            continue;
        }
        c.vx[i] = v[0];
        c.vy[i] = v[1];
        c.vz[i] = v[2];
        c.px[i] = c.x[i] + v[0] * h;
        c.py[i] = c.y[i] + v[1] * h;
        c.pz[i] = c.z[i] + v[2] * h;
    }
}

#[cfg(test)]
#[path = "clamp_tests.rs"]
mod tests;
