//! A spatial hash of mesh faces: an unbounded grid of cubic cells of edge `h`, stored in a
//! fixed table by hashing the integer cell coordinates (Teschner et al. 2003 style:
//! `(i*73856093) xor (j*19349663) xor (k*83492791) mod table`).
//!
//! Unlike the paper's grid it does not depend on the mesh box, so it suits scenes where the
//! obstacle moves far or the cell size is chosen from the cloth (e.g. the particle spacing).
//! Cell coordinates are `floor(q / h)`; as with the grid this is monotonic, so a face whose box
//! overlaps the query box always shares a cell with it (distinct cells sharing a table slot only
//! add candidates). Faces spanning more than [`BIG_FACE_CELLS`] cells are kept in a separate
//! list returned by every query, and a query spanning more than [`QUERY_CELL_LIMIT`] cells
//! returns every face: both keep the work bounded without ever missing a face.

use crate::obstacles::mesh::broadphase::FaceBroadphase;
use crate::obstacles::mesh::TriMesh;
use crate::Result;

/// The automatic cell edge in mean face sizes ([`FaceHash::auto`]). Obstacle queries come from
/// the particles' gathered boxes ([`face_cache`](crate::obstacles::mesh::face_cache)): the path's box grown by
/// the contact reach and a margin of a few steps' motion, a face size or two across. With
/// cells of two face sizes such a box spans about two cells per axis, and each cell holds a
/// handful of faces; one face size visits about three times as many cells for the same faces.
pub const AUTO_CELL_FACES: f32 = 2.0;
/// A face spanning more cells than this is not hashed but returned by every query.
pub const BIG_FACE_CELLS: u64 = 64;
/// A query spanning more cells than this returns every face.
pub const QUERY_CELL_LIMIT: u64 = 512;

/// Spatial hash of the faces of one mesh.
#[derive(Debug, Clone)]
pub struct FaceHash {
    inv: f32,
    cell: f32,
    mask: u64,
    start: Vec<u32>,
    faces: Vec<u32>,
    big: Vec<u32>,
    face_cell: Vec<[i64; 3]>,
    nfaces: u32,
    stamp: u64,
}

#[inline]
fn coord(q: f32, inv: f32) -> i64 {
    (q * inv).floor() as i64
}

#[inline]
fn slot(i: i64, j: i64, k: i64, mask: u64) -> usize {
    let h = (i as u64).wrapping_mul(73_856_093) ^ (j as u64).wrapping_mul(19_349_663) ^ (k as u64).wrapping_mul(83_492_791);
    (h & mask) as usize
}

fn span(a: [i64; 3], b: [i64; 3]) -> u64 {
    (0..3).fold(1u64, |acc, k| acc.saturating_mul(b[k].saturating_sub(a[k]) as u64 + 1))
}

/// Mean over faces of the largest side of the face box: a natural cell edge.
pub fn mean_face_size(mesh: &TriMesh) -> f32 {
    let n = mesh.face_count();
    let s: f64 = (0..n as u32)
        .map(|f| {
            let (a, b) = (mesh.face_lo(f), mesh.face_hi(f));
            (0..3).map(|k| (b[k] - a[k]) as f64).fold(0.0, f64::max)
        })
        .sum();
    (s / n as f64) as f32
}

impl FaceHash {
    /// Hashes `mesh`'s faces into cells of edge `cell` (finite, > 0).
    pub fn new(mesh: &TriMesh, cell: f32) -> Result<Self> {
        crate::error::positive("face hash cell", cell)?;
        let inv = 1.0 / cell;
        if !inv.is_finite() {
            return Err(crate::WeftError::param("face hash cell", cell, "is too small"));
        }
        let nf = mesh.face_count() as u32;
        let ranges: Vec<([i64; 3], [i64; 3])> = (0..nf)
            .map(|f| (mesh.face_lo(f).map(|q| coord(q, inv)), mesh.face_hi(f).map(|q| coord(q, inv))))
            .collect();
        let entries: u64 = ranges.iter().map(|&(a, b)| span(a, b)).filter(|&s| s <= BIG_FACE_CELLS).sum();
        let size = (2 * entries).max(16).next_power_of_two() as usize;
        let mut h = FaceHash {
            inv,
            cell,
            mask: size as u64 - 1,
            start: vec![0; size + 1],
            faces: vec![0; entries as usize],
            big: Vec::new(),
            face_cell: ranges.iter().map(|r| r.0).collect(),
            nfaces: nf,
            stamp: mesh.stamp(),
        };
        let each = |a: [i64; 3], b: [i64; 3], mask: u64, f: &mut dyn FnMut(usize)| {
            for k in a[2]..=b[2] {
                for j in a[1]..=b[1] {
                    for i in a[0]..=b[0] {
                        f(slot(i, j, k, mask));
                    }
                }
            }
        };
        for (f, &(a, b)) in ranges.iter().enumerate() {
            if span(a, b) > BIG_FACE_CELLS {
                h.big.push(f as u32);
            } else {
                each(a, b, h.mask, &mut |s| h.start[s + 1] += 1);
            }
        }
        for s in 0..size {
            h.start[s + 1] += h.start[s];
        }
        let mut fill = h.start.clone();
        for (f, &(a, b)) in ranges.iter().enumerate() {
            if span(a, b) <= BIG_FACE_CELLS {
                each(a, b, h.mask, &mut |s| {
                    h.faces[fill[s] as usize] = f as u32;
                    fill[s] += 1;
                });
            }
        }
        Ok(h)
    }

