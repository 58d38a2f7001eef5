//! The step's pair list (the first bullet of the pipeline in [`crate::self_collision`]): each
//! particle's travel, the broadphase (hash or tree) built on the positions at the step's
//! start, or the kept candidates when they still hold ([`reuse`]), and the error of a
//! list past [`MAX_PAIRS_PER_PARTICLE`].

pub(crate) mod reuse;
pub(crate) mod travel;

use std::time::Instant;

use crate::data::exec::Exec;
use crate::error::{Result, WeftError};
use crate::self_collision::broadphase::{PairQuery, RestData};
use crate::self_collision::hash::SpatialHash;
use crate::self_collision::lists::travel::TravelRule;
use crate::self_collision::{SelfBroadphase, SelfCollisionData, State, MAX_PAIRS_PER_PARTICLE};

/// The error of a step whose pairs passed [`MAX_PAIRS_PER_PARTICLE`], for distance `d` and
/// reach `q`.
#[cold]
#[inline(never)]
fn too_many_pairs(d: f32, q: f32) -> WeftError {
    WeftError::param(
        "self_collision.distance",
        format!("{d} m"),
        format!(
            "gives more than {MAX_PAIRS_PER_PARTICLE} pairs a particle on average within the step's reach {q} m \
             (particles collapsed onto each other, or a distance far above the cloth's spacing): \
             lower the distance or the travel"
        ),
    )
}

/// The hash's cells are sized for all but at most `n / FAST_SHARE` of the fastest particles,
/// which search boxes of their own ([`SpatialHash::attach_travel`]).
const FAST_SHARE: usize = 32;

impl SelfCollisionData {
    /// Fills the step's lists from `x` (each pair once, rest neighbours dropped) and the flat
    /// pair list: from the kept candidates when they still hold ([`reuse`]), else from the
    /// broadphase built afresh; `false` when off.
    pub(super) fn build_lists(&mut self, x: [&[f32]; 3], n: usize, exec: Exec) -> Result<bool> {
        let Some(a) = self.active() else { return Ok(false) };
        if self.travel_now.is_none() || self.travel_of.len() < n {
            // No step has set the travels (or not for these particles): all the bound's.
            self.travel_of.clear();
            self.travel_of.resize(n, a.travel);
            self.travel_uniform = true;
        }
        let broadphase = self.config.as_ref().map(|c| c.broadphase).unwrap_or_default();
        let mut st = self.state.take().unwrap_or_else(|| State {
            hash: SpatialHash::new(n),
            ..State::default()
        });
        let q = a.q;
        let limit = MAX_PAIRS_PER_PARTICLE.saturating_mul(n);
        st.cand.set_limit(limit);
        st.lists.set_limit(limit);
        st.probe.set_limit(limit.saturating_mul(2));
        let t0 = Instant::now();
        let mut r = Ok(());
        let mut t1 = t0;
        st.fresh = false;
        if !st.reuse.holds(x, &self.travel_of, n, a.d, broadphase) {
            let skin = st.reuse.next_skin(a.d);
            let (d, travel) = (a.d, &self.travel_of[..]);
            let hashed = broadphase == SelfBroadphase::Hash && !self.travel_uniform;
            // Each particle's travel of the build: its own, or with a skin at least the cells'
            // members' (so the candidates last while a slow particle stays below it).
            let (cell, t_max) = (self.travel_cell.min(a.travel), a.travel);
            let build_travel = |i: usize| match (hashed, skin > 0.0) {
                (true, false) => travel[i],
                (true, true) => travel[i].max(cell),
                (false, _) => t_max,
            };
            // The hash searches each pair within its own reach plus the skin (travels raised by
            // half the skin, cells as wide as their members' reach); the tree, or a hash of
            // equal travels, searches the step's query radius plus the skin, and without a skin
            // keeps each pair within its own reach in its filter.
            let half = skin / (d + d);
            let members = cell + half;
            let reach = if hashed { d + (members + members) * d } else { q + skin };
            if hashed {
                self.travel_build.clear();
                self.travel_build.extend((0..n).map(|i| build_travel(i) + half));
            }
            let rest = self.rest_data();
            let query = PairQuery {
                x,
                n,
                d,
                reach,
                travel: match (hashed, skin == 0.0 && !self.travel_uniform) {
                    (true, _) => Some(&self.travel_build[..]),
                    (false, true) => Some(travel),
                    (false, false) => None,
                },
                members,
                rest,
                skip: a.skip,
            };
            let (bp, [cand, lists, _]) = st.broadphase(broadphase);
            r = bp.build(x, n, reach, rest, exec);
            t1 = Instant::now();
            // With a skin the query fills the candidates, filtered to the lists below; without,
            // it lists each pair within its own reach.
            let out = if skin > 0.0 { cand } else { lists };
            r = r.and_then(|_| bp.pairs(&query, out, exec));
            if r.is_ok() {
                st.reuse.built(x, n, a.d, build_travel, broadphase, skin);
                st.fresh = true;
            }
        }
        if r.is_ok() && st.reuse.skin() > 0.0 {
            r = reuse::within_reach(&st.cand, x, a.d, &self.travel_of, &mut st.lists, exec);
        }
        if st.cand.limited() || st.lists.limited() {
            r = Err(too_many_pairs(a.d, q));
        }
        let ph = &mut self.stats.phases;
        ph.build_s += t1.duration_since(t0).as_secs_f64();
        ph.query_s += t1.elapsed().as_secs_f64();
        ph.rebuilds = st.reuse.builds;
        st.ready = r.is_ok();
        if r.is_ok() {
            st.rows.fill(&st.lists.first, &st.lists.ids);
        } else {
            st.lists.clear();
            st.rows.fill(&[0], &[]);
        }
        self.state = Some(st);
        r.map(|_| true)
    }

    /// Sets this step's travel of every particle from the velocities `v` of the `n` particles
    /// (inverse masses `w`) at its start and the step `dt` (see the module docs): its speed
    /// relative to the free particles' mean, or the mean's own speed if larger, over a step,
    /// times [`TRAVEL_GROWTH`], at least [`TRAVEL_FLOOR`] and at most the setting's travel (a
    /// non-finite velocity gives the setting's travel).
    pub(crate) fn adapt_travel(&mut self, v: [&[f32]; 3], w: &[f32], n: usize, dt: f32, exec: Exec) {
        let Some(c) = self.config.as_ref() else { return };
        let (bound, d) = (c.travel, self.distance());
        let m = crate::self_collision::mean::mean_velocity_in(&mut self.mean_parts, v, w, n, exec);
        let len = v[0].len().min(v[1].len()).min(v[2].len());
        self.travel_of.clear();
        self.travel_of.resize(len.max(n), bound);
        let rule = TravelRule { m, dt, d, bound };
        let tally = rule.all(v, &mut self.travel_of[..n.min(len)], exec);
        self.travel_now = Some(tally.hi);
        self.travel_uniform = tally.lo == tally.hi;
        // The cells' members: every particle but at most `n / FAST_SHARE` of the fastest.
        self.travel_cell = rule.members_travel(&tally, n.min(len), n.min(len) / FAST_SHARE);
    }

    /// The cloths' rest positions and groups.
    pub(super) fn rest_data(&self) -> RestData<'_> {
        RestData {
            pos: [&self.rest[0], &self.rest[1], &self.rest[2]],
            cloth_of: &self.cloth_of,
        }
    }
}
