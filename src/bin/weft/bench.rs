//! `weft bench`: a quick (< 60 s) report of the kernel figures for people without criterion
//! patience.

use std::path::Path;
use std::process::ExitCode;

use serde::Serialize;
use weft::perf;
use weft::scene::Scene;

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
        scenes.push(SceneFigure {
            scene: p.display().to_string(),
            particles: w.particle_count(),
            ms_per_step: perf::step_ms(&mut w, 15)?,
        });
    }
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
        "full step, {} particles, 5 substeps: {t1:.2} ms on 1 thread, {t2:.2} ms on 2 ({:.2}x)",
        report.step_particles,
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
    Ok(ExitCode::SUCCESS)
}
