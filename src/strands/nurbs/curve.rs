//! NURBS curves (paper formula 2.5/2.8): `C(u) = Σ N_{i,p}(u) w_i P_i / Σ N_{i,p}(u) w_i`.
//!
//! Control points are stored as structure of arrays (`x`, `y`, `z`, `w`). The global
//! evaluator sums over all control points in `f64` (the reference); the local one sums only
//! the `p + 1` control points of the span holding `u`, in `f32` (formula 2.11).

use super::basis::{basis_global, basis_in_span, GlobalScratch, MAX_ORDER};
use super::knots::KnotVector;
use crate::{Result, WeftError};

/// A NURBS curve in 3-D with SoA control points, positive weights and a validated knot vector.
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsCurve {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    w: Vec<f32>,
    knots: KnotVector,
}

/// Checks SoA control arrays: all of length `n`, finite coordinates, finite positive weights.
pub(crate) fn check_control(x: &[f32], y: &[f32], z: &[f32], w: &[f32], n: usize) -> Result<()> {
    for (name, a) in [("x", x), ("y", y), ("z", z), ("weights", w)] {
        if a.len() != n {
            return Err(WeftError::BufferLength {
                name,
                got: a.len(),
                expected: n,
            });
        }
    }
    for (name, a) in [("x", x), ("y", y), ("z", z)] {
        if let Some(i) = a.iter().position(|v| !v.is_finite()) {
            return Err(WeftError::param(
                format!("{name}[{i}]"),
                a[i],
                "control point coordinates must be finite",
            ));
        }
    }
    if let Some(i) = w.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(WeftError::param(
            format!("weights[{i}]"),
            w[i],
            "weights must be finite and greater than zero",
        ));
    }
    Ok(())
}

impl NurbsCurve {
    /// A curve of the given degree over the control points, with the clamped uniform knot
    /// vector on `[0, 1]`. Errors on empty or unequal arrays, non-finite coordinates,
    /// non-positive or NaN weights, and `degree >= number of control points`.
    pub fn new(x: Vec<f32>, y: Vec<f32>, z: Vec<f32>, w: Vec<f32>, degree: usize) -> Result<Self> {
        let knots = KnotVector::clamped_uniform(x.len(), degree)?;
        Self::with_knots(x, y, z, w, knots)
    }

    /// A curve with a given knot vector (whose degree and control count must fit the arrays).
    pub fn with_knots(x: Vec<f32>, y: Vec<f32>, z: Vec<f32>, w: Vec<f32>, knots: KnotVector) -> Result<Self> {
        check_control(&x, &y, &z, &w, knots.n_ctrl())?;
        Ok(Self { x, y, z, w, knots })
    }

    /// Number of control points.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Always false: a curve has at least `degree + 1 >= 1` control points.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Polynomial degree `p`.
    pub fn degree(&self) -> usize {
        self.knots.degree()
    }

    /// The paper's order `k = p + 1`.
    pub fn order(&self) -> usize {
        self.knots.degree() + 1
    }

    /// The knot vector.
    pub fn knots(&self) -> &KnotVector {
        &self.knots
    }

    /// Control point x coordinates.
    pub fn x(&self) -> &[f32] {
        &self.x
    }

    /// Control point y coordinates.
    pub fn y(&self) -> &[f32] {
        &self.y
    }

    /// Control point z coordinates.
    pub fn z(&self) -> &[f32] {
        &self.z
    }

    /// Weights.
    pub fn weights(&self) -> &[f32] {
        &self.w
    }

    /// Moves control point `i` (e.g. after a simulation step). Only the curve on
    /// [`NurbsCurve::influence`]`(i)` changes.
    pub fn set_control_point(&mut self, i: usize, p: [f32; 3]) -> Result<()> {
        if i >= self.len() {
            return Err(WeftError::IndexOutOfRange {
                name: "control point",
                index: i,
                len: self.len(),
            });
        }
        crate::error::finite3("control point", p)?;
        self.x[i] = p[0];
        self.y[i] = p[1];
        self.z[i] = p[2];
        Ok(())
    }

    /// The parameter interval `[t_i, t_{i+p+1}]` outside which control point `i` has no
    /// effect: `p + 1 = k` knot spans, the local support the paper exploits.
    pub fn influence(&self, i: usize) -> Result<(f32, f32)> {
        if i >= self.len() {
            return Err(WeftError::IndexOutOfRange {
                name: "control point",
                index: i,
                len: self.len(),
            });
        }
        let t = self.knots.knots();
        Ok((t[i], t[i + self.degree() + 1]))
    }

    /// Reference evaluation (formula 2.8): all basis functions by Cox–de Boor, the rational
    /// sum over all control points, everything in `f64`. `O(n p)` per point.
    pub fn eval_global(&self, u: f32) -> Result<[f64; 3]> {
        self.eval_global_with(u, &mut GlobalScratch::default())
    }

    /// [`NurbsCurve::eval_global`] reusing `scratch` to avoid allocation.
    pub fn eval_global_with(&self, u: f32, scratch: &mut GlobalScratch) -> Result<[f64; 3]> {
        basis_global(&self.knots, u, &mut scratch.nu)?;
        let (mut sx, mut sy, mut sz, mut sw) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for (i, &n) in scratch.nu.iter().enumerate() {
            let nw = n * self.w[i] as f64;
            sx += nw * self.x[i] as f64;
            sy += nw * self.y[i] as f64;
            sz += nw * self.z[i] as f64;
            sw += nw;
        }
        Ok([sx / sw, sy / sw, sz / sw])
    }

    /// Local evaluation (formula 2.11): only the `p + 1` control points of the span holding
    /// `u`, in `f32`. `O(p^2)` per point whatever the number of control points. Errors if `u`
    /// is not finite or outside `[0, 1]` (the domain).
    pub fn eval_local(&self, u: f32) -> Result<[f32; 3]> {
        let s = self.knots.find_span(u)?;
        Ok(self.eval_in_span(s, u))
    }

    /// The local sum for a known span; the arithmetic order the SIMD batch copies.
    #[inline]
    pub(crate) fn eval_in_span(&self, s: usize, u: f32) -> [f32; 3] {
        let p = self.degree();
        let mut n = [0.0f32; MAX_ORDER];
        basis_in_span(self.knots.knots(), p, s, u, &mut n);
        let (mut sx, mut sy, mut sz, mut sw) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for (r, &nr) in n.iter().enumerate().take(p + 1) {
            let i = s - p + r;
            let nw = nr * self.w[i];
            sx += nw * self.x[i];
            sy += nw * self.y[i];
            sz += nw * self.z[i];
            sw += nw;
        }
        [sx / sw, sy / sw, sz / sw]
    }
}
