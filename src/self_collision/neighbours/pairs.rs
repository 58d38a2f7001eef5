//! Neighbour lists assembled from emitted pairs (a cell-centric broadphase finds each pair
//! from whichever side is convenient, then files it under its smaller id).
//!
//! # Method
//! Tasks append pairs `(i, j)`, `i < j`, as two `u32` each, to their own kept buffers (in
//! parallel, a fixed number of tasks, so the split does not depend on the thread count). Then:
//! 1. count the pairs of each `i` (serial over the buffers) and prefix-sum the counts into
//!    `first`;
//! 2. group the smaller ids by partner `j` (a stable counting sort on `j`), then walk the
//!    partners in ascending order, appending each `j` to the lists of its smaller ids (a
//!    counting sort on `i`): every list comes out ascending with no comparison sort (a radix
//!    sort of the pairs, least significant key first);
//! 3. drop repeated ids (adjacent now), the lists being compacted in one serial pass.
//!
//! The two counting sorts cost a fraction of a scatter followed by a comparison sort of every
//! list (a folded cloth emits hundreds of thousands of pairs).
//!
//! Sorting and de-duplicating make the lists canonical: they do not depend on the order the
//! pairs were emitted in, nor on the number of threads, so they equal the lists of any other
//! upper query (each pair once, in the list of its smaller id).
//!
//! The assembly is serial: filing the pairs into ranges of particles assembled in parallel
//! was no faster on two threads (a folded cloth's pairs crowd into a few ranges, and joining
//! the ranges' lists costs what the parallel sorts save).

use crate::self_collision::neighbours::{prefix_sum, too_many, Budget, Meter, Neighbours};
use crate::Result;
use rayon::prelude::*;

impl Neighbours {
    /// Fills upper lists (each pair once, under its smaller id) for `n` particles from pairs:
    /// `f(t, buf, meter)` for each task `t < tasks` (in parallel) appends pairs `i, j`
    /// (`i < j < n`, flattened) to `buf`; a pair may be emitted more than once. The task
    /// counts the pairs it appends on its `meter` as it goes ([`Meter::add`], flushed here when
    /// it returns) and stops when told to: past the lists' limit the fill empties them and
    /// returns an error.
    pub(crate) fn fill_pairs_parallel<F>(&mut self, n: usize, tasks: usize, f: F) -> Result<()>
    where
        F: Fn(usize, &mut Vec<u32>, &mut Meter<'_>) + Sync,
    {
        if self.scratch.len() < tasks {
            self.scratch.resize_with(tasks, Vec::new);
        }
        let budget = Budget::new(self.limit);
        self.scratch[..tasks].par_iter_mut().enumerate().for_each(|(t, buf)| {
            buf.clear();
            if !budget.over() {
                let mut meter = budget.meter();
                f(t, buf, &mut meter);
                meter.flush();
            }
        });
        self.assemble_within(n, tasks, &budget)
    }

    /// Serial twin of [`Neighbours::fill_pairs_parallel`]: one task appends every pair.
    pub(crate) fn fill_pairs_serial<F>(&mut self, n: usize, f: F) -> Result<()>
    where
        F: FnOnce(&mut Vec<u32>, &mut Meter<'_>),
    {
        if self.scratch.is_empty() {
            self.scratch.push(Vec::new());
        }
        self.scratch[0].clear();
        let budget = Budget::new(self.limit);
        let mut meter = budget.meter();
        f(&mut self.scratch[0], &mut meter);
        meter.flush();
        self.assemble_within(n, 1, &budget)
    }

    /// [`Neighbours::assemble`], or the limit's error when the emitting passed it.
    fn assemble_within(&mut self, n: usize, tasks: usize, budget: &Budget) -> Result<()> {
        self.limited = budget.over();
        if self.limited {
            for b in &mut self.scratch[..tasks] {
                b.clear();
            }
            self.clear();
            return Err(too_many(self.limit, n));
        }
        self.assemble(n, tasks)
    }

    /// Counts and places the pairs of the first `tasks` buffers (two stable counting sorts,
    /// by `j` then by `i`, so every list comes out ascending), then drops repeats.
    fn assemble(&mut self, n: usize, tasks: usize) -> Result<()> {
        let bufs = &self.scratch[..tasks];
        self.first.clear();
        self.first.resize(n + 1, 0);
        self.by_j.clear();
        self.by_j.resize(n + 1, 0);
        for b in bufs {
            for p in b.chunks_exact(2) {
                self.first[p[0] as usize + 1] += 1;
                self.by_j[p[1] as usize + 1] += 1;
            }
        }
        let total = match prefix_sum(&mut self.first) {
            Ok(t) => t,
            Err(e) => {
                self.clear();
                return Err(e);
            }
        };
        self.ids.clear();
        if total == 0 {
            return Ok(());
        }
        // The same total, so no overflow here.
        prefix_sum(&mut self.by_j)?;
        // Pass 1: the smaller ids grouped by partner `j` (`by_j[j]` is the cursor of group `j`;
        // afterwards it holds the group's end, the start of group `j + 1`).
        self.order.clear();
        self.order.resize(total, 0);
        for b in bufs {
            for p in b.chunks_exact(2) {
                let c = &mut self.by_j[p[1] as usize];
                self.order[*c as usize] = p[0];
                *c += 1;
            }
        }
        // Pass 2: partners in ascending order into the lists (`first[i]` the cursor of list
        // `i`; afterwards shifted back by one to the offsets).
        self.ids.resize(total, 0);
        let mut k = 0usize;
        for j in 0..n {
            let end = self.by_j[j] as usize;
            for &i in &self.order[k..end] {
                let c = &mut self.first[i as usize];
                self.ids[*c as usize] = j as u32;
                *c += 1;
            }
            k = end;
        }
        self.first.copy_within(0..n, 1);
        self.first[0] = 0;
        self.dedup_sorted();
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
                got.fill_pairs_parallel(n, tasks, |t, buf, _| {
                    for &(i, j) in pairs.iter().skip(t * per).take(per) {
                        buf.extend([i, j]);
                    }
                })
            })
            .unwrap();
            assert_eq!(got, want, "{tasks} tasks");
        }
        got.fill_pairs_serial(n, |buf, _| pairs.iter().for_each(|&(i, j)| buf.extend([i, j])))
            .unwrap();
        assert_eq!(got, want);
        got.fill_pairs_serial(5, |_, _| {}).unwrap();
        assert_eq!((got.len(), got.total()), (5, 0));
    }
}
