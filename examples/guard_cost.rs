//! What the guard (`SolverParams::guard`) costs: the roofline's 100 x 100 hanging cloth with the
//! guard on and off, stepped in turn (one step of each, so both see the same machine), and the
//! medians of their step times.
//!
//! ```text
//! cargo run --release --example guard_cost [substeps] [threads] [steps]
//! ```
//!
//! `threads` is 1 (the caller's thread, the default) or 0 (both worlds on the global pool; a
//! world of its own pool each would put two pools on the same cores).

fn main() -> weft::Result<()> {
    let _ = rayon::ThreadPoolBuilder::new().use_current_thread().build_global();
    let arg = |i: usize, d: usize| std::env::args().nth(i).and_then(|a| a.parse().ok()).unwrap_or(d);
    let (substeps, threads, steps) = (arg(1, 1) as u32, arg(2, 1), arg(3, 4000).max(1));
    if threads > 1 {
        return Err(weft::WeftError::param("threads", threads, "must be 0 or 1"));
    }
    let mut worlds = Vec::new();
    for guard in [true, false] {
        let mut w = weft::perf::roofline::hanging_world(substeps, 1, threads)?;
        let mut p = w.params().clone();
        p.guard = guard;
        w.set_params(p)?;
        worlds.push(w);
    }
    let dt = 1.0 / 60.0;
    let mut times = [Vec::with_capacity(steps), Vec::with_capacity(steps)];
    for s in 0..steps + 50 {
        for (w, t) in worlds.iter_mut().zip(times.iter_mut()) {
            let start = std::time::Instant::now();
            w.step(dt)?;
            // the first 50 steps warm the caches and let the cloth start to swing
            if s >= 50 {
                t.push(start.elapsed().as_secs_f64() * 1e3);
            }
        }
    }
    let [on, off] = times.map(|mut t| {
        t.sort_by(f64::total_cmp);
        t[t.len() / 2]
    });
    println!("100 x 100 hanging cloth, {substeps} substep(s) x 1 iteration, threads = {threads}, {steps} steps each");
    println!("guard on {on:.4} ms, off {off:.4} ms a step (medians); on / off {:.3}", on / off);
    Ok(())
}
