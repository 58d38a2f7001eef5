//! Cloth self-collision as particle–particle contacts (Müller's "Ten Minute Physics" self-collision and Shapri,
//! Sulaiman & Bade 2016, VcCPBD).
//!
//! # The stage, once per step and once per substep
//! Constants: `q = QUERY_FACTOR d` (3), hash cell `CELL_FACTOR q` (1), travel `T = TRAVEL_FACTOR d`
//! (1), VcCPBD box radius `r = BOX_RADIUS d` (1: with `r = d/2` the box test put particles back
//! into contact, 1.27% average collision on the 100x100 fold against 0.0007% with `r = d`).
//!
//! * **Before the substeps** ([`SelfCollisionData::begin_step`]), the paper's "generate
//!   collision constraints" line of Algorithm 1, done once before the solver iterates: the
//!   broadphase (spatial hash or AABB tree, refitted) finds, from the positions `x` at the start
//!   of the step, every pair closer than the query radius `q = d + 2 T`, `d` the collision
//!   distance and `T = d` the relative travel a particle is allowed in one step, and drops the
//!   **rest neighbours** at once: pairs of one cloth whose rest distance is at most `q`
//!   (`REST_SKIP_FACTOR`). These are held by the cloth's own stretch, shear and bend
//!   constraints; in the flat cloth every pair the query finds is one, so before a fold the
//!   compact lists are empty. Each pair is listed once, under its smaller id (the hash tests
//!   `j > i` on the candidates before anything else). The substeps work only on the **active
//!   blocks** (eight consecutive particles, one of them with a partner; see the `self_active`
//!   module). Dropping rest neighbours is a rule, not an approximation: the same pairs would
//!   be dropped by a recomputation in every substep (tests hold the compact pass equal, bit
//!   for bit, to a brute force over all pairs with this rule).
//! * **Reuse** (the `self_verlet` module): the broadphase actually runs with the reach
//!   `q + skin` and its candidate lists are kept across steps while no particle has moved more
//!   than `0.49 skin` since; each step's lists are the candidates within `q` of each other at
//!   the step's start, exactly those of a fresh query (tests: lists equal and results bitwise
//!   equal to a rebuild every step, 1 and 2 threads, the three responses and both
//!   broadphases). The substeps test only a **near list** (candidates within `d + s₂` of where
//!   it was built, kept while no particle moves more than `0.49 s₂`), and only the blocks that
//!   received a contact are corrected; both exact too.
//!
//!   Why: on a folded cloth a fresh query every step dominated the stage, and the substeps
//!   tested thousands of listed pairs of which few were in contact. After the fold settles
//!   the lists last many steps and the near list holds a few hundred pairs; while the cloth
//!   falls every step still runs the query. The skin is `3 d` only when the cloth moved at
//!   most `d` a step since the last build (otherwise zero: a wider reach would cost more than
//!   the reuse saves; see `self_verlet`). With the hash such slow steps build no candidate
//!   lists at all: every block is active and the substeps query their mid list from a hash of
//!   the predicted positions (`self_verlet`, `self_near`), refreshed afterwards for the few
//!   particles that move past its bound (`self_mid`, per-particle references; the same
//!   lists). The hash query tests the rest-neighbour rule in its eight-lane mask (the
//!   `hash_rest` module), so only kept pairs leave the lanes, and walks the cells over a half
//!   shell (the `hash_cells` module: each pair tested once, the rows looked up once a cell).
//! * **After predict** (each substep): the speed clamp ([`crate::self_collision::response`]) limits a free
//!   particle's velocity relative to the mean velocity of the free particles to `T / substeps`
//!   a substep, so two particles close in by at most `2T` in a step: any pair that touches
//!   during the step was in the lists. (The clamp is relative so a falling cloth still falls at
//!   full speed; Müller's version clamps absolute speed to one cell a substep.) The clamp bounds the
//!   predicted motion; the constraint sweeps move particles further, so the bound is the
//!   model's, not a proof.
//! * **After the constraint sweeps** (each substep): the pair pass below over the active
//!   blocks, then the velocity-correction kernel [`crate::self_collision::response::apply`] on them.
//!
//! # Pair pass
//! For each particle `i`, over its list (sorted ids, fixed order), with predicted positions `p`:
//!
//! ```text
//! rest neighbours (above): same cloth and |r_i - r_j| <= q: never in the lists
//! rest rule (Müller): same cloth and |p_i - p_j| > |r_i - r_j| (rest grid positions): skip
//! min_dist = min(d, |r_i - r_j|);   contact if |p_i - p_j| < min_dist
//! n = (p_i - p_j) / |p_i - p_j|, or for coincident particles (distance 0) the rest direction
//!     (r_i - r_j) / |r_i - r_j|, or ±(1, 2, 3)/√14 by id order (antisymmetric, never NaN)
//! PBD, VcCPBD (Algorithm 1 projection):  c_i += w_i / (w_i + w_j) (min_dist - dist) n
//! movement speed: v_n = ((p_i - x_i) - (p_j - x_j)) · n;  if v_n < 0: c_i -= w_i / (w_i + w_j) v_n n
//! ```
//!
//! Each unordered pair is tested once, on the upper half of the lists (`j > i`), eight
//! candidates at a time (`f32x8` on gathered positions, with a 1e-4 margin so that the scalar
//! test above makes every decision: the SIMD and scalar backends give the same bits); the
//! contacts are then added to both particles' sums in `(i, j)` order, so every particle sums
//! its contacts in ascending partner order, as a loop over its own sorted list would
//! (the `self_active` module). The sums feed a Jacobi update (the kernel averages over the
//! contact count, the movement-speed correction over the approaching contacts), and the
//! result is the same on any number of threads; the serial loop is the twin.
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

