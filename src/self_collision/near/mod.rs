//! The near list: the candidate pairs the substeps test, kept across substeps (exact, like the
//! candidate lists of [`crate::self_collision::verlet`]; the method is described in
//! [`crate::self_collision`]).
//!
//! A contact needs `|p_i - p_j| < d` for the predicted positions `p`. The near list holds the
//! candidate pairs within `d + s₂` of the positions `y` of its build (a substep's `p`); while
//! every particle of the active blocks stays within `0.49 s₂` of `y`, a pair in contact is in
//! it. The substeps test only the near pairs, and a pair also has to be within `q` at the
//! step's start (in the lists of the step), exactly as the fresh path requires.
//!
//! # Mid list (session 7)
//! Once the cloth has folded, the candidate lists are built with a skin of `3 d` (reach
//! `6 d`): ~763 000 pairs on the 100x100 fold, mostly pairs of one layer between `3 d` and
//! `6 d` apart at rest that are never near. Each near rebuild walked all of them (timers: 59
//! rebuilds over lists above 500 000 pairs, 28 of the stage's ~140 ms on one thread). The near
//! list is now built from a **mid list**: the candidate pairs within
//! `r₁ = d + MID_NEAR_SKIN_MAX d + MID_SKIN d` (`2.5 d`, ~66 000 pairs on the fold) of its
//! build positions `y₁`, kept while every particle of the active blocks stays within
//! `0.49 MID_SKIN d` of `y₁`. Exact: a pair within `d + s₂` (`s₂ <= MID_NEAR_SKIN_MAX d`, the
//! near skin's cap while the mid list is in use) at a near build was within
//! `d + s₂ + 0.98 MID_SKIN d < r₁` at `y₁`, so the near list built from the mid list is the one
//! built from the candidates (tested at every rebuild; a mid radius of `2 d` fails the test).
//! The mid list is used only when the candidate reach is at least `MID_REACH_RATIO r₁`: while
//! the cloth falls the reach is `3 d` and the mid list would hold nearly every candidate (an
//! extra pass at every rebuild cost ~0.5 ms a step over steps 41-50); there the near list is
//! built from the candidates with the skin capped at `NEAR_SKIN_MAX d` as before.
//! Measured with `examples/self_collision_timeline` (basic VcCPBD, 150 steps, alternate runs,
//! ms over the run's segments, steps 47-99 folding and 100-149 settled): one thread, pairs
//! column folding 38.6-39.8 -> 31.3-33.0, settled 16.9-17.9 -> 12.1-12.3, the step of the
//! wide rebuild 1.9-2.0 -> 3.1-3.3 (the mid list's first build), falling unchanged; stage
//! total 141-148 -> 133-142. Two threads: pairs folding 23.8-27.2 -> 21.1-23.2, settled
//! 11.0-13.4 -> 9.3-10.0. (Those figures are for the first version: mid radius `3 d`, the
//! near skin capped at `d` on both paths, ~108 000 mid pairs. Capping the near skin at `d / 2`
//! on the mid path only, which allows the `2.5 d` radius: callgrind over the stage, one
//! thread, 2 111 -> 2 046 million instructions with the cap on both paths; timeline, two
//! threads, three alternate runs: pairs folding 19.9-20.6 -> 17.7-18.3 ms, stage total
//! 85.8-100.6 -> 82.8-86.5.)
//!
//! On slow steps with the hash there are no candidate lists (session 8, see
//! [`crate::self_collision::verlet`]): the mid list is then queried from a hash built on the predicted
//! positions ([`MidSource::Hash`]): every pair within `r₁` but the rest neighbours, all
//! blocks active. The argument above holds with "every pair" for "the candidates".
//!
//! Session 9: each of those mid queries was triggered by 1 to 9 of the 10 000 particles
//! passing the bound (the 100x100 basic fold, 13 queries of ~1.35 ms on one thread). Each
//! particle now keeps its own reference, and only the particles past the bound are refreshed:
//! probed in the hash of the last query, their pairs merged into a short list beside the
//! query's (module `self_mid`; the same near lists). A run then makes 4 queries and ~66
//! refreshes (~0.1 ms each at first, ~40 µs once the merge into the query's list went).
//! Timeline example, basic VcCPBD, 150 steps, one thread, two alternate runs: pairs column
//! 54.1-55.7 -> 43.6 ms, stage 105.5-107.6 -> 94.6-94.8. `MID_SKIN` 0.5 and 0.75 (more
//! queries: the stale particles reach their cap sooner) measured slower (pairs 52-54 and
//! 47 ms), 1.5 and a stale cap four times larger the same within noise.
//!
//! Tried in session 9 and not kept: the near list refreshed per particle the same way (an
//! index of the mid list by particle, the moved particles' pairs re-tested against the other
//! ends' references, exact with a near skin up to `d / 3`). The folded cloth's motion is
//! collective at the near list's scale: ~760 refreshes a run with ~66 particles each (up to
//! ~180), nearly every substep, each scanning all particles; pairs column 44.4-44.5 -> 57.5-58.0
//! ms (adaptive skin) and 62-64 ms (skin fixed at `d / 3`, ~9 500 near pairs).
//!
//! Session 10 gave a few fast particles (at most 16) the skin's cap while the rest of a folded
//! cloth kept a narrow skin (a module `self_near_fast`, removed in session 13, below): on the
//! movement-speed fold a handful of edge particles had set the skin to its cap `d / 2`.
//!
//! Session 13: the cap on the mid path lowered to the floor, `d / 8`, so the skin there is
//! one number and the mid radius `d (1 + 1/8 + 1) = 2.125 d` instead of `2.5 d`: ~28% fewer
//! mid pairs for every near rebuild to filter (the filter and the mid list's upkeep were
//! ~11 of the ~15 ms of the fold's pairs column, steps 46-70, timer probes), against more
//! rebuilds when a few particles move fast (cheap now). The split of session 10 could then
//! never pay, so it went (with the scans' per-pair widening and the masked displacement
//! check). Timeline, one thread, alternate runs, pairs column over the run: VcCPBD
//! 37.4-37.7 -> 34.1-35.5 ms (caps `d / 4` and `3 d / 16`: 38.4-38.6 and 35.2-35.7 against
//! 34.7-35.1 in a faster spell), PBD 37.6-37.7 -> 34.8-34.9, movement speed 44.5-46.0 ->
//! 41.3-42.0; a floor of `d / 16` under the same cap was slower (VcCPBD 35.9-36.2, movement
//! speed 51.6-51.7); `MID_SKIN` 0.75 and 1.25 at the new cap: 38.8-39.4 and 33.8-34.3 against
//! 34.0-34.5, so 1 stays. `weft reproduce vccpbd --size 100 --repeat 3`, two alternate runs
//! (a fast spell): sum of the 12 hash rows 5.12 / 5.09 -> 5.00 / 5.02 ms, basic VcCPBD 0.491 /
//! 0.490 -> 0.484 / 0.473 ms (49.3-49.4x -> 50.1-51.2x); the movement-speed rows of cotton
//! and polyester 3-8% slower (0.398-0.401 -> 0.419-0.431 and 0.417-0.420 -> 0.432-0.434 ms,
//! still 68-76x), the others faster or the same.
//!
//! Session 11: the full queries after the first were all made because the stale particles
//! passed their cap, with 12 to 77 particles moved. The hash is now built again from the
//! references instead (module `self_mid`, "Rehash"): one mid query a basic run instead of
//! four. `weft reproduce vccpbd --size 100 --repeat 3`, one thread, two alternate runs
//! against the session's starting build (so with the session's faster hash build and
//! displacement check too): sum of the 12 hash rows 5.89 / 5.91 -> 5.61 / 5.65 ms, basic
//! VcCPBD 0.570 / 0.566 -> 0.530 / 0.560, PBD 0.582 / 0.571 -> 0.527 / 0.545. With full
//! queries that rare, `MID_SKIN` 0.5 and 0.75 were measured again (timeline, basic VcCPBD,
//! one thread, two alternate runs): 89-90 and 84 ms against 79-80, also with the limit on
//! particles moved at once raised to `n / 8`; and `NEAR_LIFETIME` 4 and 7: no gain. Both stay.
//!
//! With rebuilds that cheap the near skin is sized for `NEAR_LIFETIME = 5` substeps at the
//! fastest particle's rate (20 before): with 20 one fast particle of the movement-speed fold
//! set the skin to its cap and the substeps then tested ~40 000 near pairs for the rest of
//! the run. Timeline, one thread, stage total / pairs column over the run (ms, two runs
//! each): lifetime 20: VcCPBD 128-140 / 58-61, movement speed 155-172 / 87-88; 8: 135-136 /
//! 58-62, 150-164 / 82-91, PBD 126-127 / 59-61; 5: 129-134 / 57-60, 131-141 / 66-70, PBD
//! 121-123 / 56-57; 3: 128-174 / 57-78 (slower with every response).
//!
//! Session 12: the pair pass's candidate test and the filter of the mid list gather without
//! per-lane bounds checks, the largest index of their pairs checked once a scan
//! (`lanes::gather1_unchecked`, `self_near_scan::gather_xyzw8_unchecked`): callgrind over the
//! timeline, one thread, candidate test 158.2 -> 86.0 million instructions, filter 120.5 ->
//! 101.7, pair phase 872.6 -> 783.6; three alternate runs, pairs column 43.6-44.8 -> 41.5-42.6
//! ms. The candidate lists' scan keeps its checks (a check a list, or one over a range's
//! entries, saved nothing: 118.4 -> 131.1 and 117.6 million); the AVX2 hardware gather was
//! slower (see `lanes::gather1`).
//!
//! Session 13: the eight-pair groups of the candidate test, the mid-list filter and the
//! candidate lists' scan are read as fixed-size arrays (`as_chunks`), so taking their indices
//! needs no per-lane bounds checks: callgrind over the timeline, one thread, candidate test
//! 86.0 -> 63.6 million instructions, filter 103.1 -> 99.6, scan 118.4 -> 116.3, pair phase
//! 781.9 -> 753.8; three alternate runs, pairs column 39.1-39.7 -> 38.5-38.8 ms.
//!
//! Session 13: while the cloth falls (near list straight from the candidate lists) the near
//! rebuilds, about four a step, walked all 10 000 lists, most of them empty, and tested each
//! short list's entries one by one; the candidates are now copied once a build into pairs
//! and filtered eight at a time like the mid list (the same list, in the same order). Timer
//! probes over the timeline's segments (one thread): the near rebuilds of steps 0-40 took
//! ~3.5 of the segment's 4.3 ms of pairs column; three alternate runs, steps 0-45's pairs
//! 8.40-8.57 -> 7.92-8.18 ms. (Session 8 had tried the same copy and seen no change in the
//! reproduction's sums, then dominated by other phases.)
//!
//! Session 12: the skin's floor (`d / 8`, where a settled cloth's skin sits) at `d / 16`
//! lists fewer near pairs (timeline, basic VcCPBD, one thread, two runs: settled steps'
//! pairs column 9.9-10.1 -> 8.9-9.1 ms; `d / 4` 11.7-12.3) but rebuilds more often while
//! folding; `weft reproduce vccpbd --size 100 --repeat 3`, two alternate runs in a slow spell:
//! sums of the 12 hash rows 6.11 / 6.06 ms at `d / 8` against 6.19 / 6.27 at `d / 16`. Kept.
//!
//! # Cost (issue #5, `examples/self_collision_timeline.rs`, basic VcCPBD 100x100, 1 thread)
//! Measured per substep, averaged over the 1500 substeps, with timers around the parts
//! (loaded shared machine, so roughly): the near-list update 36 µs (274 rebuilds, ~180 µs
//! each over ~180 000 candidate pairs once folded, plus the displacement check), the
//! candidate test of the near pairs 15 µs (~5 600 near pairs), zeroing and storing the sums
//! 16 µs, the ~205 contacts themselves 4 µs. What changed, and why:
//! * the displacement check and the copy of the build positions cover only the active
//!   blocks ([`max_disp2_blocks`](crate::self_collision::near::moves::max_disp2_blocks)): every near pair has both ends in them, and while the
//!   cloth falls they are a few of the 1 250 blocks (the check ran over all 10 000
//!   particles every substep);
//! * the rebuild ([`collect_near`]) tests eight candidates of a particle at a time from a
//!   `[x, y, z, 0]` copy of the positions (one 16-byte load a candidate, transposed in
//!   registers) instead of three scattered loads; measured within the noise of the shared
//!   machine (the rebuild stays bound by its ~1 ns a candidate), kept because it is not
//!   slower and the scalar twin is the same list;
//! * the eight-lane gathers are written out ([`crate::data::lanes::gather1`],
//!   [`crate::data::lanes::idx8`]): with `array::map` the compiler once emitted an out-of-line call
//!   per gather in the pair pass's candidate test, which made that test twice as slow (perf
//!   annotate).
//!
//! * session 5: the displacement check loads its three coordinates written out (with
//!   `[0, 1, 2].map(..)` each coordinate was an out-of-line `try_map` call: ~140 million
//!   instructions of the pair phase over the 1 500 substeps), a build copies the positions
//!   of a block with one slice copy and the `[x, y, z, 0]` copy without bounds checks.
//!   Callgrind over the pair phase (`self_collision_pairs_pass`, timeline example, 150 steps,
//!   1 thread): 1 600 to 1 292 million instructions, same bits; wall time of the pairs
//!   column 0.809 / 0.770 / 0.616 ms a step before against 1.235 / 0.658 / 0.586 after,
//!   alternate runs at load ~6 on two cores (noise larger than the change).
//!
//! Tried in session 5 and not kept (callgrind over the pair phase, same scene, against
//! 1 600 million instructions before the change above):
//! * **per-block references** (a block whose particle passed `0.49 s₂` takes new references
//!   alone; the owner blocks of the pairs touching it, found through a block adjacency built
//!   with the list, are tested again; the list stays exact: tested against the full build
//!   and every contact): with a fixed skin `d / 2`, 1 637 million (the partial retests cost
//!   less than the rebuilds, but the fixed skin lists ~10 000 near pairs against ~6 400 for
//!   the adaptive one, and the pair test runs every substep); with a skin per block
//!   (adapted like the global one, pair radius `d + s_i / 2 + s_j / 2`): 2 170 million with
//!   skins reset at each candidate rebuild, 2 525 million when kept across them (blocks
//!   keep the wide skins of the fall). A block that moves retests ~4 owner blocks, so the
//!   partial updates walked ~60% of the candidates the global rebuilds walk, at ~2.5 times
//!   the instructions a candidate (short per-block loops, the per-pair radius);
//! * the partial last group of a particle's candidates in the eight-lane test (masked)
//!   instead of the scalar tail: 1 230 to 1 384 million (the clamped indices slow every
//!   group);
//! * the pair pass's candidate test loading `[x, y, z, 0]` copies of the predicted
//!   positions (two transposed gathers instead of six lane gathers): 1 230 to 1 221
//!   million, the per-substep copy eats the gain; not worth its buffer;
//! * the rebuild in parallel over fixed chunks of 2 048 particles (per-chunk buffers joined
//!   in order: the same list): on two threads the pairs column measured 0.421-0.649 ms a
//!   step before against 0.433-0.647 after (seven alternate runs each, load 3.3-3.5: the
//!   second core was busy), no measurable gain on the shared machine (but see session 6).
//!
//! Session 6 (issue #5 on two threads): a rebuild runs in parallel over ranges of particles
//! of about [`NEAR_CHUNK`] candidate entries each ([`chunk_bounds`], cut from the list
//! offsets, so a folded region's long lists spread over several tasks), each range into its
//! own buffer, joined in order: the same list on any number of threads (tested). Measured
//! under the CPU lock on the otherwise idle machine, `weft reproduce vccpbd --size 100
//! --threads 2`, basic VcCPBD hash row, five alternate runs each: collision 0.704 -> 0.631
//! ms a step (medians), pairs column 0.356 -> 0.267; the rebuilds alone (timers around
//! them, timeline example, 150 steps, 240 rebuilds) 30.0 -> 18.9 ms in all. One thread: no
//! change (pairs 0.366 -> 0.368).
//!
//! Tried in session 6 and not kept: the near list kept as the ranges' buffers and each
//! rebuild run inside the pair pass's parallel candidate search (one region for both, the
//! candidate search then split by the same ranges). Timeline example, two threads, three
//! alternate runs: pairs 0.265-0.274 ms a step before against 0.287-0.302 (0.269-0.285 with
//! the search parallel from 2 048 near pairs instead of 4 096): the ranges, cut by candidate
//! entries, split the near pairs of a kept list unevenly; one region fewer a rebuild did not
//! make up for it. Without the `[x, y, z, 0]` copy (three lane gathers from `p`) 0.316-0.338.
//!
//! The skin rule is unchanged: a larger cap than `d` makes the near list approach the
//! candidate lists (radius `3 d` against `4 d`), and a cap of `d / 2` (tried: fewer near
//! pairs, more rebuilds) measured no faster (CPU of these phases over the distance solve's,
//! 0.68-0.75 against 0.64-0.70, three runs each); the remaining cost is the folding phase
//! (steps ~40-100), where the cloth moves `~d / 10` a substep and the list is rebuilt every
//! 4-10 substeps. (Session 7 changed the rule: see "Mid list" above.)

