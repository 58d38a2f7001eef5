//! Spatial hash for cloth self-collision: SEEDS section C (after Müller, "Ten Minute Physics"
//! 11 and 15).
//!
//! # Method
//! Space is cut into cubic cells of side `spacing`; particle `i` lies in cell
//! `(⌊x_i / s⌋, ⌊y_i / s⌋, ⌊z_i / s⌋)` (computed as `floor(x * (1/s))` in `f32`). The grid is
//! unbounded, so cells are hashed into a table of `table_size` buckets; two cells sharing a
//! bucket is harmless because every candidate is distance-checked.
//!
//! **Dense layout by counting sort** (the paper's `cellStart` / `cellEntries`):
//! 1. bucket of every particle (parallel, one independent value per particle);
//! 2. count particles per bucket, prefix sum, so `cell_start[b]` is where bucket `b` begins;
//! 3. write particle ids into `cell_entries` (serial, stable: ids ascend within a bucket).
//!
//! The result is a pure function of the positions: no step depends on the thread count.
//!
//! **Query** (`queryAll`): for each particle, the cells overlapped by the box
//! `[x_i - r, x_i + r]³` are scanned, `r` being `max_dist` plus a tiny rounding margin
//! (see [`super::neighbours`]). With `max_dist < spacing` that is at most the 27 cells around
//! the particle's own (the paper's rule); with `max_dist == spacing` a particle lying exactly on
//! a cell boundary sees one more layer (up to 4 cells an axis), because the margin reaches past
//! the boundary. Candidates pass the shared neighbour predicate; the list is sorted and
//! de-duplicated (two rows of the box may share buckets). Candidates are tested eight at a time
//! (`f32x8`, the predicate computed operation for operation like the scalar one, no FMA), and
//! queries run in parallel over particles; the lists are canonical, so the output is bitwise
//! the same for any thread count, equal to the scalar serial twin and to the brute force.
//!
//! # Choices
//! * `table_size` is the smallest power of two `>= 2n` (at least 16): the paper's "about twice
//!   the particle count", rounded to a power of two so the modulo is a mask.
//! * Bucket of cell `(cx, cy, cz)` = `mix(cy, cz) + cx` modulo `table_size`, `mix` being the
//!   splitmix64 finalizer: the cells of one row along x sit in consecutive buckets, so a query
//!   reads each row of its search box as one contiguous range of `cell_entries` (9 to 16 ranges
//!   instead of 27 to 64 cells), while different rows land at random places.
//! * The build also copies the positions into `cell_entries` order, so candidates are read
//!   contiguously; the query checks that it is given the positions of the build.
//! * Spacing: the paper uses `spacing = max_dist`. On a folded cloth at rest (particles on the
//!   cell lattice) a spacing of about `1.5 * max_dist` queried ~1.5x faster in our runs (fewer
//!   ranges for a similar number of candidates); measure on your scene (`benches/broadphase.rs`).
//! * Non-finite particles (NaN or ±Inf in any coordinate) go in no bucket and get no
//!   neighbours, matching the predicate; [`SpatialHash::non_finite`] counts them so the caller
//!   can report a diverged state. Huge finite coordinates saturate the integer cell coordinate;
//!   that is still correct (only slower), as cells are monotone in the coordinate.
//! * A particle whose search box spans more than 4 cells along an axis — possible only for a
//!   spacing below about `1e-18`, where the margin for underflowing squares dominates — is
//!   tested against all particles instead (correct, slow).

use super::neighbours::{
    check_max_dist, check_positions, retain_tail, search_radius, sort_dedup_tail, within, Candidates, Neighbours, CHUNK,
};
use crate::lanes::LANES;
use crate::{Result, WeftError};
use rayon::prelude::*;

/// Bucket value of a particle that is in no bucket (non-finite coordinates).
const NO_BUCKET: u32 = u32::MAX;

