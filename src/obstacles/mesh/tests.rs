//! Tests of `mesh.rs`.
use super::*;

fn tetra() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let f = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    (v, f)
}

#[test]
fn tetra_is_closed_and_outward() {
    let (v, f) = tetra();
    let (m, r) = TriMesh::new(v, f).unwrap();
    assert_eq!(r.non_manifold_edges, 0);
    assert_eq!(r.boundary_edges, 0);
    assert!(r.warnings.is_empty());
    assert!((m.signed_volume() - 1.0 / 6.0).abs() < 1e-9);
    assert_eq!(m.solid_side(), Some(1.0));
    let (v, f) = tetra();
    let inward = f.iter().map(|t| [t[0], t[2], t[1]]).collect();
    assert_eq!(TriMesh::new(v.clone(), inward).unwrap().0.solid_side(), Some(-1.0));
    let mut mixed = f.clone();
    mixed[1] = [0, 3, 1];
    let (mm, r) = TriMesh::new(v, mixed).unwrap();
    assert_eq!((mm.solid_side(), r.misoriented_edges), (None, 3));
    assert_eq!(m.bounds(), ([0.0; 3], [1.0; 3]));
    assert_eq!(m.normals()[0], [0.0, 0.0, -1.0]);
}

#[test]
fn bad_input_is_an_error() {
    let (v, f) = tetra();
    let mut vn = v.clone();
    vn[2][1] = f32::NAN;
    let e = TriMesh::new(vn, f.clone()).unwrap_err().to_string();
    assert!(e.contains("vertex 2 is not finite"), "{e}");
    let mut fi = f.clone();
    fi[3][2] = 9;
    let e = TriMesh::new(v.clone(), fi).unwrap_err().to_string();
    assert!(e.contains("face 3 uses vertex 9"), "{e}");
    assert!(TriMesh::new(vec![], vec![]).is_err());
    assert!(TriMesh::new(v.clone(), vec![]).is_err());
    let e = TriMesh::new(v, vec![[0, 0, 1]]).unwrap_err().to_string();
    assert!(e.contains("zero area"), "{e}");
}

#[test]
fn slivers_skipped_and_non_manifold_counted() {
    let (mut v, mut f) = tetra();
    v.push([0.5, 0.5, 0.0]); // on edge 1-2: face (1,2,4) has zero area
    f.push([1, 2, 4]);
    v.push([0.3, 0.3, -1.0]); // a fin on edge 0-1: that edge now has three faces
    f.push([0, 1, 5]);
    let (m, r) = TriMesh::new(v, f).unwrap();
    assert_eq!(r.skipped_faces, vec![4]);
    assert_eq!(m.face_count(), 5);
    assert_eq!(r.non_manifold_edges, 1);
    assert_eq!(r.boundary_edges, 2);
    assert_eq!(r.warnings.len(), 3);
    assert_eq!(m.solid_side(), None);
}

#[test]
fn translate_moves_boxes_and_changes_stamp() {
    let (v, f) = tetra();
    let (mut m, _) = TriMesh::new(v, f).unwrap();
    let s = m.stamp();
    m.translate([1.0, 2.0, 3.0]).unwrap();
    assert_ne!(m.stamp(), s);
    assert_eq!(m.bounds(), ([1.0, 2.0, 3.0], [2.0, 3.0, 4.0]));
    assert_eq!(m.face_lo(3), [1.0, 2.0, 3.0]);
    // the box filter: every face overlaps all of space, an index out of range overlaps nothing
    let all = ([f32::NEG_INFINITY; 3], [f32::INFINITY; 3]);
    assert!((0..4).all(|f| m.face_overlaps(f, all.0, all.1)));
    assert!(!m.face_overlaps(4, all.0, all.1) && !m.face_overlaps(u32::MAX, all.0, all.1));
    assert!(m.translate([f32::NAN, 0.0, 0.0]).is_err());
    assert!(m.translate([f32::MAX, 0.0, 0.0]).is_err());
}
