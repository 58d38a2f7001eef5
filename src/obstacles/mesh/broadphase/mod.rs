//! The broadphase contract for mesh obstacles: "which faces may touch this box?".
//!
//! A particle moving from `x` to `p` with fabric thickness `Th` can only touch faces whose
//! axis-aligned box overlaps the segment's box grown by `Th`. A broadphase answers that
//! question quickly and *conservatively*: it must return every face whose box overlaps the
//! query box (closed intervals, exact `f32` comparisons) and may return more. The narrowphase
//! ([`mesh_contact`](crate::obstacles::mesh::narrow::mesh_contact)) then tests exactly those overlapping faces
//! and breaks ties deterministically, so every correct broadphase yields bit-identical contacts.
//! Implementations: [`UniformGrid`](crate::obstacles::mesh::broadphase::grid::UniformGrid) (the paper's),
//! [`Bvh`](crate::obstacles::mesh::broadphase::bvh::Bvh), [`FaceHash`](crate::obstacles::mesh::broadphase::hash::FaceHash) and [`BruteForce`].

pub mod bvh;
pub mod grid;
pub mod hash;

use crate::obstacles::mesh::TriMesh;

/// Finds the faces of a [`TriMesh`] that may touch an axis-aligned box.
pub trait FaceBroadphase {
    /// Clears `out`, then fills it with face indices: at least every face whose box overlaps
    /// `[lo, hi]`. Order is unspecified and a face may appear more than once.
    fn candidates(&self, mesh: &TriMesh, lo: [f32; 3], hi: [f32; 3], out: &mut Vec<u32>);
    /// The [`TriMesh::stamp`] of the mesh state this structure was built for.
    fn stamp(&self) -> u64;
    /// Short description for reports and benches, e.g. `grid 5x5x5`.
    fn describe(&self) -> String;
}

/// No acceleration: every face is a candidate (the reference, and the paper's 1x1x1 grid).
#[derive(Debug, Clone)]
pub struct BruteForce {
    stamp: u64,
}

impl BruteForce {
    /// A brute-force broadphase for `mesh`.
    pub fn new(mesh: &TriMesh) -> Self {
        BruteForce { stamp: mesh.stamp() }
    }
}

impl FaceBroadphase for BruteForce {
    fn candidates(&self, mesh: &TriMesh, _lo: [f32; 3], _hi: [f32; 3], out: &mut Vec<u32>) {
        out.clear();
        out.extend(0..mesh.face_count() as u32);
    }
    fn stamp(&self) -> u64 {
        self.stamp
    }
    fn describe(&self) -> String {
        "brute force".into()
    }
}
