//! Narrowphase: a particle's step `x -> p` against the faces of a mesh (Landovskaya, Landovsky & Frolovsky).
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
//!    `Th`, the particle ends inside the fabric's thickness layer: a contact at `t = 1`. When
//!    `p` is in front of the plane but its projection falls outside the triangle, `c` lies on
//!    an edge or a corner, where the layer is rounded: the contact normal is then
//!    `(p - c) / |p - c|` and the depth `Th - |p - c|`. With the face normal instead, a
//!    particle resting a thickness above a flat top beside a convex rim was pushed almost
//!    `Th` sideways by the rim's side face, in one substep.
//!
//! The plane data of step 1 (corner, normal, unit normal) is computed once per mesh state
//! ([`FacePlane`]), with the same operations, and a face is rejected right after the two
//! heights when the path does not cross its plane and `p` lies farther than `Th` from it on
//! either side (behind the plane with a tiny relative pad, [`PLANE_SLACK`]): no triangle
//! point can then be within `Th`. Both change the cost, not the answer (a test compares with
//! the full computation).
//!
//! A contact carries the face, the point (`q` or `c`), the face normal turned to the
//! particle's side (`s n`, or the edge normal of step 3), the time of impact `t`, and
//! `depth = Th - s*hp` (`Th - |p - c|` at an edge), how far `p` must move along that normal to
//! stand `Th` off the contact plane.
//!
//! [`mesh_contact`] asks a broadphase for candidates, keeps exactly the faces whose box
//! overlaps the step's box grown by `Th` (plus a tiny relative pad), and returns the contact
//! with the smallest `t`, ties going to the smallest face index. The candidate sets of
//! different broadphases differ, but the faces tested and the choice made do not, so every
//! broadphase gives bit-identical contacts.

use crate::obstacles::mesh::broadphase::FaceBroadphase;
use crate::obstacles::mesh::{FacePlane, TriMesh};

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
        let r2 = dot(r, r);
        if r2 < th2 {
            let mut contact = make(cp, 1.0, ContactKind::Proximity);
            if s * hp > 0.0 && !inside(axpy(pd, -hp, u), a, b, c, n, nn, EDGE_TOLERANCE) {
                // In front of the face but beside it: the nearest point is on an edge or a
                // corner, and the layer around them is round. Stand off along `p - c`.
                let len = r2.sqrt();
                contact.normal = r.map(|k| (k / len) as f32);
                contact.depth = (th as f64 - len) as f32;
            }
            return Some(contact);
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
#[path = "narrow_tests.rs"]
mod tests;
