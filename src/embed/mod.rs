//! Embedding weft in an engine: the API a host program drives each frame without a scene file.
//!
//! A game or tool engine owns the clock, the threads and the render buffers; weft owns the
//! particles. This module is the seam between the two:
//!
//! - [`kinematic`]: move pinned particles (a hand, a hanger, an animated bone) each frame with
//!   [`World::set_pin_position`]. The pin gets the velocity implied by the move,
//!   `v = (target - x) / dt`, so within the step's substeps it travels in a straight line,
//!   `x_k = x + k h v`, and the constraints see a smooth motion instead of a teleport; after the
//!   step it sits exactly on the target.
//! - [`readback`]: copy positions and area-weighted vertex normals into the caller's buffer,
//!   interleaved or structure-of-arrays, with a length check and no other copy.
//! - [`advance`]: frame-rate independence. A render frame of any length feeds an accumulator;
//!   whole fixed steps of [`SolverParams::dt`](crate::SolverParams::dt) are taken from it
//!   (Fiedler, "Fix your timestep!"), so uneven frames never change the physics, and
//!   [`World::interpolated_positions`] blends the last two states for display.
//! - [`runtime`]: change stiffness at run time in place, snapshot and roll back, reset.
//! - Threads: global rayon pool or the calling thread, whichever measures faster
//!   (`threads = 0`, [`crate::world::threads`]), the calling thread (`threads = 1`), an own
//!   pool (`threads = k > 1`), a pool the caller gives ([`World::set_thread_pool`]) or the
//!   calling thread only whatever `threads` says ([`World::set_caller_thread_only`]); the
//!   results are the same bits in every case. A thread outside the global pool hands each
//!   step to it and sleeps until the step ends; a thread that steps many small worlds can
//!   join the pool first (`rayon::ThreadPoolBuilder::new().use_current_thread().build_global()`,
//!   as the `weft` binary does) and run the passes itself.
//!
//! After the first step of a scene whose topology does not change, [`World::step`] does not
//! allocate (tested with a counting global allocator in `tests/no_alloc_step.rs`).

pub mod advance;
pub mod kinematic;
pub mod readback;
pub mod runtime;

use std::sync::Arc;

use crate::world::World;

pub use advance::AdvanceReport;
pub use readback::{Soa, Vec3Out};
pub use runtime::Snapshot;

/// Default cap on fixed steps per [`World::advance`] call (the spiral-of-death guard).
pub const DEFAULT_MAX_STEPS_PER_ADVANCE: u32 = 8;

/// Per-world state of the embedding API (kept inside [`World`]).
#[derive(Clone, Debug)]
pub(crate) struct EmbedState {
    /// Kinematic targets for the next step: particle, position.
    pub(crate) pending: Vec<(u32, [f32; 3])>,
    /// Particles given a kinematic velocity by the last step (zeroed unless moved again).
    pub(crate) moving: Vec<u32>,
    /// Simulated time owed by [`World::advance`], s.
    pub(crate) accumulator: f64,
    /// Cap on steps per advance call.
    pub(crate) max_steps: u32,
    /// Positions before the last step taken by `advance`, for interpolation.
    pub(crate) prev: [Vec<f32>; 3],
    /// `World::steps()` when `prev` was saved.
    pub(crate) prev_steps: Option<u64>,
    /// The state before the first step (for [`World::reset`]).
    pub(crate) initial: Option<Box<Snapshot>>,
    /// Run every kernel on the calling thread.
    pub(crate) caller_thread_only: bool,
}

impl Default for EmbedState {
    fn default() -> Self {
        EmbedState {
            pending: Vec::new(),
            moving: Vec::new(),
            accumulator: 0.0,
            max_steps: DEFAULT_MAX_STEPS_PER_ADVANCE,
            prev: Default::default(),
            prev_steps: None,
            initial: None,
            caller_thread_only: false,
        }
    }
}

impl World {
    /// Runs the world's steps on a rayon pool the caller owns (shared with the engine, say).
    /// Replaces the world's own or global pool; a later [`set_params`](World::set_params) with a
    /// different `threads` value replaces it again. Results do not depend on the pool.
    pub fn set_thread_pool(&mut self, pool: Arc<rayon::ThreadPool>) {
        self.pool = Some(pool);
        self.embed.caller_thread_only = false;
    }

    /// With `true`, every kernel runs on the thread that calls [`step`](World::step): no rayon
    /// pool is entered and no task is spawned. The results are the same bits as with threads.
    pub fn set_caller_thread_only(&mut self, on: bool) {
        self.embed.caller_thread_only = on;
    }

    /// Whether kernels run on the calling thread only (see
    /// [`set_caller_thread_only`](World::set_caller_thread_only)).
    pub fn caller_thread_only(&self) -> bool {
        self.embed.caller_thread_only
    }

    /// Called by `rebuild_topology`: particle-indexed embedding state is no longer valid.
    pub(crate) fn embed_topology_changed(&mut self) {
        self.embed.pending.clear();
        self.embed.moving.clear();
        self.embed.prev_steps = None;
        self.embed.initial = None;
    }
}
