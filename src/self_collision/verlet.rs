//! Reuse of the self-collision candidate pairs across steps (Verlet lists with a skin), exact:
//! the contacts are those of a fresh broadphase every step (the method is described in
//! [`crate::self_collision`]; the near list across substeps is [`crate::self_collision::near`]).
//!
//! # Candidate lists across steps (Verlet, skin `s`)
//! The broadphase finds the pairs within `q + s` of the positions `x⁰` of its build, rest
//! neighbours dropped, each pair once. While every particle stays within `0.49 s` of `x⁰`
//! (`|x_i - x⁰_i| <= 0.49 s`), a pair within `q` now was within `q + 0.98 s < q + s` at the
//! build (triangle inequality), so it is in the candidate lists: filtering them with the same
//! predicate `|x_i - x_j| <= q` gives exactly the lists a fresh query would. The 2% margin is
//! far above the `f32` rounding of the distances (a few ulps, relative). A particle past the
//! bound (or non-finite) triggers a rebuild. The skin is chosen at each build from how fast
//! the cloth moved since the last one: `SKIN_FACTOR d` when the largest displacement a step
//! was at most `SLOW_FACTOR d` (a slow, folded cloth: the lists then last several steps),
//! otherwise zero (a falling cloth: a larger reach would cost more than it saves; with a zero
//! skin the lists are reused only if no particle moved at all).
//!
//! # Choice of the skin (measured)
//! `examples/self_collision_timeline` (100x100 fold, basic VcCPBD, 150 steps, one thread,
//! load 3-5 on two cores), broadphase = hash build + query, ms a step averaged over the run,
//! with the query that tests order and rest neighbours in the lanes (`hash_rest`):
//!
//! | skin / slow | build + query | rebuilds | pairs (near list) | stage total |
//! |---|---|---|---|---|
//! | d / 0.25 d (before) | 0.98-1.29 | 63 | 0.56-0.70 | 1.86-2.42 |
//! | 0.5 d / 0.25 d | 1.26 | 72 | 0.73 | 2.41 |
//! | 2 d / d (kept) | 0.69-0.83 | 49 | 0.66-0.81 | 1.65-2.04 |
//! | 3 d / d | 0.59-0.60 | 47 | 0.76-0.80 | 1.66-1.69 |
//! | 3 d / 2 d | 1.27 | 38 | 1.11 | 2.74 |
//!
//! and on the 12 hash rows of `weft reproduce vccpbd --size 100` (mean ms a step, load 5-6,
//! so only the broadphase columns are clear): build + query + start 1.52 (d / 0.25 d), 0.91
//! (2 d / d), 0.85 (3 d / d); pairs 1.55, 1.41, 1.71. The near list of the substeps is built
//! from the candidate lists, so a wider skin costs there: 2 d is kept as the balance (3 d saves
//! another ~0.05 ms of broadphase and costs more in the pairs phase).
//!
//! With the cell query (`hash_cells`, fifth session; same timeline, load 7-8, three alternate
//! runs): skin 2 d build + query + start 0.44-0.51 ms a step, pairs 0.71-0.91, 49 rebuilds;
//! skin d 0.68-0.74, pairs 0.63-0.68, 58 rebuilds (stage total 1.40-1.77 against 1.62-1.73).
//! The cheaper rebuilds do not make a narrower skin pay for the broadphase, so 2 d stays.
//! A bound on the displacement relative to the mean displacement (exact too: the lists hold
//! while `|(x_i - x⁰_i) - t| <= 0.49 s` for one common `t`) was tried with `t` the mean: 49
//! rebuilds either way (the cloth hangs from a pinned row, so it does not translate as a
//! whole), broadphase 0.55-0.59 against 0.48-0.53, not kept.
//!
//! Session 6 (issue #5 on two threads, with the near-list rebuild in parallel): the skin
//! measured again on `weft reproduce vccpbd --size 100 --threads 2`, basic VcCPBD hash row,
//! CPU lock, idle machine, alternate runs. Collision ms a step: skin 2 d 0.603-0.638 (six
//! runs without the two slow outliers of the VM, 0.690 and 0.854), 3 d 0.582-0.609 (six runs,
//! one outlier 0.683); query column 0.19-0.23 against 0.16-0.18 (47 rebuilds against 49),
//! pairs 0.264-0.269 against 0.271-0.281; 1.5 d 0.627-0.641, d 0.675-0.700, 2.5 d
//! 0.648-0.663, 4 d 0.667-0.672. One thread, two runs each: 2 d 0.804 / 0.811, 3 d 0.802 /
//! 0.822 (no change). The skin is now 3 d: the wider reach's extra candidates cost the near
//! list's rebuild, which two threads now share, less than the rebuilds it saves.
//!
//! A wider skin makes each rebuild's reach (`q + s`) and candidate count larger but lets the
//! folding cloth (steps ~42-75, 4.5-9.7 ms of queries a step before) keep its lists for
//! several steps; allowing the skin for faster motion (`SLOW_FACTOR` 2) makes the falling
//! steps query with the wide reach and still rebuild every step, which costs more.
//!
//! # Slow steps without candidate lists (session 8, hash broadphase)
//! Once the near list came from a mid list (pairs within `2.5 d`, see [`crate::self_collision::near`]),
//! the wide candidate lists (reach `6 d`, ~763 000 pairs on the folded 100x100 cloth) were only
//! a superset to filter the mid list from, and one wide rebuild cost 9-11 ms of a run's
//! ~80 ms (timeline example, two threads: its first build grows every buffer). With the hash,
//! a slow step (the same rule: at most `SLOW_FACTOR d` a step) now builds no lists
//! ([`Plan::Direct`]): every block is active and the substeps query the mid list from a hash
//! of the predicted positions when it expires (`query_upper_unskipped_cells`, reach
//! `2.5 d`, the rest rule in the lanes: the same pairs, so the near lists and the results are
//! the same bits; tests: the lists and positions of the fresh path every step, and the near
//! list of a hashed mid list against the build from every pair). The motion of such a step is
//! measured from the previous step's start positions, which the stage keeps anyway. A mid
//! query costs about twice the filter from the candidates (0.74 against 0.36 ms, two threads),
//! ~13 of them a basic run. Timeline example, two threads, alternate runs, stage total over
//! 150 steps: basic VcCPBD 80.1-80.7 -> 77.4-79.2 ms (query column 25.0-25.6 -> 16.5-17.3,
//! pairs 34.3-34.7 -> 40.2-41.3), in a slow spell of the VM 124.6-125.4 -> 118.3-119.8;
//! polyester movement speed (five wide rebuilds before) 78.7-80.7 -> 71.3-71.9; the tethered
//! basic fold (`--tethers 0`) 188.0-201.3 -> 180.6-195.2. On one thread, where runs repeat
//! within 1-3% on this machine (two threads drift up to 1.35 times), `weft reproduce vccpbd
//! --size 100 --repeat 3`, two alternate runs: the 12 hash rows' medians sum to 7.92-8.18 ms
//! before against 7.24-7.44 after (the mid lists copied to pairs, next paragraph), the basic
//! rows 0.70-0.77 against 0.66-0.79 (unchanged within the noise: there one wide rebuild went
//! and 13 mid queries of ~1.35 ms each came). The tree keeps the wide lists (its query is the
//! slow part either way).
//!
//! Session 13, `SLOW_FACTOR` 1.5, 2 and 4 (more of the fall without candidate lists; timeline,
//! basic VcCPBD, one thread, two runs each): stage 82.0-83.2, 95.0-95.8 and 100.5 ms against
//! 78.7-79.1; the query column fell (24.5 -> 11.2, 4.4, 1.3 ms) but the substeps' mid queries
//! and refreshes of a fast cloth cost more (pairs 39.2 -> 57-58, 78-79, 87 ms). 1 stays.
//!
//! Tried in session 13 and not kept: going direct also on a fast step (up to 1.5 d a step)
//! when the last build's candidates were dense (at least 2, 3 or 4 pairs a particle: the
//! steps of the impact, whose queries keep 47 000-110 000 pairs). Timeline, basic VcCPBD, one
//! thread, two runs each: query column 22.8-23.0 -> 19.5-20.8 ms, pairs 38.9-39.1 ->
//! 42.4-44.5, stage 77.2-77.6 -> 78.0-79.1.
//!
//! The hashed mid list is copied to pairs for the near rebuilds' eight-lane filter (with ~7
//! partners a particle the scan over lists ran its scalar tail): 7.49-7.85 -> 7.43 ms (sum
//! above). Tried and not kept: `MID_SKIN` 1.5 and 2 (fewer mid queries, larger mid lists):
//! sums 7.08-7.31 and 7.23-7.34 against 7.18-7.32; the candidates of a falling step filtered
//! as pairs too (cached per build): 7.38-7.45 against 7.19-7.41.

