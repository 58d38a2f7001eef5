//! `weft reproduce vccpbd`: the collision-time table of Shapri, Sulaiman & Bade (2016),
//! "Velocity Correction Position Based Dynamic to optimize collision computation in cloth
//! simulation".
//!
//! The paper times the collision stage of a cloth falling and folding onto itself, for three
//! grid sizes and four fabric presets (its dt, particle mass and damping), with three
//! responses. Our experiment: a 1 m square cloth, horizontal, hung over a line (its middle row
//! pinned) so both halves fall, swing under the line and fold against each other face to face.
//! Collision distance = thickness = grid spacing. Per row we report the self-collision time
//! per step (broadphase, speed clamp, pair pass, velocity correction), the whole step, and the
//! paper's "average collision" (percentage of particles in penetration after each step).
//! The paper's machine was a Core 2 Duo at 1.5 GHz running C#/XNA; ours is whatever runs this.
//!
//! Threads: the table runs on one thread by default (`--threads 2` for more), because
//! the paper's program was single-threaded and the table should compare like with like. The
//! results are the same bits on any thread count.
//!
//! A second table splits the collision time by phase (hash build, query, the rest of the step
//! start, substep pair passes, substep corrections, the speed clamp) and gives the number of
//! steps that ran the broadphase (the others reused the candidate lists).
//!
//! Substeps: 10 by default (`--substeps`). With 5 the fold still runs but the cloth does not
//! converge (the largest strain and the average collision grow several times).
//!
//! Stretch: the strain column is the largest `|l - l0| / l0` over all constraints. At the
//! paper's time steps with 10 substeps and no tethers the cloth stretches a great deal near
//! the line, with self-collision on or off: this is the solver's convergence (one Gauss-Seidel
//! sweep a substep over 50 rows of hanging cloth), not the collision response; more substeps
//! reduce it. `--tethers SLACK` ties every particle to the pinned row (long-range attachments,
//! slack a fraction of the rest distance): with slack 0 nearly every edge stays within 1% of
//! its rest length. That cloth folds tighter (its two layers touch over most of their area,
//! an order of magnitude more contacts a substep), and the collision stage costs about twice
//! as much. The table keeps the untethered fold by default; the tethered rows are the harder
//! case.
//!
//! `--repeat N` runs every row N times and keeps the run with the median collision time,
//! with the spread in a last table: single runs on a shared machine drift between runs.

use std::process::ExitCode;
use std::time::Instant;

use clap::Args;
use serde::Serialize;
use weft::model::self_collision::{Response, SelfBroadphase, SelfCollision};
use weft::{Fabric, SolverParams, WeftError, World};

/// Options of `weft reproduce vccpbd`.
#[derive(Args)]
pub struct VccpbdArgs {
    /// Fewer steps (a smoke run: figures are noisier).
    #[arg(long)]
    quick: bool,
    /// Print one JSON array instead of the table.
    #[arg(long)]
    json: bool,
    /// Steps per row (default 150, or 30 with --quick).
    #[arg(long)]
    steps: Option<u32>,
    /// Solver threads (default 1, like the paper's program; `2` is faster here, `0` measures
    /// which of all cores and one thread is, see the module docs).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Substeps a step (a modelling choice: fewer is faster but the cloth stretches more;
    /// the table reports the largest strain at the end of each row).
    #[arg(long, default_value_t = SUBSTEPS)]
    substeps: u32,
    /// Only the rows of this grid size (34, 50 or 100); all three when absent.
    #[arg(long)]
    size: Option<u32>,
    /// Tethers from every particle to the pinned row with this slack (a fraction of the rest
    /// distance, e.g. 0): a cloth that barely stretches, at a higher collision cost (see the
    /// module docs). None by default, like the figures of the table above.
    #[arg(long)]
    tethers: Option<f32>,
    /// Runs of every row: the table gives the run with the median collision time and a last
    /// table the spread (the shared machine's speed drifts between runs).
    #[arg(long, default_value_t = 1)]
    repeat: u32,
}

