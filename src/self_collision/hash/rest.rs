//! The self-collision query of the spatial hash: each pair once, rest neighbours dropped,
//! both decided inside the eight-lane mask.
//!
//! # What it computes
//! For every particle `i`, the ids `j` with
//!
//! ```text
//! j > i  and  (dx*dx + dy*dy) + dz*dz <= max_dist²         (the shared predicate, x_j - x_i)
//!        and  not (cloth_j == cloth_i and |r_i - r_j|² <= skip²)     (r: rest positions)
//! ```
//!
//! sorted ascending: exactly [`SpatialHash::query_upper_filtered`] with the filter
//! `keep(i, j) = !(cloth_i == cloth_j && dist2(r_i, r_j) <= skip * skip)`, the rest-neighbour
//! rule of Müller's "Ten Minute Physics" self-collision as the self-collision stage applies it (`rest_skipped` in
//! [`crate::self_collision`]; the rest distance is computed there as
//! `(r_i - r_j)` per axis, squared and summed in the same order, no FMA, so both decide alike).
//!
//! # Why
//! In the generic query every candidate within reach leaves the lanes and goes through scalar
//! code: the `j > i` branch, then the filter (three scalar gathers of rest positions from
//! scattered ids), then the sort. In a flat cloth every pair within the reach `q` is a rest
//! neighbour, so all that work is thrown away. Here [`SpatialHash::attach_rest`] copies the
//! rest positions, cloth ids and particle ids into `cell_entries` order once per build (a
//! gather of `n` particles), so the three tests are lane operations on contiguous data; only
//! kept pairs reach scalar code, and a particle with nothing kept skips the sort. The query
//! reads the positions from the build's cell-ordered copy (the query particle's through its
//! slot), so unlike [`SpatialHash::query_all`] it needs no pass checking that it was given the
//! build's positions. The lane loop is then the cost (the candidates scanned), and the skin policy
//! (`self_collision::reuse`) decides how often it runs.

use crate::data::lanes::{load_idx, F32s, Vec3x8, LANES};
use crate::self_collision::hash::{SpatialHash, NO_BUCKET};
use crate::self_collision::neighbours::{search_radius, sort_dedup_tail, within, Neighbours};
use crate::{Result, WeftError};
use wide::u32x8;

/// Rest data in `cell_entries` order, padded with [`LANES`] entries (NaN positions, id 0), so
/// lane loads never leave the arrays and padding lanes are never kept.
#[derive(Debug, Clone, Default)]
pub(super) struct RestCopy {
    pub(super) x: Vec<f32>,
    pub(super) y: Vec<f32>,
    pub(super) z: Vec<f32>,
    pub(super) cloth: Vec<u32>,
    pub(super) ids: Vec<u32>,
    /// Whether the copy belongs to the current build (cleared by every build).
    pub(super) valid: bool,
}

/// What one particle's scan needs.
struct Probe {
    i: u32,
    p: [f32; 3],
    md2: f32,
    r: [f32; 3],
    cloth: u32,
    s2: f32,
}

impl SpatialHash {
    /// Copies the rest positions `rest` and cloth ids `cloth` of particles `0..n` (the last
    /// build's) into cell order, for [`SpatialHash::query_upper_unskipped`]. Errors if an
    /// array is shorter than the build's particle count.
    pub fn attach_rest(&mut self, rest: [&[f32]; 3], cloth: &[u32]) -> Result<()> {
        let n = self.n;
        for (name, len) in [
            ("rest x", rest[0].len()),
            ("rest y", rest[1].len()),
            ("rest z", rest[2].len()),
            ("cloth", cloth.len()),
        ] {
            if len < n {
                return Err(WeftError::BufferLength {
                    name,
                    got: len,
                    expected: n,
                });
            }
        }
        let placed = self.cell_entries.len();
        let rc = &mut self.rest;
        for v in [&mut rc.x, &mut rc.y, &mut rc.z] {
            v.clear();
            v.resize(placed + LANES, f32::NAN);
        }
        rc.cloth.clear();
        rc.cloth.resize(placed + LANES, 0);
        rc.ids.clear();
        rc.ids.resize(placed + LANES, 0);
        for (k, &i) in self.cell_entries.iter().enumerate() {
            let i = i as usize;
            (rc.x[k], rc.y[k], rc.z[k]) = (rest[0][i], rest[1][i], rest[2][i]);
            rc.cloth[k] = cloth[i];
            rc.ids[k] = i as u32;
        }
        rc.valid = true;
        Ok(())
    }

