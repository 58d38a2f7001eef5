//! `weft reproduce landovsky [--quick] [--json]`: the timing table of Landovskaya, Landovsky &
//! Frolovsky (SEEDS.md section D).
//!
//! The paper drops fabric (particles at the warp/weft crossings) on dress-form meshes of 4800
//! and 8350 faces and times 500 or 150 "iterations" with uniform grids of 1x1x1, 5x5x5,
//! 15x30x15 and 25x25x25 cells (Intel i7-4770). We read an iteration as one simulation step:
//! here one `World::step` of `dt = 1/200 s` with [`SUBSTEPS`] XPBD substeps of one sweep each
//! (collision detection runs every substep). The paper integrates with leapfrog, one force
//! evaluation per step; with a single substep our nearly inextensible cotton sheet of 15000
//! or 32500 particles does not converge (strain above 1000%), hangs through and slides off the
//! form, so four substeps are the honest equivalent of a converged step. The cloth is a horizontal cotton
//! sheet of the paper's particle count (130 x 250 = 32500, 100 x 150 = 15000) released just
//! above the form's neck, so it falls on the form and drapes over it while being timed. The
//! forms are our procedural ones (`weft::collide::dressform`: exactly 4800, and 8352 faces).
//!
//! Each row times the whole step (cloth constraints included) on all cores: `seconds` is wall
//! time, `cpu_seconds` the process's CPU time over the same steps (on a machine shared with
//! other work the wall time includes waiting; the CPU time does not, and CPU seconds summed
//! over both threads bound the unloaded wall time from above), `collision_seconds` the
//! wall time of the obstacle stages alone ([`World::obstacle_time`]), the part the paper's
//! grid sizes change. It also reports the
//! deepest particle inside the form at the end (`max_penetration`, m). Beyond the paper's
//! rows: the BVH and hash broadphases and an automatically sized grid (no hand-tuned cells),
//! and the paper's face memory on the best grids, to show what it saves and what it costs in
//! accuracy (`deviation`: the largest distance between a particle's final position with and
//! without face memory). `--quick` runs a tenth of the iterations and scales the seconds by
//! ten, and says so.

use std::process::ExitCode;
use std::time::Instant;

use weft::collide::dressform::dress_form;
use weft::collide::obstacles::{BroadphaseKind, Obstacle};
use weft::{ClothDesc, Effects, Fabric, SolverParams, World};

/// Options of `weft reproduce landovsky`.
#[derive(clap::Args)]
pub struct Args {
    /// Run a tenth of the iterations and scale the times (says so in the output).
    #[arg(long)]
    quick: bool,
    /// Print one JSON array instead of a table.
    #[arg(long)]
    json: bool,
}

/// Step length of one "iteration", s.
const DT: f32 = 1.0 / 200.0;
/// XPBD substeps per iteration (module doc).
const SUBSTEPS: u32 = 4;

/// One row to run.
struct Spec {
    rows: u32,
    cols: u32,
    spacing: f32,
    faces: usize,
    iterations: u32,
    broadphase: BroadphaseKind,
    face_memory: bool,
    paper_seconds: Option<f64>,
}

/// One measured row (the JSON object).
#[derive(serde::Serialize)]
struct Row {
    particles: usize,
    faces: usize,
    iterations: u32,
    measured_iterations: u32,
    broadphase: String,
    cells: Option<[usize; 3]>,
    face_memory: bool,
    seconds: f64,
    cpu_seconds: Option<f64>,
    collision_seconds: f64,
    paper_seconds: Option<f64>,
    speedup_wall: Option<f64>,
    speedup_cpu: Option<f64>,
    max_penetration: f32,
    deviation: Option<f32>,
}

fn specs() -> Vec<Spec> {
    let big = |broadphase, face_memory, paper_seconds| Spec {
        rows: 250,
        cols: 130,
        spacing: 0.006,
        faces: 4800,
        iterations: 500,
        broadphase,
        face_memory,
        paper_seconds,
    };
    let small = |broadphase, face_memory, paper_seconds| Spec {
        rows: 150,
        cols: 100,
        spacing: 0.009,
        faces: 8350,
        iterations: 150,
        broadphase,
        face_memory,
        paper_seconds,
    };
    use BroadphaseKind::*;
    vec![
        big(Grid(Some([1, 1, 1])), false, Some(3000.0)),
        big(Grid(Some([5, 5, 5])), false, Some(70.0)),
        big(Grid(Some([15, 30, 15])), false, Some(28.0)),
        big(Grid(None), false, None),
        big(Bvh, false, None),
        big(Hash, false, None),
        big(Grid(Some([15, 30, 15])), true, None),
        small(Grid(Some([1, 1, 1])), false, Some(600.0)),
        small(Grid(Some([25, 25, 25])), false, Some(13.0)),
        small(Grid(None), false, None),
        small(Bvh, false, None),
        small(Hash, false, None),
        small(Grid(Some([25, 25, 25])), true, None),
    ]
}

