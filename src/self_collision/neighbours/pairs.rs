//! Neighbour lists assembled from emitted pairs (a cell-centric broadphase finds each pair
//! from whichever side is convenient, then files it under its smaller id).
//!
//! # Method
//! Tasks append pairs `(i, j)`, `i < j`, as two `u32` each, to their own kept buffers (in
//! parallel, a fixed number of tasks, so the split does not depend on the thread count). Then
//! two stable counting sorts, least significant key first, make every list ascending with no
//! comparison sort:
//! 1. by partner `j`: the smaller ids are grouped by partner;
//! 2. by owner `i`: the partners are walked in ascending order, each `j` appended to the
//!    lists of its smaller ids. A repeated pair (emitted twice: hash collisions, particles on
//!    a cell face) falls in one group; it is dropped when the second sort counts the lists, so
//!    the lists come out without repeats and no pass compacts them.
//!
//! Sorting and dropping repeats make the lists canonical: they do not depend on the order the
//! pairs were emitted in, nor on the number of threads, so they equal the lists of any other
//! upper query (each pair once, in the list of its smaller id).
//!
//! # Parts
//! From [`PARALLEL_PAIRS`] pairs each sort runs in parts, one a thread: the first over equal
//! runs of the emitted pairs, the second over shares of the partners holding about as many
//! pairs each. A part counts its keys in counts of its own (a particle each); the counts are
//! prefix-summed key by key and part by part, so each part writes its keys to places no other
//! part writes (a parallel radix pass). The output is the same whatever the number of parts,
//! so the parts may follow the threads.

