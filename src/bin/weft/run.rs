//! `weft run SCENE`: simulate, show progress, write pictures, a summary and checkpoints.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use weft::files::write_atomic;
use weft::scene::{ClothSurface, Scene};
use weft::world::checkpoint::Checkpoint;
use weft::{WeftError, World};

use crate::pictures::{self, Frame};

#[derive(Args)]
pub struct RunArgs {
    /// The scene file (TOML). Not needed with --resume.
    scene: Option<PathBuf>,
    /// Output directory (default: out/<scene name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Steps to run in total (default: the scene's output.steps).
    #[arg(long)]
    steps: Option<u32>,
    /// Frames to keep for the contact sheet, OBJ and GIF (default: the scene's output.frames).
    #[arg(long)]
    frames: Option<u32>,
    /// Write an OBJ file per kept frame.
    #[arg(long)]
    obj: bool,
    /// Write an animated GIF of the kept frames.
    #[arg(long)]
    gif: bool,
    /// Write the kept frames as one animated binary glTF 2.0 file, run.glb (cloth with
    /// normals, strands as lines, obstacles as meshes; open it in Blender or three.js).
    #[arg(long)]
    gltf: bool,
    /// Write DIR/checkpoint.bin every K steps (and on Ctrl-C and at the end).
    #[arg(long, value_name = "K")]
    checkpoint_every: Option<u32>,
    /// Continue from a checkpoint file (it carries its scene).
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Skip the pictures (for timing runs).
    #[arg(long)]
    no_pictures: bool,
    /// Draw cloth as a NURBS surface over its particle grid (same as the scene's
    /// `[output] cloth_surface = "nurbs"`).
    #[arg(long)]
    nurbs_surface: bool,
}

#[derive(Serialize)]
struct Summary {
    scene: String,
    particles: usize,
    constraints: usize,
    tethers: usize,
    colours: usize,
    effects: Vec<&'static str>,
    dt: f32,
    substeps: u32,
    iterations: u32,
    steps: u64,
    steps_this_run: u64,
    resumed_from_step: Option<u64>,
    simulated_time_s: f64,
    wall_time_s: f64,
    ms_per_step_median: f64,
    ms_per_step_p95: f64,
    ms_per_step_mean: f64,
    max_strain: f64,
    mean_strain: f64,
    final_energy: weft::Metrics,
    /// Present when self-collision is on: the paper's average collision and its time.
    #[serde(skip_serializing_if = "Option::is_none")]
    self_collision: Option<SelfCollisionSummary>,
    /// With `threads = 0`: where the last trial chose to run the steps, and its step times.
    thread_choice: Option<weft::world::threads::ThreadChoiceReport>,
    interrupted: bool,
    warnings: Vec<String>,
    files: Vec<String>,
}

#[derive(Serialize)]
struct SelfCollisionSummary {
    response: &'static str,
    broadphase: &'static str,
    distance: f32,
    /// Over the steps, when the scene asks for it (`measure = true`; absent otherwise).
    avg_collision_pct: Option<f64>,
    max_collision_pct: Option<f64>,
    final_collision_pct: f64,
    collision_ms_per_step: f64,
    stats: weft::self_collision::config::SelfCollisionStats,
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let i = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[i]
}

