//! The near list: the candidate pairs the substeps test, kept across substeps (exact, like the
//! candidate lists of [`crate::self_collision::verlet`]; the method is described in
//! [`crate::self_collision`]).
//!
//! A contact needs `|p_i - p_j| < d` for the predicted positions `p`. The near list holds the
//! candidate pairs within `d + s₂` of the positions `y` of its build (a substep's `p`); while
//! every particle of the active blocks stays within `0.49 s₂` of `y`, a pair in contact is in
//! it. The substeps test only the near pairs, and a pair also has to be within `q` at the
//! step's start (in the lists of the step), exactly as the fresh path requires. The skin `s₂`
//! adapts: it is sized to last [`NEAR_LIFETIME`] substeps at the fastest particle's rate
//! since the last build, within `[NEAR_SKIN_FLOOR d, cap]`.
//!
//! # Mid list
//! Once the cloth has folded, the candidate lists carry a wide skin and hold many pairs of one
//! layer that are never near. The near list is then built from a **mid list**: the candidate
//! pairs within `r₁ = d + MID_NEAR_SKIN_MAX d + MID_SKIN d` of its build positions `y₁`, kept
//! while every particle of the active blocks stays within `0.49 MID_SKIN d` of `y₁`. Exact: a
//! pair within `d + s₂` (`s₂ <= MID_NEAR_SKIN_MAX d` on this path) at a near build was within
//! `d + s₂ + 0.98 MID_SKIN d < r₁` at `y₁`, so the near list built from the mid list is the one
//! built from the candidates (the tests check it at every rebuild). The mid list is used only
//! when the candidate reach is at least `MID_REACH_RATIO r₁`; with a smaller reach (a falling
//! cloth) it would hold nearly every candidate, so the near list is filtered from the
//! candidate lists directly, copied once into pairs and tested eight at a time.
//!
//! On slow steps with the hash there are no candidate lists (see [`crate::self_collision::verlet`]): the
//! mid list is then queried from a hash built on the predicted positions ([`MidSource::Hash`]):
//! every pair within `r₁` but the rest neighbours, all blocks active. When only a few particles
//! pass their bound, they alone are refreshed, or the hash is rebuilt from the references
//! (module `self_mid`; the same lists).
//!
//! # Scans
//! Only the active blocks are checked for displacement and copied
//! (`self_near_moves::max_disp2_blocks`): every near pair has both ends in them. A rebuild tests eight candidates at a time from an `[x, y, z, 0]` copy of the
//! positions, and runs in parallel over ranges of particles of about
//! [`NEAR_CHUNK`](crate::self_collision::near::scan::NEAR_CHUNK) candidate entries, each range into its own
//! buffer, joined in order: the same list on any thread count. The eight-lane gathers take no
//! per-lane bounds check (the largest index is checked once a scan); the scalar paths of
//! [`collect`] and [`filter_pairs`] are the twins and give the same lists.

pub(crate) mod mid;
pub(crate) mod moves;
pub(crate) mod scan;

use crate::data::exec::Exec;
use crate::data::lanes::LANES;
use crate::self_collision::near::mid::{merge_unique, HashedMid, RestRule};
use crate::self_collision::near::moves::{as_refs, copy_blocks, max_disp2_blocks};
use crate::self_collision::near::scan::{collect, filter_pairs, filter_range, ScanScratch};
use crate::self_collision::neighbours::Neighbours;
use crate::self_collision::verlet::SAFE;

/// Largest near-list skin over the collision distance (the adaptive skin's cap) when the
/// near list is built from the candidates directly.
pub(crate) const NEAR_SKIN_MAX: f32 = 1.0;

/// The cap when it is built from the mid list (the mid radius allows for it): the floor, so
/// on the mid path the skin is `d / 8` (see the module docs).
pub(crate) const MID_NEAR_SKIN_MAX: f32 = NEAR_SKIN_FLOOR;

/// Smallest near-list skin over the collision distance (where a settled cloth's skin sits).
pub(crate) const NEAR_SKIN_FLOOR: f32 = 0.125;

/// Substeps the near skin is sized to last, at the fastest particle's rate since the last
/// build (see the module docs).
pub(crate) const NEAR_LIFETIME: f32 = 5.0;

/// Skin of the mid list over the collision distance: its pairs are those within
/// `d + MID_NEAR_SKIN_MAX d + MID_SKIN d` of its build, kept while no particle of the active
/// blocks moves more than `0.49 MID_SKIN d` from it (see the module docs).
pub(crate) const MID_SKIN: f32 = 1.0;

