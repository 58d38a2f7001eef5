//! NURBS surfaces (paper formula 2.6/2.9):
//! `S(u,v) = Σ_i Σ_j N_{i,pu}(u) N_{j,pv}(v) w_ij P_ij / Σ_i Σ_j N_{i,pu}(u) N_{j,pv}(v) w_ij`.
//!
//! The control grid has `rows` points along `u` and `cols` along `v`, stored row-major in SoA
//! arrays: point `(i, j)` is at index `i * cols + j`. The global evaluator sums over the whole
//! grid in `f64`, `O(rows * cols)` per point; the local one (formula 2.12) sums the
//! `(pu + 1)(pv + 1)` points of the span pair holding `(u, v)`, in `f32`.

use super::basis::{basis_global, basis_in_span, GlobalScratch, MAX_ORDER};
use super::curve::check_control;
use super::knots::KnotVector;
use crate::{Result, WeftError};

/// A tensor-product NURBS surface with SoA control grid and two validated knot vectors.
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsSurface {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    w: Vec<f32>,
    ku: KnotVector,
    kv: KnotVector,
}

impl NurbsSurface {
    /// A surface over a `rows x cols` control grid (row-major SoA) with clamped uniform knot
    /// vectors of degrees `degree_u` (along rows) and `degree_v` (along columns). Errors on
    /// empty grids, arrays whose length is not `rows * cols`, non-finite coordinates,
    /// non-positive or NaN weights, and a degree not below its grid dimension.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        rows: usize,
        cols: usize,
        x: Vec<f32>,
        y: Vec<f32>,
        z: Vec<f32>,
        w: Vec<f32>,
        degree_u: usize,
        degree_v: usize,
    ) -> Result<Self> {
        let ku = KnotVector::clamped_uniform(rows, degree_u)?;
        let kv = KnotVector::clamped_uniform(cols, degree_v)?;
        Self::with_knots(x, y, z, w, ku, kv)
    }

    /// A surface with given knot vectors; the grid is `ku.n_ctrl() x kv.n_ctrl()`.
    pub fn with_knots(x: Vec<f32>, y: Vec<f32>, z: Vec<f32>, w: Vec<f32>, ku: KnotVector, kv: KnotVector) -> Result<Self> {
        let n = ku
            .n_ctrl()
            .checked_mul(kv.n_ctrl())
            .ok_or_else(|| WeftError::param("grid", "rows * cols", "too many control points"))?;
        check_control(&x, &y, &z, &w, n)?;
        Ok(Self { x, y, z, w, ku, kv })
    }

    /// Control points along `u`.
    pub fn rows(&self) -> usize {
        self.ku.n_ctrl()
    }

    /// Control points along `v`.
    pub fn cols(&self) -> usize {
        self.kv.n_ctrl()
    }

    /// Degrees `(pu, pv)`.
    pub fn degrees(&self) -> (usize, usize) {
        (self.ku.degree(), self.kv.degree())
    }

    /// Knot vector along `u`.
    pub fn knots_u(&self) -> &KnotVector {
        &self.ku
    }

    /// Knot vector along `v`.
    pub fn knots_v(&self) -> &KnotVector {
        &self.kv
    }

    /// Control point coordinates and weights, row-major: `(x, y, z, w)`.
    pub fn control(&self) -> (&[f32], &[f32], &[f32], &[f32]) {
        (&self.x, &self.y, &self.z, &self.w)
    }

    /// Moves control point `(i, j)`; only `influence_u(i) x influence_v(j)` changes.
    pub fn set_control_point(&mut self, i: usize, j: usize, p: [f32; 3]) -> Result<()> {
        if i >= self.rows() || j >= self.cols() {
            return Err(WeftError::IndexOutOfRange {
                name: "control point (row-major)",
                index: i.saturating_mul(self.cols()).saturating_add(j),
                len: self.x.len(),
            });
        }
        crate::error::finite3("control point", p)?;
        let k = i * self.cols() + j;
        [self.x[k], self.y[k], self.z[k]] = p;
        Ok(())
    }

    /// Reference evaluation (formula 2.9): full Cox–de Boor in both directions and the double
    /// sum over the whole grid, in `f64`.
    pub fn eval_global(&self, u: f32, v: f32) -> Result<[f64; 3]> {
        self.eval_global_with(u, v, &mut GlobalScratch::default())
    }

    /// [`NurbsSurface::eval_global`] reusing `scratch`.
    pub fn eval_global_with(&self, u: f32, v: f32, scratch: &mut GlobalScratch) -> Result<[f64; 3]> {
        basis_global(&self.ku, u, &mut scratch.nu)?;
        basis_global(&self.kv, v, &mut scratch.nv)?;
        let cols = self.cols();
        let (mut sx, mut sy, mut sz, mut sw) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for (i, &nu) in scratch.nu.iter().enumerate() {
            for (j, &nv) in scratch.nv.iter().enumerate() {
                let k = i * cols + j;
                let nw = nu * nv * self.w[k] as f64;
                sx += nw * self.x[k] as f64;
                sy += nw * self.y[k] as f64;
                sz += nw * self.z[k] as f64;
                sw += nw;
            }
        }
        Ok([sx / sw, sy / sw, sz / sw])
    }

    /// Local evaluation (formula 2.12): only the `(pu+1)(pv+1)` control points of the span
    /// pair, in `f32`. Errors if `u` or `v` is not finite or outside `[0, 1]`.
    pub fn eval_local(&self, u: f32, v: f32) -> Result<[f32; 3]> {
        let su = self.ku.find_span(u)?;
        let sv = self.kv.find_span(v)?;
        let (pu, pv) = self.degrees();
        let mut nu = [0.0f32; MAX_ORDER];
        let mut nv = [0.0f32; MAX_ORDER];
        basis_in_span(self.ku.knots(), pu, su, u, &mut nu);
        basis_in_span(self.kv.knots(), pv, sv, v, &mut nv);
        Ok(self.sum_in_span(su, &nu, sv, &nv))
    }

    /// The local tensor sum given both spans and basis values; the arithmetic order that the
    /// SIMD grid kernel copies: `nw = (Nu * Nv) * w`, accumulate row by row.
    #[inline]
    pub(crate) fn sum_in_span(&self, su: usize, nu: &[f32; MAX_ORDER], sv: usize, nv: &[f32; MAX_ORDER]) -> [f32; 3] {
        let (pu, pv) = self.degrees();
        let cols = self.cols();
        let (mut sx, mut sy, mut sz, mut sw) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for (r, &a) in nu.iter().enumerate().take(pu + 1) {
            let row = (su - pu + r) * cols;
            for (c, &b) in nv.iter().enumerate().take(pv + 1) {
                let k = row + sv - pv + c;
                let nw = a * b * self.w[k];
                sx += nw * self.x[k];
                sy += nw * self.y[k];
                sz += nw * self.z[k];
                sw += nw;
            }
        }
        [sx / sw, sy / sw, sz / sw]
    }
}
