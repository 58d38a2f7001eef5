//! Property and behaviour tests for the NURBS module.

use super::*;
use crate::WeftError;
use proptest::prelude::*;

/// Relative tolerance of local (`f32`) against global (`f64`) evaluation, times the largest
/// control-point coordinate.
const REL_TOL: f64 = 1e-6;

#[derive(Clone, Debug)]
struct Ctrl {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    w: Vec<f32>,
}

impl Ctrl {
    fn scale(&self) -> f64 {
        let mut m = 0.0f64;
        for &v in self.x.iter().chain(&self.y).chain(&self.z) {
            if (v.abs() as f64) > m {
                m = v.abs() as f64;
            }
        }
        m
    }
}

/// Uniform `f32` in `[lo, hi]` on a grid of 2^24 steps, drawn from an integer. proptest's own
/// `f32` range sampler trips a debug assertion on some seeds (proptest 1.12, known upstream),
/// so float ranges are never used directly.
fn uf(lo: f32, hi: f32) -> impl Strategy<Value = f32> + Clone {
    (0u32..=1 << 24).prop_map(move |k| {
        let t = k as f32 / (1u32 << 24) as f32;
        (lo + (hi - lo) * t).clamp(lo, hi)
    })
}

/// `n` random control points scaled by `10^e`, weights in `[0.2, 5]`.
fn ctrl(n: std::ops::RangeInclusive<usize>) -> impl Strategy<Value = Ctrl> {
    (
        prop::collection::vec((uf(-1.0, 1.0), uf(-1.0, 1.0), uf(-1.0, 1.0), uf(0.2, 5.0)), n),
        -3i32..=3,
    )
        .prop_map(|(v, e)| {
            let s = 10f32.powi(e);
            Ctrl {
                x: v.iter().map(|c| c.0 * s).collect(),
                y: v.iter().map(|c| c.1 * s).collect(),
                z: v.iter().map(|c| c.2 * s).collect(),
                w: v.iter().map(|c| c.3).collect(),
            }
        })
}

fn curve_of(c: &Ctrl, kv: KnotVector) -> NurbsCurve {
    NurbsCurve::with_knots(c.x.clone(), c.y.clone(), c.z.clone(), c.w.clone(), kv).unwrap()
}

/// Clamped knots with random sorted interior knots (repeats allowed up to what f32 gives).
fn random_knots(n: usize, p: usize, mut interior: Vec<f32>) -> KnotVector {
    interior.truncate(n - p - 1);
    interior.sort_by(f32::total_cmp);
    let mut t = vec![0.0f32; p + 1];
    t.extend(interior);
    t.extend(vec![1.0f32; p + 1]);
    KnotVector::new(t, p, n).unwrap()
}

fn params() -> impl Strategy<Value = Vec<f32>> {
    prop::collection::vec(uf(0.0, 1.0), 1..24).prop_map(|mut v| {
        v.extend([0.0, 1.0]);
        v
    })
}

/// Largest coordinate difference (NaN counts as infinitely wrong).
fn max_err(a: [f32; 3], b: [f64; 3]) -> f64 {
    let mut m = 0.0f64;
    for i in 0..3 {
        let d = (a[i] as f64 - b[i]).abs();
        if d.is_nan() || d > m {
            m = d;
        }
    }
    m
}

