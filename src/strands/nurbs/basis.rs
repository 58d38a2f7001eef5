//! B-spline basis functions by the Cox–de Boor recursion, globally and locally.
//!
//! The recursion (paper formula 2.7, written with degree `p` instead of order `k = p + 1`):
//!
//! ```text
//! N_{i,0}(u) = 1 if t_i <= u < t_{i+1}, else 0
//! N_{i,p}(u) = (u - t_i)/(t_{i+p} - t_i) N_{i,p-1}(u)
//!            + (t_{i+p+1} - u)/(t_{i+p+1} - t_{i+1}) N_{i+1,p-1}(u)      (0/0 := 0)
//! ```
//!
//! [`basis_global`] evaluates all `n_ctrl` functions this way, level by level, in `f64`: the
//! reference, `O(n p)` per point. Since `N_{i,p}` vanishes outside `[t_i, t_{i+p+1})`, only the
//! `p + 1` functions `N_{s-p} ..= N_s` are non-zero on the span `[t_s, t_{s+1})` that holds
//! `u`. [`basis_local`] finds `s` (directly for the clamped uniform vector, by binary search
//! for any other) and computes just those with the triangular scheme (Piegl & Tiller, *The
//! NURBS Book*, A2.2): `O(p^2)` per point, independent of `n` (plus `O(log n)` for the search
//! when the knots are not uniform).
//! This is the paper's "local evaluation" (formula 2.11): it sums over `[now - k, now + k]`,
//! a window that contains the `k` non-zero terms; the others are exactly zero.

use super::knots::{KnotVector, MAX_DEGREE};
use crate::Result;

/// Number of basis values the local scheme may return (`MAX_DEGREE + 1`).
pub const MAX_ORDER: usize = MAX_DEGREE + 1;

/// Reusable work space for the global (reference) evaluators, so that repeated calls do not
/// allocate. `Default` gives an empty one; it grows on first use.
#[derive(Clone, Debug, Default)]
pub struct GlobalScratch {
    pub(crate) nu: Vec<f64>,
    pub(crate) nv: Vec<f64>,
}

/// Evaluates every basis function `N_{i,p}(u)`, `i = 0 .. n_ctrl`, in `f64` by the plain
/// Cox–de Boor recursion. On return `out` holds exactly `n_ctrl` values (it is reused as work
/// space, so passing the same vector again avoids allocation).
///
/// At the right end of the domain, `u = t_{n_ctrl}`, the last non-empty span counts as closed,
/// so the clamped curve ends at its last control point. Errors if `u` is outside the domain.
pub fn basis_global(kv: &KnotVector, u: f32, out: &mut Vec<f64>) -> Result<()> {
    kv.check_param("u", u)?;
    let kn = kv.knots();
    let t = |i: usize| kn[i] as f64;
    let p = kv.degree();
    let n = kv.n_ctrl();
    let uu = u as f64;
    let m = kn.len() - 1; // number of degree-0 functions
    out.clear();
    out.resize(m, 0.0);
    // Degree 0: the indicator of the span holding u. A linear scan, independent of the binary
    // search used by the local scheme: the last non-empty span of the domain starting at or
    // before u (that is the span containing u, or the closed last span at the right end).
    let mut span = p;
    for i in p..n {
        if t(i) < t(i + 1) && t(i) <= uu {
            span = i;
        }
    }
    out[span] = 1.0;
    for d in 1..=p {
        for i in 0..m - d {
            let a = t(i + d) - t(i);
            let b = t(i + d + 1) - t(i + 1);
            let left = if a > 0.0 { (uu - t(i)) / a * out[i] } else { 0.0 };
            let right = if b > 0.0 { (t(i + d + 1) - uu) / b * out[i + 1] } else { 0.0 };
            out[i] = left + right;
        }
    }
    out.truncate(n);
    Ok(())
}

/// The `p + 1` non-zero basis values at `u`: returns the span `s`, and `out[r]` holds
/// `N_{s-p+r,p}(u)` for `r = 0 ..= p`. Errors if `u` is outside the domain.
pub fn basis_local(kv: &KnotVector, u: f32, out: &mut [f32; MAX_ORDER]) -> Result<usize> {
    let s = kv.find_span(u)?;
    basis_in_span(kv.knots(), kv.degree(), s, u, out);
    Ok(s)
}

/// The triangular scheme for a known span `s` (with `t_s < t_{s+1}`), in `f32`.
///
/// The arithmetic order here is the contract the SIMD batch kernels copy lane by lane, so that
/// they agree with this function bit for bit. Every denominator `right[r+1] + left[j-r]` equals
/// `t_{s+r+1} - t_{s+r+1-j}`, an interval that contains the non-empty span, so it is positive.
#[inline]
pub(crate) fn basis_in_span(t: &[f32], p: usize, s: usize, u: f32, out: &mut [f32; MAX_ORDER]) {
    let mut left = [0.0f32; MAX_ORDER];
    let mut right = [0.0f32; MAX_ORDER];
    out[0] = 1.0;
    for j in 1..=p {
        left[j] = u - t[s + 1 - j];
        right[j] = t[s + j] - u;
        let mut saved = 0.0f32;
        for r in 0..j {
            let temp = out[r] / (right[r + 1] + left[j - r]);
            out[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        out[j] = saved;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_basis_is_hat_functions() {
        // Degree 1 on 3 control points: knots 0 0 .5 1 1; hats peaking at 0, .5, 1.
        let kv = KnotVector::clamped_uniform(3, 1).unwrap();
        let mut g = Vec::new();
        basis_global(&kv, 0.25, &mut g).unwrap();
        assert_eq!(g, vec![0.5, 0.5, 0.0]);
        basis_global(&kv, 1.0, &mut g).unwrap();
        assert_eq!(g, vec![0.0, 0.0, 1.0]);
        let mut l = [0.0; MAX_ORDER];
        let s = basis_local(&kv, 0.75, &mut l).unwrap();
        assert_eq!((s, l[0], l[1]), (2, 0.5, 0.5));
    }

    #[test]
    fn local_matches_global_on_span_and_global_vanishes_elsewhere() {
        let kv = KnotVector::clamped_uniform(12, 4).unwrap();
        let mut g = Vec::new();
        let mut l = [0.0; MAX_ORDER];
        for i in 0..=200 {
            let u = i as f32 / 200.0;
            basis_global(&kv, u, &mut g).unwrap();
            let s = basis_local(&kv, u, &mut l).unwrap();
            for (idx, &gv) in g.iter().enumerate() {
                if idx + 4 >= s && idx <= s {
                    let lv = l[idx + 4 - s] as f64;
                    assert!((gv - lv).abs() < 1e-6, "u={u} i={idx} {gv} vs {lv}");
                } else {
                    assert_eq!(gv, 0.0, "u={u} i={idx} outside the span");
                }
            }
        }
    }

    #[test]
    fn bad_parameter_is_an_error() {
        let kv = KnotVector::clamped_uniform(4, 2).unwrap();
        let mut g = Vec::new();
        let mut l = [0.0; MAX_ORDER];
        assert!(basis_global(&kv, 1.5, &mut g).is_err());
        assert!(basis_local(&kv, f32::NAN, &mut l).is_err());
        assert!(basis_local(&kv, -0.0, &mut l).is_ok());
    }
}
