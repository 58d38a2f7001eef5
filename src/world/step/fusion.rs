//! Which of a step's passes run fused (the "fused forms" of the stage list in
//! [`world::step`](super::step)): decided once a step from the world's state. Every fused form
//! gives the same bits as its passes one after the other (`fusion_tests.rs`); none runs
//! in the stage-by-stage replay of the guard (`check`), which needs every stage apart.

use crate::world::World;

/// The fused forms a step runs.
#[derive(Clone, Copy, Debug)]
pub(super) struct Fusion {
    /// The guard's copy of `x, v` made inside the first predict and its finite check inside
    /// the last update, while the data is in cache.
    pub fused_guard: bool,
    /// Without wind nothing runs between a substep's update and the next substep's predict,
    /// and both are element-wise, so the update pass runs the next predict on each chunk
    /// while it is in cache: one sweep over the particles fewer a substep.
    pub fuse_next: bool,
    /// The speed clamp's mean velocity summed by the predict pass chunk by chunk while the
    /// velocities are in cache (the same sums as `mean_velocity`); obstacles change
    /// velocities between predict and the clamp, so they keep the separate pass.
    pub fused_mean: bool,
    /// All-shape obstacles run chunk by chunk inside the element-wise passes
    /// (`obstacles::chunkwise`): the contacts after each chunk's predict, the velocity pass
    /// after its update.
    pub chunk_obstacles: bool,
    /// And the last iteration's projection before its update, when nothing runs between the
    /// two (no scalp, no self-collision).
    pub fuse_project: bool,
    /// With one sweep a substep and nothing between the tethers and the update but the
    /// all-shape obstacles' projection, the tethers run chunk by chunk in the update pass,
    /// just before it (`TetherSet::solve_range`, the anchors copied before the pass), when
    /// the step runs on the pool and the world is small enough to gain from it.
    pub tethers_in_update: bool,
    /// One grid cloth swept once a substep with nothing else in the iteration but the
    /// tethers run in the update pass: the sweep
    /// hands each band of rows to the update pass as soon as it is done with it
    /// (`DistanceSet::solve_wave`), so a substep reads the particles from memory once.
    pub wave: bool,
    /// The wave predicts each band (and runs its obstacle contacts) just before it sweeps it,
    /// when bands start on whole blocks (and, with tethers, without wind or obstacles: their
    /// anchors are predicted ahead of the wave): element-wise, so the same bits as a pass
    /// before the sweep.
    pub wave_can_predict: bool,
}

/// Most particles for which the tethers run in the update pass ([`Fusion::tethers_in_update`]).
/// The bench cloth of `examples/step_times.rs` on two threads, against the tether pass: 0.82
/// of the time at 10 000 particles, 0.99 at 100 000, 1.03 at 1 000 000.
pub(crate) const TETHERS_IN_UPDATE_MAX: usize = 1 << 18;

impl World {
    /// The fused forms of this step for `n` particles: none with `check`; `self_collision`
    /// when the step runs self-collision, `simd` when it runs the lanes, `parallel` when it
    /// runs on the pool.
    pub(super) fn fusion(&self, check: bool, self_collision: bool, simd: bool, parallel: bool, n: usize) -> Fusion {
        let fuse = self.fuse_predict && !check;
        let has_obstacles = !self.obstacles.is_empty();
        let chunk_obstacles = has_obstacles && fuse && self.obstacles.runs_chunkwise();
        let no_wind = self.effects.wind.is_none() && self.wind.is_none();
        let alone =
            simd && fuse && self.params.iterations == 1 && self.scalps.is_empty() && !self_collision && (!has_obstacles || chunk_obstacles);
        // What the tethers in the update pass save is a fork and join or two a substep: on
        // one thread nothing, and past `TETHERS_IN_UPDATE_MAX` particles less than they cost.
        // The anchors must be pinned: the update pass's tethers read them before the sweep.
        let tethers_in_update = alone
            && parallel
            && n <= TETHERS_IN_UPDATE_MAX
            && !self.tethers.is_empty()
            && self.tethers.by_range()
            && self.tethers.anchors_pinned(&self.particles.w);
        let wave = alone && (self.tethers.is_empty() || tethers_in_update) && self.distance.wave_ready(n);
        Fusion {
            fused_guard: self.params.guard && !check,
            fuse_next: fuse && no_wind,
            fused_mean: self_collision && fuse && !has_obstacles,
            chunk_obstacles,
            fuse_project: chunk_obstacles && self.scalps.is_empty() && !self_collision,
            tethers_in_update,
            wave,
            // the tethers read the anchors' predictions before the wave: made ahead of it
            // from the anchors alone (`TetherSet::predict_anchors`), so without wind (whose
            // forces the predict reads by particle) or obstacles (whose contacts follow it)
            wave_can_predict: wave && self.distance.bands_on_blocks() && (self.tethers.is_empty() || (!has_obstacles && no_wind)),
        }
    }
}
