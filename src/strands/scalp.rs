//! The scalp: where strands grow (AHS root placement) and what they must stay outside of.
//!
//! A scalp is an ellipsoid `((x-c_x)/a)² + ((y-c_y)/b)² + ((z-c_z)/c)² = 1` (a sphere when
//! `a = b = c`), with `y` up. Points are addressed by a polar angle `θ` from `+y` and an
//! azimuth `φ` around it: `S(θ, φ) = c + (a sinθ cosφ, b cosθ, c sinθ sinφ)`; the outward
//! normal there is `∇f ∝ ((x-c_x)/a², (y-c_y)/b², (z-c_z)/c²)`. Hair grows on the patch
//! `θ_min <= θ <= θ_max` (degrees in the API and in scene files).
//!
//! **Root placement** (the NURBS thesis, AHS: "for each root point P on the scalp C"): roots must be
//! spread evenly and deterministically. [`Scalp::roots`] uses a Fibonacci spiral on the patch:
//! root `i` of `n` takes `cosθ_i = cosθ_min + (i + ½)/n · (cosθ_max - cosθ_min)` (equal area
//! bands on a sphere) and `φ_i = i · 2π/ϕ²` (the golden angle), so neighbouring roots never line
//! up. On an ellipsoid the same parameters are used, so the spacing stretches with the radii.
//!
//! **Collision** ([`ScalpSet`]): during the solver iterations every free strand particle is
//! kept outside the scalp inflated by a margin `t` (half the strand thickness). With inflated
//! radii `R = (a+t, b+t, c+t)` and `d = p - c`, `s = |d / R|` (componentwise division); if
//! `s < 1` the particle is moved to `c + d / s`, the point of the inflated ellipsoid on the same
//! scaled ray. On a sphere that is the closest surface point; on an ellipsoid it is a cheap,
//! non-iterative stand-in that always lands on the surface. Pinned particles (roots, `w = 0`)
//! are left alone. The kernel is element-wise, so the parallel path (chunks on rayon) and the
//! serial scalar twin give the same bits on any thread count.

use rayon::prelude::*;

use crate::error::{finite3, Result, WeftError};
pub use crate::model::layout::{Scalp, ScalpRange};

impl Scalp {
    /// A whole sphere.
    pub fn sphere(center: [f32; 3], radius: f32) -> Scalp {
        Scalp {
            center,
            radii: [radius; 3],
            polar_degrees: [0.0, 180.0],
        }
    }

    /// An ellipsoid patch between two polar angles (degrees from `+y`).
    pub fn ellipsoid(center: [f32; 3], radii: [f32; 3], polar_degrees: [f32; 2]) -> Scalp {
        Scalp {
            center,
            radii,
            polar_degrees,
        }
    }

    /// True when all three radii are equal.
    pub fn is_sphere(&self) -> bool {
        self.radii[0] == self.radii[1] && self.radii[1] == self.radii[2]
    }

