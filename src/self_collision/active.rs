//! The self-collision work of one step, restricted to the particles that can collide (the
//! method is described in [`crate::self_collision`]).
//!
//! The broadphase leaves, per particle, the *candidate* list: partners within the reach that
//! are not the particle's own rest neighbours (kept across steps, see
//! [`crate::self_collision::verlet`]). Before the fold most lists are empty. The substeps then touch
//! only the **active blocks**: the groups of [`LANES`] consecutive particles (`8 b .. 8 b + 8`)
//! holding at least one particle with a non-empty list. The contact sums, the predicted
//! positions (VcCPBD box centres) and the damping rates are kept in compact arrays, block
//! after block, so the velocity-correction kernel [`crate::self_collision::response::apply`] runs unchanged
//! on each block that received a contact (`start` is the block's compact offset, `x`, `w`,
//! `p` the block's slices of the particle arrays).
//!
//! Every block is computed independently (a Jacobi pass: a particle writes only its own
//! sums and position), so the result is the same serially, in parallel and on any number of
//! threads; parallel work is split into fixed groups of blocks.
//!
//! Per substep the pass computes each contact once for both of its particles
//! ([`crate::self_collision::pairs::PairCtx::pair_contact`], the same bits as one computation per end;
//! the compact-step test holds it to the per-particle form). The contacts are computed in the
//! parallel candidate search, so the serial part only adds them into the sums. Only the sums
//! of particles that received a contact are written, and a particle's sums are zeroed only
//! when its contacts end (most contacts last several substeps; a folded cloth has a few
//! hundred contacts spread over many blocks, and zeroing whole blocks would cost more than
//! the contacts). The correction runs on the touched blocks, consecutive ones in one kernel
//! call.
//!
//! The contacts keep their bounds checks: the scattered loads, not the checks, set the pace.

use crate::data::exec::Exec;
use rayon::prelude::*;

use crate::data::lanes::{SharedVec3, Vec3x8, LANES};
use crate::model::self_collision::Response;
use crate::self_collision::neighbours::Neighbours;
use crate::self_collision::pairs::{PairContact, PairCtx};
use crate::self_collision::response::{apply_runs, ApplyInput, ContactSums};

/// Near pairs one parallel task handles in the pair pass's candidate search.
const PAIR_CHUNK: usize = 2048;

/// Particle blocks one parallel task handles in the correction pass at least.
pub(crate) const APPLY_BLOCKS: usize = 64;

/// Touched blocks from which the correction runs in parallel (see [`ActiveSet::apply`]).
pub(crate) const APPLY_PARALLEL_BLOCKS: usize = 17;

/// Marks a block that is not active.
const INACTIVE: u32 = u32::MAX;

/// Inputs of [`ActiveSet::apply`] besides the particle arrays.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ApplyParams {
    pub response: Response,
    pub friction: f32,
    pub h: f32,
    pub r: f32,
}

/// Where the predicted positions of the active blocks are copied to (the box centres of the
/// correction), from any chunk of whole blocks, on any thread ([`ActiveSet::prediction_sink`]).
///
/// Each chunk of the clamp's parallel pass copies its own blocks (a serial copy after it cost
/// about as much as the clamp).
pub(crate) struct PredictionSink<'a> {
    slot_of_block: &'a [u32],
    /// The compact predictions, written at disjoint slots only (see [`PredictionSink::keep`]).
    pred: SharedVec3,
}

impl PredictionSink<'_> {
    /// Copies the active blocks among the particles `start..start + len` of the predicted
    /// positions `p` (one chunk's slices; `start` and the lengths multiples of [`LANES`]).
    ///
    /// Chunks given to concurrent calls must not overlap (the clamp's chunks do not).
    pub(crate) fn keep(&self, start: usize, p: [&[f32]; 3]) {
        let len = p[0].len().min(p[1].len()).min(p[2].len());
        let first = start / LANES;
        for (k, b) in (first..self.slot_of_block.len()).enumerate().take(len / LANES) {
            let slot = self.slot_of_block[b];
            if slot == INACTIVE {
                continue;
            }
            let l = k * LANES;
            let v = Vec3x8::load(p[0], p[1], p[2], l);
            let dst = slot as usize * LANES;
            if dst + LANES <= self.pred.len() {
                // SAFETY: in bounds (checked); slot `slot` belongs to particle block `b` alone
                // (the numbering of `rebuild` is one-to-one), block `b` to this chunk alone,
                // and nothing reads the predictions while the clamp's chunks write them.
                unsafe { self.pred.store_run(dst, v) };
            }
        }
    }
}

