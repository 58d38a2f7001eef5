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
struct Report {
    integrate_simd_speedup: f64,
    solve_simd_speedup: f64,
    step_thread_speedup: f64,
    integrate_bandwidth_fraction: f64,
    bandwidth_reference_gb_s: f64,
    kernels: Vec<perf::KernelFigures>,
    step_particles: usize,
    step_ms_1_thread: f64,
    step_ms_2_threads: f64,
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
    // Bandwidth: both the kernel and the triad on two threads, over 4M particles (about 400 MB
    // moved per integrate, far beyond the last-level cache) so neither runs from cache.
    let two = perf::pool(2)?;
    let bw_particles = 4_000_000usize;
    let bytes = (bw_particles as f64 * perf::INTEGRATE_BYTES_PER_PARTICLE) as usize;
    let triad = two.install(|| perf::triad_bandwidth(bytes, 5));
    let kernel_bw = two.install(|| perf::integrate_bandwidth(bw_particles, 5));
    let mut w1 = perf::cloth_world(100_000, 1)?;
    let mut w2 = perf::cloth_world(100_000, 2)?;
    let t1 = perf::step_ms(&mut w1, 9)?;
    let t2 = perf::step_ms(&mut w2, 9)?;
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
        integrate_bandwidth_fraction: kernel_bw / triad,
        bandwidth_reference_gb_s: triad / 1e9,
        kernels,
        step_particles: w1.particle_count(),
        step_ms_1_thread: t1,
        step_ms_2_threads: t2,
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
    println!(
        "integrate at 4M particles, 2 threads: {:.1} GB/s vs a 2-thread triad over the same bytes {:.1} GB/s = {:.0}%",
        kernel_bw / 1e9,
        triad / 1e9,
        report.integrate_bandwidth_fraction * 100.0
    );
    println!(
        "full step, {} particles, 5 substeps: {t1:.2} ms on 1 thread, {t2:.2} ms on 2 ({:.2}x)",
        report.step_particles,
        t1 / t2
    );
    for s in &report.ms_per_step {
        println!("scene {:<28} {:>8} particles {:>9.3} ms/step", s.scene, s.particles, s.ms_per_step);
    }
    Ok(ExitCode::SUCCESS)
}