    /// Checks the centre, radii and angle range.
    pub fn validate(&self) -> Result<()> {
        finite3("scalp.center", self.center)?;
        if !self.radii.iter().all(|r| r.is_finite() && *r > 0.0) {
            return Err(WeftError::param(
                "scalp.radii",
                format!("{:?}", self.radii),
                "every radius must be a finite number greater than zero",
            ));
        }
        let [lo, hi] = self.polar_degrees;
        if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi && hi <= 180.0) {
            return Err(WeftError::param(
                "scalp.polar_degrees",
                format!("{:?}", self.polar_degrees),
                "must be [min, max] with 0 <= min <= max <= 180",
            ));
        }
        Ok(())
    }

    /// Surface point and unit outward normal at polar angle `theta` and azimuth `phi`
    /// (radians), computed in f64.
    pub fn point_normal(&self, theta: f64, phi: f64) -> ([f32; 3], [f32; 3]) {
        let r = self.radii.map(f64::from);
        let d = [r[0] * theta.sin() * phi.cos(), r[1] * theta.cos(), r[2] * theta.sin() * phi.sin()];
        let g = [d[0] / (r[0] * r[0]), d[1] / (r[1] * r[1]), d[2] / (r[2] * r[2])];
        let l = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        let n = if l > 0.0 { g.map(|c| c / l) } else { [0.0, 1.0, 0.0] };
        let p = [0, 1, 2].map(|k| (self.center[k] as f64 + d[k]) as f32);
        (p, n.map(|c| c as f32))
    }

    /// `count` roots spread over the patch by the Fibonacci spiral (module docs): each with its
    /// unit outward normal. Deterministic.
    pub fn roots(&self, count: usize) -> Vec<([f32; 3], [f32; 3])> {
        let [lo, hi] = self.polar_degrees.map(|d| (d as f64).to_radians());
        let (c0, c1) = (lo.cos(), hi.cos());
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..count)
            .map(|i| {
                let t = (i as f64 + 0.5) / count as f64;
                let theta = (c0 + t * (c1 - c0)).clamp(-1.0, 1.0).acos();
                let phi = (i as f64 * golden) % std::f64::consts::TAU;
                self.point_normal(theta, phi)
            })
            .collect()
    }

    /// The implicit value `|(p - c) / radii|`: below 1 inside, 1 on the surface.
    pub fn scaled_distance(&self, p: [f32; 3]) -> f32 {
        let q = [0, 1, 2].map(|k| (p[k] - self.center[k]) / self.radii[k]);
        (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt()
    }
}

/// Particles per parallel task of the scalp stage.
pub const SCALP_CHUNK: usize = 4096;

/// All scalp collision ranges of a world (empty: the stage does not run).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ScalpSet {
    /// The ranges, solved in order.
    pub ranges: Vec<ScalpRange>,
}

/// Moves one particle out of the inflated ellipsoid (module docs). Pinned particles stay.
#[inline]
fn push_out(x: &mut f32, y: &mut f32, z: &mut f32, w: f32, c: [f32; 3], r: [f32; 3]) {
    if w <= 0.0 {
        return;
    }
    let d = [*x - c[0], *y - c[1], *z - c[2]];
    let q = [d[0] / r[0], d[1] / r[1], d[2] / r[2]];
    let s2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
    if s2 >= 1.0 {
        return;
    }
    if s2 < 1e-12 {
        // At the centre there is no direction: leave through the crown.
        *y = c[1] + r[1];
        return;
    }
    let s = s2.sqrt();
    *x = c[0] + d[0] / s;
    *y = c[1] + d[1] / s;
    *z = c[2] + d[2] / s;
}

impl ScalpSet {
    /// True when there is nothing to collide.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Adds the particles `start..end` against `scalp` inflated by `margin`.
    pub fn push(&mut self, start: usize, end: usize, scalp: &Scalp, margin: f32) {
        self.ranges.push(ScalpRange {
            start,
            end,
            center: scalp.center,
            radii: scalp.radii.map(|r| r + margin),
        });
    }

    /// The scalp stage on predicted positions, in parallel chunks of [`SCALP_CHUNK`].
    pub fn solve(&self, px: &mut [f32], py: &mut [f32], pz: &mut [f32], w: &[f32]) {
        for r in &self.ranges {
            let s = r.start..r.end;
            (
                px[s.clone()].par_chunks_mut(SCALP_CHUNK),
                py[s.clone()].par_chunks_mut(SCALP_CHUNK),
                pz[s.clone()].par_chunks_mut(SCALP_CHUNK),
                w[s].par_chunks(SCALP_CHUNK),
            )
                .into_par_iter()
                .for_each(|(x, y, z, w)| {
                    for i in 0..x.len() {
                        push_out(&mut x[i], &mut y[i], &mut z[i], w[i], r.center, r.radii);
                    }
                });
        }
    }

    /// Scalar twin of [`solve`](Self::solve): one thread, particle by particle.
    pub fn solve_scalar(&self, px: &mut [f32], py: &mut [f32], pz: &mut [f32], w: &[f32]) {
        for r in &self.ranges {
            for i in r.start..r.end {
                push_out(&mut px[i], &mut py[i], &mut pz[i], w[i], r.center, r.radii);
            }
        }
    }
}
