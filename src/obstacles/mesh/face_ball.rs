//! The clearance ball of a kept face list: which of a particle's listed faces can touch its
//! step while it stays near where the list was last sorted (exact, like the kept lists of
//! [`face_cache`](crate::obstacles::mesh::face_cache)).
//!
//! A kept list holds every face whose box overlaps the particle's gathered box, about eight
//! faces on the dress form; most of them are far from the particle, yet every step tests all
//! of their boxes and often their planes. The ball sorts the list once for a centre `o` (the
//! predicted position `p` of the step that sorts it) and keeps two numbers:
//!
//! * the **near faces** `K`, put at the front of the list: the faces closer to `o` than
//!   `reach + m + s`, `m` a margin for the coming steps ([`ball_margin`]: a quarter reach
//!   plus the sorting step's largest coordinate change) and `s` a rounding pad ([`pad`]);
//! * the **clearance** `c`: a lower bound on the distance from `o` to every other face of
//!   the mesh, minus the pad: `c = min(D, dist(o, G) for the listed G outside K) - s`, where
//!   `D` is the distance from `o` to the outside of the gathered box (a face missing from
//!   the list does not overlap that box). A face is first measured by the distance from `o`
//!   to its box (a lower bound), and only faces whose box is nearer than `reach + m + s` get
//!   the exact point-triangle distance ([`closest_point_on_triangle`]).
//!
//! While a later step `x -> p` with reach `r` has both ends within `c - r` of `o`, every face
//! `G` outside `K` is farther than `r + s` from every point of the segment (triangle
//! inequality; the segment lies in the ball, which is convex): `G` can give no proximity
//! (closer than `r`) and no crossing (a crossing point lies on `G`, up to the narrowphase's
//! barycentric tolerance of about `1e-9` of the face's size, far below `s`). So the
//! narrowphase over `K` alone (`best_contact`, whose
//! choice does not depend on the order or on faces that give no contact) returns exactly the
//! contact of the whole list. The test runs in `f32` against `(c - r)(1 - 1e-4)`, a bound
//! far outside the few-ulp rounding of the squared distances, so it can only say "outside"
//! too often, never "inside" wrongly. A particle that leaves its ball sorts its list again;
//! a non-finite position or reach never holds a ball.
//!
//! With the quarter-reach margin most kept-list steps are vouched for by the ball and test
//! one or two near faces instead of the whole list. The contact pass also skips, eight lanes
//! at once, the particles whose ball has no near face and vouches for the step
//! ([`vouches_simd`], `mesh_pass::skip_lanes_simd`).
//!
//! The pad `s` is `1e-6 (1 + max |o_k|)`: above the `f64` rounding of the distances (about
//! `1e-15` relative) and of the crossing point, and above the `f32` rounding of the stored
//! clearance (which is stored rounded down).

use crate::data::lanes::{F32s, Vec3x8};
use crate::obstacles::mesh::narrow::closest_point_on_triangle;
use crate::obstacles::mesh::TriMesh;

/// The near faces reach this many contact reaches beyond the reach (module doc) ...
pub const BALL_REACH: f32 = 0.25;
/// ... plus this many times the sorting step's largest coordinate change.
pub const BALL_STEPS: f32 = 1.0;

/// The margin `m` of the near faces for a sort at the step `x -> p` of reach `reach`.
#[inline]
pub fn ball_margin(x: [f32; 3], p: [f32; 3], reach: f32) -> f32 {
    BALL_REACH * reach + BALL_STEPS * crate::obstacles::mesh::face_cache::largest_change(x, p)
}

/// Relative size of the rounding pad `s` (module doc).
pub const BALL_PAD: f64 = 1e-6;

/// The ball test's safety factor on `c - r` (module doc).
const SHRINK: f32 = 1.0 - 1e-4;

/// A lane's clearance ball (module doc). The default holds nothing.
#[derive(Debug, Clone, Copy)]
pub struct Ball {
    /// Centre.
    o: [f32; 3],
    /// Clearance: every face outside the near ones is at least this far from `o`, plus the pad.
    c: f32,
    /// The first `near` faces of the list are the near faces `K`.
    near: u32,
}

impl Default for Ball {
    fn default() -> Self {
        Ball {
            o: [0.0; 3],
            c: f32::NEG_INFINITY,
            near: 0,
        }
    }
}

/// The rounding pad `s` for a centre `o` (module doc).
#[inline]
pub fn pad(o: [f64; 3]) -> f64 {
    BALL_PAD * (1.0 + o.iter().fold(0.0f64, |m, v| m.max(v.abs())))
}

