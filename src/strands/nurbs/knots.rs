//! Knot vectors: the clamped uniform vector, the paper's formula as printed, and validation.
//!
//! A B-spline of degree `p` (order `k = p + 1`) over `n_ctrl` control points needs
//! `n_ctrl + p + 1` non-decreasing knots `t_0 ..= t_{n_ctrl + p}`. The curve is defined on the
//! domain `[t_p, t_{n_ctrl}]`; "clamped" means the first and last knots are repeated `k`
//! times so that the curve starts at the first control point and ends at the last.
//!
//! # Index mapping to the paper (the NURBS thesis, formula 2.9)
//! The paper counts `n + 1` control points `P_0 ..= P_n` and uses the *order* `k` (its
//! `N_{i,1}` is the piecewise-constant basis), so `n = n_ctrl - 1` and `k = p + 1`. Its knot
//! formula is
//!
//! ```text
//! knot_i = 0                      for 0 <= i < k
//! knot_i = (i - k + 1)/(n - k + 1) for k <= i <= n
//! knot_i = 1                      for n < i <= n + k
//! ```
//!
//! With that denominator `knot_n = 1`, so `1` appears `k + 1` times and the last basis function
//! `N_{n,k}` has the empty support `[1, 1]`: the last control point never influences the
//! curve, which ends at `P_{n-1}`. [`KnotVector::paper_verbatim`] builds exactly this vector so
//! the defect can be shown (see the tests). The textbook open-uniform vector (Hearn & Baker)
//! has denominator `n - k + 2`; in our indices that is
//!
//! ```text
//! t_i = 0                    for i <= p
//! t_i = (i - p)/(n_ctrl - p) for p < i < n_ctrl
//! t_i = 1                    for i >= n_ctrl
//! ```
//!
//! which [`KnotVector::clamped_uniform`] builds and every constructor of weft uses by default.

use crate::{Result, WeftError};

/// Largest degree accepted. Local evaluation keeps `MAX_DEGREE + 1` basis values on the stack;
/// degrees this high are numerically pointless for strands and sheets anyway.
pub const MAX_DEGREE: usize = 15;

/// Largest number of control points per direction (2^30): far beyond any strand or sheet, and
/// it keeps every index computation free of overflow.
pub const MAX_CONTROL: usize = 1 << 30;

/// A validated knot vector for a given degree and number of control points.
#[derive(Clone, Debug, PartialEq)]
pub struct KnotVector {
    knots: Vec<f32>,
    degree: usize,
    n_ctrl: usize,
    /// The knots are exactly [`KnotVector::clamped_uniform`]'s: the span is found in O(1).
    uniform: bool,
}

/// The clamped uniform knot values (see the module docs).
fn clamped_values(n_ctrl: usize, degree: usize) -> Vec<f32> {
    let spans = (n_ctrl - degree) as f64;
    (0..n_ctrl + degree + 1)
        .map(|i| {
            if i <= degree {
                0.0
            } else if i >= n_ctrl {
                1.0
            } else {
                ((i - degree) as f64 / spans) as f32
            }
        })
        .collect()
}

fn check_shape(n_ctrl: usize, degree: usize) -> Result<()> {
    if n_ctrl == 0 {
        return Err(WeftError::param("control points", 0, "at least one control point is needed"));
    }
    if n_ctrl > MAX_CONTROL {
        return Err(WeftError::param(
            "control points",
            n_ctrl,
            format!("at most {MAX_CONTROL} per direction"),
        ));
    }
    if degree > MAX_DEGREE {
        return Err(WeftError::param("degree", degree, format!("must be at most {MAX_DEGREE}")));
    }
    if degree >= n_ctrl {
        return Err(WeftError::param(
            "degree",
            degree,
            format!("must be less than the number of control points ({n_ctrl})"),
        ));
    }
    Ok(())
}

