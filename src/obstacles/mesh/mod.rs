//! Triangle-mesh obstacles: validated storage with per-face caches.
//!
//! An obstacle in Landovskaya, Landovsky & Frolovsky ("cloth against polyhedral solids") is "a finite set of points that are the vertices of its triangular
//! faces". [`TriMesh`] keeps exactly that, plus what every query needs again and again:
//!
//! * the unit face normal `n = (b - a) x (c - a) / |(b - a) x (c - a)|` (counter-clockwise
//!   winding seen from outside gives an outward normal),
//! * the face's axis-aligned box (min/max of its three vertices), and
//! * the whole mesh's box, which is the paper's first test ("is the particle inside the box
//!   around the object at all?").
//!
//! Input is checked: non-finite vertices, indices out of range and meshes with no usable face
//! are errors ([`WeftError::InvalidMesh`]). Zero-area and sliver faces (twice the area below
//! [`SLIVER_RATIO`] times the squared longest edge) cannot carry a normal, so they are dropped
//! and counted in [`MeshReport`]. Edges shared by more than two faces (non-manifold) and by a
//! single face (open boundary) are counted but accepted: collision does not need a closed
//! surface. A closed, consistently wound mesh is recognised as a solid
//! ([`TriMesh::solid_side`]), which fixes on which side of each face particles belong.

pub mod batch;
pub mod broadphase;
pub mod contact;
pub mod dressform;
pub mod face_ball;
pub mod face_cache;
pub mod face_memory;
pub mod narrow;
pub mod obj;
pub(crate) mod pass;
pub mod response;

use crate::{Result, WeftError};
use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};

/// A face is a sliver (and is skipped) when `|(b-a) x (c-a)| <= SLIVER_RATIO * longest_edge^2`.
pub const SLIVER_RATIO: f32 = 1e-6;

static NEXT_STAMP: AtomicU64 = AtomicU64::new(1);

fn fresh_stamp() -> u64 {
    NEXT_STAMP.fetch_add(1, Ordering::Relaxed)
}

/// What [`TriMesh::new`] found and forgave in its input.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshReport {
    /// Faces given.
    pub faces_in: usize,
    /// Input indices of faces dropped because they had (nearly) zero area.
    pub skipped_faces: Vec<usize>,
    /// Edges used by more than two faces.
    pub non_manifold_edges: usize,
    /// Edges used by exactly one face (the mesh is open there).
    pub boundary_edges: usize,
    /// Edges whose two faces run along them in the same direction (inconsistent winding).
    pub misoriented_edges: usize,
    /// Human-readable warnings, one per kind of problem found.
    pub warnings: Vec<String>,
}

/// A face's plane as the narrowphase ([`face_contact`](crate::obstacles::mesh::narrow::face_contact)) uses it,
/// computed once per mesh state in `f64` from the `f32` corners `a, b, c`: the first corner
/// `a`, the unnormalised normal `n = (b - a) x (c - a)`, `nn = n.n` and the unit normal
/// `u = n / sqrt(nn)` (each component divided by the square root, the very operations the
/// narrowphase performed per test before, so its results are unchanged).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FacePlane {
    /// First corner.
    pub a: [f64; 3],
    /// Unnormalised normal `(b - a) x (c - a)`.
    pub n: [f64; 3],
    /// `n.n`.
    pub nn: f64,
    /// Unit normal.
    pub u: [f64; 3],
}

impl FacePlane {
    /// The plane of the triangle with corners `c`.
    pub fn of(c: [[f32; 3]; 3]) -> FacePlane {
        let [a, b, c] = c.map(|v| v.map(|x| x as f64));
        let (e, g) = ([0, 1, 2].map(|k| b[k] - a[k]), [0, 1, 2].map(|k| c[k] - a[k]));
        let n = [e[1] * g[2] - e[2] * g[1], e[2] * g[0] - e[0] * g[2], e[0] * g[1] - e[1] * g[0]];
        let nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
        FacePlane {
            a,
            n,
            nn,
            u: n.map(|k| k / nn.sqrt()),
        }
    }
}