pub(crate) mod mid;
pub(crate) mod moves;
pub(crate) mod scan;

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
/// on the mid path the skin is `d / 8` (session 13, see the module docs).
pub(crate) const MID_NEAR_SKIN_MAX: f32 = NEAR_SKIN_FLOOR;

/// Smallest near-list skin over the collision distance (where a settled cloth's skin sits).
pub(crate) const NEAR_SKIN_FLOOR: f32 = 0.125;

/// Substeps the near skin is sized to last, at the fastest particle's rate since the last
/// build (20 before the mid list made rebuilds cheap; see the module docs).
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
    pub(crate) fn update(
        &mut self,
        source: MidSource<'_>,
        p: [&[f32]; 3],
        blocks: &[u32],
        n: usize,
        d: f32,
        simd: bool,
        parallel: bool,
    ) -> MidUpdate {
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
                filter_pairs(&self.cand_pairs, p, n, r, simd, parallel, &mut self.scratch, &mut self.pairs);
            }
            source => {
                mid = self.update_mid(source, p, blocks, n, d, simd, parallel);
                filter_pairs(&self.mid, p, n, r, simd, parallel, &mut self.scratch, &mut self.pairs);
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
    fn update_mid(
        &mut self,
        source: MidSource<'_>,
        p: [&[f32]; 3],
        blocks: &[u32],
        n: usize,
        d: f32,
        simd: bool,
        parallel: bool,
    ) -> MidUpdate {
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
                        .refresh(p, &mut self.mid_at, blocks, n, lim, r, *rule, &mut self.mid, parallel, simd)
                {
                    return MidUpdate::Refreshed;
                }
            }
        }
        copy_blocks(p, blocks, &mut self.mid_at);
        self.mid_rebuilds += 1;
        match source {
            MidSource::Candidates { cand, .. } => {
                collect(cand, p, n, r, simd, parallel, &mut self.scratch, &mut self.mid);
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