/// A spatial hash over particle positions, rebuilt each step (see the module docs).
#[derive(Debug, Clone)]
pub struct SpatialHash {
    spacing: f32,
    inv_spacing: f32,
    table_size: usize,
    /// `64 - log2(table_size)`: the bucket is the top bits of the mixed hash.
    shift: u32,
    n: usize,
    non_finite: usize,
    /// Bucket of each particle, `NO_BUCKET` when non-finite.
    bucket_of: Vec<u32>,
    /// Length `table_size + 1`: bucket `b` holds `cell_entries[cell_start[b]..cell_start[b+1]]`.
    cell_start: Vec<u32>,
    /// Particle ids grouped by bucket, ascending within a bucket.
    cell_entries: Vec<u32>,
    /// Positions in `cell_entries` order, so a bucket's candidates are read contiguously.
    sx: Vec<f32>,
    sy: Vec<f32>,
    sz: Vec<f32>,
    /// Index of each particle in `cell_entries`, `NO_BUCKET` when non-finite.
    slot_of: Vec<u32>,
}

/// The table size used for `n` particles: smallest power of two `>= max(2n, 16)`.
pub fn table_size_for(n: usize) -> usize {
    (2 * n).max(16).next_power_of_two()
}

impl SpatialHash {
    /// An empty hash with buffers reserved for `max_particles`; building with more particles
    /// later works too (the buffers grow once).
    pub fn new(max_particles: usize) -> Self {
        let ts = table_size_for(max_particles);
        Self {
            spacing: 1.0,
            inv_spacing: 1.0,
            table_size: table_size_for(0),
            shift: 64 - table_size_for(0).trailing_zeros(),
            n: 0,
            non_finite: 0,
            bucket_of: Vec::with_capacity(max_particles),
            cell_start: {
                let mut v = Vec::with_capacity(ts + 1);
                v.resize(table_size_for(0) + 1, 0);
                v
            },
            cell_entries: Vec::with_capacity(max_particles),
            sx: Vec::with_capacity(max_particles + LANES),
            sy: Vec::with_capacity(max_particles + LANES),
            sz: Vec::with_capacity(max_particles + LANES),
            slot_of: Vec::with_capacity(max_particles),
        }
    }

    /// Cell side length of the last build.
    pub fn spacing(&self) -> f32 {
        self.spacing
    }

    /// Number of buckets of the last build.
    pub fn table_size(&self) -> usize {
        self.table_size
    }

    /// Number of particles of the last build.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the last build had zero particles.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Particles of the last build left out because a coordinate was NaN or infinite.
    pub fn non_finite(&self) -> usize {
        self.non_finite
    }

    /// Bucket offsets, length `table_size + 1` (the paper's `cellStart`).
    pub fn cell_start(&self) -> &[u32] {
        &self.cell_start
    }

    /// Particle ids grouped by bucket (the paper's `cellEntries`).
    pub fn cell_entries(&self) -> &[u32] {
        &self.cell_entries
    }

    /// Integer cell coordinate of a coordinate value (saturating for huge values).
    #[inline(always)]
    fn coord(&self, v: f32) -> i32 {
        (v * self.inv_spacing).floor() as i32
    }