/// A validated triangle mesh with face normals and face boxes.
#[derive(Debug, Clone)]
pub struct TriMesh {
    vertices: Vec<[f32; 3]>,
    faces: Vec<[u32; 3]>,
    normals: Vec<[f32; 3]>,
    planes: Vec<FacePlane>,
    /// Each face's box `[lo, hi]`, the two corners side by side (one cache line per face for
    /// the narrowphase's box filter, which reads faces in no particular order).
    face_box: Vec<[[f32; 3]; 2]>,
    lo: [f32; 3],
    hi: [f32; 3],
    stamp: u64,
    solid_side: Option<f32>,
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn norm2(a: [f32; 3]) -> f32 {
    a[0] * a[0] + a[1] * a[1] + a[2] * a[2]
}

/// Is the triangle usable: finite, not a sliver (see [`SLIVER_RATIO`])?
fn face_ok([a, b, c]: [[f32; 3]; 3]) -> bool {
    let (e0, e1, e2) = (sub(b, a), sub(c, a), sub(c, b));
    let longest = norm2(e0).max(norm2(e1)).max(norm2(e2));
    let twice_area = norm2(cross(e0, e1)).sqrt();
    longest.is_finite() && twice_area.is_finite() && twice_area > SLIVER_RATIO * longest
}

fn bad(reason: String) -> WeftError {
    WeftError::InvalidMesh { source_name: None, reason }
}

impl TriMesh {
    /// Builds a mesh from vertex positions and triangles (indices into `vertices`).
    ///
    /// Errors: no vertices or no faces, a non-finite coordinate, an index out of range, or no
    /// face left after dropping slivers. Slivers and non-manifold/boundary edges are reported.
    pub fn new(vertices: Vec<[f32; 3]>, faces: Vec<[u32; 3]>) -> Result<(TriMesh, MeshReport)> {
        if vertices.is_empty() || faces.is_empty() {
            return Err(bad(format!("empty mesh ({} vertices, {} faces)", vertices.len(), faces.len())));
        }
        if vertices.len() > u32::MAX as usize || faces.len() >= u32::MAX as usize {
            return Err(bad(
                "too many vertices or faces (indices are u32; u32::MAX means \"no face\")".into()
            ));
        }
        if let Some((i, v)) = vertices.iter().enumerate().find(|(_, v)| !v.iter().all(|c| c.is_finite())) {
            return Err(bad(format!("vertex {i} is not finite: {v:?}")));
        }
        let nv = vertices.len();
        let mut report = MeshReport {
            faces_in: faces.len(),
            ..MeshReport::default()
        };
        let mut kept = Vec::with_capacity(faces.len());
        for (fi, f) in faces.iter().enumerate() {
            if let Some(&k) = f.iter().find(|&&k| k as usize >= nv) {
                return Err(bad(format!("face {fi} uses vertex {k} but there are only {nv} vertices")));
            }
            if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] || !face_ok(f.map(|k| vertices[k as usize])) {
                report.skipped_faces.push(fi);
            } else {
                kept.push(*f);
            }
        }
        if kept.is_empty() {
            return Err(bad(format!("all {} faces have zero area or are slivers", faces.len())));
        }
        if !report.skipped_faces.is_empty() {
            report.warnings.push(format!(
                "skipped {} zero-area or sliver faces (first: face {})",
                report.skipped_faces.len(),
                report.skipped_faces[0]
            ));
        }
        // per undirected edge: (uses, uses running from the smaller to the larger index)
        let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::with_capacity(kept.len() * 3 / 2);
        for f in &kept {
            for k in 0..3 {
                let (i, j) = (f[k], f[(k + 1) % 3]);
                let e = edges.entry((i.min(j), i.max(j))).or_insert((0, 0));
                e.0 += 1;
                e.1 += (i < j) as u32;
            }
        }
        report.non_manifold_edges = edges.values().filter(|c| c.0 > 2).count();
        report.boundary_edges = edges.values().filter(|c| c.0 == 1).count();
        report.misoriented_edges = edges.values().filter(|c| c.0 == 2 && c.1 != 1).count();
        if report.misoriented_edges > 0 {
            report.warnings.push(format!(
                "{} edges with inconsistent winding (faces on both sides run the same way)",
                report.misoriented_edges
            ));
        }
        if report.non_manifold_edges > 0 {
            report.warnings.push(format!(
                "{} non-manifold edges (shared by more than two faces)",
                report.non_manifold_edges
            ));
        }
        if report.boundary_edges > 0 {
            report
                .warnings
                .push(format!("{} boundary edges: the mesh is not closed", report.boundary_edges));
        }
        let mut mesh = TriMesh {
            vertices,
            faces: kept,
            normals: Vec::new(),
            planes: Vec::new(),
            face_box: Vec::new(),
            lo: [0.0; 3],
            hi: [0.0; 3],
            stamp: 0,
            solid_side: None,
        };
        mesh.recompute();
        let closed = report.non_manifold_edges + report.boundary_edges + report.misoriented_edges == 0;
        if closed {
            let v = mesh.signed_volume();
            if v != 0.0 {
                mesh.solid_side = Some(if v > 0.0 { 1.0 } else { -1.0 });
            }
        }
        Ok((mesh, report))
    }

    /// Moves the whole mesh by `d` (a moving obstacle) and recomputes the boxes.
    ///
    /// The mesh gets a new [`stamp`](Self::stamp): broadphases built before must be rebuilt
    /// (or, for [`Bvh`](crate::obstacles::mesh::broadphase::bvh::Bvh), refitted); batch queries refuse stale ones.
    pub fn translate(&mut self, d: [f32; 3]) -> Result<()> {
        crate::error::finite3("translation", d)?;
        let moved: Vec<[f32; 3]> = self.vertices.iter().map(|v| [v[0] + d[0], v[1] + d[1], v[2] + d[2]]).collect();
        if let Some(v) = moved.iter().find(|v| !v.iter().all(|c| c.is_finite())) {
            return Err(bad(format!("translation makes a vertex non-finite: {v:?}")));
        }
        if let Some(fi) = self.faces.iter().position(|f| !face_ok(f.map(|k| moved[k as usize]))) {
            return Err(bad(format!(
                "translation by {d:?} collapses face {fi} (coordinates too large for f32)"
            )));
        }
        self.vertices = moved;
        self.recompute();
        Ok(())
    }

