//! The paper's face memory (Landovskaya, Landovsky & Frolovsky).
//!
//! **The paper's rule.** After a particle crossed a face and was put back, "special conditions
//! apply: while it stays in the region of the crossed face, the force acting on it is the
//! projection of the resultant force onto the face". This (1) removes the test against every
//! other face and (2) stops repeated crossings of that face. Each particle keeps the index of
//! the face it interacted with on the previous step; when it is found outside that face's
//! region the search starts again from the whole-object box, and a new crossing replaces the
//! remembered face.
//!
//! **Our reading.** "The region of a face" is the prism over the triangle: a point `q` is over
//! face `f` when its projection on the face plane lies in the triangle and its height above
//! the plane is within a band, `|n.(q - a)| <= band` (choose `band` a little above the
//! thickness, e.g. `2 Th`). Memory is used for a step only when both the start `x` and the
//! prediction `p` are over the face, so a particle sliding off the face onto a neighbour is
//! searched in full that very step and cannot tunnel through the neighbour. While memory
//! holds, only the remembered face is tested (it still catches a re-crossing, which the
//! response undoes) and [`project_onto_face`] gives the force (or velocity) tangential to the
//! face: [`Projection::Full`] is the paper's projection; [`Projection::IntoFaceOnly`] removes
//! only a component pushing into the face, so cloth can still be lifted off.
//! [`NO_FACE`] (`u32::MAX`) marks an empty memory; an index out of range counts as empty.

use crate::obstacles::mesh::broadphase::FaceBroadphase;
use crate::obstacles::mesh::narrow::{face_contact, inside, mesh_contact_with, Contact};
use crate::obstacles::mesh::TriMesh;

/// Empty face memory.
pub const NO_FACE: u32 = u32::MAX;

/// How a vector is projected onto a remembered face.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Projection {
    /// Remove the whole normal component (the paper).
    Full,
    /// Remove the normal component only when it points into the face (against the outward
    /// normal of the face's winding).
    IntoFaceOnly,
}

/// Is `q` over face `f`: projection inside the triangle, height within `band` of its plane?
pub fn over_face(mesh: &TriMesh, f: u32, q: [f32; 3], band: f32) -> bool {
    if f as usize >= mesh.face_count() {
        return false;
    }
    let [a, b, c] = mesh.corners(f).map(|v| v.map(|x| x as f64));
    let qd = q.map(|x| x as f64);
    let n = mesh.normals()[f as usize].map(|x| x as f64);
    let h = n[0] * (qd[0] - a[0]) + n[1] * (qd[1] - a[1]) + n[2] * (qd[2] - a[2]);
    h.abs() <= band as f64 && inside(qd, a, b, c, n, 1.0, 0.0)
}

/// `v` projected onto the plane of face `f` according to `rule`.
pub fn project_onto_face(mesh: &TriMesh, f: u32, v: [f32; 3], rule: Projection) -> [f32; 3] {
    let Some(n) = mesh.normals().get(f as usize) else {
        return v;
    };
    let vn = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
    if rule == Projection::IntoFaceOnly && vn >= 0.0 {
        return v;
    }
    [0, 1, 2].map(|k| v[k] - vn * n[k])
}

/// Projects `v` onto the remembered face if the particle at `x` is over it; otherwise `v`.
pub fn project_if_remembered(mesh: &TriMesh, memory: u32, x: [f32; 3], band: f32, rule: Projection, v: [f32; 3]) -> [f32; 3] {
    if memory != NO_FACE && over_face(mesh, memory, x, band) {
        project_onto_face(mesh, memory, v, rule)
    } else {
        v
    }
}

/// Result of [`contact_with_memory`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemoryContact {
    /// The contact of this step, if any.
    pub contact: Option<Contact>,
    /// Whether only the remembered face was tested.
    pub used_memory: bool,
}

