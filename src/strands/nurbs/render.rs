//! Smooth curves and sheets drawn over simulated particles (the paper draws strands and cloth
//! as NURBS whose control points are the simulated points, SEEDS.md B / AHS last step).
//!
//! The particles become the control points, with unit weights and the clamped uniform knot
//! vector. The curve therefore passes *through* the first and last particle (a strand's root
//! and tip) and runs *near* the others: it stays in the convex hull of every `p + 1`
//! consecutive particles and smooths the polyline's corners (it does not interpolate interior
//! particles; a degree-1 curve is the polyline itself). Sampling evaluates the curve or
//! surface with the SIMD batch kernels at equally spaced parameters.

use super::curve::NurbsCurve;
use super::surface::NurbsSurface;
use crate::{Result, WeftError};

/// Dense points along a curve, SoA.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CurveSamples {
    /// x coordinates.
    pub x: Vec<f32>,
    /// y coordinates.
    pub y: Vec<f32>,
    /// z coordinates.
    pub z: Vec<f32>,
}

/// A triangle mesh sampled from a surface: SoA positions and counter-clockwise triangles
/// (seen with `u` pointing right and `v` up).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceMesh {
    /// x coordinates, row-major `ru x rv`.
    pub x: Vec<f32>,
    /// y coordinates.
    pub y: Vec<f32>,
    /// z coordinates.
    pub z: Vec<f32>,
    /// Vertex indices, two triangles per grid quad.
    pub triangles: Vec<[u32; 3]>,
}

/// `count >= 2` equally spaced parameters on `[0, 1]`, with both ends exact.
fn params(name: &str, count: usize) -> Result<Vec<f32>> {
    if count < 2 {
        return Err(WeftError::param(
            name,
            count,
            "at least 2 samples are needed",
        ));
    }
    let last = (count - 1) as f64;
    Ok((0..count).map(|i| (i as f64 / last) as f32).collect())
}

/// Degree actually used for `n` points: `min(max_degree, n - 1)`.
fn fit_degree(name: &str, n: usize, max_degree: usize) -> Result<usize> {
    if n < 2 {
        return Err(WeftError::param(name, n, "at least 2 points are needed"));
    }
    Ok(max_degree.min(n - 1))
}

impl NurbsCurve {
    /// A smooth strand through its end particles and near the others: the particles
    /// (`x[i], y[i], z[i]`, root first) are the control points, weights are 1, the degree is
    /// `min(max_degree, n - 1)` so short strands still work. Errors on fewer than 2 points,
    /// unequal lengths or non-finite coordinates.
    pub fn strand(x: &[f32], y: &[f32], z: &[f32], max_degree: usize) -> Result<Self> {
        let degree = fit_degree("strand points", x.len(), max_degree)?;
        NurbsCurve::new(
            x.to_vec(),
            y.to_vec(),
            z.to_vec(),
            vec![1.0; x.len()],
            degree,
        )
    }

    /// `count >= 2` points at equally spaced parameters from `u = 0` to `u = 1`.
    pub fn sample(&self, count: usize) -> Result<CurveSamples> {
        let us = params("count", count)?;
        let mut s = CurveSamples {
            x: vec![0.0; count],
            y: vec![0.0; count],
            z: vec![0.0; count],
        };
        self.eval_many(&us, &mut s.x, &mut s.y, &mut s.z)?;
        Ok(s)
    }
}

impl NurbsSurface {
    /// A smooth sheet over a `rows x cols` particle grid (row-major SoA): the particles are the
    /// control points, weights are 1, degrees are `min(max_degree, rows - 1)` and
    /// `min(max_degree, cols - 1)`. The sheet passes through the four corner particles and
    /// the boundary curves are the [`NurbsCurve::strand`]s of the boundary rows and columns.
    pub fn sheet(
        rows: usize,
        cols: usize,
        x: &[f32],
        y: &[f32],
        z: &[f32],
        max_degree: usize,
    ) -> Result<Self> {
        let pu = fit_degree("grid rows", rows, max_degree)?;
        let pv = fit_degree("grid cols", cols, max_degree)?;
        let n = rows
            .checked_mul(cols)
            .ok_or_else(|| WeftError::param("grid", "rows * cols", "too many particles"))?;
        NurbsSurface::new(
            rows,
            cols,
            x.to_vec(),
            y.to_vec(),
            z.to_vec(),
            vec![1.0; n],
            pu,
            pv,
        )
    }

    /// Samples an `ru x rv` grid of points (`ru, rv >= 2`, equally spaced on `[0, 1]^2`) and
    /// triangulates it: vertex `a * rv + b` is `S(u_a, v_b)`; each quad gives two triangles.
    pub fn sample(&self, ru: usize, rv: usize) -> Result<SurfaceMesh> {
        let us = params("ru", ru)?;
        let vs = params("rv", rv)?;
        let total = ru
            .checked_mul(rv)
            .filter(|&t| t <= u32::MAX as usize)
            .ok_or_else(|| WeftError::param("ru * rv", "too large", "must fit u32 indices"))?;
        let mut m = SurfaceMesh {
            x: vec![0.0; total],
            y: vec![0.0; total],
            z: vec![0.0; total],
            triangles: Vec::with_capacity(2 * (ru - 1) * (rv - 1)),
        };
        self.eval_grid(&us, &vs, &mut m.x, &mut m.y, &mut m.z)?;
        for a in 0..ru - 1 {
            for b in 0..rv - 1 {
                let i00 = (a * rv + b) as u32;
                let i10 = i00 + rv as u32;
                let i01 = i00 + 1;
                let i11 = i10 + 1;
                m.triangles.push([i00, i10, i11]);
                m.triangles.push([i00, i11, i01]);
            }
        }
        Ok(m)
    }
}
