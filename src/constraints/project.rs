//! The XPBD projection of one distance constraint, scalar and eight lanes at a time: the one
//! piece of arithmetic every distance kernel shares, so that SIMD kernels and their scalar
//! twins agree bit for bit.
//!
//! `ONE_DIV` picks how the correction per unit of `p_b - p_a`, `s = Δλ / len`, is computed:
//! with one division, `s = (-C - α̃ λ) / (denom len)` and `Δλ = s len` (the structured grid
//! kernels); or as `Δλ = (-C - α̃ λ) / denom`, `s = Δλ / len` (the general colours, whose
//! rounding the small worlds and their recorded results keep). The grid form also fuses its
//! products and sums (the squared length, `-C - α̃ λ`, the position updates and `λ + Δλ`: ten
//! of its thirty operations), with one rounding on every target ([`mul_add`]): the grid sweep
//! is bound by its floating-point operations (`docs/performance.md`), so fewer make it faster.

use crate::data::lanes::{mul_add, F32s, Vec3x8};
use crate::model::params::MIN_LENGTH;

/// One XPBD distance constraint, scalar: new `p_a`, `p_b` and multiplier, from `alpha = α / h²`.
/// The SIMD kernels' lanes ([`project8`]) do the same operations in the same order.
#[inline(always)]
pub(crate) fn project1<const ONE_DIV: bool>(
    pa: [f32; 3],
    pb: [f32; 3],
    wa: f32,
    wb: f32,
    rest: f32,
    alpha: f32,
    lam: f32,
) -> ([f32; 3], [f32; 3], f32) {
    let (dx, dy, dz) = (pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]);
    let len = if ONE_DIV {
        dz.mul_add(dz, dy.mul_add(dy, dx * dx))
    } else {
        dx * dx + dy * dy + dz * dz
    }
    .sqrt();
    let c = len - rest;
    let denom = wa + wb + alpha;
    let valid = len > MIN_LENGTH && denom > 0.0;
    if ONE_DIV {
        let s = if valid { (-alpha).mul_add(lam, -c) / (denom * len) } else { 0.0 };
        let (sa, sb) = (wa * s, wb * s);
        let pa = [(-dx).mul_add(sa, pa[0]), (-dy).mul_add(sa, pa[1]), (-dz).mul_add(sa, pa[2])];
        let pb = [dx.mul_add(sb, pb[0]), dy.mul_add(sb, pb[1]), dz.mul_add(sb, pb[2])];
        return (pa, pb, s.mul_add(len, lam));
    }
    let (s, dl) = if !valid {
        (0.0, 0.0)
    } else {
        let dl = (-c - alpha * lam) / denom;
        (dl / len, dl)
    };
    let (sa, sb) = (wa * s, wb * s);
    let pa = [pa[0] - dx * sa, pa[1] - dy * sa, pa[2] - dz * sa];
    let pb = [pb[0] + dx * sb, pb[1] + dy * sb, pb[2] + dz * sb];
    (pa, pb, lam + dl)
}

/// Eight constraints at once: [`project1`] lane by lane. Without `CHECK_DENOM` the lanes skip
/// the test `w_a + w_b + α̃ > 0`, which the caller knows to hold (`α̃ > 0`, inverse masses
/// finite and not negative): the same results with two operations fewer.
#[inline(always)]
pub(crate) fn project8<const ONE_DIV: bool, const CHECK_DENOM: bool>(
    pa: Vec3x8,
    pb: Vec3x8,
    wa: F32s,
    wb: F32s,
    rest: F32s,
    alpha: F32s,
    lam: F32s,
) -> (Vec3x8, Vec3x8, F32s) {
    let zero = F32s::ZERO;
    let d = pb - pa;
    let len = if ONE_DIV {
        mul_add(d.z, d.z, mul_add(d.y, d.y, d.x * d.x))
    } else {
        d.length_sq()
    }
    .sqrt();
    let c = len - rest;
    let denom = wa + wb + alpha;
    let long = len.simd_gt(F32s::splat(MIN_LENGTH));
    let valid = if CHECK_DENOM { long & denom.simd_gt(zero) } else { long };
    if ONE_DIV {
        // The mask zeroes the other lanes (`+0.0`, as a select would), and the multiplier
        // needs no mask of its own: `s len + λ` is `λ` where `s` is zero and `len` finite.
        let sc = valid & (mul_add(-alpha, lam, -c) / (denom * len));
        let (sa, sb) = (wa * sc, wb * sc);
        let pa = Vec3x8 {
            x: mul_add(-d.x, sa, pa.x),
            y: mul_add(-d.y, sa, pa.y),
            z: mul_add(-d.z, sa, pa.z),
        };
        let pb = Vec3x8 {
            x: mul_add(d.x, sb, pb.x),
            y: mul_add(d.y, sb, pb.y),
            z: mul_add(d.z, sb, pb.z),
        };
        return (pa, pb, mul_add(sc, len, lam));
    }
    let dl = valid.select((-c - alpha * lam) / denom, zero);
    let sc = valid.select(dl / len, zero);
    (pa - d.scale(wa * sc), pb + d.scale(wb * sc), lam + dl)
}
