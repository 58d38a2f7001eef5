//! `weft bench`: a quick (about 10 s) report of the kernel figures and the roofline for people without criterion
//! patience.

use std::path::Path;
use std::process::ExitCode;

use serde::Serialize;
use weft::perf;
use weft::scene::Scene;

mod self_collision;
pub use self_collision::bench_self_collision;

#[derive(Serialize)]
struct SceneFigure {
    scene: String,
    particles: usize,
    ms_per_step: f64,
}

#[derive(Serialize)]
struct DrapeFigure {
    particles: usize,
    threads: usize,
    substeps: u32,
    iterations: u32,
    ms_per_step: f64,
    /// Where the real step's time goes (adds up to the step).
    step_stages: Vec<perf::StepStageFigure>,
}

/// One effect's cost when named at zero strength against not named (same world, same steps).
#[derive(Serialize)]
struct EffectCost {
    effect: &'static str,
    particles: usize,
    ms_not_named: f64,
    ms_named_zero: f64,
    /// `ms_named_zero / ms_not_named`: what naming the effect costs even when it does nothing.
    ratio: f64,
}

#[derive(Serialize)]
struct Report {
    integrate_simd_speedup: f64,
    solve_simd_speedup: f64,
    step_thread_speedup: f64,
    /// Integrate (SIMD, 2 threads, 1M particles) as a fraction of the stream reference.
    integrate_bandwidth_fraction: f64,
    bandwidth: Vec<perf::BandwidthFigures>,
    kernels: Vec<perf::KernelFigures>,
    step_particles: usize,
    step_ms_1_thread: f64,
    step_ms_2_threads: f64,
    drape_1m_sphere: DrapeFigure,
    ms_per_step: Vec<SceneFigure>,
    /// Per effect, the step not named against named at zero strength.
    effect_cost: Vec<EffectCost>,
    /// Arithmetic peak of the roofline, single-precision vector GFLOP/s: one thread's FMA peak
    /// measured in this run, times the machine's threads.
    peak_gflops: f64,
    /// The headline cases against the machine's limits (`weft::perf::roofline`).
    roofline: Vec<perf::roofline::RooflineCase>,
}

/// Steps a 100k-particle cloth (one thread) with `effects` and with nothing named, alternating
/// three times and keeping each one's fastest median, per effect named at zero strength.
fn effect_costs() -> weft::Result<Vec<EffectCost>> {
    use weft::{Effects, Wind};
    let zero_wind = Wind {
        velocity: [0.0; 3],
        gust: 0.0,
        ..Wind::default()
    };
    let cases: [(&str, Effects); 3] = [
        (
            "gravity",
            Effects {
                gravity: Some([0.0; 3]),
                ..Effects::default()
            },
        ),
        (
            "drag",
            Effects {
                drag: Some(0.0),
                ..Effects::default()
            },
        ),
        (
            "wind",
            Effects {
                wind: Some(zero_wind),
                ..Effects::default()
            },
        ),
    ];
    let mut out = Vec::new();
    for (effect, named) in cases {
        let mut off = perf::cloth_world(100_000, 1)?;
        off.set_effects(Effects::default())?;
        let mut on = perf::cloth_world(100_000, 1)?;
        on.set_effects(named)?;
        let (mut a, mut b) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..3 {
            a = a.min(perf::step_ms(&mut off, 7)?);
            b = b.min(perf::step_ms(&mut on, 7)?);
        }
        out.push(EffectCost {
            effect,
            particles: off.particle_count(),
            ms_not_named: a,
            ms_named_zero: b,
            ratio: b / a,
        });
    }
    Ok(out)
}

