//! A particle's contact with a mesh obstacle during the step: which face's plane to stand off.
//!
//! The narrowphase ([`face_contact`]) tests each face; this module chooses among the faces the
//! broadphase offers. A **crossing** (the path went through a face) wins over any proximity,
//! and the earliest crossing (smallest `t`, then smallest face index) is the one the paper
//! resolves. Without a crossing, the **nearest** face within reach (smallest `|p - c|`, then
//! smallest face index) gives the contact plane: the step keeps contacts within a reach of a
//! few millimetres, and near a concave edge the lowest-index face within that reach may face
//! another way, so projecting onto its plane would push the particle into the neighbour.
//! [`mesh_contact`](crate::obstacles::mesh::narrow::mesh_contact) keeps its own rule (first `t`, then face
//! index) for its callers. Only faces whose box overlaps the query box are tested, so every
//! broadphase gives the same bits.
//!
//! [`MeshBroadphase`] holds the broadphase a mesh obstacle was given ([`BroadphaseKind`]).
//!
//! With face memory (the paper; [`face_memory`](crate::obstacles::mesh::face_memory)), a particle whose start
//! and prediction both lie over its remembered face tests that face alone; otherwise the full
//! search runs and remembers the face it found (or forgets).

use crate::error::Result;
use crate::obstacles::mesh::broadphase::bvh::Bvh;
use crate::obstacles::mesh::broadphase::grid::UniformGrid;
use crate::obstacles::mesh::broadphase::hash::FaceHash;
use crate::obstacles::mesh::broadphase::FaceBroadphase;
use crate::obstacles::mesh::face_memory::{over_face, NO_FACE};
use crate::obstacles::mesh::narrow::{face_contact, query_box, Contact, ContactKind};
use crate::obstacles::mesh::TriMesh;

/// Which broadphase a mesh obstacle uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BroadphaseKind {
    /// The paper's uniform grid with these cells per axis, or sized automatically (`None`).
    Grid(Option<[usize; 3]>),
    /// An AABB tree of the faces.
    Bvh,
    /// A spatial hash of the faces.
    Hash,
}

/// A built broadphase.
#[derive(Debug, Clone)]
pub enum MeshBroadphase {
    /// Uniform grid.
    Grid(UniformGrid),
    /// AABB tree.
    Bvh(Bvh),
    /// Spatial hash.
    Hash(FaceHash),
}

impl MeshBroadphase {
    /// Builds the broadphase `kind` for `mesh`.
    pub fn build(kind: BroadphaseKind, mesh: &TriMesh) -> Result<Self> {
        Ok(match kind {
            BroadphaseKind::Grid(Some(d)) => MeshBroadphase::Grid(UniformGrid::new(mesh, d)?),
            BroadphaseKind::Grid(None) => MeshBroadphase::Grid(UniformGrid::auto(mesh)?),
            BroadphaseKind::Bvh => MeshBroadphase::Bvh(Bvh::new(mesh)),
            BroadphaseKind::Hash => MeshBroadphase::Hash(FaceHash::auto(mesh)?),
        })
    }
    fn inner(&self) -> &(dyn FaceBroadphase + Sync) {
        match self {
            MeshBroadphase::Grid(g) => g,
            MeshBroadphase::Bvh(b) => b,
            MeshBroadphase::Hash(h) => h,
        }
    }
}

impl FaceBroadphase for MeshBroadphase {
    fn candidates(&self, mesh: &TriMesh, lo: [f32; 3], hi: [f32; 3], out: &mut Vec<u32>) {
        self.inner().candidates(mesh, lo, hi, out)
    }
    fn stamp(&self) -> u64 {
        self.inner().stamp()
    }
    fn describe(&self) -> String {
        self.inner().describe()
    }
}

fn dist2(a: [f32; 3], b: [f32; 3]) -> f32 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

/// Is `a` preferred over `b` for the step ending at `p` (module doc)?
fn better(a: &Contact, b: &Contact, p: [f32; 3]) -> bool {
    match (a.kind, b.kind) {
        (ContactKind::Crossing, ContactKind::Proximity) => true,
        (ContactKind::Proximity, ContactKind::Crossing) => false,
        (ContactKind::Crossing, ContactKind::Crossing) => a.t < b.t || (a.t == b.t && a.face < b.face),
        (ContactKind::Proximity, ContactKind::Proximity) => {
            let (da, db) = (dist2(p, a.point), dist2(p, b.point));
            da < db || (da == db && a.face < b.face)
        }
    }
}

/// The contact of the step `x -> p` with `mesh` within `reach` (module doc).
pub fn step_contact<B: FaceBroadphase + ?Sized>(
    mesh: &TriMesh,
    bp: &B,
    x: [f32; 3],
    p: [f32; 3],
    reach: f32,
    scratch: &mut Vec<u32>,
) -> Option<Contact> {
    let (lo, hi) = query_box(x, p, reach);
    bp.candidates(mesh, lo, hi, scratch);
    best_contact(mesh, scratch, x, p, reach, lo, hi)
}

