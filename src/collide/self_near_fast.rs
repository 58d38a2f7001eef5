//! The near list's fast particles (session 10; the near list is described in
//! [`super::self_near`]).
//!
//! # A wider skin for a few particles
//! The near list keeps every pair within `d + s` of its build positions `y` while each
//! particle stays within `0.49 s` of its own `y_i`. Nothing asks the skin to be one number:
//! give particle `i` the skin `s_i` and keep the pairs within `d + max(s_i, s_j)`; a pair left
//! out is then farther than `d + max(s_i, s_j) - 0.49 s_i - 0.49 s_j > d` while every particle
//! stays within `0.49 s_i`. So the near list has two skins: `s` for the bulk of the cloth,
//! sized for [`super::self_near::NEAR_LIFETIME`] substeps at the rate of the fastest of them,
//! and the cap (`wide`) for at most [`FAST_MAX`] *fast* particles. The cap is the bound the
//! mid list assumes of the near skin, so the mid list still holds every pair needed.
//!
//! At a rebuild from the mid list (a folded cloth) the particles that passed the bulk's bound
//! (`0.49 s`) become the fast set if there are at most [`FAST_MAX`] of them and the set pays:
//! the bulk's skin sized without them is narrower than the one sized with them, or some were
//! fast already and passed the bound again since the last build (a particle going back and
//! forth can be near its build position at the rebuild; dropped, it forces the next one).
//! Past that many the motion is collective and one skin is sized from the fastest particle,
//! as before; while the cloth falls (no mid list) there is no split at all. The check between
//! rebuilds masks the fast particles out of the bulk's eight-lane scan
//! ([`super::self_near_moves::max_disp2_blocks`]) and tests them one by one against their own
//! bound, recording each one's largest displacement. The scans of the rebuild read each
//! particle's widening `wide - s` (0 for the bulk) beside its position
//! ([`super::self_near_scan::Reach`]); with no fast particle they run the single-radius loops,
//! the same lists to the bit as before.
//!
//! # Why
//! On the 100x100 basic fold with the movement-speed response a handful of particles near an
//! edge (5201, 4801, 4701 of the grid) move ~0.09 d in a substep, back and forth, while the
//! 1% fastest of the rest move ~0.006 d. With one skin, each of them either set the skin to
//! its cap for a while (~14 000 near pairs tested every substep, against ~3 500 for VcCPBD)
//! or forced a rebuild every one to four substeps.
//!
//! Measured on one thread, alternate runs against the build before (two each):
//! * `examples/self_collision_timeline 150 1 movement-speed basic`: pairs column over the run
//!   55.0-56.4 -> 49.4-49.8 ms, steps 110-149 3.2-3.3 -> 2.0-2.4 ms a ten steps; near pairs
//!   tested over the substeps of the folded cloth (instrumented) 7.1 -> 4.5 million, with
//!   145 near builds against 91. VcCPBD: 3.36 -> 3.26 million, 118 -> 112 builds; cotton
//!   VcCPBD 1.14 -> 1.11 million;
//! * `weft reproduce vccpbd --size 100 --repeat 3`, first round: movement-speed rows basic
//!   0.622-0.632 -> 0.597-0.613 ms collision a step, cotton 0.482-0.485 -> 0.446-0.455, wool
//!   0.482-0.490 -> 0.470-0.478, polyester 0.495-0.504 -> 0.468-0.482; the VcCPBD and PBD rows
//!   within their noise; the 12 hash rows' sum 5.91-5.95 -> 5.76-5.87 ms. Second round (the
//!   final form, a faster spell of the VM): movement speed basic 0.604-0.609 -> 0.590-0.596,
//!   cotton 0.465-0.476 -> 0.448-0.452, wool 0.475 -> 0.454-0.460, polyester 0.482-0.483 ->
//!   0.470-0.475; but cotton VcCPBD 0.415-0.423 -> 0.426-0.439 and wool VcCPBD 0.425-0.428
//!   -> 0.432-0.438; the sum 5.70-5.73 -> 5.69-5.78;
//! * callgrind, timeline 150 steps: basic VcCPBD 3 856 -> 3 874 million instructions, cotton
//!   VcCPBD 3 557 -> 3 581 (+0.7%: the split at each rebuild, the masked check, a loop of the
//!   fall's scans that got an instruction longer a particle); three alternate timeline runs
//!   of cotton VcCPBD: stage 65.5-68.6 -> 68.2-69.0 ms, PBD 66.0-68.2 -> 66.6-67.2. No split
//!   when there is no fast set and the skin is at its floor anyway (the settled cloth's
//!   rebuilds; the same decisions): cotton VcCPBD 3 581 -> 3 570 million.
//!
//! So the movement-speed rows gain 2-8% and the other responses lose up to ~3%, within or
//! near their noise; kept because it removes the movement-speed fold's pathology (its pair
//! tests now match the other responses') and the list stays exact.
//!
//! The first version split at every rebuild, also while the cloth falls, and recorded every
//! particle past the bound: the fall's pair column went from ~1.0 to 1.2 ms a ten steps (the
//! fall passes thousands of particles at a time); a first fill of the `[x, y, z, g]` copy read
//! the widening with a bounds check per particle and cost five times the fall's pair column.

