//! The mid list of a slow step queried from a spatial hash, refreshed particle by particle
//! (the mid list itself is described in [`crate::self_collision::near`]).
//!
//! # Per-particle references
//! The mid list holds the pairs within `r₁` of the *references* `a`, one position a particle,
//! rest neighbours dropped: `M = {(i, j): i < j, |a_i - a_j| <= r₁, not rest neighbours}`.
//! A full build queries a hash built on the predicted positions `p` and sets `a = p`. While
//! every particle stays within `0.49 MID_SKIN d` of its own reference, a pair within
//! `d + s₂` of `p` is in `M` (the triangle inequality, as in [`crate::self_collision::near`]); nothing
//! asks the references to be taken at one time.
//!
//! So when some particles pass that bound (the set `F`), only they take new references
//! (`a_i = p_i`), and only the pairs with an end in `F` change: they are dropped from `M`, and
//! each `i` in `F` is probed for its partners within `r₁` of the new `a_i`:
//! * through the hash of the last full build, for the partners that kept the reference of
//!   that build (the hash holds exactly their `a_j`);
//! * one by one against the *stale* particles (those that took a new reference since the
//!   build: the hash holds an old position for them), which the hash's hits skip.
//!
//! The new pairs are sorted, the repeats (both ends in `F`) dropped, and merged with the
//! kept ones: the list holds `M` again (with the build's pairs of the stale particles, which
//! may no longer be within `r₁`: the near filter drops them), so the near lists built from
//! it, and every result, are the bits of a full query each time (tested: the near list
//! against the build from every pair at each substep, and the runs against the fresh path).
//! When a position is not finite, or a probe falls far off the hash's scale, the caller
//! makes a full build.
//!
//! # Rehash
//! Each refresh tests its particles against every stale one, so the stale particles are
//! capped (`n / STALE_SHARE`, at least `STALE_MIN`). Past the cap the hash is built again from
//! the references, the moved particles' new ones included, so it holds every reference
//! exactly and none is stale: much cheaper than a full query when only a few dozen particles
//! moved. The build's pairs keep those with no stale or moved end (their references are the
//! build's), the refreshes' pairs (each has a stale end) are folded in, and the moved particles
//! are probed in the new hash. The list is then exactly `M` (tested against every pair at each
//! rehash). A full build is still made when more particles than the cap move at once.
//!
//! # Why
//! On a folded cloth a mid list typically expires because a handful of particles pass the
//! bound; a refresh probes those few and merges the lists instead of querying every particle.

use crate::data::exec::Exec;
use crate::data::lanes::{finite_lanes, load, F32s, LANES};
use crate::self_collision::hash::SpatialHash;
use crate::self_collision::near::moves::as_refs;
use crate::self_collision::neighbours::{within, Neighbours};
use crate::self_collision::{build_hash, REST_SKIP_FACTOR};

/// Most stale particles (taken new references since the last full build) a refresh may
/// leave, over the particle count, before a full build is cheaper (at least
/// [`STALE_MIN`]): each refresh tests its particles against all of them one by one.
pub(crate) const STALE_SHARE: usize = 64;

/// Floor of the stale particles a refresh may leave.
pub(crate) const STALE_MIN: usize = 64;

/// What the mid list's particle refresh needs of the cloths: rest positions, cloth ids, and
/// the rest distance up to which a pair of one cloth is a rest neighbour.
#[derive(Clone, Copy)]
pub(crate) struct RestRule<'a> {
    pub rest: [&'a [f32]; 3],
    pub cloth_of: &'a [u32],
    pub skip: f32,
}

impl<'a> RestRule<'a> {
    /// The self-collision stage's rule for collision distance `d`: rest neighbours up to
    /// `REST_SKIP_FACTOR d`.
    pub(crate) fn of(rest: &'a [Vec<f32>; 3], cloth_of: &'a [u32], d: f32) -> Self {
        RestRule {
            rest: [&rest[0], &rest[1], &rest[2]],
            cloth_of,
            skip: REST_SKIP_FACTOR * d,
        }
    }

    /// Whether `(i, j)` are rest neighbours (the hash's rule, the same operations).
    #[inline]
    pub(crate) fn skips(&self, i: usize, j: usize) -> bool {
        let r = self.rest;
        let (dx, dy, dz) = (r[0][i] - r[0][j], r[1][i] - r[1][j], r[2][i] - r[2][j]);
        self.cloth_of[i] == self.cloth_of[j] && dx * dx + dy * dy + dz * dz <= self.skip * self.skip
    }
}

