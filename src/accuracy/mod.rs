//! What accuracy costs in time: run a scene under a grid of solver settings and measure each
//! run against a reference solution.
//!
//! For every [`Setting`] (method × substeps × iterations × precision) the scene is simulated for
//! a fixed number of steps of its `dt`, timing only the steps, and compared after every step with
//! the cached f64 [`Reference`]:
//!
//! - **rms_error** — `sqrt(mean over steps and particles of |x - x_ref|²)`, m;
//! - **max_error** — the largest `|x - x_ref|` over the run, m;
//! - **max_strain** — the largest relative stretch of a stretch constraint over the run;
//! - **energy_drift** — `E(T) - E(0)`, J, with `E` = kinetic + gravitational + spring energy
//!   `Σ ½ k (l - rest)²` (the same energy for every method; [`Report::reference_drift`] is the
//!   reference's own change, which damping and drag make negative);
//! - **max_penetration / penetration_count** — the deepest any particle sat inside an obstacle
//!   after any step (exact signed distances of the shapes and closed meshes), and how many sit
//!   deeper than [`PENETRATION_COUNT_DEPTH`] at the end;
//! - **self_penetration_pct** — with self-collision, the mean over steps of the percentage of
//!   particles in penetration (VcCPBD's "average collision", [`crate::World::measure_self_collision`]).
//!
//! Every method runs the scene's obstacle and self-collision stages (the force-based methods
//! through `world::contacts`), and so does the f64 reference (analytic obstacles
//! and cloth self-collision; scenes with mesh obstacles fall back to an f32 reference and get no
//! f64 rows, [`ReferenceKind`]). With self-collision the grid also varies the response and the
//! broadphase ([`grid_for`]).
//!
//! A run whose step reports [`WeftError::Diverged`](crate::WeftError::Diverged), or whose RMS
//! error passes [`DIVERGED_RMS`], is reported as `diverged` with no numbers.
//!
//! **Bounded blow-ups.** A run can blow up and stay finite: the self-collision speed clamp
//! limits how far a particle moves per substep, not its velocity, so an unstable explicit run
//! keeps finite positions while its velocities (and energy) grow by many orders of magnitude.
//! Total energy cannot tell this apart from a stable stiff run, because the spring energy
//! `½ k (l - rest)²` of a cloth with `k = 1e8–1e9 N/m` is large for stretches that are tiny
//! (implicit Euler on cotton). Kinetic energy can: a stable run cannot move faster than the
//! energy it was given allows. The rule: a run whose kinetic energy after any step exceeds
//! [`BLOWUP_FACTOR`] times the reference's energy budget ([`energy_budget`]: the largest
//! kinetic energy of the reference and the largest gravitational energy it released) is
//! `diverged-bounded`, with no numbers; [`Outcome::kinetic_ratio`] reports every run's peak
//! ratio so the margin can be read.
//!
//! The Pareto front is the set of converged runs that no other run beats on both ms/step and
//! rms error.
//!
//! Tethers are position limits with no force counterpart, so [`prepare_scene`] switches them off
//! and every method integrates the same equations.

pub mod energy;
pub mod reference;
pub mod run;

pub use energy::{energy_budget, kinetic_energy, model_energy};
pub use reference::{fnv1a, MakeWorld, Reference, ReferenceKind, F32_REFERENCE_ITERATIONS};
pub use run::{
    default_grid, grid_for, obstacle_penetration, reference_drift, run_grid, run_setting, Outcome, Precision, Report, Setting,
    PENETRATION_COUNT_DEPTH,
};

use crate::scene::{Scene, TetherSetting};

/// RMS position error, m, past which a run counts as diverged even if it stayed finite.
pub const DIVERGED_RMS: f64 = 1e3;

/// Peak kinetic energy over the reference's energy budget past which a finite run counts as a
/// bounded blow-up (module docs).
pub const BLOWUP_FACTOR: f64 = 100.0;

/// The scene as the accuracy report simulates it: tethers off (see the module docs).
pub fn prepare_scene(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for c in &mut s.cloth {
        c.get_mut().tethers = Some(TetherSetting::Switch(false));
    }
    s
}

/// Indices of the Pareto front of `(time, error)` points: those no other point matches or beats
/// on both with one strictly better. `None` entries (diverged) are never on the front.
pub fn pareto(points: &[Option<(f64, f64)>]) -> Vec<bool> {
    points
        .iter()
        .map(|p| {
            let Some((t, e)) = *p else { return false };
            !points.iter().flatten().any(|&(t2, e2)| t2 <= t && e2 <= e && (t2 < t || e2 < e))
        })
        .collect()
}

#[cfg(test)]
mod tests;
