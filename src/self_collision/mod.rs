//! Cloth self-collision as particle–particle contacts (Müller's "Ten Minute Physics" self-collision and Shapri,
//! Sulaiman & Bade 2016, VcCPBD).
//!
//! # The pipeline
//! Constants: the travel bound `T_max = travel d` (the setting [`SelfCollision::travel`], 1 by
//! default), hash cell `CELL_FACTOR q` (1), VcCPBD box radius `r = BOX_RADIUS d` (1: with
//! `r = d/2` the box test put particles back into contact, 1.27% average collision on the
//! 100x100 fold against 0.0007% with `r = d`).
//!
//! * **Once a step** (`SelfCollisionData::adapt_travel`, `SelfCollisionData::begin_step`; the list in `lists`),
//!   the paper's "generate collision constraints" line of Algorithm 1. First each particle's
//!   travel `T_i`, how far it may move relative to the mean during the step: with `m` the
//!   mean velocity of the free particles and `u_i` the larger of `|v_i - m|` and `|m|` (a
//!   particle stopped by an obstacle moves at `-m` relative to the mean),
//!   `T_i = min(T_max, max(TRAVEL_FLOOR d, TRAVEL_GROWTH u_i dt))` ([`TRAVEL_FLOOR`] 0.25,
//!   [`TRAVEL_GROWTH`] 1.5). Two particles then close in by at most `T_i + T_j`, so the pair
//!   is listed when closer than its reach `d + T_i + T_j`: two particles at rest within
//!   `1.5 d`, two fast ones within `(1 + 2 travel) d`. The broadphase (the spatial hash, a
//!   counting sort of the particles over cells, or the AABB tree, refitted; one trait,
//!   `broadphase`, answers the same query with either) lists, from the
//!   positions `x` at the start of the step, every pair within its own reach, `d` the
//!   collision distance. The tree searches the step's query radius `q = d + 2 max T_i` and
//!   keeps each pair within its own reach in its filter. The hash's cells are as wide as the
//!   reach of its *members*, all particles but at most the fastest `n / FAST_SHARE` (their
//!   largest travel `T_c`, from a histogram of the travels: cells `d + 2 T_c`), which search
//!   over the half shell of their cell; each faster particle searches a box of its own, of
//!   radius `d + T_i + max T`, so a few fast particles do not widen every cell
//!   ([`SpatialHash::attach_travel`]). Kept candidates pass through `lists::reuse::within_reach`.
//!   **Rest neighbours** are dropped as the list is written: pairs of one cloth whose rest
//!   distance is at most `d + 2 T_max` (plus 0.1%,
//!   [`SelfCollision::rest_skip_factor`]: the rule does not change with the travels),
//!   held apart by the cloth's own constraints (in a flat cloth every pair the query finds is
//!   one). The lists hold at most [`MAX_PAIRS_PER_PARTICLE`] pairs a particle on average.
//!   Each pair is listed once, `(i, j)` with `i < j`, ordered by `i` then `j`, and read as a
//!   structure-of-arrays pair list: the lists' ids are the `j`, and each entry's `i` is
//!   written out (`pass::pairs`). Both broadphases give the same list (tested equal to each other
//!   and to a brute force).
//! * **After predict** (each substep): the speed clamp ([`crate::self_collision::clamp`])
//!   limits a free particle's velocity relative to the mean velocity of the free particles to
//!   `T_i / substeps` a substep, so two particles close in by at most `T_i + T_j` in a step:
//!   any pair that touches during the step is in the list. (The clamp is relative so a falling cloth
//!   still falls at full speed; Müller's version clamps absolute speed to one cell a substep.)
//!   It never speeds a particle up, so a particle slower than the mean (stopped by an obstacle)
//!   keeps its velocity and is exempt from the bound. The clamp bounds the predicted motion;
//!   the constraint sweeps move particles further, so the bound is the model's, not a proof.
//!   With its own travel a particle may gain half its relative speed from one step to the
//!   next (or `TRAVEL_FLOOR d` a step from rest) before the clamp holds it; the lists of a
//!   settled cloth, or of the slow particles of a busy one, are then a fraction of those at
//!   `T_max`.
//! * **After the constraint sweeps** (each substep): the pair pass below over the whole list,
//!   eight pairs at a time (`pass`), then the velocity-correction kernel
//!   ([`crate::self_collision::response`]) on the blocks of eight particles that received a
//!   contact, reading each particle's record of sums.
//!
//! # Pair pass
//! For each particle `i`, over its list (sorted ids, fixed order), with predicted positions `p`:
//!
//! ```text
//! rest neighbours (above): same cloth and |r_i - r_j| <= 1.001 (d + 2 T_max): never in the lists
//! rest rule (Müller): same cloth and |p_i - p_j| > |r_i - r_j| (rest grid positions): skip
//! min_dist = min(d, |r_i - r_j|);   contact if |p_i - p_j| < min_dist
//! n = (p_i - p_j) / |p_i - p_j|, or for coincident particles (distance 0) the rest direction
//!     (r_i - r_j) / |r_i - r_j|, or ±(1, 2, 3)/√14 by id order (antisymmetric, never NaN)
//! PBD, VcCPBD (Algorithm 1 projection):  c_i += w_i / (w_i + w_j) (min_dist - dist) n
//! movement speed: v_n = ((p_i - x_i) - (p_j - x_j)) · n;  if v_n < 0: c_i -= w_i / (w_i + w_j) v_n n
//! ```
//!
//! Each unordered pair is tested once, eight at a time (`f32x8` on gathered positions, with a
//! 1e-4 margin so that the scalar test above makes every decision: the SIMD and scalar
//! backends give the same bits); the contacts are then added to both particles' sums in list
//! order, so every particle sums its contacts in ascending partner order, as a loop over its
//! own sorted list would. The sums feed a Jacobi update (the kernel averages over the contact
//! count, the movement-speed correction over the approaching contacts, and over-relaxes the
//! average by [`RELAXATION`]), and the result is the same on any number of threads; the
//! serial loop is the twin.
//!
//! **Movement speed.** The VcCPBD paper names this response only as the velocity-based
//! technique of current software it compares against and gives no algorithm for it. Our
//! reading is the usual inelastic velocity response: zero the approaching normal velocity
//! (fully inelastic) and move the particle along its corrected velocity; it does not push out
//! an existing overlap, which is why it is the weakest of the three (as in the paper).
//!
//! # Average collision (the paper's metric)
//! A particle is *in penetration* when a non-neighbour particle (another cloth, or rest distance
//! above `1.5 d`) lies closer than `(1 - PENETRATION_TOLERANCE) d`. When the settings ask for
//! it ([`SelfCollision::measure`]; on demand otherwise) the percentage is measured
//! on the positions the next step's broadphase is built from, with its own query of that
//! broadphase (reach `(1 - PENETRATION_TOLERANCE) d`, outside the timed stage; it counts the
//! pairs between `1.5 d` and `q` at rest that the response leaves to the cloth's constraints),
//! and averaged over the steps ([`SelfCollisionStats`]).

