//! Kernel benches: integrate (predict + update) and constraint solve, each as the scalar f32
//! twin, SIMD on one thread, and SIMD on two threads, for N = 1k, 10k, 100k, 1M particles.
//! Ratios are always against the scalar f32 twin (never the f64 reference).
//!
//! `integrate/stream_ref*` is the memory ceiling of the integrate kernels' access pattern
//! (`weft::perf::stream_reference`: the same arrays read and written, in place, in the
//! same chunks, trivial arithmetic); integrate's fraction of it is `stream_ref / simd`.
//! `drape_1m` is the large case: a 1M-particle cloth (stretch + bend) over a sphere,
//! 5 substeps, 1 iteration, on 2 threads.
//!
//! Run: `cargo bench --bench kernels` (add `-- --quick` for a shorter run).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use weft::integrate::{predict, update, PredictParams};
use weft::model::cloth::ClothDesc;
use weft::{Effects, Fabric, PinSpec, SolverParams, World};

const SIZES: [usize; 4] = [1_000, 10_000, 100_000, 1_000_000];

fn cloth_world(n: usize) -> World {
    let side = (n as f64).sqrt().round() as u32;
    let desc = ClothDesc {
        rows: side,
        cols: side,
        spacing: 0.01,
        pins: vec![PinSpec::FirstRowCorners],
        fabric: Fabric::default(),
        ..Default::default()
    };
    let mut w = World::new(
        SolverParams {
            threads: 1,
            ..Default::default()
        },
        Effects::gravity(),
    )
    .unwrap();
    w.add_cloth(&desc).unwrap();
    w
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap()
}

fn integrate(c: &mut Criterion) {
    let mut g = c.benchmark_group("integrate");
    let (one, two) = (pool(1), pool(2));
    for n in SIZES {
        let world = cloth_world(n);
        let mut p = world.particles().clone();
        g.throughput(Throughput::Elements(p.count() as u64));
        let params = PredictParams {
            h: 1.0 / 600.0,
            gravity: Some([0.0, -9.81, 0.0]),
            drag: None,
            force: None,
        };
        let run = |p: &mut weft::data::particles::Particles, simd: bool, par: bool| {
            p.for_chunks(par, |c| predict(c, &params, simd));
            p.for_chunks(par, |c| update(c, 1.0 / 600.0, None, simd));
        };
        g.bench_with_input(BenchmarkId::new("scalar", n), &n, |b, _| {
            one.install(|| b.iter(|| run(&mut p, false, false)))
        });
        g.bench_with_input(BenchmarkId::new("simd", n), &n, |b, _| {
            one.install(|| b.iter(|| run(&mut p, true, false)))
        });
        g.bench_with_input(BenchmarkId::new("simd_2threads", n), &n, |b, _| {
            two.install(|| b.iter(|| run(&mut p, true, true)))
        });
        g.bench_with_input(BenchmarkId::new("stream_ref", n), &n, |b, _| {
            one.install(|| b.iter(|| weft::perf::stream_reference(&mut p, false)))
        });
        g.bench_with_input(BenchmarkId::new("stream_ref_2threads", n), &n, |b, _| {
            two.install(|| b.iter(|| weft::perf::stream_reference(&mut p, true)))
        });
    }
    g.finish();
}

fn solve(c: &mut Criterion) {
    let mut g = c.benchmark_group("solve");
    let (one, two) = (pool(1), pool(2));
    for n in SIZES {
        let world = cloth_world(n);
        let mut p = world.particles().clone();
        let mut set = world.distance_set().clone();
        g.throughput(Throughput::Elements(p.count() as u64));
        let inv_h2 = 3.6e5;
        g.bench_with_input(BenchmarkId::new("scalar", n), &n, |b, _| {
            b.iter(|| set.solve_scalar(&mut p.px, &mut p.py, &mut p.pz, &p.w, inv_h2))
        });
        g.bench_with_input(BenchmarkId::new("simd", n), &n, |b, _| {
            one.install(|| b.iter(|| set.solve_simd(&mut p.px, &mut p.py, &mut p.pz, &p.w, inv_h2, false)))
        });
        g.bench_with_input(BenchmarkId::new("simd_2threads", n), &n, |b, _| {
            two.install(|| b.iter(|| set.solve_simd(&mut p.px, &mut p.py, &mut p.pz, &p.w, inv_h2, true)))
        });
    }
    g.finish();
}

fn step(c: &mut Criterion) {
    let mut g = c.benchmark_group("step");
    g.sample_size(10);
    for n in [10_000usize, 100_000] {
        for threads in [1usize, 2] {
            let mut w = cloth_world(n);
            w.set_params(SolverParams {
                threads,
                substeps: 5,
                iterations: 1,
                ..Default::default()
            })
            .unwrap();
            g.throughput(Throughput::Elements(n as u64));
            g.bench_with_input(BenchmarkId::new(format!("{threads}threads"), n), &n, |b, _| {
                b.iter(|| w.step(1.0 / 60.0).unwrap())
            });
        }
    }
    g.finish();
}

fn drape(c: &mut Criterion) {
    let mut g = c.benchmark_group("drape_1m");
    g.sample_size(10);
    let mut w = weft::perf::sphere_drape_world(1_000_000, 2).unwrap();
    g.throughput(Throughput::Elements(w.particle_count() as u64));
    g.bench_function("sphere_2threads", |b| b.iter(|| w.step(1.0 / 60.0).unwrap()));
    g.finish();
}

criterion_group!(benches, integrate, solve, step, drape);
criterion_main!(benches);
