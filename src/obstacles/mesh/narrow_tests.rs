//! Tests of `narrow.rs`.
use super::*;
use crate::obstacles::mesh::broadphase::BruteForce;

use crate::obstacles::mesh::unit_square as square;

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
            let mut contact = make(cp, 1.0, ContactKind::Proximity);
            if s * hp > 0.0 && !inside(axpy(pd, -hp, u), a, b, c, n, nn, EDGE_TOLERANCE) {
                let len = dot(r, r).sqrt();
                contact.normal = r.map(|k| (k / len) as f32);
                contact.depth = (th as f64 - len) as f32;
            }
            return Some(contact);
        }
    }
    None
}

#[test]
fn precomputed_planes_and_the_cheap_reject_change_no_answer() {
    let mut m = crate::obstacles::mesh::dressform::dress_form(600).unwrap();
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

/// A particle a thickness above a flat top, just beyond its convex rim, is within the
/// thickness of the rim's edge only: the contact stands it off the (round) edge, not off the
/// side face's plane, so the response moves it by the tiny depth, not sideways by almost `Th`.
#[test]
fn beside_a_convex_rim_the_contact_normal_points_from_the_edge() {
    let v = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 0.0, -1.0],
        [1.0, 1.0, -1.0],
    ];
    let (m, _) = TriMesh::new(v, vec![[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]]).unwrap();
    let th = 0.1;
    let (x, p) = ([1.001, 0.5, 0.2], [1.001, 0.5, 0.0999]);
    let mut contacts = 0;
    for f in 0..m.face_count() as u32 {
        let Some(c) = face_contact(&m, f, x, p, th) else { continue };
        contacts += 1;
        assert_eq!(c.kind, ContactKind::Proximity);
        let len = (0.001f64.powi(2) + 0.0999f64.powi(2)).sqrt();
        assert!(
            (c.normal[0] as f64 - 0.001 / len).abs() < 1e-5 && (c.normal[2] as f64 - 0.0999 / len).abs() < 1e-5,
            "face {f}: {c:?}"
        );
        assert!((c.depth as f64 - (th as f64 - len)).abs() < 1e-6, "face {f}: {c:?}");
        let q = crate::obstacles::mesh::response::resolve_position(x, p, &c, th);
        let moved = (0..3).map(|k| (q[k] - p[k]).powi(2)).sum::<f32>().sqrt();
        assert!(moved < 1e-4, "face {f} moved the particle {moved} m: {c:?}");
    }
    // the rim's edge belongs to a top face and to a side face
    assert!(contacts >= 2, "{contacts}");
    // straight above the top, the face normal as before
    let c = face_contact(&m, 1, [0.2, 0.5, 0.2], [0.2, 0.5, 0.05], th).unwrap();
    assert_eq!((c.normal, c.depth), ([0.0, 0.0, 1.0], 0.05));
}
