//! Where a row of cells starts in the table: a linear map of the rows when the particles' box
//! is small enough, the mixing hash otherwise (the bucket of a cell is its row's base plus
//! `cx`, see [`super`]).
//!
//! # Linear rows
//! With the mixing hash the rows of a cell's neighbourhood (`cy ± 1`, `cz + 1`) land at random
//! places in the table, so the self-collision query (module `cells`) reads each from a
//! random place in the slot arrays: eight arrays of 40 kB for 10 000 particles, with the
//! bucket offsets more than the core's second-level cache holds once the substeps have run.
//! When the box of the particles' cells (one cell added on every side, for the neighbours of
//! the outer cells) has at most [`LINEAR_CELLS`] times `table_size` cells, the row base is
//! `cy a + cz b` with `a` the box's cells along x and `b = a` times its cells along y: the
//! cells are numbered in `(z, y, x)` order modulo the table, so a cell's neighbour rows lie
//! `a` and `b` buckets away, and their particles near in the slots. Up to `table_size`
//! cells no two cells of the box share a bucket; beyond, the numbering wraps along z (a
//! bucket holds cells whose numbers differ by a multiple of the table size, far apart). A box
//! larger than that (a particle thrown far away) keeps the mixing hash, whose collisions do
//! not line up.
//!
//! The map is a pure function of the positions (the box of this build), so the tables stay
//! the same on any number of threads and between the build and its serial twin.

use crate::data::lanes::{finite_lanes, load, F32s, LANES};
use crate::self_collision::hash::SpatialHash;

/// Most cells of the particles' box, over the table size, for the linear row map.
pub(super) const LINEAR_CELLS: u64 = 4;

