//! The roofline of a step: the bytes that must move and the flops that must be done, counted
//! from the data layout, against what the machine delivers in the same run.
//!
//! **Bytes.** An XPBD step of `s` substeps and `k` iterations must, per substep, read and
//! write every particle's state once for prediction and update (the pattern of
//! [`stream_reference`](super::stream_reference): 100 bytes a particle), and in each
//! iteration read and write every prediction once (24 + 24 bytes a particle). The
//! constraints of a grid cloth are implied by the grid and share their rest length and
//! compliance per family, so no constraint data is compulsory: the count is a lower bound
//! that any layout must pay, and what weft's layout moves beyond it (indices, rest lengths,
//! compliances, multipliers) shows as a fraction below one.
//!
//! **Flops.** Per substep and particle, 18 (prediction `v += h g`, `p = x + h v`; update
//! `v = (p - x) / h`); per constraint and iteration, 30 (difference, length, the XPBD
//! multiplier, two weighted corrections), counting a square root or a division as one.
//!
//! **Limits.** The memory limit is the bytes at the bandwidth the stream reference reaches
//! over the same number of particles (its best run on one or two threads); the arithmetic
//! limit is the flops at the peak of a register-only FMA loop of the vector width, measured on
//! one thread (best run) and counted once per thread ([`peak_gflops`]). A limit is what the machine can do, so the best runs
//! count; the step itself is timed by its median. `limit_ms` is the larger of the two times; `fraction` is
//! `limit_ms / ms`.

use crate::data::lanes::{F32s, LANES};
use crate::error::Result;
use crate::World;

/// Bytes a particle moves per substep in prediction and update (the stream reference's).
pub const INTEGRATE_BYTES: f64 = 100.0;
/// Bytes a particle moves per iteration (its prediction read and written once).
pub const SWEEP_BYTES: f64 = 48.0;
/// Flops a particle costs per substep in prediction and update.
pub const INTEGRATE_FLOPS: f64 = 18.0;
/// Flops a constraint costs per iteration.
pub const CONSTRAINT_FLOPS: f64 = 30.0;

/// The compulsory work of one step.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Work {
    /// Bytes that must move between the core and the level of memory the data lives in.
    pub bytes: f64,
    /// Floating-point operations.
    pub flops: f64,
}

/// The compulsory work of one step of `world` (module doc).
pub fn step_work(world: &World) -> Work {
    let n = world.particle_count() as f64;
    let m = world.distance_set().len() as f64;
    let (s, k) = (world.params().substeps as f64, world.params().iterations as f64);
    Work {
        bytes: s * n * (INTEGRATE_BYTES + k * SWEEP_BYTES),
        flops: s * (n * INTEGRATE_FLOPS + k * m * CONSTRAINT_FLOPS),
    }
}

/// Bytes per second the stream reference reaches over `n` particles: the best of `reps` runs on
/// one thread and on `threads` (a limit is what the machine can do, so the best run counts).
pub fn stream_bandwidth(n: usize, threads: usize, reps: usize) -> Result<f64> {
    let mut p = super::particle_cloud(n);
    let mut best = f64::INFINITY;
    for t in [1, threads.max(1)] {
        let pool = super::pool(t)?;
        best = best.min(pool.install(|| best_secs(reps, || super::stream_reference(&mut p, t > 1))));
    }
    Ok(INTEGRATE_BYTES * n as f64 / best)
}

/// The shortest of `reps` timings of `f` (after one untimed run), in seconds.
fn best_secs(reps: usize, f: impl FnMut()) -> f64 {
    super::timings(reps, f).into_iter().fold(f64::INFINITY, f64::min)
}

/// Independent accumulators of [`peak_gflops`]'s loop: enough to cover the FMA latency.
const CHAINS: usize = 8;

