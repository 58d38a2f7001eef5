//! `weft accuracy SCENE [--json] [--plot FILE.svg|png]`: ms/step against error for a grid of
//! solver settings, with the Pareto front marked (see `weft::accuracy`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args;
use plot_png::PngBackend;
use weft::accuracy::{grid_for, prepare_scene, reference_drift, run_grid, Outcome, Reference, ReferenceKind, Report};
use weft::scene::Scene;

/// Arguments of `weft accuracy`.
#[derive(Args)]
pub struct AccuracyArgs {
    /// The scene file (TOML).
    scene: PathBuf,
    /// Print one JSON array of results instead of the table.
    #[arg(long)]
    json: bool,
    /// Write a log-log plot of rms error against ms/step (SVG or PNG, by the file's extension).
    #[arg(long, value_name = "FILE.svg|png")]
    plot: Option<PathBuf>,
    /// Also write the whole report (header figures and every row) as JSON to this file.
    #[arg(long, value_name = "FILE.json")]
    save_json: Option<PathBuf>,
    /// Simulated time, s (default 1).
    #[arg(long, default_value_t = 1.0)]
    time: f64,
    /// Substeps per step of the reference's finer run (even; default 1024, or 64 for scenes
    /// with mesh obstacles, whose reference is f32: see weft::accuracy::reference).
    #[arg(long)]
    reference_substeps: Option<u32>,
    /// Richardson-extrapolate the reference from its R and R/2 runs (helps smooth motion,
    /// hurts cloth ringing in stiff modes; see weft::accuracy::reference).
    #[arg(long)]
    extrapolate: bool,
    /// Directory of the reference cache (default out/<scene name>).
    #[arg(long)]
    out: Option<PathBuf>,
}

mod plot_png;