/// Distance from `o` to the box `[lo, hi]` (zero inside), a lower bound on the distance to
/// anything inside the box.
fn box_distance(o: [f64; 3], lo: [f32; 3], hi: [f32; 3]) -> f64 {
    let g = |k: usize| (lo[k] as f64 - o[k]).max(o[k] - hi[k] as f64).max(0.0);
    (g(0) * g(0) + g(1) * g(1) + g(2) * g(2)).sqrt()
}

/// Exact distance from `o` to face `f` (`f64`).
fn face_distance(mesh: &TriMesh, f: u32, o: [f64; 3]) -> f64 {
    let [a, b, c] = mesh.corners(f).map(|v| v.map(|k| k as f64));
    let q = closest_point_on_triangle(o, a, b, c);
    let r = [o[0] - q[0], o[1] - q[1], o[2] - q[2]];
    (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt()
}

/// Does the ball of centre `o` and clearance `c` vouch for the step `x -> p` of reach
/// `reach` (both ends within `c - reach` of the centre, with the safety factor)?
#[inline]
pub fn vouches(o: [f32; 3], c: f32, x: [f32; 3], p: [f32; 3], reach: f32) -> bool {
    let lim = (c - reach) * SHRINK;
    let d2 = |y: [f32; 3]| {
        let d = [y[0] - o[0], y[1] - o[1], y[2] - o[2]];
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    };
    // `lim > 0` is false for NaN; a non-finite `x` or `p` makes its comparison false
    lim > 0.0 && d2(x) <= lim * lim && d2(p) <= lim * lim
}

/// [`vouches`] for eight lanes at once (bit `l` for lane `l`): the same operations in the
/// same order, no fused multiply-add, so the same bits.
#[inline]
pub fn vouches_simd(o: Vec3x8, c: F32s, x: Vec3x8, p: Vec3x8, reach: F32s) -> u32 {
    let lim = (c - reach) * F32s::splat(SHRINK);
    let d2 = |y: Vec3x8| {
        let d = [y.x - o.x, y.y - o.y, y.z - o.z];
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    };
    let l2 = lim * lim;
    (lim.simd_gt(F32s::splat(0.0)) & d2(x).simd_le(l2) & d2(p).simd_le(l2)).to_bitmask()
}

impl Ball {
    /// Does the ball vouch for the step `x -> p` of reach `reach` ([`vouches`])?
    #[inline]
    pub fn holds(&self, x: [f32; 3], p: [f32; 3], reach: f32) -> bool {
        vouches(self.o, self.c, x, p, reach)
    }

    /// The centre and clearance, when no face is near (else a clearance that vouches for
    /// nothing): such a ball vouches that the step has no contact at all.
    #[inline]
    pub fn empty_part(&self) -> ([f32; 3], f32) {
        (self.o, if self.near == 0 { self.c } else { f32::NEG_INFINITY })
    }

    /// How many faces at the front of the list are the near faces.
    #[inline]
    pub fn near(&self) -> usize {
        self.near as usize
    }

    /// Sorts `faces` (a kept list, every face overlapping the gathered box `[glo, ghi]`) for
    /// the centre `o`: near faces first, and the clearance beyond them (module doc); `m` is
    /// the gathering margin. A non-finite input gives the ball that holds nothing.
    pub fn sort(mesh: &TriMesh, faces: &mut [u32], o: [f32; 3], reach: f32, m: f32, (glo, ghi): ([f32; 3], [f32; 3])) -> Ball {
        let finite = o.iter().chain([&reach, &m]).all(|v| v.is_finite());
        if !finite || reach < 0.0 || m < 0.0 {
            return Ball::default();
        }
        let od = o.map(|k| k as f64);
        let s = pad(od);
        let want = reach as f64 + m as f64 + s;
        let mut out = (0..3).fold(f64::INFINITY, |d, k| d.min(od[k] - glo[k] as f64).min(ghi[k] as f64 - od[k]));
        let mut near = 0;
        for i in 0..faces.len() {
            let f = faces[i];
            let (lo, hi) = (mesh.face_lo(f), mesh.face_hi(f));
            let lb = box_distance(od, lo, hi);
            let d = if lb >= want { lb } else { face_distance(mesh, f, od) };
            if d < want {
                faces.swap(near, i);
                near += 1;
            } else {
                out = out.min(d);
            }
        }
        let c = out - s;
        if c.is_nan() || c <= 0.0 {
            return Ball {
                near: near as u32,
                ..Ball::default()
            };
        }
        Ball {
            o,
            // rounded down: a relative step far above the f32 rounding
            c: (c * (1.0 - 1e-6)) as f32,
            near: near as u32,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::obstacles::mesh::contact::best_contact;
    use crate::obstacles::mesh::dressform::dress_form;
    use crate::obstacles::mesh::narrow::query_box;

    /// Every step the ball vouches for gives, over its near faces, the contact of the whole
    /// mesh (brute force), and no face outside them comes within reach of the step; the
    /// random steps sit on and around the form's surface.
    #[test]
    fn near_faces_give_the_contact_of_the_whole_mesh() {
        let mesh = dress_form(1200).unwrap();
        let all: Vec<u32> = (0..mesh.face_count() as u32).collect();
        let mut r = crate::test_rng::unit(11);
        let (lo, hi) = mesh.bounds();
        let (mut vouched, mut contacts, mut refused) = (0, 0, 0);
        for _ in 0..400 {
            // a point near the surface: a face's centroid pushed along its normal
            let f = (r() * mesh.face_count() as f32) as u32 % mesh.face_count() as u32;
            let [a, b, c] = mesh.corners(f);
            let n = mesh.normals()[f as usize];
            let h = (r() - 0.3) * 0.01;
            let o = [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0 + h * n[k]);
            let reach = 0.002 + 0.003 * r();
            let m = 0.004 * r();
            let mut faces = all.clone();
            let ball = Ball::sort(&mesh, &mut faces, o, reach, m, (lo.map(|v| v - 1.0), hi.map(|v| v + 1.0)));
            for _ in 0..20 {
                let jitter = |s: f32, r: &mut dyn FnMut() -> f32| [0; 3].map(|_| (r() - 0.5) * s);
                let dx = jitter(0.006, &mut r);
                let dp = jitter(0.006, &mut r);
                let x = [0, 1, 2].map(|k| o[k] + dx[k]);
                let p = [0, 1, 2].map(|k| o[k] + dp[k]);
                if !ball.holds(x, p, reach) {
                    refused += 1;
                    continue;
                }
                vouched += 1;
                let (ql, qh) = query_box(x, p, reach);
                let want = best_contact(&mesh, &all, x, p, reach, ql, qh);
                let got = best_contact(&mesh, &faces[..ball.near()], x, p, reach, ql, qh);
                assert_eq!(got, want, "o {o:?} x {x:?} p {p:?}");
                contacts += want.is_some() as usize;
                for &g in &faces[ball.near()..] {
                    assert!(crate::obstacles::mesh::narrow::face_contact(&mesh, g, x, p, reach).is_none());
                }
            }
        }
        assert!(vouched > 1000 && contacts > 200 && refused > 500, "{vouched} {contacts} {refused}");
    }

    /// Non-finite centres or reaches hold nothing; a centre outside the gathered box holds
    /// nothing; the default ball holds nothing.
    #[test]
    fn degenerate_balls_hold_nothing() {
        let mesh = dress_form(600).unwrap();
        let mut faces: Vec<u32> = (0..mesh.face_count() as u32).collect();
        let (lo, hi) = mesh.bounds();
        let far = [0.0, crate::obstacles::mesh::dressform::HEIGHT + 0.5, 0.0];
        let wide = (lo.map(|v| v - 2.0), hi.map(|v| v + 2.0));
        assert!(Ball::sort(&mesh, &mut faces, far, 0.003, 0.001, wide).holds(far, far, 0.003));
        assert!(!Ball::default().holds(far, far, 0.0));
        for (o, reach) in [([f32::NAN, 0.0, 0.0], 0.003), (far, f32::NAN), (far, f32::INFINITY), (far, -1.0)] {
            let b = Ball::sort(&mesh, &mut faces, o, reach, 0.001, wide);
            assert!(!b.holds(far, far, 0.003) && !b.holds(far, far, 0.0));
        }
        let b = Ball::sort(&mesh, &mut faces, far, 0.003, 0.001, (lo, hi));
        assert!(!b.holds(far, far, 0.003), "the centre lies outside the gathered box");
        let b = Ball::sort(&mesh, &mut faces, far, 0.003, 0.001, wide);
        assert!(!b.holds([f32::NAN; 3], far, 0.003) && !b.holds(far, far, f32::NAN));
    }
}