use crate::self_collision::neighbours::{too_many, Budget, Meter, Neighbours, MAX_ENTRIES};
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
        self.assemble_within(n, tasks, &budget, true)
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
        self.assemble_within(n, 1, &budget, false)
    }

    /// [`Neighbours::assemble`], or the limit's error when the emitting passed it.
    fn assemble_within(&mut self, n: usize, tasks: usize, budget: &Budget, parallel: bool) -> Result<()> {
        self.limited = budget.over();
        if self.limited {
            for b in &mut self.scratch[..tasks] {
                b.clear();
            }
            self.clear();
            return Err(too_many(self.limit, n));
        }
        self.assemble(n, tasks, parallel)
    }

    /// Counts and places the pairs of the first `tasks` buffers (two stable counting sorts,
    /// by `j` then by `i`, so every list comes out ascending), then drops repeats; over
    /// parts on their own threads when `parallel` and the pairs are many (see the module
    /// docs).
    fn assemble(&mut self, n: usize, tasks: usize, parallel: bool) -> Result<()> {
        let bufs = &self.scratch[..tasks];
        self.starts.clear();
        self.starts.push(0);
        let mut m = 0usize;
        for b in bufs {
            m += b.len() / 2;
            self.starts.push(m);
        }
        self.first.clear();
        self.first.resize(n + 1, 0);
        self.ids.clear();
        if m > MAX_ENTRIES {
            self.clear();
            return Err(too_many(MAX_ENTRIES, n));
        }
        if m == 0 || n == 0 {
            return Ok(());
        }
        let parts = if parallel && m >= PARALLEL_PAIRS {
            rayon::current_num_threads().clamp(1, MAX_PARTS)
        } else {
            1
        };
        let src = PairSource {
            bufs,
            starts: &self.starts,
        };
        // Part `p` reads the pairs `range(p)`.
        let range = |p: usize| p * m / parts..(p + 1) * m / parts;
        let counts = &mut self.counts;
        counts.clear();
        counts.resize(parts * n, 0);
        // 1. Each part counts its partners.
        each_part(parts, counts, n, |p, c| src.each(range(p), |_, j| c[j as usize] += 1));
        // 2. Group `j` starts at `group[j]`; part `p` places its smaller ids of partner `j`
        //    from `counts[p n + j]` on.
        self.by_j.clear();
        self.by_j.resize(n + 1, 0);
        cursors(counts, n, &mut self.by_j);
        // 3. The smaller ids grouped by partner, each part its own places.
        self.order.clear();
        self.order.resize(m, 0);
        let out = Out::new(&mut self.order);
        // SAFETY: the cursors of step 2 give each (part, partner) its own span of places, as
        // long as that part's count of the partner; the part writes each place once.
        each_part(parts, counts, n, |p, c| {
            src.each(range(p), |i, j| {
                let k = &mut c[j as usize];
                unsafe { out.put(*k as usize, i) };
                *k += 1;
            })
        });
        // 4. The partners are cut into shares of about as many pairs; each share counts its
        //    smaller ids, once each: a repeat of `(i, j)` (in the same group, `mark[i] == j`)
        //    is overwritten with `NONE`.
        let group = &self.by_j[..];
        let mut cut = [n; MAX_PARTS + 1];
        for (s, c) in cut.iter_mut().enumerate().take(parts) {
            *c = group.partition_point(|&g| (g as usize) < s * m / parts).min(n);
        }
        cut[0] = 0;
        let mut shares: [&mut [u32]; MAX_PARTS] = Default::default();
        let mut rest = &mut self.order[..];
        for (s, share) in shares.iter_mut().enumerate().take(parts) {
            let (mine, tail) = rest.split_at_mut((group[cut[s + 1]] - group[cut[s]]) as usize);
            (*share, rest) = (mine, tail);
        }
        counts.fill(0);
        self.marks.clear();
        self.marks.resize(parts * n, NONE);
        let count = |s: usize, c: &mut [u32], mark: &mut [u32], order: &mut [u32]| {
            let base = group[cut[s]];
            for j in cut[s]..cut[s + 1] {
                for i in &mut order[(group[j] - base) as usize..(group[j + 1] - base) as usize] {
                    let at = *i as usize;
                    if mark[at] == j as u32 {
                        *i = NONE;
                    } else {
                        mark[at] = j as u32;
                        c[at] += 1;
                    }
                }
            }
        };
        if parts > 1 {
            counts
                .par_chunks_mut(n)
                .zip(self.marks.par_chunks_mut(n))
                .zip(shares[..parts].par_iter_mut())
                .enumerate()
                .for_each(|(s, ((c, mark), order))| count(s, c, mark, order));
        } else {
            count(0, counts, &mut self.marks, shares[0]);
        }
        // 5. List `i` starts at `first[i]`; share `s` places its partners of `i` from
        //    `counts[s n + i]` on.
        cursors(counts, n, &mut self.first);
        // 6. The partners in ascending order into the lists, each share its own places.
        self.ids.resize(self.first[n] as usize, 0);
        let out = Out::new(&mut self.ids);
        let order = &self.order[..];
        // SAFETY: as in step 3, with the cursors of step 5.
        each_part(parts, counts, n, |s, c| {
            for j in cut[s]..cut[s + 1] {
                for &i in &order[group[j] as usize..group[j + 1] as usize] {
                    if i != NONE {
                        let k = &mut c[i as usize];
                        unsafe { out.put(*k as usize, j as u32) };
                        *k += 1;
                    }
                }
            }
        });
        Ok(())
    }
}

/// An id no particle has: a mark not yet set, a repeat dropped.
const NONE: u32 = u32::MAX;

/// Pairs from which the assembly runs in parts (fewer cost more to fork than the parts save).
const PARALLEL_PAIRS: usize = 1 << 15;

/// Most parts of the assembly (one a thread; each holds a count a particle).
const MAX_PARTS: usize = 8;

/// Turns the parts' counts (`n` keys a part, part after part) into cursors: key `k` starts at
/// `starts[k]` (`starts[n]` the total), and part `p` places its keys `k` from
/// `counts[p n + k]` on, after the earlier parts' keys `k`.
fn cursors(counts: &mut [u32], n: usize, starts: &mut [u32]) {
    let parts = counts.len() / n;
    let mut acc = 0u32;
    for k in 0..n {
        starts[k] = acc;
        for p in 0..parts {
            let c = &mut counts[p * n + k];
            (*c, acc) = (acc, acc + *c);
        }
    }
    starts[n] = acc;
}

