//! `weft bench --scaling DIR`: ms per step against particle count (1k .. 1M) on 1 and 2
//! threads for two cloths — the bench cloth (stretch, shear, bend, tethers, 2 pinned corners,
//! default solver settings) and the drape (stretch + bend over a sphere, 5 substeps,
//! 1 iteration) — printed as a Markdown table and written to `DIR/scaling.md` and the log-log
//! plot `DIR/scaling.svg`. The README's table and plot come from this command.

use std::fmt::Write as _;
use std::path::Path;

use weft::perf;

/// One measured point.
struct Point {
    scene: &'static str,
    particles: usize,
    threads: usize,
    ms: f64,
}

const SIZES: [usize; 6] = [1_000, 2_000, 4_000, 10_000, 100_000, 1_000_000];

fn measure() -> weft::Result<Vec<Point>> {
    let mut out = Vec::new();
    for n in SIZES {
        // Fewer repetitions for the large sizes keep the sweep under a minute.
        let reps = (2_000_000 / n).clamp(3, 41);
        for threads in [1usize, 2] {
            let mut w = perf::cloth_world(n, threads)?;
            out.push(Point {
                scene: "bench cloth",
                particles: w.particle_count(),
                threads,
                ms: perf::step_ms(&mut w, reps)?,
            });
            let mut w = perf::sphere_drape_world(n, threads)?;
            out.push(Point {
                scene: "drape over sphere",
                particles: w.particle_count(),
                threads,
                ms: perf::step_ms(&mut w, reps)?,
            });
        }
    }
    Ok(out)
}

/// The 1-minute load average before and after the sweep (Linux), so a reader can tell whether
/// other processes shared the cores: 2-thread figures mean little when the load exceeds the
/// core count minus two.
fn load_average() -> Option<String> {
    let s = std::fs::read_to_string("/proc/loadavg").ok()?;
    s.split_whitespace().next().map(str::to_string)
}

/// The processor's model name (Linux) and the lane instructions the kernels use, as
/// `"AMD EPYC, AVX2 + FMA"`; the model is left out where the system does not say it.
fn machine() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo").ok().and_then(|s| {
        s.lines()
            .find(|l| l.starts_with("model name"))
            .and_then(|l| l.split_once(':'))
            .map(|(_, m)| m.trim().to_string())
    });
    #[cfg(target_arch = "x86_64")]
    let lanes = match (is_x86_feature_detected!("avx2"), is_x86_feature_detected!("fma")) {
        (true, true) => "AVX2 + FMA",
        (true, false) => "AVX2",
        _ => "no AVX2",
    };
    #[cfg(not(target_arch = "x86_64"))]
    let lanes = std::env::consts::ARCH;
    match model {
        Some(m) => format!("{m}, {lanes}"),
        None => lanes.to_string(),
    }
}

fn table(points: &[Point], load: (Option<String>, Option<String>)) -> String {
    let mut s = String::new();
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let machine = machine();
    if let (Some(a), Some(b)) = load {
        let _ = writeln!(
            s,
            "Measured on {machine}, {cores} cores; 1-minute load average {a} before, {b} after the sweep.\n"
        );
    } else {
        let _ = writeln!(s, "Measured on {machine}, {cores} cores.\n");
    }
    let _ = writeln!(
        s,
        "| scene | particles | 1 thread ms/step | 2 threads ms/step | 2t speedup | 2t ns/particle/step |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|");
    for one in points.iter().filter(|p| p.threads == 1) {
        let Some(two) = points
            .iter()
            .find(|p| p.threads == 2 && p.scene == one.scene && p.particles == one.particles)
        else {
            continue;
        };
        let _ = writeln!(
            s,
            "| {} | {} | {:.3} | {:.3} | {:.2}x | {:.1} |",
            one.scene,
            one.particles,
            one.ms,
            two.ms,
            one.ms / two.ms,
            two.ms * 1e6 / two.particles as f64
        );
    }
    s
}

fn plot(points: &[Point], path: &Path) -> weft::Result<()> {
    use plotters::prelude::*;
    let err = |e: &dyn std::fmt::Display| weft::WeftError::io(path, std::io::Error::other(e.to_string()));
    let (n0, n1) = (500.0, 2e6);
    let (mut t0, mut t1) = (f64::MAX, f64::MIN);
    for p in points {
        t0 = t0.min(p.ms.max(1e-4));
        t1 = t1.max(p.ms.max(1e-4));
    }
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption("ms per step vs particles (1 and 2 threads)", ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((n0..n1).log_scale(), (t0 / 2.0..t1 * 2.0).log_scale())
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("particles")
        .y_desc("ms per step")
        .draw()
        .map_err(|e| err(&e))?;
    let series = [
        ("bench cloth", 1, BLUE),
        ("bench cloth", 2, CYAN),
        ("drape over sphere", 1, RED),
        ("drape over sphere", 2, MAGENTA),
    ];
    for (scene, threads, colour) in series {
        let pts: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.scene == scene && p.threads == threads)
            .map(|p| (p.particles as f64, p.ms.max(1e-4)))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(format!("{scene}, {threads} thread{}", if threads > 1 { "s" } else { "" }))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2)));
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, colour.filled())))
            .map_err(|e| err(&e))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// Runs the sweep, prints the table, writes `dir/scaling.md` and `dir/scaling.svg`.
pub fn scaling(dir: &Path) -> weft::Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| weft::WeftError::io(dir, e))?;
    let before = load_average();
    let points = measure()?;
    let t = table(&points, (before, load_average()));
    print!("{t}");
    let md = dir.join("scaling.md");
    std::fs::write(&md, &t).map_err(|e| weft::WeftError::io(&md, e))?;
    plot(&points, &dir.join("scaling.svg"))
}
