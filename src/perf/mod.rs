//! Quick performance report (`weft bench`): per-kernel cost, SIMD/scalar and 2-thread/1-thread
//! ratios, the integrate kernel against a memory-bandwidth reference, and whole-scene step
//! times.
//!
//! The bandwidth reference for integrate is [`stream_reference`]: two passes that read exactly
//! the arrays predict and update read and write exactly the arrays they write, in place, in
//! the same chunks on the same pool, with one add or subtract per value. Both therefore move
//! the same bytes with the same write-allocate traffic, so `t_stream / t_integrate` is the
//! fraction of what the memory system allows for this access pattern, with no byte counting
//! (a triad `a = b + s c` has a different read/write mix and overstates or understates it). Medians over repeated runs, measured in one process so the ratios are comparable;
//! criterion benches (`cargo bench`) are the careful version of the same figures.

pub mod roofline;

use crate::data::exec::Exec;
use std::time::Instant;

use crate::constraints::DistanceSet;
use crate::data::lanes::{load, Vec3x8, LANES};
use crate::data::particles::{ParticleChunk, Particles};
use crate::error::{Result, WeftError};
use crate::integrate::{predict, update, PredictParams};
use crate::model::cloth::{ClothDesc, PinSpec};
use crate::model::effects::Effects;
use crate::model::fabric::Fabric;
use crate::model::params::SolverParams;
use crate::model::self_collision::SelfCollision;
use crate::World;

/// `reps` (at least one) timings of `f` after one untimed run, in seconds.
pub fn timings(reps: usize, mut f: impl FnMut()) -> Vec<f64> {
    f();
    (0..reps.max(1))
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect()
}

/// Median of `reps` timings of `f`, in seconds.
pub fn median_secs(reps: usize, f: impl FnMut()) -> f64 {
    median_of(timings(reps, f))
}

/// The median of `v` (not empty).
fn median_of(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// How long a kernel runs untimed before [`kernel_median_secs`] times it: long enough for a
/// pool's other cores to be at work. On a virtual machine a core left idle (while a one-thread
/// figure was measured) can take milliseconds to come back, and a two-thread figure of a
/// short kernel then measured the first runs at one thread's speed. It does not remove the
/// spread of a machine shared with other work: compare several runs.
pub const WARM_UP_S: f64 = 0.1;

/// Median of `reps` timings of a kernel `f`, in seconds, after untimed runs for at least
/// [`WARM_UP_S`]: the cost of the kernel run back to back, as a simulation runs it.
pub fn kernel_median_secs(reps: usize, mut f: impl FnMut()) -> f64 {
    let warm = Instant::now();
    while warm.elapsed().as_secs_f64() < WARM_UP_S {
        f();
    }
    median_secs(reps, f)
}

/// Runs `f` as [`World::step`] runs its passes: the other workers of the pool the caller runs
/// in poll for work between the passes instead of falling asleep after each (the wake-up
/// would be timed with the next pass). The kernel figures' parallel runs go through it.
pub fn awake<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    crate::world::threads::keep_awake::run(f)
}

/// A rayon pool of `threads` threads.
pub fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| WeftError::param("threads", threads, format!("cannot start the thread pool: {e}")))
}

/// A square cloth world of about `n` particles (stretch, shear, bend, two pinned corners).
pub fn cloth_world(n: usize, threads: usize) -> Result<World> {
    let side = (n as f64).sqrt().round().max(1.0) as u32;
    let desc = ClothDesc {
        rows: side,
        cols: side,
        spacing: 0.01,
        pins: vec![PinSpec::FirstRowCorners],
        ..Default::default()
    };
    let mut w = World::new(
        SolverParams {
            threads,
            ..Default::default()
        },
        Effects::gravity(),
    )?;
    w.add_cloth(&desc)?;
    Ok(w)
}

/// The fold of `weft reproduce vccpbd` (Shapri, Sulaiman & Bade 2016, VcCPBD): a `size x size` cloth of 1 m
/// in `fabric` with the thickness of its spacing, hung over its middle row 1.5 m up, so that
/// both halves fall and fold face to face, with `self_collision` on. `params` gives threads,
/// substeps, iterations and backend; its `dt` is replaced by the fabric's, which is also
/// returned (the step to use). No tethers: see [`fold_world_tethered`].
pub fn fold_world(size: u32, fabric: Fabric, params: SolverParams, self_collision: SelfCollision) -> Result<(World, f32)> {
    fold_world_tethered(size, fabric, params, self_collision, None)
}