impl SpatialHash {
    /// Bucket of cell `(0, cy, cz)` (any `u64`; [`SpatialHash::in_row`] adds `cx` and takes it
    /// modulo the table size): linear in `(cy, cz)` when the build chose strides, else the
    /// top `log2(table_size)` bits of a 64-bit mix of the row.
    #[inline(always)]
    pub(super) fn row_base(&self, cy: i32, cz: i32) -> u64 {
        if let Some((a, b)) = self.strides {
            return (cy as i64 as u64).wrapping_mul(a).wrapping_add((cz as i64 as u64).wrapping_mul(b));
        }
        // The splitmix64 finalizer of the packed pair: every input bit reaches every top bit.
        let mut h = ((cy as u32 as u64) << 32) | cz as u32 as u64;
        h = (h ^ (h >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        h = (h ^ (h >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (h ^ (h >> 31)) >> self.shift
    }

    /// Chooses the row map for particles `0..n` of `p` (after `prepare`: the spacing and the
    /// table size are set): the strides of the linear map when the box of the finite
    /// particles' cells is small enough, else none. The box is found eight particles at a
    /// time when `simd`, else one by one (the twin: minimum and maximum are exact, so the
    /// same box).
    pub(super) fn choose_rows(&mut self, p: [&[f32]; 3], n: usize, simd: bool) {
        self.strides = None;
        let Some((lo, hi)) = finite_box(p, n, simd) else { return };
        let cells = |a: usize| (i64::from(self.coord(hi[a])) - i64::from(self.coord(lo[a])) + 3) as u64;
        let (nx, ny, nz) = (cells(0), cells(1), cells(2));
        let limit = LINEAR_CELLS * self.table_size as u64;
        if nx.saturating_mul(ny).saturating_mul(nz) <= limit {
            self.strides = Some((nx, nx * ny));
        }
    }

    /// Whether the last build numbered the rows linearly (see the module docs).
    pub fn linear_rows(&self) -> bool {
        self.strides.is_some()
    }
}

/// The smallest and largest coordinates of the particles `0..n` with three finite
/// coordinates, or `None` when there is none.
fn finite_box(p: [&[f32]; 3], n: usize, simd: bool) -> Option<([f32; 3], [f32; 3])> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let mut i = 0;
    if simd {
        let (inf, ninf) = (F32s::splat(f32::INFINITY), F32s::splat(f32::NEG_INFINITY));
        let (mut vlo, mut vhi) = ([inf; 3], [ninf; 3]);
        while i + LANES <= n {
            let v = [load(p[0], i), load(p[1], i), load(p[2], i)];
            let ok = finite_lanes(v[0]) & finite_lanes(v[1]) & finite_lanes(v[2]);
            for a in 0..3 {
                vlo[a] = vlo[a].min(ok.select(v[a], inf));
                vhi[a] = vhi[a].max(ok.select(v[a], ninf));
            }
            i += LANES;
        }
        for a in 0..3 {
            lo[a] = vlo[a].to_array().into_iter().fold(lo[a], f32::min);
            hi[a] = vhi[a].to_array().into_iter().fold(hi[a], f32::max);
        }
    }
    for ((&x, &y), &z) in p[0][i..n].iter().zip(&p[1][i..n]).zip(&p[2][i..n]) {
        let v = [x, y, z];
        if v.iter().all(|c| c.is_finite()) {
            for a in 0..3 {
                lo[a] = lo[a].min(v[a]);
                hi[a] = hi[a].max(v[a]);
            }
        }
    }
    (lo[0] <= hi[0]).then_some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::signed;

    #[test]
    fn the_box_in_lanes_equals_its_twin_and_skips_non_finite_particles() {
        let mut rng = signed(31);
        for n in [0usize, 3, 8, 29] {
            let mut p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 5.0 * rng()).collect());
            let pr = [&p[0][..], &p[1][..], &p[2][..]];
            let want = finite_box(pr, n, false);
            assert_eq!(want, finite_box(pr, n, true), "n {n}");
            assert_eq!(want.is_none(), n == 0);
            if n > 4 {
                let before = want;
                // A far non-finite particle changes nothing.
                (p[0][2], p[1][4]) = (f32::INFINITY, f32::NAN);
                let kept: Vec<usize> = (0..n).filter(|&i| i != 2 && i != 4).collect();
                let pr = [&p[0][..], &p[1][..], &p[2][..]];
                let got = finite_box(pr, n, true);
                assert_eq!(got, finite_box(pr, n, false));
                let (lo, hi) = got.unwrap();
                for a in 0..3 {
                    let m = kept.iter().map(|&i| p[a][i]).fold(f32::INFINITY, f32::min);
                    let x = kept.iter().map(|&i| p[a][i]).fold(f32::NEG_INFINITY, f32::max);
                    assert_eq!((lo[a], hi[a]), (m, x));
                    assert!(lo[a] >= before.unwrap().0[a] && hi[a] <= before.unwrap().1[a]);
                }
            }
        }
        let nan = [vec![f32::NAN; 9], vec![0.0; 9], vec![0.0; 9]];
        assert_eq!(finite_box([&nan[0], &nan[1], &nan[2]], 9, true), None);
    }

    /// A compact cloud numbers its rows linearly, the same cloud with one particle thrown far
    /// keeps the mixing hash, and both find every pair within reach (brute force), serially
    /// and in parallel.
    #[test]
    fn compact_boxes_take_the_linear_rows_and_far_ones_the_mixing_hash() {
        use crate::self_collision::neighbours::{within, Neighbours};
        let mut rng = signed(37);
        let n = 900;
        let mut p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 0.2 * rng()).collect());
        let reach = 0.03f32;
        for (far, linear) in [(None, true), (Some(1e6f32), false), (Some(f32::NAN), true)] {
            if let Some(v) = far {
                p[2][7] = v;
            }
            let mut want = Neighbours::new();
            want.fill_serial(n, |i, buf| {
                for j in 0..n {
                    if j != i && within(p[0][i], p[1][i], p[2][i], p[0][j], p[1][j], p[2][j], reach * reach) {
                        buf.push(j as u32);
                    }
                }
            })
            .unwrap();
            assert!(want.total() > 500);
            let mut h = SpatialHash::new(n);
            let mut got = Neighbours::new();
            h.build_serial(&p[0], &p[1], &p[2], n, reach).unwrap();
            assert_eq!(h.linear_rows(), linear, "far {far:?}");
            h.query_all_serial(&p[0], &p[1], &p[2], n, reach, &mut got).unwrap();
            assert_eq!(got, want, "serial, far {far:?}");
            h.build(&p[0], &p[1], &p[2], n, reach).unwrap();
            assert_eq!(h.linear_rows(), linear);
            h.query_all(&p[0], &p[1], &p[2], n, reach, &mut got).unwrap();
            assert_eq!(got, want, "parallel, far {far:?}");
        }
    }
}
