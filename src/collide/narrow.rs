//! Narrowphase: a particle's step `x -> p` against the faces of a mesh (SEEDS.md section D).
//!
//! The paper checks, after each integration step, whether the particle's trajectory crossed a
//! face, finds the crossing point, and puts the particle back on its own side at the fabric
//! thickness `Th`. Per face (computed in `f64` from the `f32` data):
//!
//! 1. **Side.** With the unit normal `n` and a corner `a`, the signed heights are
//!    `hx = n.(x - a)` and `hp = n.(p - a)`. On a two-sided sheet (an open mesh) the
//!    particle's side is where it came from, `s = sign(hx)` (`+1` when `x` lies exactly on
//!    the plane). On a solid ([`TriMesh::solid_side`]) `s` is the solid's outside for every
//!    face. Why: near a concave edge a particle outside the body can be behind the plane of
//!    one of the edge's faces (e.g. falling past the overhang of the shoulders) and the
//!    `sign(hx)` rule would push it to that plane's back side, into the body; a test
//!    (`falling_particles_never_penetrate_the_form`) showed exactly that.
//! 2. **Crossing (continuous test).** If `s*hx >= 0 > s*hp` the segment crosses the plane at
//!    `t = hx / (hx - hp)`, which lies in `[0, 1]` and never divides by zero because the two
//!    heights have strictly different signs. A segment lying in the plane never "crosses"; a
//!    particle leaving a solid from inside is let out.
//!    The point `q = x + t (p - x)` is inside the triangle when its three barycentric weights
//!    `w_i = n.((v_j - q) x (v_k - q)) / |(b-a) x (c-a)|` are all `>= -EDGE_TOLERANCE`: hits
//!    exactly on an edge or vertex count for every face sharing it (no tunnelling through
//!    seams) and no step divides by a quantity that can vanish, so no NaN arises.
//! 3. **Proximity.** Otherwise, if the closest point `c` of the triangle to `p` is closer than
//!    `Th`, the particle ends inside the fabric's thickness layer: a contact at `t = 1`.
//!
//! The plane data of step 1 (corner, normal, unit normal) is computed once per mesh state
//! ([`FacePlane`]), with the same operations, and a face is rejected right after the two
//! heights when the path does not cross its plane and `p` lies farther than `Th` from it on
//! either side (behind the plane with a tiny relative pad, [`PLANE_SLACK`]): no triangle
//! point can then be within `Th`. Both change the cost, not the answer (a test compares with
//! the full computation).
//!
//! A contact carries the face, the point (`q` or `c`), the face normal turned to the
//! particle's side (`s n`), the time of impact `t`, and `depth = Th - s*hp`, how far `p` must
//! move along that normal to stand `Th` off the face's plane.
//!
//! [`mesh_contact`] asks a broadphase for candidates, keeps exactly the faces whose box
//! overlaps the step's box grown by `Th` (plus a tiny relative pad), and returns the contact
//! with the smallest `t`, ties going to the smallest face index. The candidate sets of
//! different broadphases differ, but the faces tested and the choice made do not, so every
//! broadphase gives bit-identical contacts.

use super::face_broadphase::FaceBroadphase;
use super::mesh::{FacePlane, TriMesh};

/// Barycentric slack accepted when deciding that a crossing point is inside a face.
pub const EDGE_TOLERANCE: f64 = 1e-9;
/// Relative padding of the behind-the-plane reject in [`face_contact`].
pub const PLANE_SLACK: f64 = 1e-9;
/// The query box is grown by this times `1 + max |coordinate|` beyond the thickness.
pub const QUERY_PAD: f32 = 1e-6;

/// How a contact was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactKind {
    /// The step `x -> p` crossed the face.
    Crossing,
    /// The step ended closer than the thickness to the face.
    Proximity,
}

/// A particle's contact with a mesh face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Face index in the mesh.
    pub face: u32,
    /// Crossing point on the face (crossing) or closest face point to `p` (proximity).
    pub point: [f32; 3],
    /// Unit face normal turned towards the side the particle came from.
    pub normal: [f32; 3],
    /// Time of impact as a fraction of the step, in `[0, 1]` (`1` for proximity).
    pub t: f32,
    /// How far `p` must move along `normal` to stand the thickness off the face's plane.
    pub depth: f32,
    /// Crossing or proximity.
    pub kind: ContactKind,
}

