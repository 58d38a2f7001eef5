//! Neighbour lists of a particle set in compressed-sparse-row (CSR) form.
//!
//! The self-collision broadphase ([`crate::self_collision::hash`], [`crate::self_collision::tree`]) answers one
//! question for every particle `i`: which particles `j != i` lie within `max_dist`? The answer
//! is stored the way Müller's "Ten Minute Physics" hash stores it (`firstAdjId` / `adjIds`): the neighbours of `i`
//! are `ids[first[i] .. first[i + 1]]`.
//!
//! # The neighbour predicate
//! Every broadphase in weft, and the brute-force reference [`Neighbours::fill_brute_force`],
//! uses one predicate, evaluated in `f32` in this exact order:
//!
//! ```text
//! dx = x[j] - x[i];  dy = y[j] - y[i];  dz = z[j] - z[i]
//! j is a neighbour of i  <=>  j != i  and  (dx*dx + dy*dy) + dz*dz <= max_dist * max_dist
//! ```
//!
//! Swapping `i` and `j` only negates `dx, dy, dz`, so the relation is symmetric bit for bit.
//! A particle with a non-finite coordinate (NaN or ±Inf) fails the predicate with everyone, so
//! it has no neighbours and is nobody's neighbour. Coincident particles (`dist2 == 0`) are
//! neighbours: the response must handle them, not the broadphase skip them.
//!
//! # Canonical form
//! Each list is sorted ascending and holds no duplicates, so the CSR arrays are a function of
//! the positions alone: the hash, the tree, the brute force, serial or parallel, on any number
//! of threads, all produce the same bits.
//!
//! Buffers are kept between calls: once the lists have reached their working size, refilling
//! them allocates nothing.
//!
//! # Limit
//! The entries a fill may write are bounded ([`Neighbours::set_limit`]): particles that have
//! collapsed onto each other, or a reach far above their spacing, would otherwise list every
//! pair (`n²` entries). A fill that passes the limit stops writing, empties the lists and
//! returns an error.

pub(crate) mod limit;
pub(crate) mod predicate;

use crate::Result;
use rayon::prelude::*;

pub(crate) use limit::{too_many, Meter};
use limit::{Budget, MAX_ENTRIES};
pub(crate) use predicate::{check_max_dist, check_positions, pair_reach2, search_radius, within, Candidates};

/// Particles handled by one parallel task when filling lists. Fixed, so the work split does not
/// depend on the thread count (the result would not either: lists are canonical).
pub(crate) const CHUNK: usize = 256;

/// Neighbour lists in CSR form: the neighbours of particle `i` are
/// `ids[first[i] as usize .. first[i + 1] as usize]`, sorted ascending.
#[derive(Debug, Clone)]
pub struct Neighbours {
    /// Offsets into `ids`, length `n + 1`, `first[0] == 0`, non-decreasing.
    pub first: Vec<u32>,
    /// Neighbour ids of particle 0, then of particle 1, and so on.
    pub ids: Vec<u32>,
    /// Per-chunk output buffers of the parallel fill, kept to avoid allocation.
    scratch: Vec<Vec<u32>>,
    /// Pair assembly ([`pairs`]): pairs before each buffer, each part's counts (a particle
    /// each) and marks (a particle each), group starts by partner, then the smaller ids by
    /// partner.
    starts: Vec<usize>,
    counts: Vec<u32>,
    marks: Vec<u32>,
    by_j: Vec<u32>,
    order: Vec<u32>,
    /// Most entries a fill may write (see the module docs).
    limit: usize,
    /// Whether the last fill stopped at the limit.
    limited: bool,
}

impl Default for Neighbours {
    fn default() -> Self {
        Self::new()
    }
}

impl PartialEq for Neighbours {
    /// Two sets of lists are equal when their CSR arrays are (scratch space is ignored).
    fn eq(&self, other: &Self) -> bool {
        self.first == other.first && self.ids == other.ids
    }
}

impl Eq for Neighbours {}