use super::self_near_scan::Reach;
use crate::lanes::{load, F32s, LANES};

/// Most particles the near list gives the wide skin (more of them past the bound at a
/// rebuild: the motion is collective and one skin serves better).
pub(crate) const FAST_MAX: usize = 16;

/// What [`FastSet::split`] found in the displacements since the build.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Split {
    /// Largest squared displacement (infinity when one is NaN).
    pub(crate) all: f32,
    /// Largest squared displacement among the particles within the bound.
    pub(crate) bulk: f32,
    /// Particles past the bound (or NaN).
    pub(crate) over: usize,
}

/// The fast particles of the near list's last build and the arrays that give them their skin.
#[derive(Clone, Debug, Default)]
pub(crate) struct FastSet {
    /// The fast particles and their slots in the build copy (block `k` of the active blocks at
    /// slots `8 k..8 k + 8`).
    ids: Vec<u32>,
    slots: Vec<u32>,
    /// Each one's largest squared displacement at the checks since the build.
    peak: Vec<f32>,
    /// The new set while it is made.
    next: Vec<(u32, u32)>,
    /// Per slot of the build copy: 0 for a fast particle, else 1 (empty while there is none).
    mask: Vec<f32>,
    /// The fast particles' skin, and the bulk's at the build.
    wide: f32,
    skin: f32,
    /// [`FastSet::split`]'s particles past the bound (particle, slot): at most `FAST_MAX + 1`;
    /// and the square of that bound.
    over: Vec<(u32, u32)>,
    lim2: f32,
}

impl FastSet {
    /// The fast particles (ascending).
    #[cfg(test)]
    pub(crate) fn ids(&self) -> &[u32] {
        &self.ids
    }

    /// The bulk's mask of the build copy's slots, `None` without fast particles.
    pub(crate) fn mask(&self) -> Option<&[f32]> {
        (!self.ids.is_empty()).then_some(&self.mask[..])
    }

