//! Eight-lane (`f32x8`) versions of the obstacle response and velocity pass of
//! [`kernels`](super): [`resolve_simd`] is the twin of
//! [`resolve_along_path`](crate::obstacles::kernels::resolve_along_path), [`velocity_pass_simd`] of
//! [`velocity_pass`](crate::obstacles::kernels::velocity_pass).
//!
//! Both run over whole blocks of eight particles (chunks start at and span multiples of eight,
//! as [`project_simd`](crate::obstacles::kernels::project_simd) does) and skip blocks without any contact, like
//! the scalar passes. Within a block every lane computes every branch of the scalar code and
//! a mask chooses per lane; lanes the scalar code leaves alone (no contact: zero normal, or
//! not touching in the velocity pass) keep their value through the mask, never through an
//! arithmetic identity (`-0 + 0` would turn into `+0`). The operations and their order are the
//! scalar ones, with no fused multiply-add, the clamp `t.clamp(0, 1)` is "below 0 -> 0, then
//! above 1 -> 1" (NaN passes, as in `f32::clamp`) and the maxima of
//! [`contact_velocity`](crate::obstacles::kernels::contact_velocity) are comparisons and choices, so both agree bit
//! for bit (`kernels/tests.rs`).

use crate::data::lanes::{load, F32s, Vec3x8, LANES};
use crate::obstacles::kernels::{block_touched, SlotBlocks, TOUCH_SLACK};

/// Contact point and normal of the eight slots of block `b` of one obstacle's slots, and the
/// lanes holding a contact; `None` when the block's flag is down (all `+0.0`: no lane holds a
/// contact, so a pass leaves every lane as it is).
#[inline(always)]
pub(super) fn slot_lanes<S: SlotBlocks>(slots: &S, b: usize) -> Option<(Vec3x8, Vec3x8, F32s)> {
    if !slots.touched()[b] {
        return None;
    }
    let s = slots.data();
    let o = b * crate::obstacles::kernels::SLOT_BLOCK;
    let c = Vec3x8 {
        x: load(s, o),
        y: load(s, o + LANES),
        z: load(s, o + 2 * LANES),
    };
    let n = Vec3x8 {
        x: load(s, o + 3 * LANES),
        y: load(s, o + 4 * LANES),
        z: load(s, o + 5 * LANES),
    };
    let zero = F32s::splat(0.0);
    let set = n.x.simd_ne(zero) | n.y.simd_ne(zero) | n.z.simd_ne(zero);
    Some((c, n, set))
}

/// [`resolve_along_path`](crate::obstacles::kernels::resolve_along_path) eight particles at a time (bitwise equal
/// to it); `start` and the chunk length are multiples of eight.
pub fn resolve_simd<S: SlotBlocks>(
    slots: &[S],
    shifts: &[[f32; 3]],
    mesh: &[bool],
    th: &[f32],
    start: usize,
    x: [&[f32]; 3],
    p: [&mut [f32]; 3],
) {
    let [px, py, pz] = p;
    let (zero, one) = (F32s::splat(0.0), F32s::splat(1.0));
    for j in (0..px.len()).step_by(LANES) {
        let g = start + j;
        let b = g / LANES;
        if !block_touched(slots, b) {
            continue;
        }
        let mut q = Vec3x8::load(px, py, pz, j);
        let t = load(th, g);
        let x0 = Vec3x8::load(x[0], x[1], x[2], j);
        for ((s, u), &mesh) in slots.iter().zip(shifts).zip(mesh) {
            let Some((c, n, set)) = slot_lanes(s, b) else { continue };
            let xr = x0 - Vec3x8::splat(*u);
            let (hx, hp) = (n.dot(xr - c), n.dot(q - c));
            let back = set & hx.simd_gt(hp) & hx.simd_ge(t);
            let stay = if mesh {
                set & !back & hx.simd_gt(zero) & hp.simd_lt(zero)
            } else {
                zero
            };
            let push = set & !back & !stay & hp.simd_lt(t);
            let tau = (hx - t) / (hx - hp);
            let tau = tau.simd_lt(zero).select(zero, tau);
            let tau = tau.simd_gt(one).select(one, tau);
            let along = xr + (q - xr).scale(tau);
            let out = q + n.scale(t - hp);
            q = Vec3x8::select(back, along, Vec3x8::select(stay, xr, Vec3x8::select(push, out, q)));
        }
        q.store(px, py, pz, j);
    }
}

/// [`velocity_pass`](crate::obstacles::kernels::velocity_pass) eight particles at a time (bitwise equal to it);
/// `start` and the chunk length are multiples of eight.
pub fn velocity_pass_simd<S: SlotBlocks>(
    slots: &[S],
    motion: &[([f32; 3], f32)],
    th: &[f32],
    start: usize,
    x: [&[f32]; 3],
    v: [&mut [f32]; 3],
) {
    let [vx, vy, vz] = v;
    let zero = F32s::splat(0.0);
    for j in (0..vx.len()).step_by(LANES) {
        let g = start + j;
        let b = g / LANES;
        if !block_touched(slots, b) {
            continue;
        }
        let q = Vec3x8::load(x[0], x[1], x[2], j);
        let limit = load(th, g) + F32s::splat(TOUCH_SLACK);
        let mut vel = Vec3x8::load(vx, vy, vz, j);
        for (s, &(u, mu)) in slots.iter().zip(motion) {
            let Some((c, n, set)) = slot_lanes(s, b) else { continue };
            let touch = set & !n.dot(q - c).simd_gt(limit);
            let a = load(s.data(), b * crate::obstacles::kernels::SLOT_BLOCK + 6 * LANES);
            let uu = Vec3x8::splat(u);
            let w = vel - uu;
            let wn = w.dot(n);
            let wt = w - n.scale(wn);
            let keep_n = wn.simd_gt(zero).select(wn, zero);
            let lt = wt.length_sq().sqrt();
            let neg = -wn;
            let drop = F32s::splat(mu) * neg.simd_gt(a).select(neg, a);
            let f = lt.simd_le(drop).select(zero, F32s::splat(1.0) - drop / lt);
            let out = (wt.scale(f) + n.scale(keep_n)) + uu;
            vel = Vec3x8::select(touch, out, vel);
        }
        vel.store(vx, vy, vz, j);
    }
}