    /// For every particle `i` of the last build, the ids `j > i` within `max_dist` that are
    /// not rest neighbours (same cloth and rest distance at most `skip`), sorted (see the
    /// module docs); parallel over particles, eight candidates a lane operation. The positions
    /// are the build's own (its cell-ordered copy), so they need no check.
    ///
    /// Errors if `max_dist` or `skip` is negative or non-finite, `max_dist` exceeds the
    /// spacing, or no rest data was attached since the last build.
    pub fn query_upper_unskipped(&self, max_dist: f32, skip: f32, out: &mut Neighbours) -> Result<()> {
        let (md2, s2) = self.check_rest_query(max_dist, skip)?;
        let r = search_radius(max_dist);
        out.fill_parallel(self.n, |i, buf| self.scan_unskipped::<true>(i, md2, r, s2, buf))
    }

    /// Serial, scalar twin of [`SpatialHash::query_upper_unskipped`]; produces identical lists.
    pub fn query_upper_unskipped_serial(&self, max_dist: f32, skip: f32, out: &mut Neighbours) -> Result<()> {
        let (md2, s2) = self.check_rest_query(max_dist, skip)?;
        let r = search_radius(max_dist);
        out.fill_serial(self.n, |i, buf| self.scan_unskipped::<false>(i, md2, r, s2, buf))
    }

    /// Checks the arguments; returns `max_dist²` and `skip²`.
    pub(super) fn check_rest_query(&self, max_dist: f32, skip: f32) -> Result<(f32, f32)> {
        crate::error::non_negative("skip", skip)?;
        let md2 = self.check_reach(max_dist)?;
        if !self.rest.valid {
            return Err(WeftError::param(
                "rest",
                "missing",
                "attach the rest data after each build (attach_rest)",
            ));
        }
        Ok((md2, skip * skip))
    }

    /// Appends the kept neighbours of particle `i`, sorted, to `buf`.
    #[inline]
    fn scan_unskipped<const SIMD: bool>(&self, i: usize, md2: f32, r: f32, s2: f32, buf: &mut Vec<u32>) {
        // Non-finite particles have no slot and no neighbours.
        let k = match self.slot_of[i] {
            NO_BUCKET => return,
            k => k as usize,
        };
        let rc = &self.rest;
        let p = [self.sx[k], self.sy[k], self.sz[k]];
        let probe = Probe {
            i: i as u32,
            p,
            md2,
            r: [rc.x[k], rc.y[k], rc.z[k]],
            cloth: rc.cloth[k],
            s2,
        };
        let start = buf.len();
        let boxed = self.box_ranges(p, r, |b0, b1| {
            let (s, e) = (self.cell_start[b0] as usize, self.cell_start[b1] as usize);
            if SIMD {
                rc.scan_lanes(&self.sx, &self.sy, &self.sz, &probe, s, e, buf);
            } else {
                rc.scan_scalar(&self.sx, &self.sy, &self.sz, &probe, s, e, buf);
            }
        });
        if !boxed {
            rc.scan_scalar(&self.sx, &self.sy, &self.sz, &probe, 0, self.cell_entries.len(), buf);
        }
        sort_dedup_tail(buf, start);
    }
}

