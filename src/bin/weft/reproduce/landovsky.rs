//! `weft reproduce landovsky [--quick] [--json] [--png DIR] [--only TEXT]`: the timing table of
//! Landovskaya, Landovsky & Frolovsky (cloth against polyhedral solids).
//!
//! The paper drops fabric (particles at the warp/weft crossings) on dress-form meshes of 4800
//! and 8350 faces and times 500 or 150 "iterations" with uniform grids of 1x1x1, 5x5x5,
//! 15x30x15 and 25x25x25 cells (Intel i7-4770). It integrates with leapfrog: one iteration is
//! one force evaluation, one position update and one collision test per particle. Our unit of
//! the same work is one `World::step` of [`DT`] `= 1/800 s` with one XPBD substep of one
//! constraint sweep: one integration, one sweep over the cloth constraints and one obstacle
//! pass (contacts, response, projection, velocity pass) per particle. A step of 1/800 s is
//! what our nearly inextensible cotton needs to converge with one sweep (with `1/200 s` and one
//! sweep the sheet stretches above 1000%, hangs through and slides off the form): the physics
//! is bit for bit the earlier "one step of 1/200 s with four substeps", each of our iterations
//! being one of those substeps. 500 iterations cover 0.625 s of simulated time, 150 cover
//! 0.1875 s. The cloth is a horizontal cotton sheet of the paper's particle count
//! (130 x 250 = 32500, 100 x 150 = 15000) released [`DROP`] above the top of the form's
//! neck. Every row first runs [`WARMUP`] untimed iterations (0.5 s), in which the sheet lands
//! and settles onto the shoulders, and then times its 500 or 150 iterations while the sheet
//! drapes over the form: without the warm-up the 150 iterations of the 8352-face row ended
//! before the sheet reached the shoulders (about 1% of the particles in contact), so the row
//! timed mostly free fall. The `contact` column is the mean share of particles holding an
//! obstacle contact over the timed iterations. The forms are our procedural ones (`weft::obstacles::mesh::dressform`:
//! exactly 4800, and 8352 faces).
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
//! without face memory). `--quick` leaves out the two brute-force (1x1x1) rows, which take
//! most of the run; every other row runs all its iterations (no scaling). `--png DIR` writes
//! the last frame of the paper's 15x30x15 and 25x25x25 rows to `DIR/landovsky_<faces>.png`;
//! `--only TEXT` runs the rows whose "particles faces broadphase" line contains `TEXT`.

use std::process::ExitCode;
use std::time::Instant;

use weft::obstacles::mesh::dressform::dress_form;
use weft::obstacles::{BroadphaseKind, Obstacle};
use weft::{ClothDesc, Effects, Fabric, SolverParams, World};

/// Options of `weft reproduce landovsky`.
#[derive(clap::Args)]
pub struct Args {
    /// Leave out the two brute-force (1x1x1) rows (says so in the output).
    #[arg(long)]
    quick: bool,
    /// Write the last frame of the paper's 15x30x15 and 25x25x25 rows as PNGs into this folder.
    #[arg(long)]
    png: Option<std::path::PathBuf>,
    /// Run only the rows whose line (particles, faces, broadphase) contains this text, e.g.
    /// `4800 grid 15x30x15` or `bvh`.
    #[arg(long)]
    only: Option<String>,
    /// Print one JSON array instead of a table.
    #[arg(long)]
    json: bool,
}

