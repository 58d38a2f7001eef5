//! The self-collision work of one step, restricted to the particles that can collide (the
//! method is described in [`super::self_collision`]).
//!
//! The broadphase runs once per step and leaves, per particle, the *compact* list: partners
//! within the query reach `q` that are not the particle's own rest neighbours. Before the fold
//! most lists are empty. The substeps then touch only the **active blocks**: the groups of
//! [`LANES`] consecutive particles (`8 b .. 8 b + 8`) holding at least one particle with a
//! non-empty list. The contact sums, the predicted positions (VcCPBD box centres) and the
//! damping rates are kept in compact arrays, block after block, so the velocity-correction
//! kernel [`super::response::apply`] runs unchanged on each active block (`start` is the
//! block's compact offset, `x`, `w`, `p` the block's slices of the particle arrays).
//!
//! Every block is computed independently (a Jacobi pass: a particle writes only its own
//! sums and position), so the result is the same serially, in parallel and on any number of
//! threads; parallel work is split into fixed groups of blocks.

use rayon::prelude::*;

use super::neighbours::Neighbours;
use super::response::{apply, ApplyInput, ApplyMode, ContactSums};
use super::self_pairs::PairCtx;
use crate::lanes::LANES;

/// Particles (compact slots) one parallel task handles in the pair pass.
const PAIR_CHUNK: usize = 128;

/// Blocks one parallel task handles in the correction pass at least.
const APPLY_BLOCKS: usize = 16;

/// Marks a block that is not active.
const INACTIVE: u32 = u32::MAX;

/// Inputs of [`ActiveSet::apply`] besides the particle arrays.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ApplyParams {
    pub mode: ApplyMode,
    pub friction: f32,
    pub h: f32,
    pub r: f32,
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
}

fn resize(v: &mut Vec<f32>, len: usize) {
    v.clear();
    v.resize(len, 0.0);
}

