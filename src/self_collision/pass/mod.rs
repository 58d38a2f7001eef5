//! The substep pass over the step's pair list (the method is described in
//! [`crate::self_collision`]): the pairs in contact are found eight at a time, in parallel over
//! fixed chunks of the list, and their contacts computed once for both particles, eight pairs
//! at a time ([`PairCtx::pair_contacts`]); the contacts are then added on one thread, in list
//! order, to both particles' records of sums, and the velocity-correction kernel
//! ([`crate::self_collision::response::apply_runs`]) runs on the blocks of [`LANES`] particles
//! that received one, reading their records and zeroing them. On one thread each chunk's
//! contacts are added as soon as they are found, while they are still in cache.
//!
//! The list is ordered by `i` then `j`, so every particle receives its contacts in ascending
//! partner order, as a loop over its own sorted list would; the chunks are fixed, so nothing
//! depends on the thread count. The sums live in per-particle arrays that are zero outside
//! the blocks the last pass touched: a pass writes whole blocks (a run of each of the eleven
//! arrays), those it touches and, back to zero, those of the last pass it does not touch.

pub(crate) mod contact;
pub(crate) mod pairs;
pub(crate) mod sums;

use crate::data::exec::Exec;
use rayon::prelude::*;

use crate::data::lanes::{SharedVec3, Vec3x8, LANES};
use crate::data::particles::{chunk_len, CHUNK};
use crate::model::self_collision::Response;
use crate::self_collision::pass::contact::PairContact;
use crate::self_collision::pass::pairs::{PairCtx, PairList};
use crate::self_collision::pass::sums::{Accumulator, Record, RECORD};
use crate::self_collision::response::{apply_runs, ApplyInput};

/// Pairs one parallel task tests in the pair pass. Small enough that a list of a few thousand
/// pairs makes several tasks: the contacts crowd into some stretches of the list (the lower
/// layers of a pile), and three or four tasks on two threads left one thread most of them.
pub(crate) const PAIR_CHUNK: usize = 1024;

/// Particle blocks one parallel task handles in the correction pass.
pub(crate) const APPLY_BLOCKS: usize = 64;

/// Particles a parallel task copies into the position records. Below it, a parallel step
/// above [`CHUNK`] particles copies them in the two halves of its element-wise passes
/// ([`chunk_len`]), one a thread: copied by one thread, half the predictions came from the
/// other core's cache, which cost the 10 000-particle fold of the self-collision suite about
/// a tenth of its step on two threads.
const XYZW_CHUNK: usize = 16 * 1024;

/// Touched blocks from which the correction runs in parallel. The parallel form walks every
/// block's flag in tasks of [`APPLY_BLOCKS`] and splits the touched ones between threads;
/// below about a thousand touched blocks the serial walk over the touched runs was as fast or
/// faster on every scene of the self-collision suite (the twist and the fold touch about 60 a
/// substep, the pile and the stacked cloths about 400, the heap 3 500).
pub(crate) const APPLY_PARALLEL_BLOCKS: usize = 1024;

/// The correction's settings besides the particle arrays.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ApplyParams {
    pub response: Response,
    pub friction: f32,
    pub h: f32,
    pub r: f32,
}

/// Writes `out[k] = [x, y, z, w]` of particle `start + k` from the positions `p` and inverse
/// masses `w` (zero past the end of `w`); `p` must cover every record. The main loop reads
/// slices cut to its length, so it runs without bounds checks and in lanes (the compiler
/// interleaves the four arrays).
fn copy_records(p: [&[f32]; 3], w: &[f32], start: usize, out: &mut [[f32; 4]]) {
    let m = out.len().min(w.len().saturating_sub(start));
    let (body, tail) = out.split_at_mut(m);
    if m > 0 {
        let r = start..start + m;
        let (x, y, z, w) = (&p[0][r.clone()], &p[1][r.clone()], &p[2][r.clone()], &w[r]);
        for (k, o) in body.iter_mut().enumerate() {
            *o = [x[k], y[k], z[k], w[k]];
        }
    }
    for (k, o) in (start + m..).zip(tail) {
        *o = [p[0][k], p[1][k], p[2][k], 0.0];
    }
}

