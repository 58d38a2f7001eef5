//! XPBD distance constraints in coloured SoA batches: the SIMD kernel and its scalar twin.
//!
//! Each colour stores `a, b, rest, compliance, lambda` as separate arrays padded to the lane
//! width with dummy constraints on the particle sink (inverse mass 0, so they move nothing).
//! Padding sits only at the end of a colour, so only the last parallel chunk touches the sink.
//! The SIMD kernel and the scalar twin perform the same operations in the same order without
//! fused multiply-add, so they agree bit for bit; within a colour no particle repeats, so the
//! order of constraints (and therefore chunking and thread count) cannot change the result.
//!
//! That freedom is used for speed: each colour is sorted by index offset `b − a`, then by `a`,
//! so that on a grid most blocks of eight constraints read contiguous particles, and a
//! [block plan](super::blocks) lets the kernel use contiguous loads and stores (or a fixed
//! permutation of a 16-particle window) instead of gathers and scatters.
//!
//! Each colour is a rayon fork and join, not a spinning barrier between colours on a private
//! pool: a barrier waits for a descheduled thread where work stealing does not.

use rayon::prelude::*;

use crate::constraints::blocks::{plan, Block, Window, GATHER, RUN, WINDOW};
use crate::constraints::colour::colour_pairs;
use crate::data::lanes::{gather1, load, load_idx, pick16, pick16_vec, round_up, store, F32s, SharedVec3, Vec3x8, LANES};

pub use crate::model::params::MIN_LENGTH;

/// Constraints per parallel task (a multiple of the lane width).
pub const CHUNK: usize = 2048;

/// An offset family (constraints with the same `b − a`) at least this large is coloured apart
/// from the irregular rest, in order of `a` (see [`DistanceSet::new`]).
pub const FAMILY_MIN: usize = 1024;

/// One colour: constraints that share no particle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Colour {
    /// First particle of each constraint.
    pub a: Vec<u32>,
    /// Second particle.
    pub b: Vec<u32>,
    /// Rest length, m.
    pub rest: Vec<f32>,
    /// Compliance, m/N.
    pub compliance: Vec<f32>,
    /// Accumulated Lagrange multiplier of the current substep. After
    /// [`DistanceSet::reset_lambda`] the stored values are stale and read as zero by the next
    /// sweep, which overwrites them.
    pub lambda: Vec<f32>,
    /// Number of real (non-padding) constraints.
    pub real: usize,
    /// One plan per block of eight constraints, derived from `a` and `b` (call
    /// [`Colour::replan`] after changing them).
    pub blocks: Vec<Block>,
    /// The distinct window permutations the blocks name.
    pub windows: Vec<Window>,
}

impl Colour {
    /// Recomputes [`blocks`](Self::blocks) and [`windows`](Self::windows) from `a` and `b`.
    pub fn replan(&mut self) {
        (self.blocks, self.windows) = plan(&self.a, &self.b);
    }
}

/// All distance constraints of a world, grouped by colour.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DistanceSet {
    /// The colours, solved in order.
    pub colours: Vec<Colour>,
    /// Multipliers were reset and not yet written: the next sweep reads them as zero.
    lambda_reset: bool,
}

/// A distance constraint given to [`DistanceSet::new`] (global particle indices).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistanceInput {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Rest length, m.
    pub rest: f32,
    /// Compliance, m/N.
    pub compliance: f32,
}

