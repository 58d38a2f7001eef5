//! Smooth curves and sheets drawn over simulated particles (the paper draws strands and cloth
//! as NURBS whose control points are the simulated points, the NURBS thesis, AHS last step).
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
        return Err(WeftError::param(name, count, "at least 2 samples are needed"));
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
        NurbsCurve::new(x.to_vec(), y.to_vec(), z.to_vec(), vec![1.0; x.len()], degree)
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
    pub fn sheet(rows: usize, cols: usize, x: &[f32], y: &[f32], z: &[f32], max_degree: usize) -> Result<Self> {
        let pu = fit_degree("grid rows", rows, max_degree)?;
        let pv = fit_degree("grid cols", cols, max_degree)?;
        let n = rows
            .checked_mul(cols)
            .ok_or_else(|| WeftError::param("grid", "rows * cols", "too many particles"))?;
        NurbsSurface::new(rows, cols, x.to_vec(), y.to_vec(), z.to_vec(), vec![1.0; n], pu, pv)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Smallest and largest value, by comparisons. Not `fold(f32::INFINITY, f32::min)`: with
    /// rustc 1.95 at opt-level 2 for x86-64-v3 that fold over a 9-element vector was vectorized
    /// into an 8-lane `vminps` whose NaN-free path skipped the ninth element (seen in this test's
    /// disassembly; the test then failed with min -0.7 instead of -0.8).
    fn bounds(v: &[f32]) -> (f32, f32) {
        let mut lo = f32::INFINITY;
        let mut hi = f32::NEG_INFINITY;
        for &x in v {
            if x < lo {
                lo = x;
            }
            if x > hi {
                hi = x;
            }
        }
        (lo, hi)
    }

    #[test]
    fn strand_runs_from_root_to_tip_inside_the_particle_box() {
        let n = 9;
        let x: Vec<f32> = (0..n).map(|i| (i as f32 * 0.7).sin()).collect();
        let y: Vec<f32> = (0..n).map(|i| -0.1 * i as f32).collect();
        let z: Vec<f32> = (0..n).map(|i| (i as f32 * 0.3).cos()).collect();
        let c = NurbsCurve::strand(&x, &y, &z, 3).unwrap();
        assert_eq!(c.degree(), 3);
        let s = c.sample(100).unwrap();
        assert_eq!(s.x.len(), 100);
        let tol = 1e-6;
        assert!((s.x[0] - x[0]).abs() < tol && (s.y[99] - y[n - 1]).abs() < tol);
        for (pts, samp) in [(&x, &s.x), (&y, &s.y), (&z, &s.z)] {
            let (lo, hi) = bounds(pts);
            for &v in samp.iter() {
                assert!(v >= lo - tol && v <= hi + tol, "{v} outside [{lo}, {hi}]");
            }
        }
        // Two particles: the degree drops to 1 and the strand is the segment.
        let two = NurbsCurve::strand(&[0.0, 2.0], &[0.0, 0.0], &[0.0, 4.0], 3).unwrap();
        assert_eq!(two.degree(), 1);
        assert_eq!(two.eval_local(0.5).unwrap(), [1.0, 0.0, 2.0]);
    }

    #[test]
    fn sheet_sample_is_a_consistent_mesh() {
        let (rows, cols) = (5, 7);
        let mut x = Vec::new();
        let mut y = Vec::new();
        let mut z = Vec::new();
        for i in 0..rows {
            for j in 0..cols {
                x.push(j as f32);
                y.push(i as f32);
                z.push(((i + j) % 2) as f32);
            }
        }
        let s = NurbsSurface::sheet(rows, cols, &x, &y, &z, 3).unwrap();
        let m = s.sample(9, 13).unwrap();
        assert_eq!(m.x.len(), 9 * 13);
        assert_eq!(m.triangles.len(), 2 * 8 * 12);
        assert!(m.triangles.iter().flatten().all(|&k| (k as usize) < m.x.len()));
        let last = m.x.len() - 1;
        assert_eq!([m.x[0], m.y[0], m.z[0]], [0.0, 0.0, 0.0]);
        assert_eq!([m.x[last], m.y[last]], [6.0, 4.0]);
        // Triangles are counter-clockwise in (u, v); here u runs along y and v along x, which
        // mirrors them: all clockwise in (x, y), none degenerate, so the sheet is not folded.
        for t in &m.triangles {
            let [a, b, c] = t.map(|k| k as usize);
            let cross = (m.x[b] - m.x[a]) * (m.y[c] - m.y[a]) - (m.y[b] - m.y[a]) * (m.x[c] - m.x[a]);
            assert!(cross != 0.0);
            assert_eq!(cross.signum(), -1.0);
        }
        assert!(m.z.iter().all(|&v| (0.0..=1.0).contains(&v)));
    }
}