impl ActiveSet {
    /// Recomputes the active blocks from the compact `lists` of `n` particles and gathers their
    /// damping rates. Allocation-free once the buffers have reached their working size.
    pub(crate) fn rebuild(&mut self, lists: &Neighbours, n: usize, damping: &[f32]) {
        let nb = n.div_ceil(LANES);
        self.blocks.clear();
        self.slot_of_block.clear();
        self.slot_of_block.resize(nb, INACTIVE);
        for b in 0..nb {
            let (s, e) = (b * LANES, ((b + 1) * LANES).min(n));
            if lists.first[e] > lists.first[s] {
                self.slot_of_block[b] = self.blocks.len() as u32;
                self.blocks.push(b as u32);
            }
        }
        let len = self.blocks.len() * LANES;
        let s = &mut self.sums;
        for v in s.c.iter_mut().chain(s.f.iter_mut()).chain(s.n.iter_mut()) {
            resize(v, len);
        }
        resize(&mut s.gap, len);
        resize(&mut s.count, len);
        for v in &mut self.pred {
            resize(v, len);
        }
        resize(&mut self.damping, len);
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

    /// Copies the predicted positions of the active blocks (after the speed clamp).
    pub(crate) fn keep_predictions(&mut self, p: [&[f32]; 3]) {
        for (dst, src) in self.pred.iter_mut().zip(p) {
            for (k, &b) in self.blocks.iter().enumerate() {
                let g = b as usize * LANES;
                dst[k * LANES..(k + 1) * LANES].copy_from_slice(&src[g..g + LANES]);
            }
        }
    }

    /// The pair pass over the active blocks: the contact sums of every particle in them (zero
    /// for particles with no contact or `i >= n`). Parallel over fixed chunks when `parallel`.
    pub(crate) fn pair_pass(&mut self, ctx: &PairCtx<'_>, n: usize, parallel: bool, simd: bool) {
        let blocks = &self.blocks;
        let body = |start: usize, out: [&mut [f32]; 11]| {
            let [c0, c1, c2, f0, f1, f2, n0, n1, n2, g, k] = out;
            for o in 0..c0.len() {
                let s = start + o;
                let i = blocks[s / LANES] as usize * LANES + s % LANES;
                let r = if i < n { ctx.sums(i, simd) } else { [0.0; 11] };
                let dst = [
                    &mut c0[o], &mut c1[o], &mut c2[o], &mut f0[o], &mut f1[o], &mut f2[o], &mut n0[o], &mut n1[o], &mut n2[o], &mut g[o],
                    &mut k[o],
                ];
                for (d, v) in dst.into_iter().zip(r) {
                    *d = v;
                }
            }
        };
        let s = &mut self.sums;
        let len = s.len();
        let [c0, c1, c2] = &mut s.c;
        let [f0, f1, f2] = &mut s.f;
        let [n0, n1, n2] = &mut s.n;
        if parallel && len > PAIR_CHUNK {
            (
                c0.par_chunks_mut(PAIR_CHUNK),
                c1.par_chunks_mut(PAIR_CHUNK),
                c2.par_chunks_mut(PAIR_CHUNK),
                f0.par_chunks_mut(PAIR_CHUNK),
                f1.par_chunks_mut(PAIR_CHUNK),
                f2.par_chunks_mut(PAIR_CHUNK),
                n0.par_chunks_mut(PAIR_CHUNK),
                n1.par_chunks_mut(PAIR_CHUNK),
                n2.par_chunks_mut(PAIR_CHUNK),
                s.gap.par_chunks_mut(PAIR_CHUNK),
                s.count.par_chunks_mut(PAIR_CHUNK),
            )
                .into_par_iter()
                .enumerate()
                .for_each(|(k, (a, b, c, d, e, f, g, h, i, j, l))| body(k * PAIR_CHUNK, [a, b, c, d, e, f, g, h, i, j, l]));
        } else {
            body(0, [c0, c1, c2, f0, f1, f2, n0, n1, n2, &mut s.gap, &mut s.count]);
        }
    }

    /// The velocity-correction kernel on every active block of the predicted positions `p`
    /// (full particle arrays, padded to the lane width), with start positions `x` and inverse
    /// masses `w`. Parallel over the blocks when `parallel`; same bits either way.
    pub(crate) fn apply(&self, x: [&[f32]; 3], w: &[f32], p: [&mut [f32]; 3], ap: ApplyParams, parallel: bool, simd: bool) {
        let one = |k: usize, b: usize, p: [&mut [f32]; 3]| {
            let g = b * LANES..(b + 1) * LANES;
            let inp = ApplyInput {
                start: k * LANES,
                x: [&x[0][g.clone()], &x[1][g.clone()], &x[2][g.clone()]],
                w: &w[g],
                q: [&self.pred[0], &self.pred[1], &self.pred[2]],
                b: &self.damping,
                sums: &self.sums,
                friction: ap.friction,
                h: ap.h,
                r: ap.r,
            };
            apply(&inp, p, ap.mode, simd);
        };
        let [px, py, pz] = p;
        if parallel && self.blocks.len() > APPLY_BLOCKS {
            let nb = self.slot_of_block.len();
            (
                px[..nb * LANES].par_chunks_mut(LANES),
                py[..nb * LANES].par_chunks_mut(LANES),
                pz[..nb * LANES].par_chunks_mut(LANES),
            )
                .into_par_iter()
                .with_min_len(APPLY_BLOCKS * 4)
                .enumerate()
                .for_each(|(b, (a, c, d))| {
                    let k = self.slot_of_block[b];
                    if k != INACTIVE {
                        one(k as usize, b, [a, c, d]);
                    }
                });
        } else {
            for (k, &b) in self.blocks.iter().enumerate() {
                let g = b as usize * LANES..(b as usize + 1) * LANES;
                one(k, b as usize, [&mut px[g.clone()], &mut py[g.clone()], &mut pz[g]]);
            }
        }
    }
}