/// [`fold_world`] with tethers to the pinned row of slack `tethers` (a fraction of the rest
/// distance; `None` for none, an error if negative or not finite). At the paper's time steps
/// and 10 substeps the untethered cloth stretches well past its rest lengths near the line
/// (see `weft reproduce vccpbd --tethers`).
pub fn fold_world_tethered(
    size: u32,
    fabric: Fabric,
    params: SolverParams,
    self_collision: SelfCollision,
    tethers: Option<f32>,
) -> Result<(World, f32)> {
    if size < 2 {
        return Err(WeftError::param("size", size, "a fold needs at least 2 x 2 particles"));
    }
    let spacing = 1.0 / (size - 1) as f32;
    let fabric = Fabric {
        thickness: spacing,
        ..fabric
    };
    let dt = fabric.dt;
    let mut w = World::new(SolverParams { dt, ..params }, Effects::gravity())?;
    w.add_cloth(&ClothDesc {
        rows: size,
        cols: size,
        spacing,
        origin: [-0.5, 1.5, -0.5],
        u: [1.0, 0.0, 0.0],
        v: [0.0, 0.0, 1.0],
        fabric,
        pins: vec![PinSpec::Row(size / 2)],
        shear: true,
        bend: true,
        tethers,
    })?;
    w.set_self_collision(Some(self_collision))?;
    Ok((w, dt))
}

/// Pass 1 of the stream reference: reads x, v, w and writes v, p (as predict does):
/// `v += w`, `p = x + v`.
fn stream_predict(c: ParticleChunk<'_>) {
    for i in (0..c.x.len()).step_by(LANES) {
        let w = load(c.w, i);
        let v = Vec3x8::load(c.vx, c.vy, c.vz, i) + Vec3x8 { x: w, y: w, z: w };
        let p = Vec3x8::load(c.x, c.y, c.z, i) + v;
        v.store(c.vx, c.vy, c.vz, i);
        p.store(c.px, c.py, c.pz, i);
    }
}

/// Pass 2 of the stream reference: reads p, x and writes v, x (as update does): `v = p − x`,
/// `x = p`.
fn stream_update(c: ParticleChunk<'_>) {
    for i in (0..c.x.len()).step_by(LANES) {
        let p = Vec3x8::load(c.px, c.py, c.pz, i);
        let v = p - Vec3x8::load(c.x, c.y, c.z, i);
        v.store(c.vx, c.vy, c.vz, i);
        p.store(c.x, c.y, c.z, i);
    }
}

/// The stream reference over `p`: both passes, SIMD, in parallel chunks when `parallel` (on
/// the current rayon pool) — the memory ceiling of the integrate kernels' access pattern.
pub fn stream_reference(p: &mut Particles, parallel: bool) {
    p.for_chunks(parallel, stream_predict);
    p.for_chunks(parallel, stream_update);
}

/// Median seconds of [`stream_reference`] over `reps` runs.
pub fn time_stream_reference(p: &mut Particles, parallel: bool, reps: usize) -> f64 {
    kernel_median_secs(reps, || stream_reference(p, parallel))
}

/// Integrate against its memory ceiling at one size and thread count.
#[derive(Clone, Debug, serde::Serialize)]
pub struct BandwidthFigures {
    /// Particles.
    pub particles: usize,
    /// Threads (1: serial chunks; 2: parallel chunks on a 2-thread pool).
    pub threads: usize,
    /// Scalar twin on one thread, ns per particle.
    pub scalar_ns: f64,
    /// SIMD integrate (predict + update), ns per particle.
    pub simd_ns: f64,
    /// The stream reference over the same arrays, ns per particle.
    pub ceiling_ns: f64,
    /// `ceiling_ns / simd_ns`: the fraction of the memory ceiling integrate reaches.
    pub fraction: f64,
}