impl DistanceSet {
    /// Colours the constraints and lays them out; `sink` is an inert padding particle.
    pub fn new(input: &[DistanceInput], particle_count: usize, sink: u32) -> Self {
        // Large offset families (same `b − a`: on a grid, horizontal stretch, vertical bend, a
        // shear diagonal...) are coloured greedily family after family, each in order of `a`,
        // which gives mostly regular colours (alternate edges, alternate rows). The rest
        // (irregular meshes, short pieces, any world below `FAMILY_MIN` per family) is coloured
        // on its own in input order, as it always was, so small worlds keep their Gauss–Seidel
        // order. Each colour is then laid out by offset and `a` (free within a colour), which
        // the block plans turn into contiguous loads and stores.
        let offset = |k: usize| input[k].b as i64 - input[k].a as i64;
        let mut order: Vec<usize> = (0..input.len()).collect();
        order.sort_by_key(|&k| (offset(k), input[k].a));
        let (mut large, mut rest) = (Vec::new(), Vec::new());
        for family in order.chunk_by(|&i, &j| offset(i) == offset(j)) {
            if family.len() >= FAMILY_MIN {
                large.extend_from_slice(family);
            } else {
                rest.extend_from_slice(family);
            }
        }
        rest.sort_unstable();
        let groups = [large, rest];
        let (mut colour_of, mut count) = (vec![0u32; input.len()], 0u32);
        for g in &groups {
            let pairs: Vec<(u32, u32)> = g.iter().map(|&k| (input[k].a, input[k].b)).collect();
            let (c, n) = colour_pairs(&pairs, particle_count);
            for (&k, c) in g.iter().zip(c) {
                colour_of[k] = c + count;
            }
            count += n;
        }
        // Stable: within a colour, the (offset, a) order from above.
        order.sort_by_key(|&k| colour_of[k]);
        let colour_of: Vec<u32> = order.iter().map(|&k| colour_of[k]).collect();
        let mut colours = vec![Colour::default(); count as usize];
        for (&k, &col) in order.iter().zip(&colour_of) {
            let (c, col) = (&input[k], &mut colours[col as usize]);
            col.a.push(c.a);
            col.b.push(c.b);
            col.rest.push(c.rest);
            col.compliance.push(c.compliance);
        }
        for col in &mut colours {
            col.real = col.a.len();
            let len = round_up(col.real);
            col.a.resize(len, sink);
            col.b.resize(len, sink);
            col.rest.resize(len, 0.0);
            col.compliance.resize(len, 0.0);
            col.lambda = vec![0.0; len];
            col.replan();
        }
        colours.retain(|c| c.real > 0);
        DistanceSet {
            colours,
            lambda_reset: false,
        }
    }

    /// Number of real constraints.
    pub fn len(&self) -> usize {
        self.colours.iter().map(|c| c.real).sum()
    }

    /// Whether there are no constraints.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sets every multiplier to zero (start of a substep). Lazily: the next sweep reads zero
    /// instead of the stored values and writes them, which saves one pass over the
    /// multipliers and one read of them per substep (with one iteration, the common case,
    /// the multipliers are then only ever written).
    pub fn reset_lambda(&mut self) {
        self.lambda_reset = true;
    }

    /// One Gauss–Seidel sweep over all colours, SIMD, each colour in parallel chunks when
    /// `parallel` (on the current rayon pool).
    pub fn solve_simd(&mut self, px: &mut [f32], py: &mut [f32], pz: &mut [f32], w: &[f32], inv_h2: f32, parallel: bool) {
        let p = SharedVec3::new(px, py, pz);
        let solve = if std::mem::take(&mut self.lambda_reset) {
            solve_block_simd::<true>
        } else {
            solve_block_simd::<false>
        };
        for col in &mut self.colours {
            if parallel && col.a.len() > CHUNK {
                col.a
                    .par_chunks(CHUNK)
                    .zip(col.b.par_chunks(CHUNK))
                    .zip(col.rest.par_chunks(CHUNK))
                    .zip(col.compliance.par_chunks(CHUNK))
                    .zip(col.lambda.par_chunks_mut(CHUNK))
                    .zip(col.blocks.par_chunks(CHUNK / LANES))
                    .for_each(|(((((a, b), rest), comp), lambda), blocks)| {
                        let cons = Cons { a, b, rest, comp, blocks };
                        solve(&cons, lambda, &col.windows, &p, w, inv_h2)
                    });
            } else {
                let cons = Cons {
                    a: &col.a,
                    b: &col.b,
                    rest: &col.rest,
                    comp: &col.compliance,
                    blocks: &col.blocks,
                };
                solve(&cons, &mut col.lambda, &col.windows, &p, w, inv_h2);
            }
        }
    }

    /// The scalar f32 twin of [`solve_simd`](Self::solve_simd): one constraint at a time,
    /// one thread, the same arithmetic.
    pub fn solve_scalar(&mut self, px: &mut [f32], py: &mut [f32], pz: &mut [f32], w: &[f32], inv_h2: f32) {
        let reset = std::mem::take(&mut self.lambda_reset);
        for col in &mut self.colours {
            for k in 0..col.a.len() {
                let lam = if reset { 0.0 } else { col.lambda[k] };
                let (a, b) = (col.a[k] as usize, col.b[k] as usize);
                let (wa, wb) = (w[a], w[b]);
                let (dx, dy, dz) = (px[b] - px[a], py[b] - py[a], pz[b] - pz[a]);
                let len = (dx * dx + dy * dy + dz * dz).sqrt();
                let c = len - col.rest[k];
                let alpha = col.compliance[k] * inv_h2;
                let denom = wa + wb + alpha;
                let valid = len > MIN_LENGTH && denom > 0.0;
                let dl = if valid { (-c - alpha * lam) / denom } else { 0.0 };
                let s = if valid { dl / len } else { 0.0 };
                let (sa, sb) = (wa * s, wb * s);
                px[a] -= dx * sa;
                py[a] -= dy * sa;
                pz[a] -= dz * sa;
                px[b] += dx * sb;
                py[b] += dy * sb;
                pz[b] += dz * sb;
                col.lambda[k] = lam + dl;
            }
        }
    }
}

