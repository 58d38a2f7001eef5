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
//! # Choice of the skin
//! A wider skin makes each rebuild's reach (`q + s`) and candidate count larger but lets a
//! folding cloth keep its lists for several steps. `3 d` balances the broadphase against the
//! near-list rebuilds that filter the candidates (those run in parallel, so a wider reach
//! costs them less). Allowing the skin for faster motion (a larger `SLOW_FACTOR`) makes the
//! falling steps query with the wide reach and still rebuild every step.
//!
//! # Slow steps without candidate lists (hash broadphase)
//! The near list comes from a mid list (see [`crate::self_collision::near`]), so on a folded cloth the
//! wide candidate lists would only be a superset to filter the mid list from, and one wide
//! rebuild is expensive. With the hash, a slow step (at most `SLOW_FACTOR d` a step) builds no
//! lists ([`Plan::Direct`]): every block is active and the substeps query the mid list from a
//! hash of the predicted positions when it expires (`query_upper_unskipped_cells`, the rest
//! rule in the lanes). These are the same pairs, so the near lists and the results are the
//! same bits; the tests compare the lists and positions with the fresh path every step, and
//! the near list of a hashed mid list with the build from every pair. The motion of such a
//! step is measured from the previous step's start positions, which the stage keeps anyway.
//! The AABB tree keeps the wide lists (its query is the slow part either way).

use crate::data::lanes::{load, F32s, LANES};
use crate::model::self_collision::SelfBroadphase;
use crate::self_collision::neighbours::Neighbours;

/// Skin of the candidate lists over the collision distance, when the cloth moves slowly
/// (see the module docs).
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
