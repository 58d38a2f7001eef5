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
//! is bound by the dependency chain of its floating-point operations (`docs/performance.md`),
//! so fewer make it faster.
//!
//! `FRESH` says the multiplier is zero (the first sweep of a substep, or a class that keeps
//! none): `-C - α̃ λ` is then `-C` exactly, for `(-α̃) · (+0)` is `-0` and `α̃ · (+0)` is `+0`
//! for every finite `α̃ ≥ 0`, and adding `-0` or subtracting `+0` changes no value. The lanes
//! skip that multiply-add and give the same bits.

use crate::data::lanes::{mul_add, F32s, Vec3x8};
use crate::model::params::MIN_LENGTH;

/// One XPBD distance constraint, scalar: new `p_a`, `p_b` and multiplier, from `alpha = α / h²`.
/// The SIMD kernels' lanes ([`project8`]) do the same operations in the same order.
#[inline(always)]
pub(crate) fn project1<const ONE_DIV: bool, const FRESH: bool>(
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
        let num = if FRESH { -c } else { (-alpha).mul_add(lam, -c) };
        let s = if valid { num / (denom * len) } else { 0.0 };
        let (sa, sb) = (wa * s, wb * s);
        let pa = [(-dx).mul_add(sa, pa[0]), (-dy).mul_add(sa, pa[1]), (-dz).mul_add(sa, pa[2])];
        let pb = [dx.mul_add(sb, pb[0]), dy.mul_add(sb, pb[1]), dz.mul_add(sb, pb[2])];
        return (pa, pb, s.mul_add(len, lam));
    }
    let (s, dl) = if !valid {
        (0.0, 0.0)
    } else {
        let num = if FRESH { -c } else { -c - alpha * lam };
        let dl = num / denom;
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
pub(crate) fn project8<const ONE_DIV: bool, const CHECK_DENOM: bool, const FRESH: bool>(
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
        let num = if FRESH { -c } else { mul_add(-alpha, lam, -c) };
        let sc = valid & (num / (denom * len));
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
    let num = if FRESH { -c } else { -c - alpha * lam };
    let dl = valid.select(num / denom, zero);
    let sc = valid.select(dl / len, zero);
    (pa - d.scale(wa * sc), pb + d.scale(wb * sc), lam + dl)
}

#[cfg(test)]
mod tests {
    use super::{project1, project8};
    use crate::data::lanes::{F32s, Vec3x8};
    use proptest::prelude::*;

    /// The bits of a projection's results.
    fn bits(r: ([f32; 3], [f32; 3], f32)) -> [u32; 7] {
        let (a, b, l) = r;
        [a[0], a[1], a[2], b[0], b[1], b[2], l].map(f32::to_bits)
    }

    /// One constraint with a zero multiplier in the `FRESH` form and the general one, scalar
    /// and in the lanes (lane 0 of eight equal lanes): the bits of the four results.
    fn forms<const ONE_DIV: bool>(pa: [f32; 3], pb: [f32; 3], w: [f32; 2], rest: f32, alpha: f32) -> [[u32; 7]; 4] {
        let lane0 = |r: (Vec3x8, Vec3x8, F32s)| {
            let g = |v: F32s| v.to_array()[0];
            let (a, b, l) = r;
            ([g(a.x), g(a.y), g(a.z)], [g(b.x), g(b.y), g(b.z)], g(l))
        };
        let s = |v: f32| F32s::splat(v);
        let (a8, b8) = (Vec3x8::splat(pa), Vec3x8::splat(pb));
        let (w8, r8, al8) = ([s(w[0]), s(w[1])], s(rest), s(alpha));
        [
            bits(project1::<ONE_DIV, false>(pa, pb, w[0], w[1], rest, alpha, 0.0)),
            bits(project1::<ONE_DIV, true>(pa, pb, w[0], w[1], rest, alpha, 0.0)),
            bits(lane0(project8::<ONE_DIV, true, false>(a8, b8, w8[0], w8[1], r8, al8, F32s::ZERO))),
            bits(lane0(project8::<ONE_DIV, true, true>(a8, b8, w8[0], w8[1], r8, al8, F32s::ZERO))),
        ]
    }

    /// The four forms agree bit for bit, with one division and with two.
    fn check(pa: [f32; 3], pb: [f32; 3], wa: f32, wb: f32, rest: f32, alpha: f32) {
        for f in [
            forms::<true>(pa, pb, [wa, wb], rest, alpha),
            forms::<false>(pa, pb, [wa, wb], rest, alpha),
        ] {
            assert!(f.iter().all(|r| *r == f[0]), "{f:?}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// A fresh multiplier changes no bit, with or without compliance, at any length, and at
        /// exactly the rest length (`C = +0`), where the sign of a zero could show.
        #[test]
        fn fresh_multipliers_change_no_bit(
            pa in prop::array::uniform3(-2.0f32..2.0),
            d in prop::array::uniform3(-1.0f32..1.0),
            wa in prop_oneof![Just(0.0f32), 0.01f32..10.0],
            wb in prop_oneof![Just(0.0f32), 0.01f32..10.0],
            alpha in prop_oneof![Just(0.0f32), 1e-9f32..1e3],
            rest in 0.0f32..1.5,
        ) {
            let pb = [pa[0] + d[0], pa[1] + d[1], pa[2] + d[2]];
            check(pa, pb, wa, wb, rest, alpha);
            // a constraint exactly at its rest length along x, and one of zero length
            check([0.0, 0.5, -0.0], [rest, 0.5, -0.0], wa, wb, rest, alpha);
            check([-0.0, 0.0, 0.0], [-0.0, 0.0, 0.0], wa, wb, 0.0, alpha);
        }
    }
}
