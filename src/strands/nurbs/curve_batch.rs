//! Batch evaluation of a NURBS curve at many parameters, SoA out, SIMD over parameters.
//!
//! Eight parameters are evaluated at once, one per lane: each lane finds its own knot span
//! (scalar), the knots and control points it needs are gathered into `f32x8`
//! registers, and the triangular Cox–de Boor scheme and the rational sum run in SIMD with
//! exactly the operations, in exactly the order, of the scalar local evaluator. The SIMD path
//! and its scalar twin ([`NurbsCurve::eval_many_scalar`]) therefore agree bit for bit (no FMA
//! anywhere, IEEE division in both). What SIMD buys is the `p(p+1)/2` divisions and the
//! multiply-adds of the basis; the gathers stay scalar loads.

use super::basis::MAX_ORDER;
use super::curve::NurbsCurve;
use crate::data::lanes::{F32s, LANES};
use crate::{Result, WeftError};

impl NurbsCurve {
    fn check_batch(&self, us: &[f32], ox: &[f32], oy: &[f32], oz: &[f32]) -> Result<()> {
        for (name, o) in [("out_x", ox), ("out_y", oy), ("out_z", oz)] {
            if o.len() != us.len() {
                return Err(WeftError::BufferLength {
                    name,
                    got: o.len(),
                    expected: us.len(),
                });
            }
        }
        for (i, &u) in us.iter().enumerate() {
            self.knots().check_param(&format!("us[{i}]"), u)?;
        }
        Ok(())
    }

    /// Evaluates the curve at every `us[i]` into `out_x[i], out_y[i], out_z[i]` (SIMD over
    /// parameters; the tail of fewer than eight goes through the scalar twin, which gives the
    /// same bits). All parameters are checked before anything is written; an empty `us` is
    /// fine and writes nothing.
    pub fn eval_many(&self, us: &[f32], out_x: &mut [f32], out_y: &mut [f32], out_z: &mut [f32]) -> Result<()> {
        self.check_batch(us, out_x, out_y, out_z)?;
        let full = us.len() / LANES * LANES;
        for c in (0..full).step_by(LANES) {
            let u: [f32; LANES] = us[c..c + LANES].try_into().expect("lane chunk");
            let [x, y, z] = self.eval_lanes(u);
            crate::data::lanes::store(out_x, c, x);
            crate::data::lanes::store(out_y, c, y);
            crate::data::lanes::store(out_z, c, z);
        }
        for i in full..us.len() {
            let s = self.knots().span_unchecked(us[i]);
            [out_x[i], out_y[i], out_z[i]] = self.eval_in_span(s, us[i]);
        }
        Ok(())
    }

    /// Scalar twin of [`NurbsCurve::eval_many`]: [`NurbsCurve::eval_local`] point by point.
    pub fn eval_many_scalar(&self, us: &[f32], out_x: &mut [f32], out_y: &mut [f32], out_z: &mut [f32]) -> Result<()> {
        self.check_batch(us, out_x, out_y, out_z)?;
        for (i, &u) in us.iter().enumerate() {
            let s = self.knots().span_unchecked(u);
            [out_x[i], out_y[i], out_z[i]] = self.eval_in_span(s, u);
        }
        Ok(())
    }

    /// Eight checked parameters, one per lane; mirrors `basis_in_span` + `eval_in_span`.
    #[inline]
    fn eval_lanes(&self, u: [f32; LANES]) -> [F32s; 3] {
        let p = self.degree();
        let t = self.knots().knots();
        let span: [usize; LANES] = u.map(|ul| self.knots().span_unchecked(ul));
        let gather =
            |a: &[f32], off: isize| -> F32s { F32s::from(std::array::from_fn::<f32, LANES, _>(|l| a[(span[l] as isize + off) as usize])) };
        let uv = F32s::from(u);
        let zero = F32s::splat(0.0);
        let mut n = [zero; MAX_ORDER];
        let mut left = [zero; MAX_ORDER];
        let mut right = [zero; MAX_ORDER];
        n[0] = F32s::splat(1.0);
        for j in 1..=p {
            left[j] = uv - gather(t, 1 - j as isize);
            right[j] = gather(t, j as isize) - uv;
            let mut saved = zero;
            for r in 0..j {
                let temp = n[r] / (right[r + 1] + left[j - r]);
                n[r] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            n[j] = saved;
        }
        let (mut sx, mut sy, mut sz, mut sw) = (zero, zero, zero, zero);
        for (r, &nr) in n.iter().enumerate().take(p + 1) {
            let off = r as isize - p as isize;
            let nw = nr * gather(self.weights(), off);
            sx += nw * gather(self.x(), off);
            sy += nw * gather(self.y(), off);
            sz += nw * gather(self.z(), off);
            sw += nw;
        }
        [sx / sw, sy / sw, sz / sw]
    }
}