pub mod audit;
pub(crate) mod broadphase;
pub mod clamp;
pub mod config;
pub mod hash;
mod lists;
pub(crate) mod mean;
pub mod neighbours;
pub(crate) mod pass;
pub mod response;
pub mod tree;

use crate::data::exec::Exec;
use std::time::Instant;

use crate::error::{positive, Result, WeftError};
use crate::self_collision::broadphase::{Broadphase, Tree};
use crate::self_collision::hash::SpatialHash;
use crate::self_collision::lists::reuse::Reuse;
use crate::self_collision::neighbours::Neighbours;
use crate::self_collision::pass::pairs::{PairCtx, PairRows};
pub(crate) use crate::self_collision::pass::ApplyParams;
use crate::self_collision::pass::{ContactPass, PredictionSink};

pub use crate::model::self_collision::{
    Response, SelfBroadphase, SelfCollision, BOX_RADIUS, CELL_FACTOR, MAX_TRAVEL, QUERY_FACTOR, RELAXATION, REST_SKIP_FACTOR,
    TRAVEL_FACTOR, TRAVEL_FLOOR, TRAVEL_GROWTH,
};
pub use crate::self_collision::config::{SelfCollisionPhases, SelfCollisionStats, PENETRATION_TOLERANCE};

/// Most pairs a step's lists may hold, per particle: the cap is `MAX_PAIRS_PER_PARTICLE n`
/// pairs in all, so one crowded region may hold more as long as the average stays below (the
/// metric's lists, which hold each pair twice, twice as many). The densest scenes of the
/// suite list about 20 a particle at the default travel, about 90 at the largest; a state that needs more has particles collapsed
/// onto each other or a collision distance far above the spacing, and would otherwise list
/// up to every pair (`n²`). Past it the step's broadphase stops and reports an error, the
/// step runs without self-collision, and [`SelfCollisionStats::failed_steps`] counts it.
pub const MAX_PAIRS_PER_PARTICLE: usize = 128;

