//! The query of the spatial hash (`queryAll` of Müller's "Ten Minute Physics" hash): for each particle, its
//! neighbours within `max_dist`, read row by row from the cells of the build (the method is
//! in [`super`]).

use crate::self_collision::hash::{SpatialHash, NO_BUCKET};
use crate::self_collision::neighbours::{
    check_max_dist, check_positions, retain_tail, search_radius, sort_dedup_tail, within, Candidates, Neighbours,
};
use crate::{Result, WeftError};
use rayon::prelude::*;

/// Most cells a search box may span along an axis before a query tests all particles instead:
/// a box of `max_dist <= spacing` spans at most 4, a fast particle's box in the self-collision
/// query (module `cells`) at most 8 with the world's travels.
pub(super) const MAX_BOX_CELLS: i64 = 8;

impl SpatialHash {
    /// Whether particle `i` has the position it had at the last build (bitwise; a non-finite
    /// particle only has to stay non-finite).
    #[inline]
    pub(super) fn unchanged(&self, x: &[f32], y: &[f32], z: &[f32], i: usize) -> bool {
        match self.slot_of[i] {
            NO_BUCKET => !(x[i].is_finite() && y[i].is_finite() && z[i].is_finite()),
            k => {
                let k = k as usize;
                x[i].to_bits() == self.sx[k].to_bits() && y[i].to_bits() == self.sy[k].to_bits() && z[i].to_bits() == self.sz[k].to_bits()
            }
        }
    }

    /// Checks a query distance (finite, not negative, at most the spacing); returns its square.
    pub(super) fn check_reach(&self, max_dist: f32) -> Result<f32> {
        let md2 = check_max_dist(max_dist)?;
        if max_dist > self.spacing {
            return Err(WeftError::param(
                "max_dist",
                max_dist,
                format!("must not exceed the hash spacing ({})", self.spacing),
            ));
        }
        Ok(md2)
    }

    /// Checks query inputs against the build; returns `max_dist²`. `same` is whether the
    /// positions are those of the build (computed by the caller, in parallel or not).
    pub(super) fn check_query(&self, x: &[f32], y: &[f32], z: &[f32], n: usize, max_dist: f32, same: impl FnOnce() -> bool) -> Result<f32> {
        check_positions(x, y, z, n)?;
        if n != self.n {
            return Err(WeftError::param(
                "n",
                n,
                format!("must equal the particle count of the last build ({})", self.n),
            ));
        }
        let md2 = self.check_reach(max_dist)?;
        if !same() {
            return Err(WeftError::param(
                "x, y, z",
                "moved",
                "must be the positions given to the last build; build the hash again",
            ));
        }
        Ok(md2)
    }

    /// For every particle, its neighbours within `max_dist` (the shared predicate), sorted,
    /// into `out`; parallel over particles, no allocation once `out` is warm.
    ///
    /// `x, y, z, n` must be the positions given to the last [`SpatialHash::build`]: the cells,
    /// and a cell-ordered copy of the positions that the candidates are read from, come from
    /// the build. This is checked (bitwise, one pass). Errors if the positions differ from the
    /// build, an array is short, or `max_dist` is negative, non-finite or above `spacing`.
    pub fn query_all(&self, x: &[f32], y: &[f32], z: &[f32], n: usize, max_dist: f32, out: &mut Neighbours) -> Result<()> {
        self.query_filtered(x, y, z, n, max_dist, &|_, _| true, out)
    }

    /// Serial, scalar twin of [`SpatialHash::query_all`] (no threads, no lanes); produces
    /// identical lists.
    pub fn query_all_serial(&self, x: &[f32], y: &[f32], z: &[f32], n: usize, max_dist: f32, out: &mut Neighbours) -> Result<()> {
        self.query_filtered_serial(x, y, z, n, max_dist, &|_, _| true, out)
    }

