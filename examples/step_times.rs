//! Times the steps of the bench worlds of `weft::perf`, for A/B runs of two builds:
//! `step_times [cloth|drape] [particles] [threads] [steps]` prints the median, mean and p95 ms
//! per step after 20 steps of warm-up. `cloth` is `perf::roofline::cloth_world_5x1` (the
//! `step_100k_5x1` case of `weft bench`, with its tethers), `drape` is
//! `perf::sphere_drape_world` (the `drape_1m_5x1` case).
fn main() -> Result<(), Box<dyn std::error::Error>> {
    // As the `weft` binary does: this thread runs the steps' parallel passes as a thread of the
    // global pool, with no hand-off a step.
    let _ = rayon::ThreadPoolBuilder::new().use_current_thread().build_global();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let kind = args.first().map_or("cloth", String::as_str);
    let num =
        |i: usize, d: usize| -> Result<usize, Box<dyn std::error::Error>> { Ok(args.get(i).map(|s| s.parse()).transpose()?.unwrap_or(d)) };
    let (n, threads, steps) = (num(1, 100_000)?, num(2, 2)?, num(3, 200)?.max(1));
    let mut w = match kind {
        "cloth" => weft::perf::roofline::cloth_world_5x1(n, threads)?,
        "drape" => weft::perf::sphere_drape_world(n, threads)?,
        other => return Err(format!("unknown world {other:?}: cloth or drape").into()),
    };
    let dt = w.params().dt;
    for _ in 0..20 {
        w.step(dt)?;
    }
    let mut t: Vec<f64> = (0..steps)
        .map(|_| {
            let t0 = std::time::Instant::now();
            w.step(dt).map(|_| t0.elapsed().as_secs_f64() * 1e3)
        })
        .collect::<Result<_, _>>()?;
    let mean = t.iter().sum::<f64>() / t.len() as f64;
    t.sort_by(f64::total_cmp);
    let at = |q: usize| t[(t.len() * q / 100).min(t.len() - 1)];
    println!(
        "{kind} {} particles, {threads} threads: median {:.4} mean {mean:.4} p95 {:.4} ms a step",
        w.particle_count(),
        at(50),
        at(95)
    );
    Ok(())
}
