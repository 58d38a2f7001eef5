//! NURBS evaluation: local against global per point (the NURBS thesis' claim), and the SIMD batch kernels
//! against their scalar twins.
//!
//! Run briefly with `cargo bench --bench nurbs -- --warm-up-time 1 --measurement-time 2`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use weft::strands::nurbs::{GlobalScratch, NurbsCurve, NurbsSurface};

/// Deterministic wavy control points (no RNG dependency): `len` points.
fn control(len: usize) -> [Vec<f32>; 4] {
    let f = |i: usize, a: f32| ((i as f32) * a).sin();
    [
        (0..len).map(|i| f(i, 0.37)).collect(),
        (0..len).map(|i| f(i, 0.91)).collect(),
        (0..len).map(|i| f(i, 1.73)).collect(),
        (0..len).map(|i| 1.25 + 0.5 * f(i, 0.53)).collect(),
    ]
}

fn params(count: usize) -> Vec<f32> {
    (0..count).map(|j| ((j as f64 + 0.5) / count as f64) as f32).collect()
}

fn curve_per_point(c: &mut Criterion) {
    let us = params(64);
    let mut g = c.benchmark_group("nurbs_curve_point");
    g.throughput(Throughput::Elements(us.len() as u64));
    for n in [16usize, 256, 4096] {
        let [x, y, z, w] = control(n);
        let curve = NurbsCurve::new(x, y, z, w, 3).expect("valid curve");
        let mut scratch = GlobalScratch::default();
        g.bench_with_input(BenchmarkId::new("global", n), &n, |b, _| {
            b.iter(|| {
                for &u in &us {
                    black_box(curve.eval_global_with(black_box(u), &mut scratch).ok());
                }
            })
        });
        g.bench_with_input(BenchmarkId::new("local", n), &n, |b, _| {
            b.iter(|| {
                for &u in &us {
                    black_box(curve.eval_local(black_box(u)).ok());
                }
            })
        });
    }
    g.finish();
}

fn surface_per_point(c: &mut Criterion) {
    let us = params(16);
    let mut g = c.benchmark_group("nurbs_surface_point");
    g.throughput(Throughput::Elements(us.len() as u64));
    for n in [16usize, 64] {
        let [x, y, z, w] = control(n * n);
        let s = NurbsSurface::new(n, n, x, y, z, w, 3, 3).expect("valid surface");
        let mut scratch = GlobalScratch::default();
        g.bench_with_input(BenchmarkId::new("global", n), &n, |b, _| {
            b.iter(|| {
                for &u in &us {
                    black_box(s.eval_global_with(black_box(u), 1.0 - u, &mut scratch).ok());
                }
            })
        });
        g.bench_with_input(BenchmarkId::new("local", n), &n, |b, _| {
            b.iter(|| {
                for &u in &us {
                    black_box(s.eval_local(black_box(u), 1.0 - u).ok());
                }
            })
        });
    }
    g.finish();
}

fn batch(c: &mut Criterion) {
    let m = 4096;
    let us = params(m);
    let mut g = c.benchmark_group("nurbs_curve_batch");
    g.throughput(Throughput::Elements(m as u64));
    let (mut ox, mut oy, mut oz) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
    for p in [1usize, 3, 5] {
        let [x, y, z, w] = control(256);
        let curve = NurbsCurve::new(x, y, z, w, p).expect("valid curve");
        g.bench_with_input(BenchmarkId::new("scalar", p), &p, |b, _| {
            b.iter(|| curve.eval_many_scalar(black_box(&us), &mut ox, &mut oy, &mut oz))
        });
        g.bench_with_input(BenchmarkId::new("simd", p), &p, |b, _| {
            b.iter(|| curve.eval_many(black_box(&us), &mut ox, &mut oy, &mut oz))
        });
    }
    g.finish();

    let (ru, rv) = (64usize, 64usize);
    let (gu, gv) = (params(ru), params(rv));
    let mut g = c.benchmark_group("nurbs_surface_grid");
    g.throughput(Throughput::Elements((ru * rv) as u64));
    let (mut ox, mut oy, mut oz) = (vec![0.0; ru * rv], vec![0.0; ru * rv], vec![0.0; ru * rv]);
    for p in [1usize, 3] {
        let [x, y, z, w] = control(32 * 32);
        let s = NurbsSurface::new(32, 32, x, y, z, w, p, p).expect("valid surface");
        g.bench_with_input(BenchmarkId::new("scalar", p), &p, |b, _| {
            b.iter(|| s.eval_grid_scalar(black_box(&gu), &gv, &mut ox, &mut oy, &mut oz))
        });
        g.bench_with_input(BenchmarkId::new("simd", p), &p, |b, _| {
            b.iter(|| s.eval_grid(black_box(&gu), &gv, &mut ox, &mut oy, &mut oz))
        });
    }
    g.finish();
}

criterion_group!(benches, curve_per_point, surface_per_point, batch);
criterion_main!(benches);
