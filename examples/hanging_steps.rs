//! Steps the roofline's 100 x 100 hanging cloth, for profilers: `[substeps] [iterations] [threads] [steps]`.
fn main() {
    // As the `weft` binary does: this thread runs the steps' parallel passes as a thread of the
    // global pool, with no hand-off a step.
    let _ = rayon::ThreadPoolBuilder::new().use_current_thread().build_global();
    let a: Vec<u32> = std::env::args().skip(1).map(|s| s.parse().unwrap()).collect();
    let g = |i: usize, d: u32| a.get(i).copied().unwrap_or(d);
    let mut w = weft::perf::roofline::hanging_world(g(0, 5), g(1, 1), g(2, 0) as usize).unwrap();
    for _ in 0..g(3, 2000) {
        w.step(1.0 / 60.0).unwrap();
    }
    println!("{} particles, thread choice {:?}", w.particle_count(), w.thread_choice());
}