/// The active blocks of a step and their compact per-particle data.
#[derive(Clone, Debug, Default)]
pub(crate) struct ActiveSet {
    /// Active block indices, ascending.
    pub(crate) blocks: Vec<u32>,
    /// Compact slot of each block (`INACTIVE` when not active).
    slot_of_block: Vec<u32>,
    /// Contact sums, compact.
    pub(crate) sums: ContactSums,
    /// Predicted positions after the clamp (box centres), compact.
    pred: [Vec<f32>; 3],
    /// Damping rates, compact.
    damping: Vec<f32>,
    /// Candidate pairs of the pair pass, one buffer per chunk (kept between substeps).
    candidates: Vec<Vec<(u32, u32)>>,
    /// The contact of each candidate pair (computed in the parallel part), same layout.
    contacts: Vec<Vec<Option<PairContact>>>,
    /// Per-slot sums and approaching counts while the contacts are added (zero between
    /// passes).
    acc: Vec<([f32; 11], f32)>,
    /// Compact blocks the last pair pass wrote contacts to, ascending.
    touched: Vec<u32>,
    /// Whether each compact block is in `touched`.
    hit: Vec<bool>,
    /// Compact slots (particles) the last pair pass added a contact to, in first-contact
    /// order: the only non-zero entries of `sums`.
    written: Vec<u32>,
    /// `written` of the pass before (zeroed unless written again).
    last_written: Vec<u32>,
}

impl ActiveSet {
    /// Recomputes the active blocks from the compact `lists` of `n` particles (each pair once,
    /// in the list of its smaller id: both ends' blocks are active) and gathers their damping
    /// rates. Allocation-free once the buffers have reached their working size.
    pub(crate) fn rebuild(&mut self, lists: &Neighbours, n: usize, damping: &[f32]) {
        let nb = n.div_ceil(LANES);
        self.slot_of_block.clear();
        self.slot_of_block.resize(nb, INACTIVE);
        // Mark (any value but INACTIVE), then number the marked blocks in order.
        for i in 0..n.min(lists.len()) {
            let list = lists.of(i);
            if !list.is_empty() {
                self.slot_of_block[i / LANES] = 0;
            }
            for &j in list {
                if let Some(b) = self.slot_of_block.get_mut(j as usize / LANES) {
                    *b = 0;
                }
            }
        }
        self.number_marked(damping);
    }

    /// Makes every block of `n` particles active (a step without candidate lists, where any
    /// particle may meet any other) and gathers their damping rates.
    pub(crate) fn rebuild_all(&mut self, n: usize, damping: &[f32]) {
        self.slot_of_block.clear();
        self.slot_of_block.resize(n.div_ceil(LANES), 0);
        self.number_marked(damping);
    }

    /// Numbers the marked blocks of `slot_of_block` in order and sizes the compact arrays.
    ///
    /// Between pair passes the compact arrays are zero but for the sums of the slots the last
    /// pass wrote (`written`; `acc` is zeroed as it is read, `hit` is false but for
    /// `touched`): those are zeroed, and the arrays are resized, not cleared (a falling step
    /// renumbers ~700 blocks: clearing every array cost ~0.6 MB of stores a step). The box
    /// centres and damping rates are written before they are read (the clamp's copy,
    /// [`ActiveSet::refresh_damping`]).
    fn number_marked(&mut self, damping: &[f32]) {
        let nb = self.slot_of_block.len();
        self.blocks.clear();
        for b in 0..nb {
            if self.slot_of_block[b] != INACTIVE {
                self.slot_of_block[b] = self.blocks.len() as u32;
                self.blocks.push(b as u32);
            }
        }
        let len = self.blocks.len() * LANES;
        let mut rows = self.sums.rows();
        for &k in self.written.iter().chain(&self.last_written) {
            rows.set(k as usize, &[0.0; 11]);
        }
        let s = &mut self.sums;
        for v in s.c.iter_mut().chain(s.f.iter_mut()).chain(s.n.iter_mut()) {
            v.resize(len, 0.0);
        }
        s.gap.resize(len, 0.0);
        s.count.resize(len, 0.0);
        for v in &mut self.pred {
            v.resize(len, 0.0);
        }
        self.acc.resize(len, ([0.0; 11], 0.0));
        self.touched.clear();
        self.written.clear();
        self.last_written.clear();
        self.hit.clear();
        self.hit.resize(self.blocks.len(), false);
        self.damping.resize(len, 0.0);
        self.refresh_damping(damping);
    }