/// Where the speed clamp's chunks copy the predicted positions (the VcCPBD box centres), from
/// any chunk on any thread ([`ContactPass::prediction_sink`]).
pub(crate) struct PredictionSink {
    pred: SharedVec3,
}

impl PredictionSink {
    /// Copies the predictions `p` of the particles `start..start + len` (one chunk's slices;
    /// `start` and the lengths multiples of [`LANES`]). Concurrent calls must be given
    /// disjoint chunks (the clamp's chunks are).
    pub(crate) fn keep(&self, start: usize, p: [&[f32]; 3]) {
        let len = p[0].len().min(p[1].len()).min(p[2].len());
        for l in (0..len / LANES).map(|b| b * LANES) {
            if start + l + LANES <= self.pred.len() {
                let v = Vec3x8::load(p[0], p[1], p[2], l);
                // SAFETY: in bounds (checked); the run belongs to this chunk alone, and nothing
                // reads the copy while the clamp's chunks write it.
                unsafe { self.pred.store_run(start + l, v) };
            }
        }
    }
}

/// The buffers of the substep pass, kept across steps (no allocation once sized).
#[derive(Clone, Debug, Default)]
pub(crate) struct ContactPass {
    /// Box centres: the predictions after the clamp, when the kernel cannot derive them.
    pred: [Vec<f32>; 3],
    /// Damping rates per particle, padded.
    damping: Vec<f32>,
    /// The predicted positions and inverse masses, one `[x, y, z, w]` record a particle
    /// (whole positions gathered in one load each).
    xyzw: Vec<[f32; 4]>,
    /// Pairs in contact range, one buffer per chunk of the list.
    near: Vec<Vec<(u32, u32)>>,
    /// Their contacts (computed in the parallel part), same layout.
    found: Vec<Vec<Option<PairContact>>>,
    /// Each particle's contact sums (padded to whole blocks), zero outside `touched` between
    /// a pair pass and its correction, and everywhere after the correction.
    acc: Vec<Record>,
    /// The blocks the last pair pass added contacts to, ascending.
    touched: Vec<u32>,
    /// Whether each block is in `touched`.
    hit: Vec<bool>,
    /// Pairs in contact the last pass found (with at least one free particle).
    contacts: usize,
}

impl ContactPass {
    /// Sizes the buffers for `n` particles and copies their damping rates (at each step start).
    pub(crate) fn prepare(&mut self, n: usize, damping: &[f32]) {
        let len = n.div_ceil(LANES) * LANES;
        for v in &mut self.pred {
            v.resize(len, 0.0);
        }
        self.acc.resize(len, [0.0; RECORD]);
        self.hit.resize(len / LANES, false);
        self.damping.clear();
        self.damping.extend_from_slice(&damping[..damping.len().min(len)]);
        self.damping.resize(len, 0.0);
    }

    /// A sink the speed clamp's chunks copy the box centres into.
    pub(crate) fn prediction_sink(&mut self) -> PredictionSink {
        let [x, y, z] = &mut self.pred;
        PredictionSink {
            pred: SharedVec3::new(x, y, z),
        }
    }

    /// The contact sums `[c(3), f(3), n(3), gap, count]` of each particle from the last pair
    /// pass (before its correction), the corrections over the approaching contacts.
    #[cfg(test)]
    pub(crate) fn sums(&self) -> Vec<[f32; 11]> {
        self.acc.iter().map(crate::self_collision::pass::sums::finished).collect()
    }

    /// Number of pairs the last pass found in contact.
    pub(crate) fn contacts(&self) -> usize {
        self.contacts
    }

    /// Number of blocks the last pass wrote contacts to.
    pub(crate) fn touched(&self) -> usize {
        self.touched.len()
    }