/// Step length of one "iteration", s (one substep, one sweep: module doc).
const DT: f32 = 1.0 / 800.0;
/// Height of the sheet above the top of the form when released, m.
const DROP: f32 = 0.005;

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
    contact_share: f64,
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
        substeps: 1,
        iterations: 1,
        ..SolverParams::default()
    };
    let mut w = World::new(params, Effects::gravity())?;
    let (wx, wz) = ((s.cols - 1) as f32 * s.spacing, (s.rows - 1) as f32 * s.spacing);
    w.add_cloth(&ClothDesc {
        rows: s.rows,
        cols: s.cols,
        spacing: s.spacing,
        origin: [-wx / 2.0, weft::obstacles::mesh::dressform::HEIGHT + DROP, -wz / 2.0],
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

/// What one row's run gives: wall seconds, CPU seconds, mean contact share, final
/// positions, obstacle-stage seconds of the timed iterations, the world.
type Measured = (f64, Option<f64>, f64, Vec<[f32; 3]>, f64, World);

/// Times the contact share is sampled during a run (evenly spaced; the counting, a read of
/// one slot per particle, is timed with the steps and costs well under 1% of them).
const CONTACT_SAMPLES: u32 = 20;

/// Untimed iterations before each row's timed ones (module doc): 0.5 s of simulated time, in
/// which the sheet lands and settles onto the form's shoulders.
const WARMUP: u32 = 400;

/// Runs one row: [`WARMUP`] untimed iterations, then the row's timed ones.
fn measure(s: &Spec) -> weft::Result<Measured> {
    let mut w = world(s)?;
    for _ in 0..WARMUP {
        w.step(DT)?;
    }
    let warm_collision = w.obstacle_time();
    let every = (s.iterations / CONTACT_SAMPLES).max(1);
    let (mut share, mut samples) = (0.0f64, 0u32);
    let (t0, c0) = (Instant::now(), cpu_seconds());
    for i in 1..=s.iterations {
        w.step(DT)?;
        if i % every == 0 {
            share += w.obstacle_contacts() as f64 / w.particle_count().max(1) as f64;
            samples += 1;
        }
    }
    let secs = t0.elapsed().as_secs_f64();
    let cpu = cpu_seconds().zip(c0).map(|(b, a)| b - a);
    let mut pos = Vec::new();
    w.positions_interleaved(&mut pos);
    Ok((
        secs,
        cpu,
        share / samples.max(1) as f64,
        pos,
        (w.obstacle_time() - warm_collision).as_secs_f64(),
        w,
    ))
}

/// The row's broadphase label, the mesh's face count and the grid's cells.
fn label(w: &World, face_memory: bool) -> (String, usize, Option<[usize; 3]>) {
    use weft::obstacles::mesh::broadphase::FaceBroadphase;
    use weft::obstacles::{Geometry, MeshBroadphase};
    match w.obstacles().first().map(|o| o.geometry()) {
        Some(Geometry::Mesh(m)) => {
            let cells = match m.broadphase() {
                MeshBroadphase::Grid(g) => Some(g.dims()),
                _ => None,
            };
            let text = m.broadphase().describe();
            let text = if face_memory { format!("{text} + face memory") } else { text };
            (text, m.mesh().face_count(), cells)
        }
        _ => (String::new(), 0, None),
    }
}

/// Writes the world's current frame to `dir/landovsky_<faces>.png`.
fn write_png(dir: &std::path::Path, w: &World, pos: Vec<[f32; 3]>, faces: usize) -> weft::Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| weft::WeftError::Scene(format!("{}: {e}", dir.display())))?;
    let frame = crate::pictures::Frame {
        positions: pos,
        normals: Vec::new(),
        time: w.time(),
        obstacles: crate::pictures::obstacle_items(w, crate::pictures::plane_span(w)),
    };
    let style = crate::pictures::Style::default();
    let (width, height) = (800, 800);
    let frames = [frame];
    let cam = crate::pictures::shared_camera(w, &frames, 1.0, None, None, style)?;
    let img = crate::pictures::render_frame(w, &frames[0], width, height, cam, style)?;
    let p = dir.join(format!("landovsky_{faces}.png"));
    img.write_png(&p)?;
    eprintln!("wrote {}", p.display());
    Ok(())
}

pub fn run(args: &Args) -> weft::Result<ExitCode> {
    let mut rows: Vec<Row> = Vec::new();
    let mut plain: Vec<(usize, BroadphaseKind, Vec<[f32; 3]>)> = Vec::new();
    if !args.json {
        println!("weft reproduce landovsky: cloth dropped on a dress form; one iteration = one step of 1/800 s (one substep, one sweep)");
        if args.quick {
            println!("QUICK: the brute-force 1x1x1 rows are left out; every other row runs all its iterations");
        }
        println!(
            "{:>9} {:>6} {:>6} {:<30} {:>9} {:>8} {:>10} {:>7} {:>7} {:>8} {:>8} {:>11} {:>9}",
            "particles",
            "faces",
            "iters",
            "broadphase",
            "ours (s)",
            "cpu (s)",
            "collide(s)",
            "contact",
            "paper",
            "x (wall)",
            "x (cpu)",
            "max pen (m)",
            "deviation"
        );
    }
    for s in specs() {
        if args.quick && s.broadphase == BroadphaseKind::Grid(Some([1, 1, 1])) {
            continue;
        }
        if let Some(text) = &args.only {
            let line = format!("{} {} {}", s.rows * s.cols, s.faces, label(&world(&s)?, s.face_memory).0);
            if !line.contains(text.as_str()) {
                continue;
            }
        }
        let (seconds, cpu_seconds, contact_share, pos, collision_seconds, w) = measure(&s)?;
        let best_grid = matches!(s.broadphase, BroadphaseKind::Grid(Some([15, 30, 15] | [25, 25, 25])));
        if let (Some(dir), true) = (&args.png, best_grid && !s.face_memory) {
            write_png(dir, &w, pos.clone(), s.faces)?;
        }
        let (label, faces, cells) = label(&w, s.face_memory);
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
            contact_share,
            broadphase: label,
            cells,
            face_memory: s.face_memory,
            seconds,
            cpu_seconds,
            collision_seconds,
            paper_seconds: s.paper_seconds,
            speedup_wall: s.paper_seconds.map(|p| p / seconds),
            speedup_cpu: s.paper_seconds.zip(cpu_seconds).map(|(p, c)| p / c),
            max_penetration: w.max_penetration(),
            deviation,
        };
        if !args.json {
            println!(
                "{:>9} {:>6} {:>6} {:<30} {:>9.3} {:>8} {:>10.3} {:>6.0}% {:>7} {:>8} {:>8} {:>11.2e} {:>9}",
                row.particles,
                row.faces,
                row.iterations,
                row.broadphase,
                row.seconds,
                row.cpu_seconds.map_or("-".into(), |c| format!("{c:.2}")),
                row.collision_seconds,
                row.contact_share * 100.0,
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
