//! Self-collision broadphase: spatial hash (build + query) against the particle AABB tree
//! (refit + query) and, for small N, the O(n²) brute force, on a folded cloth.
//!
//! Layout: a square sheet of `side x side` particles at grid spacing `s = 1/128` (a power of two,
//! so in-sheet neighbours sit at exactly `s`), folded like an accordion into four flat layers
//! `0.6 s` apart, so every particle has its in-sheet neighbours plus neighbours in the layers
//! above and below. `max_dist = s`, hash spacing `s` (Müller's rule: cell = particle diameter
//! = collision distance); `hash15` uses cells of `1.5 s`.
//!
//! Run briefly: `cargo bench --bench broadphase -- --warm-up-time 1 --measurement-time 2`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use weft::self_collision::hash::SpatialHash;
use weft::self_collision::neighbours::Neighbours;
use weft::self_collision::tree::{ParticleTree, TreeShape};

struct Cloth {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
}

/// A `side x side` sheet at spacing `s`, folded into four layers `0.6 s` apart.
fn folded_cloth(side: usize, s: f32) -> Cloth {
    let fold = side.div_ceil(4);
    let mut c = Cloth {
        x: Vec::with_capacity(side * side),
        y: Vec::with_capacity(side * side),
        z: Vec::with_capacity(side * side),
    };
    for v in 0..side {
        for u in 0..side {
            let (layer, t) = (u / fold, u % fold);
            let along = if layer % 2 == 0 { t } else { fold - 1 - t };
            c.x.push(along as f32 * s);
            c.y.push(v as f32 * s);
            c.z.push(layer as f32 * 0.6 * s);
        }
    }
    c
}

fn bench(cr: &mut Criterion) {
    let s = 1.0f32 / 128.0;
    let mut g = cr.benchmark_group("broadphase");
    g.sample_size(10);
    for side in [32usize, 100, 316] {
        let n = side * side;
        let c = folded_cloth(side, s);
        let (x, y, z) = (&c.x[..], &c.y[..], &c.z[..]);
        g.throughput(Throughput::Elements(n as u64));

        let mut h = SpatialHash::new(n);
        let mut nb = Neighbours::new();
        h.build(x, y, z, n, s).unwrap();
        h.query_all(x, y, z, n, s, &mut nb).unwrap();
        eprintln!(
            "N = {n}: {} neighbour entries ({:.1} per particle)",
            nb.total(),
            nb.total() as f64 / n as f64
        );

        g.bench_with_input(BenchmarkId::new("hash_build_query", n), &n, |b, &n| {
            b.iter(|| {
                h.build(x, y, z, n, s).unwrap();
                h.query_all(x, y, z, n, s, &mut nb).unwrap();
                black_box(nb.total())
            })
        });
        // Same query with cells 1.5x the collision distance (see the hash module docs).
        g.bench_with_input(BenchmarkId::new("hash15_build_query", n), &n, |b, &n| {
            b.iter(|| {
                h.build(x, y, z, n, 1.5 * s).unwrap();
                h.query_all(x, y, z, n, s, &mut nb).unwrap();
                black_box(nb.total())
            })
        });
        g.bench_with_input(BenchmarkId::new("hash_build_only", n), &n, |b, &n| {
            b.iter(|| {
                h.build(x, y, z, n, s).unwrap();
                black_box(h.cell_entries().len())
            })
        });
        g.bench_with_input(BenchmarkId::new("hash_serial", n), &n, |b, &n| {
            b.iter(|| {
                h.build_serial(x, y, z, n, s).unwrap();
                h.query_all_serial(x, y, z, n, s, &mut nb).unwrap();
                black_box(nb.total())
            })
        });

        let mut t = ParticleTree::build(x, y, z, n, TreeShape::LeafSize(8)).unwrap();
        g.bench_with_input(BenchmarkId::new("tree8_refit_query", n), &n, |b, &n| {
            b.iter(|| {
                t.refit(x, y, z, n).unwrap();
                t.query_all(x, y, z, n, s, &mut nb).unwrap();
                black_box(nb.total())
            })
        });
        g.bench_with_input(BenchmarkId::new("tree8_refit_only", n), &n, |b, &n| {
            b.iter(|| {
                t.refit(x, y, z, n).unwrap();
                black_box(t.boxes().len())
            })
        });
        g.bench_with_input(BenchmarkId::new("tree8_serial", n), &n, |b, &n| {
            b.iter(|| {
                t.refit_serial(x, y, z, n).unwrap();
                t.query_all_serial(x, y, z, n, s, &mut nb).unwrap();
                black_box(nb.total())
            })
        });

        if n <= 10_000 {
            // The paper's box hierarchy: depth 5, 32 leaves.
            let mut t5 = ParticleTree::build(x, y, z, n, TreeShape::Depth(5)).unwrap();
            g.bench_with_input(BenchmarkId::new("tree_depth5_refit_query", n), &n, |b, &n| {
                b.iter(|| {
                    t5.refit(x, y, z, n).unwrap();
                    t5.query_all(x, y, z, n, s, &mut nb).unwrap();
                    black_box(nb.total())
                })
            });
            g.bench_with_input(BenchmarkId::new("brute_force", n), &n, |b, &n| {
                b.iter(|| {
                    nb.fill_brute_force(x, y, z, n, s).unwrap();
                    black_box(nb.total())
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
