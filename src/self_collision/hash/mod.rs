//! Spatial hash for cloth self-collision, after Müller, "Ten Minute Physics" 11 and 15.
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
//! (see [`crate::self_collision::neighbours`]). With `max_dist < spacing` that is at most the 27 cells around
//! the particle's own (the paper's rule); with `max_dist == spacing` a particle lying exactly on
//! a cell boundary sees one more layer (up to 4 cells an axis), because the margin reaches past
//! the boundary. Candidates pass the shared neighbour predicate; the list is sorted and
//! de-duplicated (two rows of the box may share buckets). Candidates are tested eight at a time
//! (`f32x8`, the predicate computed operation for operation like the scalar one, no FMA), and
//! queries run in parallel over particles; the lists are canonical, so the output is bitwise
//! the same for any thread count, equal to the scalar serial twin and to the brute force.
//! The self-collision stage uses a cell-centric form of the query instead (module
//! `hash::cells`: occupied buckets walked over a half shell, each pair tested once, the same
//! lists).
//!
//! # Choices
//! * `table_size` is the smallest power of two `>= 2n` (at least 16): the paper's "about twice
//!   the particle count", rounded to a power of two so the modulo is a mask (smaller tables
//!   made the query slower, larger ones the build).
//! * Bucket of cell `(cx, cy, cz)` = `row(cy, cz) + cx` modulo `table_size`: the cells of one
//!   row along x sit in consecutive buckets, so a query reads each row of its search box as one
//!   contiguous range of `cell_entries` (9 to 16 ranges instead of 27 to 64 cells). The row's
//!   base is linear, `cy a + cz b` (cells numbered in `(z, y, x)` order over the particles'
//!   box, so neighbouring rows lie near each other in the slots), when that box has at most
//!   four times `table_size` cells, and otherwise the splitmix64 finalizer of `(cy, cz)` (rows
//!   at random places); the choice is made at each build from its positions (module `rows`).
//! * The build also copies the positions into `cell_entries` order, so candidates are read
//!   contiguously; the query checks that it is given the positions of the build. The
//!   self-collision query ([`SpatialHash::query_upper_unskipped_cells`], module `hash::rest`) also
//!   reads rest positions and cloth ids copied into that order after the build.
//! * Spacing: the paper uses `spacing = max_dist`. On a folded cloth at rest (particles on the
//!   cell lattice) a spacing of about `1.5 * max_dist` queried ~1.5x faster in our runs (fewer
//!   ranges for a similar number of candidates); measure on your scene (`benches/broadphase.rs`).
//! * Non-finite particles (NaN or ±Inf in any coordinate) go in no bucket and get no
//!   neighbours, matching the predicate; [`SpatialHash::non_finite`] counts them so the caller
//!   can report a diverged state. Huge finite coordinates saturate the integer cell coordinate;
//!   that is still correct (only slower), as cells are monotone in the coordinate.
//! * A particle whose search box spans more than 8 cells along an axis — possible only for a
//!   spacing below about `1e-18`, where the margin for underflowing squares dominates, or for
//!   a fast particle of the self-collision query with travels attached far above the members'
//!   — is tested against all particles instead (correct, slow).

use crate::data::lanes::{finite_lanes, load, F32s, LANES};
use crate::self_collision::neighbours::{check_positions, CHUNK};
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
    /// `64 - log2(table_size)`: the mixing hash's row base is its top bits.
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
    /// Rest data in cell order for the self-collision query (the `hash::rest` module).
    rest: rest::RestCopy,
    /// Row strides of the linear row map, or `None` for the mixing hash (module `rows`).
    strides: Option<(u64, u64)>,
}

impl Default for SpatialHash {
    /// An empty hash (for no particles).
    fn default() -> Self {
        Self::new(0)
    }
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
            rest: rest::RestCopy::default(),
            strides: None,
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

    /// Bucket of the cell `(cx, cy, cz)`: the row's hashed base plus `cx`, modulo the table
    /// size, so the cells of a row along x sit in consecutive buckets and a query reads each
    /// row of its search box as one contiguous range of `cell_entries`.
    #[inline(always)]
    fn bucket(&self, cx: i32, cy: i32, cz: i32) -> usize {
        self.in_row(self.row_base(cy, cz), cx)
    }