type V = [f64; 3];

#[inline]
fn d(a: [f32; 3]) -> V {
    [a[0] as f64, a[1] as f64, a[2] as f64]
}
#[inline]
fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
fn cross(a: V, b: V) -> V {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
#[inline]
fn axpy(a: V, t: f64, b: V) -> V {
    [a[0] + t * b[0], a[1] + t * b[1], a[2] + t * b[2]]
}

/// Closest point of triangle `abc` to `q` (Voronoi-region walk over vertices, edges, face;
/// Ericson, Real-Time Collision Detection 5.1.5). Every division is by a squared edge length
/// or twice-area term, positive for a non-degenerate triangle.
pub fn closest_point_on_triangle(q: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let (ab, ac, aq) = (sub(b, a), sub(c, a), sub(q, a));
    let (d1, d2) = (dot(ab, aq), dot(ac, aq));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bq = sub(q, b);
    let (d3, d4) = (dot(ab, bq), dot(ac, bq));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return axpy(a, d1 / (d1 - d3), ab);
    }
    let cq = sub(q, c);
    let (d5, d6) = (dot(ab, cq), dot(ac, cq));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return axpy(a, d2 / (d2 - d6), ac);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return axpy(b, (d4 - d3) / ((d4 - d3) + (d5 - d6)), sub(c, b));
    }
    let den = 1.0 / (va + vb + vc);
    let (v, w) = (vb * den, vc * den);
    axpy(axpy(a, v, ab), w, ac)
}

/// Are the barycentric weights of `q` (projected on the plane of `abc`, normal `n` not
/// normalised, `nn = n.n`) all at least `-tol`?
#[inline]
pub(crate) fn inside(q: V, a: V, b: V, c: V, n: V, nn: f64, tol: f64) -> bool {
    let (qa, qb, qc) = (sub(a, q), sub(b, q), sub(c, q));
    dot(cross(qb, qc), n) >= -tol * nn && dot(cross(qc, qa), n) >= -tol * nn && dot(cross(qa, qb), n) >= -tol * nn
}

/// The behind-the-plane pad of [`face_contact`]: [`PLANE_SLACK`] times `1 + max |p_k|`.
#[inline]
fn slack(p: V) -> f64 {
    PLANE_SLACK * (1.0 + p.iter().fold(0.0f64, |m, v| m.max(v.abs())))
}

/// Tests the step `x -> p` of a particle with thickness `th` against face `f` alone.
pub fn face_contact(mesh: &TriMesh, f: u32, x: [f32; 3], p: [f32; 3], th: f32) -> Option<Contact> {
    let FacePlane { a, n, nn, u } = mesh.planes()[f as usize];
    let (xd, pd) = (d(x), d(p));
    let hx = dot(u, sub(xd, a));
    let hp = dot(u, sub(pd, a));
    let s = match mesh.solid_side() {
        Some(side) => side as f64,
        None if hx < 0.0 => -1.0,
        None => 1.0,
    };
    let crossing = s * hp < 0.0 && s * hx >= 0.0;
    // Cheap reject: no crossing, and `p` is farther than `th` from the plane (so from the
    // triangle) on either side. Behind the plane the bound is padded by `PLANE_SLACK`
    // relative to the coordinates, far above the rounding of `hp` and of the closest point,
    // so no proximity the full test would find is dropped (the pad is computed only when
    // `p` lies behind the plane by more than `th`).
    if !crossing && (th.is_nan() || s * hp >= th as f64 || (s * hp <= -(th as f64) && s * hp <= -(th as f64) - slack(pd))) {
        return None;
    }
    let [_, b, c] = mesh.corners(f);
    let (b, c) = (d(b), d(c));
    let fnorm = mesh.normals()[f as usize];
    let make = |point: V, t: f64, kind| Contact {
        face: f,
        point: point.map(|k| k as f32),
        normal: fnorm.map(|k| if s < 0.0 { -k } else { k }),
        t: t as f32,
        depth: (th as f64 - s * hp) as f32,
        kind,
    };
    if crossing {
        let t = hx / (hx - hp);
        let q = axpy(xd, t, sub(pd, xd));
        if inside(q, a, b, c, n, nn, EDGE_TOLERANCE) {
            return Some(make(q, t, ContactKind::Crossing));
        }
    }
    let th2 = th as f64 * th as f64;
    if th > 0.0 && s * hp < th as f64 {
        let cp = closest_point_on_triangle(pd, a, b, c);
        let r = sub(pd, cp);
        if dot(r, r) < th2 {
            return Some(make(cp, 1.0, ContactKind::Proximity));
        }
    }
    None
}

