//! The strand step: 1000 and 5000 strands x 16 points on a head-sized sphere, gravity and gusty
//! wind (per-point drag), 10 substeps, scalp collision — one `World::step` per iteration, on
//! one and two threads.
//!
//! Run: `cargo bench --bench strands -- --warm-up-time 1 --measurement-time 2`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use weft::strands::{Scalp, StrandsDesc};
use weft::{Effects, SolverParams, Wind, World};

fn hair_world(count: u32, threads: usize) -> World {
    let effects = Effects {
        wind: Some(Wind {
            velocity: [4.0, 0.0, -1.0],
            gust: 0.5,
            ..Wind::default()
        }),
        ..Effects::gravity()
    };
    let params = SolverParams {
        substeps: 10,
        threads,
        ..Default::default()
    };
    let mut w = World::new(params, effects).unwrap();
    w.add_strands(&StrandsDesc {
        scalp: Scalp::ellipsoid([0.0, 1.6, 0.0], [0.1; 3], [0.0, 105.0]),
        count,
        points: 16,
        segment_length: 0.012,
        bend_compliance: 1.0,
        mass: 2e-6,
        thickness: 5e-4,
        damping: 1.0,
        ..Default::default()
    })
    .unwrap();
    // Let the strands fall onto the head first, so the bench measures a draped state.
    for _ in 0..30 {
        w.step(1.0 / 60.0).unwrap();
    }
    w
}

fn strand_step(c: &mut Criterion) {
    let mut g = c.benchmark_group("strand_step");
    for count in [1000u32, 5000] {
        for threads in [1usize, 2] {
            let mut w = hair_world(count, threads);
            g.throughput(Throughput::Elements(count as u64 * 16));
            g.bench_function(BenchmarkId::new(format!("{threads}t"), format!("{count}x16")), |b| {
                b.iter(|| w.step(1.0 / 60.0).unwrap())
            });
        }
    }
    g.finish();
}

criterion_group!(benches, strand_step);
criterion_main!(benches);