/// The preferred contact (module doc) among the `faces` whose box overlaps the step's query
/// box `[lo, hi]`; `faces` must hold at least every face overlapping it, in any order.
pub(crate) fn best_contact(
    mesh: &TriMesh,
    faces: &[u32],
    x: [f32; 3],
    p: [f32; 3],
    reach: f32,
    lo: [f32; 3],
    hi: [f32; 3],
) -> Option<Contact> {
    let mut best: Option<Contact> = None;
    for &f in faces {
        if mesh.face_overlaps(f, lo, hi) {
            if let Some(c) = face_contact(mesh, f, x, p, reach) {
                if best.as_ref().is_none_or(|b| better(&c, b, p)) {
                    best = Some(c);
                }
            }
        }
    }
    best
}

/// [`step_contact`] with the paper's face memory in `memory` (module doc); `band` is the
/// height above a face within which a point counts as over it.
#[allow(clippy::too_many_arguments)]
pub fn step_contact_remembered<B: FaceBroadphase + ?Sized>(
    mesh: &TriMesh,
    bp: &B,
    memory: &mut u32,
    x: [f32; 3],
    p: [f32; 3],
    reach: f32,
    band: f32,
    scratch: &mut Vec<u32>,
) -> Option<Contact> {
    remembered_with(mesh, memory, x, p, reach, band, || step_contact(mesh, bp, x, p, reach, scratch))
}

/// The face-memory rule around any full search `search` of the step (which must return
/// [`step_contact`]'s answer, e.g. from a [`CacheBlock`](crate::obstacles::mesh::face_cache::CacheBlock)).
pub(crate) fn remembered_with(
    mesh: &TriMesh,
    memory: &mut u32,
    x: [f32; 3],
    p: [f32; 3],
    reach: f32,
    band: f32,
    search: impl FnOnce() -> Option<Contact>,
) -> Option<Contact> {
    let f = *memory;
    if f != NO_FACE && over_face(mesh, f, x, band) && over_face(mesh, f, p, band) {
        return face_contact(mesh, f, x, p, reach);
    }
    let c = search();
    *memory = c.map_or(NO_FACE, |c| c.face);
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::obstacles::mesh::broadphase::grid::UniformGrid;
    use crate::obstacles::mesh::broadphase::BruteForce;

    /// An open "L" of two unit squares meeting at a concave edge along z: floor y = 0 and wall
    /// x = 0, faces in index order wall first.
    fn corner() -> TriMesh {
        let v = vec![
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 1.0, 1.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [1.0, 0.0, 1.0],
        ];
        TriMesh::new(v, vec![[0, 1, 2], [0, 2, 3], [0, 3, 5], [0, 5, 4]]).unwrap().0
    }

    #[test]
    fn nearest_face_wins_among_proximities() {
        let m = corner();
        let bp = BruteForce::new(&m);
        // just above the floor, 4 mm from the wall: the floor is nearer
        let (x, p) = ([0.004, 0.0015, 0.5], [0.004, 0.001, 0.5]);
        let c = step_contact(&m, &bp, x, p, 0.005, &mut Vec::new()).unwrap();
        assert!(c.face >= 2, "{c:?}");
        assert_eq!(c.kind, ContactKind::Proximity);
        // a crossing wins over proximities, and every broadphase agrees
        let (x, p) = ([0.5, 0.3, 0.5], [0.5, -0.2, 0.5]);
        let g = UniformGrid::new(&m, [3, 3, 3]).unwrap();
        let a = step_contact(&m, &bp, x, p, 0.005, &mut Vec::new()).unwrap();
        assert_eq!(a.kind, ContactKind::Crossing);
        assert_eq!(Some(a), step_contact(&m, &g, x, p, 0.005, &mut Vec::new()));
    }

    #[test]
    fn memory_keeps_and_forgets() {
        let m = corner();
        let bp = BruteForce::new(&m);
        let mut mem = NO_FACE;
        let c = step_contact_remembered(&m, &bp, &mut mem, [0.5, 0.3, 0.3], [0.5, -0.2, 0.3], 0.005, 0.01, &mut Vec::new()).unwrap();
        assert_eq!(mem, c.face);
        let again = step_contact_remembered(
            &m,
            &bp,
            &mut mem,
            [0.5, 0.002, 0.3],
            [0.51, 0.001, 0.3],
            0.005,
            0.01,
            &mut Vec::new(),
        );
        assert_eq!(again.map(|c| c.face), Some(mem));
        let gone = step_contact_remembered(&m, &bp, &mut mem, [0.5, 0.5, 0.3], [0.5, 0.6, 0.3], 0.005, 0.01, &mut Vec::new());
        assert!(gone.is_none());
        assert_eq!(mem, NO_FACE);
    }
}