/// The box a step `x -> p` with thickness `th` may touch: the segment's box grown by `th`
/// and by [`QUERY_PAD`] relative to the coordinates' size.
pub fn query_box(x: [f32; 3], p: [f32; 3], th: f32) -> ([f32; 3], [f32; 3]) {
    let mut big = 0.0f32;
    for v in [x[0], x[1], x[2], p[0], p[1], p[2]] {
        big = big.max(v.abs());
    }
    let g = th + QUERY_PAD * (1.0 + big);
    let lo = [x[0].min(p[0]) - g, x[1].min(p[1]) - g, x[2].min(p[2]) - g];
    (lo, [x[0].max(p[0]) + g, x[1].max(p[1]) + g, x[2].max(p[2]) + g])
}

/// Is contact `a` chosen over `b`? Smaller time of impact first, then smaller face index.
#[inline]
pub fn precedes(a: &Contact, b: &Contact) -> bool {
    a.t < b.t || (a.t == b.t && a.face < b.face)
}

/// The first contact of the step `x -> p` (thickness `th`) with `mesh`, using `scratch` for
/// the candidate list. Deterministic and independent of the broadphase (module doc).
pub fn mesh_contact_with<B: FaceBroadphase + ?Sized>(
    mesh: &TriMesh,
    bp: &B,
    x: [f32; 3],
    p: [f32; 3],
    th: f32,
    scratch: &mut Vec<u32>,
) -> Option<Contact> {
    let (lo, hi) = query_box(x, p, th);
    bp.candidates(mesh, lo, hi, scratch);
    let mut best: Option<Contact> = None;
    for &f in scratch.iter() {
        if (f as usize) < mesh.face_count() && mesh.face_overlaps(f, lo, hi) {
            if let Some(c) = face_contact(mesh, f, x, p, th) {
                if best.as_ref().is_none_or(|b| precedes(&c, b)) {
                    best = Some(c);
                }
            }
        }
    }
    best
}