pub(crate) mod active;
pub mod audit;
pub mod config;
pub mod hash;
pub(crate) mod near;
pub mod neighbours;
pub(crate) mod pairs;
pub mod response;
pub mod tree;
pub(crate) mod verlet;

use crate::data::exec::Exec;
use std::sync::OnceLock;
use std::time::Instant;

use crate::error::{positive, Result, WeftError};
use crate::self_collision::active::ActiveSet;
pub(crate) use crate::self_collision::active::ApplyParams;
use crate::self_collision::active::{PredictionSink, APPLY_PARALLEL_BLOCKS};
use crate::self_collision::hash::SpatialHash;
use crate::self_collision::near::mid::RestRule;
use crate::self_collision::near::{MidSource, MidUpdate, NearList};
use crate::self_collision::neighbours::Neighbours;
use crate::self_collision::pairs::PairCtx;
use crate::self_collision::tree::{ParticleTree, TreeShape};
use crate::self_collision::verlet::{Plan, VerletLists};

pub use crate::model::self_collision::{
    Response, SelfBroadphase, SelfCollision, BOX_RADIUS, CELL_FACTOR, QUERY_FACTOR, REST_SKIP_FACTOR, TRAVEL_FACTOR,
};
pub use crate::self_collision::config::{SelfCollisionPhases, SelfCollisionStats, PENETRATION_TOLERANCE};

/// Leaf size of the AABB tree (the paper's depth 5 gives ~312 particles a leaf at 10 000
/// particles; 16 queries much faster and gives the same pairs).
const TREE_LEAF: u32 = 16;

/// Rest data of the cloths and the runtime state of self-collision, owned by the world.
#[derive(Clone, Debug, Default)]
pub struct SelfCollisionData {
    pub(crate) config: Option<SelfCollision>,
    /// Chunk sums of the speed clamp's mean velocity, kept so a step allocates none.
    pub(crate) mean_parts: crate::self_collision::response::MeanParts,
    rest: [Vec<f32>; 3],
    cloth_of: Vec<u32>,
    /// Smallest `min(thickness, spacing)` over the cloths (the default distance).
    default_distance: f32,
    state: Option<State>,
    pub(crate) stats: SelfCollisionStats,
    last_measured: Option<u64>,
    /// Rebuild the candidate lists every step (no reuse): the reference the tests hold the
    /// reuse to.
    pub(crate) fresh_every_step: bool,
    /// Copy the box centres in the clamp even when the correction could derive them (tests
    /// compare both).
    pub(crate) copy_centres: bool,
}