/// The hash of the mid list's last full build and the particles refreshed since.
#[derive(Clone, Debug, Default)]
pub(crate) struct HashedMid {
    hash: Option<SpatialHash>,
    /// Particle count and mid radius of the build the hash holds (`None`: no usable build).
    built: Option<(usize, u32)>,
    lists: Neighbours,
    /// Particles with a reference newer than the hash's build, in the order they took it.
    stale: Vec<u32>,
    is_stale: Vec<bool>,
    /// This refresh's particles, and whether each particle is one of them.
    moved: Vec<u32>,
    is_moved: Vec<bool>,
    fresh: Vec<(u32, u32)>,
    /// Pairs added by the refreshes since the build (ordered, no repeats; see the module docs).
    extra: Vec<(u32, u32)>,
    merged: Vec<(u32, u32)>,
    /// Refreshes so far.
    pub(crate) refreshes: u64,
    /// Refreshes that built the hash again from the references (see [`HashedMid::refresh`]).
    pub(crate) rehashes: u64,
}

impl HashedMid {
    /// Pairs the refreshes added since the last build, ordered: with the build's pairs they
    /// hold every pair within the mid radius of the references (and some that were, once).
    pub(crate) fn extra(&self) -> &[(u32, u32)] {
        &self.extra
    }

    /// Forgets the build (the mid list came from elsewhere): the next refresh fails.
    pub(crate) fn forget(&mut self) {
        self.built = None;
        self.extra.clear();
    }

    /// The full build: `pairs` = every pair within `r` of `p` but the rest neighbours, each once
    /// as `(i, j)`, `i < j`, ordered. Returns `false` (and empty pairs) when the hash build
    /// fails (non-finite positions).
    pub(crate) fn build(
        &mut self,
        p: [&[f32]; 3],
        n: usize,
        r: f32,
        rule: RestRule<'_>,
        parallel: bool,
        pairs: &mut Vec<(u32, u32)>,
    ) -> bool {
        let hash = self.hash.get_or_insert_with(|| SpatialHash::new(n));
        let lists = &mut self.lists;
        let res = build_hash(hash, p, n, r, rule.rest, rule.cloth_of, parallel).and_then(|_| {
            if parallel {
                hash.query_upper_unskipped_cells(r, rule.skip, lists)
            } else {
                hash.query_upper_unskipped_cells_serial(r, rule.skip, lists)
            }
        });
        for &s in &self.stale {
            self.is_stale[s as usize] = false;
        }
        self.stale.clear();
        self.extra.clear();
        self.is_stale.resize(n, false);
        self.is_moved.resize(n, false);
        pairs.clear();
        // Copied to pairs: ~7 partners a particle, so the near rebuilds' eight-lane filter runs
        // over the pairs, not over the short lists.
        if res.is_ok() {
            pairs.extend(self.lists.pairs());
            self.built = Some((n, r.to_bits()));
        } else {
            self.built = None;
        }
        res.is_ok()
    }