/// [`mesh_contact_with`] with its own scratch list.
pub fn mesh_contact<B: FaceBroadphase + ?Sized>(mesh: &TriMesh, bp: &B, x: [f32; 3], p: [f32; 3], th: f32) -> Option<Contact> {
    mesh_contact_with(mesh, bp, x, p, th, &mut Vec::new())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::face_broadphase::BruteForce;

    use crate::collide::mesh::unit_square as square;

    #[test]
    fn crossing_gives_time_point_and_side() {
        let m = square();
        let c = face_contact(&m, 0, [0.75, 0.25, 1.0], [0.75, 0.25, -1.0], 0.1).unwrap();
        assert_eq!(c.kind, ContactKind::Crossing);
        assert_eq!(c.t, 0.5);
        assert_eq!(c.point, [0.75, 0.25, 0.0]);
        assert_eq!(c.normal, [0.0, 0.0, 1.0]);
        assert!((c.depth - 1.1).abs() < 1e-6);
        let c = face_contact(&m, 0, [0.75, 0.25, -1.0], [0.75, 0.25, 3.0], 0.0).unwrap();
        assert_eq!((c.t, c.normal), (0.25, [0.0, 0.0, -1.0]));
        assert!(face_contact(&m, 1, [0.75, 0.25, 1.0], [0.75, 0.25, -1.0], 0.1).is_none());
    }

    #[test]
    fn proximity_and_misses() {
        let m = square();
        let c = face_contact(&m, 0, [0.75, 0.25, 1.0], [0.75, 0.25, 0.05], 0.1).unwrap();
        assert_eq!(c.kind, ContactKind::Proximity);
        assert_eq!(c.t, 1.0);
        assert!((c.depth - 0.05).abs() < 1e-6);
        assert!(face_contact(&m, 0, [0.75, 0.25, 1.0], [0.75, 0.25, 0.2], 0.1).is_none());
        // past the edge, near it: proximity measured to the edge
        let c = face_contact(&m, 0, [1.05, 0.5, 1.0], [1.05, 0.5, 0.0], 0.1).unwrap();
        assert_eq!(c.point, [1.0, 0.5, 0.0]);
        assert!(face_contact(&m, 0, [1.2, 0.5, 1.0], [1.2, 0.5, -1.0], 0.1).is_none());
    }

    #[test]
    fn exact_edges_vertices_and_in_plane_are_finite() {
        let m = square();
        let bp = BruteForce::new(&m);
        // through the shared diagonal: both faces hit, the smaller index wins
        let c = mesh_contact(&m, &bp, [0.5, 0.5, 1.0], [0.5, 0.5, -1.0], 0.01).unwrap();
        assert_eq!((c.face, c.t), (0, 0.5));
        // through a corner vertex
        let c = mesh_contact(&m, &bp, [1.0, 1.0, 1.0], [1.0, 1.0, -1.0], 0.0).unwrap();
        assert_eq!(c.point, [1.0, 1.0, 0.0]);
        // lying in the plane, on the face: proximity, normal is the outside
        let c = mesh_contact(&m, &bp, [0.2, 0.1, 0.0], [0.6, 0.1, 0.0], 0.01).unwrap();
        assert_eq!((c.kind, c.normal, c.depth), (ContactKind::Proximity, [0.0, 0.0, 1.0], 0.01));
        // starting exactly on the face, moving in: crossing at t = 0
        let c = mesh_contact(&m, &bp, [0.3, 0.1, 0.0], [0.3, 0.1, -0.5], 0.0).unwrap();
        assert_eq!((c.kind, c.t), (ContactKind::Crossing, 0.0));
        // zero-length step on a vertex, zero thickness: nothing, no NaN
        assert!(mesh_contact(&m, &bp, [0.0; 3], [0.0; 3], 0.0).is_none());
        for q in [[0.0f32; 3], [1.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.5, 0.0, 0.0]] {
            let c = mesh_contact(&m, &bp, q, q, 0.05).unwrap();
            assert!(c.point.iter().chain(&c.normal).all(|v| v.is_finite()));
            assert_eq!(c.depth, 0.05);
        }
    }

    #[test]
    fn solids_have_one_outside() {
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let f = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let (m, _) = TriMesh::new(v, f).unwrap();
        let bp = BruteForce::new(&m);
        let (inside, below) = ([0.2, 0.2, 0.2], [0.2, 0.2, -0.5]);
        // entering: caught, normal points out of the solid
        let c = mesh_contact(&m, &bp, below, inside, 0.0).unwrap();
        assert_eq!((c.face, c.kind, c.normal), (0, ContactKind::Crossing, [0.0, 0.0, -1.0]));
        // leaving: let out
        assert!(mesh_contact(&m, &bp, inside, below, 0.0).is_none());
        // ended just inside the floor, within the thickness: pushed out, below the floor
        let c = mesh_contact(&m, &bp, [0.2, 0.2, 0.05], [0.2, 0.2, 0.01], 0.02).unwrap();
        assert_eq!((c.face, c.normal), (0, [0.0, 0.0, -1.0]));
        assert!((c.depth - 0.03).abs() < 1e-6);
        // as a two-sided sheet the same step is kept inside instead
        let mut sheet = m.clone();
        sheet.set_two_sided();
        let c = mesh_contact(&sheet, &bp, [0.2, 0.2, 0.05], [0.2, 0.2, 0.01], 0.02).unwrap();
        assert_eq!(c.normal, [0.0, 0.0, 1.0]);
    }

    #[test]
    fn nan_input_gives_no_contact() {
        let m = square();
        let bp = BruteForce::new(&m);
        assert!(mesh_contact(&m, &bp, [f32::NAN, 0.5, 1.0], [0.5, 0.5, -1.0], 0.1).is_none());
        assert!(mesh_contact(&m, &bp, [0.5, 0.5, 1.0], [0.5, 0.5, -1.0], f32::NAN).is_none());
    }

    /// The old per-test computation, without the precomputed plane and the cheap reject.
    fn full(mesh: &TriMesh, f: u32, x: [f32; 3], p: [f32; 3], th: f32) -> Option<Contact> {
        let [a, b, c] = mesh.corners(f).map(d);
        let n = cross(sub(b, a), sub(c, a));
        let nn = dot(n, n);
        let u = n.map(|k| k / nn.sqrt());
        let (xd, pd) = (d(x), d(p));
        let (hx, hp) = (dot(u, sub(xd, a)), dot(u, sub(pd, a)));
        let s = match mesh.solid_side() {
            Some(side) => side as f64,
            None if hx < 0.0 => -1.0,
            None => 1.0,
        };
        let fnorm = mesh.normals()[f as usize];
        let make = |point: V, t: f64, kind| Contact {
            face: f,
            point: point.map(|k| k as f32),
            normal: fnorm.map(|k| if s < 0.0 { -k } else { k }),
            t: t as f32,
            depth: (th as f64 - s * hp) as f32,
            kind,
        };
        if s * hp < 0.0 && s * hx >= 0.0 {
            let t = hx / (hx - hp);
            let q = axpy(xd, t, sub(pd, xd));
            if inside(q, a, b, c, n, nn, EDGE_TOLERANCE) {
                return Some(make(q, t, ContactKind::Crossing));
            }
        }
        if th > 0.0 && s * hp < th as f64 {
            let cp = closest_point_on_triangle(pd, a, b, c);
            let r = sub(pd, cp);
            if dot(r, r) < th as f64 * th as f64 {
                return Some(make(cp, 1.0, ContactKind::Proximity));
            }
        }
        None
    }

    #[test]
    fn precomputed_planes_and_the_cheap_reject_change_no_answer() {
        let mut m = crate::collide::dressform::dress_form(600).unwrap();
        let (lo, hi) = m.bounds();
        let mut r = crate::test_rng::unit(11);
        let mut hits = 0;
        for round in 0..2 {
            if round == 1 {
                m.set_two_sided();
            }
            for _ in 0..400 {
                let f = (r() * m.face_count() as f32) as u32;
                let [a, b, c] = m.corners(f);
                let (wa, wb) = (r(), r());
                let on = [0, 1, 2].map(|k| a[k] + wa * (b[k] - a[k]) * (1.0 - wb) + wb * (c[k] - a[k]) * (1.0 - wa));
                let nrm = m.normals()[f as usize];
                for _ in 0..8 {
                    let h = (r() - 0.5) * 0.02;
                    let x = [0, 1, 2].map(|k| on[k] + nrm[k] * h + (r() - 0.5) * 0.01);
                    let p = [0, 1, 2].map(|k| x[k] + (r() - 0.5) * 0.012);
                    let th = [0.0, 0.001, 0.004, f32::NAN][(r() * 4.0) as usize % 4];
                    for g in 0..m.face_count() as u32 {
                        let want = full(&m, g, x, p, th);
                        hits += want.is_some() as usize;
                        // Debug text: NaN depths (th = NaN) compare equal too
                        let got = format!("{:?}", face_contact(&m, g, x, p, th));
                        assert_eq!(got, format!("{want:?}"), "face {g} x {x:?} p {p:?} th {th}");
                    }
                    let far = [0, 1, 2].map(|k| lo[k] + (hi[k] - lo[k]) * r());
                    assert_eq!(face_contact(&m, f, far, p, 0.004), full(&m, f, far, p, 0.004));
                }
            }
        }
        assert!(hits > 1000, "{hits}");
    }
}