    /// The pair pass: the contact sums of every particle from the predicted positions of
    /// `ctx` over the pairs of `list` (see the module docs).
    pub(crate) fn pair_pass(&mut self, ctx: &PairCtx<'_>, list: PairList<'_>, exec: Exec) {
        let simd = exec.simd();
        let chunks = list.len().div_ceil(PAIR_CHUNK);
        if self.near.len() < chunks.max(1) {
            self.near.resize_with(chunks.max(1), Vec::new);
            self.found.resize_with(chunks.max(1), Vec::new);
        }
        let p = ctx.p;
        let n = p[0].len().min(p[1].len()).min(p[2].len());
        if list.len() > 0 {
            // Sized once (not cleared): the copy below overwrites every record.
            self.xyzw.resize(n, [0.0; 4]);
            let w = ctx.w;
            // Up to `XYZW_CHUNK`, the halves of the element-wise passes (see there).
            let chunk = if n > XYZW_CHUNK { XYZW_CHUNK } else { chunk_len(n) };
            let copy = |(c, out): (usize, &mut [[f32; 4]])| copy_records(p, w, c * chunk, out);
            if exec.parallel() && n > CHUNK {
                self.xyzw.par_chunks_mut(chunk).enumerate().for_each(copy);
            } else {
                self.xyzw.chunks_mut(chunk).enumerate().for_each(copy);
            }
        }
        let xyzw = &self.xyzw[..];
        let find = |c: usize, (near, found): (&mut Vec<(u32, u32)>, &mut Vec<Option<PairContact>>)| {
            near.clear();
            ctx.touching(list, c * PAIR_CHUNK..((c + 1) * PAIR_CHUNK).min(list.len()), xyzw, simd, near);
            found.clear();
            ctx.pair_contacts(xyzw, near, simd, found);
        };
        let mut sums = Accumulator::begin(&mut self.acc, &mut self.hit, &self.touched);
        if exec.parallel() && chunks > 1 {
            let bufs = (&mut self.near[..chunks], &mut self.found[..chunks]);
            bufs.into_par_iter().enumerate().for_each(|(c, b)| find(c, b));
            // The contacts are added on this thread, chunk by chunk in list order. Adding them
            // in parallel parts of the particles, each part reading the whole contact list found
            // on the other cores, took more time than this on the suite's pile and heap.
            for (near, found) in self.near[..chunks].iter().zip(&self.found[..chunks]) {
                sums.add(near, found);
            }
        } else {
            // One thread: each chunk's contacts are added as soon as they are found, while
            // they are in cache (the same order as above, so the same sums).
            let (near, found) = (&mut self.near[0], &mut self.found[0]);
            for c in 0..chunks {
                find(c, (&mut *near, &mut *found));
                sums.add(near, found);
            }
        }
        self.contacts = sums.finish(&mut self.touched);
    }

