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
//! A grid cloth whose constraints are whole classes (see [`grid`]) is laid out
//! by class instead, and its colours run the structured kernels, which read no index, rest
//! length or compliance array; the arrays stay for the scalar twin and every other reader.
//!
//! Each pass (a colour, or a grid's band colours or seam colours together) is a rayon fork and join, not
//! a spinning barrier between colours on a private pool: a barrier waits for a descheduled
//! thread where work stealing does not.

use rayon::prelude::*;

use crate::constraints::blocks::{plan, solve_block_simd, Block, Cons, Window};
use crate::constraints::colour::colour_families;
use crate::constraints::grid::{self, GridColour, GridSpec};
use crate::constraints::grid_sweep::{self, Sweep};
pub(crate) use crate::constraints::project::{project1, project8};
use crate::data::lanes::{round_up, SharedVec3, LANES};

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
    /// A class of a grid cloth: the SIMD sweep runs the structured kernel instead of the
    /// arrays above (which list the same constraints in the kernel's order).
    pub grid: Option<GridColour>,
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
    /// How the SIMD sweep runs the colours, in order.
    passes: Vec<Pass>,
    /// Multipliers were reset and not yet written: the next sweep reads them as zero.
    lambda_reset: bool,
    /// The next sweep does not write the multipliers (see [`DistanceSet::reset_lambda_unkept`]).
    unkept: bool,
}

