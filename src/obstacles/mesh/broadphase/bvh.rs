//! A bounding-volume hierarchy (AABB tree) over mesh faces: the usual alternative to the
//! paper's uniform grid, adaptive where faces are dense.
//!
//! Build (top down, median split): the node's faces are ordered by their box centre along the
//! longest axis of the centres' spread and split at the median (ties broken by face index, so
//! the tree is deterministic), until at most [`LEAF_SIZE`] faces remain. A node's box is the
//! exact union of its faces' boxes (min/max, no rounding), so testing `node overlaps query`
//! never drops a face whose own box overlaps the query: the tree is conservative.
//! Nodes are stored depth-first in one array (left child right after its parent), which makes
//! [`Bvh::refit`] after a [`TriMesh::translate`] a single backwards sweep.

use crate::obstacles::mesh::broadphase::FaceBroadphase;
use crate::obstacles::mesh::TriMesh;
use crate::{Result, WeftError};

/// Most faces in a leaf.
pub const LEAF_SIZE: usize = 4;

#[derive(Debug, Clone, Copy)]
struct Node {
    lo: [f32; 3],
    hi: [f32; 3],
    /// Leaf: first index into `order`. Inner: index of the right child.
    first: u32,
    /// Leaf: number of faces (> 0). Inner: 0.
    count: u32,
}

/// AABB tree over the faces of one mesh.
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    stamp: u64,
}

fn overlaps(alo: &[f32; 3], ahi: &[f32; 3], lo: &[f32; 3], hi: &[f32; 3]) -> bool {
    alo[0] <= hi[0] && alo[1] <= hi[1] && alo[2] <= hi[2] && lo[0] <= ahi[0] && lo[1] <= ahi[1] && lo[2] <= ahi[2]
}

impl Bvh {
    /// Builds the tree for `mesh`.
    pub fn new(mesh: &TriMesh) -> Self {
        let n = mesh.face_count();
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * n / LEAF_SIZE + 1),
            order: (0..n as u32).collect(),
            stamp: mesh.stamp(),
        };
        let centre: Vec<[f32; 3]> = (0..n as u32)
            .map(|f| {
                let (a, b) = (mesh.face_lo(f), mesh.face_hi(f));
                [0, 1, 2].map(|k| 0.5 * a[k] + 0.5 * b[k])
            })
            .collect();
        bvh.build(mesh, &centre, 0, n);
        bvh
    }

    fn build(&mut self, mesh: &TriMesh, centre: &[[f32; 3]], first: usize, end: usize) {
        let me = self.nodes.len();
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let (mut clo, mut chi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for &f in &self.order[first..end] {
            let (a, b, c) = (mesh.face_lo(f), mesh.face_hi(f), centre[f as usize]);
            for k in 0..3 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(b[k]);
                clo[k] = clo[k].min(c[k]);
                chi[k] = chi[k].max(c[k]);
            }
        }
        self.nodes.push(Node {
            lo,
            hi,
            first: first as u32,
            count: (end - first) as u32,
        });
        if end - first <= LEAF_SIZE {
            return;
        }
        let spread = [0, 1, 2].map(|k| chi[k] - clo[k]);
        let axis = if spread[0] >= spread[1] && spread[0] >= spread[2] {
            0
        } else if spread[1] >= spread[2] {
            1
        } else {
            2
        };
        let mid = first + (end - first) / 2;
        self.order[first..end].select_nth_unstable_by(mid - first, |&a, &b| {
            centre[a as usize][axis].total_cmp(&centre[b as usize][axis]).then(a.cmp(&b))
        });
        self.build(mesh, centre, first, mid);
        let right = self.nodes.len() as u32;
        self.build(mesh, centre, mid, end);
        self.nodes[me].first = right;
        self.nodes[me].count = 0;
    }

    /// Recomputes every node box from the (moved) mesh without rebuilding the tree.
    /// The mesh must have the same faces as the one the tree was built for.
    pub fn refit(&mut self, mesh: &TriMesh) -> Result<()> {
        if mesh.face_count() != self.order.len() {
            return Err(WeftError::InvalidMesh {
                source_name: None,
                reason: format!(
                    "cannot refit a tree of {} faces to a mesh of {}",
                    self.order.len(),
                    mesh.face_count()
                ),
            });
        }
        for i in (0..self.nodes.len()).rev() {
            let nd = self.nodes[i];
            let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
            let mut grow = |a: [f32; 3], b: [f32; 3]| {
                for k in 0..3 {
                    lo[k] = lo[k].min(a[k]);
                    hi[k] = hi[k].max(b[k]);
                }
            };
            if nd.count > 0 {
                for &f in &self.order[nd.first as usize..(nd.first + nd.count) as usize] {
                    grow(mesh.face_lo(f), mesh.face_hi(f));
                }
            } else {
                let (l, r) = (&self.nodes[i + 1], &self.nodes[nd.first as usize]);
                grow(l.lo, l.hi);
                grow(r.lo, r.hi);
            }
            self.nodes[i].lo = lo;
            self.nodes[i].hi = hi;
        }
        self.stamp = mesh.stamp();
        Ok(())
    }

    /// Number of tree nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }
}

impl FaceBroadphase for Bvh {
    fn candidates(&self, _mesh: &TriMesh, lo: [f32; 3], hi: [f32; 3], out: &mut Vec<u32>) {
        out.clear();
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let i = stack[top] as usize;
            let nd = &self.nodes[i];
            if !overlaps(&nd.lo, &nd.hi, &lo, &hi) {
                continue;
            }
            if nd.count > 0 {
                out.extend_from_slice(&self.order[nd.first as usize..(nd.first + nd.count) as usize]);
            } else {
                // Median splits halve the count, so depth stays below 64 for any u32 size.
                stack[top] = nd.first;
                stack[top + 1] = i as u32 + 1;
                top += 2;
            }
        }
    }
    fn stamp(&self) -> u64 {
        self.stamp
    }
    fn describe(&self) -> String {
        "bvh".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::obstacles::mesh::dressform::dress_form;

    fn covers(m: &TriMesh, b: &Bvh) {
        let (lo, hi) = m.bounds();
        let mut out = Vec::new();
        for i in 0..150 {
            let t = i as f32 / 150.0;
            let c = [0, 1, 2].map(|k| lo[k] + (hi[k] - lo[k]) * ((t * (k as f32 + 2.3)) % 1.0));
            let (ql, qh) = (c.map(|v| v - 0.01), c.map(|v| v + 0.04));
            b.candidates(m, ql, qh, &mut out);
            for f in 0..m.face_count() as u32 {
                if m.face_overlaps(f, ql, qh) {
                    assert!(out.contains(&f), "face {f} missed");
                }
            }
        }
    }

    #[test]
    fn tree_is_conservative_and_refits() {
        let mut m = dress_form(1500).unwrap();
        let mut b = Bvh::new(&m);
        assert!(b.node_count() >= m.face_count() / LEAF_SIZE);
        covers(&m, &b);
        m.translate([0.3, -0.1, 0.05]).unwrap();
        assert_ne!(b.stamp(), m.stamp());
        b.refit(&m).unwrap();
        assert_eq!(b.stamp(), m.stamp());
        covers(&m, &b);
        let other = dress_form(600).unwrap();
        assert!(b.refit(&other).is_err());
    }
}