    /// The radius of the near list's scans for the bulk's radius `r` (`r + wide - skin` for
    /// the pairs with a fast end).
    pub(crate) fn reach(&self, r: f32) -> Reach<'_> {
        Reach {
            r,
            wide: self.wide - self.skin,
            fast: &self.ids,
        }
    }

    /// Whether a fast particle moved more than `0.49 wide` from its build position `at` (or
    /// has a NaN coordinate); records each one's largest displacement since the build.
    pub(crate) fn passed(&mut self, p: [&[f32]; 3], at: [&[f32]; 3]) -> bool {
        let lim = 0.5 * super::self_verlet::SAFE * self.wide;
        let mut out = false;
        for ((&i, &c), peak) in self.ids.iter().zip(&self.slots).zip(&mut self.peak) {
            let (i, c) = (i as usize, c as usize);
            let d2: f32 = (0..3).map(|k| (p[k][i] - at[k][c]) * (p[k][i] - at[k][c])).sum();
            *peak = peak.max(d2);
            out |= d2 > lim * lim || d2.is_nan();
        }
        out
    }

    /// Whether a fast particle passed the bound of the last [`FastSet::split`] at a check
    /// since the build (it stays fast at the rebuild).
    pub(crate) fn kept_any(&self) -> bool {
        self.peak.iter().any(|&p| p > self.lim2)
    }

    /// Drops the fast particles (one skin for all).
    pub(crate) fn clear(&mut self) {
        self.ids.clear();
        self.slots.clear();
        self.peak.clear();
    }

    /// Splits the particles of `blocks` (build copy `at`, block `k` at `at[8 k..]`) by their
    /// displacement: past `lim` (remembered, up to `FAST_MAX + 1` of them) or within it. Eight
    /// lanes at a time when `simd`, else one particle at a time (the twin; the same result).
    pub(crate) fn split(&mut self, p: [&[f32]; 3], at: [&[f32]; 3], blocks: &[u32], lim: f32, simd: bool) -> Split {
        let lim2 = lim * lim;
        self.lim2 = lim2;
        let len = p[0].len().min(p[1].len()).min(p[2].len());
        let (mut all, mut bulk, mut over) = (0.0f32, 0.0f32, 0usize);
        let (mut all_v, mut bulk_v, zero) = (F32s::splat(0.0), F32s::splat(0.0), F32s::splat(0.0));
        let mut nan = false;
        self.over.clear();
        let mut past = |i: usize, c: usize, over: &mut usize| {
            *over += 1;
            if self.over.len() <= FAST_MAX {
                self.over.push((i as u32, c as u32));
            }
        };
        for (k, &b) in blocks.iter().enumerate() {
            let (g, c) = (b as usize * LANES, k * LANES);
            if simd && g + LANES <= len {
                let vx = load(p[0], g) - load(at[0], c);
                let vy = load(p[1], g) - load(at[1], c);
                let vz = load(p[2], g) - load(at[2], c);
                let d2 = vx * vx + vy * vy + vz * vz;
                let out = d2.simd_gt(F32s::splat(lim2)) | d2.is_nan();
                nan |= d2.is_nan().any();
                all_v = all_v.max(d2);
                bulk_v = bulk_v.max(out.select(zero, d2));
                let mut bits = out.to_bitmask();
                if over > FAST_MAX {
                    // Past the fast set's size only the count matters (the fall of a cloth
                    // passes thousands of particles at a time).
                    over += bits.count_ones() as usize;
                    bits = 0;
                }
                while bits != 0 {
                    let l = bits.trailing_zeros() as usize;
                    past(g + l, c + l, &mut over);
                    bits &= bits - 1;
                }
                continue;
            }
            for l in 0..LANES.min(len.saturating_sub(g)) {
                let (vx, vy, vz) = (p[0][g + l] - at[0][c + l], p[1][g + l] - at[1][c + l], p[2][g + l] - at[2][c + l]);
                let d2 = vx * vx + vy * vy + vz * vz;
                nan |= d2.is_nan();
                all = all.max(d2);
                if d2 > lim2 || d2.is_nan() {
                    past(g + l, c + l, &mut over);
                } else {
                    bulk = bulk.max(d2);
                }
            }
        }
        let all = all_v.to_array().into_iter().fold(all, f32::max);
        let bulk = bulk_v.to_array().into_iter().fold(bulk, f32::max);
        Split {
            all: if nan { f32::INFINITY } else { all },
            bulk,
            over,
        }
    }

    /// Makes the fast set the particles [`FastSet::split`] found past its bound, and the fast
    /// particles of the last build that passed that bound at a check since (one going back
    /// and forth may be near its build position at the rebuild; dropped, it would force the
    /// next one). The skin is `wide` against the bulk's `skin` (`slots` in the build copy).
    /// With more than [`FAST_MAX`] of them, none past the bound, or `wide <= skin`, there is
    /// no fast set. Returns whether there is one.
    pub(crate) fn set(&mut self, slots: usize, skin: f32, wide: f32) -> bool {
        let lim2 = self.lim2;
        self.over.sort_unstable();
        let over = &self.over;
        // Past the bound at a check since the build, and not past it now.
        let kept = self
            .ids
            .iter()
            .zip(&self.slots)
            .zip(&self.peak)
            .filter(|&((&i, &c), &peak)| peak > lim2 && (c as usize) < slots && over.binary_search_by_key(&i, |o| o.0).is_err());
        self.next.clear();
        self.next.extend(over.iter().copied());
        self.next.extend(kept.map(|((&i, &c), _)| (i, c)));
        self.clear();
        if self.over.is_empty() || self.next.len() > FAST_MAX || wide <= skin {
            return false;
        }
        // In particle order (`Reach` searches the ids).
        self.next.sort_unstable();
        self.mask.clear();
        self.mask.resize(slots, 1.0);
        for &(i, c) in &self.next {
            self.ids.push(i);
            self.slots.push(c);
            self.peak.push(0.0);
            self.mask[c as usize] = 0.0;
        }
        (self.wide, self.skin) = (wide, skin);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::signed;

    /// The split's eight-lane scan and its scalar twin agree (counts, maxima, the particles
    /// found), also with a NaN and a partial last block; `set` then widens and masks exactly
    /// the particles found, and `clear` undoes it.
    #[test]
    fn split_simd_equals_scalar_and_set_marks_the_particles_past_the_bound() {
        let mut rng = signed(5);
        let n = 8 * 9 + 3;
        let at_p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| rng()).collect());
        let mut p = at_p.clone();
        for (k, a) in p.iter_mut().enumerate() {
            for (i, x) in a.iter_mut().enumerate() {
                *x += if [3, 30, 70, 73].contains(&i) { 0.5 } else { 0.01 * rng() } * [0.6, 0.8, 0.0][k];
            }
        }
        let blocks: Vec<u32> = vec![0, 2, 8, 9];
        // The build copy of those blocks (block 9 is partial: zeros past the end).
        let at: [Vec<f32>; 3] = std::array::from_fn(|k| {
            blocks
                .iter()
                .flat_map(|&b| (0..LANES).map(move |l| b as usize * LANES + l))
                .map(|i| at_p[k].get(i).copied().unwrap_or(0.0))
                .collect()
        });
        let (pr, ar) = ([&p[0][..], &p[1][..], &p[2][..]], [&at[0][..], &at[1][..], &at[2][..]]);
        let mut got = Vec::new();
        for simd in [false, true] {
            let mut f = FastSet::default();
            let s = f.split(pr, ar, &blocks, 0.1, simd);
            got.push((s, f.over.clone()));
        }
        assert_eq!(got[0], got[1]);
        let (s, over) = got[0].clone();
        // Particle 3 (block 0), 70 and 73 (blocks 8 and 9); 30 is in an inactive block.
        assert_eq!(over, vec![(3, 3), (70, 22), (73, 25)]);
        assert_eq!(s.over, 3);
        assert!(s.all >= 0.24 && s.bulk > 0.0 && s.bulk <= 0.01, "{s:?}");
        let mut f = FastSet::default();
        f.split(pr, ar, &blocks, 0.1, true);
        assert!(f.set(at[0].len(), 0.1, 0.4));
        assert_eq!(f.ids(), &[3, 70, 73]);
        let reach = f.reach(1.0);
        assert!((0..n).all(|i| reach.grow_of(i) == if [3, 70, 73].contains(&i) { 0.3f32 } else { 0.0 }));
        assert_eq!((reach.r2(3, 4), reach.r2(5, 4)), (1.3 * 1.3, 1.0));
        let mask = f.mask().unwrap();
        assert!(mask
            .iter()
            .enumerate()
            .all(|(c, &m)| m == if [3, 22, 25].contains(&c) { 0.0 } else { 1.0 }));
        // Within 0.49 of the wide skin (0.4): 0.5 moved is past it.
        assert!(f.passed(pr, ar));
        // Back at their build positions: not past it.
        let mut back = p.clone();
        for i in [3usize, 70, 73] {
            let c = over.iter().find(|o| o.0 as usize == i).unwrap().1 as usize;
            for k in 0..3 {
                back[k][i] = at[k][c];
            }
        }
        assert!(!f.passed([&back[0][..], &back[1][..], &back[2][..]], ar));
        f.clear();
        assert!(f.ids().is_empty() && f.reach(1.0).fast.is_empty() && f.mask().is_none());
        // NaN: counted past the bound, `all` infinite.
        p[1][20] = f32::NAN;
        let pr = [&p[0][..], &p[1][..], &p[2][..]];
        for simd in [false, true] {
            let s = f.split(pr, ar, &blocks, 0.1, simd);
            assert_eq!((s.all, s.over), (f32::INFINITY, 4), "simd {simd}");
        }
        // More than FAST_MAX past the bound: no fast set.
        let s = f.split(pr, ar, &blocks, 0.0, true);
        assert!(s.over > FAST_MAX);
        assert!(!f.set(at[0].len(), 0.1, 0.4));
        assert!(f.ids().is_empty());
    }
}