/// Rest data of the cloths and the runtime state of self-collision, owned by the world.
#[derive(Clone, Debug, Default)]
pub struct SelfCollisionData {
    pub(crate) config: Option<SelfCollision>,
    /// Chunk sums of the speed clamp's mean velocity, kept so a step allocates none.
    pub(crate) mean_parts: crate::self_collision::mean::MeanParts,
    rest: [Vec<f32>; 3],
    cloth_of: Vec<u32>,
    /// The same, one `[x, y, z, cloth]` record a particle (the pair pass's contacts).
    rest4: Vec<[f32; 4]>,
    /// Smallest `min(thickness, spacing)` over the cloths (the default distance).
    default_distance: f32,
    state: Option<State>,
    pub(crate) stats: SelfCollisionStats,
    last_measured: Option<u64>,
    /// Copy the box centres in the clamp even when the correction could derive them (tests
    /// compare both).
    pub(crate) copy_centres: bool,
    /// This step's largest travel over `d` (at most the setting's), from the velocities at
    /// its start, each particle's (padded like the particle arrays), and whether they are all
    /// the same.
    travel_now: Option<f32>,
    pub(crate) travel_of: Vec<f32>,
    travel_uniform: bool,
    /// The largest travel over `d` of the hash cells' members this step (see
    /// [`SelfCollisionData::adapt_travel`]), and each particle's travel of the next build.
    travel_cell: f32,
    travel_build: Vec<f32>,
}

#[derive(Clone, Debug, Default)]
struct State {
    hash: SpatialHash,
    tree: Tree,
    /// Candidates within `q` plus the skin at their build, kept across steps while they hold.
    cand: Neighbours,
    reuse: Reuse,
    /// The step's pair lists (CSR, each pair under its smaller id).
    lists: Neighbours,
    /// The `i` of each entry of `lists`: the same pairs, flat.
    rows: PairRows,
    /// The substep pass's buffers.
    pass: ContactPass,
    /// Metric lists: non-neighbours within the penetration limit (not timed).
    probe: Neighbours,
    /// Whether the lists hold for this step's start.
    ready: bool,
    /// Whether the hash or tree was built from this step's start (not kept with the
    /// candidates).
    fresh: bool,
}

impl State {
    /// The broadphase of kind `kind`, with the lists it fills: the candidates, the step's
    /// lists and the metric's.
    fn broadphase(&mut self, kind: SelfBroadphase) -> (&mut dyn Broadphase, [&mut Neighbours; 3]) {
        let bp: &mut dyn Broadphase = match kind {
            SelfBroadphase::Hash => &mut self.hash,
            SelfBroadphase::AabbTree => &mut self.tree,
        };
        (bp, [&mut self.cand, &mut self.lists, &mut self.probe])
    }
}

/// What the step needs each substep.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Active {
    pub d: f32,
    pub response: Response,
    pub friction: f32,
    /// This step's largest travel over `d` (at most [`SelfCollision::travel`]).
    pub travel: f32,
    /// The query radius `q = d + 2 travel d` and the rest-skip radius (of the setting's
    /// travel), m.
    pub q: f32,
    pub skip: f32,
}