/// The mid list is used when the candidate lists' reach is at least this many times its
/// radius (with a smaller reach it holds nearly every candidate and only adds a pass).
pub(crate) const MID_REACH_RATIO: f32 = 1.5;

/// Near pairs of the candidate lists for the substeps (see the module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct NearList {
    /// Pairs `(i, j)`, `i < j`, ordered by `i` then `j`.
    pub(crate) pairs: Vec<(u32, u32)>,
    /// Positions of the build (the active blocks' particles, block by block).
    at: [Vec<f32>; 3],
    skin: f32,
    valid: bool,
    subs_since: u32,
    /// Builds so far.
    pub(crate) rebuilds: u64,
    /// The mid list the near list is built from (pairs `(i, j)`, `i < j`, ordered by `i` then
    /// `j`).
    mid: Vec<(u32, u32)>,
    /// Positions of the mid list's build (like `at`).
    mid_at: [Vec<f32>; 3],
    mid_valid: bool,
    /// Mid-list builds so far.
    pub(crate) mid_rebuilds: u64,
    /// The hash of the mid list's last query ([`MidSource::Hash`]) and its refreshes.
    pub(crate) hashed: HashedMid,
    /// The refreshes' pairs within the near radius, and the merge's buffer.
    extra_near: Vec<(u32, u32)>,
    merged: Vec<(u32, u32)>,
    scratch: ScanScratch,
    /// The candidate lists as pairs, in list order, for the near rebuilds straight from them
    /// (made at the first such rebuild after [`NearList::invalidate`]).
    cand_pairs: Vec<(u32, u32)>,
    cand_pairs_valid: bool,
}

/// Where a mid list comes from.
pub(crate) enum MidSource<'a> {
    /// The candidate lists, reaching `reach` around the positions of their build.
    Candidates { cand: &'a Neighbours, reach: f32 },
    /// A query of the hash, rebuilt on the predicted positions (a slow step without candidate
    /// lists): every pair within the mid radius but the rest neighbours (rest distance at
    /// most `skip`, with the cloths' rest positions and cloth ids).
    Hash(RestRule<'a>),
}

/// What became of the mid list in an update.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MidUpdate {
    /// Kept as it was, or built from the candidate lists.
    Kept,
    /// Queried from a hash built afresh.
    Queried,
    /// Refreshed for the particles that moved (module `self_mid`).
    Refreshed,
}

impl NearList {
    /// Forgets the lists (new candidate lists).
    pub(crate) fn invalidate(&mut self) {
        self.valid = false;
        self.mid_valid = false;
        self.cand_pairs_valid = false;
    }

