//! Long-range attachments (tethers): one-sided distance limits from free particles to pins.
//!
//! Each free particle has at most one tether, to a pinned (inverse mass 0) anchor, so a single
//! pass is race-free: tethered particles are all distinct and anchors are only read. The
//! projection is `p <- anchor + (p - anchor) * L / |p - anchor|` when `|p - anchor| > L`.
//!
//! A sweep first copies the anchors' predictions (few: the pins) and reads them from the copy.
//! Then it can also run a particle range at a time, inside the update pass, while other
//! ranges are already updated and predicted for the next substep
//! ([`TetherSet::solve_range`]): a tether depends on its particle and the anchors' copy only.

use std::ops::Range;

use rayon::prelude::*;

use crate::data::lanes::{gather1, idx8, load, load_idx, round_up, F32s, SharedVec3, Vec3x8, LANES};
use crate::data::particles::ParticleChunk;
use crate::model::cloth::Tether;

/// Tethers in SoA, padded with dummies on the particle sink.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TetherSet {
    /// Tethered (free) particle.
    pub particle: Vec<u32>,
    /// Pinned anchor.
    pub anchor: Vec<u32>,
    /// Largest allowed distance, m (infinite for the padding: never projected).
    pub max_len: Vec<f32>,
    real: usize,
    /// The distinct anchors, and each tether's place among them.
    anchors: Vec<u32>,
    slot: Vec<u32>,
    /// The anchors' predictions as the last [`take_anchors`](Self::take_anchors) (or
    /// [`predict_anchors`](Self::predict_anchors)) found them, padded to whole lanes.
    at: [Vec<f32>; 3],
    /// Whether the tethered particles ascend, so that a particle range's tethers are
    /// consecutive.
    ascending: bool,
    /// Copies of the anchors' state for [`predict_anchors`](Self::predict_anchors): seven
    /// arrays (positions, velocities, inverse masses) as long as `at`'s.
    copies: Vec<f32>,
}

/// Tethers per parallel task.
const CHUNK: usize = 4096;

impl TetherSet {
    /// Lays out tethers (global indices); `sink` is an inert padding particle.
    pub fn new(tethers: &[Tether], sink: u32) -> Self {
        let len = round_up(tethers.len());
        let mut s = TetherSet {
            real: tethers.len(),
            ..Default::default()
        };
        s.particle = tethers.iter().map(|t| t.particle).collect();
        s.anchor = tethers.iter().map(|t| t.anchor).collect();
        s.max_len = tethers.iter().map(|t| t.max_len).collect();
        s.ascending = s.particle.windows(2).all(|w| w[0] < w[1]);
        let mut anchors = s.anchor.clone();
        anchors.sort_unstable();
        anchors.dedup();
        s.slot = s.anchor.iter().map(|a| anchors.binary_search(a).map_or(0, |k| k as u32)).collect();
        s.at = std::array::from_fn(|_| vec![0.0; round_up(anchors.len().max(1))]);
        s.anchors = anchors;
        s.particle.resize(len, sink);
        s.anchor.resize(len, sink);
        s.max_len.resize(len, f32::INFINITY);
        s.slot.resize(len, 0);
        s
    }

    /// Number of real tethers.
    pub fn len(&self) -> usize {
        self.real
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.real == 0
    }

    /// Whether [`solve_range`](Self::solve_range) can run: the tethered particles ascend.
    pub fn by_range(&self) -> bool {
        self.ascending
    }

    /// Whether every anchor is pinned in `w` (inverse masses). A pinned anchor keeps its
    /// prediction through the distance sweep, so tethers that read it before the sweep (as in
    /// the update pass) read what a pass after the sweep reads; an anchor made free later
    /// ([`World::set_inverse_masses`](crate::World::set_inverse_masses)) moves in the sweep.
    pub fn anchors_pinned(&self, w: &[f32]) -> bool {
        self.anchors.iter().all(|&a| w.get(a as usize) == Some(&0.0))
    }

    /// Copies the anchors' predictions, which the sweeps read until the next call.
    pub fn take_anchors(&mut self, px: &[f32], py: &[f32], pz: &[f32]) {
        for (at, p) in self.at.iter_mut().zip([px, py, pz]) {
            for (v, &a) in at.iter_mut().zip(&self.anchors) {
                *v = p[a as usize];
            }
        }
    }

