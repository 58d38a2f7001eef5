//! The paper's uniform grid over a mesh obstacle (Landovskaya, Landovsky & Frolovsky).
//!
//! Build: take the obstacle's axis-aligned box `[lo, hi]` ("a parallelepiped whose faces pass
//! through the object's extreme points"), split it into `nx x ny x nz` equal cells, and give
//! each cell the list of faces whose box touches it (a large face sits in several adjacent
//! cells). Lists are stored compressed (one offset array, one face array).
//!
//! Query: is the query box inside the mesh box at all? If not, no face can be touched. If so,
//! the cell index along each axis is `i = floor((q - lo) * n / (hi - lo))`, clamped to
//! `0..n`, and the faces of the cells between the corners' cells are returned. The paper looks
//! up the single cell holding the particle; we look up every cell the particle's whole
//! segment box (grown by the thickness) touches, so a fast particle cannot skip a face in a
//! neighbouring cell whatever the cell size. A face met in several of those cells is reported
//! once, from the first cell it shares with the query (a comparison of cell indices; no sort). Because `floor`, `*` and `-` are monotonic in
//! floating point, a face whose box overlaps the query box always shares a cell with it: the
//! grid is conservative, bit for bit.
//!
//! `1 x 1 x 1` is brute force (every face in one cell), the first row of the paper's table.
//! Cell size: the paper asks that a cell be no larger than the faces (and than a particle's
//! step, which our segment-box query makes unnecessary). [`auto_dims`] takes that rule: the
//! cell edge is the mean face size (mean over faces of the largest side of the face box), and
//! the count is capped at `4 x faces` cells, shrinking all axes alike, to bound memory.

use crate::obstacles::mesh::broadphase::FaceBroadphase;
use crate::obstacles::mesh::TriMesh;
use crate::{Result, WeftError};

/// Largest number of cells a grid may have.
pub const MAX_CELLS: usize = 1 << 26;

/// The paper's uniform grid of face lists over the mesh box.
#[derive(Debug, Clone)]
pub struct UniformGrid {
    dims: [usize; 3],
    lo: [f32; 3],
    hi: [f32; 3],
    inv: [f32; 3],
    start: Vec<u32>,
    faces: Vec<u32>,
    /// Each face's first cell (the cell of its box's lower corner).
    face_cell: Vec<[u32; 3]>,
    stamp: u64,
}

/// Cell counts per axis from the mesh's face size (see the module doc).
pub fn auto_dims(mesh: &TriMesh) -> [usize; 3] {
    let n = mesh.face_count();
    let mut size = 0.0f64;
    for f in 0..n as u32 {
        let (a, b) = (mesh.face_lo(f), mesh.face_hi(f));
        size += (0..3).map(|k| (b[k] - a[k]) as f64).fold(0.0, f64::max);
    }
    let size = size / n as f64;
    let (lo, hi) = mesh.bounds();
    let ext = [0, 1, 2].map(|k| (hi[k] - lo[k]) as f64);
    let cap = (4 * n).max(1) as f64;
    let mut d = ext.map(|e| if size > 0.0 { (e / size).ceil().max(1.0) } else { 1.0 });
    let total = d[0] * d[1] * d[2];
    if total > cap {
        let s = (cap / total).cbrt();
        d = d.map(|x| (x * s).floor().max(1.0));
    }
    d.map(|x| x as usize)
}

impl UniformGrid {
    /// Builds an `nx x ny x nz` grid over `mesh`'s box. Each count must be at least 1 and the
    /// product at most [`MAX_CELLS`].
    pub fn new(mesh: &TriMesh, dims: [usize; 3]) -> Result<Self> {
        if dims.contains(&0) {
            return Err(WeftError::param(
                "grid cells",
                format!("{dims:?}"),
                "every count must be at least 1",
            ));
        }
        let total = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
        let total = match total {
            Some(t) if t <= MAX_CELLS => t,
            _ => {
                return Err(WeftError::param(
                    "grid cells",
                    format!("{dims:?}"),
                    format!("at most {MAX_CELLS} cells in all"),
                ))
            }
        };
        let (lo, hi) = mesh.bounds();
        let inv = [0, 1, 2].map(|k| {
            let e = hi[k] - lo[k];
            if e > 0.0 {
                dims[k] as f32 / e
            } else {
                0.0
            }
        });
        let mut g = UniformGrid {
            dims,
            lo,
            hi,
            inv,
            start: vec![0; total + 1],
            faces: Vec::new(),
            face_cell: Vec::new(),
            stamp: mesh.stamp(),
        };
        let nf = mesh.face_count() as u32;
        for f in 0..nf {
            let (a, b) = g.range(mesh.face_lo(f), mesh.face_hi(f));
            g.for_cells(a, b, |c, s| s.start[c + 1] += 1);
        }
        for c in 0..total {
            g.start[c + 1] += g.start[c];
        }
        g.face_cell = (0..nf)
            .map(|f| g.range(mesh.face_lo(f), mesh.face_hi(f)).0.map(|i| i as u32))
            .collect();
        let mut fill = g.start.clone();
        g.faces = vec![0; g.start[total] as usize];
        for f in 0..nf {
            let (a, b) = g.range(mesh.face_lo(f), mesh.face_hi(f));
            g.for_cells(a, b, |c, s| {
                s.faces[fill[c] as usize] = f;
                fill[c] += 1;
            });
        }
        Ok(g)
    }