/// One row of the result.
#[derive(Serialize, Clone, Debug)]
struct Row {
    particles: usize,
    fabric: &'static str,
    response: &'static str,
    broadphase: &'static str,
    collision_ms: f64,
    step_ms: f64,
    avg_collision_pct: f64,
    paper_ms: f64,
    /// Process CPU time a step, ms (Linux `/proc/self/stat`; absent elsewhere). On a loaded
    /// machine wall time counts the waits for a core; CPU time does not.
    cpu_step_ms: Option<f64>,
    /// `cpu_step_ms` times the collision share of the wall time: an estimate of the collision
    /// CPU time a step, ms.
    cpu_collision_ms: Option<f64>,
    /// Largest constraint strain `|l - l0| / l0` at the end of the row.
    max_strain: f64,
    /// Collision wall time a step by phase, ms: hash build (or tree refit), broadphase
    /// query, rest of the step start (reuse check, flat pair list), substep pair passes,
    /// substep corrections; the speed clamp (with its mean velocity, summed in the predict
    /// pass) is the rest of `collision_ms`.
    phase_ms: [f64; 5],
    /// Steps that ran the broadphase (the others kept the candidate lists).
    rebuilds: u64,
    /// Runs of the row (`--repeat`); the row is the one with the median collision time.
    runs: u32,
    /// Smallest and largest collision wall ms a step over the runs.
    collision_ms_range: [f64; 2],
}

/// CPU time (user + system) of this process so far, s, from `/proc/self/stat` (100 ticks a
/// second, the Linux value); `None` where that file does not exist.
fn process_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // Fields 14 and 15 of the file (utime, stime) are 11 and 12 after the command name.
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

const SIZES: [u32; 3] = [34, 50, 100];
const FABRICS: [&str; 4] = ["basic", "cotton", "wool", "polyester"];
const RESPONSES: [Response; 3] = [Response::MovementSpeed, Response::Pbd, Response::Vccpbd];

/// The paper's collision time a step, ms: `[size][fabric][movement speed, PBD, VcCPBD]`.
const PAPER_MS: [[[f64; 3]; 4]; 3] = [
    [
        [2.290, 2.325, 2.281],
        [2.283, 2.191, 2.173],
        [2.322, 2.215, 2.173],
        [2.350, 2.316, 2.193],
    ],
    [
        [5.370, 5.310, 5.245],
        [5.131, 5.107, 5.097],
        [5.840, 5.301, 5.208],
        [5.585, 5.900, 5.396],
    ],
    [
        [28.331, 27.337, 24.232],
        [31.771, 28.631, 25.513],
        [36.497, 30.080, 26.788],
        [29.516, 29.589, 26.723],
    ],
];

/// The paper's average collision, %: movement speed, PBD, VcCPBD.
const PAPER_AVG_PCT: [f64; 3] = [1.995, 1.151, 1.018];

/// Substeps of the paper's (large) time step, by default.
const SUBSTEPS: u32 = 10;

/// What every row shares: steps, threads, substeps, tethers.
#[derive(Clone, Copy)]
struct RunCfg {
    steps: u32,
    threads: usize,
    substeps: u32,
    tethers: Option<f32>,
}

fn world(size: u32, fabric: &str, response: Response, broadphase: SelfBroadphase, cfg: RunCfg) -> weft::Result<(World, f32)> {
    let params = SolverParams {
        substeps: cfg.substeps,
        iterations: 1,
        threads: cfg.threads,
        ..Default::default()
    };
    let sc = SelfCollision {
        response,
        broadphase,
        measure: true,
        ..SelfCollision::default()
    };
    weft::perf::fold_world_tethered(size, Fabric::preset(fabric)?, params, sc, cfg.tethers)
}

/// Runs a row `runs` times (at least once) and keeps the run with the median collision time
/// (the upper median for an even count), with the spread over all runs.
fn measure_median(size: u32, fi: usize, ri: usize, broadphase: SelfBroadphase, cfg: RunCfg, runs: u32) -> weft::Result<Row> {
    let mut all = (0..runs.max(1))
        .map(|_| measure(size, fi, ri, broadphase, cfg))
        .collect::<weft::Result<Vec<Row>>>()?;
    all.sort_by(|a, b| a.collision_ms.total_cmp(&b.collision_ms));
    let range = [all[0].collision_ms, all[all.len() - 1].collision_ms];
    let mut row = all.swap_remove(all.len() / 2);
    row.runs = runs.max(1);
    row.collision_ms_range = range;
    Ok(row)
}