    /// Sets the anchors' predictions to what `predict` makes of their positions `x`,
    /// velocities `v` and inverse masses `w`, before the pass that predicts them has run:
    /// `predict` gets a chunk of copies of the anchors (padded with copies of the first) and
    /// computes each lane as it would in place, so the copy holds the bits the particles will
    /// hold. `predict` must not read per-particle inputs other than the chunk's (no wind).
    pub fn predict_anchors(&mut self, x: [&[f32]; 3], v: [&[f32]; 3], w: &[f32], predict: impl FnOnce(ParticleChunk<'_>)) {
        let Some(&first) = self.anchors.first() else {
            return;
        };
        let m = self.at[0].len();
        self.copies.resize(7 * m, 0.0);
        let [cx, cy, cz, cvx, cvy, cvz, cw] = split7(&mut self.copies, m);
        for (l, slot) in (0..m).zip(self.anchors.iter().chain(std::iter::repeat(&first))) {
            let a = *slot as usize;
            (cx[l], cy[l], cz[l]) = (x[0][a], x[1][a], x[2][a]);
            (cvx[l], cvy[l], cvz[l]) = (v[0][a], v[1][a], v[2][a]);
            cw[l] = w[a];
        }
        // the predictions land in `at` itself
        let [px, py, pz] = &mut self.at;
        predict(ParticleChunk::from_arrays(0, [cx, cy, cz, px, py, pz, cvx, cvy, cvz], cw));
    }

    /// Projects every tether, SIMD, in parallel chunks when `parallel`.
    pub fn solve_simd(&mut self, px: &mut [f32], py: &mut [f32], pz: &mut [f32], parallel: bool) {
        self.take_anchors(px, py, pz);
        let p = SharedVec3::new(px, py, pz);
        let this = &*self;
        let block = |k: usize| this.block(k, &p, 0);
        if parallel && self.particle.len() > CHUNK {
            (0..self.particle.len())
                .into_par_iter()
                .step_by(CHUNK)
                .for_each(|k0| (k0..(k0 + CHUNK).min(this.particle.len())).step_by(LANES).for_each(block));
        } else {
            (0..self.particle.len()).step_by(LANES).for_each(block);
        }
    }

    /// Projects the tethers of the particles `range` (global indices) with the anchors of the
    /// last [`take_anchors`](Self::take_anchors); `px, py, pz` hold those particles only (the
    /// first is particle `range.start`). Needs [`by_range`](Self::by_range). The same bits as
    /// the tethers' part of a whole sweep: the lanes and the scalar tail compute each tether
    /// as the scalar twin does.
    ///
    /// # Panics
    /// If the tethered particles do not ascend ([`by_range`](Self::by_range)) or the arrays
    /// are shorter than the range: the kernel's raw accesses rely on both.
    pub fn solve_range(&self, range: Range<usize>, px: &mut [f32], py: &mut [f32], pz: &mut [f32]) {
        assert!(self.ascending, "solve_range needs tethered particles in ascending order");
        assert!(px.len() >= range.len(), "{} values for the particles {range:?}", px.len());
        let real = &self.particle[..self.real];
        let lo = real.partition_point(|&i| (i as usize) < range.start);
        let hi = real.partition_point(|&i| (i as usize) < range.end);
        let p = SharedVec3::new(px, py, pz);
        let mut k = lo;
        while k + LANES <= hi {
            self.block(k, &p, range.start);
            k += LANES;
        }
        for k in k..hi {
            let i = self.particle[k] as usize - range.start;
            let s = self.slot[k] as usize;
            let a = [self.at[0][s], self.at[1][s], self.at[2][s]];
            // SAFETY: `i` is a particle of the range, below the arrays' length.
            let pi = unsafe { p.get(i) };
            if let Some(q) = project1(pi, a, self.max_len[k]) {
                // SAFETY: as above; the caller owns the range.
                unsafe { p.set(i, q) };
            }
        }
    }

    /// Scalar twin of [`solve_simd`](Self::solve_simd): reads the anchors from the arrays.
    pub fn solve_scalar(&self, px: &mut [f32], py: &mut [f32], pz: &mut [f32]) {
        for k in 0..self.real {
            let (i, a) = (self.particle[k] as usize, self.anchor[k] as usize);
            if let Some(q) = project1([px[i], py[i], pz[i]], [px[a], py[a], pz[a]], self.max_len[k]) {
                [px[i], py[i], pz[i]] = q;
            }
        }
    }

    /// Projects the eight tethers from `k`, whose particles are the elements `particle - offset`
    /// of `p`. A block whose tethered particles are consecutive (the usual layout: tethers
    /// listed in particle order) loads and stores them as runs, and a block with one anchor
    /// reads it once; other blocks gather and scatter. A block with no tether over its length
    /// writes nothing. Each lane's arithmetic is the scalar twin's, so the choice of path
    /// changes no bit.
    #[inline(always)]
    fn block(&self, k: usize, p: &SharedVec3, offset: usize) {
        let ii = load_idx(&self.particle, k).map(|i| i.wrapping_sub(offset as u32));
        let slots = load_idx(&self.slot, k);
        let i0 = ii[0];
        let run = ii == idx8(|l| i0.wrapping_add(l as u32));
        let pa = if slots == [slots[0]; LANES] {
            let s = slots[0] as usize;
            Vec3x8::splat([self.at[0][s], self.at[1][s], self.at[2][s]])
        } else {
            Vec3x8 {
                x: gather1(&self.at[0], &slots),
                y: gather1(&self.at[1], &slots),
                z: gather1(&self.at[2], &slots),
            }
        };
        // SAFETY: indices are below the arrays' length (a run's last index is one of them);
        // tethered particles are distinct and the caller's task owns them.
        let pi = unsafe {
            if run {
                p.load_run(i0 as usize)
            } else {
                p.gather(&ii)
            }
        };
        let d = pi - pa;
        let len = d.length_sq().sqrt();
        let l = load(&self.max_len, k);
        let over = len.simd_gt(l);
        if !over.any() {
            return;
        }
        let s = over.select(l / len, F32s::ONE);
        let out = Vec3x8::select(over, pa + d.scale(s), pi);
        // SAFETY: as above.
        unsafe {
            if run {
                p.store_run(i0 as usize, out);
            } else {
                p.scatter(&ii, out);
            }
        }
    }
}

/// Seven consecutive arrays of `m` values.
fn split7(s: &mut [f32], m: usize) -> [&mut [f32]; 7] {
    let mut it = s.chunks_exact_mut(m);
    std::array::from_fn(|_| it.next().expect("seven arrays"))
}

/// One tether: the particle at `pi` pulled back to `max_len` from the anchor at `pa`, when
/// farther (`None` when not).
#[inline(always)]
fn project1(pi: [f32; 3], pa: [f32; 3], max_len: f32) -> Option<[f32; 3]> {
    let (dx, dy, dz) = (pi[0] - pa[0], pi[1] - pa[1], pi[2] - pa[2]);
    let len = (dx * dx + dy * dy + dz * dz).sqrt();
    if len > max_len {
        let s = max_len / len;
        Some([pa[0] + dx * s, pa[1] + dy * s, pa[2] + dz * s])
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simd_matches_scalar_and_limits_length() {
        let n = 40;
        let len = round_up(n + 1);
        let mut x: Vec<f32> = (0..len).map(|i| (i as f32 * 0.37).sin() * 3.0).collect();
        let mut y: Vec<f32> = (0..len).map(|i| (i as f32 * 0.11).cos() * 3.0).collect();
        let mut z: Vec<f32> = (0..len).map(|i| i as f32 * 0.01).collect();
        let tethers: Vec<Tether> = (1..n as u32)
            .map(|i| Tether {
                particle: i,
                anchor: 0,
                max_len: 1.0 + (i % 3) as f32,
            })
            .collect();
        let mut set = TetherSet::new(&tethers, (len - 1) as u32);
        let (mut x2, mut y2, mut z2) = (x.clone(), y.clone(), z.clone());
        set.solve_scalar(&mut x, &mut y, &mut z);
        set.solve_simd(&mut x2, &mut y2, &mut z2, true);
        assert_eq!(x, x2);
        assert_eq!(y, y2);
        assert_eq!(z, z2);
        for t in &tethers {
            let i = t.particle as usize;
            let d = ((x[i] - x[0]).powi(2) + (y[i] - y[0]).powi(2) + (z[i] - z[0]).powi(2)).sqrt();
            assert!(d <= t.max_len * (1.0 + 1e-5), "{d} > {}", t.max_len);
        }
    }

    /// Every path of the lane kernel equals the scalar twin: blocks of consecutive particles
    /// with one anchor (runs, the anchor read once), consecutive particles whose anchors differ
    /// (alternating, or only the first lane's), particles out of order (gather and scatter),
    /// a block with no tether over its length (nothing written) and the padding.
    #[test]
    fn every_block_path_matches_scalar() {
        let n = 200usize;
        let len = round_up(n + 1);
        let mut tethers = Vec::new();
        // Runs from particle 2 on: tethers 0..8 slack, one block of anchor 0 alone, one whose
        // first lane alone takes anchor 1, then anchors 0 and 1 alternating.
        for i in 2..120u32 {
            let anchor = match i {
                26 => 1,
                40.. => i % 2,
                _ => 0,
            };
            let max_len = if i < 10 { 1e3 } else { 0.5 + (i % 5) as f32 * 0.3 };
            tethers.push(Tether {
                particle: i,
                anchor,
                max_len,
            });
        }
        // Out of order: descending indices.
        for i in (120..n as u32).rev() {
            tethers.push(Tether {
                particle: i,
                anchor: 1,
                max_len: 0.8,
            });
        }
        let mut set = TetherSet::new(&tethers, (len - 1) as u32);
        let start: [Vec<f32>; 3] = std::array::from_fn(|a| (0..len).map(|i| ((i * (a + 3)) as f32 * 0.29).sin() * 4.0).collect());
        let mut want = start.clone();
        let [wx, wy, wz] = &mut want;
        set.solve_scalar(wx, wy, wz);
        let moved = (0..n).filter(|&i| (0..3).any(|a| want[a][i] != start[a][i])).count();
        assert!(moved > 100, "{moved} particles moved");
        assert!((2..10).all(|i| (0..3).all(|a| want[a][i] == start[a][i])), "the slack block stays");
        for parallel in [false, true] {
            let mut got = start.clone();
            let [gx, gy, gz] = &mut got;
            set.solve_simd(gx, gy, gz, parallel);
            assert_eq!(got, want, "parallel {parallel}");
        }
    }

    /// Particle ranges of any length, cut anywhere (inside a block of eight tethers, around
    /// particles with no tether), each solved with `solve_range` on its own slice of the
    /// arrays, give the bits of the whole sweep.
    #[test]
    fn ranges_equal_the_whole_sweep() {
        let n = 300usize;
        let len = round_up(n + 1);
        // particles 3..250 tethered in order, except every seventh, to anchors 0 and 1
        let tethers: Vec<Tether> = (3..250u32)
            .filter(|i| i % 7 != 0)
            .map(|i| Tether {
                particle: i,
                anchor: u32::from(i % 3 == 0),
                max_len: 0.4 + (i % 4) as f32 * 0.2,
            })
            .collect();
        let mut set = TetherSet::new(&tethers, (len - 1) as u32);
        assert!(set.by_range());
        let start: [Vec<f32>; 3] = std::array::from_fn(|a| (0..len).map(|i| ((i * (a + 2)) as f32 * 0.41).cos() * 3.0).collect());
        let mut want = start.clone();
        let [wx, wy, wz] = &mut want;
        set.solve_simd(wx, wy, wz, false);
        let moved = (0..n).filter(|&i| (0..3).any(|a| want[a][i] != start[a][i])).count();
        assert!(moved > 100, "{moved} particles moved");
        for cuts in [vec![0, len], vec![0, 5, 17, 18, 130, len], vec![0, 100, 101, 102, 240, 241, len]] {
            let mut got = start.clone();
            let [gx, gy, gz] = &mut got;
            set.take_anchors(gx, gy, gz);
            for r in cuts.windows(2) {
                let (a, b) = (r[0], r[1]);
                set.solve_range(a..b, &mut gx[a..b], &mut gy[a..b], &mut gz[a..b]);
            }
            assert_eq!(got, want, "cuts {cuts:?}");
        }
    }
}
