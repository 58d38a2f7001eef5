//! Where a step runs: on the caller's thread or in a rayon pool, and, for `threads = 0`, the
//! measured choice between the two.
//!
//! - `threads = 1`, [`World::set_caller_thread_only`], or the scalar backend: the caller's
//!   thread, no pool entered.
//! - `threads = k > 1` or a pool of the caller's ([`World::set_thread_pool`]): that pool, every
//!   step.
//! - `threads = 0` (the default): the global rayon pool or the caller's thread, whichever the
//!   world measures faster. Whether a second core pays depends on the size and on the effects
//!   (a plain 32 x 32 cloth steps faster alone, the same cloth with self-collision on two
//!   cores), so the world times its own steps: a *trial* of [`TRIAL_STEPS`] steps runs blocks of
//!   [`TRIAL_BLOCK`] steps in the pool and on the caller's thread in turn, the first
//!   [`TRIAL_WARM_UP`] of each block not counted (after a turn on the caller's thread the
//!   pool's second worker can take milliseconds to join in: on a 2-core virtual machine an
//!   idle CPU is slow to come back), and the side with the shortest counted step runs until
//!   the next trial: [`CONFIRM_AFTER`] steps after the first trial of a shape, after a close
//!   call and after a trial that reversed the one before it (a trial can catch the machine
//!   busy, an idle pool slow to wake: a choice lasts long only once two trials in a row made
//!   it), else [`RETRY_AFTER`] steps, and at once when the world's shape changes (particles,
//!   substeps, iterations, method, self-collision, obstacles).
//!
//! A fixed pool needs its cores: when one of them is busy with other work, a worker can be
//! preempted in the middle of a pass and the step waits for it, so `threads = k > 1` can step
//! several times slower than one thread; the measured choice then picks the caller's thread.
//!
//! Every choice gives the same bits (the kernels split their work into fixed chunks), so the
//! choice changes the time of a step, never its result. A pool's other workers poll for work
//! through the step's serial parts (`keep_awake`).

pub(crate) mod keep_awake;

use std::time::Instant;

use crate::data::exec::Exec;
use crate::model::params::{Backend, Method};
use crate::world::World;

/// Steps of one block of a trial of `threads = 0` (all in the pool or all on the caller's
/// thread).
pub const TRIAL_BLOCK: u32 = 8;

/// Steps at the start of a block that are not counted.
pub const TRIAL_WARM_UP: u32 = TRIAL_BLOCK / 2;

/// Steps of one trial: two blocks on each side, the pool first.
pub const TRIAL_STEPS: u32 = 4 * TRIAL_BLOCK;

/// Steps after the first trial of a shape before the second.
pub const CONFIRM_AFTER: u64 = 50;

/// Steps after any later trial before the next, when it chose by at least [`CLEAR_MARGIN`]
/// and as the trial before it did.
pub const RETRY_AFTER: u64 = 500;

/// How much slower the other side's shortest trial step must be for a choice to last
/// [`RETRY_AFTER`] steps; a closer choice is tried again after [`CONFIRM_AFTER`] (a close call
/// can flip with the machine's state, and its trials cost little: both sides are about as
/// fast).
pub const CLEAR_MARGIN: f64 = 1.25;

/// What makes a choice stale when it changes.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Shape {
    particles: usize,
    substeps: u32,
    iterations: u32,
    method: Method,
    self_collision: bool,
    obstacles: usize,
}

/// The state of the `threads = 0` choice (module docs).
#[derive(Clone, Debug)]
pub(crate) struct ThreadChoice {
    shape: Option<Shape>,
    /// Steps into the current trial; `TRIAL_STEPS` once chosen.
    trial: u32,
    /// Shortest counted step of the trial, s: pool, caller's thread.
    best: [f64; 2],
    /// The world's step count when the choice was made.
    chosen_at: u64,
    /// The outcome of the last finished trial of this shape: the choice.
    last: Option<ThreadChoiceReport>,
    /// Whether the last trial chose as the one before it (false after the first).
    agreed: bool,
    /// Start of the step being timed.
    start: Option<Instant>,
}

impl Default for ThreadChoice {
    fn default() -> Self {
        ThreadChoice {
            shape: None,
            trial: 0,
            best: [f64::INFINITY; 2],
            chosen_at: 0,
            last: None,
            agreed: false,
            start: None,
        }
    }
}

/// The outcome of the last `threads = 0` trial ([`World::thread_choice`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ThreadChoiceReport {
    /// The steps run on the caller's thread (else in the global pool).
    pub caller_thread: bool,
    /// Shortest trial step in the pool, ms.
    pub pool_ms: f64,
    /// Shortest trial step on the caller's thread, ms.
    pub caller_ms: f64,
}

impl ThreadChoice {
    /// Whether the next step runs on the caller's thread: the trial's odd blocks, then the
    /// choice.
    fn caller_next(&self) -> bool {
        if self.trial < TRIAL_STEPS {
            (self.trial / TRIAL_BLOCK) % 2 == 1
        } else {
            self.last.is_some_and(|l| l.caller_thread)
        }
    }