/// One chunk of a colour's constraint arrays (a multiple of the lane width long).
struct Cons<'a> {
    a: &'a [u32],
    b: &'a [u32],
    rest: &'a [f32],
    comp: &'a [f32],
    blocks: &'a [Block],
}

/// One chunk of a colour, eight constraints at a time; `RESET`: the multipliers read as zero.
#[inline]
fn solve_block_simd<const RESET: bool>(cons: &Cons<'_>, lambda: &mut [f32], windows: &[Window], p: &SharedVec3, w: &[f32], inv_h2: f32) {
    let inv_h2 = F32s::splat(inv_h2);
    let zero = F32s::ZERO;
    let min_len = F32s::splat(MIN_LENGTH);
    for (k, bl) in cons.blocks.iter().enumerate() {
        let i = k * LANES;
        let s = bl.first as usize;
        // SAFETY (all particle accesses below): every index or run of indices comes from this
        // block's constraints, which are below the padded particle count, and within one
        // colour no particle appears in two constraints, so no other task touches them. A run
        // block's `a` and `b` runs are disjoint; a window block owns all sixteen particles.
        let (pa, pb, wa, wb) = match bl.kind {
            GATHER => {
                let (ia, ib) = (load_idx(cons.a, i), load_idx(cons.b, i));
                unsafe { (p.gather(&ia), p.gather(&ib), gather1(w, &ia), gather1(w, &ib)) }
            }
            RUN => {
                let t = bl.second as usize;
                unsafe { (p.load_run(s), p.load_run(t), load(w, s), load(w, t)) }
            }
            kind => {
                let win = &windows[(kind - WINDOW) as usize];
                let (lo, hi) = unsafe { (p.load_run(s), p.load_run(s + LANES)) };
                let (wl, wh) = (load(w, s), load(w, s + LANES));
                let pa = pick16_vec(lo, hi, &win.pos_a);
                let pb = pick16_vec(lo, hi, &win.pos_b);
                (pa, pb, pick16(wl, wh, &win.pos_a), pick16(wl, wh, &win.pos_b))
            }
        };
        let d = pb - pa;
        let len = d.length_sq().sqrt();
        let c = len - load(cons.rest, i);
        let alpha = load(cons.comp, i) * inv_h2;
        let denom = wa + wb + alpha;
        let lam = if RESET { zero } else { load(lambda, i) };
        let valid = len.simd_gt(min_len) & denom.simd_gt(zero);
        let dl = valid.select((-c - alpha * lam) / denom, zero);
        let sc = valid.select(dl / len, zero);
        let pa = pa - d.scale(wa * sc);
        let pb = pb + d.scale(wb * sc);
        store(lambda, i, lam + dl);
        write_back(bl, windows, p, cons, i, pa, pb);
    }
}

/// Writes a block's new positions back the way its plan read them.
#[inline(always)]
fn write_back(bl: &Block, windows: &[Window], p: &SharedVec3, cons: &Cons<'_>, i: usize, pa: Vec3x8, pb: Vec3x8) {
    let s = bl.first as usize;
    // SAFETY: as in `solve_block_simd`; for gathers `a` is scattered before `b`, and
    // `a != b` for real constraints.
    unsafe {
        match bl.kind {
            GATHER => {
                p.scatter(&load_idx(cons.a, i), pa);
                p.scatter(&load_idx(cons.b, i), pb);
            }
            RUN => {
                p.store_run(s, pa);
                p.store_run(bl.second as usize, pb);
            }
            kind => {
                let win = &windows[(kind - WINDOW) as usize];
                p.store_run(s, pick16_vec(pa, pb, &win.src_lo));
                p.store_run(s + LANES, pick16_vec(pa, pb, &win.src_hi));
            }
        }
    }
}

#[cfg(test)]
#[path = "distance_tests.rs"]
mod tests;