    /// Builds a grid with [`auto_dims`].
    pub fn auto(mesh: &TriMesh) -> Result<Self> {
        Self::new(mesh, auto_dims(mesh))
    }

    /// Cell counts per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Total face entries over all cells (a face in several cells counts several times).
    pub fn entries(&self) -> usize {
        self.faces.len()
    }

    #[inline]
    fn cell_of(&self, q: f32, k: usize) -> usize {
        let i = ((q - self.lo[k]) * self.inv[k]).floor();
        if i >= 0.0 {
            (i as usize).min(self.dims[k] - 1)
        } else {
            0
        }
    }

    #[inline]
    fn range(&self, lo: [f32; 3], hi: [f32; 3]) -> ([usize; 3], [usize; 3]) {
        ([0, 1, 2].map(|k| self.cell_of(lo[k], k)), [0, 1, 2].map(|k| self.cell_of(hi[k], k)))
    }

    fn for_cells(&mut self, a: [usize; 3], b: [usize; 3], mut f: impl FnMut(usize, &mut Self)) {
        for z in a[2]..=b[2] {
            for y in a[1]..=b[1] {
                for x in a[0]..=b[0] {
                    let c = (z * self.dims[1] + y) * self.dims[0] + x;
                    f(c, self);
                }
            }
        }
    }
}

impl FaceBroadphase for UniformGrid {
    fn candidates(&self, _mesh: &TriMesh, lo: [f32; 3], hi: [f32; 3], out: &mut Vec<u32>) {
        out.clear();
        // Stage one of the paper: is the (box of the) particle inside the object's box?
        let outside = (0..3).any(|k| !(lo[k] <= self.hi[k] && self.lo[k] <= hi[k]));
        if outside {
            return;
        }
        // Stage two: which cells?
        // A face in several visited cells is reported only from the first of them, the cell
        // `max(face's first cell, query's first cell)` on each axis: no duplicates, no sort.
        let (a, b) = self.range(lo, hi);
        for z in a[2]..=b[2] {
            for y in a[1]..=b[1] {
                let row = (z * self.dims[1] + y) * self.dims[0];
                for x in a[0]..=b[0] {
                    let c = row + x;
                    let faces = &self.faces[self.start[c] as usize..self.start[c + 1] as usize];
                    let cell = [x as u32, y as u32, z as u32];
                    let first = [0, 1, 2].map(|k| cell[k] == a[k] as u32);
                    if first == [true; 3] {
                        out.extend_from_slice(faces);
                        continue;
                    }
                    out.extend(faces.iter().copied().filter(|&f| {
                        let fc = &self.face_cell[f as usize];
                        (0..3).all(|k| first[k] || fc[k] == cell[k])
                    }));
                }
            }
        }
    }
    fn stamp(&self) -> u64 {
        self.stamp
    }
    fn describe(&self) -> String {
        format!("grid {}x{}x{}", self.dims[0], self.dims[1], self.dims[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::obstacles::mesh::dressform::dress_form;

    #[test]
    fn one_cell_holds_every_face_once() {
        let m = dress_form(600).unwrap();
        let g = UniformGrid::new(&m, [1, 1, 1]).unwrap();
        assert_eq!(g.entries(), m.face_count());
        let (lo, hi) = m.bounds();
        let mut out = Vec::new();
        g.candidates(&m, lo, hi, &mut out);
        assert_eq!(out, (0..m.face_count() as u32).collect::<Vec<_>>());
        g.candidates(&m, [10.0; 3], [11.0; 3], &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn candidates_cover_every_overlapping_face() {
        let m = dress_form(2000).unwrap();
        let g = UniformGrid::new(&m, [7, 13, 5]).unwrap();
        let (lo, hi) = m.bounds();
        let mut out = Vec::new();
        for i in 0..200 {
            let t = i as f32 / 200.0;
            let c = [0, 1, 2].map(|k| lo[k] + (hi[k] - lo[k]) * ((t * (k as f32 + 1.7)) % 1.0));
            let (ql, qh) = (c.map(|v| v - 0.02), c.map(|v| v + 0.03));
            g.candidates(&m, ql, qh, &mut out);
            let n = out.len();
            out.sort_unstable();
            out.dedup();
            assert_eq!(out.len(), n, "a face reported twice");
            for f in 0..m.face_count() as u32 {
                if m.face_overlaps(f, ql, qh) {
                    assert!(out.binary_search(&f).is_ok(), "face {f} missed");
                }
            }
        }
    }

    #[test]
    fn bad_dims_and_auto() {
        let m = dress_form(600).unwrap();
        assert!(UniformGrid::new(&m, [0, 1, 1]).is_err());
        assert!(UniformGrid::new(&m, [1 << 20, 1 << 20, 1]).is_err());
        assert!(UniformGrid::new(&m, [usize::MAX, 2, 2]).is_err());
        let d = auto_dims(&m);
        assert!(d.iter().all(|&x| x >= 1));
        assert!(d[0] * d[1] * d[2] <= 4 * m.face_count());
        assert!(d[1] > d[0], "the form is taller than wide: {d:?}");
    }
}