    /// Starts timing a step of a world of `shape` that has taken `steps` steps; starts a new
    /// trial when the shape changed or the choice is old (module docs).
    fn begin(&mut self, shape: Shape, steps: u64) {
        if self.shape != Some(shape) {
            *self = ThreadChoice {
                shape: Some(shape),
                ..ThreadChoice::default()
            };
        } else if self.trial >= TRIAL_STEPS {
            let (fast, slow) = (self.best[0].min(self.best[1]), self.best[0].max(self.best[1]));
            let close = slow < CLEAR_MARGIN * fast;
            let life = if close || !self.agreed { CONFIRM_AFTER } else { RETRY_AFTER };
            if steps.saturating_sub(self.chosen_at) >= life {
                (self.trial, self.best) = (0, [f64::INFINITY; 2]);
            }
        }
        self.start = Some(Instant::now());
    }

    /// Records a step that ended well, `secs` long (the world's step count now `steps`).
    fn record(&mut self, secs: f64, steps: u64) {
        if self.trial >= TRIAL_STEPS {
            return;
        }
        if self.trial % TRIAL_BLOCK >= TRIAL_WARM_UP {
            let side = usize::from(self.caller_next());
            self.best[side] = self.best[side].min(secs);
        }
        self.trial += 1;
        if self.trial == TRIAL_STEPS {
            self.chosen_at = steps;
            let caller_thread = self.best[1] < self.best[0];
            self.agreed = self.last.is_some_and(|l| l.caller_thread == caller_thread);
            self.last = Some(ThreadChoiceReport {
                caller_thread,
                pool_ms: self.best[0] * 1e3,
                caller_ms: self.best[1] * 1e3,
            });
        }
    }

    /// Ends timing the step started by [`ThreadChoice::begin`].
    fn end(&mut self, steps: u64) {
        if let Some(t0) = self.start.take() {
            self.record(t0.elapsed().as_secs_f64(), steps);
        }
    }

    /// Whether no trial runs and the last one chose as the one before it.
    fn settled(&self) -> bool {
        self.trial >= TRIAL_STEPS && self.agreed
    }

    /// The last finished trial's outcome (kept while a later trial runs).
    fn report(&self) -> Option<ThreadChoiceReport> {
        self.last
    }
}

impl World {
    /// How this world's stages run: the SIMD kernels unless the scalar backend is chosen, in
    /// parallel chunks unless the step runs on its caller's thread.
    pub(crate) fn exec(&self) -> Exec {
        let simd = self.params.backend == Backend::Simd;
        Exec::new(simd, simd && !self.on_caller_thread())
    }

    /// Whether the step runs on the caller's thread alone (module docs). A pool of one worker
    /// would only add a hand-off to another thread and back each step (about 60 µs, as much as
    /// a 100 x 100 cloth's whole step), so `threads = 1` makes none.
    pub(crate) fn on_caller_thread(&self) -> bool {
        self.embed.caller_thread_only
            || (self.pool.is_none() && self.params.threads == 1)
            || (self.measures_threads() && self.thread_choice.caller_next())
    }

    /// Whether the steps choose between the global pool and the caller's thread by measuring
    /// (`threads = 0`, SIMD kernels, no pool or caller-thread setting of the caller's).
    fn measures_threads(&self) -> bool {
        self.pool.is_none() && self.params.threads == 0 && self.params.backend == Backend::Simd && !self.embed.caller_thread_only
    }

    /// The outcome of the last finished `threads = 0` trial (module docs): `None` for other
    /// settings and before the first trial of the world's current shape has finished.
    pub fn thread_choice(&self) -> Option<ThreadChoiceReport> {
        if self.measures_threads() {
            self.thread_choice.report()
        } else {
            None
        }
    }

    /// Whether the `threads = 0` choice is settled: its last trial finished and made the
    /// choice of the one before it (always for other settings).
    pub(crate) fn thread_choice_settled(&self) -> bool {
        !self.measures_threads() || self.thread_choice.settled()
    }

    /// Starts timing a step for the `threads = 0` choice (nothing for other settings).
    pub(crate) fn begin_thread_choice(&mut self) {
        if self.measures_threads() {
            let shape = Shape {
                particles: self.particles.count(),
                substeps: self.params.substeps,
                iterations: self.params.iterations,
                method: self.params.method,
                self_collision: self.selfcol.active().is_some(),
                obstacles: self.obstacles.len(),
            };
            self.thread_choice.begin(shape, self.steps);
        }
    }

    /// Records the step begun by [`World::begin_thread_choice`], which ended well.
    pub(crate) fn end_thread_choice(&mut self) {
        self.thread_choice.end(self.steps);
    }

    /// Runs `f` (the substeps) where the step runs: on the caller's thread, or in the pool with
    /// its other workers polling for work between the passes ([`keep_awake`]).
    pub(crate) fn in_pool<R: Send>(&mut self, f: impl FnOnce(&mut World) -> R + Send) -> R {
        match self.pool.clone() {
            _ if self.on_caller_thread() || self.params.backend == Backend::Scalar => f(self),
            Some(pool) => pool.install(|| keep_awake::run(|| f(self))),
            // Enter the global pool once per step (one injected job instead of one per kernel).
            None => rayon::scope(|_| keep_awake::run(|| f(self))),
        }
    }
}

#[cfg(test)]
mod tests;