impl RestCopy {
    /// The scalar decision for slot `k` (the twin of the lanes).
    #[inline(always)]
    fn keeps(&self, sx: &[f32], sy: &[f32], sz: &[f32], q: &Probe, k: usize) -> bool {
        let (dx, dy, dz) = (q.r[0] - self.x[k], q.r[1] - self.y[k], q.r[2] - self.z[k]);
        self.ids[k] > q.i
            && within(q.p[0], q.p[1], q.p[2], sx[k], sy[k], sz[k], q.md2)
            && !(self.cloth[k] == q.cloth && dx * dx + dy * dy + dz * dz <= q.s2)
    }

    /// Scalar scan of slots `s..e`.
    #[allow(clippy::too_many_arguments)]
    fn scan_scalar(&self, sx: &[f32], sy: &[f32], sz: &[f32], q: &Probe, s: usize, e: usize, buf: &mut Vec<u32>) {
        for k in s..e {
            if self.keeps(sx, sy, sz, q, k) {
                buf.push(self.ids[k]);
            }
        }
    }

    /// Scan of slots `s..e`, eight at a time: distance, order, cloth and rest distance in lanes
    /// (each computed operation for operation like [`RestCopy::keeps`], no FMA).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn scan_lanes(&self, sx: &[f32], sy: &[f32], sz: &[f32], q: &Probe, s: usize, e: usize, buf: &mut Vec<u32>) {
        let (pv, m2) = (Vec3x8::splat(q.p), F32s::splat(q.md2));
        let (rv, s2) = (Vec3x8::splat(q.r), F32s::splat(q.s2));
        let (iv, cv) = (u32x8::splat(q.i), u32x8::splat(q.cloth));
        let mut k = s;
        while k < e {
            let d = Vec3x8::load(sx, sy, sz, k) - pv;
            let mut bits = (d.x * d.x + d.y * d.y + d.z * d.z).simd_le(m2).to_bitmask();
            if e - k < LANES {
                bits &= (1u32 << (e - k)) - 1;
            }
            if bits != 0 {
                let ids = u32x8::from(load_idx(&self.ids, k));
                bits &= ids.simd_gt(iv).to_bitmask();
                if bits != 0 {
                    let rd = rv - Vec3x8::load(&self.x, &self.y, &self.z, k);
                    let near = (rd.x * rd.x + rd.y * rd.y + rd.z * rd.z).simd_le(s2).to_bitmask();
                    let same = u32x8::from(load_idx(&self.cloth, k)).simd_eq(cv).to_bitmask();
                    bits &= !(near & same);
                    while bits != 0 {
                        buf.push(self.ids[k + bits.trailing_zeros() as usize]);
                        bits &= bits - 1;
                    }
                }
            }
            k += LANES;
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::test_rng::signed;

    /// Positions, rest positions and cloth ids of a test scene.
    pub(crate) type Scene = ([Vec<f32>; 3], [Vec<f32>; 3], Vec<u32>);

    /// Two `side x side` lattices of rest spacing `h`, the second lifted by `lift h`,
    /// positions displaced by `noise h` (zero noise: particles exactly on cell faces).
    pub(crate) fn lattices(side: usize, h: f32, noise: f32, lift: f32, seed: u64) -> Scene {
        let mut rng = signed(seed);
        let (mut p, mut rest): ([Vec<f32>; 3], [Vec<f32>; 3]) = Default::default();
        let mut cloth = Vec::new();
        for c in 0..2u32 {
            for a in 0..side {
                for b in 0..side {
                    let r = [a as f32 * h, b as f32 * h, 0.0];
                    for k in 0..3 {
                        rest[k].push(r[k]);
                        let up = if k == 2 { lift * h * c as f32 } else { 0.0 };
                        p[k].push(r[k] + noise * h * rng() + up);
                    }
                    cloth.push(c);
                }
            }
        }
        (p, rest, cloth)
    }

    /// Two 12x12 lattices (rest spacing `h`, so many rest distances fall exactly on the skip
    /// radius `3 h`), crumpled by noise of about `h` and partly overlapping, one particle NaN.
    fn scene() -> Scene {
        let mut s = lattices(12, 0.01, 1.0, 0.5, 17);
        s.0[1][40] = f32::NAN;
        s
    }

    #[test]
    fn unskipped_query_equals_the_filtered_query_twin_and_thread_counts() {
        let (p, rest, cloth) = scene();
        let n = cloth.len();
        let (reach, skip) = (0.04f32, 0.03f32 * 1.001);
        let mut h = SpatialHash::new(n);
        h.build(&p[0], &p[1], &p[2], n, reach).unwrap();
        let mut got = Neighbours::new();
        let err = h.query_upper_unskipped(reach, skip, &mut got);
        assert!(err.is_err(), "no rest data attached");
        h.attach_rest([&rest[0], &rest[1], &rest[2]], &cloth).unwrap();
        // The rule as the self-collision stage writes it (`rest_skipped`).
        let skipped = |i: usize, j: usize| {
            let d = |k: usize| rest[k][i] - rest[k][j];
            cloth[i] == cloth[j] && d(0) * d(0) + d(1) * d(1) + d(2) * d(2) <= skip * skip
        };
        let mut want = Neighbours::new();
        h.query_upper_filtered_serial(&p[0], &p[1], &p[2], n, reach, &|i, j| !skipped(i, j as usize), &mut want)
            .unwrap();
        let (kept, all) = (want.total(), (0..n).filter(|&i| (0..n).any(|j| skipped(i, j) && j != i)).count());
        assert!(kept > 200 && all > 200, "{kept} kept pairs, {all} particles with rest neighbours");
        let pool = |t: usize| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap();
        for t in [1, 2] {
            pool(t).install(|| h.query_upper_unskipped(reach, skip, &mut got)).unwrap();
            assert_eq!(got, want, "{t} threads");
        }
        h.query_upper_unskipped_serial(reach, skip, &mut got).unwrap();
        assert_eq!(got, want);
        // A zero skip drops only coincident rest positions (none): every upper pair is kept.
        h.query_upper_unskipped(reach, 0.0, &mut got).unwrap();
        h.query_upper_filtered(&p[0], &p[1], &p[2], n, reach, &|_, _| true, &mut want)
            .unwrap();
        assert_eq!(got, want);
        assert!(h.query_upper_unskipped(reach, f32::NAN, &mut got).is_err());
        assert!(h.query_upper_unskipped(2.0 * reach, skip, &mut got).is_err(), "beyond the spacing");
        assert!(h.attach_rest([&rest[0], &rest[1], &rest[2][..5]], &cloth).is_err());
        // A new build needs the rest data again.
        h.build(&p[0], &p[1], &p[2], n, reach).unwrap();
        assert!(h.query_upper_unskipped_serial(reach, skip, &mut got).is_err());
    }

    #[test]
    fn unskipped_query_handles_the_all_pairs_path() {
        // A spacing far below the radius's rounding margin: every particle tests all slots.
        let z = [vec![0.0f32; 6], vec![0.0; 6], vec![0.0; 6]];
        let rest = [vec![0.0f32, 1.0, 2.0, 3.0, 4.0, 5.0], vec![0.0; 6], vec![0.0; 6]];
        let cloth = vec![0, 0, 0, 1, 1, 1];
        let mut h = SpatialHash::new(6);
        h.build(&z[0], &z[1], &z[2], 6, 1e-30).unwrap();
        h.attach_rest([&rest[0], &rest[1], &rest[2]], &cloth).unwrap();
        let mut got = Neighbours::new();
        // Skip 1: rest neighbours are (0,1), (1,2), (3,4), (4,5).
        h.query_upper_unskipped(1e-30, 1.0, &mut got).unwrap();
        let pairs: Vec<_> = got.pairs().collect();
        assert_eq!(
            pairs,
            vec![
                (0, 2),
                (0, 3),
                (0, 4),
                (0, 5),
                (1, 3),
                (1, 4),
                (1, 5),
                (2, 3),
                (2, 4),
                (2, 5),
                (3, 5)
            ]
        );
    }
}