/// One step's contact search with face memory (module doc). Updates `memory`: kept while the
/// particle stays over the remembered face, cleared when it leaves, set to the face of a
/// contact found by the full search.
#[allow(clippy::too_many_arguments)]
pub fn contact_with_memory<B: FaceBroadphase + ?Sized>(
    mesh: &TriMesh,
    bp: &B,
    memory: &mut u32,
    x: [f32; 3],
    p: [f32; 3],
    th: f32,
    band: f32,
    scratch: &mut Vec<u32>,
) -> MemoryContact {
    let f = *memory;
    if f != NO_FACE && over_face(mesh, f, x, band) && over_face(mesh, f, p, band) {
        return MemoryContact {
            contact: face_contact(mesh, f, x, p, th),
            used_memory: true,
        };
    }
    let contact = mesh_contact_with(mesh, bp, x, p, th, scratch);
    *memory = contact.map_or(NO_FACE, |c| c.face);
    MemoryContact {
        contact,
        used_memory: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::obstacles::mesh::broadphase::BruteForce;

    use crate::obstacles::mesh::unit_square as square;

    #[test]
    fn memory_set_used_and_cleared() {
        let m = square();
        let bp = BruteForce::new(&m);
        let (th, band) = (0.05, 0.1);
        let mut mem = NO_FACE;
        let mut s = Vec::new();
        let r = contact_with_memory(&m, &bp, &mut mem, [0.8, 0.2, 0.5], [0.8, 0.2, -0.1], th, band, &mut s);
        assert!(!r.used_memory);
        assert_eq!(mem, 0);
        // resting on face 0 and pressing in: only face 0 tested, contact found
        let r = contact_with_memory(&m, &bp, &mut mem, [0.8, 0.2, 0.05], [0.8, 0.3, 0.0], th, band, &mut s);
        assert!(r.used_memory);
        assert_eq!(r.contact.unwrap().face, 0);
        // moving over face 1: full search, memory follows the new contact
        let r = contact_with_memory(&m, &bp, &mut mem, [0.8, 0.3, 0.05], [0.2, 0.7, 0.02], th, band, &mut s);
        assert!(!r.used_memory);
        assert_eq!(mem, 1);
        // lifted beyond the band: memory cleared
        let r = contact_with_memory(&m, &bp, &mut mem, [0.2, 0.7, 0.3], [0.2, 0.7, 0.5], th, band, &mut s);
        assert!(!r.used_memory && r.contact.is_none());
        assert_eq!(mem, NO_FACE);
        // garbage memory counts as empty
        let mut bad = 77;
        let r = contact_with_memory(&m, &bp, &mut bad, [0.2, 0.7, 0.3], [0.2, 0.7, 0.5], th, band, &mut s);
        assert!(!r.used_memory);
        assert_eq!(bad, NO_FACE);
    }

    #[test]
    fn projection_rules() {
        let m = square();
        let g = [1.0, 2.0, -9.8];
        assert_eq!(project_onto_face(&m, 0, g, Projection::Full), [1.0, 2.0, 0.0]);
        assert_eq!(project_onto_face(&m, 0, g, Projection::IntoFaceOnly), [1.0, 2.0, 0.0]);
        let up = [1.0, 2.0, 3.0];
        assert_eq!(project_onto_face(&m, 0, up, Projection::Full), [1.0, 2.0, 0.0]);
        assert_eq!(project_onto_face(&m, 0, up, Projection::IntoFaceOnly), up);
        assert_eq!(
            project_if_remembered(&m, 0, [0.9, 0.1, 0.01], 0.1, Projection::Full, g),
            [1.0, 2.0, 0.0]
        );
        assert_eq!(project_if_remembered(&m, 0, [0.1, 0.9, 0.01], 0.1, Projection::Full, g), g);
        assert_eq!(project_if_remembered(&m, NO_FACE, [0.9, 0.1, 0.01], 0.1, Projection::Full, g), g);
        assert!(over_face(&m, 0, [1.0, 0.0, 0.0], 0.0));
        assert!(!over_face(&m, 5, [1.0, 0.0, 0.0], 1.0));
    }
}