    /// Hash with the cell edge set to [`AUTO_CELL_FACES`] times the [`mean_face_size`].
    pub fn auto(mesh: &TriMesh) -> Result<Self> {
        Self::new(mesh, AUTO_CELL_FACES * mean_face_size(mesh))
    }

    /// Cell edge length.
    pub fn cell(&self) -> f32 {
        self.cell
    }

    /// Faces too large to hash (returned by every query).
    pub fn big_faces(&self) -> usize {
        self.big.len()
    }
}

impl FaceBroadphase for FaceHash {
    fn candidates(&self, _mesh: &TriMesh, lo: [f32; 3], hi: [f32; 3], out: &mut Vec<u32>) {
        out.clear();
        let a = lo.map(|q| coord(q, self.inv));
        let b = hi.map(|q| coord(q, self.inv));
        if !(0..3).all(|k| lo[k] <= hi[k]) {
            return; // empty (or NaN) box: nothing overlaps it
        }
        if span(a, b) > QUERY_CELL_LIMIT {
            out.extend(0..self.nfaces);
            return;
        }
        out.extend_from_slice(&self.big);
        // As in the grid, a face is reported from the first cell it shares with the query
        // only (a face registered in two cells of one slot may still come twice).
        for k in a[2]..=b[2] {
            for j in a[1]..=b[1] {
                for i in a[0]..=b[0] {
                    let s = slot(i, j, k, self.mask);
                    let faces = &self.faces[self.start[s] as usize..self.start[s + 1] as usize];
                    let cell = [i, j, k];
                    let first = [0, 1, 2].map(|q| cell[q] == a[q]);
                    out.extend(faces.iter().copied().filter(|&f| {
                        let fc = &self.face_cell[f as usize];
                        (0..3).all(|q| first[q] || fc[q] == cell[q])
                    }));
                }
            }
        }
    }
    fn stamp(&self) -> u64 {
        self.stamp
    }
    fn describe(&self) -> String {
        format!("hash h={}", self.cell)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::obstacles::mesh::dressform::dress_form;

    #[test]
    fn hash_is_conservative_for_several_cells() {
        let m = dress_form(1500).unwrap();
        let (lo, hi) = m.bounds();
        let mut out = Vec::new();
        for cell in [0.004, 0.02, 0.1, 5.0] {
            let h = FaceHash::new(&m, cell).unwrap();
            for i in 0..100 {
                let t = i as f32 / 100.0;
                let c = [0, 1, 2].map(|k| lo[k] + (hi[k] - lo[k]) * ((t * (k as f32 + 1.3)) % 1.0));
                let (ql, qh) = (c.map(|v| v - 0.015), c.map(|v| v + 0.02));
                h.candidates(&m, ql, qh, &mut out);
                out.sort_unstable();
                for f in 0..m.face_count() as u32 {
                    if m.face_overlaps(f, ql, qh) {
                        assert!(out.binary_search(&f).is_ok(), "cell {cell}: face {f} missed");
                    }
                }
            }
        }
        assert!(FaceHash::new(&m, 0.004).unwrap().big_faces() > 0);
        assert!(FaceHash::new(&m, 0.0).is_err());
        assert!(FaceHash::new(&m, f32::NAN).is_err());
        assert!(FaceHash::new(&m, 1e-40).is_err());
    }
}
