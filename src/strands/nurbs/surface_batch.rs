//! Batch evaluation of a NURBS surface on a `(u, v)` grid, SoA out, SIMD with scalar twin.
//!
//! On a grid the basis values repeat, and the tensor sum factors. For a row `u_a` with span
//! `su`, first contract the `pu + 1` control rows of that span into one homogeneous control
//! polygon along `v`:
//!
//! ```text
//! Q_j = Σ_r Nu_r(u_a) w_{su-pu+r, j} P_{su-pu+r, j},   Qw_j = Σ_r Nu_r(u_a) w_{su-pu+r, j}
//! ```
//!
//! then every `v_b` of the row is a rational curve evaluation of that polygon:
//! `S(u_a, v_b) = Σ_c Nv_c(v_b) Q_{sv-pv+c} / Σ_c Nv_c(v_b) Qw_{sv-pv+c}`. Spans and local
//! basis values are computed once per `u` and once per `v` (the scalar triangular scheme).
//! A grid point then costs `pv + 1` terms instead of `(pu + 1)(pv + 1)`, plus the row
//! contraction shared by the whole row.
//!
//! SIMD: the contraction runs over eight consecutive columns `j` (contiguous loads, no
//! gathers; a tail of fewer than eight columns goes through the scalar code). The `v` stage is
//! scalar in both kernels: a lane-per-`v_b` version has to gather `Q` per lane, and measured
//! (criterion, `nurbs_surface_grid`) it was about twice as slow as the scalar loop.
//! The scalar twin [`NurbsSurface::eval_grid_scalar`] does the same operations in the same
//! order, so the two agree bit for bit. Against [`NurbsSurface::eval_local`] (which sums the
//! unfactored `(Nu Nv) w P`) they agree to rounding: within `1e-6` of the control-point scale,
//! like local against global.

use super::basis::{basis_in_span, MAX_ORDER};
use super::surface::NurbsSurface;
use crate::data::lanes::{load, store, F32s, LANES};
use crate::{Result, WeftError};

/// Spans and local basis values for a list of parameters along one direction.
struct Tables {
    span: Vec<usize>,
    /// `soa[c * len + b]` = basis value `c` of parameter `b`.
    soa: Vec<f32>,
}

fn tables(kv: &super::KnotVector, ts: &[f32]) -> Tables {
    let p = kv.degree();
    let mut span = Vec::with_capacity(ts.len());
    let mut soa = vec![0.0f32; (p + 1) * ts.len()];
    for (b, &t) in ts.iter().enumerate() {
        let s = kv.span_unchecked(t);
        let mut n = [0.0f32; MAX_ORDER];
        basis_in_span(kv.knots(), p, s, t, &mut n);
        for (c, &v) in n.iter().enumerate().take(p + 1) {
            soa[c * ts.len() + b] = v;
        }
        span.push(s);
    }
    Tables { span, soa }
}

/// The row contraction `Q` (homogeneous: `x, y, z` already multiplied by weight) over all
/// columns of the control grid.
struct Row {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    w: Vec<f32>,
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

    /// Contracts the `pu + 1` control rows of span `su` with basis `tu.soa[r * nus + a]` into
    /// `q` for columns `j0..j1`; columns in `simd_end..j1` (and all, if `simd` is false) are
    /// done by the scalar loop with the same arithmetic.
    fn contract_row(&self, tu: &Tables, nus: usize, a: usize, q: &mut Row, simd: bool) {
        let pu = self.degrees().0;
        let cols = self.cols();
        let (x, y, z, w) = self.control();
        let su = tu.span[a];
        let full = if simd { cols / LANES * LANES } else { 0 };
        let zero = F32s::splat(0.0);
        for j in (0..full).step_by(LANES) {
            let (mut qx, mut qy, mut qz, mut qw) = (zero, zero, zero, zero);
            for r in 0..=pu {
                let k = (su - pu + r) * cols + j;
                let nw = F32s::splat(tu.soa[r * nus + a]) * load(w, k);
                qx += nw * load(x, k);
                qy += nw * load(y, k);
                qz += nw * load(z, k);
                qw += nw;
            }
            store(&mut q.x, j, qx);
            store(&mut q.y, j, qy);
            store(&mut q.z, j, qz);
            store(&mut q.w, j, qw);
        }
        for j in full..cols {
            let (mut qx, mut qy, mut qz, mut qw) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
            for r in 0..=pu {
                let k = (su - pu + r) * cols + j;
                let nw = tu.soa[r * nus + a] * w[k];
                qx += nw * x[k];
                qy += nw * y[k];
                qz += nw * z[k];
                qw += nw;
            }
            [q.x[j], q.y[j], q.z[j], q.w[j]] = [qx, qy, qz, qw];
        }
    }

    /// The `v` stage for one parameter `b`, scalar.
    #[inline]
    fn v_point(&self, tv: &Tables, nvs: usize, b: usize, q: &Row) -> [f32; 3] {
        let pv = self.degrees().1;
        let (mut sx, mut sy, mut sz, mut sw) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for c in 0..=pv {
            let j = tv.span[b] - pv + c;
            let nv = tv.soa[c * nvs + b];
            sx += nv * q.x[j];
            sy += nv * q.y[j];
            sz += nv * q.z[j];
            sw += nv * q.w[j];
        }
        [sx / sw, sy / sw, sz / sw]
    }

    fn grid(&self, us: &[f32], vs: &[f32], out: [&mut [f32]; 3], simd: bool) -> Result<()> {
        let [out_x, out_y, out_z] = out;
        let (tu, tv) = self.check_grid(us, vs, [out_x, out_y, out_z])?;
        let cols = self.cols();
        let (nus, nvs) = (us.len(), vs.len());
        let mut q = Row {
            x: vec![0.0; cols],
            y: vec![0.0; cols],
            z: vec![0.0; cols],
            w: vec![0.0; cols],
        };
        for a in 0..nus {
            self.contract_row(&tu, nus, a, &mut q, simd);
            for b in 0..nvs {
                let o = a * nvs + b;
                [out_x[o], out_y[o], out_z[o]] = self.v_point(&tv, nvs, b, &q);
            }
        }
        Ok(())
    }

    /// Evaluates the surface at every `(us[a], vs[b])` into `out[a * vs.len() + b]` (factored
    /// tensor sum, SIMD over control columns). All parameters are checked first; nothing
    /// is written on error. Empty `us` or `vs` is fine and writes nothing.
    pub fn eval_grid(&self, us: &[f32], vs: &[f32], out_x: &mut [f32], out_y: &mut [f32], out_z: &mut [f32]) -> Result<()> {
        self.grid(us, vs, [out_x, out_y, out_z], true)
    }

    /// Scalar twin of [`NurbsSurface::eval_grid`]: the same factored sums, one value at a time.
    pub fn eval_grid_scalar(&self, us: &[f32], vs: &[f32], out_x: &mut [f32], out_y: &mut [f32], out_z: &mut [f32]) -> Result<()> {
        self.grid(us, vs, [out_x, out_y, out_z], false)
    }
}
