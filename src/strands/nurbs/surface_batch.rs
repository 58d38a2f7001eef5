//! Batch evaluation of a NURBS surface on a `(u, v)` grid, SoA out, SIMD over `v`.
//!
//! On a grid the basis values repeat: every row shares the `v` basis and every column the `u`
//! basis. So the spans and the `p + 1` local basis values are computed once per `u` and once
//! per `v` (scalar triangular scheme, `O((|us| + |vs|) p^2)` in total), and each grid point
//! costs only the `(pu+1)(pv+1)` tensor sum. That sum runs over eight consecutive `v` values
//! at once: the `v` basis is stored as structure of arrays so eight lanes load contiguously,
//! the `u` basis value is broadcast, and the control points are gathered per lane. The
//! arithmetic is that of [`NurbsSurface::eval_local`], in the same order, so the SIMD kernel,
//! its scalar twin [`NurbsSurface::eval_grid_scalar`] and the point evaluator agree bit for bit.

use super::basis::{basis_in_span, MAX_ORDER};
use super::surface::NurbsSurface;
use crate::lanes::{load, store, F32s, LANES};
use crate::{Result, WeftError};

/// Spans and local basis values for a list of parameters along one direction.
struct Tables {
    span: Vec<usize>,
    basis: Vec<[f32; MAX_ORDER]>,
    /// `soa[c * len + b]` = basis value `c` of parameter `b`.
    soa: Vec<f32>,
}

fn tables(kv: &super::KnotVector, ts: &[f32]) -> Tables {
    let p = kv.degree();
    let mut span = Vec::with_capacity(ts.len());
    let mut basis = Vec::with_capacity(ts.len());
    let mut soa = vec![0.0f32; (p + 1) * ts.len()];
    for (b, &t) in ts.iter().enumerate() {
        let s = kv.span_unchecked(t);
        let mut n = [0.0f32; MAX_ORDER];
        basis_in_span(kv.knots(), p, s, t, &mut n);
        for (c, &v) in n.iter().enumerate().take(p + 1) {
            soa[c * ts.len() + b] = v;
        }
        span.push(s);
        basis.push(n);
    }
    Tables { span, basis, soa }
}

impl NurbsSurface {
    fn check_grid(&self, us: &[f32], vs: &[f32], outs: [&[f32]; 3]) -> Result<(Tables, Tables)> {
        let total = us
            .len()
            .checked_mul(vs.len())
            .ok_or_else(|| WeftError::param("grid", "us * vs", "too many points"))?;
        for (name, o) in ["out_x", "out_y", "out_z"].into_iter().zip(outs) {
            if o.len() != total {
                return Err(WeftError::BufferLength {
                    name,
                    got: o.len(),
                    expected: total,
                });
            }
        }
        for (i, &u) in us.iter().enumerate() {
            self.knots_u().check_param(&format!("us[{i}]"), u)?;
        }
        for (i, &v) in vs.iter().enumerate() {
            self.knots_v().check_param(&format!("vs[{i}]"), v)?;
        }
        Ok((tables(self.knots_u(), us), tables(self.knots_v(), vs)))
    }

    /// Evaluates the surface at every `(us[a], vs[b])` into `out[a * vs.len() + b]` (SIMD over
    /// `v`, scalar tail with identical bits). All parameters are checked first; nothing is
    /// written on error. Empty `us` or `vs` is fine and writes nothing.
    pub fn eval_grid(
        &self,
        us: &[f32],
        vs: &[f32],
        out_x: &mut [f32],
        out_y: &mut [f32],
        out_z: &mut [f32],
    ) -> Result<()> {
        let (tu, tv) = self.check_grid(us, vs, [out_x, out_y, out_z])?;
        let (pu, pv) = self.degrees();
        let cols = self.cols();
        let (x, y, z, w) = self.control();
        let nvs = vs.len();
        let full = nvs / LANES * LANES;
        let zero = F32s::splat(0.0);
        for a in 0..us.len() {
            let su = tu.span[a];
            for b in (0..full).step_by(LANES) {
                let (mut sx, mut sy, mut sz, mut sw) = (zero, zero, zero, zero);
                for r in 0..=pu {
                    let nu = F32s::splat(tu.basis[a][r]);
                    let row = (su - pu + r) * cols;
                    for c in 0..=pv {
                        let nv = load(&tv.soa, c * nvs + b);
                        let idx: [usize; LANES] =
                            std::array::from_fn(|l| row + tv.span[b + l] - pv + c);
                        let g = |s: &[f32]| F32s::from(idx.map(|k| s[k]));
                        let nw = nu * nv * g(w);
                        sx += nw * g(x);
                        sy += nw * g(y);
                        sz += nw * g(z);
                        sw += nw;
                    }
                }
                let o = a * nvs + b;
                store(out_x, o, sx / sw);
                store(out_y, o, sy / sw);
                store(out_z, o, sz / sw);
            }
            for b in full..nvs {
                let o = a * nvs + b;
                [out_x[o], out_y[o], out_z[o]] =
                    self.sum_in_span(su, &tu.basis[a], tv.span[b], &tv.basis[b]);
            }
        }
        Ok(())
    }

    /// Scalar twin of [`NurbsSurface::eval_grid`]: same precomputed tables, one point at a time.
    pub fn eval_grid_scalar(
        &self,
        us: &[f32],
        vs: &[f32],
        out_x: &mut [f32],
        out_y: &mut [f32],
        out_z: &mut [f32],
    ) -> Result<()> {
        let (tu, tv) = self.check_grid(us, vs, [out_x, out_y, out_z])?;
        let nvs = vs.len();
        for a in 0..us.len() {
            for b in 0..nvs {
                let o = a * nvs + b;
                [out_x[o], out_y[o], out_z[o]] =
                    self.sum_in_span(tu.span[a], &tu.basis[a], tv.span[b], &tv.basis[b]);
            }
        }
        Ok(())
    }
}