/// The world of one row: the sheet centred above the form's neck.
fn world(s: &Spec) -> weft::Result<World> {
    let params = SolverParams {
        dt: DT,
        substeps: SUBSTEPS,
        iterations: 1,
        ..SolverParams::default()
    };
    let mut w = World::new(params, Effects::gravity())?;
    let (wx, wz) = ((s.cols - 1) as f32 * s.spacing, (s.rows - 1) as f32 * s.spacing);
    w.add_cloth(&ClothDesc {
        rows: s.rows,
        cols: s.cols,
        spacing: s.spacing,
        origin: [-wx / 2.0, weft::collide::dressform::HEIGHT + 0.02, -wz / 2.0],
        u: [1.0, 0.0, 0.0],
        v: [0.0, 0.0, 1.0],
        fabric: Fabric::preset("cotton")?,
        pins: vec![],
        tethers: None,
        ..ClothDesc::default()
    })?;
    w.set_friction(0.3)?;
    w.add_obstacle(Obstacle::mesh(dress_form(s.faces)?, s.broadphase, s.face_memory)?)?;
    Ok(w)
}

/// CPU time of this process so far (user + system, all threads), s: Linux `/proc/self/stat`
/// fields 14 and 15 in clock ticks of 1/100 s. `None` elsewhere.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// What one row's run gives: wall seconds, CPU seconds, final positions, the world.
type Measured = (f64, Option<f64>, Vec<[f32; 3]>, World);

/// Runs one row.
fn measure(s: &Spec, steps: u32) -> weft::Result<Measured> {
    let mut w = world(s)?;
    let (t0, c0) = (Instant::now(), cpu_seconds());
    for _ in 0..steps {
        w.step(DT)?;
    }
    let secs = t0.elapsed().as_secs_f64();
    let cpu = cpu_seconds().zip(c0).map(|(b, a)| b - a);
    let mut pos = Vec::new();
    w.positions_interleaved(&mut pos);
    Ok((secs, cpu, pos, w))
}

pub fn run(args: &Args) -> weft::Result<ExitCode> {
    let scale = if args.quick { 10 } else { 1 };
    let mut rows: Vec<Row> = Vec::new();
    let mut plain: Vec<(usize, BroadphaseKind, Vec<[f32; 3]>)> = Vec::new();
    if !args.json {
        println!("weft reproduce landovsky: cloth dropped on a dress form; one iteration = one step of 1/200 s ({SUBSTEPS} substeps)");
        if args.quick {
            println!("QUICK: every row runs a tenth of its iterations; seconds are the measured time x 10");
        }
        println!(
            "{:>9} {:>6} {:>6} {:<30} {:>9} {:>8} {:>10} {:>7} {:>8} {:>8} {:>11} {:>9}",
            "particles",
            "faces",
            "iters",
            "broadphase",
            "ours (s)",
            "cpu (s)",
            "collide(s)",
            "paper",
            "x (wall)",
            "x (cpu)",
            "max pen (m)",
            "deviation"
        );
    }
    for s in specs() {
        let steps = (s.iterations / scale).max(1);
        let (secs, cpu, pos, w) = measure(&s, steps)?;
        let seconds = secs * (s.iterations as f64 / steps as f64);
        let cpu_seconds = cpu.map(|c| c * (s.iterations as f64 / steps as f64));
        let om = &w.obstacles()[0];
        let (faces, label, cells) = match om.geometry() {
            weft::collide::obstacles::Geometry::Mesh(m) => {
                use weft::collide::face_broadphase::FaceBroadphase;
                let cells = match m.broadphase() {
                    weft::collide::obstacles::MeshBroadphase::Grid(g) => Some(g.dims()),
                    _ => None,
                };
                (m.mesh().face_count(), m.broadphase().describe(), cells)
            }
            _ => (0, String::new(), None),
        };
        let deviation = if s.face_memory {
            plain.iter().find(|(f, b, _)| *f == s.faces && *b == s.broadphase).map(|(_, _, p)| {
                p.iter()
                    .zip(&pos)
                    .map(|(a, b)| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt())
                    .fold(0.0f32, f32::max)
            })
        } else {
            plain.push((s.faces, s.broadphase, pos));
            None
        };
        let row = Row {
            particles: w.particle_count(),
            faces,
            iterations: s.iterations,
            measured_iterations: steps,
            broadphase: if s.face_memory { format!("{label} + face memory") } else { label },
            cells,
            face_memory: s.face_memory,
            seconds,
            cpu_seconds,
            collision_seconds: w.obstacle_time().as_secs_f64() * (s.iterations as f64 / steps as f64),
            paper_seconds: s.paper_seconds,
            speedup_wall: s.paper_seconds.map(|p| p / seconds),
            speedup_cpu: s.paper_seconds.zip(cpu_seconds).map(|(p, c)| p / c),
            max_penetration: w.max_penetration(),
            deviation,
        };
        if !args.json {
            println!(
                "{:>9} {:>6} {:>6} {:<30} {:>9.3} {:>8} {:>10.3} {:>7} {:>8} {:>8} {:>11.2e} {:>9}",
                row.particles,
                row.faces,
                row.iterations,
                row.broadphase,
                row.seconds,
                row.cpu_seconds.map_or("-".into(), |c| format!("{c:.2}")),
                row.collision_seconds,
                row.paper_seconds.map_or("-".into(), |p| format!("{p}")),
                row.speedup_wall.map_or("-".into(), |x| format!("{x:.0}x")),
                row.speedup_cpu.map_or("-".into(), |x| format!("{x:.0}x")),
                row.max_penetration,
                row.deviation.map_or("-".into(), |d| format!("{d:.2e}")),
            );
        }
        rows.push(row);
    }
    if args.json {
        let text = serde_json::to_string_pretty(&rows).map_err(|e| weft::WeftError::Scene(e.to_string()))?;
        println!("{text}");
    }
    Ok(ExitCode::SUCCESS)
}