    /// [`SpatialHash::query_all`] keeping only the neighbours `j` of `i` with `keep(i, j)`:
    /// the lists equal the unfiltered ones with the other entries removed. The filter runs on
    /// each particle's candidates before they are sorted, so a filter that drops most pairs
    /// (self-collision drops the cloth's own rest neighbours) also saves most of the sorting.
    /// The build's positions are checked in parallel, then every particle scanned in lanes.
    #[allow(clippy::too_many_arguments)]
    pub fn query_filtered<K>(&self, x: &[f32], y: &[f32], z: &[f32], n: usize, max_dist: f32, keep: &K, out: &mut Neighbours) -> Result<()>
    where
        K: Fn(usize, u32) -> bool + Sync,
    {
        let same = || (0..n).into_par_iter().all(|i| self.unchanged(x, y, z, i));
        let md2 = self.check_query(x, y, z, n, max_dist, same)?;
        let r = search_radius(max_dist);
        out.fill_parallel(n, |i, buf| self.scan::<true, K>(x, y, z, n, i, md2, r, keep, buf))
    }

    /// Serial, scalar twin of [`SpatialHash::query_filtered`]; produces identical lists.
    #[allow(clippy::too_many_arguments)]
    pub fn query_filtered_serial<K>(
        &self,
        x: &[f32],
        y: &[f32],
        z: &[f32],
        n: usize,
        max_dist: f32,
        keep: &K,
        out: &mut Neighbours,
    ) -> Result<()>
    where
        K: Fn(usize, u32) -> bool,
    {
        let same = || (0..n).all(|i| self.unchanged(x, y, z, i));
        let md2 = self.check_query(x, y, z, n, max_dist, same)?;
        let r = search_radius(max_dist);
        out.fill_serial(n, |i, buf| self.scan::<false, K>(x, y, z, n, i, md2, r, keep, buf))
    }

