//! The sweeps over a distance set: every colour in SIMD blocks (grid cloths by band, or as a
//! wave handing finished rows to the update), and the scalar twin.

use rayon::prelude::*;

use super::*;
use crate::constraints::blocks::{solve_block_simd, Cons};
use crate::constraints::grid_sweep::{self, Sweep};
use crate::data::lanes::SharedVec3;

impl DistanceSet {
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
            let uses = col.grid.as_ref().is_none_or(GridColour::keeps_multipliers);
            let (reset, keep) = (reset || !uses, keep && uses);
            // The form chosen once a colour, so that `project1` inlines into the loop.
            let p = [&mut *px, &mut *py, &mut *pz];
            match (col.grid.is_some(), reset) {
                (true, true) => colour_scalar::<true, true>(col, p, w, inv_h2, keep),
                (true, false) => colour_scalar::<true, false>(col, p, w, inv_h2, keep),
                (false, true) => colour_scalar::<false, true>(col, p, w, inv_h2, keep),
                (false, false) => colour_scalar::<false, false>(col, p, w, inv_h2, keep),
            }
        }
    }
}

/// One colour of [`DistanceSet::solve_scalar`], constraint by constraint: [`project1`] with one
/// division (`ONE_DIV`, grid colours) or two; multipliers read as zero with `RESET`, written
/// with `keep`.
fn colour_scalar<const ONE_DIV: bool, const RESET: bool>(col: &mut Colour, p: [&mut [f32]; 3], w: &[f32], inv_h2: f32, keep: bool) {
    let [px, py, pz] = p;
    for k in 0..col.a.len() {
        let lam = if RESET { 0.0 } else { col.lambda[k] };
        let (a, b) = (col.a[k] as usize, col.b[k] as usize);
        let pa = [px[a], py[a], pz[a]];
        let pb = [px[b], py[b], pz[b]];
        let alpha = col.compliance[k] * inv_h2;
        let (pa, pb, lam) = project1::<ONE_DIV, RESET>(pa, pb, w[a], w[b], col.rest[k], alpha, lam);
        [px[a], py[a], pz[a]] = pa;
        [px[b], py[b], pz[b]] = pb;
        if keep {
            col.lambda[k] = lam;
        }
    }
}

/// The kernel of one colour chunk (see [`solve_block_simd`]).
type Solve = fn(&Cons<'_>, &mut [f32], &[Window], &SharedVec3, &[f32], f32);
/// The kernel of one grid pass (see [`grid_sweep::run_pass`]).
type GridPass = fn(&mut [Colour], &Sweep<'_>, bool);
/// The kernel of one grid's bands and seams as a wave (see [`grid_sweep::run_wave`]).
type GridWave = fn(&mut [Colour], &mut [Colour], &Sweep<'_>, bool, Option<grid_sweep::Finish<'_>>);