impl Neighbours {
    /// Empty lists for zero particles.
    pub fn new() -> Self {
        Self {
            first: vec![0],
            ids: Vec::new(),
            scratch: Vec::new(),
            starts: Vec::new(),
            counts: Vec::new(),
            marks: Vec::new(),
            by_j: Vec::new(),
            order: Vec::new(),
            limit: MAX_ENTRIES,
            limited: false,
        }
    }

    /// Bounds the entries a fill may write (at most `2^32 - 1`, the default): a fill that
    /// would write more empties the lists and returns an error instead.
    pub fn set_limit(&mut self, entries: usize) {
        self.limit = entries.min(MAX_ENTRIES);
    }

    /// The limit of [`Neighbours::set_limit`].
    pub fn limit(&self) -> usize {
        self.limit
    }

    /// Whether the last fill stopped at the limit (and returned its error).
    pub fn limited(&self) -> bool {
        self.limited
    }

    /// Number of particles the lists are for.
    pub fn len(&self) -> usize {
        self.first.len().saturating_sub(1)
    }

    /// Whether the lists are for zero particles.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Total number of entries over all lists (each unordered pair counts twice).
    pub fn total(&self) -> usize {
        self.ids.len()
    }

    /// The neighbours of particle `i`, ascending.
    ///
    /// # Panics
    /// If `i >= self.len()`, like slice indexing. Use [`Neighbours::get`] to check instead.
    pub fn of(&self, i: usize) -> &[u32] {
        &self.ids[self.first[i] as usize..self.first[i + 1] as usize]
    }

    /// The neighbours of particle `i`, or `None` if `i` is out of range.
    pub fn get(&self, i: usize) -> Option<&[u32]> {
        if i < self.len() {
            Some(self.of(i))
        } else {
            None
        }
    }

    /// Every unordered neighbour pair once, as `(i, j)` with `i < j`, ordered by `i` then `j`.
    pub fn pairs(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        (0..self.len()).flat_map(move |i| {
            let list = self.of(i);
            // The list is sorted: skip the part with j <= i.
            let from = list.partition_point(|&j| (j as usize) <= i);
            list[from..].iter().map(move |&j| (i as u32, j))
        })
    }

    /// Removes every entry `j` of list `i` without `keep(i, j)` (serial, in place, order kept).
    pub fn retain(&mut self, keep: impl Fn(usize, u32) -> bool) {
        let mut w = 0usize;
        let mut start = 0usize;
        for i in 0..self.len() {
            let end = self.first[i + 1] as usize;
            for r in start..end {
                let j = self.ids[r];
                if keep(i, j) {
                    self.ids[w] = j;
                    w += 1;
                }
            }
            start = end;
            self.first[i + 1] = w as u32;
        }
        self.ids.truncate(w);
    }

    /// Empties the lists (zero particles) and keeps every buffer's capacity.
    pub fn clear(&mut self) {
        self.first.clear();
        self.first.push(0);
        self.ids.clear();
    }

    /// Fills the lists by testing every pair: O(n²), serial. The reference the broadphases are
    /// tested against, and the right choice for a few dozen particles.
    pub fn fill_brute_force(&mut self, x: &[f32], y: &[f32], z: &[f32], n: usize, max_dist: f32) -> Result<()> {
        check_positions(x, y, z, n)?;
        let md2 = check_max_dist(max_dist)?;
        self.fill_serial(n, |i, buf| {
            let (xi, yi, zi) = (x[i], y[i], z[i]);
            for j in 0..n {
                if j != i && within(xi, yi, zi, x[j], y[j], z[j], md2) {
                    buf.push(j as u32);
                }
            }
        })
    }