    /// The bucket of cell `cx` of the row whose hashed base is `base`.
    #[inline(always)]
    fn in_row(&self, base: u64, cx: i32) -> usize {
        (base.wrapping_add(cx as i64 as u64) & (self.table_size as u64 - 1)) as usize
    }

    /// The bucket of one point, or `NO_BUCKET` when a coordinate is not finite (the
    /// reference of [`SpatialHash::fill_buckets`]).
    #[cfg(test)]
    fn bucket_of_point(&self, x: f32, y: f32, z: f32) -> u32 {
        if x.is_finite() && y.is_finite() && z.is_finite() {
            self.bucket(self.coord(x), self.coord(y), self.coord(z)) as u32
        } else {
            NO_BUCKET
        }
    }

    /// The buckets of particles `start..start + out.len()` into `out` (the bucket of each
    /// particle's cell, `NO_BUCKET` for a non-finite one). The cell coordinates are computed
    /// eight particles at a time when `simd` (`floor` then the saturating conversion of `as
    /// i32`: the same integers as [`SpatialHash::coord`]), else one by one (the twin). The
    /// particles of a cloth row often share the cell row `(cy, cz)` (a row along x shares it
    /// all along), so the row's hashed base is reused from the particle before when it is the
    /// same row: the same value without the two 64-bit multiplications.
    fn fill_buckets(&self, p: [&[f32]; 3], start: usize, out: &mut [u32], simd: bool) {
        let mut rows = RowMemo::new(self);
        let mut k = 0;
        if simd {
            let inv = F32s::splat(self.inv_spacing);
            while k + LANES <= out.len() {
                let i = start + k;
                let (x, y, z) = (load(p[0], i), load(p[1], i), load(p[2], i));
                let finite = finite_lanes(x) & finite_lanes(y) & finite_lanes(z);
                let bad = !finite.to_bitmask();
                let c = [x, y, z].map(|v| (v * inv).floor().trunc_int().to_array());
                for l in 0..LANES {
                    out[k + l] = if bad & (1 << l) != 0 {
                        NO_BUCKET
                    } else {
                        rows.bucket(c[0][l], c[1][l], c[2][l])
                    };
                }
                k += LANES;
            }
        }
        for (k, b) in out.iter_mut().enumerate().skip(k) {
            let i = start + k;
            let (x, y, z) = (p[0][i], p[1][i], p[2][i]);
            *b = if x.is_finite() && y.is_finite() && z.is_finite() {
                rows.bucket(self.coord(x), self.coord(y), self.coord(z))
            } else {
                NO_BUCKET
            };
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
        self.rest.valid = false;
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
        self.choose_rows([x, y, z], n, true);
        let mut buckets = std::mem::take(&mut self.bucket_of);
        let this = &*self;
        buckets
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, out)| this.fill_buckets([x, y, z], c * CHUNK, out, true));
        self.bucket_of = buckets;
        self.counting_sort(x, y, z);
        Ok(())
    }

    /// Serial twin of [`SpatialHash::build`]; produces identical tables.
    pub fn build_serial(&mut self, x: &[f32], y: &[f32], z: &[f32], n: usize, spacing: f32) -> Result<()> {
        self.prepare(x, y, z, n, spacing)?;
        self.choose_rows([x, y, z], n, false);
        let mut buckets = std::mem::take(&mut self.bucket_of);
        self.fill_buckets([x, y, z], 0, &mut buckets, false);
        self.bucket_of = buckets;
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
}

/// The last cell row's hashed base (see [`SpatialHash::fill_buckets`]).
struct RowMemo<'a> {
    hash: &'a SpatialHash,
    last: Option<(i32, i32, u64)>,
}

impl<'a> RowMemo<'a> {
    fn new(hash: &'a SpatialHash) -> Self {
        RowMemo { hash, last: None }
    }

    /// [`SpatialHash::bucket`] of cell `(cx, cy, cz)`, the row's base reused when the row is
    /// the last one's.
    #[inline(always)]
    fn bucket(&mut self, cx: i32, cy: i32, cz: i32) -> u32 {
        let base = match self.last {
            Some((ly, lz, base)) if ly == cy && lz == cz => base,
            _ => {
                let base = self.hash.row_base(cy, cz);
                self.last = Some((cy, cz, base));
                base
            }
        };
        self.hash.in_row(base, cx) as u32
    }
}

mod query;

mod rest;

mod cells;

mod rows;