    /// Bucket of cell `(0, cy, cz)`: a 64-bit mix of the row, top `log2(table_size)` bits.
    #[inline(always)]
    fn row_base(&self, cy: i32, cz: i32) -> u64 {
        // The splitmix64 finalizer of the packed pair: every input bit reaches every top bit.
        let mut h = ((cy as u32 as u64) << 32) | cz as u32 as u64;
        h = (h ^ (h >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        h = (h ^ (h >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (h ^ (h >> 31)) >> self.shift
    }

    /// Bucket of the cell `(cx, cy, cz)`: the row's hashed base plus `cx`, modulo the table
    /// size, so the cells of a row along x sit in consecutive buckets and a query reads each
    /// row of its search box as one contiguous range of `cell_entries`.
    #[inline(always)]
    fn bucket(&self, cx: i32, cy: i32, cz: i32) -> usize {
        let mask = self.table_size as u64 - 1;
        (self.row_base(cy, cz).wrapping_add(cx as i64 as u64) & mask) as usize
    }

    #[inline(always)]
    fn bucket_of_point(&self, x: f32, y: f32, z: f32) -> u32 {
        if x.is_finite() && y.is_finite() && z.is_finite() {
            self.bucket(self.coord(x), self.coord(y), self.coord(z)) as u32
        } else {
            NO_BUCKET
        }
    }

    /// Validates inputs and sizes the tables for `n` particles.
    fn prepare(&mut self, x: &[f32], y: &[f32], z: &[f32], n: usize, spacing: f32) -> Result<()> {
        if !(spacing.is_normal() && spacing > 0.0) {
            return Err(WeftError::param(
                "spacing",
                spacing,
                "must be a finite number greater than zero (and not subnormal)",
            ));
        }
        check_positions(x, y, z, n)?;
        self.spacing = spacing;
        self.inv_spacing = 1.0 / spacing;
        self.table_size = table_size_for(n);
        self.shift = 64 - self.table_size.trailing_zeros();
        self.n = n;
        self.bucket_of.clear();
        self.bucket_of.resize(n, 0);
        Ok(())
    }

    /// Builds the hash of particles `0..n` with cell size `spacing`, hashing in parallel.
    ///
    /// Errors if `spacing` is not a positive normal number or an array is shorter than `n`.
    /// Particles with a non-finite coordinate are put in no cell (see the module docs).
    pub fn build(&mut self, x: &[f32], y: &[f32], z: &[f32], n: usize, spacing: f32) -> Result<()> {
        self.prepare(x, y, z, n, spacing)?;
        let mut buckets = std::mem::take(&mut self.bucket_of);
        let this = &*self;
        buckets.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
            for (k, b) in out.iter_mut().enumerate() {
                let i = c * CHUNK + k;
                *b = this.bucket_of_point(x[i], y[i], z[i]);
            }
        });
        self.bucket_of = buckets;
        self.counting_sort(x, y, z);
        Ok(())
    }

    /// Serial twin of [`SpatialHash::build`]; produces identical tables.
    pub fn build_serial(&mut self, x: &[f32], y: &[f32], z: &[f32], n: usize, spacing: f32) -> Result<()> {
        self.prepare(x, y, z, n, spacing)?;
        for i in 0..n {
            self.bucket_of[i] = self.bucket_of_point(x[i], y[i], z[i]);
        }
        self.counting_sort(x, y, z);
        Ok(())
    }

    /// Stable counting sort of particle ids by bucket into `cell_start` / `cell_entries`, with
    /// the positions copied alongside.
    fn counting_sort(&mut self, x: &[f32], y: &[f32], z: &[f32]) {
        let ts = self.table_size;
        self.cell_start.clear();
        self.cell_start.resize(ts + 1, 0);
        let mut placed = 0u32;
        for &b in &self.bucket_of {
            if b != NO_BUCKET {
                self.cell_start[b as usize] += 1;
                placed += 1;
            }
        }
        // Inclusive prefix: cell_start[b] = end of bucket b.
        let mut acc = 0u32;
        for c in &mut self.cell_start[..ts] {
            acc += *c;
            *c = acc;
        }
        self.cell_start[ts] = placed;
        self.non_finite = self.n - placed as usize;
        self.cell_entries.clear();
        self.cell_entries.resize(placed as usize, 0);
        for v in [&mut self.sx, &mut self.sy, &mut self.sz] {
            v.clear();
            // LANES of NaN padding: a lane load at any entry stays in bounds, and NaN lanes
            // fail the predicate.
            v.resize(placed as usize + LANES, f32::NAN);
        }
        self.slot_of.clear();
        self.slot_of.resize(self.n, NO_BUCKET);
        // Filling from the back while decrementing leaves cell_start[b] = start of bucket b and
        // the ids ascending within each bucket.
        for i in (0..self.n).rev() {
            let b = self.bucket_of[i];
            if b != NO_BUCKET {
                let slot = &mut self.cell_start[b as usize];
                *slot -= 1;
                let k = *slot as usize;
                self.cell_entries[k] = i as u32;
                (self.sx[k], self.sy[k], self.sz[k]) = (x[i], y[i], z[i]);
                self.slot_of[i] = k as u32;
            }
        }
    }

    /// Whether particle `i` has the position it had at the last build (bitwise; a non-finite
    /// particle only has to stay non-finite).
    #[inline]
    fn unchanged(&self, x: &[f32], y: &[f32], z: &[f32], i: usize) -> bool {
        match self.slot_of[i] {
            NO_BUCKET => !(x[i].is_finite() && y[i].is_finite() && z[i].is_finite()),
            k => {
                let k = k as usize;
                x[i].to_bits() == self.sx[k].to_bits() && y[i].to_bits() == self.sy[k].to_bits() && z[i].to_bits() == self.sz[k].to_bits()
            }
        }
    }

    /// Checks query inputs against the build; returns `max_dist²`. `same` is whether the
    /// positions are those of the build (computed by the caller, in parallel or not).
    fn check_query(&self, x: &[f32], y: &[f32], z: &[f32], n: usize, max_dist: f32, same: impl FnOnce() -> bool) -> Result<f32> {
        check_positions(x, y, z, n)?;
        if n != self.n {
            return Err(WeftError::param(
                "n",
                n,
                format!("must equal the particle count of the last build ({})", self.n),
            ));
        }
        let md2 = check_max_dist(max_dist)?;
        if max_dist > self.spacing {
            return Err(WeftError::param(
                "max_dist",
                max_dist,
                format!("must not exceed the hash spacing ({})", self.spacing),
            ));
        }
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
        // Clamping to ±f32::MAX keeps the range finite; finite neighbours lie inside anyway.
        let lo = |v: f32| self.coord((v - r).max(-f32::MAX));
        let hi = |v: f32| self.coord((v + r).min(f32::MAX));
        let (x0, x1, y0, y1, z0, z1) = (lo(xi), hi(xi), lo(yi), hi(yi), lo(zi), hi(zi));
        let start = buf.len();
        let wide = |a: i32, b: i32| i64::from(b) - i64::from(a) > 3;
        if wide(x0, x1) || wide(y0, y1) || wide(z0, z1) {
            for j in 0..n {
                if j != i && within(xi, yi, zi, x[j], y[j], z[j], md2) && keep(i, j as u32) {
                    buf.push(j as u32);
                }
            }
            return;
        }
        let iu = i as u32;
        let ts = self.table_size;
        let p = [xi, yi, zi];
        // Buckets b0 ..= b0 + w hold one row of cells; they may wrap past the table's end.
        let cells = (x1 as i64 - x0 as i64) as usize + 1;
        for cz in z0..=z1 {
            for cy in y0..=y1 {
                let b0 = self.bucket(x0, cy, cz);
                let b1 = b0 + cells;
                if b1 <= ts {
                    self.scan_buckets::<SIMD>(b0, b1, iu, p, md2, buf);
                } else {
                    self.scan_buckets::<SIMD>(b0, ts, iu, p, md2, buf);
                    self.scan_buckets::<SIMD>(0, b1 - ts, iu, p, md2, buf);
                }
            }
        }
        retain_tail(buf, start, |j| keep(i, j));
        sort_dedup_tail(buf, start);
    }

    /// Tests the particles of buckets `b0..b1` (one contiguous range) against `p`.
    #[inline(always)]
    fn scan_buckets<const SIMD: bool>(&self, b0: usize, b1: usize, iu: u32, p: [f32; 3], md2: f32, buf: &mut Vec<u32>) {
        let range = self.cell_start[b0] as usize..self.cell_start[b1] as usize;
        let c = Candidates {
            ids: &self.cell_entries,
            x: &self.sx,
            y: &self.sy,
            z: &self.sz,
        };
        c.scan::<SIMD>(range, iu, p, md2, buf);
    }
}