    /// The refresh (see the module docs): the particles of `blocks` (here every block of the
    /// `n` particles, block `k` at `at[8 k..]`) farther than `lim` from their reference `at`
    /// take `p` as their new reference, and their pairs within `r` of the references are
    /// added to [`HashedMid::extra`]. When the stale particles would pass their cap, the hash
    /// is built again from the references instead (a *rehash*, see the module docs): `mid`,
    /// the pairs of the last full build, becomes the whole list and the extra pairs go.
    /// Returns `false` when a full build is needed instead.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn refresh(
        &mut self,
        p: [&[f32]; 3],
        at: &mut [Vec<f32>; 3],
        blocks: &[u32],
        n: usize,
        lim: f32,
        r: f32,
        rule: RestRule<'_>,
        mid: &mut Vec<(u32, u32)>,
        exec: Exec,
    ) -> bool {
        let (parallel, simd) = (exec.parallel(), exec.simd());
        let covers = blocks.len() * LANES >= n && blocks.iter().enumerate().all(|(k, &b)| b as usize == k);
        let short = at.iter().any(|a| a.len() < n) || p.iter().any(|c| c.len() < n);
        if self.hash.is_none() || self.built != Some((n, r.to_bits())) || !covers || short {
            return false;
        }
        let lim2 = lim * lim;
        if !moved_past(p, as_refs(at), n, lim2, simd, &mut self.moved) {
            return false;
        }
        let cap = (n / STALE_SHARE).max(STALE_MIN);
        let new_stale = self.moved.iter().filter(|&&i| !self.is_stale[i as usize]).count();
        let rehash = self.stale.len() + new_stale > cap;
        if rehash && self.moved.len() > cap {
            // Many particles at once: the full query is the cheaper way.
            return false;
        }
        for &i in &self.moved {
            let i = i as usize;
            self.is_moved[i] = true;
            if !rehash && !self.is_stale[i] {
                self.is_stale[i] = true;
                self.stale.push(i as u32);
            }
            for k in 0..3 {
                at[k][i] = p[k][i];
            }
        }
        let ok = if rehash {
            self.rehash(at, n, r, rule, mid, parallel)
        } else {
            self.probe_moved(at, r, rule)
        };
        if !ok {
            // A build or a probe failed (far off the hash's scale): the caller builds afresh
            // (which takes every reference anew, so the ones taken above do not matter).
            for &i in &self.moved {
                self.is_moved[i as usize] = false;
            }
            self.built = None;
            return false;
        }
        self.fresh.sort_unstable();
        self.fresh.dedup();
        // The added pairs without those with a moved end, merged with the new ones (which
        // all have one, so no pair is in both).
        let is_moved = &self.is_moved;
        self.extra.retain(|&(a, b)| !is_moved[a as usize] && !is_moved[b as usize]);
        merge_unique(&mut self.extra, &self.fresh, &mut self.merged);
        if rehash {
            // The extra pairs all have an end that was stale (none is in `mid` any more):
            // folded in, `mid` is the whole list again.
            merge_unique(mid, &self.extra, &mut self.merged);
            self.extra.clear();
            self.rehashes += 1;
        }
        for &i in &self.moved {
            self.is_moved[i as usize] = false;
        }
        self.refreshes += 1;
        true
    }

    /// The new pairs of each moved particle into `fresh`: through the hash for the partners
    /// it holds exactly, the stale particles one by one. Returns `false` when a probe falls
    /// far off the hash's scale.
    fn probe_moved(&mut self, at: &[Vec<f32>; 3], r: f32, rule: RestRule<'_>) -> bool {
        let Some(hash) = self.hash.as_ref() else { return false };
        self.fresh.clear();
        let mut ok = true;
        for &i in &self.moved {
            let iu = i as usize;
            let ai = [at[0][iu], at[1][iu], at[2][iu]];
            let rest_i = [rule.rest[0][iu], rule.rest[1][iu], rule.rest[2][iu]];
            let (fresh, is_stale) = (&mut self.fresh, &self.is_stale);
            ok &= hash.probe_unskipped(i, ai, rest_i, rule.cloth_of[iu], r, rule.skip, |j| {
                if !is_stale[j as usize] {
                    fresh.push((i.min(j), i.max(j)));
                }
            });
            for &s in &self.stale {
                let su = s as usize;
                if s != i && within(ai[0], ai[1], ai[2], at[0][su], at[1][su], at[2][su], r * r) && !rule.skips(iu, su) {
                    self.fresh.push((i.min(s), i.max(s)));
                }
            }
        }
        ok
    }

    /// The rehash: the hash built again from the references `at` (the moved particles' new
    /// ones included), so it holds every reference exactly and no particle is stale; `mid`
    /// keeps the pairs of the last full build whose ends are neither stale nor moved (their
    /// references are still the build's), and the moved particles are probed in the new hash
    /// into `fresh`. The pairs with a stale end that did not move are in `extra` already.
    fn rehash(&mut self, at: &[Vec<f32>; 3], n: usize, r: f32, rule: RestRule<'_>, mid: &mut Vec<(u32, u32)>, parallel: bool) -> bool {
        let Some(hash) = self.hash.as_mut() else { return false };
        if build_hash(hash, as_refs(at), n, r, rule.rest, rule.cloth_of, parallel).is_err() {
            return false;
        }
        let (is_stale, is_moved) = (&self.is_stale, &self.is_moved);
        let old = |i: u32| is_stale[i as usize] || is_moved[i as usize];
        mid.retain(|&(a, b)| !old(a) && !old(b));
        for &s in &self.stale {
            self.is_stale[s as usize] = false;
        }
        self.stale.clear();
        // No particle is stale now: the probe finds every partner through the new hash.
        self.probe_moved(at, r, rule)
    }
}