pub fn run(args: RunArgs) -> weft::Result<ExitCode> {
    let (scene, text, name, resume) = match (&args.resume, &args.scene) {
        (Some(ck), _) => {
            let c = Checkpoint::load(ck)?;
            let scene = Scene::parse(&c.scene, &format!("{} (embedded scene)", ck.display()))?;
            let name = ck
                .parent()
                .and_then(|p| p.file_name())
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_else(|| "resumed".into());
            (scene, c.scene.clone(), name, Some(c))
        }
        (None, Some(path)) => {
            let (scene, text) = Scene::load(path)?;
            let name = path
                .file_stem()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_else(|| "scene".into());
            (scene, text, name, None)
        }
        (None, None) => return Err(WeftError::Scene("give a scene file, or --resume CHECKPOINT".into())),
    };
    let out = args.out.clone().unwrap_or_else(|| Path::new("out").join(&name));
    std::fs::create_dir_all(&out).map_err(|e| WeftError::io(&out, e))?;
    let mut world = scene.world()?;
    if let Some(c) = &resume {
        world.restore(c)?;
    }
    let total = args.steps.map(u64::from).unwrap_or(scene.output.steps.0 as u64);
    let n_frames = args.frames.unwrap_or(scene.output.frames.0).max(1) as u64;
    let want_obj = args.obj || scene.output.obj;
    let want_gif = args.gif || scene.output.gif;
    let want_gltf = args.gltf;
    let dt = world.params().dt;
    let start_step = world.steps();
    // Frames at evenly spaced steps, always including the start and the end.
    let frame_steps: Vec<u64> = (0..=n_frames).map(|k| k * total / n_frames).collect();

    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        // A second handler cannot be installed in one process; ignore that case.
        let _ = ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst));
    }

    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(total)
    };
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} steps  {per_sec}  eta {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_position(start_step.min(total));

    let mut frames: Vec<Frame> = Vec::new();
    // Planes are drawn (and exported) as one fixed quad around the cloth as it starts.
    let span = pictures::plane_span(&world);
    let mut files = Vec::new();
    let mut warnings = Vec::new();
    let record = |world: &World, frames: &mut Vec<Frame>, files: &mut Vec<String>| -> weft::Result<()> {
        let mut positions = Vec::new();
        world.positions_interleaved(&mut positions);
        if want_obj {
            let p = out.join(format!("frame_{:06}.obj", world.steps()));
            weft::export::write_obj(&p, &positions, world.triangles())?;
            files.push(p.display().to_string());
        }
        let mut normals = Vec::new();
        if want_gltf {
            normals.resize(positions.len(), [0.0; 3]);
            world.read_normals(&mut normals[..])?;
        }
        frames.push(Frame {
            positions,
            normals,
            time: world.time(),
            obstacles: pictures::obstacle_items(world, span),
        });
        Ok(())
    };
    if frame_steps.contains(&world.steps()) {
        record(&world, &mut frames, &mut files)?;
    }
    let ckpt_path = out.join("checkpoint.bin");
    let mut times = Vec::with_capacity(total.saturating_sub(start_step) as usize);
    let wall = Instant::now();
    let mut interrupted = false;
    let mut diverged = false;
    while world.steps() < total {
        if stop.load(Ordering::SeqCst) {
            interrupted = true;
            break;
        }
        let t0 = Instant::now();
        let failed = world.self_collision_stats().failed_steps;
        if let Err(e) = world.step(dt) {
            warnings.push(e.to_string());
            diverged = true;
            break;
        }
        // A step whose self-collision could not run (too many pairs) stops the run like a
        // diverged step: what follows would be a cloth passing through itself.
        if world.self_collision_stats().failed_steps > failed {
            let why = world.self_collision_stats().last_error.clone().unwrap_or_default();
            warnings.push(format!("step {} ran without self-collision: {why}", world.steps()));
            diverged = true;
            break;
        }
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        bar.inc(1);
        if frame_steps.contains(&world.steps()) {
            record(&world, &mut frames, &mut files)?;
        }
        if let Some(k) = args.checkpoint_every {
            if k > 0 && world.steps() % k as u64 == 0 {
                world.checkpoint(&text).save(&ckpt_path)?;
            }
        }
    }
    let wall_s = wall.elapsed().as_secs_f64();
    bar.finish_and_clear();
    if args.checkpoint_every.is_some() || interrupted || diverged {
        world.checkpoint(&text).save(&ckpt_path)?;
        files.push(ckpt_path.display().to_string());
    }

    let m = world.metrics();
    let self_collision = match world.self_collision().cloned() {
        Some(c) => {
            // The measure needs the same lists: when they cannot be built it is the warning above.
            let last = world.measure_self_collision().unwrap_or(f64::NAN);
            let st = world.self_collision_stats().clone();
            Some(SelfCollisionSummary {
                response: c.response.name(),
                broadphase: c.broadphase.name(),
                distance: world.self_collision_distance(),
                avg_collision_pct: c.measure.then_some(st.average_pct),
                max_collision_pct: c.measure.then_some(st.max_pct),
                final_collision_pct: last,
                collision_ms_per_step: st.ms_per_step(),
                stats: st,
            })
        }
        None => None,
    };
    if m.max_strain > 0.1 {
        warnings.push(format!(
            "max strain {:.1}% exceeds 10%: consider more substeps or tethers",
            m.max_strain * 100.0
        ));
    }
    if want_gltf && !frames.is_empty() {
        let p = out.join("run.glb");
        crate::glb::write_run(&world, &frames, &p)?;
        files.push(p.display().to_string());
    }
    if !args.no_pictures && !frames.is_empty() {
        let (w, h) = (scene.output.width.0, scene.output.height.0);
        let style = pictures::Style {
            nurbs_surface: args.nurbs_surface || scene.output.cloth_surface == ClothSurface::Nurbs,
        };
        let cam = pictures::shared_camera(
            &world,
            &frames,
            w as f32 / h as f32,
            scene.output.camera_eye.map(|v| v.0),
            scene.output.camera_target.map(|v| v.0),
            style,
        )?;
        let last = frames.last().expect("non-empty");
        let img = pictures::render_frame(&world, last, w, h, cam, style)?;
        let p = out.join("final.png");
        img.write_png(&p)?;
        files.push(p.display().to_string());
        let (tw, th) = ((w / 2).max(1), (h / 2).max(1));
        let thumbs = frames
            .iter()
            .map(|f| pictures::render_frame(&world, f, tw, th, cam, style))
            .collect::<weft::Result<Vec<_>>>()?;
        let cols = (thumbs.len() as f64).sqrt().ceil() as u32;
        let sheet = weft::render::contact_sheet(&thumbs, cols.max(1), true)?;
        let p = out.join("frames.png");
        sheet.write_png(&p)?;
        files.push(p.display().to_string());
        if want_gif {
            let p = out.join("run.gif");
            weft::render::write_gif(&p, &thumbs, 20)?;
            files.push(p.display().to_string());
        }
    }

    let mut sorted = times.clone();
    sorted.sort_by(|a, b| a.total_cmp(b));
    let summary = Summary {
        scene: args.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| name.clone()),
        particles: world.particle_count(),
        constraints: world.constraint_count(),
        tethers: world.tether_count(),
        colours: world.colour_count(),
        effects: world.effects().named(),
        dt,
        substeps: world.params().substeps,
        iterations: world.params().iterations,
        steps: world.steps(),
        steps_this_run: times.len() as u64,
        resumed_from_step: resume.as_ref().map(|c| c.steps),
        simulated_time_s: world.time(),
        wall_time_s: wall_s,
        ms_per_step_median: percentile(&sorted, 0.5),
        ms_per_step_p95: percentile(&sorted, 0.95),
        ms_per_step_mean: if times.is_empty() {
            0.0
        } else {
            times.iter().sum::<f64>() / times.len() as f64
        },
        max_strain: m.max_strain,
        mean_strain: m.mean_strain,
        final_energy: m,
        self_collision,
        thread_choice: world.thread_choice(),
        interrupted,
        warnings,
        files,
    };
    let json = serde_json::to_string_pretty(&summary).map_err(|e| WeftError::Scene(e.to_string()))?;
    let sp = out.join("summary.json");
    write_atomic(&sp, json.as_bytes())?;
    if !args.quiet {
        println!(
            "{} particles, {} steps in {:.2} s ({:.3} ms/step median, {:.3} p95); max strain {:.2}%",
            summary.particles,
            summary.steps_this_run,
            wall_s,
            summary.ms_per_step_median,
            summary.ms_per_step_p95,
            summary.max_strain * 100.0
        );
        if let Some(c) = &summary.self_collision {
            let last = c.final_collision_pct;
            let fin = if last.is_finite() {
                format!("{last:.3}%")
            } else {
                "not measured".to_string()
            };
            let avg = match c.avg_collision_pct {
                Some(a) => format!("average collision {a:.3}% (final {fin})"),
                None => format!("final collision {fin} (measure = true in [effects.self_collision] for the average over the steps)"),
            };
            println!(
                "self-collision ({}, {}): {avg}, {:.3} ms/step",
                c.response, c.broadphase, c.collision_ms_per_step
            );
        }
        if let Some(t) = &summary.thread_choice {
            let ((on, mine), (other, theirs)) = if t.caller_thread {
                (("the caller's thread", t.caller_ms), ("in the pool", t.pool_ms))
            } else {
                (("the global pool", t.pool_ms), ("on the caller's thread", t.caller_ms))
            };
            println!("threads = 0: steps run on {on} (shortest trial step {mine:.3} ms/step against {theirs:.3} {other})");
        }
        for w in &summary.warnings {
            println!("warning: {w}");
        }
        println!("wrote {}", sp.display());
        for f in &summary.files {
            println!("wrote {f}");
        }
    }
    Ok(if diverged {
        ExitCode::from(2)
    } else if interrupted {
        ExitCode::from(130)
    } else {
        ExitCode::SUCCESS
    })
}