/// One thread's FMA loop: `iters` rounds of [`CHAINS`] independent vector FMAs. Returns a sum
/// so that the work is not optimised away.
fn fma_loop(iters: usize, seed: f32) -> f32 {
    let mut acc = [F32s::splat(seed); CHAINS];
    let (a, b) = (F32s::splat(0.999_999), F32s::splat(1e-7));
    for _ in 0..iters {
        for c in acc.iter_mut() {
            *c = c.mul_add(a, b);
        }
    }
    acc.iter().map(|v| v.reduce_add()).sum()
}

/// Peak single-precision GFLOP/s of vector FMAs on `threads` threads (best of `reps`): two
/// flops per lane per FMA, registers only.
pub fn peak_gflops(threads: usize, reps: usize) -> Result<f64> {
    const ITERS: usize = 200_000;
    let t = threads.max(1);
    let pool = super::pool(t)?;
    let mut sink = 0.0f32;
    // `broadcast` runs the loop once on every thread of the pool (a parallel iterator of `t`
    // items may run them all on one thread).
    let secs = best_secs(reps, || {
        sink += pool.broadcast(|ctx| fma_loop(ITERS, ctx.index() as f32)).iter().sum::<f32>();
    });
    std::hint::black_box(sink);
    Ok((t * ITERS * CHAINS * LANES * 2) as f64 / secs / 1e9)
}

/// The small case: a 100 x 100 cloth of 1 cm spacing hanging from its two first-row
/// corners, no tethers, `substeps x iterations`, on `threads` threads (0: the global pool or the
/// caller's thread, measured).
pub fn hanging_world(substeps: u32, iterations: u32, threads: usize) -> Result<World> {
    use crate::model::cloth::{ClothDesc, PinSpec};
    let desc = ClothDesc {
        rows: 100,
        cols: 100,
        spacing: 0.01,
        pins: vec![PinSpec::FirstRowCorners],
        tethers: None,
        ..Default::default()
    };
    let params = crate::model::params::SolverParams {
        substeps,
        iterations,
        threads,
        ..Default::default()
    };
    let mut w = World::new(params, crate::model::effects::Effects::gravity())?;
    w.add_cloth(&desc)?;
    Ok(w)
}

/// The bench cloth of [`cloth_world`](super::cloth_world) at 5 substeps x 1 iteration: the
/// `step_100k_5x1` case of [`headline_cases`] at any size.
pub fn cloth_world_5x1(n: usize, threads: usize) -> Result<World> {
    let mut w = super::cloth_world(n, threads)?;
    let mut p = w.params().clone();
    (p.substeps, p.iterations) = (5, 1);
    w.set_params(p)?;
    Ok(w)
}

/// The headline cases of `weft bench` (JSON `roofline`): the 100 x 100 hanging cloth at 1 x 1,
/// 5 x 1 and 10 x 10 (`threads = 0`, timed after the world's first two thread trials), a
/// 100k-particle cloth at 5 x 1 and the 1M-particle drape
/// over a sphere at 5 x 1 (two threads each). Also returns the arithmetic peak used: one
/// thread's measured FMA peak times the machine's threads.
pub fn headline_cases() -> Result<(f64, Vec<RooflineCase>)> {
    // One thread's peak times the threads: the FMA loop on two threads at once measured 120 or
    // 250 GFLOP/s from one run to the next (virtual CPUs that share a core some of the time),
    // one thread's is steady; a limit that assumes independent cores is the stricter one.
    let threads = rayon::current_num_threads().max(1);
    let gflops = peak_gflops(1, 9)? * threads as f64;
    let mut out = Vec::new();
    for (name, s, k, steps) in [
        ("cloth_100x100_1x1", 1, 1, 301),
        ("cloth_100x100_5x1", 5, 1, 201),
        ("cloth_100x100_10x10", 10, 10, 31),
    ] {
        let mut w = hanging_world(s, k, 0)?;
        past_thread_trials(&mut w)?;
        out.push(roofline_case(name, &mut w, steps, threads, gflops)?);
    }
    let mut w = cloth_world_5x1(100_000, 2)?;
    out.push(roofline_case("step_100k_5x1", &mut w, 21, 2, gflops)?);
    let mut w = super::sphere_drape_world(1_000_000, 2)?;
    out.push(roofline_case("drape_1m_5x1", &mut w, 7, 2, gflops)?);
    Ok((gflops, out))
}

