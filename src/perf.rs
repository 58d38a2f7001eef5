//! Quick performance report (`weft bench`): per-kernel cost, SIMD/scalar and 2-thread/1-thread
//! ratios, the integrate kernel against a memory-bandwidth reference, and whole-scene step
//! times. Medians over repeated runs, measured in one process so the ratios are comparable;
//! criterion benches (`cargo bench`) are the careful version of the same figures.

use std::time::Instant;

use crate::cloth::{ClothDesc, PinSpec};
use crate::constraints::DistanceSet;
use crate::effects::Effects;
use crate::error::{Result, WeftError};
use crate::integrate::{predict, update, PredictParams};
use crate::params::SolverParams;
use crate::particles::Particles;
use crate::world::World;

/// Bytes the integrate kernels (predict + update) move per particle: predict reads x, y, z,
/// vx, vy, vz, w and writes vx, vy, vz, px, py, pz; update reads px, py, pz, x, y, z and
/// writes vx, vy, vz, x, y, z — 25 arrays of f32.
pub const INTEGRATE_BYTES_PER_PARTICLE: f64 = 25.0 * 4.0;

/// Median of `reps` timings of `f`, in seconds.
pub fn median_secs(reps: usize, mut f: impl FnMut()) -> f64 {
    f();
    let mut t: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(|a, b| a.total_cmp(b));
    t[t.len() / 2]
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

/// Memory bandwidth reference: a triad `a = b + s c` over arrays totalling `bytes`, on the
/// current rayon pool (in parallel chunks), in bytes per second (loads plus stores, the same
/// accounting as the kernels). Use a size far beyond the last-level cache.
pub fn triad_bandwidth(bytes: usize, reps: usize) -> f64 {
    use rayon::prelude::*;
    let n = (bytes / 12).max(1024);
    let b = vec![1.0f32; n];
    let c = vec![2.0f32; n];
    let mut a = vec![0.0f32; n];
    let s = 0.5f32;
    let t = median_secs(reps, || {
        a.par_chunks_mut(1 << 16)
            .zip(b.par_chunks(1 << 16))
            .zip(c.par_chunks(1 << 16))
            .for_each(|((a, b), c)| {
                for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                    *a = *b + s * *c;
                }
            });
        std::hint::black_box(&mut a);
    });
    (n * 12) as f64 / t
}

/// Particles for a bandwidth measurement: `n` free particles on a line (no constraints).
pub fn particle_cloud(n: usize) -> Particles {
    let mut p = Particles::new();
    let pos: Vec<[f32; 3]> = (0..n).map(|i| [i as f32 * 1e-3, 1.0, 0.0]).collect();
    p.extend(&pos, &vec![1.0; n]);
    p
}

/// Bandwidth of the integrate kernels (SIMD, parallel on the current pool) over `n` particles,
/// in bytes per second, counting [`INTEGRATE_BYTES_PER_PARTICLE`].
pub fn integrate_bandwidth(n: usize, reps: usize) -> f64 {
    let mut p = particle_cloud(n);
    let t = time_integrate(&mut p, true, true, reps);
    n as f64 * INTEGRATE_BYTES_PER_PARTICLE / t
}

/// Seconds for one predict + update over `p` (SIMD or scalar twin, parallel or not).
pub fn time_integrate(p: &mut Particles, simd: bool, parallel: bool, reps: usize) -> f64 {
    let params = PredictParams {
        h: 1.0 / 600.0,
        gravity: Some([0.0, -9.81, 0.0]),
        drag: None,
        force: None,
    };
    median_secs(reps, || {
        p.for_chunks(parallel, |c| predict(c, &params, simd));
        p.for_chunks(parallel, |c| update(c, 1.0 / 600.0, None, simd));
    })
}

/// Seconds for one sweep of the distance constraints.
pub fn time_solve(set: &mut DistanceSet, p: &mut Particles, simd: bool, parallel: bool, reps: usize) -> f64 {
    let inv_h2 = 3.6e5;
    median_secs(reps, || {
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
    /// SIMD on one thread, ns per particle.
    pub simd_ns: f64,
    /// SIMD on two threads, ns per particle.
    pub simd_2t_ns: f64,
    /// scalar / SIMD.
    pub simd_speedup: f64,
    /// SIMD 1 thread / SIMD 2 threads.
    pub thread_speedup: f64,
}

/// Measures integrate and solve at `n` particles.
pub fn kernel_figures(n: usize, reps: usize) -> Result<(KernelFigures, KernelFigures)> {
    let world = cloth_world(n, 1)?;
    let (one, two) = (pool(1)?, pool(2)?);
    let count = world.particle_count() as f64;
    let mut p = world.particles().clone();
    let per = |s: f64| s * 1e9 / count;
    let is = one.install(|| time_integrate(&mut p, false, false, reps));
    let iv = one.install(|| time_integrate(&mut p, true, false, reps));
    let i2 = two.install(|| time_integrate(&mut p, true, true, reps));
    let mut set = world.distance_set().clone();
    let ss = one.install(|| time_solve(&mut set, &mut p, false, false, reps));
    let sv = one.install(|| time_solve(&mut set, &mut p, true, false, reps));
    let s2 = two.install(|| time_solve(&mut set, &mut p, true, true, reps));
    let fig = |kernel, s: f64, v: f64, t2: f64| KernelFigures {
        kernel,
        particles: count as usize,
        scalar_ns: per(s),
        simd_ns: per(v),
        simd_2t_ns: per(t2),
        simd_speedup: s / v,
        thread_speedup: v / t2,
    };
    Ok((fig("integrate", is, iv, i2), fig("solve", ss, sv, s2)))
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