fn measure(size: u32, fi: usize, ri: usize, broadphase: SelfBroadphase, cfg: RunCfg) -> weft::Result<Row> {
    let (steps, response) = (cfg.steps, RESPONSES[ri]);
    let (mut w, dt) = world(size, FABRICS[fi], response, broadphase, cfg)?;
    let c0 = process_cpu_s();
    let t0 = Instant::now();
    for _ in 0..steps {
        w.step(dt)?;
    }
    let wall = t0.elapsed().as_secs_f64();
    let cpu = process_cpu_s()
        .zip(c0)
        .map(|(a, b)| (a - b) * 1e3 / steps.max(1) as f64)
        .filter(|c| *c > 0.0);
    w.measure_self_collision()?;
    let st = w.self_collision_stats();
    let si = SIZES.iter().position(|&s| s == size).unwrap_or(0);
    let step_ms = wall * 1e3 / steps.max(1) as f64;
    let share = if step_ms > 0.0 { st.ms_per_step() / step_ms } else { 0.0 };
    Ok(Row {
        particles: w.particle_count(),
        fabric: FABRICS[fi],
        response: response.name(),
        broadphase: broadphase.name(),
        collision_ms: st.ms_per_step(),
        step_ms,
        avg_collision_pct: st.average_pct,
        paper_ms: PAPER_MS[si][fi][ri],
        cpu_step_ms: cpu,
        cpu_collision_ms: cpu.map(|c| c * share),
        max_strain: w.metrics().max_strain,
        phase_ms: {
            let p = &st.phases;
            let list_rest = p.step_start_s - p.build_s - p.query_s;
            [p.build_s, p.query_s, list_rest, p.pairs_s, p.correction_s].map(|t| t * 1e3 / steps.max(1) as f64)
        },
        rebuilds: st.phases.rebuilds,
        runs: 1,
        collision_ms_range: [st.ms_per_step(); 2],
    })
}

/// The first columns of every table: the heading and a row's.
const KEY_HEAD: &str = "particles    fabric       response     broad";

fn key(r: &Row) -> String {
    format!("{:>9} {:>9} {:>14} {:>9}", r.particles, r.fabric, r.response, r.broadphase)
}