pub fn bench(json: bool, scenes_dir: &Path) -> weft::Result<ExitCode> {
    let mut kernels = Vec::new();
    for (n, reps) in [(10_000usize, 41usize), (100_000, 21), (1_000_000, 7)] {
        let (i, s) = perf::kernel_figures(n, reps)?;
        kernels.push(i);
        kernels.push(s);
    }
    let find = |k: &str, n: usize| kernels.iter().find(|f| f.kernel == k && f.particles.abs_diff(n) < n / 50).cloned();
    let i100 = find("integrate", 100_000).expect("measured");
    let s100 = find("solve", 100_000).expect("measured");
    // Integrate against the stream reference (same arrays, same chunks, same pool).
    let bandwidth = vec![
        perf::stream_figures(1_000_000, 2, 9)?,
        perf::stream_figures(1_000_000, 1, 9)?,
        perf::stream_figures(100_000, 1, 21)?,
        perf::stream_figures(100_000, 2, 21)?,
    ];
    let mut w1 = perf::cloth_world(100_000, 1)?;
    let mut w2 = perf::cloth_world(100_000, 2)?;
    let t1 = perf::step_ms(&mut w1, 9)?;
    let t2 = perf::step_ms(&mut w2, 9)?;
    let drape = {
        let mut w = perf::sphere_drape_world(1_000_000, 2)?;
        let ms = perf::step_ms(&mut w, 5)?;
        let step_stages = perf::step_stage_times(&mut w, 3)?;
        DrapeFigure {
            particles: w.particle_count(),
            threads: 2,
            substeps: w.params().substeps,
            iterations: w.params().iterations,
            ms_per_step: ms,
            step_stages,
        }
    };
    let mut scenes = Vec::new();
    let mut paths: Vec<_> = std::fs::read_dir(scenes_dir)
        .map_err(|e| weft::WeftError::io(scenes_dir, e))?
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .collect();
    paths.sort();
    for p in paths.into_iter().filter(|p| p.extension().is_some_and(|e| e == "toml")) {
        let (scene, _) = Scene::load(&p)?;
        let mut w = scene.world()?;
        perf::roofline::past_thread_trials(&mut w)?;
        scenes.push(SceneFigure {
            scene: p.display().to_string(),
            particles: w.particle_count(),
            ms_per_step: perf::step_ms(&mut w, 15)?,
        });
    }
    let effect_cost = effect_costs()?;
    let (peak_gflops, roofline) = perf::roofline::headline_cases()?;
    let report = Report {
        integrate_simd_speedup: i100.simd_speedup,
        solve_simd_speedup: s100.simd_speedup,
        step_thread_speedup: t1 / t2,
        integrate_bandwidth_fraction: bandwidth[0].fraction,
        bandwidth,
        kernels,
        step_particles: w1.particle_count(),
        step_ms_1_thread: t1,
        step_ms_2_threads: t2,
        drape_1m_sphere: drape,
        ms_per_step: scenes,
        effect_cost,
        peak_gflops,
        roofline,
    };
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).map_err(|e| weft::WeftError::Scene(e.to_string()))?
        );
        return Ok(ExitCode::SUCCESS);
    }
    println!("kernel      particles   scalar ns/p   SIMD ns/p   SIMD 2t ns/p   SIMD/scalar   2t/1t");
    for k in &report.kernels {
        println!(
            "{:<10} {:>10} {:>13.2} {:>11.2} {:>14.2} {:>12.2}x {:>6.2}x",
            k.kernel, k.particles, k.scalar_ns, k.simd_ns, k.simd_2t_ns, k.simd_speedup, k.thread_speedup
        );
    }
    println!("integrate vs its memory ceiling (stream reference: same arrays read and written, trivial arithmetic)");
    println!("particles threads  scalar ns/p  SIMD ns/p  ceiling ns/p  fraction");
    for b in &report.bandwidth {
        println!(
            "{:>9} {:>7} {:>12.2} {:>10.2} {:>13.2} {:>8.0}%",
            b.particles,
            b.threads,
            b.scalar_ns,
            b.simd_ns,
            b.ceiling_ns,
            b.fraction * 100.0
        );
    }
    println!(
        "full step, {} particles, {} substeps x {} iterations: {t1:.2} ms on 1 thread, {t2:.2} ms on 2 ({:.2}x)",
        report.step_particles,
        w1.params().substeps,
        w1.params().iterations,
        t1 / t2
    );
    let d = &report.drape_1m_sphere;
    println!(
        "cloth (stretch + bend) over a sphere, {} particles, {} substeps, {} iteration, {} threads: {:.1} ms/step",
        d.particles, d.substeps, d.iterations, d.threads, d.ms_per_step
    );
    println!("  in the step (wall time per stage, adding up to the step):");
    for s in &d.step_stages {
        println!("    {:<26} {:>8.3} ms/step {:>6.1}%", s.stage, s.ms_per_step, s.share * 100.0);
    }
    for s in &report.ms_per_step {
        println!("scene {:<28} {:>8} particles {:>9.3} ms/step", s.scene, s.particles, s.ms_per_step);
    }
    println!(
        "roofline: compulsory bytes and flops per step against the stream bandwidth and the FMA peak ({:.0} GFLOP/s) measured now",
        report.peak_gflops
    );
    println!("  case                  particles      ms/step   memory ms   arith ms   limit ms  fraction  threads");
    for r in &report.roofline {
        let threads = match r.caller_thread {
            Some(true) => "0: caller",
            Some(false) => "0: pool",
            None => "2",
        };
        println!(
            "  {:<20} {:>10} {:>12.3} {:>11.3} {:>10.3} {:>10.3} {:>8.2}  {threads}",
            r.case, r.particles, r.ms, r.memory_ms, r.arithmetic_ms, r.limit_ms, r.fraction
        );
    }
    println!("effect cost (1 thread): step with the effect not named against named at zero strength");
    for e in &report.effect_cost {
        println!(
            "  {:<8} {:>8} particles {:>9.3} ms not named {:>9.3} ms named at zero  {:.2}x",
            e.effect, e.particles, e.ms_not_named, e.ms_named_zero, e.ratio
        );
    }
    Ok(ExitCode::SUCCESS)
}
