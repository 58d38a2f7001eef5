//! `weft bench --self-collision`: the self-collision suite (`weft::suite`) on one and two
//! threads, with and without self-collision, audited for violations and crossings.

use std::path::Path;
use std::process::ExitCode;

use serde::Serialize;

/// One row of `weft bench --self-collision`: one suite scene on one thread count.
#[derive(Serialize)]
struct SelfCollisionFigure {
    scene: String,
    particles: usize,
    substeps: u32,
    threads: usize,
    /// The travel bound `T / d` the run used.
    travel: f32,
    /// Self-collision stages of the stage clock (lists, clamp, pairs and correction) per
    /// particle per substep, ns.
    collision_ns_per_particle_substep: f64,
    /// Those stages' share of the step's wall time (the measure's stage left out).
    collision_share: f64,
    step_ms_median: f64,
    step_ms_p95: f64,
    /// The same scene, same threads, self-collision off, in the same run of the command (the
    /// two runs step in alternating blocks of 30 steps).
    step_ms_median_without: f64,
    step_ms_p95_without: f64,
    /// The 1-thread run's step median over this run's, with self-collision (1 on one thread):
    /// the four runs of a scene (1 and 2 threads, with and without) step in turn, a block each.
    speedup_over_1_thread: f64,
    /// The paper's average collision: mean over the steps of the share of particles with a
    /// non-neighbour (rest distance above 1.5 d) closer than 0.9 d, %.
    avg_collision_pct: f64,
    /// Deepest `d - |x_i - x_j|` over the steps between non-neighbours (the pipeline's rule at
    /// the default travel, whatever the run's: another cloth or more than `REST_SKIP_FACTOR d`
    /// apart at rest), m.
    max_violation_m: f64,
    /// Layer crossings summed over the steps (`self_collision::audit::count_crossings`).
    crossings: u64,
    /// Pairs in the step's lists per particle, averaged over the steps: what each substep's
    /// pair pass tests.
    pairs_per_particle: f64,
    /// Pairs in contact per particle, averaged over the substeps: what the pass adds and the
    /// correction applies.
    contacts_per_particle_substep: f64,
    /// Mean wall ms per step of each stage of the stage clock, with self-collision.
    stages_ms: Vec<(&'static str, f64)>,
    /// The same without self-collision.
    stages_ms_without: Vec<(&'static str, f64)>,
}

fn stages_ms(w: &weft::World) -> Vec<(&'static str, f64)> {
    let steps = w.stage_clock().steps().max(1) as f64;
    w.stage_clock()
        .stages()
        .iter()
        .map(|(s, t)| (*s, t.as_secs_f64() * 1e3 / steps))
        .collect()
}

/// Stages of the step that belong to self-collision (the clamp's mean velocity, summed
/// inside predict, is not among them).
const COLLISION_STAGES: [&str; 3] = ["self-collision lists", "self-collision clamp", "self-collision pairs"];
const MEASURE_STAGE: &str = "self-collision measure";

fn stage_s(w: &weft::World, name: &str) -> f64 {
    w.stage_clock()
        .stages()
        .iter()
        .filter(|(s, _)| *s == name)
        .map(|(_, t)| t.as_secs_f64())
        .sum()
}

fn median_p95(mut ms: Vec<f64>) -> (f64, f64) {
    if ms.is_empty() {
        return (0.0, 0.0);
    }
    ms.sort_by(f64::total_cmp);
    let at = |q: f64| ms[((ms.len() - 1) as f64 * q).round() as usize];
    (at(0.5), at(0.95))
}

/// Steps each run takes before the next takes its turn, and states kept between two audits.
/// A scene's runs (with and without self-collision, on one and on two threads) step in turn,
/// a block each, so that all are timed under the same conditions of the machine and the
/// ratios of their medians do not follow a drift between separate runs. The audits run
/// between steps, and a pause between steps lets the pool's workers sleep (waking them costs
/// the next step), so they run once a block, on the kept states, rather than after every step.
const BLOCK: usize = 30;

/// Deepest violation and crossings over consecutive `states` (positions of one run).
fn audit_states(run: &weft::suite::SuiteRun, states: &[[Vec<f32>; 3]]) -> weft::Result<(f64, u64)> {
    use weft::self_collision::audit;
    let rule = run.rest_rule()?;
    let d = run.distance();
    let (mut deepest, mut crossings) = (0.0f64, 0u64);
    fn s(x: &[Vec<f32>; 3]) -> [&[f32]; 3] {
        [&x[0][..], &x[1][..], &x[2][..]]
    }
    for w in states.windows(2) {
        deepest = deepest.max(audit::deepest_violation(s(&w[1]), &rule, d)? as f64);
        crossings += audit::count_crossings(s(&w[0]), s(&w[1]), run.world.triangles(), &rule, 2.0 * d)? as u64;
    }
    Ok((deepest, crossings))
}

/// Times `count` steps of `run` into `ms` (the measure's stage subtracted); with `states`, keeps
/// the positions after each step for the audit.
fn timed_steps(
    run: &mut weft::suite::SuiteRun,
    count: usize,
    ms: &mut Vec<f64>,
    mut states: Option<&mut Vec<[Vec<f32>; 3]>>,
) -> weft::Result<()> {
    for _ in 0..count {
        run.prepare_step()?;
        let m0 = stage_s(&run.world, MEASURE_STAGE);
        let t0 = std::time::Instant::now();
        run.world_step()?;
        let wall = t0.elapsed().as_secs_f64();
        ms.push((wall - (stage_s(&run.world, MEASURE_STAGE) - m0)) * 1e3);
        if let Some(st) = states.as_deref_mut() {
            st.push(snapshot(run));
        }
    }
    Ok(())
}

/// A copy of the positions of `run` (one state for the audit).
fn snapshot(run: &weft::suite::SuiteRun) -> [Vec<f32>; 3] {
    run.world.positions().map(|a| a.to_vec())
}

/// Step times (ms) with and without self-collision of each pair of runs, deepest violation
/// (m) and crossings.
type Timed = (Vec<(Vec<f64>, Vec<f64>)>, f64, u64);

/// The step times (ms) of each `(on, off)` pair of `runs`, `steps` steps each, every run a
/// block of [`BLOCK`] steps in turn; also the deepest violation and the crossings of every step
/// of the first pair's `on` (outside the timed steps).
fn timed_runs(runs: &mut [(weft::suite::SuiteRun, weft::suite::SuiteRun)], steps: u32) -> weft::Result<Timed> {
    let steps = steps as usize;
    let mut ms: Vec<(Vec<f64>, Vec<f64>)> = runs
        .iter()
        .map(|_| (Vec::with_capacity(steps), Vec::with_capacity(steps)))
        .collect();
    let (mut deepest, mut crossings) = (0.0f64, 0u64);
    let mut states = runs.first().map(|(on, _)| vec![snapshot(on)]);
    let mut done = 0;
    while done < steps {
        let count = BLOCK.min(steps - done);
        for (k, ((on, off), (ms_on, ms_off))) in runs.iter_mut().zip(ms.iter_mut()).enumerate() {
            let audited = if k == 0 { states.as_mut() } else { None };
            timed_steps(on, count, ms_on, audited)?;
            if let (0, Some(st)) = (k, &mut states) {
                let (dv, c) = audit_states(on, st)?;
                deepest = deepest.max(dv);
                crossings += c;
                st.drain(..st.len() - 1);
            }
            timed_steps(off, count, ms_off, None)?;
        }
        done += count;
    }
    Ok((ms, deepest, crossings))
}

/// `weft bench --self-collision`: each suite scene on 1 and 2 threads, with and without
/// self-collision, `steps` steps each; with `pictures`, the last state of each scene as
/// `DIR/NAME.png`; `only` (if not empty) names the scenes to run; `travel` (if given) replaces
/// each scene's travel bound.
pub fn bench_self_collision(
    json: bool,
    dir: &Path,
    steps: u32,
    pictures: Option<&Path>,
    only: &[String],
    travel: Option<f32>,
) -> weft::Result<ExitCode> {
    use weft::suite::{SuiteRun, SCENES};
    if steps == 0 {
        return Err(weft::WeftError::param("steps", 0, "must be at least 1"));
    }
    if let Some(p) = pictures {
        std::fs::create_dir_all(p).map_err(|e| weft::WeftError::io(p, e))?;
    }
    if let Some(bad) = only.iter().find(|o| !SCENES.contains(&o.as_str())) {
        return Err(weft::WeftError::param(
            "only",
            bad,
            format!("expected scenes among {}", SCENES.join(", ")),
        ));
    }
    let mut rows = Vec::new();
    const THREADS: [usize; 2] = [1, 2];
    for name in SCENES.into_iter().filter(|s| only.is_empty() || only.iter().any(|o| o == s)) {
        let (mut runs, mut spans) = (Vec::new(), Vec::new());
        let mut used = 0.0;
        for threads in THREADS {
            let mut run = SuiteRun::load(dir, name, threads, true)?;
            if let Some(mut sc) = run.world.self_collision().cloned() {
                sc.measure = true;
                sc.travel = travel.unwrap_or(sc.travel);
                used = sc.travel;
                run.world.set_self_collision(Some(sc))?;
            }
            spans.push(crate::pictures::plane_span(&run.world));
            run.world.set_stage_clock(true);
            let mut off = SuiteRun::load(dir, name, threads, false)?;
            off.world.set_stage_clock(true);
            runs.push((run, off));
        }
        let (ms, deepest, crossings) = timed_runs(&mut runs, steps)?;
        let medians: Vec<_> = ms.into_iter().map(|(on, off)| (median_p95(on), median_p95(off))).collect();
        for (k, (threads, (run, off))) in THREADS.into_iter().zip(&runs).enumerate() {
            let w = &run.world;
            let collision_s: f64 = COLLISION_STAGES.iter().map(|s| stage_s(w, s)).sum();
            let clock_s = w.stage_clock().total().as_secs_f64() - stage_s(w, MEASURE_STAGE);
            let (n, substeps) = (w.particle_count(), w.params().substeps);
            let ((median, p95), (median_off, p95_off)) = medians[k];
            rows.push(SelfCollisionFigure {
                scene: name.to_string(),
                particles: n,
                substeps,
                threads,
                travel: used,
                collision_ns_per_particle_substep: collision_s * 1e9 / (steps as f64 * n as f64 * substeps as f64),
                collision_share: if clock_s > 0.0 { collision_s / clock_s } else { 0.0 },
                step_ms_median: median,
                step_ms_p95: p95,
                step_ms_median_without: median_off,
                step_ms_p95_without: p95_off,
                speedup_over_1_thread: medians[0].0 .0 / median,
                avg_collision_pct: w.self_collision_stats().average_pct,
                max_violation_m: deepest,
                crossings,
                pairs_per_particle: w.self_collision_stats().pairs_per_step / n.max(1) as f64,
                contacts_per_particle_substep: w.self_collision_stats().contacts_per_substep / n.max(1) as f64,
                stages_ms: stages_ms(w),
                stages_ms_without: stages_ms(&off.world),
            });
            if let (Some(dir), 1) = (pictures, threads) {
                let span = spans[k];
                let mut positions = Vec::new();
                w.positions_interleaved(&mut positions);
                let frame = crate::pictures::Frame {
                    positions,
                    normals: Vec::new(),
                    time: w.time(),
                    obstacles: crate::pictures::obstacle_items(w, span),
                };
                let style = crate::pictures::Style::default();
                let (width, height) = (480, 360);
                let frames = std::slice::from_ref(&frame);
                let cam =
                    crate::pictures::shared_camera(w, frames, width as f32 / height as f32, run.camera_eye, run.camera_target, style)?;
                crate::pictures::render_frame(w, &frame, width, height, cam, style)?.write_png(&dir.join(format!("{name}.png")))?;
            }
            if json {
                println!(
                    "{}",
                    serde_json::to_string(rows.last().expect("pushed")).map_err(|e| weft::WeftError::Scene(e.to_string()))?
                );
            }
        }
    }
    if json {
        return Ok(ExitCode::SUCCESS);
    }
    let travel = travel.map_or("each scene's".to_string(), |t| t.to_string());
    println!("self-collision suite, {steps} steps a run, travel {travel}; step ms with self-collision (median, p95) and without (median)");
    println!(
        "{:<8} {:>7} {:>3} {:>3} {:>9} {:>6} {:>8} {:>8} {:>8} {:>6} {:>6} {:>9} {:>10} {:>9} {:>7} {:>8}",
        "scene",
        "parts",
        "sub",
        "thr",
        "coll ns",
        "share",
        "median",
        "p95",
        "without",
        "ratio",
        "vs 1t",
        "avg coll%",
        "violation",
        "crossings",
        "pairs/p",
        "cont/p/s"
    );
    for r in &rows {
        println!(
            "{:<8} {:>7} {:>3} {:>3} {:>9.1} {:>5.0}% {:>8.3} {:>8.3} {:>8.3} {:>5.2}x {:>5.2}x {:>9.4} {:>10.2e} {:>9} {:>7.2} {:>8.3}",
            r.scene,
            r.particles,
            r.substeps,
            r.threads,
            r.collision_ns_per_particle_substep,
            r.collision_share * 100.0,
            r.step_ms_median,
            r.step_ms_p95,
            r.step_ms_median_without,
            r.step_ms_median / r.step_ms_median_without,
            r.speedup_over_1_thread,
            r.avg_collision_pct,
            r.max_violation_m,
            r.crossings,
            r.pairs_per_particle,
            r.contacts_per_particle_substep
        );
    }
    println!("mean ms per step by stage (with / without self-collision):");
    for r in &rows {
        let without = |s: &str| r.stages_ms_without.iter().find(|(n, _)| *n == s).map_or(0.0, |(_, t)| *t);
        let line: Vec<String> = r.stages_ms.iter().map(|(s, t)| format!("{s} {t:.3}/{:.3}", without(s))).collect();
        println!("  {} {}t: {}", r.scene, r.threads, line.join(", "));
    }
    Ok(ExitCode::SUCCESS)
}