/// Runs the experiment and prints the table (or JSON).
pub fn run(args: VccpbdArgs) -> weft::Result<ExitCode> {
    let steps = args.steps.unwrap_or(if args.quick { 30 } else { 150 }).max(1);
    if args.substeps == 0 {
        return Err(WeftError::param("substeps", 0, "must be at least 1"));
    }
    if args.repeat == 0 {
        return Err(WeftError::param("repeat", 0, "must be at least 1"));
    }
    if let Some(t) = args.tethers.filter(|t| !(t.is_finite() && *t >= 0.0)) {
        return Err(WeftError::param("tethers", t, "slack must be a finite number, zero or greater"));
    }
    let cfg = RunCfg {
        steps,
        threads: args.threads,
        substeps: args.substeps,
        tethers: args.tethers,
    };
    let mut rows = Vec::new();
    if let Some(s) = args.size.filter(|s| !SIZES.contains(s)) {
        return Err(WeftError::param("size", s, "must be 34, 50 or 100"));
    }
    for &size in SIZES.iter().filter(|&&s| args.size.is_none_or(|a| a == s)) {
        for fi in 0..FABRICS.len() {
            for ri in 0..RESPONSES.len() {
                rows.push(measure_median(size, fi, ri, SelfBroadphase::Hash, cfg, args.repeat)?);
            }
            rows.push(measure_median(size, fi, 2, SelfBroadphase::AabbTree, cfg, args.repeat)?);
        }
    }
    if args.json {
        let s = serde_json::to_string_pretty(&rows).map_err(|e| WeftError::Scene(e.to_string()))?;
        println!("{s}");
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "VcCPBD (Shapri et al. 2016): cloth hung over a line folding onto itself, {steps} steps a row, {} substeps, {} thread(s), {}{}",
        args.substeps,
        args.threads,
        match args.tethers {
            Some(t) => format!("tethers to the line (slack {t})"),
            None => "no tethers".to_string(),
        },
        if args.repeat > 1 {
            format!(", each row the median of {} runs", args.repeat)
        } else {
            String::new()
        }
    );
    println!("collision, step: wall ms a step (ours); cpu coll, cpu step: CPU ms a step (collision estimated from its wall share)");
    println!("ratio = paper collision ms / our collision wall ms; cpu rat = paper / our collision CPU ms");
    println!();
    println!(
        "{} {:>10} {:>9} {:>9} {:>9} {:>10} {:>9} {:>8} {:>8} {:>7}",
        KEY_HEAD, "collision", "step", "cpu coll", "cpu step", "avg coll%", "paper ms", "ratio", "cpu rat", "strain"
    );
    for r in &rows {
        println!(
            "{} {:>10.3} {:>9.3} {:>9.3} {:>9.3} {:>10.3} {:>9.3} {:>7.2}x {:>7.2}x {:>7.4}",
            key(r),
            r.collision_ms,
            r.step_ms,
            r.cpu_collision_ms.unwrap_or(f64::NAN),
            r.cpu_step_ms.unwrap_or(f64::NAN),
            r.avg_collision_pct,
            r.paper_ms,
            r.paper_ms / r.collision_ms.max(1e-9),
            r.paper_ms / r.cpu_collision_ms.unwrap_or(f64::NAN).max(1e-9),
            r.max_strain
        );
    }
    println!();
    println!("collision wall ms a step by phase (clamp = the rest), broadphase runs out of {steps} steps");
    println!(
        "{} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>8}",
        KEY_HEAD, "build", "query", "start", "pairs", "correct", "clamp", "rebuilds"
    );
    for r in &rows {
        let p = r.phase_ms;
        println!(
            "{} {:>7.3} {:>7.3} {:>7.3} {:>7.3} {:>7.3} {:>7.3} {:>8}",
            key(r),
            p[0],
            p[1],
            p[2],
            p[3],
            p[4],
            r.collision_ms - p.iter().sum::<f64>(),
            r.rebuilds
        );
    }
    println!();
    if args.repeat > 1 {
        println!(
            "collision wall ms a step over the {} runs of each row (the tables give the median run)",
            args.repeat
        );
        println!(
            "{} {:>9} {:>9} {:>9} {:>8} {:>8}",
            KEY_HEAD, "min", "median", "max", "ratio lo", "ratio hi"
        );
        for r in &rows {
            let [lo, hi] = r.collision_ms_range;
            println!(
                "{} {:>9.3} {:>9.3} {:>9.3} {:>7.2}x {:>7.2}x",
                key(r),
                lo,
                r.collision_ms,
                hi,
                r.paper_ms / hi.max(1e-9),
                r.paper_ms / lo.max(1e-9)
            );
        }
        println!();
    }
    for (ri, resp) in RESPONSES.iter().enumerate() {
        let mine: Vec<&Row> = rows
            .iter()
            .filter(|r| r.response == resp.name() && r.broadphase == "hash")
            .collect();
        let avg = mine.iter().map(|r| r.avg_collision_pct).sum::<f64>() / mine.len().max(1) as f64;
        println!(
            "average collision, {:>14}: ours {:.3}%  paper {:.3}%",
            resp.name(),
            avg,
            PAPER_AVG_PCT[ri]
        );
    }
    println!();
    println!(
        "100x100 hash rows against the paper (a ratio to times measured on a 1.5 GHz Core 2 Duo: it moves with the machine and its load; compare rows of one run, not runs of different days)"
    );
    for resp in RESPONSES {
        let big: Vec<&Row> = rows
            .iter()
            .filter(|r| r.particles == 10_000 && r.broadphase == "hash" && r.response == resp.name())
            .collect();
        if big.is_empty() {
            println!("  {:>14}: no 100x100 row was run (see --size)", resp.name());
            continue;
        }
        let ratio = big
            .iter()
            .map(|r| r.paper_ms / r.collision_ms.max(1e-9))
            .fold(f64::INFINITY, f64::min);
        let worst = big.iter().map(|r| r.avg_collision_pct).fold(0.0, f64::max);
        println!(
            "  {:>14}: slowest row {ratio:.2}x the paper's speed; worst average collision {worst:.3}% (the paper's best: 1.018%)",
            resp.name()
        );
    }
    Ok(ExitCode::SUCCESS)
}