/// Measures integrate (scalar, SIMD) and the stream reference over `n` free particles on
/// `threads` threads, interleaving the two SIMD timings so that load from other processes
/// hits both alike.
pub fn stream_figures(n: usize, threads: usize, reps: usize) -> Result<BandwidthFigures> {
    let mut p = particle_cloud(n);
    let par = threads > 1;
    let pool = pool(threads)?;
    let scalar = pool.install(|| time_integrate(&mut p, Exec::Scalar, reps));
    let (mut kern, mut ceil) = (Vec::new(), Vec::new());
    for _ in 0..3 {
        kern.push(pool.install(|| time_integrate(&mut p, Exec::new(true, par), reps)));
        ceil.push(pool.install(|| time_stream_reference(&mut p, par, reps)));
    }
    let (kern, ceil) = (median_of(kern), median_of(ceil));
    let per = |t: f64| t * 1e9 / n as f64;
    Ok(BandwidthFigures {
        particles: n,
        threads,
        scalar_ns: per(scalar),
        simd_ns: per(kern),
        ceiling_ns: per(ceil),
        fraction: ceil / kern,
    })
}

/// Particles for a bandwidth measurement: `n` free particles on a line (no constraints).
pub fn particle_cloud(n: usize) -> Particles {
    let mut p = Particles::new();
    let pos: Vec<[f32; 3]> = (0..n).map(|i| [i as f32 * 1e-3, 1.0, 0.0]).collect();
    p.extend(&pos, &vec![1.0; n]);
    p
}

/// Seconds for one predict + update over `p` (SIMD or scalar twin, parallel or not).
pub fn time_integrate(p: &mut Particles, exec: Exec, reps: usize) -> f64 {
    let (simd, parallel) = (exec.simd(), exec.parallel());
    let params = PredictParams {
        h: 1.0 / 600.0,
        gravity: Some([0.0, -9.81, 0.0]),
        drag: None,
        force: None,
    };
    kernel_median_secs(reps, || {
        p.for_chunks(parallel, |c| predict(c, &params, simd));
        p.for_chunks(parallel, |c| update(c, 1.0 / 600.0, None, simd));
    })
}

/// Seconds for one sweep of the distance constraints.
pub fn time_solve(set: &mut DistanceSet, p: &mut Particles, exec: Exec, reps: usize) -> f64 {
    let (simd, parallel) = (exec.simd(), exec.parallel());
    let inv_h2 = 3.6e5;
    kernel_median_secs(reps, || {
        if simd {
            set.solve_simd(&mut p.px, &mut p.py, &mut p.pz, &p.w, inv_h2, parallel);
        } else {
            set.solve_scalar(&mut p.px, &mut p.py, &mut p.pz, &p.w, inv_h2);
        }
    })
}

/// One kernel's figures at one size.
#[derive(Clone, Debug, serde::Serialize)]
pub struct KernelFigures {
    /// Kernel name.
    pub kernel: &'static str,
    /// Particles.
    pub particles: usize,
    /// Scalar twin, ns per particle.
    pub scalar_ns: f64,
    /// SIMD on one thread, ns per particle (the median of [`THREAD_ROUNDS`]).
    pub simd_ns: f64,
    /// SIMD on two threads, ns per particle (the median of [`THREAD_ROUNDS`]).
    pub simd_2t_ns: f64,
    /// scalar / SIMD.
    pub simd_speedup: f64,
    /// SIMD 1 thread / SIMD 2 threads: the median of the rounds' ratios.
    pub thread_speedup: f64,
}

/// Rounds of one thread against two in [`kernel_figures`]: the threads' ratio is the median of
/// the rounds' ratios, each from one timing on one thread and one on two taken back to back,
/// so that a drift of the machine's speed between two timings moves one round, not the figure.
pub const THREAD_ROUNDS: usize = 5;