    /// Fills the lists in parallel: `f(i, buf)` appends the neighbours of `i` to `buf`, sorted
    /// and without duplicates. Particles are split into fixed chunks of [`CHUNK`]; each chunk
    /// appends to its own kept buffer, then the buffers are copied into `ids` in parallel.
    pub(crate) fn fill_parallel<F>(&mut self, n: usize, f: F) -> Result<()>
    where
        F: Fn(usize, &mut Vec<u32>) + Sync,
    {
        let chunks = n.div_ceil(CHUNK);
        if self.scratch.len() < chunks {
            self.scratch.resize_with(chunks, Vec::new);
        }
        self.first.clear();
        self.first.resize(n + 1, 0);
        let budget = Budget::new(self.limit);
        self.first[1..]
            .par_chunks_mut(CHUNK)
            .zip(self.scratch[..chunks].par_iter_mut())
            .enumerate()
            .for_each(|(c, (counts, buf))| {
                buf.clear();
                if budget.over() {
                    return;
                }
                let mut meter = budget.meter();
                for (k, count) in counts.iter_mut().enumerate() {
                    let before = buf.len();
                    f(c * CHUNK + k, buf);
                    *count = (buf.len() - before) as u32;
                    if !meter.add(buf.len() - before) {
                        return;
                    }
                }
                meter.flush();
            });
        self.limited = budget.over();
        if self.limited {
            self.clear();
            return Err(too_many(self.limit, n));
        }
        let total = match prefix_sum(&mut self.first) {
            Ok(t) => t,
            Err(e) => {
                self.clear();
                return Err(e);
            }
        };
        self.ids.clear();
        self.ids.resize(total, 0);
        copy_buffers(&self.scratch[..chunks], &mut self.ids);
        Ok(())
    }

    /// Serial twin of [`Neighbours::fill_parallel`]: one loop, appending straight into `ids`.
    #[inline]
    pub(crate) fn fill_serial<F>(&mut self, n: usize, mut f: F) -> Result<()>
    where
        F: FnMut(usize, &mut Vec<u32>),
    {
        self.clear();
        self.limited = false;
        for i in 0..n {
            f(i, &mut self.ids);
            if self.ids.len() > self.limit {
                self.clear();
                self.limited = true;
                return Err(too_many(self.limit, n));
            }
            self.first.push(self.ids.len() as u32);
        }
        Ok(())
    }
}

/// Turns per-particle counts in `first[1..]` into offsets; returns the total.
fn prefix_sum(first: &mut [u32]) -> Result<usize> {
    let mut acc: u64 = 0;
    for v in first.iter_mut().skip(1) {
        acc += u64::from(*v);
        if acc > u64::from(u32::MAX) {
            return Err(too_many(MAX_ENTRIES, first.len().saturating_sub(1)));
        }
        *v = acc as u32;
    }
    Ok(acc as usize)
}

/// Copies the chunk buffers one after another into `dst` (whose length is their total),
/// splitting the work in halves with `rayon::join` (no allocation).
fn copy_buffers(bufs: &[Vec<u32>], dst: &mut [u32]) {
    if bufs.len() <= 4 {
        let mut at = 0;
        for b in bufs {
            dst[at..at + b.len()].copy_from_slice(b);
            at += b.len();
        }
        return;
    }
    let mid = bufs.len() / 2;
    let left: usize = bufs[..mid].iter().map(Vec::len).sum();
    let (dl, dr) = dst.split_at_mut(left);
    rayon::join(|| copy_buffers(&bufs[..mid], dl), || copy_buffers(&bufs[mid..], dr));
}

/// Removes from `buf[start..]` the entries without `keep(j)`, keeping the others in order.
#[inline]
pub(crate) fn retain_tail(buf: &mut Vec<u32>, start: usize, keep: impl Fn(u32) -> bool) {
    let mut w = start;
    for r in start..buf.len() {
        let j = buf[r];
        if keep(j) {
            buf[w] = j;
            w += 1;
        }
    }
    buf.truncate(w);
}

/// Sorts `buf[start..]` and removes repeated ids from it.
#[inline]
pub(crate) fn sort_dedup_tail(buf: &mut Vec<u32>, start: usize) {
    let tail = &mut buf[start..];
    if tail.len() < 2 {
        return;
    }
    tail.sort_unstable();
    let mut w = 1;
    for r in 1..tail.len() {
        if tail[r] != tail[w - 1] {
            tail[w] = tail[r];
            w += 1;
        }
    }
    buf.truncate(start + w);
}

mod pairs;

#[cfg(test)]
mod tests;