    /// Appends the sorted neighbours `j` of particle `i` with `keep(i, j)` to `buf`.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn scan<const SIMD: bool, K: Fn(usize, u32) -> bool>(
        &self,
        x: &[f32],
        y: &[f32],
        z: &[f32],
        n: usize,
        i: usize,
        md2: f32,
        r: f32,
        keep: &K,
        buf: &mut Vec<u32>,
    ) {
        let (xi, yi, zi) = (x[i], y[i], z[i]);
        if !(xi.is_finite() && yi.is_finite() && zi.is_finite()) {
            return;
        }
        let start = buf.len();
        let iu = i as u32;
        let p = [xi, yi, zi];
        let boxed = self.box_ranges(p, r, |b0, b1| self.scan_buckets::<SIMD>(b0, b1, iu, p, md2, buf));
        if !boxed {
            for j in 0..n {
                if j != i && within(xi, yi, zi, x[j], y[j], z[j], md2) && keep(i, j as u32) {
                    buf.push(j as u32);
                }
            }
            return;
        }
        retain_tail(buf, start, |j| keep(i, j));
        sort_dedup_tail(buf, start);
    }

    /// Calls `f(b0, b1)` for each row of cells overlapped by the box `[p - r, p + r]³`
    /// (`p` finite), `b0..b1` being the row's contiguous bucket range (a row wrapping past the
    /// table's end gives two calls). Returns `false`, calling nothing, when the box spans more
    /// than [`MAX_BOX_CELLS`] cells along an axis (the caller then tests all particles).
    #[inline(always)]
    pub(super) fn box_ranges(&self, p: [f32; 3], r: f32, mut f: impl FnMut(usize, usize)) -> bool {
        // Clamping to ±f32::MAX keeps the range finite; finite neighbours lie inside anyway.
        let lo = |v: f32| self.coord((v - r).max(-f32::MAX));
        let hi = |v: f32| self.coord((v + r).min(f32::MAX));
        let (x0, x1, y0, y1, z0, z1) = (lo(p[0]), hi(p[0]), lo(p[1]), hi(p[1]), lo(p[2]), hi(p[2]));
        let wide = |a: i32, b: i32| i64::from(b) - i64::from(a) >= MAX_BOX_CELLS;
        if wide(x0, x1) || wide(y0, y1) || wide(z0, z1) {
            return false;
        }
        let ts = self.table_size;
        // Buckets b0 ..= b0 + w hold one row of cells; they may wrap past the table's end.
        let cells = (x1 as i64 - x0 as i64) as usize + 1;
        for cz in z0..=z1 {
            for cy in y0..=y1 {
                let b0 = self.bucket(x0, cy, cz);
                let b1 = b0 + cells;
                if b1 <= ts {
                    f(b0, b1);
                } else {
                    f(b0, ts);
                    f(0, b1 - ts);
                }
            }
        }
        true
    }

    /// Tests the particles of buckets `b0..b1` (one contiguous range) against `p`.
    #[inline(always)]
    fn scan_buckets<const SIMD: bool>(&self, b0: usize, b1: usize, iu: u32, p: [f32; 3], md2: f32, buf: &mut Vec<u32>) {
        let range = self.cell_start[b0] as usize..self.cell_start[b1] as usize;
        let c = Candidates {
            above: false,
            ids: &self.cell_entries,
            x: &self.sx,
            y: &self.sy,
            z: &self.sz,
        };
        c.scan::<SIMD>(range, iu, p, md2, buf);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::signed;

    #[test]
    fn filtered_query_equals_its_twin_and_the_all_pairs_path() {
        let mut rng = signed(5);
        let n = 700;
        let p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 0.3 * rng()).collect());
        let mut h = SpatialHash::new(n);
        h.build(&p[0], &p[1], &p[2], n, 0.05).unwrap();
        let keep = |i: usize, j: u32| !(i + j as usize).is_multiple_of(3);
        let (mut a, mut b, mut all) = (Neighbours::new(), Neighbours::new(), Neighbours::new());
        h.query_filtered(&p[0], &p[1], &p[2], n, 0.05, &keep, &mut a).unwrap();
        h.query_filtered_serial(&p[0], &p[1], &p[2], n, 0.05, &keep, &mut b).unwrap();
        h.query_all(&p[0], &p[1], &p[2], n, 0.05, &mut all).unwrap();
        all.retain(keep);
        assert!(all.total() > 100);
        assert_eq!(a, all);
        assert_eq!(b, all);
        // A spacing far below the radius's rounding margin takes the all-pairs path.
        let tiny = [vec![0.0f32; 5], vec![0.0; 5], vec![0.0; 5]];
        h.build(&tiny[0], &tiny[1], &tiny[2], 5, 1e-30).unwrap();
        h.query_filtered_serial(&tiny[0], &tiny[1], &tiny[2], 5, 1e-30, &|_, _| true, &mut b)
            .unwrap();
        assert_eq!(b.pairs().count(), 10);
        assert_eq!(b.total(), 20);
    }

    /// The row memo of `fill_buckets` gives every particle the bucket of its own point: runs
    /// of one row (a cloth row along x), rows that change every particle, rows that come back
    /// after another, non-finite particles between them, and chunk starts inside a run.
    #[test]
    fn buckets_with_the_row_memo_are_each_points_bucket() {
        let mut rng = signed(9);
        let n = 600;
        let mut p: [Vec<f32>; 3] = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let [px, py, pz] = &mut p;
        for (i, ((x, y), z)) in px.iter_mut().zip(py.iter_mut()).zip(pz.iter_mut()).enumerate() {
            let (row, rand) = (i / 40 % 3, rng());
            *x = 0.01 * i as f32 - 2.0;
            *y = if i % 7 == 0 { rand } else { 0.1 * row as f32 };
            *z = if i % 11 == 0 { -rand } else { 0.3 - 0.1 * row as f32 };
        }
        p[1][17] = f32::NAN;
        p[2][18] = f32::INFINITY;
        p[0][19] = f32::NEG_INFINITY;
        // Finite but past the cell coordinates' range: both paths saturate like `as i32`.
        (p[0][23], p[1][24], p[2][25], p[0][26]) = (3e38, -1e20, 2.2e9 * 0.05, -2.2e9 * 0.05);
        let mut h = SpatialHash::new(n);
        h.build_serial(&p[0], &p[1], &p[2], n, 0.05).unwrap();
        let want: Vec<u32> = (0..n).map(|i| h.bucket_of_point(p[0][i], p[1][i], p[2][i])).collect();
        assert_eq!(want.iter().filter(|&&b| b == NO_BUCKET).count(), 3);
        for simd in [false, true] {
            let mut got = vec![0u32; n];
            h.fill_buckets([&p[0], &p[1], &p[2]], 0, &mut got, simd);
            assert_eq!(got, want, "simd {simd}");
            for start in [1, 18, 41, 333] {
                let mut part = vec![0u32; n - start];
                h.fill_buckets([&p[0], &p[1], &p[2]], start, &mut part, simd);
                assert_eq!(part, want[start..], "from {start}, simd {simd}");
            }
        }
        assert_eq!(h.bucket_of, want, "the build's own buckets");
        h.build(&p[0], &p[1], &p[2], n, 0.05).unwrap();
        assert_eq!(h.bucket_of, want, "parallel build");
    }
}