pub fn accuracy(args: AccuracyArgs) -> weft::Result<ExitCode> {
    if !(args.time.is_finite() && args.time > 0.0) {
        return Err(weft::WeftError::param("--time", args.time, "must be a positive number of seconds"));
    }
    if let Some(p) = &args.plot {
        plot_kind(p)?;
    }
    let (scene, text) = Scene::load(&args.scene)?;
    let scene = prepare_scene(&scene);
    let make = || scene.world();
    let dt = scene.solver.dt.0 as f64;
    let steps = ((args.time / dt).round() as usize).max(1);
    let stem = args
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let dir = args.out.clone().unwrap_or_else(|| Path::new("out").join(&stem));
    let world = make()?;
    let kind = ReferenceKind::for_world(&world);
    let reference_substeps = args.reference_substeps.unwrap_or(match kind {
        ReferenceKind::F64Xpbd => 1024,
        ReferenceKind::F32World => 64,
    });
    if !args.json {
        eprintln!(
            "reference: {}, {} and {} substeps/step{} ...",
            kind.describe(),
            reference_substeps,
            reference_substeps / 2,
            if args.extrapolate { ", Richardson-extrapolated" } else { "" }
        );
    }
    let (reference, cached) = Reference::cached(&make, &text, steps, reference_substeps, args.extrapolate, &dir)?;
    let grid = grid_for(&world);
    let quiet = args.json;
    let outcomes = run_grid(&make, &reference, &grid, steps, |i, o| {
        if !quiet {
            eprintln!(
                "  [{}/{}] {} {}x{} {:?}: {:.3} ms/step",
                i + 1,
                grid.len(),
                o.method,
                o.substeps,
                o.iterations,
                o.precision,
                o.ms_per_step
            );
        }
    })?;
    let report = Report {
        steps,
        dt: scene.solver.dt.0,
        reference_kind: kind,
        reference_substeps,
        reference_self_error: reference.self_error,
        reference_drift: reference_drift(&make, &reference)?,
        outcomes,
    };
    if let Some(p) = &args.plot {
        plot(&report.outcomes, p, &stem)?;
    }
    if let Some(p) = &args.save_json {
        let text = serde_json::to_string_pretty(&report).map_err(|e| weft::WeftError::Scene(e.to_string()))?;
        std::fs::write(p, text + "\n").map_err(|e| weft::WeftError::io(p, e))?;
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report.outcomes).map_err(|e| weft::WeftError::Scene(e.to_string()))?
        );
    } else {
        println!(
            "scene {}: {} particles, {} steps of {:.5} s ({:.2} s simulated)",
            args.scene.display(),
            world.particle_count(),
            steps,
            dt,
            steps as f64 * dt
        );
        println!(
            "reference: {}, {} substeps/step{} ({}), own error estimate {:.2e} m, energy change {:.4e} J",
            kind.describe(),
            reference_substeps,
            if args.extrapolate { " extrapolated" } else { "" },
            if cached { "cached" } else { "computed" },
            report.reference_self_error,
            report.reference_drift
        );
        print!("{}", table(&report.outcomes));
        println!(
            "* = Pareto front (no other setting is both faster and more accurate). penet = deepest obstacle penetration (m) / particles deeper than 0.1 mm at the end; self% = mean % of particles in self-penetration; bounded = finite but blown up (kinetic energy over {} x the reference's energy budget).",
            weft::accuracy::BLOWUP_FACTOR
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn num(v: Option<f64>, status: &str) -> String {
    let what = if status == "diverged-bounded" { "bounded" } else { "diverged" };
    v.map_or_else(|| what.to_string(), |v| format!("{v:.3e}"))
}

/// The text table.
pub fn table(outcomes: &[Outcome]) -> String {
    let mut s = format!(
        "{:<17} {:<20} {:>5} {:>5} {:>4} {:>11} {:>10} {:>10} {:>10} {:>11} {:>13} {:>6}\n",
        "method",
        "self-collision",
        "subst",
        "iter",
        "prec",
        "ms/step",
        "rms err m",
        "max err m",
        "max strain",
        "energy dJ",
        "penet",
        "self%"
    );
    for o in outcomes {
        let sc = match (o.response, o.broadphase) {
            (Some(r), Some(b)) => format!("{r}/{b}"),
            _ => "-".into(),
        };
        let penet = match (o.max_penetration, o.penetration_count) {
            (Some(d), Some(c)) => format!("{d:.1e}/{c}"),
            _ => "-".into(),
        };
        s += &format!(
            "{:<17} {:<20} {:>5} {:>5} {:>4} {:>11.4} {:>10} {:>10} {:>10} {:>11} {:>13} {:>6}{}\n",
            o.method,
            sc,
            o.substeps,
            o.iterations,
            format!("{:?}", o.precision).to_lowercase(),
            o.ms_per_step,
            num(o.rms_error, o.status),
            num(o.max_error, o.status),
            num(o.max_strain, o.status),
            num(o.energy_drift, o.status),
            penet,
            o.self_penetration_pct.map_or("-".into(), |p| format!("{p:.2}")),
            if o.pareto { " *" } else { "" }
        );
    }
    s
}

/// Whether `path` names a PNG (`Ok(true)`) or an SVG (`Ok(false)`) plot.
fn plot_kind(path: &Path) -> weft::Result<bool> {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("png") => Ok(true),
        Some("svg") => Ok(false),
        _ => Err(weft::WeftError::param("--plot", path.display(), "must end in .svg or .png")),
    }
}

/// Plot size in pixels.
const PLOT_SIZE: (u32, u32) = (900, 600);

/// Size of the point labels, and an upper estimate of the width of one of their characters
/// (6 pixels in the PNG backend's font), in pixels.
const LABEL_FONT_PX: u32 = 12;
const LABEL_CHAR_PX: i32 = 7;

fn plot(outcomes: &[Outcome], path: &Path, title: &str) -> weft::Result<()> {
    use plotters::prelude::*;
    if plot_kind(path)? {
        draw(PngBackend::new(path, PLOT_SIZE).into_drawing_area(), outcomes, path, title)
    } else {
        draw(SVGBackend::new(path, PLOT_SIZE).into_drawing_area(), outcomes, path, title)
    }
}

fn draw<DB: plotters::prelude::DrawingBackend>(
    root: plotters::drawing::DrawingArea<DB, plotters::coord::Shift>,
    outcomes: &[Outcome],
    path: &Path,
    title: &str,
) -> weft::Result<()> {
    use plotters::prelude::*;
    let err = |e: &dyn std::fmt::Display| weft::WeftError::io(path, std::io::Error::other(e.to_string()));
    let ok: Vec<&Outcome> = outcomes.iter().filter(|o| o.rms_error.is_some()).collect();
    if ok.is_empty() {
        return Err(weft::WeftError::param(
            "--plot",
            path.display(),
            "every setting diverged; nothing to plot",
        ));
    }
    let (mut t0, mut t1, mut e0, mut e1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for o in &ok {
        let e = o.rms_error.unwrap_or(1.0);
        t0 = t0.min(o.ms_per_step.max(1e-6));
        t1 = t1.max(o.ms_per_step.max(1e-6));
        e0 = e0.min(e.max(1e-12));
        e1 = e1.max(e.max(1e-12));
    }
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("{title}: rms error vs time per step"), ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((t0 / 2.0..t1 * 2.0).log_scale(), (e0 / 2.0..e1 * 2.0).log_scale())
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("ms per step")
        .x_label_formatter(&|v| format!("{v}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .y_desc("rms position error (m)")
        .draw()
        .map_err(|e| err(&e))?;
    let series = [
        ("xpbd", weft::accuracy::Precision::F32, BLUE),
        ("xpbd", weft::accuracy::Precision::F64, CYAN),
        ("symplectic-euler", weft::accuracy::Precision::F32, RED),
        ("leapfrog", weft::accuracy::Precision::F32, MAGENTA),
        ("implicit-euler", weft::accuracy::Precision::F32, GREEN),
    ];
    for (name, prec, colour) in series {
        let pts: Vec<(f64, f64)> = ok
            .iter()
            .filter(|o| o.method == name && o.precision == prec)
            .map(|o| (o.ms_per_step.max(1e-6), o.rms_error.unwrap_or(1.0).max(1e-12)))
            .collect();
        if pts.is_empty() {
            continue;
        }
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 5, colour.filled())))
            .map_err(|e| err(&e))?
            .label(format!("{name} ({prec:?})").to_lowercase())
            .legend(move |(x, y)| Circle::new((x + 8, y), 5, colour.filled()));
    }
    // Each point labelled with its substeps x iterations (and self-collision response), placed
    // beside the point where it covers no point and no label placed before.
    let mut placed: Vec<(i32, i32, i32, i32)> = ok
        .iter()
        .map(|o| {
            let (px, py) = chart.backend_coord(&(o.ms_per_step.max(1e-6), o.rms_error.unwrap_or(1.0).max(1e-12)));
            (px - 5, py - 5, px + 6, py + 6)
        })
        .collect();
    let mut labels = Vec::new();
    for o in &ok {
        let p = (o.ms_per_step.max(1e-6), o.rms_error.unwrap_or(1.0).max(1e-12));
        let text = match o.response {
            Some(r) => format!("{}x{} {r}/{}", o.substeps, o.iterations, o.broadphase.unwrap_or("-")),
            None => format!("{}x{}", o.substeps, o.iterations),
        };
        let (px, py) = chart.backend_coord(&p);
        let (w, h) = (LABEL_CHAR_PX * text.chars().count() as i32, LABEL_FONT_PX as i32);
        let candidates = [(7, -h - 2), (7, 2), (-w - 7, -h - 2), (-w - 7, 2), (-w / 2, -h - 8), (-w / 2, 8)];
        let rect = |(dx, dy): (i32, i32)| (px + dx, py + dy, px + dx + w, py + dy + h);
        let free = |r: &(i32, i32, i32, i32)| placed.iter().all(|q| r.2 <= q.0 || q.2 <= r.0 || r.3 <= q.1 || q.3 <= r.1);
        let off = candidates.iter().copied().find(|&c| free(&rect(c))).unwrap_or(candidates[0]);
        placed.push(rect(off));
        labels.push((p, off, text));
    }
    chart
        .draw_series(labels.into_iter().map(|(p, off, text)| {
            EmptyElement::at(p) + Text::new(text, off, ("sans-serif", LABEL_FONT_PX).into_font().color(&BLACK.mix(0.8)))
        }))
        .map_err(|e| err(&e))?
        .label("label: substeps x iterations")
        .legend(|(x, y)| EmptyElement::at((x, y)));
    let mut front: Vec<(f64, f64)> = ok
        .iter()
        .filter(|o| o.pareto)
        .map(|o| (o.ms_per_step.max(1e-6), o.rms_error.unwrap_or(1.0).max(1e-12)))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(front, BLACK.stroke_width(1)))
        .map_err(|e| err(&e))?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        // Lower left: no setting is both fast and accurate, so that corner is usually empty.
        .position(SeriesLabelPosition::LowerLeft)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