impl Active {
    /// The correction pass's parameters for a substep of length `h`.
    pub(crate) fn apply_params(&self, h: f32) -> ApplyParams {
        ApplyParams {
            response: self.response,
            friction: self.friction,
            h,
            r: BOX_RADIUS * self.d,
        }
    }
}

impl SelfCollisionData {
    /// Records the rest (grid) positions of a new cloth with index `cloth`.
    pub(crate) fn add_cloth(&mut self, rest: &[[f32; 3]], cloth: u32, spacing: f32, thickness: f32) {
        self.add_group(rest, cloth);
        let d = thickness.min(spacing);
        self.default_distance = if cloth == 0 { d } else { self.default_distance.min(d) };
    }

    /// Registers a piece that is not a cloth (a strand group) under its own group id: its rest
    /// positions feed the rest-neighbour rule; the default distance stays the cloths'.
    pub(crate) fn add_group(&mut self, rest: &[[f32; 3]], group: u32) {
        for p in rest {
            for (r, c) in self.rest.iter_mut().zip(p) {
                r.push(*c);
            }
            self.cloth_of.push(group);
            self.rest4.push(pass::pairs::rest_record(*p, group));
        }
        self.state = None;
    }

    /// The collision distance in use: the configured one, or `min(thickness, spacing)`.
    pub fn distance(&self) -> f32 {
        self.config.as_ref().and_then(|c| c.distance).unwrap_or(self.default_distance)
    }

    /// The active settings, if self-collision is on and the distance is positive.
    pub(crate) fn active(&self) -> Option<Active> {
        let c = self.config.as_ref()?;
        let d = self.distance();
        let travel = self.travel_now.map_or(c.travel, |t| t.min(c.travel));
        (d > 0.0 && d.is_finite()).then_some(Active {
            d,
            response: c.response,
            friction: c.friction,
            travel,
            q: d + (travel + travel) * d,
            skip: c.rest_skip_factor() * d,
        })
    }

    /// Lists the step's pairs from the positions `x` at its start (see the module docs) and
    /// readies the substep pass for `n` particles with damping rates `damping`. Returns
    /// `false` (nothing to do this step) when off. The broadphase runs on rayon only when
    /// `exec` is parallel (the same lists either way).
    pub(crate) fn begin_step(&mut self, x: [&[f32]; 3], n: usize, damping: &[f32], exec: Exec) -> Result<bool> {
        let t0 = Instant::now();
        match self.build_lists(x, n, exec) {
            Ok(true) => {}
            Ok(false) => return Ok(false),
            Err(e) => {
                self.stats.failed_steps += 1;
                self.stats.last_error = Some(e.to_string());
                return Err(e);
            }
        }
        if let Some(st) = &mut self.state {
            st.pass.prepare(n, damping);
            self.stats.record_pairs(st.lists.total());
        }
        let ph = &mut self.stats.phases;
        ph.step_start_s += t0.elapsed().as_secs_f64();
        Ok(true)
    }

    /// Where the speed clamp's chunks copy the predicted positions (the VcCPBD box centres).
    /// Only VcCPBD reads the box centres: the other responses get no sink (and the clamp
    /// copies nothing), and neither does a substep whose centres the correction derives from
    /// the velocities (`derive`: nothing changes the predictions or the velocities between
    /// predict and the clamp, i.e. no obstacles; then every free particle's prediction is
    /// `x + h v`, computed alike by both, and the velocities stay until the update).
    pub(crate) fn prediction_sink(&mut self, derive: bool) -> Option<PredictionSink> {
        let vc = self.config.as_ref().is_some_and(|c| c.response == Response::Vccpbd);
        let copy = vc && !self.derives_centres(derive);
        self.state.as_mut().filter(|_| copy).map(|st| st.pass.prediction_sink())
    }

    /// Whether the correction derives the box centres from the velocities when the step
    /// allows it (`derive`; see [`SelfCollisionData::prediction_sink`]).
    pub(crate) fn derives_centres(&self, derive: bool) -> bool {
        derive && !self.copy_centres
    }

