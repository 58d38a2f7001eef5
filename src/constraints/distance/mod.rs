//! XPBD distance constraints in coloured SoA batches: the SIMD kernel and its scalar twin.
//!
//! Each colour stores `a, b, rest, compliance, lambda` as separate arrays padded to the lane
//! width with dummy constraints on the particle sink (inverse mass 0, so they move nothing).
//! Padding sits only at the end of a colour, so only the last parallel chunk touches the sink.
//! The SIMD kernel and the scalar twin perform the same operations in the same order (fused
//! multiply-adds only in the grid classes' projection, named in both: `constraints::project`),
//! so they agree bit for bit; within a colour no particle repeats, so the
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

mod solve;

use crate::constraints::blocks::{plan, Block, Window};
use crate::constraints::colour::colour_families;
use crate::constraints::grid::{self, GridColour, GridSpec};
pub(crate) use crate::constraints::project::{project1, project8};
use crate::data::lanes::{round_up, LANES};

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
}

#[cfg(test)]
mod tests;