/// The particles `i < n` farther than `√lim2` from `at` into `out`, ascending; `false` (and
/// `out` unspecified) when a position or a distance is not finite. Eight particles at a time
/// when `simd`, else one by one (the twin; the same list, the same operations).
pub(crate) fn moved_past(p: [&[f32]; 3], at: [&[f32]; 3], n: usize, lim2: f32, simd: bool, out: &mut Vec<u32>) -> bool {
    out.clear();
    let mut i = 0;
    if simd {
        let lim = F32s::splat(lim2);
        while i + LANES <= n {
            let (x, y, z) = (load(p[0], i), load(p[1], i), load(p[2], i));
            let (dx, dy, dz) = (x - load(at[0], i), y - load(at[1], i), z - load(at[2], i));
            let d2 = dx * dx + dy * dy + dz * dz;
            let ok = finite_lanes(d2) & finite_lanes(x) & finite_lanes(y) & finite_lanes(z);
            if ok.to_bitmask() != 0xff {
                return false;
            }
            let mut bits = d2.simd_gt(lim).to_bitmask();
            while bits != 0 {
                out.push((i + bits.trailing_zeros() as usize) as u32);
                bits &= bits - 1;
            }
            i += LANES;
        }
    }
    for i in i..n {
        let (dx, dy, dz) = (p[0][i] - at[0][i], p[1][i] - at[1][i], p[2][i] - at[2][i]);
        let d2 = dx * dx + dy * dy + dz * dz;
        if !d2.is_finite() || !p[0][i].is_finite() || !p[1][i].is_finite() || !p[2][i].is_finite() {
            return false;
        }
        if d2 > lim2 {
            out.push(i as u32);
        }
    }
    true
}

/// `a` with the pairs of `b` merged in, both ordered, a pair in both once (`tmp` the buffer).
pub(crate) fn merge_unique(a: &mut Vec<(u32, u32)>, b: &[(u32, u32)], tmp: &mut Vec<(u32, u32)>) {
    tmp.clear();
    tmp.reserve(a.len() + b.len());
    let mut f = b.iter().copied().peekable();
    for &x in a.iter() {
        while let Some(y) = f.next_if(|&y| y < x) {
            tmp.push(y);
        }
        f.next_if_eq(&x);
        tmp.push(x);
    }
    tmp.extend(f);
    std::mem::swap(a, tmp);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::signed;

    /// The eight-lane scan lists the same particles as its twin (ascending; a particle exactly
    /// at the bound is not past it) for every length around the lane width, and both report a
    /// non-finite position or distance, in the lanes and in the tail.
    #[test]
    fn moved_past_simd_equals_scalar_and_stops_at_non_finite() {
        let mut rng = signed(41);
        for n in [0usize, 3, 8, 13, 40] {
            let mut at: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| rng()).collect());
            let mut p = at.clone();
            for i in 0..n {
                p[i % 3][i] += if i % 4 == 0 { 0.5 } else { 0.1 * rng() };
            }
            if n > 5 {
                // Exactly at the bound (0.25² = lim2, every operation exact): not past it.
                for k in 0..3 {
                    (at[k][5], p[k][5]) = (0.0, 0.0);
                }
                p[1][5] = 0.25;
            }
            let (pr, ar) = ([&p[0][..], &p[1][..], &p[2][..]], [&at[0][..], &at[1][..], &at[2][..]]);
            let (mut a, mut b) = (Vec::new(), Vec::new());
            assert!(moved_past(pr, ar, n, 0.0625, false, &mut a));
            assert!(moved_past(pr, ar, n, 0.0625, true, &mut b));
            assert_eq!(a, b, "n {n}");
            let want: Vec<u32> = (0..n as u32).filter(|&i| i % 4 == 0).collect();
            assert_eq!(a, want, "n {n}: the particles moved 0.5");
        }
        let n = 13;
        for bad in [2usize, 11] {
            for v in [f32::NAN, f32::INFINITY] {
                let at = [vec![0.0f32; n], vec![0.0; n], vec![0.0; n]];
                let mut p = at.clone();
                p[2][bad] = v;
                let (pr, ar) = ([&p[0][..], &p[1][..], &p[2][..]], [&at[0][..], &at[1][..], &at[2][..]]);
                let mut out = Vec::new();
                for simd in [false, true] {
                    assert!(!moved_past(pr, ar, n, 1.0, simd, &mut out), "particle {bad} = {v}, simd {simd}");
                }
            }
        }
    }
}