    fn recompute(&mut self) {
        let n = self.faces.len();
        self.normals = Vec::with_capacity(n);
        self.planes = Vec::with_capacity(n);
        self.face_box = Vec::with_capacity(n);
        self.lo = [f32::INFINITY; 3];
        self.hi = [f32::NEG_INFINITY; 3];
        for f in &self.faces {
            let [a, b, c] = f.map(|k| self.vertices[k as usize]);
            let nn = cross(sub(b, a), sub(c, a));
            // Computed in f64 so that a tiny (but accepted) face still gets a unit normal.
            let l = nn.iter().map(|&x| x as f64 * x as f64).sum::<f64>().sqrt();
            self.normals.push(nn.map(|x| (x as f64 / l) as f32));
            self.planes.push(FacePlane::of([a, b, c]));
            let lo = [0, 1, 2].map(|k| a[k].min(b[k]).min(c[k]));
            let hi = [0, 1, 2].map(|k| a[k].max(b[k]).max(c[k]));
            for k in 0..3 {
                self.lo[k] = self.lo[k].min(lo[k]);
                self.hi[k] = self.hi[k].max(hi[k]);
            }
            self.face_box.push([lo, hi]);
        }
        self.stamp = fresh_stamp();
    }

    /// Vertex positions.
    pub fn vertices(&self) -> &[[f32; 3]] {
        &self.vertices
    }
    /// Triangles (only the accepted ones; indices into [`vertices`](Self::vertices)).
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }
    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.faces.len()
    }
    /// Unit normal of each face (right-hand rule on the winding).
    pub fn normals(&self) -> &[[f32; 3]] {
        &self.normals
    }
    /// The narrowphase's `f64` plane data of each face ([`FacePlane`]).
    pub fn planes(&self) -> &[FacePlane] {
        &self.planes
    }
    /// The three corners of face `f`.
    pub fn corners(&self, f: u32) -> [[f32; 3]; 3] {
        let [i, j, k] = self.faces[f as usize];
        [self.vertices[i as usize], self.vertices[j as usize], self.vertices[k as usize]]
    }
    /// Lower corner of face `f`'s box.
    pub fn face_lo(&self, f: u32) -> [f32; 3] {
        self.face_box[f as usize][0]
    }
    /// Upper corner of face `f`'s box.
    pub fn face_hi(&self, f: u32) -> [f32; 3] {
        self.face_box[f as usize][1]
    }
    /// The whole mesh's box `(lo, hi)`.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        (self.lo, self.hi)
    }
    /// Identifies this mesh state; changes on every construction and every translation.
    pub fn stamp(&self) -> u64 {
        self.stamp
    }
    /// Does face `f`'s box overlap the box `[lo, hi]` (closed intervals)? `false` for a face
    /// index out of range.
    #[inline]
    pub fn face_overlaps(&self, f: u32, lo: [f32; 3], hi: [f32; 3]) -> bool {
        match self.face_box.get(f as usize) {
            // `&` rather than `&&`: one branch for the six comparisons
            Some([a, b]) => (a[0] <= hi[0]) & (a[1] <= hi[1]) & (a[2] <= hi[2]) & (lo[0] <= b[0]) & (lo[1] <= b[1]) & (lo[2] <= b[2]),
            None => false,
        }
    }
    /// For a closed, consistently wound mesh (a solid): `+1.0` if the face normals point out
    /// (positive [`signed_volume`](Self::signed_volume)), `-1.0` if they point in. `None` for
    /// open or inconsistent meshes, and after [`set_two_sided`](Self::set_two_sided). The
    /// narrowphase takes a solid's outside as the particle's side (see `narrow`).
    pub fn solid_side(&self) -> Option<f32> {
        self.solid_side
    }
    /// Treat the mesh as a two-sided sheet even if it is closed: the particle's side is then
    /// taken from where it started (the brief's rule), not from the solid's outside.
    pub fn set_two_sided(&mut self) {
        self.solid_side = None;
    }
    /// Signed volume enclosed (positive for a closed mesh with outward winding).
    pub fn signed_volume(&self) -> f64 {
        self.faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|k| self.vertices[k as usize].map(|x| x as f64));
                let bc = [b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2], b[0] * c[1] - b[1] * c[0]];
                (a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2]) / 6.0
            })
            .sum()
    }
}

/// Test fixture: the unit square in the xy-plane as two triangles.
#[cfg(test)]
pub(crate) fn unit_square() -> TriMesh {
    let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    TriMesh::new(v, vec![[0, 1, 2], [0, 2, 3]]).expect("valid square").0
}

#[cfg(test)]
mod tests;