/// Steps a `threads = 0` world through its first two thread trials
/// ([`crate::world::threads`]), and on through later ones while the last reversed the one
/// before it (at most [`EXTRA_TRIALS`] more), so that the timed steps all run where the world
/// settled (a world of another thread setting takes the first two trials' steps).
pub fn past_thread_trials(w: &mut World) -> Result<()> {
    use crate::world::threads::{CONFIRM_AFTER, TRIAL_STEPS};
    let dt = w.params().dt;
    let first = 2 * u64::from(TRIAL_STEPS) + CONFIRM_AFTER;
    let most = first + EXTRA_TRIALS * (u64::from(TRIAL_STEPS) + CONFIRM_AFTER);
    while w.steps() < first || (w.steps() < most && !w.thread_choice_settled()) {
        w.step(dt)?;
    }
    Ok(())
}

/// Most trials [`past_thread_trials`] waits for after the first two.
pub const EXTRA_TRIALS: u64 = 4;

/// One case of the roofline.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RooflineCase {
    /// Case name.
    pub case: String,
    /// Particles.
    pub particles: usize,
    /// Measured median ms per step.
    pub ms: f64,
    /// The step's compulsory work.
    pub work: Work,
    /// Time the compulsory traffic takes at the measured bandwidth, ms.
    pub memory_ms: f64,
    /// Time the compulsory flops take at the measured peak, ms.
    pub arithmetic_ms: f64,
    /// The larger of the two: the fastest the step could be on this machine.
    pub limit_ms: f64,
    /// `limit_ms / ms`.
    pub fraction: f64,
    /// With `threads = 0`: whether the world's trial chose the caller's thread (else the
    /// pool); absent for a fixed thread count.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub caller_thread: Option<bool>,
}

/// The roofline of `world`'s step: `steps` steps timed (median), the stream bandwidth
/// measured over the world's particle count on up to `threads` threads, `gflops` the peak.
pub fn roofline_case(case: &str, world: &mut World, steps: usize, threads: usize, gflops: f64) -> Result<RooflineCase> {
    let ms = super::step_ms(world, steps)?;
    let n = world.particle_count();
    let work = step_work(world);
    let bw = stream_bandwidth(n, threads, if n > 200_000 { 9 } else { 41 })?;
    let memory_ms = work.bytes / bw * 1e3;
    let arithmetic_ms = work.flops / (gflops * 1e9) * 1e3;
    let limit_ms = memory_ms.max(arithmetic_ms);
    Ok(RooflineCase {
        case: case.to_string(),
        particles: n,
        ms,
        work,
        memory_ms,
        arithmetic_ms,
        limit_ms,
        fraction: limit_ms / ms,
        caller_thread: world.thread_choice().map(|c| c.caller_thread),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn work_counts_follow_the_layout() {
        let mut w = super::super::cloth_world(100, 1).unwrap();
        let mut p = w.params().clone();
        (p.substeps, p.iterations) = (2, 3);
        w.set_params(p).unwrap();
        let n = w.particle_count() as f64;
        let m = w.distance_set().len() as f64;
        assert!(m > n, "a cloth has more constraints than particles");
        let work = step_work(&w);
        assert_eq!(work.bytes, 2.0 * n * (100.0 + 3.0 * 48.0));
        assert_eq!(work.flops, 2.0 * (18.0 * n + 3.0 * 30.0 * m));
    }

    #[test]
    fn the_fma_loop_computes() {
        // x -> 0.999999 x + 1e-7 converges towards 0.1 from 1: the sum moves.
        let s = fma_loop(1000, 1.0);
        assert!(s.is_finite() && s < (CHAINS * LANES) as f32, "{s}");
    }
}
