//! Pay only for what the scene names: the same 100x100 cloth stepped with no effects, with
//! gravity only, and with every effect named but at zero strength (gravity 0, drag 0, wind 0).
//! An effect that is not named must add nothing measurable; a named one costs its kernel even
//! at zero strength.
//!
//! Run: `cargo bench --bench effects`

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use weft::{ClothDesc, Effects, PinSpec, SolverParams, Wind, World};

fn world(effects: Effects) -> World {
    let desc = ClothDesc {
        rows: 100,
        cols: 100,
        spacing: 0.01,
        pins: vec![PinSpec::FirstRowCorners],
        ..Default::default()
    };
    let mut w = World::new(
        SolverParams {
            threads: 1,
            substeps: 5,
            ..Default::default()
        },
        effects,
    )
    .unwrap();
    w.add_cloth(&desc).unwrap();
    w
}

fn effects(c: &mut Criterion) {
    let mut g = c.benchmark_group("effects");
    let cases = [
        ("none", Effects::default()),
        ("gravity", Effects::gravity()),
        (
            "all-named-zero-strength",
            Effects {
                gravity: Some([0.0; 3]),
                drag: Some(0.0),
                wind: Some(Wind {
                    velocity: [0.0; 3],
                    ..Wind::default()
                }),
            },
        ),
    ];
    for (name, e) in cases {
        let mut w = world(e);
        g.bench_with_input(BenchmarkId::new("step_100x100", name), &name, |b, _| {
            b.iter(|| w.step(1.0 / 60.0).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, effects);
criterion_main!(benches);