#[derive(Clone, Debug)]
struct State {
    hash: SpatialHash,
    tree: Option<ParticleTree>,
    /// Whether the hash (or tree) was built from the positions of this step's start.
    structure_fresh: bool,
    /// Candidate lists (Verlet, reach `q + skin`), reused across steps.
    verlet: VerletLists,
    /// Near pairs of the candidates for the substeps.
    near: NearList,
    /// Candidate-list build the active blocks were made from.
    active_of: u64,
    /// Positions at the start of the step.
    start: [Vec<f32>; 3],
    /// Compact lists (partners within `q` at the step's start, rest neighbours left out),
    /// filtered from the candidates on demand.
    lists: OnceLock<Neighbours>,
    /// Metric lists: non-neighbours within the penetration limit (not timed).
    probe: Neighbours,
    ready: bool,
    active: ActiveSet,
}

/// What the step needs each substep.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Active {
    pub d: f32,
    pub response: Response,
    pub friction: f32,
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
        (d > 0.0 && d.is_finite()).then_some(Active {
            d,
            response: c.response,
            friction: c.friction,
        })
    }

    /// Makes the pair lists and the active blocks hold for the positions at the start of a
    /// step (reusing the candidate lists when they still hold, see [`crate::self_collision::verlet`]).
    /// Returns `false` (nothing to do this step) when off.
    pub(crate) fn begin_step(&mut self, x: [&[f32]; 3], n: usize, damping: &[f32], exec: Exec) -> Result<bool> {
        let t0 = Instant::now();
        let before = self.stats.phases.build_s + self.stats.phases.query_s;
        if !self.build_lists(x, n, exec)? {
            return Ok(false);
        }
        if let Some(st) = &mut self.state {
            if st.active_of != st.verlet.rebuilds {
                if st.verlet.is_direct() {
                    st.active.rebuild_all(n, damping);
                } else {
                    st.active.rebuild(&st.verlet.cand, n, damping);
                }
                st.active_of = st.verlet.rebuilds;
            } else {
                st.active.refresh_damping(damping);
            }
        }
        let ph = &mut self.stats.phases;
        let total = t0.elapsed().as_secs_f64();
        ph.step_start_s += total;
        ph.lists_s += total - (ph.build_s + ph.query_s - before);
        Ok(true)
    }

    /// Whether `i` and `j` are rest neighbours: one cloth, rest distance at most
    /// `REST_SKIP_FACTOR d`. Such pairs are never contacts (the cloth's own constraints keep
    /// them apart), so the broadphase drops them once per step.
    #[inline]
    pub(crate) fn rest_skipped(&self, i: usize, j: usize, d: f32) -> bool {
        RestRule::of(&self.rest, &self.cloth_of, d).skips(i, j)
    }

    /// Copies the step's start positions and runs the broadphase on `x` with the reach
    /// `q + skin` (`q = 3 d`) unless the candidate lists still hold, keeping each pair once
    /// (`(i, j)` in the list of `i`, `j > i`) and dropping rest neighbours; `false` when off.
    /// The broadphase runs on rayon only when `exec` is parallel (the same lists either way).
    fn build_lists(&mut self, x: [&[f32]; 3], n: usize, exec: Exec) -> Result<bool> {
        let Some(a) = self.active() else { return Ok(false) };
        let broadphase = self.config.as_ref().map(|c| c.broadphase).unwrap_or_default();
        let mut st = self.state.take().unwrap_or_else(|| State {
            hash: SpatialHash::new(n),
            tree: None,
            structure_fresh: false,
            verlet: VerletLists::default(),
            near: NearList::default(),
            active_of: u64::MAX,
            start: Default::default(),
            lists: OnceLock::new(),
            probe: Neighbours::new(),
            ready: false,
            active: ActiveSet::default(),
        });
        let q = QUERY_FACTOR * a.d;
        st.ready = false;
        st.lists = OnceLock::new();
        // Planned against the previous start positions (the motion of a step without lists),
        // then replaced by this step's.
        let prev = [&st.start[0][..], &st.start[1][..], &st.start[2][..]];
        let plan = st.verlet.plan(x, prev, n, a.d, broadphase, self.fresh_every_step);
        for (s, src) in st.start.iter_mut().zip(x) {
            s.clear();
            s.extend_from_slice(&src[..n.min(src.len())]);
        }
        let done = match plan {
            Plan::Keep => {
                st.structure_fresh = false;
                Ok(())
            }
            Plan::Direct => {
                st.structure_fresh = false;
                if st.verlet.went_direct() {
                    st.near.invalidate();
                }
                Ok(())
            }
            Plan::Build(skin) => {
                let reach = q + skin;
                // Each pair once (`j > i`), rest neighbours dropped.
                let keep = |i: usize, j: u32| j as usize > i && !self.rest_skipped(i, j as usize, a.d);
                let t0 = Instant::now();
                let built = self.build_structure(&mut st, x, n, reach, broadphase, exec);
                let t1 = Instant::now();
                let r = built.and_then(|_| match (&st.tree, broadphase) {
                    (Some(t), SelfBroadphase::AabbTree) => t
                        .query_all_exec(x[0], x[1], x[2], n, reach, &mut st.verlet.cand, exec)
                        .map(|_| st.verlet.cand.retain(keep)),
                    _ => st
                        .hash
                        .query_upper_unskipped_cells_exec(reach, REST_SKIP_FACTOR * a.d, &mut st.verlet.cand, exec),
                });
                let ph = &mut self.stats.phases;
                ph.build_s += t1.duration_since(t0).as_secs_f64();
                ph.query_s += t1.elapsed().as_secs_f64();
                match r {
                    Ok(()) => {
                        st.verlet.built(x, n, a.d, broadphase, skin);
                        st.near.invalidate();
                        self.stats.phases.rebuilds += 1;
                    }
                    Err(_) => st.verlet.invalidate(),
                }
                r
            }
        };
        st.ready = done.is_ok();
        self.state = Some(st);
        done.map(|_| true)
    }

    /// The cloths' rest positions (the pair pass spells the fields out: it also holds the
    /// state mutably).
    fn rest(&self) -> [&[f32]; 3] {
        [&self.rest[0], &self.rest[1], &self.rest[2]]
    }

    /// Builds the hash (cell `reach`) or refits the tree on `x`, in parallel when `exec` is.
    fn build_structure(&self, st: &mut State, x: [&[f32]; 3], n: usize, reach: f32, broadphase: SelfBroadphase, exec: Exec) -> Result<()> {
        st.structure_fresh = false;
        match broadphase {
            SelfBroadphase::Hash => {
                build_hash(&mut st.hash, x, n, reach, self.rest(), &self.cloth_of, exec.parallel())?;
            }
            SelfBroadphase::AabbTree => {
                let t = match st.tree.take() {
                    Some(mut t) if t.len() == n && exec.parallel() => t.refit(x[0], x[1], x[2], n).map(|_| t),
                    Some(mut t) if t.len() == n => t.refit_serial(x[0], x[1], x[2], n).map(|_| t),
                    _ => ParticleTree::build(x[0], x[1], x[2], n, TreeShape::LeafSize(TREE_LEAF)),
                }?;
                st.tree = Some(t);
            }
        }
        st.structure_fresh = true;
        Ok(())
    }

    /// Copies the predicted positions (the VcCPBD box centres) of the active blocks after
    /// the speed clamp.
    #[cfg(test)]
    pub(crate) fn keep_predictions(&mut self, p: [&[f32]; 3]) {
        if let Some(st) = &mut self.state {
            st.active.keep_predictions(p);
        }
    }

    /// Where the speed clamp's chunks copy the predictions of the active blocks (the parallel
    /// form of [`SelfCollisionData::keep_predictions`], the same copy).
    /// Only VcCPBD reads the box centres: the other responses get no sink (and the clamp
    /// copies nothing), and neither does a substep whose centres the correction derives from
    /// the velocities (`derive`: nothing changes the predictions or the velocities between
    /// predict and the clamp, i.e. no obstacles; then every free particle's prediction is
    /// `x + h v`, computed alike by both, and the velocities stay until the update).
    pub(crate) fn prediction_sink(&mut self, derive: bool) -> Option<PredictionSink<'_>> {
        let vc = self.config.as_ref().is_some_and(|c| c.response == Response::Vccpbd);
        let copy = vc && !self.derives_centres(derive);
        self.state.as_mut().filter(|_| copy).map(|st| st.active.prediction_sink())
    }

    /// Whether the correction derives the box centres from the velocities when the step
    /// allows it (`derive`; see [`SelfCollisionData::prediction_sink`]).
    pub(crate) fn derives_centres(&self, derive: bool) -> bool {
        derive && !self.copy_centres
    }

    /// The pair pass: updates the near list, then fills the contact sums of the active blocks
    /// from the predicted positions `p`, start positions `x` and inverse masses `w` (see the
    /// module docs). Parallel over fixed chunks when `parallel`; the serial loop is its twin.
    pub(crate) fn pair_pass(&mut self, x: [&[f32]; 3], p: [&[f32]; 3], w: &[f32], n: usize, exec: Exec) {
        let t0 = Instant::now();
        let Some(a) = self.active() else { return };
        let Some(st) = self.state.as_mut().filter(|s| s.ready) else {
            return;
        };
        let q = QUERY_FACTOR * a.d;
        let source = if st.verlet.is_direct() {
            MidSource::Hash(RestRule::of(&self.rest, &self.cloth_of, a.d))
        } else {
            // The candidate lists reach `q` plus their skin.
            MidSource::Candidates {
                cand: &st.verlet.cand,
                reach: q + st.verlet.skin(),
            }
        };
        let mid = st.near.update(source, p, &st.active.blocks, n, a.d, exec);
        let ctx = PairCtx {
            x,
            p,
            w,
            rest: [&self.rest[0], &self.rest[1], &self.rest[2]],
            cloth_of: &self.cloth_of,
            start: [&st.start[0], &st.start[1], &st.start[2]],
            q2: q * q,
            d: a.d,
            response: a.response,
        };
        st.active.pair_pass(&ctx, &st.near.pairs, exec);
        let ph = &mut self.stats.phases;
        ph.pairs_s += t0.elapsed().as_secs_f64();
        ph.mid_queries += u64::from(mid == MidUpdate::Queried);
        ph.mid_refreshes += u64::from(mid == MidUpdate::Refreshed);
    }

    /// The velocity-correction kernel on the active blocks of the predicted positions `p`;
    /// with the substep's velocities `v`, the box centres are derived as `x + h v` instead of
    /// read from the copy the clamp kept (see [`SelfCollisionData::prediction_sink`]).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn apply(&mut self, x: [&[f32]; 3], w: &[f32], v: Option<[&[f32]; 3]>, p: [&mut [f32]; 3], ap: ApplyParams, exec: Exec) {
        let simd = exec.simd();
        let t0 = Instant::now();
        if let Some(st) = self.state.as_ref().filter(|s| s.ready) {
            // On one worker the serial path (runs of blocks, one kernel call) is the faster.
            let parallel = exec.parallel() && st.active.touched() >= APPLY_PARALLEL_BLOCKS && rayon::current_num_threads() > 1;
            st.active.apply(x, w, v, p, ap, Exec::new(simd, parallel));
        }
        self.stats.phases.correction_s += t0.elapsed().as_secs_f64();
    }

    /// Number of active blocks (groups of eight particles the substeps work on): those holding
    /// a particle with a partner in the candidate lists (a superset of the step's lists).
    pub fn active_blocks(&self) -> usize {
        self.state.as_ref().filter(|s| s.ready).map_or(0, |s| s.active.len())
    }

    /// Blocks the last pair pass found a contact in.
    pub fn touched_blocks(&self) -> usize {
        self.state.as_ref().filter(|s| s.ready).map_or(0, |s| s.active.touched())
    }
}

/// Builds `hash` on `x` (first `n`) with cells of `reach` (times [`CELL_FACTOR`]) and
/// attaches the cloths' `rest` positions and `cloth_of` ids for the rest rule of its
/// self-collision query; `parallel` false builds serially (the same hash).
pub(crate) fn build_hash(
    hash: &mut SpatialHash,
    x: [&[f32]; 3],
    n: usize,
    reach: f32,
    rest: [&[f32]; 3],
    cloth_of: &[u32],
    parallel: bool,
) -> Result<()> {
    if parallel {
        hash.build(x[0], x[1], x[2], n, reach * CELL_FACTOR)?;
    } else {
        hash.build_serial(x[0], x[1], x[2], n, reach * CELL_FACTOR)?;
    }
    hash.attach_rest(rest, cloth_of)
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
    Ok(())
}

mod metric;

#[cfg(test)]
mod active_tests;