use crate::data::lanes::{load, F32s, LANES};
use crate::self_collision::config::SelfBroadphase;
use crate::self_collision::neighbours::Neighbours;

/// Skin of the candidate lists over the collision distance, when the cloth moves slowly
/// (measured, see the module docs: 2 on one thread, 3 since the near-list rebuild runs on
/// two).
pub const SKIN_FACTOR: f32 = 3.0;

/// Largest displacement a step (over the collision distance) for which the skin is used.
pub const SLOW_FACTOR: f32 = 1.0;

/// Share of half the skin a particle may move before the lists are rebuilt.
pub(crate) const SAFE: f32 = 0.98;

/// Largest squared distance between `a_i` and `b_i`, `i < n`, or infinity when one is NaN:
/// eight particles at a time when `simd`, else one by one (the twin; same value).
pub(crate) fn max_disp2(a: [&[f32]; 3], b: [&[f32]; 3], n: usize, simd: bool) -> f32 {
    let mut m = 0.0f32;
    let mut nan = false;
    let mut i = 0;
    if simd {
        let mut mv = F32s::splat(0.0);
        let mut bad = F32s::splat(0.0);
        while i + LANES <= n {
            let d = [0, 1, 2].map(|k| load(a[k], i) - load(b[k], i));
            let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            bad |= d2.is_nan();
            mv = mv.max(d2);
            i += LANES;
        }
        nan = bad.any();
        m = mv.to_array().into_iter().fold(0.0, f32::max);
    }
    for i in i..n {
        let d = [0, 1, 2].map(|k| a[k][i] - b[k][i]);
        let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        nan |= d2.is_nan();
        m = m.max(d2);
    }
    if nan {
        f32::INFINITY
    } else {
        m
    }
}