impl KnotVector {
    /// Checks and wraps a user-given knot vector: `n_ctrl + degree + 1` finite, non-decreasing
    /// values whose domain `[t_degree, t_n_ctrl]` has positive length.
    pub fn new(knots: Vec<f32>, degree: usize, n_ctrl: usize) -> Result<Self> {
        check_shape(n_ctrl, degree)?;
        let expected = n_ctrl + degree + 1;
        if knots.len() != expected {
            return Err(WeftError::BufferLength {
                name: "knots",
                got: knots.len(),
                expected,
            });
        }
        if let Some(i) = knots.iter().position(|t| !t.is_finite()) {
            return Err(WeftError::param(format!("knots[{i}]"), knots[i], "must be a finite number"));
        }
        if let Some(i) = knots.windows(2).position(|w| w[1] < w[0]) {
            return Err(WeftError::param(
                format!("knots[{}]", i + 1),
                knots[i + 1],
                format!("knots must be non-decreasing (previous is {})", knots[i]),
            ));
        }
        if knots[degree] >= knots[n_ctrl] {
            return Err(WeftError::param(
                "knots",
                format!("[{}, {}]", knots[degree], knots[n_ctrl]),
                "the domain [t_degree, t_n_ctrl] must have positive length",
            ));
        }
        let uniform = knots == clamped_values(n_ctrl, degree);
        Ok(Self {
            knots,
            degree,
            n_ctrl,
            uniform,
        })
    }

    /// The clamped (open) uniform knot vector on `[0, 1]`: `degree + 1` zeros, equally spaced
    /// interior knots, `degree + 1` ones. The curve interpolates its first and last control
    /// points.
    pub fn clamped_uniform(n_ctrl: usize, degree: usize) -> Result<Self> {
        check_shape(n_ctrl, degree)?;
        Self::new(clamped_values(n_ctrl, degree), degree, n_ctrl)
    }

    /// The paper's formula 2.9 exactly as printed (order `k = degree + 1`, `n = n_ctrl - 1`,
    /// denominator `n - k + 1`). Kept to reproduce the paper; its last control point has no
    /// influence (see the module docs). Use [`KnotVector::clamped_uniform`] for real work.
    pub fn paper_verbatim(n_ctrl: usize, degree: usize) -> Result<Self> {
        check_shape(n_ctrl, degree)?;
        let k = degree + 1;
        let n = n_ctrl - 1;
        let knots = (0..=n + k)
            .map(|i| {
                if i < k {
                    0.0
                } else if i <= n {
                    // k <= i <= n implies n - k + 1 >= 1: no division by zero.
                    ((i - k + 1) as f64 / (n - k + 1) as f64) as f32
                } else {
                    1.0
                }
            })
            .collect();
        Self::new(knots, degree, n_ctrl)
    }

    /// The knot values `t_0 ..= t_{n_ctrl + degree}`.
    pub fn knots(&self) -> &[f32] {
        &self.knots
    }

    /// Polynomial degree `p` (the paper's order is `p + 1`).
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Number of control points this vector serves.
    pub fn n_ctrl(&self) -> usize {
        self.n_ctrl
    }

    /// Parameter domain `[t_p, t_{n_ctrl}]` (`[0, 1]` for the clamped vectors).
    pub fn domain(&self) -> (f32, f32) {
        (self.knots[self.degree], self.knots[self.n_ctrl])
    }

    /// Checks that `u` is finite and inside the domain. Parameters outside are an error, not
    /// clamped: a value outside `[0, 1]` is almost always a bug in the caller.
    pub fn check_param(&self, name: &str, u: f32) -> Result<()> {
        let (a, b) = self.domain();
        if u.is_finite() && u >= a && u <= b {
            Ok(())
        } else {
            Err(WeftError::param(
                name,
                u,
                format!("must be a finite number in the domain [{a}, {b}]"),
            ))
        }
    }

    /// The knot span `s` with `t_s <= u < t_{s+1}` and `degree <= s < n_ctrl` (at the right end
    /// of the domain, the last non-empty span): computed directly for the clamped uniform
    /// vector, by binary search otherwise. Errors if `u` is outside the domain or not finite.
    pub fn find_span(&self, u: f32) -> Result<usize> {
        self.check_param("u", u)?;
        Ok(self.span_unchecked(u))
    }

    /// [`KnotVector::find_span`] for a `u` already known to be in the domain. For the clamped
    /// uniform vector the span is computed directly, `s = p + floor(u (n_ctrl - p))`, then
    /// corrected by a step if the rounding of the `f32` knots disagrees: O(1), so local
    /// evaluation costs the same for any number of control points. Otherwise binary search.
    #[inline]
    pub(crate) fn span_unchecked(&self, u: f32) -> usize {
        if !self.uniform {
            return self.span_search(u);
        }
        let (p, n, t) = (self.degree, self.n_ctrl, &self.knots);
        let spans = n - p;
        let mut s = p + ((u as f64 * spans as f64) as usize).min(spans - 1);
        while s > p && t[s] > u {
            s -= 1;
        }
        while s + 1 < n && t[s + 1] <= u {
            s += 1;
        }
        s
    }