    /// The velocity-correction kernel on the touched blocks of the predicted positions `p`
    /// (padded particle arrays), with start positions `x`, inverse masses `w` and, when given,
    /// the substep's velocities `v` (the box centres are then `x + h v`, else the clamp's
    /// copy); zeroes the records it reads. The kernel leaves particles without contacts as they
    /// are, so the other blocks are skipped. In parallel over fixed groups of [`APPLY_BLOCKS`]
    /// blocks when `exec` is parallel and enough blocks were touched, else the runs of
    /// consecutive touched blocks in one call: the same bits either way.
    pub(crate) fn apply(&mut self, x: [&[f32]; 3], w: &[f32], v: Option<[&[f32]; 3]>, p: [&mut [f32]; 3], ap: ApplyParams, exec: Exec) {
        let simd = exec.simd();
        let [px, py, pz] = p;
        let nb = [px.len(), py.len(), pz.len(), self.acc.len(), self.damping.len()]
            .into_iter()
            .chain(self.pred.iter().map(Vec::len))
            .min()
            .unwrap_or(0)
            / LANES;
        let nb = nb.min(self.hit.len());
        let ContactPass {
            pred,
            damping,
            acc,
            hit,
            touched,
            ..
        } = self;
        let (pred, damping, hit, touched) = (&*pred, &damping[..], &hit[..], &touched[..]);
        // The kernel's input over the particles `g` (sums, box centres and damping rates
        // indexed from `g.start`).
        fn input<'a>(
            x: [&'a [f32]; 3],
            w: &'a [f32],
            v: Option<[&'a [f32]; 3]>,
            (pred, damping, g): (&'a [Vec<f32>; 3], &'a [f32], std::ops::Range<usize>),
            sums: &'a [Record],
            ap: ApplyParams,
        ) -> ApplyInput<'a> {
            ApplyInput {
                start: 0,
                x,
                w,
                v,
                q: [&pred[0][g.clone()], &pred[1][g.clone()], &pred[2][g.clone()]],
                b: &damping[g],
                sums,
                friction: ap.friction,
                h: ap.h,
                r: ap.r,
            }
        }
        let parallel = exec.parallel() && touched.len() >= APPLY_PARALLEL_BLOCKS && rayon::current_num_threads() > 1;
        if parallel {
            let len = APPLY_BLOCKS * LANES;
            let all = ..nb * LANES;
            (
                px[all].par_chunks_mut(len),
                py[all].par_chunks_mut(len),
                pz[all].par_chunks_mut(len),
                acc[all].par_chunks_mut(len),
            )
                .into_par_iter()
                .enumerate()
                .for_each(|(c, (a, b, d, recs))| {
                    let g = c * len..c * len + a.len();
                    let hit = &hit[c * APPLY_BLOCKS..][..a.len() / LANES];
                    // Runs of one block (local to the group's slices).
                    let runs = || (0..hit.len()).filter(|&l| hit[l]);
                    let x = [&x[0][g.clone()], &x[1][g.clone()], &x[2][g.clone()]];
                    let v = v.map(|v| [&v[0][g.clone()], &v[1][g.clone()], &v[2][g.clone()]]);
                    let one = input(x, &w[g.clone()], v, (pred, damping, g), recs, ap);
                    apply_runs(&one, [a, b, d], runs().map(|l| (l, l, 1)), ap.response, simd);
                    for l in runs() {
                        recs[l * LANES..(l + 1) * LANES].fill([0.0; RECORD]);
                    }
                });
        } else {
            let runs = || {
                let mut t = 0;
                std::iter::from_fn(move || {
                    let b = *touched.get(t)? as usize;
                    let mut run = 1;
                    while t + run < touched.len() && touched[t + run] as usize == b + run {
                        run += 1;
                    }
                    t += run;
                    Some((b, b, run))
                })
                .filter(move |&(b, _, run)| b + run <= nb)
            };
            let all = 0..nb * LANES;
            apply_runs(
                &input(x, w, v, (pred, damping, all), acc, ap),
                [px, py, pz],
                runs(),
                ap.response,
                simd,
            );
            for (b, _, run) in runs() {
                acc[b * LANES..(b + run) * LANES].fill([0.0; RECORD]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::copy_records;

    /// Each record holds its particle's position and inverse mass, zero past the end of the
    /// masses, from any start (the parallel chunks') and for any length.
    #[test]
    fn records_hold_positions_and_masses() {
        let n = 21;
        let p: [Vec<f32>; 3] = std::array::from_fn(|a| (0..n).map(|k| (100 * a + k) as f32).collect());
        let w: Vec<f32> = (0..13).map(|k| 0.5 + k as f32).collect();
        let pr = [&p[0][..], &p[1][..], &p[2][..]];
        for start in [0, 5, 13, 17] {
            for len in [0, 1, 4, n - start] {
                let mut out = vec![[f32::NAN; 4]; len];
                copy_records(pr, &w, start, &mut out);
                for (k, o) in (start..).zip(&out) {
                    let mass = w.get(k).copied().unwrap_or(0.0);
                    assert_eq!(*o, [p[0][k], p[1][k], p[2][k], mass], "start {start}, particle {k}");
                }
            }
        }
    }
}