/// One pass of the SIMD sweep.
#[derive(Clone, Debug, PartialEq)]
enum Pass {
    /// One colour through its block plan.
    Planned(usize),
    /// Grid colours of one grid, row by row: one colour, or several row-local ones.
    Grid(std::ops::Range<usize>),
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
        Self::with_grids(input, particle_count, sink, &[])
    }

    /// As [`new`](Self::new), where `grids` names cloth grids and the range of `input` that
    /// holds each one's constraints: a grid whose constraints are whole classes of one rest
    /// length and compliance each gets one colour per class and the structured kernels; the
    /// others are coloured with the rest.
    pub fn with_grids(input: &[DistanceInput], particle_count: usize, sink: u32, grids: &[(GridSpec, std::ops::Range<usize>)]) -> Self {
        let mut colours = Vec::new();
        let mut taken = vec![false; input.len()];
        for (spec, range) in grids {
            let end = spec.first as u64 + spec.rows as u64 * spec.cols as u64;
            let Some(part) = input.get(range.clone()).filter(|_| end <= particle_count as u64) else {
                continue;
            };
            let Some(classes) = grid::classify(*spec, part.iter().map(|c| (c.a, c.b, c.rest, c.compliance))) else {
                continue;
            };
            for (mut g, slots) in grid::layout(*spec, &classes) {
                let c0 = &part[slots[0]];
                (g.rest, g.compliance) = (c0.rest, c0.compliance);
                let mut col = Colour {
                    grid: Some(g),
                    ..Colour::default()
                };
                for &k in &slots {
                    let c = &part[k];
                    col.a.push(c.a);
                    col.b.push(c.b);
                    col.rest.push(c.rest);
                    col.compliance.push(c.compliance);
                }
                colours.push(col);
            }
            taken[range.clone()].fill(true);
        }
        let rest: Vec<DistanceInput> = input.iter().zip(&taken).filter(|(_, &t)| !t).map(|(c, _)| *c).collect();
        colours.extend(colour_families(&rest, particle_count));
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
        let mut set = DistanceSet {
            colours,
            ..Default::default()
        };
        set.plan_passes();
        set
    }

    /// Groups the colours into passes: a grid's band colours share one, its seam colours
    /// another.
    fn plan_passes(&mut self) {
        self.passes.clear();
        let mut k = 0;
        while k < self.colours.len() {
            let Some(g) = &self.colours[k].grid else {
                self.passes.push(Pass::Planned(k));
                k += 1;
                continue;
            };
            let same = |c: &Colour| c.grid.as_ref().is_some_and(|h| h.spec == g.spec && h.seam == g.seam);
            let end = k + self.colours[k..].iter().take_while(|c| same(c)).count();
            self.passes.push(Pass::Grid(k..end));
            k = end;
        }
    }

    /// Re-reads each grid colour's rest length and compliance from its arrays after they were
    /// changed; a colour whose values are no longer uniform runs through its block plan.
    pub fn refresh_grids(&mut self) {
        for col in &mut self.colours {
            if let Some(g) = &mut col.grid {
                let (rest, comp) = (&col.rest[..col.real], &col.compliance[..col.real]);
                let same = |v: &[f32]| v.iter().all(|x| x.to_bits() == v[0].to_bits());
                if same(rest) && same(comp) {
                    (g.rest, g.compliance) = (rest[0], comp[0]);
                } else {
                    col.grid = None;
                }
            }
        }
        self.plan_passes();
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
        self.unkept = false;
    }

    /// As [`reset_lambda`](Self::reset_lambda), for a substep of one sweep whose multipliers
    /// nobody reads afterwards: that sweep reads them as zero and does not write them, which
    /// saves a store per constraint. The stored values stay stale until a sweep that keeps them.
    pub fn reset_lambda_unkept(&mut self) {
        self.lambda_reset = true;
        self.unkept = true;
    }

    /// Whether the next sweep reads the multipliers as zero and whether it writes them.
    fn take_reset(&mut self) -> (bool, bool) {
        let reset = std::mem::take(&mut self.lambda_reset);
        let store = !(reset && std::mem::take(&mut self.unkept));
        (reset, store)
    }

    /// One Gauss–Seidel sweep over all colours, SIMD, each colour in parallel chunks when
    /// `parallel` (on the current rayon pool).
    pub fn solve_simd(&mut self, px: &mut [f32], py: &mut [f32], pz: &mut [f32], w: &[f32], inv_h2: f32, parallel: bool) {
        let p = SharedVec3::new(px, py, pz);
        let (solve, pass, wave): (Solve, GridPass, GridWave) = match self.take_reset() {
            (true, true) => (
                solve_block_simd::<true, true>,
                grid_sweep::run_pass::<true, true>,
                grid_sweep::run_wave::<true, true>,
            ),
            (true, false) => (
                solve_block_simd::<true, false>,
                grid_sweep::run_pass::<true, false>,
                grid_sweep::run_wave::<true, false>,
            ),
            _ => (
                solve_block_simd::<false, true>,
                grid_sweep::run_pass::<false, true>,
                grid_sweep::run_wave::<false, true>,
            ),
        };
        let sweep = Sweep { p, w, inv_h2 };
        let mut pass_k = 0;
        while pass_k < self.passes.len() {
            match &self.passes[pass_k] {
                Pass::Grid(range) => match self.seams_of(pass_k) {
                    // a grid's bands and then its seams (the next pass): one wave
                    Some(seams) => {
                        let (bands, rest) = self.colours[range.start..].split_at_mut(range.len());
                        wave(
                            bands,
                            &mut rest[seams.start - range.end..seams.end - range.end],
                            &sweep,
                            parallel,
                            None,
                        );
                        pass_k += 1;
                    }
                    None => pass(&mut self.colours[range.clone()], &sweep, parallel),
                },
                &Pass::Planned(k) => {
                    let col = &mut self.colours[k];
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
            pass_k += 1;
        }
    }

    /// The seam colours of the grid whose band colours are pass `k`, when they are the next
    /// pass.
    fn seams_of(&self, k: usize) -> Option<std::ops::Range<usize>> {
        let grid = |k: usize| match self.passes.get(k)? {
            Pass::Grid(r) => Some((r.clone(), self.colours[r.start].grid.as_ref()?)),
            Pass::Planned(_) => None,
        };
        let ((_, bands), (seams, s)) = (grid(k)?, grid(k + 1)?);
        (!bands.seam && s.seam && s.spec == bands.spec).then_some(seams)
    }

    /// Whether the grid's bands start on whole blocks of eight particles, so that
    /// [`solve_wave`](Self::solve_wave) can hand them to a `before` (a set for which
    /// [`wave_ready`](Self::wave_ready) holds).
    pub fn bands_on_blocks(&self) -> bool {
        let cols = self.colours.first().and_then(|c| c.grid.as_ref()).map(|g| g.spec.cols);
        cols.is_some_and(grid_sweep::bands_on_blocks)
    }

    /// Whether [`solve_wave`](Self::solve_wave) can run this set over `count` particles: every
    /// constraint is in the structured colours of one grid cloth that starts at particle 0 and
    /// holds all `count` particles.
    pub fn wave_ready(&self, count: usize) -> bool {
        let spec = |k: usize| match &self.passes[k] {
            Pass::Grid(r) => self.colours[r.start].grid.as_ref().map(|g| (g.spec, g.seam)),
            Pass::Planned(_) => None,
        };
        match self.passes.len() {
            1 | 2 => {
                let Some((first, false)) = spec(0) else { return false };
                let seams_match = self.passes.len() == 1 || spec(1) == Some((first, true));
                seams_match && first.first == 0 && (first.rows * first.cols) as usize == count
            }
            _ => false,
        }
    }

    /// One sweep of [`solve_simd`](Self::solve_simd) as a wave over the grid that hands each
    /// range of particles to `after` as soon as the sweep is done with it, all `p`'s
    /// particles once (`grid_sweep::run_wave`), and with `before`, each band's particles
    /// to it just before the sweep reaches them; the same bits as `before` over all
    /// particles, the sweep, then `after` over all particles. Requires
    /// [`wave_ready`](Self::wave_ready), and for `before`, [`bands_on_blocks`](Self::bands_on_blocks).
    pub fn solve_wave(
        &mut self,
        p: &crate::data::particles::RawParticles<'_>,
        inv_h2: f32,
        parallel: bool,
        before: Option<&(dyn Fn(std::ops::Range<usize>) + Sync)>,
        after: &(dyn Fn(std::ops::Range<usize>) + Sync),
    ) {
        let wave = match self.take_reset() {
            (true, true) => grid_sweep::run_wave::<true, true>,
            (true, false) => grid_sweep::run_wave::<true, false>,
            _ => grid_sweep::run_wave::<false, true>,
        };
        let sweep = Sweep {
            p: p.p(),
            w: p.w(),
            inv_h2,
        };
        let split = self.passes.get(1).map_or(self.colours.len(), |q| match q {
            Pass::Grid(r) => r.start,
            Pass::Planned(k) => *k,
        });
        let (bands, seams) = self.colours.split_at_mut(split);
        let finish = grid_sweep::Finish {
            len: p.len(),
            before,
            after,
        };
        wave(bands, seams, &sweep, parallel, Some(finish));
    }

    /// The scalar f32 twin of [`solve_simd`](Self::solve_simd): one constraint at a time,
    /// one thread, the same arithmetic (a grid colour's projection with one division).
    pub fn solve_scalar(&mut self, px: &mut [f32], py: &mut [f32], pz: &mut [f32], w: &[f32], inv_h2: f32) {
        let (reset, keep) = self.take_reset();
        for col in &mut self.colours {
            for k in 0..col.a.len() {
                let lam = if reset { 0.0 } else { col.lambda[k] };
                let (a, b) = (col.a[k] as usize, col.b[k] as usize);
                let pa = [px[a], py[a], pz[a]];
                let pb = [px[b], py[b], pz[b]];
                let alpha = col.compliance[k] * inv_h2;
                let project = if col.grid.is_some() { project1::<true> } else { project1::<false> };
                let (pa, pb, lam) = project(pa, pb, w[a], w[b], col.rest[k], alpha, lam);
                [px[a], py[a], pz[a]] = pa;
                [px[b], py[b], pz[b]] = pb;
                if keep {
                    col.lambda[k] = lam;
                }
            }
        }
    }
}

/// The kernel of one colour chunk (see [`solve_block_simd`]).
type Solve = fn(&Cons<'_>, &mut [f32], &[Window], &SharedVec3, &[f32], f32);
/// The kernel of one grid pass (see [`grid_sweep::run_pass`]).
type GridPass = fn(&mut [Colour], &Sweep<'_>, bool);
/// The kernel of one grid's bands and seams as a wave (see [`grid_sweep::run_wave`]).
type GridWave = fn(&mut [Colour], &mut [Colour], &Sweep<'_>, bool, Option<grid_sweep::Finish<'_>>);

#[cfg(test)]
#[path = "distance_tests.rs"]
mod tests;