    /// The span by binary search; any valid knot vector.
    #[inline]
    fn span_search(&self, u: f32) -> usize {
        let p = self.degree;
        // Number of knots t_{p+1} .. t_{n_ctrl-1} that are <= u: the last span starting at or
        // before u. t_{p+1..n_ctrl} is sorted, so partition_point is a binary search.
        p + self.knots[p + 1..self.n_ctrl].partition_point(|&t| t <= u)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamped_uniform_matches_textbook_values() {
        let kv = KnotVector::clamped_uniform(5, 2).unwrap();
        assert_eq!(kv.knots(), &[0.0, 0.0, 0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0, 1.0, 1.0]);
        assert_eq!(kv.domain(), (0.0, 1.0));
        let bez = KnotVector::clamped_uniform(4, 3).unwrap();
        assert_eq!(bez.knots(), &[0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0]);
    }

    #[test]
    fn paper_verbatim_repeats_one_k_plus_one_times() {
        // n = 4 (5 control points), k = 3 (degree 2): denominator n - k + 1 = 2.
        let kv = KnotVector::paper_verbatim(5, 2).unwrap();
        assert_eq!(kv.knots(), &[0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 1.0]);
        let ones = kv.knots().iter().filter(|&&t| t == 1.0).count();
        assert_eq!(ones, 2 + 2, "k + 1 ones");
    }

    #[test]
    fn validation_rejects_bad_vectors() {
        assert!(KnotVector::new(vec![0.0, 0.0, 1.0, 1.0], 1, 2).is_ok());
        assert!(matches!(
            KnotVector::new(vec![0.0, 0.0, 1.0], 1, 2),
            Err(WeftError::BufferLength { .. })
        ));
        assert!(KnotVector::new(vec![0.0, 0.5, 0.4, 1.0], 1, 2).is_err());
        assert!(KnotVector::new(vec![0.0, f32::NAN, 1.0, 1.0], 1, 2).is_err());
        assert_eq!(KnotVector::new(vec![-1.0, 0.0, 2.0, 3.0], 1, 2).unwrap().domain(), (0.0, 2.0));
        assert!(KnotVector::new(vec![0.0, 0.5, 0.5, 1.0], 1, 2).is_err(), "empty domain");
        assert!(KnotVector::clamped_uniform(3, 3).is_err(), "degree >= n_ctrl");
        assert!(KnotVector::clamped_uniform(0, 0).is_err());
        assert!(KnotVector::clamped_uniform(40, MAX_DEGREE + 1).is_err());
        assert!(KnotVector::clamped_uniform(usize::MAX, 3).is_err());
        assert!(KnotVector::new(vec![0.0, 1.0], 1, usize::MAX).is_err());
    }

    #[test]
    fn span_search_finds_containing_span() {
        let kv = KnotVector::clamped_uniform(7, 3).unwrap();
        let t = kv.knots();
        for i in 0..=1000 {
            let u = i as f32 / 1000.0;
            let s = kv.find_span(u).unwrap();
            assert!((3..7).contains(&s));
            assert!(t[s] <= u && (u < t[s + 1] || (u == 1.0 && s == 6)), "u={u} s={s}");
        }
        assert!(kv.find_span(-0.001).is_err());
        assert!(kv.uniform);
        assert!(!KnotVector::paper_verbatim(7, 3).unwrap().uniform);
        assert!(kv.find_span(1.001).is_err());
        assert!(kv.find_span(f32::NAN).is_err());
    }

    #[test]
    fn direct_span_of_uniform_vector_equals_binary_search() {
        for (n, p) in [(2, 1), (7, 3), (64, 5), (1000, 2), (4096, 3), (4099, 15)] {
            let kv = KnotVector::clamped_uniform(n, p).unwrap();
            let mut us: Vec<f32> = (0..=2000).map(|i| i as f32 / 2000.0).collect();
            for &t in kv.knots() {
                us.extend([t, f32::from_bits(t.to_bits().saturating_sub(1)), t.next_up()]);
            }
            for u in us.into_iter().filter(|u| (0.0..=1.0).contains(u)) {
                assert_eq!(kv.span_unchecked(u), kv.span_search(u), "n={n} p={p} u={u}");
            }
        }
    }
}
