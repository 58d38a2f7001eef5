//! Kernel benches: integrate (predict + update) and constraint solve, each as the scalar f32
//! twin, SIMD on one thread, and SIMD on two threads, for N = 1k, 10k, 100k, 1M particles.
//! Ratios are always against the scalar f32 twin (never the f64 reference). The two-thread
//! runs go through `weft::perf::awake`, as a step runs its passes.
//!
//! `integrate/stream_ref*` is the memory ceiling of the integrate kernels' access pattern
//! (`weft::perf::stream_reference`: the same arrays read and written, in place, in the
//! same chunks, trivial arithmetic); integrate's fraction of it is `stream_ref / simd`.
//! `drape_1m` is the large case: a 1M-particle cloth (stretch + bend) over a sphere,
//! 5 substeps, 1 iteration, on 2 threads. `sphere_contacts` is the contact search of one
//! substep against a sphere for 64k particles whose paths all lie around its surface (a
//! cloth draped on a ball: no block is skipped by the pre-test), SIMD and its scalar twin.
//! `finite_check` is the guard's check of a chunk's end state (six arrays of 10k values, as a
//! 100 x 100 cloth's), SIMD and its scalar twin.
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
            two.install(|| weft::perf::awake(|| b.iter(|| run(&mut p, true, true))))
        });
        g.bench_with_input(BenchmarkId::new("stream_ref", n), &n, |b, _| {
            one.install(|| b.iter(|| weft::perf::stream_reference(&mut p, false)))
        });
        g.bench_with_input(BenchmarkId::new("stream_ref_2threads", n), &n, |b, _| {
            two.install(|| weft::perf::awake(|| b.iter(|| weft::perf::stream_reference(&mut p, true))))
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
            two.install(|| weft::perf::awake(|| b.iter(|| set.solve_simd(&mut p.px, &mut p.py, &mut p.pz, &p.w, inv_h2, true))))
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

#[allow(clippy::needless_range_loop)] // `i` indexes eight arrays alike
fn sphere_contacts(c: &mut Criterion) {
    use weft::model::shapes::Shape;
    use weft::obstacles::kernels::{shape_block_scalar, shape_block_simd, GenInput, SLOT_BLOCK};
    const N: usize = 65_536;
    // paths from 4 cm above a unit sphere to 2 mm under or over its surface, over the upper
    // half, in a golden-angle spiral
    let mut v: [Vec<f32>; 8] = std::array::from_fn(|_| vec![0.0; N]);
    for i in 0..N {
        let (z, a) = (i as f32 / N as f32, i as f32 * 2.399_963);
        let s = (1.0 - z * z).sqrt();
        let dir = [s * a.cos(), z, s * a.sin()];
        let (r0, r1) = (1.04, 1.0 + 0.002 * ((i % 3) as f32 - 1.0));
        for k in 0..3 {
            v[k][i] = dir[k] * r0;
            v[3 + k][i] = dir[k] * r1;
        }
        v[6][i] = 1.0;
        v[7][i] = 0.002;
    }
    let reach: Vec<f32> = v[7].iter().map(|t| t + t.max(3e-3)).collect();
    let g = GenInput {
        x: [&v[0], &v[1], &v[2]],
        p: [&v[3], &v[4], &v[5]],
        w: &v[6],
        th: &v[7],
        reach: &reach,
        n: N,
        shift: [0.0; 3],
    };
    let sphere = Shape::Sphere {
        center: [0.0; 3],
        radius: 1.0,
    };
    let mut out = vec![0.0f32; N / 8 * SLOT_BLOCK];
    let mut grp = c.benchmark_group("sphere_contacts");
    grp.throughput(Throughput::Elements(N as u64));
    grp.bench_function("simd", |b| {
        b.iter(|| {
            for (k, o) in out.chunks_mut(SLOT_BLOCK).enumerate() {
                shape_block_simd(&sphere, &g, k, o);
            }
        })
    });
    grp.bench_function("scalar", |b| {
        b.iter(|| {
            for (k, o) in out.chunks_mut(SLOT_BLOCK).enumerate() {
                shape_block_scalar(&sphere, &g, k, o);
            }
        })
    });
    grp.finish();
}

fn finite_check(c: &mut Criterion) {
    use weft::data::particles::{chunk_finite_scalar, chunk_finite_simd};
    const N: usize = 10_000;
    let v: Vec<Vec<f32>> = (0..6).map(|k| (0..N).map(|i| (i * 6 + k) as f32 * 1e-3).collect()).collect();
    let arrays: Vec<&[f32]> = v.iter().map(|a| &a[..]).collect();
    let mut grp = c.benchmark_group("finite_check");
    grp.throughput(Throughput::Elements(N as u64));
    grp.bench_function("simd", |b| b.iter(|| chunk_finite_simd(std::hint::black_box(&arrays), N)));
    grp.bench_function("scalar", |b| b.iter(|| chunk_finite_scalar(std::hint::black_box(&arrays), N)));
    grp.finish();
}

criterion_group!(benches, integrate, solve, step, drape, sphere_contacts, finite_check);
criterion_main!(benches);
