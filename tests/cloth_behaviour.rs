//! Physical behaviour of the core step: a hanging cloth settles with bounded strain, and an
//! undamped closed cloth keeps its energy within a band.

mod common;

use weft::{ClothDesc, Effects, Fabric, SolverParams};

#[test]
fn hanging_cloth_settles_with_bounded_strain() {
    let desc = common::hanging(30, 30);
    let params = SolverParams {
        dt: 1.0 / 60.0,
        substeps: 10,
        iterations: 1,
        ..Default::default()
    };
    let mut w = common::world_with(&desc, params, Effects::gravity());
    for _ in 0..600 {
        w.step(1.0 / 60.0).unwrap();
    }
    let m = w.metrics();
    // Settled: mean speed tiny (kinetic energy per particle).
    let per_particle = m.kinetic / w.particle_count() as f64;
    assert!(per_particle < 1e-7, "still moving: {per_particle} J per particle");
    // Stretch stays within 5% anywhere, 1% on average (tethers + small steps).
    assert!(m.max_strain < 0.05, "max strain {}", m.max_strain);
    assert!(m.mean_strain < 0.01, "mean strain {}", m.mean_strain);
    // It hangs below its pins.
    let [_, y, _] = w.positions();
    let lowest = y.iter().cloned().fold(f32::INFINITY, f32::min);
    assert!(lowest < 1.0 - 29.0 * 0.05 * 0.9, "lowest point {lowest}");
}

/// Energy band of an undamped, closed (no pins, no gravity, no drag) cloth over 10 000 steps:
/// it may lose energy (position-based projection dissipates) but must never gain more than 1%.
const ENERGY_GAIN_BAND: f64 = 0.01;

#[test]
fn undamped_closed_cloth_energy_stays_in_band() {
    let fabric = Fabric {
        damping: 0.0,
        stretch_compliance: 1e-2,
        shear_compliance: 2e-2,
        bend_compliance: 1e-1,
        ..Fabric::default()
    };
    let desc = ClothDesc {
        rows: 10,
        cols: 10,
        spacing: 0.1,
        pins: vec![],
        tethers: None,
        fabric,
        ..Default::default()
    };
    let params = SolverParams {
        dt: 1.0 / 120.0,
        substeps: 4,
        iterations: 1,
        ..Default::default()
    };
    let mut w = common::world_with(&desc, params, Effects::default());
    let n = w.particle_count();
    let vx: Vec<f32> = (0..n).map(|i| ((i * 7919) % 13) as f32 * 0.05 - 0.3).collect();
    let vy: Vec<f32> = (0..n).map(|i| ((i * 104729) % 11) as f32 * 0.05 - 0.25).collect();
    let vz: Vec<f32> = (0..n).map(|i| ((i * 31) % 7) as f32 * 0.05 - 0.15).collect();
    w.set_velocities([&vx, &vy, &vz]).unwrap();
    let e0 = w.metrics().total;
    let momentum = |w: &weft::World| {
        let v = w.velocities();
        let m = 1.0 / w.particles().w[0] as f64;
        [0, 1, 2].map(|k| v[k].iter().map(|&c| c as f64 * m).sum::<f64>())
    };
    let p0 = momentum(&w);
    let mut lowest = e0;
    for step in 0..10_000 {
        w.step(1.0 / 120.0).unwrap();
        let e = w.metrics().total;
        assert!(e.is_finite());
        assert!(e <= e0 * (1.0 + ENERGY_GAIN_BAND), "step {step}: energy {e} above start {e0}");
        lowest = lowest.min(e);
    }
    // Internal constraints conserve linear momentum (up to f32 rounding).
    let p1 = momentum(&w);
    for k in 0..3 {
        assert!((p1[k] - p0[k]).abs() < 1e-4, "momentum {k}: {} -> {}", p0[k], p1[k]);
    }
    eprintln!("energy: start {e0}, lowest {lowest}, end {}", w.metrics().total);
}
