//! Timing of global against local NURBS evaluation, for the reproduction of the NURBS thesis' claim.
//!
//! The thesis claims (section 2.2.2, "complexity"): evaluating one point of a curve costs
//! `O(n l)` with the global formula 2.8 and `O(k l)` with the local formula 2.11; for a surface
//! `O(n m (p + q))` against `O(ku kv (p + q))`. [`nurbs_timing`] measures exactly that: the
//! median wall time per evaluated point of [`NurbsCurve::eval_global_with`] and
//! [`NurbsCurve::eval_local`] (and the surface twins) as the number of control points grows.
//! Local cost should stay flat in `n`; global cost should grow linearly with `n` (with `n^2`
//! for an `n x n` surface).
//!
//! Control points are deterministic pseudo-random numbers in `[-1, 1]^3` with weights in
//! `[0.5, 2]`, so runs are repeatable. Parameters are `samples` stratified values in `[0, 1]`
//! (surfaces: `samples` scattered `(u, v)` pairs). Each measurement is repeated
//! [`REPETITIONS`] times and the median is kept.

use super::nurbs::{GlobalScratch, NurbsCurve, NurbsSurface, MAX_CONTROL, MAX_DEGREE};
use std::hint::black_box;
use std::time::Instant;

/// Surfaces are timed only up to an `n x n` grid with this `n`: the global evaluator costs
/// `n^2` per point, so a 4096 x 4096 grid would take seconds per point.
pub const SURFACE_MAX_N: usize = 256;

/// Repetitions per measurement; the median is reported.
pub const REPETITIONS: usize = 7;

/// One line of the timing table.
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsTimingRow {
    /// `"curve"` or `"surface"`.
    pub kind: &'static str,
    /// Control points per direction (`n` for a curve, an `n x n` grid for a surface).
    pub n: usize,
    /// Degree `p` in both directions (the paper's order is `p + 1`).
    pub degree: usize,
    /// Median nanoseconds per point, global evaluation (formula 2.8 / 2.9, `f64`).
    pub global_ns: f64,
    /// Median nanoseconds per point, local evaluation (formula 2.11 / 2.12, `f32`).
    pub local_ns: f64,
}

/// SplitMix64: a tiny deterministic generator, enough for repeatable test geometry.
struct Mix(u64);

impl Mix {
    /// A uniform value in `[lo, hi)`.
    fn next(&mut self, lo: f32, hi: f32) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        let unit = (z >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * unit
    }
}

/// `len` control points: x, y, z in `[-1, 1]`, weights in `[0.5, 2]`.
fn control(len: usize, seed: u64) -> [Vec<f32>; 4] {
    let mut g = Mix(seed);
    let mut c = [vec![], vec![], vec![], vec![]];
    for _ in 0..len {
        for a in c.iter_mut().take(3) {
            a.push(g.next(-1.0, 1.0));
        }
        c[3].push(g.next(0.5, 2.0));
    }
    c
}

/// Median of the per-point time over [`REPETITIONS`] runs of `f` over `samples` points.
fn median_ns(samples: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..REPETITIONS)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_nanos() as f64 / samples as f64
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[REPETITIONS / 2]
}

/// Times global against local evaluation for every `n` in `ns` and degree in `degrees`:
/// curves for every `n`, surfaces (an `n x n` grid) for `n <= SURFACE_MAX_N`. Combinations
/// that do not make a spline (`degree >= n`, `degree > MAX_DEGREE`, `n > MAX_CONTROL`) are
/// skipped; `samples` is raised to at least 1. Rows come curves first, in the order of `ns`
/// then `degrees`.
pub fn nurbs_timing(ns: &[usize], degrees: &[usize], samples: usize) -> Vec<NurbsTimingRow> {
    let samples = samples.max(1);
    let us: Vec<f32> = (0..samples).map(|j| ((j as f64 + 0.5) / samples as f64) as f32).collect();
    // A scattered second coordinate (golden-ratio sequence) so (u, v) covers the square.
    let vs: Vec<f32> = (0..samples).map(|j| ((j as f64 * 0.618_033_988_749_895).fract()) as f32).collect();
    let fits = |n: usize, p: usize| p < n && p <= MAX_DEGREE && n <= MAX_CONTROL;
    let mut rows = Vec::new();
    for &n in ns {
        for &p in degrees.iter().filter(|&&p| fits(n, p)) {
            let [x, y, z, w] = control(n, (n * 31 + p) as u64);
            let Ok(curve) = NurbsCurve::new(x, y, z, w, p) else {
                continue;
            };
            let mut scratch = GlobalScratch::default();
            let global_ns = median_ns(samples, || {
                for &u in &us {
                    let _ = black_box(curve.eval_global_with(black_box(u), &mut scratch));
                }
            });
            let local_ns = median_ns(samples, || {
                for &u in &us {
                    let _ = black_box(curve.eval_local(black_box(u)));
                }
            });
            rows.push(NurbsTimingRow {
                kind: "curve",
                n,
                degree: p,
                global_ns,
                local_ns,
            });
        }
    }
    for &n in ns.iter().filter(|&&n| n <= SURFACE_MAX_N) {
        for &p in degrees.iter().filter(|&&p| fits(n, p)) {
            let [x, y, z, w] = control(n * n, (n * 131 + p) as u64);
            let Ok(surf) = NurbsSurface::new(n, n, x, y, z, w, p, p) else {
                continue;
            };
            let mut scratch = GlobalScratch::default();
            let global_ns = median_ns(samples, || {
                for (&u, &v) in us.iter().zip(&vs) {
                    let _ = black_box(surf.eval_global_with(black_box(u), v, &mut scratch));
                }
            });
            let local_ns = median_ns(samples, || {
                for (&u, &v) in us.iter().zip(&vs) {
                    let _ = black_box(surf.eval_local(black_box(u), v));
                }
            });
            rows.push(NurbsTimingRow {
                kind: "surface",
                n,
                degree: p,
                global_ns,
                local_ns,
            });
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timing_table_has_one_row_per_valid_combination() {
        let rows = nurbs_timing(&[2, 8, 300], &[1, 3], 4);
        let keys: Vec<_> = rows.iter().map(|r| (r.kind, r.n, r.degree)).collect();
        assert_eq!(
            keys,
            vec![
                ("curve", 2, 1),
                ("curve", 8, 1),
                ("curve", 8, 3),
                ("curve", 300, 1),
                ("curve", 300, 3),
                ("surface", 2, 1),
                ("surface", 8, 1),
                ("surface", 8, 3),
            ]
        );
        for r in &rows {
            assert!(r.global_ns.is_finite() && r.global_ns > 0.0, "{r:?}");
            assert!(r.local_ns.is_finite() && r.local_ns > 0.0, "{r:?}");
        }
        assert!(nurbs_timing(&[], &[1], 4).is_empty());
        assert_eq!(nurbs_timing(&[4], &[1], 0).len(), 2, "samples raised to 1");
    }

    #[test]
    fn test_geometry_is_deterministic_and_in_range() {
        let a = control(50, 7);
        assert_eq!(a, control(50, 7));
        assert!(a[..3].iter().flatten().all(|v| (-1.0..1.0).contains(v)));
        assert!(a[3].iter().all(|v| (0.5..2.0).contains(v)));
    }
}