    /// The pair pass: fills the contact sums from the predicted positions `p`, start
    /// positions `x` and inverse masses `w` (see the module docs). Parallel over fixed chunks
    /// of the pair list when `exec` is; the same bits either way.
    pub(crate) fn pair_pass(&mut self, x: [&[f32]; 3], p: [&[f32]; 3], w: &[f32], exec: Exec) {
        let t0 = Instant::now();
        let Some(a) = self.active() else { return };
        let Some(st) = self.state.as_mut().filter(|s| s.ready) else {
            return;
        };
        let ctx = PairCtx {
            x,
            p,
            w,
            rest4: &self.rest4,
            d: a.d,
            response: a.response,
        };
        st.pass.pair_pass(&ctx, st.rows.list(&st.lists.ids), exec);
        self.stats.phases.pairs_s += t0.elapsed().as_secs_f64();
        self.stats.record_contacts(st.pass.contacts());
    }

    /// The velocity-correction kernel on the blocks the pair pass touched, on the predicted
    /// positions `p`; with the substep's velocities `v`, the box centres are derived as
    /// `x + h v` instead of read from the copy the clamp kept (see
    /// [`SelfCollisionData::prediction_sink`]).
    pub(crate) fn apply(&mut self, x: [&[f32]; 3], w: &[f32], v: Option<[&[f32]; 3]>, p: [&mut [f32]; 3], ap: ApplyParams, exec: Exec) {
        let t0 = Instant::now();
        if let Some(st) = self.state.as_mut().filter(|s| s.ready) {
            st.pass.apply(x, w, v, p, ap, exec);
        }
        self.stats.phases.correction_s += t0.elapsed().as_secs_f64();
    }

    /// Each of the first `n` particles' travel over `d` this step (empty before a step has
    /// set them).
    pub fn step_travels(&self, n: usize) -> &[f32] {
        match self.travel_now {
            Some(_) => self.travel_of.get(..n).unwrap_or(&[]),
            None => &[],
        }
    }

    /// This step's largest travel over `d`, once a step has set it.
    pub fn step_travel(&self) -> Option<f32> {
        let c = self.config.as_ref()?;
        self.travel_now.map(|t| t.min(c.travel))
    }

    /// Number of pairs in the step's list.
    pub fn pair_count(&self) -> usize {
        self.state.as_ref().filter(|s| s.ready).map_or(0, |s| s.lists.total())
    }

    /// Blocks of eight particles the last pair pass found a contact in.
    pub fn touched_blocks(&self) -> usize {
        self.state.as_ref().filter(|s| s.ready).map_or(0, |s| s.pass.touched())
    }

    /// The pair lists of the current step (empty before the first step with self-collision).
    pub fn lists(&self) -> Option<&Neighbours> {
        self.state.as_ref().filter(|s| s.ready).map(|s| &s.lists)
    }
}

#[inline(always)]
fn dist2(a: &[impl AsRef<[f32]>; 3], i: usize, j: usize) -> f32 {
    let d = |k: usize| a[k].as_ref()[i] - a[k].as_ref()[j];
    let (dx, dy, dz) = (d(0), d(1), d(2));
    dx * dx + dy * dy + dz * dz
}

/// Checks a configuration (the scene parser checks ranges too; this guards the library API).
pub(crate) fn validate(c: &SelfCollision) -> Result<()> {
    if let Some(d) = c.distance {
        positive("self_collision.distance", d)?;
    }
    if !(c.friction.is_finite() && (0.0..=1.0).contains(&c.friction)) {
        return Err(WeftError::param("self_collision.friction", c.friction, "must be between 0 and 1"));
    }
    if !(c.travel > 0.0 && c.travel <= MAX_TRAVEL) {
        return Err(WeftError::param(
            "self_collision.travel",
            c.travel,
            format!("must be above 0 and at most {MAX_TRAVEL}"),
        ));
    }
    Ok(())
}

mod metric;

#[cfg(test)]
mod contacts_tests;
#[cfg(test)]
mod runs_tests;