/// What the candidate lists were built for: particle count, collision distance bits and
/// broadphase.
type Key = (usize, u32, SelfBroadphase);

/// The candidate lists of the last build and what is needed to decide whether they still hold.
#[derive(Clone, Debug, Default)]
pub(crate) struct VerletLists {
    /// Pairs within `q + skin` at the build, rest neighbours dropped, each once (`j > i`).
    pub(crate) cand: Neighbours,
    snap: [Vec<f32>; 3],
    skin: f32,
    key: Option<Key>,
    steps_since: u32,
    /// No candidate lists: the near list's mid list comes from the hash ([`Plan::Direct`]).
    direct: bool,
    /// Builds so far (entering [`Plan::Direct`] counts as one).
    pub(crate) rebuilds: u64,
}

/// What a step start does (see [`VerletLists::plan`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Plan {
    /// The candidate lists still hold.
    Keep,
    /// Rebuild them with this skin.
    Build(f32),
    /// A slow cloth with the hash broadphase: no candidate lists; the substeps build their
    /// mid list from a hash of the predicted positions (see [`crate::self_collision::near`]).
    Direct,
}

impl VerletLists {
    /// What the step start does with the candidate lists for `x` (see the module docs):
    /// keep them, rebuild them with a skin, or (hash broadphase, a slow cloth) go without them
    /// ([`Plan::Direct`]). `fresh` forces a rebuild with no skin.
    ///
    /// `prev` holds the positions of the last call (the previous step's start): without
    /// lists, the motion a step is measured from them (no snapshot of its own to copy).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn plan(&mut self, x: [&[f32]; 3], prev: [&[f32]; 3], n: usize, d: f32, bp: SelfBroadphase, fresh: bool) -> Plan {
        if fresh || self.key != Some((n, d.to_bits(), bp)) || (self.direct && prev.iter().any(|a| a.len() < n)) {
            return Plan::Build(0.0);
        }
        let m2 = if self.direct {
            max_disp2(x, prev, n, true)
        } else {
            max_disp2(x, [&self.snap[0][..], &self.snap[1][..], &self.snap[2][..]], n, true)
        };
        let lim = 0.5 * SAFE * self.skin;
        self.steps_since += 1;
        if !self.direct && m2 <= lim * lim {
            return Plan::Keep;
        }
        let rate = m2.sqrt() / self.steps_since as f32;
        let slow = rate <= SLOW_FACTOR * d;
        match (slow, bp) {
            (true, SelfBroadphase::Hash) => Plan::Direct,
            (true, _) => Plan::Build(SKIN_FACTOR * d),
            (false, _) => Plan::Build(0.0),
        }
    }

    /// The skin of the last build (the candidate lists' reach is `q` plus this).
    pub(crate) fn skin(&self) -> f32 {
        self.skin
    }

    /// Records a successful build from `x` with `skin`.
    pub(crate) fn built(&mut self, x: [&[f32]; 3], n: usize, d: f32, bp: SelfBroadphase, skin: f32) {
        self.snapshot(x, n, d, bp);
        self.skin = skin;
        self.direct = false;
        self.rebuilds += 1;
    }

    /// Records a step of [`Plan::Direct`]: no candidate lists (emptied); the next plan
    /// measures the motion from the positions it is given as the previous ones. Counts as a
    /// build when it starts the mode; returns whether it did.
    pub(crate) fn went_direct(&mut self) -> bool {
        self.skin = 0.0;
        self.steps_since = 0;
        let entered = !self.direct;
        if entered {
            self.direct = true;
            self.cand.clear();
            self.rebuilds += 1;
        }
        entered
    }

    /// Whether the step runs without candidate lists ([`Plan::Direct`]).
    pub(crate) fn is_direct(&self) -> bool {
        self.direct
    }

    fn snapshot(&mut self, x: [&[f32]; 3], n: usize, d: f32, bp: SelfBroadphase) {
        for (s, src) in self.snap.iter_mut().zip(x) {
            s.clear();
            s.extend_from_slice(&src[..n]);
        }
        self.key = Some((n, d.to_bits(), bp));
        self.steps_since = 0;
    }

    /// Forgets the lists (a failed build): the next step rebuilds.
    pub(crate) fn invalidate(&mut self) {
        self.key = None;
        self.direct = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::signed;

    #[test]
    fn max_disp2_simd_equals_scalar_and_flags_nan() {
        let mut rng = signed(11);
        for n in [0usize, 5, 8, 37] {
            let a: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| rng()).collect());
            let b: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| rng()).collect());
            let (ra, rb) = ([&a[0][..], &a[1][..], &a[2][..]], [&b[0][..], &b[1][..], &b[2][..]]);
            let s = max_disp2(ra, rb, n, false);
            assert_eq!(s.to_bits(), max_disp2(ra, rb, n, true).to_bits());
            let want = (0..n)
                .map(|i| (0..3).map(|k| (a[k][i] - b[k][i]) * (a[k][i] - b[k][i])).fold(0.0, |x, y| x + y))
                .fold(0.0f32, f32::max);
            assert!((s - want).abs() <= 1e-6 * want.max(1.0), "{s} {want}");
        }
        let mut a = [vec![0.0f32; 20], vec![0.0; 20], vec![0.0; 20]];
        let b = a.clone();
        a[1][13] = f32::NAN;
        for simd in [false, true] {
            let r = max_disp2([&a[0], &a[1], &a[2]], [&b[0], &b[1], &b[2]], 20, simd);
            assert_eq!(r, f32::INFINITY);
        }
    }

    #[test]
    fn plan_reuses_within_the_skin_and_rebuilds_past_it() {
        let n = 4;
        let d = 0.1f32;
        let (skin, slow) = (SKIN_FACTOR * d, SLOW_FACTOR * d);
        let x = [vec![0.0f32, 1.0, 2.0, 3.0], vec![0.0; 4], vec![0.0; 4]];
        let r = [&x[0][..], &x[1][..], &x[2][..]];
        let mut v = VerletLists::default();
        let bp = SelfBroadphase::AabbTree;
        assert_eq!(v.plan(r, r, n, d, bp, false), Plan::Build(0.0), "nothing built yet");
        v.built(r, n, d, bp, skin);
        assert_eq!(v.plan(r, r, n, d, bp, false), Plan::Keep);
        assert_eq!(v.plan(r, r, n, d, bp, true), Plan::Build(0.0), "forced");
        assert_eq!(v.plan(r, r, n, 0.2, bp, false), Plan::Build(0.0), "other distance");
        let mut y = x.clone();
        y[2][3] = 0.48 * skin;
        assert_eq!(v.plan([&y[0], &y[1], &y[2]], r, n, d, bp, false), Plan::Keep);
        y[2][3] = 0.5 * skin;
        // Past 0.49 skin after three steps, at a sixth of the skin a step: slow, skin again.
        assert!(skin / 6.0 <= slow);
        assert_eq!(v.plan([&y[0], &y[1], &y[2]], r, n, d, bp, false), Plan::Build(skin));
        y[2][3] = 4.0 * (slow + skin);
        assert_eq!(v.plan([&y[0], &y[1], &y[2]], r, n, d, bp, false), Plan::Build(0.0), "fast: no skin");
        v.built(r, n, d, bp, 0.0);
        assert_eq!(v.plan(r, r, n, d, bp, false), Plan::Keep, "unmoved: reused even with no skin");
        y[2][3] = 1e-3;
        assert_eq!(v.plan([&y[0], &y[1], &y[2]], r, n, d, bp, false), Plan::Build(skin), "slow: skin");
        y[0][0] = f32::NAN;
        assert_eq!(v.plan([&y[0], &y[1], &y[2]], r, n, d, bp, false), Plan::Build(0.0), "non-finite");
    }

    /// With the hash a slow cloth goes without candidate lists, every step while it stays
    /// slow (each step measured from the one before), and back to lists when it speeds up.
    #[test]
    fn plan_goes_direct_while_slow_with_the_hash() {
        let n = 4;
        let d = 0.1f32;
        let bp = SelfBroadphase::Hash;
        let mut y = [vec![0.0f32, 1.0, 2.0, 3.0], vec![0.0; 4], vec![0.0; 4]];
        let mut v = VerletLists::default();
        v.built([&y[0], &y[1], &y[2]], n, d, bp, 0.0);
        let mut prev = y.clone();
        y[1][2] = 0.5 * d;
        let r = |a: &[Vec<f32>; 3]| [a[0].clone(), a[1].clone(), a[2].clone()];
        assert_eq!(
            v.plan([&y[0], &y[1], &y[2]], [&prev[0], &prev[1], &prev[2]], n, d, bp, false),
            Plan::Direct
        );
        v.went_direct();
        assert!(v.is_direct() && v.cand.is_empty());
        let builds = v.rebuilds;
        // Unmoved, and then 0.9 d a step for three steps (measured from the step before):
        // still direct, the mode entered once.
        for step in 0..4 {
            prev = r(&y);
            y[1][2] += if step == 0 { 0.0 } else { 0.9 * d };
            let plan = v.plan([&y[0], &y[1], &y[2]], [&prev[0], &prev[1], &prev[2]], n, d, bp, false);
            assert_eq!(plan, Plan::Direct, "step {step}");
            v.went_direct();
        }
        assert_eq!(v.rebuilds, builds);
        prev = r(&y);
        y[1][2] += 1.5 * d;
        let p = [&prev[0][..], &prev[1][..], &prev[2][..]];
        assert_eq!(v.plan([&y[0], &y[1], &y[2]], p, n, d, bp, false), Plan::Build(0.0), "fast");
        v.went_direct();
        assert_eq!(
            v.plan([&y[0], &y[1], &y[2]], [&[][..], &[][..], &[][..]], n, d, bp, false),
            Plan::Build(0.0),
            "no previous positions"
        );
        v.built([&y[0], &y[1], &y[2]], n, d, bp, 0.0);
        assert!(!v.is_direct());
        assert_eq!(v.plan([&y[0], &y[1], &y[2]], p, n, d, bp, true), Plan::Build(0.0), "forced");
    }
}