/// Measures integrate and solve at `n` particles.
pub fn kernel_figures(n: usize, reps: usize) -> Result<(KernelFigures, KernelFigures)> {
    let world = cloth_world(n, 1)?;
    let (one, two) = (pool(1)?, pool(2)?);
    let count = world.particle_count() as f64;
    let mut p = world.particles().clone();
    let mut set = world.distance_set().clone();
    let per = |s: f64| s * 1e9 / count;
    let is = one.install(|| time_integrate(&mut p, Exec::Scalar, reps));
    let ss = one.install(|| time_solve(&mut set, &mut p, Exec::Scalar, reps));
    let mut rounds = [(); 2].map(|_| Vec::new());
    for _ in 0..THREAD_ROUNDS {
        let iv = one.install(|| time_integrate(&mut p, Exec::Simd, reps));
        let i2 = two.install(|| awake(|| time_integrate(&mut p, Exec::Parallel, reps)));
        let sv = one.install(|| time_solve(&mut set, &mut p, Exec::Simd, reps));
        let s2 = two.install(|| awake(|| time_solve(&mut set, &mut p, Exec::Parallel, reps)));
        rounds[0].push((iv, i2));
        rounds[1].push((sv, s2));
    }
    let fig = |kernel, s: f64, r: &[(f64, f64)]| {
        let v = median_of(r.iter().map(|t| t.0).collect());
        KernelFigures {
            kernel,
            particles: count as usize,
            scalar_ns: per(s),
            simd_ns: per(v),
            simd_2t_ns: per(median_of(r.iter().map(|t| t.1).collect())),
            simd_speedup: s / v,
            thread_speedup: median_of(r.iter().map(|t| t.0 / t.1).collect()),
        }
    };
    Ok((fig("integrate", is, &rounds[0]), fig("solve", ss, &rounds[1])))
}

/// Median ms per step of `world` over `steps` steps.
pub fn step_ms(world: &mut World, steps: usize) -> Result<f64> {
    let dt = world.params().dt;
    let mut err = None;
    let t = median_secs(steps, || {
        if let Err(e) = world.step(dt) {
            err = Some(e);
        }
    });
    match err {
        Some(e) => Err(e),
        None => Ok(t * 1e3),
    }
}

/// The large case: a square cloth of about `n` particles with stretch and bend only
/// (no shear, no tethers, no pins) lying just above a sphere it drapes over, 5 substeps and
/// 1 iteration, on `threads` threads.
pub fn sphere_drape_world(n: usize, threads: usize) -> Result<World> {
    use crate::model::shapes::Shape;
    use crate::obstacles::Obstacle;
    let side = (n as f64).sqrt().round().max(2.0) as u32;
    let spacing = 2.0 / side as f32;
    let desc = ClothDesc {
        rows: side,
        cols: side,
        spacing,
        origin: [-1.0, 1.0, -1.0],
        u: [1.0, 0.0, 0.0],
        v: [0.0, 0.0, 1.0],
        pins: Vec::new(),
        shear: false,
        bend: true,
        tethers: None,
        ..Default::default()
    };
    let params = SolverParams {
        threads,
        substeps: 5,
        iterations: 1,
        ..Default::default()
    };
    let mut w = World::new(params, Effects::gravity())?;
    w.add_cloth(&desc)?;
    w.add_obstacle(Obstacle::shape(Shape::Sphere {
        center: [0.0, 0.49, 0.0],
        radius: 0.5,
    })?)?;
    Ok(w)
}

/// One stage's share of the real step ([`crate::world::stage_clock`]).
#[derive(Clone, Debug, serde::Serialize)]
pub struct StepStageFigure {
    /// Stage name (as the step's clock names it).
    pub stage: &'static str,
    /// Milliseconds per step (all substeps).
    pub ms_per_step: f64,
    /// Fraction of the step's wall time.
    pub share: f64,
}

/// Wall time per stage of `steps` real steps of `world` ([`World::set_stage_clock`]): what
/// the step spends where, stages adding up to the step. Leaves the clock off.
pub fn step_stage_times(world: &mut World, steps: usize) -> Result<Vec<StepStageFigure>> {
    let dt = world.params().dt;
    world.set_stage_clock(true);
    let ran = (0..steps.max(1)).try_for_each(|_| world.step(dt));
    let c = world.stage_clock();
    let (total, k) = (c.total().as_secs_f64(), c.steps().max(1) as f64);
    let out = c
        .stages()
        .iter()
        .map(|(stage, t)| StepStageFigure {
            stage,
            ms_per_step: t.as_secs_f64() * 1e3 / k,
            share: if total > 0.0 { t.as_secs_f64() / total } else { 0.0 },
        })
        .collect();
    world.set_stage_clock(false);
    ran.map(|_| out)
}