    /// Makes the list hold for the predicted positions `p`: kept if no particle of the active
    /// `blocks` (ascending; every candidate pair has both ends in them) moved more than
    /// `0.49 s₂` since the build, else rebuilt with a new skin from the mid list, itself
    /// rebuilt from `source` first when one of those particles moved more than
    /// `0.49 MID_SKIN d` since its build. Only the active blocks are checked and copied:
    /// before the fold they are a few, and the particles outside them have no candidate. The
    /// scans run in parallel over ranges of particles when `parallel` (the same lists).
    /// Returns what became of the mid list.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn update(&mut self, source: MidSource<'_>, p: [&[f32]; 3], blocks: &[u32], n: usize, d: f32, exec: Exec) -> MidUpdate {
        let simd = exec.simd();
        // The mid list is used when the candidates reach well past its radius (the wide
        // skin of a folded cloth) or come from the hash (see the module docs).
        let r_mid = d * (1.0 + MID_NEAR_SKIN_MAX + MID_SKIN);
        let use_mid = match &source {
            MidSource::Candidates { reach, .. } => *reach >= MID_REACH_RATIO * r_mid,
            MidSource::Hash(_) => true,
        };
        let cap = if use_mid { MID_NEAR_SKIN_MAX } else { NEAR_SKIN_MAX } * d;
        if self.valid && self.at[0].len() == blocks.len() * LANES {
            let m2 = max_disp2_blocks(p, as_refs(&self.at), blocks, simd);
            let lim = 0.5 * SAFE * self.skin;
            self.subs_since += 1;
            if m2 <= lim * lim {
                return MidUpdate::Kept;
            }
            // Aim at about NEAR_LIFETIME substeps between builds, within [floor, cap].
            let rate = if m2.is_finite() { m2.sqrt() / self.subs_since as f32 } else { d };
            self.skin = (NEAR_LIFETIME * rate).clamp(NEAR_SKIN_FLOOR * d, cap);
        } else if !self.valid {
            self.skin = 0.25 * d;
        }
        // Within the cap of the path taken whatever happened before (the mid radius relies
        // on it).
        self.skin = self.skin.min(cap);
        copy_blocks(p, blocks, &mut self.at);
        let r = d + self.skin;
        let mut mid = MidUpdate::Kept;
        match source {
            MidSource::Candidates { cand, .. } if !use_mid => {
                self.mid_valid = false;
                if !self.cand_pairs_valid {
                    self.cand_pairs.clear();
                    let m = n.min(cand.len());
                    self.cand_pairs
                        .extend((0..m).flat_map(|i| cand.of(i).iter().map(move |&j| (i as u32, j))));
                    self.cand_pairs_valid = true;
                }
                filter_pairs(&self.cand_pairs, p, n, r, exec, &mut self.scratch, &mut self.pairs);
            }
            source => {
                mid = self.update_mid(source, p, blocks, n, d, exec);
                filter_pairs(&self.mid, p, n, r, exec, &mut self.scratch, &mut self.pairs);
                let extra = self.hashed.extra();
                if !extra.is_empty() {
                    // The refreshes' pairs (module `self_mid`): filtered alike, then merged in
                    // order, a pair in both lists once.
                    self.extra_near.clear();
                    filter_range(extra, p, r, simd, &self.scratch.xyz, &mut self.extra_near);
                    merge_unique(&mut self.pairs, &self.extra_near, &mut self.merged);
                }
            }
        }
        self.valid = true;
        self.subs_since = 0;
        self.rebuilds += 1;
        mid
    }

    /// Keeps the mid list if no particle of `blocks` moved more than `0.49 MID_SKIN d` since
    /// its build, else rebuilds it from `source` at `p`: the pairs within
    /// `d + (MID_NEAR_SKIN_MAX + MID_SKIN) d`. A near pair (within `d + s₂`,
    /// `s₂ <= MID_NEAR_SKIN_MAX d`, at `p`) was then within `d + s₂ + 0.98 MID_SKIN d` at the
    /// mid build, so it is in the mid list: the near list built from it is the one built from
    /// the candidates, or from every pair. From the hash, only the particles past the bound
    /// are refreshed when that is possible (module `self_mid`; the same list).
    #[allow(clippy::too_many_arguments)]
    fn update_mid(&mut self, source: MidSource<'_>, p: [&[f32]; 3], blocks: &[u32], n: usize, d: f32, exec: Exec) -> MidUpdate {
        let (parallel, simd) = (exec.parallel(), exec.simd());
        let lim = 0.5 * SAFE * MID_SKIN * d;
        let r = d * (1.0 + MID_NEAR_SKIN_MAX + MID_SKIN);
        if self.mid_valid && self.mid_at[0].len() == blocks.len() * LANES {
            let m2 = max_disp2_blocks(p, as_refs(&self.mid_at), blocks, simd);
            if m2 <= lim * lim {
                return MidUpdate::Kept;
            }
            if let MidSource::Hash(rule) = &source {
                if m2.is_finite()
                    && self
                        .hashed
                        .refresh(p, &mut self.mid_at, blocks, n, lim, r, *rule, &mut self.mid, exec)
                {
                    return MidUpdate::Refreshed;
                }
            }
        }
        copy_blocks(p, blocks, &mut self.mid_at);
        self.mid_rebuilds += 1;
        match source {
            MidSource::Candidates { cand, .. } => {
                collect(cand, p, n, r, exec, &mut self.scratch, &mut self.mid);
                self.hashed.forget();
                self.mid_valid = true;
                MidUpdate::Kept
            }
            MidSource::Hash(rule) => {
                // Every pair within `r` of `p` but the rest neighbours, each once; a failed
                // build (non-finite positions) leaves an empty, invalid mid list, like the
                // failed broadphase of a step start.
                self.mid_valid = self.hashed.build(p, n, r, rule, parallel, &mut self.mid);
                MidUpdate::Queried
            }
        }
    }

    /// Parts the last rebuild's scan ran in (particle ranges of the candidate lists or
    /// fixed chunks of pairs; 0 or 1: built serially).
    #[cfg(test)]
    pub(crate) fn ranges(&self) -> usize {
        self.scratch.parts
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod prop_tests;