proptest! {
    #[test]
    fn curve_global_equals_local(
        (p, c, interior, uniform) in (1usize..=5).prop_flat_map(|p| (
            Just(p), ctrl(p + 1..=64), prop::collection::vec(uf(0.001, 0.999), 64), any::<bool>()
        )),
        us in params(),
    ) {
        let n = c.x.len();
        let kv = if uniform {
            KnotVector::clamped_uniform(n, p).unwrap()
        } else {
            random_knots(n, p, interior)
        };
        let curve = curve_of(&c, kv);
        let tol = REL_TOL * c.scale();
        for &u in &us {
            let l = curve.eval_local(u).unwrap();
            let g = curve.eval_global(u).unwrap();
            prop_assert!(max_err(l, g) <= tol, "u={} local {:?} global {:?} tol {}", u, l, g, tol);
        }
    }

    #[test]
    fn surface_global_equals_local(
        (pu, pv, cu, c) in (1usize..=5, 1usize..=5).prop_flat_map(|(pu, pv)| (
            Just(pu), Just(pv), pu + 1..=64usize, Just(pv + 1..=64usize)
        )).prop_flat_map(|(pu, pv, rows, cols)| (
            Just(pu), Just(pv), Just(rows), cols.prop_flat_map(move |m| ctrl(rows * m..=rows * m))
        )),
        us in params(),
        vs in params(),
    ) {
        let rows = cu;
        let cols = c.x.len() / rows;
        let s = NurbsSurface::new(
            rows, cols, c.x.clone(), c.y.clone(), c.z.clone(), c.w.clone(), pu, pv,
        ).unwrap();
        let tol = REL_TOL * c.scale();
        let mut scratch = GlobalScratch::default();
        for (&u, &v) in us.iter().zip(vs.iter().rev()) {
            let l = s.eval_local(u, v).unwrap();
            let g = s.eval_global_with(u, v, &mut scratch).unwrap();
            prop_assert!(max_err(l, g) <= tol, "({},{}) local {:?} global {:?}", u, v, l, g);
        }
    }

    #[test]
    fn basis_is_partition_of_unity(
        (p, n, interior, uniform) in (0usize..=MAX_DEGREE).prop_flat_map(|p| (
            Just(p), p + 1..=80usize, prop::collection::vec(uf(0.0, 1.0), 80), any::<bool>()
        )),
        us in params(),
    ) {
        let kv = if uniform {
            KnotVector::clamped_uniform(n, p).unwrap()
        } else {
            random_knots(n, p, interior)
        };
        let mut g = Vec::new();
        let mut l = [0.0f32; MAX_ORDER];
        for &u in &us {
            basis_global(&kv, u, &mut g).unwrap();
            prop_assert_eq!(g.len(), n);
            prop_assert!(g.iter().all(|&v| v >= 0.0));
            prop_assert!((g.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            basis_local(&kv, u, &mut l).unwrap();
            prop_assert!(l[..=p].iter().all(|&v| v >= 0.0));
            let sum: f64 = l[..=p].iter().map(|&v| v as f64).sum();
            prop_assert!((sum - 1.0).abs() < 1e-5, "sum {}", sum);
        }
    }

    #[test]
    fn clamped_curve_interpolates_endpoints(
        (p, c) in (1usize..=5).prop_flat_map(|p| (Just(p), ctrl(p + 1..=64))),
    ) {
        let n = c.x.len();
        let curve = curve_of(&c, KnotVector::clamped_uniform(n, p).unwrap());
        let tol = REL_TOL * c.scale();
        for (u, i) in [(0.0f32, 0usize), (1.0, n - 1)] {
            let want = [c.x[i] as f64, c.y[i] as f64, c.z[i] as f64];
            let l = curve.eval_local(u).unwrap();
            prop_assert!(max_err(l, want) <= tol, "u={} {:?} vs {:?}", u, l, want);
            let g = curve.eval_global(u).unwrap();
            let ge = max_err([0.0; 3], [g[0] - want[0], g[1] - want[1], g[2] - want[2]]);
            prop_assert!(ge <= 1e-12 * c.scale());
        }
    }

    #[test]
    fn curve_batch_simd_equals_scalar_bitwise(
        (p, c) in (1usize..=5).prop_flat_map(|p| (Just(p), ctrl(p + 1..=64))),
        us in prop::collection::vec(uf(0.0, 1.0), 0..41),
    ) {
        let curve = curve_of(&c, KnotVector::clamped_uniform(c.x.len(), p).unwrap());
        let m = us.len();
        let (mut ax, mut ay, mut az) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
        let (mut bx, mut by, mut bz) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
        curve.eval_many(&us, &mut ax, &mut ay, &mut az).unwrap();
        curve.eval_many_scalar(&us, &mut bx, &mut by, &mut bz).unwrap();
        for i in 0..m {
            let a = [ax[i].to_bits(), ay[i].to_bits(), az[i].to_bits()];
            prop_assert_eq!(a, [bx[i].to_bits(), by[i].to_bits(), bz[i].to_bits()]);
            prop_assert_eq!(a, curve.eval_local(us[i]).unwrap().map(f32::to_bits));
        }
    }

    #[test]
    fn surface_grid_simd_equals_scalar_bitwise_and_global(
        (pu, pv, rows, c) in (1usize..=4, 1usize..=4).prop_flat_map(|(pu, pv)| (
            Just(pu), Just(pv), pu + 1..=40usize, pv + 1..=40usize
        )).prop_flat_map(|(pu, pv, rows, cols)| (
            Just(pu), Just(pv), Just(rows), ctrl(rows * cols..=rows * cols)
        )),
        us in prop::collection::vec(uf(0.0, 1.0), 0..6),
        vs in prop::collection::vec(uf(0.0, 1.0), 0..27),
    ) {
        let cols = c.x.len() / rows;
        let s = NurbsSurface::new(
            rows, cols, c.x.clone(), c.y.clone(), c.z.clone(), c.w.clone(), pu, pv,
        ).unwrap();
        let m = us.len() * vs.len();
        let (mut ax, mut ay, mut az) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
        let (mut bx, mut by, mut bz) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
        s.eval_grid(&us, &vs, &mut ax, &mut ay, &mut az).unwrap();
        s.eval_grid_scalar(&us, &vs, &mut bx, &mut by, &mut bz).unwrap();
        let tol = REL_TOL * c.scale();
        for (a, &u) in us.iter().enumerate() {
            for (b, &v) in vs.iter().enumerate() {
                let i = a * vs.len() + b;
                let got = [ax[i].to_bits(), ay[i].to_bits(), az[i].to_bits()];
                prop_assert_eq!(got, [bx[i].to_bits(), by[i].to_bits(), bz[i].to_bits()]);
                let g = s.eval_global(u, v).unwrap();
                prop_assert!(max_err([ax[i], ay[i], az[i]], g) <= tol, "({}, {})", u, v);
            }
        }
    }

    #[test]
    fn moving_one_control_point_changes_only_its_k_spans(
        (p, c, pick, d) in (1usize..=5).prop_flat_map(|p| (
            Just(p), ctrl(p + 1..=64), any::<prop::sample::Index>(), (uf(-1.0, 1.0), uf(0.1, 1.0))
        )),
    ) {
        let n = c.x.len();
        let mut curve = curve_of(&c, KnotVector::clamped_uniform(n, p).unwrap());
        let i = pick.index(n);
        let (lo, hi) = curve.influence(i).unwrap();
        let us: Vec<f32> = (0..=512).map(|j| j as f32 / 512.0).collect();
        let before: Vec<_> = us.iter().map(|&u| curve.eval_local(u).unwrap()).collect();
        let before_g: Vec<_> = us.iter().map(|&u| curve.eval_global(u).unwrap()).collect();
        let moved = [c.x[i] + d.0 * c.scale() as f32, c.y[i] + d.1 * c.scale() as f32, c.z[i]];
        curve.set_control_point(i, moved).unwrap();
        let mut changed_inside = false;
        for (j, &u) in us.iter().enumerate() {
            let after = curve.eval_local(u).unwrap();
            let outside = u < lo || u > hi || (u == hi && hi < 1.0);
            if outside {
                prop_assert_eq!(after, before[j], "u={} outside [{}, {}] moved", u, lo, hi);
                prop_assert_eq!(curve.eval_global(u).unwrap(), before_g[j]);
            } else if after != before[j] {
                changed_inside = true;
                // Paper's terms (formula 2.11): the point at span `now` is summed over control
                // points in [now - k, now + k]; the moved one is among the k = p + 1 of its span.
                let now = curve.knots().find_span(u).unwrap();
                prop_assert!(i + p >= now && i <= now, "u={} span {} moved by {}", u, now, i);
            }
        }
        prop_assert!(changed_inside, "moving control point {} changed nothing", i);
        // In the paper's terms: the support spans k = p + 1 knot spans.
        let t = curve.knots().knots();
        prop_assert_eq!((lo, hi), (t[i], t[i + p + 1]));
    }
}

#[test]
fn paper_verbatim_knots_make_the_last_control_point_inert() {
    // 6 control points, degree 2 (k = 3). Formula 2.9 as printed puts knot_n = 1.
    let n = 6;
    let x: Vec<f32> = (0..n).map(|i| i as f32).collect();
    let y: Vec<f32> = (0..n).map(|i| (i * i) as f32).collect();
    let z = vec![0.0; n];
    let w = vec![1.0; n];
    let paper = KnotVector::paper_verbatim(n, 2).unwrap();
    let mut g = Vec::new();
    for j in 0..=100 {
        basis_global(&paper, j as f32 / 100.0, &mut g).unwrap();
        assert_eq!(g[n - 1], 0.0, "N_n is identically zero");
    }
    let c = NurbsCurve::with_knots(x.clone(), y.clone(), z.clone(), w.clone(), paper).unwrap();
    let end = c.eval_global(1.0).unwrap();
    assert_eq!(end, [x[n - 2] as f64, y[n - 2] as f64, 0.0], "ends at P_(n-1)");
    let fixed = NurbsCurve::new(x.clone(), y.clone(), z, w, 2).unwrap();
    assert_eq!(fixed.eval_global(1.0).unwrap(), [x[n - 1] as f64, y[n - 1] as f64, 0.0]);
}

#[test]
fn bad_inputs_are_errors() {
    let v = |n: usize| vec![0.5f32; n];
    assert!(NurbsCurve::new(v(3), v(3), v(3), v(3), 3).is_err(), "degree >= n");
    assert!(NurbsCurve::new(vec![], vec![], vec![], vec![], 0).is_err(), "empty");
    assert!(NurbsCurve::new(v(3), v(3), v(2), v(3), 1).is_err(), "lengths");
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let mut w = v(4);
        w[2] = bad;
        assert!(NurbsCurve::new(v(4), v(4), v(4), w, 2).is_err(), "weight {bad}");
    }
    let mut x = v(4);
    x[1] = f32::NAN;
    assert!(NurbsCurve::new(x, v(4), v(4), v(4), 2).is_err());
    let mut c = NurbsCurve::new(v(4), v(4), v(4), v(4), 2).unwrap();
    for u in [-0.1, 1.1, f32::NAN, f32::INFINITY] {
        assert!(c.eval_local(u).is_err() && c.eval_global(u).is_err(), "u = {u}");
    }
    let (mut a, mut b, mut d) = (v(3), v(3), v(2));
    assert!(matches!(
        c.eval_many(&[0.1, 0.2, 0.3], &mut a, &mut b, &mut d),
        Err(WeftError::BufferLength { .. })
    ));
    let mut d3 = v(3);
    assert!(c.eval_many(&[0.1, 2.0, 0.3], &mut a, &mut b, &mut d3).is_err());
    assert_eq!(a, v(3), "nothing written on error");
    assert!(c.set_control_point(4, [0.0; 3]).is_err());
    assert!(c.set_control_point(0, [f32::NAN, 0.0, 0.0]).is_err());
    assert!(c.sample(1).is_err());
    assert!(NurbsCurve::strand(&[0.0], &[0.0], &[0.0], 3).is_err());

    assert!(NurbsSurface::new(2, 3, v(6), v(6), v(6), v(6), 2, 1).is_err(), "pu >= rows");
    assert!(NurbsSurface::new(2, 3, v(6), v(6), v(5), v(6), 1, 1).is_err());
    let s = NurbsSurface::new(2, 3, v(6), v(6), v(6), v(6), 1, 2).unwrap();
    assert!(s.eval_local(0.5, -0.5).is_err() && s.eval_global(f32::NAN, 0.5).is_err());
    let (mut a, mut b, mut d) = (v(4), v(4), v(3));
    assert!(s.eval_grid(&[0.0, 1.0], &[0.0, 1.0], &mut a, &mut b, &mut d).is_err());
    assert!(s.sample(1, 5).is_err());
    assert!(NurbsSurface::sheet(1, 4, &v(4), &v(4), &v(4), 3).is_err());
}