    /// Gathers the damping rates of the active blocks again (a step that keeps the blocks).
    pub(crate) fn refresh_damping(&mut self, damping: &[f32]) {
        for (k, &b) in self.blocks.iter().enumerate() {
            for l in 0..LANES {
                let i = b as usize * LANES + l;
                self.damping[k * LANES + l] = damping.get(i).copied().unwrap_or(0.0);
            }
        }
    }

    /// Number of active blocks.
    pub(crate) fn len(&self) -> usize {
        self.blocks.len()
    }

    /// Copies the predicted positions of the active blocks (after the speed clamp; `p` the
    /// full particle arrays, padded to the lane width): the serial form of the clamp's copy
    /// ([`ActiveSet::prediction_sink`]), used by the tests.
    #[cfg(test)]
    pub(crate) fn keep_predictions(&mut self, p: [&[f32]; 3]) {
        self.prediction_sink().keep(0, p);
    }

    /// A sink the speed clamp's parallel chunks copy the predicted positions of their active
    /// blocks into ([`PredictionSink::keep`]), inside the clamp's own parallel region.
    pub(crate) fn prediction_sink(&mut self) -> PredictionSink<'_> {
        let [x, y, z] = &mut self.pred;
        PredictionSink {
            slot_of_block: &self.slot_of_block,
            pred: SharedVec3::new(x, y, z),
        }
    }

    /// The pair pass over the near pairs `near` (see [`crate::self_collision::near`]): the contact sums
    /// of every particle of the active blocks (zero for particles with no contact).
    ///
    /// Each unordered pair is tested once: the near pairs `(i, j)`, `i < j`, closer than `d`
    /// (with a margin) are found in parallel over fixed chunks of the near list, each chunk
    /// into its own buffer, with their exact contacts (computed in the same task); then,
    /// serially in buffer order (`i` ascending, then `j`), each candidate adds its contact to
    /// both particles' sums. A particle thus receives its
    /// contacts in ascending partner order, as the per-particle loop over its sorted list would
    /// (the tests hold the two equal bit for bit); nothing depends on the thread count. Only
    /// the particles that received a contact are written (their blocks are the *touched*
    /// blocks the correction runs on); those of the last pass are zeroed first, so every
    /// other sum stays zero.
    pub(crate) fn pair_pass(&mut self, ctx: &PairCtx<'_>, near: &[(u32, u32)], exec: Exec) {
        let (parallel, simd) = (exec.parallel(), exec.simd());
        let chunks = near.len().div_ceil(PAIR_CHUNK);
        if self.candidates.len() < chunks {
            self.candidates.resize_with(chunks, Vec::new);
        }
        let find = |c: usize, (buf, found): (&mut Vec<(u32, u32)>, &mut Vec<Option<PairContact>>)| {
            buf.clear();
            ctx.near_candidates(&near[c * PAIR_CHUNK..((c + 1) * PAIR_CHUNK).min(near.len())], simd, buf);
            found.clear();
            found.extend(buf.iter().map(|&(i, j)| ctx.pair_contact(i as usize, j as usize)));
        };
        if self.contacts.len() < chunks {
            self.contacts.resize_with(chunks, Vec::new);
        }
        let bufs = (&mut self.candidates[..chunks], &mut self.contacts[..chunks]);
        if parallel && chunks > 1 {
            bufs.into_par_iter().enumerate().for_each(|(c, b)| find(c, b));
        } else {
            bufs.0.iter_mut().zip(bufs.1.iter_mut()).enumerate().for_each(|(c, b)| find(c, b));
        }
        // Only the particles with a contact are written, not whole blocks (a folded cloth has
        // a few hundred contacts a substep spread over ~170 blocks: zeroing and storing the
        // whole blocks' eleven sums cost four times the contacts themselves). `acc` is zero
        // outside this pass's contacts; the last pass's particles are zeroed below unless
        // this pass writes them again (most contacts last several substeps).
        for &k in &self.touched {
            self.hit[k as usize] = false;
        }
        self.touched.clear();
        std::mem::swap(&mut self.written, &mut self.last_written);
        self.written.clear();
        let slot_of_block = &self.slot_of_block;
        let slot = |i: usize| match slot_of_block.get(i / LANES) {
            Some(&k) if k != INACTIVE => Some(k as usize * LANES + i % LANES),
            _ => None,
        };
        let found = self.candidates[..chunks]
            .iter()
            .flatten()
            .zip(self.contacts[..chunks].iter().flatten());
        for (&(i, j), contact) in found {
            let (i, j) = (i as usize, j as usize);
            for (side, a) in [(0, i), (1, j)] {
                if let Some(k) = slot(a) {
                    if let Some(c) = contact {
                        let (out, approaching) = &mut self.acc[k];
                        let first = out[10] == 0.0;
                        if c.add_to(side, out, approaching) && first {
                            self.written.push(k as u32);
                        }
                    }
                    let blk = k / LANES;
                    if !self.hit[blk] {
                        self.hit[blk] = true;
                        self.touched.push(blk as u32);
                    }
                }
            }
        }
        self.touched.sort_unstable();
        let mut s = self.sums.rows();
        for &k in &self.last_written {
            if self.acc[k as usize].0[10] == 0.0 {
                s.set(k as usize, &[0.0; 11]);
            }
        }
        for &k in &self.written {
            let (out, approaching) = &mut self.acc[k as usize];
            PairCtx::finish(out, *approaching);
            s.set(k as usize, out);
            self.acc[k as usize] = ([0.0; 11], 0.0);
        }
    }

    /// Number of blocks the last pair pass wrote contacts to.
    pub(crate) fn touched(&self) -> usize {
        self.touched.len()
    }

    /// The velocity-correction kernel on the touched blocks of the predicted positions `p`
    /// (full particle arrays, padded to the lane width), with start positions `x` and inverse
    /// masses `w`. The kernel leaves a particle without contacts as it is, so the other blocks
    /// are skipped. Parallel over fixed groups of [`APPLY_BLOCKS`] blocks when `parallel`, each
    /// group's touched blocks in one kernel call; serially, the runs of consecutive touched
    /// blocks in one call; the same bits either way. The caller asks for the parallel path
    /// from [`APPLY_PARALLEL_BLOCKS`] touched blocks and more than one worker (a folded
    /// 100x100 cloth touches ~170 a substep).
    ///
    /// One call takes all the runs, so the kernel sets up its constants once. With one worker
    /// the serial path is taken. A higher parallel threshold made this stage cheaper but not
    /// the step: an idle second worker went to sleep and the next parallel pass paid to wake
    /// it (module `keep_awake` now keeps the workers polling during a step).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn apply(&self, x: [&[f32]; 3], w: &[f32], v: Option<[&[f32]; 3]>, p: [&mut [f32]; 3], ap: ApplyParams, exec: Exec) {
        let (parallel, simd) = (exec.parallel(), exec.simd());
        let inp = |x, w, v| self.apply_input(x, w, v, ap);
        let [px, py, pz] = p;
        if parallel {
            // Fixed groups of APPLY_BLOCKS particle blocks; each group's touched blocks as
            // runs of one (group-local particle block, compact block).
            let nb = self.slot_of_block.len();
            let len = APPLY_BLOCKS * LANES;
            (
                px[..nb * LANES].par_chunks_mut(len),
                py[..nb * LANES].par_chunks_mut(len),
                pz[..nb * LANES].par_chunks_mut(len),
            )
                .into_par_iter()
                .enumerate()
                .for_each(|(c, (a, b, d))| {
                    let g = c * len..c * len + a.len();
                    let b0 = c * APPLY_BLOCKS;
                    let runs = (0..a.len() / LANES).filter_map(|l| {
                        let k = self.slot_of_block[b0 + l];
                        (k != INACTIVE && self.hit[k as usize]).then_some((k as usize, l, 1))
                    });
                    let x = [&x[0][g.clone()], &x[1][g.clone()], &x[2][g.clone()]];
                    let v = v.map(|v| [&v[0][g.clone()], &v[1][g.clone()], &v[2][g.clone()]]);
                    apply_runs(&inp(x, &w[g], v), [a, b, d], runs, ap.response, simd);
                });
        } else {
            // Runs of touched blocks consecutive both in the compact arrays and in the
            // particle arrays (element-wise: the same bits).
            let mut t = 0;
            let runs = std::iter::from_fn(|| {
                let k = *self.touched.get(t)? as usize;
                let b = self.blocks[k] as usize;
                let mut run = 1;
                while t + run < self.touched.len() && self.touched[t + run] as usize == k + run && self.blocks[k + run] as usize == b + run
                {
                    run += 1;
                }
                t += run;
                Some((k, b, run))
            });
            apply_runs(&inp(x, w, v), [px, py, pz], runs, ap.response, simd);
        }
    }

    /// The kernel's input over the particle arrays `x`, `w` (or a range of them).
    fn apply_input<'a>(&'a self, x: [&'a [f32]; 3], w: &'a [f32], v: Option<[&'a [f32]; 3]>, ap: ApplyParams) -> ApplyInput<'a> {
        ApplyInput {
            start: 0,
            x,
            w,
            v,
            q: [&self.pred[0], &self.pred[1], &self.pred[2]],
            b: &self.damping,
            sums: &self.sums,
            friction: ap.friction,
            h: ap.h,
            r: ap.r,
        }
    }
}
