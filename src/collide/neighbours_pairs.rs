//! Neighbour lists assembled from emitted pairs (a cell-centric broadphase finds each pair
//! from whichever side is convenient, then files it under its smaller id).
//!
//! # Method
//! Tasks append pairs `(i, j)`, `i < j`, as two `u32` each, to their own kept buffers (in
//! parallel, a fixed number of tasks, so the split does not depend on the thread count). Then:
//! 1. count the pairs of each `i` (serial over the buffers) and prefix-sum the counts into
//!    `first`;
//! 2. scatter each `j` to the next free place of its list (serial, buffer order);
//! 3. sort every list (in parallel, fixed chunks of particles) and drop repeated ids, the
//!    lists being compacted in one serial pass.
//!
//! Sorting and de-duplicating make the lists canonical: they do not depend on the order the
//! pairs were emitted in, nor on the number of threads, so they equal the lists of any other
//! upper query (each pair once, in the list of its smaller id).

use super::{prefix_sum, too_many, Neighbours, CHUNK};
use crate::Result;
use rayon::prelude::*;

impl Neighbours {
    /// Fills upper lists (each pair once, under its smaller id) for `n` particles from pairs:
    /// `f(t, buf)` for each task `t < tasks` (in parallel) appends pairs `i, j` (`i < j < n`,
    /// flattened) to `buf`; a pair may be emitted more than once.
    pub(crate) fn fill_pairs_parallel<F>(&mut self, n: usize, tasks: usize, f: F) -> Result<()>
    where
        F: Fn(usize, &mut Vec<u32>) + Sync,
    {
        if self.scratch.len() < tasks {
            self.scratch.resize_with(tasks, Vec::new);
        }
        self.scratch[..tasks].par_iter_mut().enumerate().for_each(|(t, buf)| {
            buf.clear();
            f(t, buf);
        });
        self.assemble(n, tasks, true)
    }

    /// Serial twin of [`Neighbours::fill_pairs_parallel`]: one task appends every pair.
    pub(crate) fn fill_pairs_serial<F>(&mut self, n: usize, f: F) -> Result<()>
    where
        F: FnOnce(&mut Vec<u32>),
    {
        if self.scratch.is_empty() {
            self.scratch.push(Vec::new());
        }
        self.scratch[0].clear();
        f(&mut self.scratch[0]);
        self.assemble(n, 1, false)
    }

    /// Counts, scatters, sorts and de-duplicates the pairs of the first `tasks` buffers.
    fn assemble(&mut self, n: usize, tasks: usize, parallel: bool) -> Result<()> {
        let bufs = &self.scratch[..tasks];
        self.first.clear();
        self.first.resize(n + 1, 0);
        for b in bufs {
            for p in b.chunks_exact(2) {
                self.first[p[0] as usize + 1] += 1;
            }
        }
        let total = match prefix_sum(&mut self.first) {
            Ok(t) => t,
            Err(e) => {
                self.clear();
                return Err(e);
            }
        };
        if total == 0 {
            self.ids.clear();
            return Ok(());
        }
        self.ids.clear();
        self.ids.resize(total, 0);
        // `first[i]` serves as the cursor of list `i`; afterwards it holds the end of list `i`,
        // which is the start of list `i + 1`, so shifting by one restores the offsets.
        for b in bufs {
            for p in b.chunks_exact(2) {
                let c = &mut self.first[p[0] as usize];
                self.ids[*c as usize] = p[1];
                *c += 1;
            }
        }
        self.first.copy_within(0..n, 1);
        self.first[0] = 0;
        if parallel {
            sort_lists_parallel(&self.first, &mut self.ids, 0, 0, n);
        } else {
            for i in 0..n {
                self.ids[self.first[i] as usize..self.first[i + 1] as usize].sort_unstable();
            }
        }
        self.dedup_sorted();
        if self.ids.len() > u32::MAX as usize {
            self.clear();
            return Err(too_many());
        }
        Ok(())
    }

    /// Drops repeated ids from every (sorted) list, compacting in place.
    fn dedup_sorted(&mut self) {
        let mut w = 0usize;
        let mut start = 0usize;
        for i in 0..self.len() {
            let end = self.first[i + 1] as usize;
            let head = w;
            for r in start..end {
                let j = self.ids[r];
                if w == head || self.ids[w - 1] != j {
                    self.ids[w] = j;
                    w += 1;
                }
            }
            start = end;
            self.first[i + 1] = w as u32;
        }
        self.ids.truncate(w);
    }
}

/// Sorts the lists of particles `lo..hi` (`ids` starting at list `lo`'s offset `base`),
/// halving the range with `rayon::join` down to [`CHUNK`] particles.
fn sort_lists_parallel(first: &[u32], ids: &mut [u32], base: usize, lo: usize, hi: usize) {
    if hi - lo <= CHUNK {
        for i in lo..hi {
            ids[first[i] as usize - base..first[i + 1] as usize - base].sort_unstable();
        }
        return;
    }
    let mid = lo + (hi - lo) / 2;
    let cut = first[mid] as usize;
    let (left, right) = ids.split_at_mut(cut - base);
    rayon::join(
        || sort_lists_parallel(first, left, base, lo, mid),
        || sort_lists_parallel(first, right, cut, mid, hi),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_become_sorted_unique_upper_lists_on_any_split() {
        // 600 particles, pairs (i, j) with j - i in {1, 7, 300} emitted in scrambled order,
        // some twice, split over a varying number of tasks.
        let n = 600usize;
        let mut pairs = Vec::new();
        for i in 0..n {
            for s in [300usize, 1, 7] {
                if i + s < n {
                    pairs.push((i as u32, (i + s) as u32));
                    if (i * s) % 5 == 0 {
                        pairs.push((i as u32, (i + s) as u32));
                    }
                }
            }
        }
        pairs.reverse();
        let mut want = Neighbours::new();
        want.fill_serial(n, |i, buf| {
            for s in [1usize, 7, 300] {
                if i + s < n {
                    buf.push((i + s) as u32);
                }
            }
        })
        .unwrap();
        let mut got = Neighbours::new();
        for tasks in [1usize, 3, 8] {
            let per = pairs.len().div_ceil(tasks);
            let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
            pool.install(|| {
                got.fill_pairs_parallel(n, tasks, |t, buf| {
                    for &(i, j) in pairs.iter().skip(t * per).take(per) {
                        buf.extend([i, j]);
                    }
                })
            })
            .unwrap();
            assert_eq!(got, want, "{tasks} tasks");
        }
        got.fill_pairs_serial(n, |buf| pairs.iter().for_each(|&(i, j)| buf.extend([i, j])))
            .unwrap();
        assert_eq!(got, want);
        got.fill_pairs_serial(5, |_| {}).unwrap();
        assert_eq!((got.len(), got.total()), (5, 0));
    }
}