/// Runs `f(p, counts of part p)` for each part: on their own threads when there are several,
/// else on this thread without entering rayon.
fn each_part(parts: usize, counts: &mut [u32], n: usize, f: impl Fn(usize, &mut [u32]) + Sync) {
    if parts > 1 {
        counts.par_chunks_mut(n).enumerate().for_each(|(p, c)| f(p, c));
    } else {
        f(0, counts);
    }
}

/// The flattened pairs `[i, j, i, j, ...]` of several buffers, read as one sequence.
struct PairSource<'a> {
    bufs: &'a [Vec<u32>],
    /// Pairs before each buffer (one more entry than buffers).
    starts: &'a [usize],
}

impl PairSource<'_> {
    /// Calls `f(i, j)` for the pairs `range` of the sequence, in order.
    #[inline(always)]
    fn each(&self, range: std::ops::Range<usize>, mut f: impl FnMut(u32, u32)) {
        let b0 = self.starts.partition_point(|&s| s <= range.start).saturating_sub(1);
        for (b, buf) in self.bufs.iter().enumerate().skip(b0) {
            let s = self.starts[b];
            if s >= range.end {
                break;
            }
            let (from, to) = (range.start.max(s) - s, range.end.min(self.starts[b + 1]) - s);
            for p in buf[2 * from..2 * to].chunks_exact(2) {
                f(p[0], p[1]);
            }
        }
    }
}

/// A raw view of an id array that the parts of a sort write at disjoint places.
#[derive(Clone, Copy)]
struct Out {
    ptr: *mut u32,
    len: usize,
}

// SAFETY: a pointer and a length; `put` is unsafe and its callers write disjoint places.
unsafe impl Send for Out {}
// SAFETY: as above.
unsafe impl Sync for Out {}

impl Out {
    fn new(v: &mut [u32]) -> Self {
        Out {
            ptr: v.as_mut_ptr(),
            len: v.len(),
        }
    }

    /// Writes `v` at `at`.
    ///
    /// # Safety
    /// Nothing else reads or writes place `at` while the view is in use.
    #[inline(always)]
    unsafe fn put(self, at: usize, v: u32) {
        assert!(at < self.len);
        // SAFETY: in bounds (checked) and exclusive by the caller's guarantee.
        unsafe { self.ptr.add(at).write(v) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_become_sorted_unique_upper_lists_on_any_split() {
        // Pairs (i, j) with j - i in a few strides emitted in scrambled order, some twice,
        // split over a varying number of tasks and threads; the second size has enough pairs
        // for the assembly to run in parts.
        for (n, strides) in [(600usize, vec![300usize, 1, 7]), (20_000, vec![4001, 300, 1, 7])] {
            let mut pairs = Vec::new();
            for i in 0..n {
                for &s in &strides {
                    if i + s < n {
                        pairs.push((i as u32, (i + s) as u32));
                        if (i * s) % 5 == 0 {
                            pairs.push((i as u32, (i + s) as u32));
                        }
                    }
                }
            }
            pairs.reverse();
            assert_eq!(pairs.len() >= PARALLEL_PAIRS, n > 600);
            let mut want = Neighbours::new();
            let mut ascending = strides.clone();
            ascending.sort_unstable();
            want.fill_serial(n, |i, buf| {
                buf.extend(ascending.iter().filter(|&&s| i + s < n).map(|&s| (i + s) as u32))
            })
            .unwrap();
            let mut got = Neighbours::new();
            for (tasks, threads) in [(1usize, 2usize), (3, 2), (8, 2), (8, 3), (5, 1)] {
                let per = pairs.len().div_ceil(tasks);
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| {
                    got.fill_pairs_parallel(n, tasks, |t, buf, _| {
                        for &(i, j) in pairs.iter().skip(t * per).take(per) {
                            buf.extend([i, j]);
                        }
                    })
                })
                .unwrap();
                assert_eq!(got, want, "{n} particles, {tasks} tasks, {threads} threads");
            }
            got.fill_pairs_serial(n, |buf, _| pairs.iter().for_each(|&(i, j)| buf.extend([i, j])))
                .unwrap();
            assert_eq!(got, want);
        }
        let mut got = Neighbours::new();
        got.fill_pairs_serial(5, |_, _| {}).unwrap();
        assert_eq!((got.len(), got.total()), (5, 0));
    }
}
