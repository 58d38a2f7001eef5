//! How deep particles sit inside obstacles: the measure behind the no-penetration tests and
//! the `max_penetration` column of `weft reproduce landovsky`.
//!
//! Analytic shapes have exact signed distances ([`Shape::signed_distance`](crate::model::shapes::Shape::signed_distance)). For a closed
//! mesh the signed distance of `q` is the distance to the nearest face, negative when `q` lies
//! behind that face's outward normal: `sign((q - c).n)` with `c` the closest point (ties to the
//! smaller face index). Near an edge or a vertex `q - c` lies in the cone of the adjacent
//! normals, so the sign agrees for every face that shares `c`. Open meshes have no inside and
//! count as zero penetration.

use crate::obstacles::mesh::broadphase::FaceBroadphase;
use crate::obstacles::mesh::narrow::closest_point_on_triangle;
use crate::obstacles::mesh::TriMesh;

/// Search radius around a point, m (every face is searched when no face is this close and the
/// point is inside the mesh box).
const PROBE: f32 = 0.02;

/// Signed distance of `q` to a closed mesh (module doc); `None` for an open mesh or when no
/// face lies within reach of a point outside the mesh box.
pub fn mesh_signed_distance<B: FaceBroadphase + ?Sized>(mesh: &TriMesh, bp: &B, q: [f32; 3], scratch: &mut Vec<u32>) -> Option<f32> {
    let side = mesh.solid_side()? as f64;
    let (lo, hi) = mesh.bounds();
    let inside_box = (0..3).all(|k| q[k] >= lo[k] && q[k] <= hi[k]);
    let qd = q.map(|c| c as f64);
    let nearest = |faces: &mut dyn Iterator<Item = u32>| {
        let mut best: Option<(f64, u32, [f64; 3])> = None;
        for f in faces {
            let [a, b, c] = mesh.corners(f).map(|v| v.map(|x| x as f64));
            let cp = closest_point_on_triangle(qd, a, b, c);
            let d2: f64 = (0..3).map(|k| (qd[k] - cp[k]) * (qd[k] - cp[k])).sum();
            if best.is_none_or(|(bd, bf, _)| d2 < bd || (d2 == bd && f < bf)) {
                best = Some((d2, f, cp));
            }
        }
        best.map(|(d2, f, cp)| {
            let n = mesh.normals()[f as usize].map(|x| x as f64);
            let s: f64 = (0..3).map(|k| (qd[k] - cp[k]) * n[k]).sum::<f64>() * side;
            (if s < 0.0 { -d2.sqrt() } else { d2.sqrt() }) as f32
        })
    };
    let (plo, phi) = (q.map(|c| c - PROBE), q.map(|c| c + PROBE));
    bp.candidates(mesh, plo, phi, scratch);
    // only faces that can be within the probe: the same set whatever the broadphase
    let near = nearest(
        &mut scratch
            .iter()
            .copied()
            .filter(|&f| (f as usize) < mesh.face_count() && mesh.face_overlaps(f, plo, phi)),
    );
    match near {
        Some(d) if d.abs() <= PROBE => Some(d),
        _ if inside_box => nearest(&mut (0..mesh.face_count() as u32)),
        _ => None,
    }
}
