//! Invariants on random scenes: energy of closed, undamped cloths never rises above its start
//! (position-based projection only dissipates), and checkpoint + resume equals an
//! uninterrupted run bit for bit.

mod common;

use proptest::prelude::*;
use weft::scene::Scene;
use weft::world::checkpoint::Checkpoint;
use weft::{ClothDesc, Effects, Fabric, SolverParams};

/// Energy may exceed its start by at most this fraction (f32 rounding of a dissipative method).
const ENERGY_BAND: f64 = 0.01;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn closed_undamped_cloth_never_gains_energy(rows in 2u32..10, cols in 2u32..10, stretch_exp in 2u32..5,
            substeps in 1u32..6, seed in 0u32..1000) {
        let c = 10f32.powi(-(stretch_exp as i32));
        let fabric = Fabric { damping: 0.0, stretch_compliance: c, shear_compliance: 2.0 * c, bend_compliance: 10.0 * c, ..Fabric::default() };
        let desc = ClothDesc { rows, cols, spacing: 0.1, pins: vec![], tethers: None, fabric, ..Default::default() };
        let params = SolverParams { dt: 1.0 / 120.0, substeps, ..Default::default() };
        let mut w = common::world_with(&desc, params, Effects::default());
        let n = w.particle_count();
        let v = |k: u32| -> Vec<f32> { (0..n as u32).map(|i| (((i * 7919 + seed * 31 + k * 104729) % 17) as f32 - 8.0) * 0.05).collect() };
        w.set_velocities([&v(0), &v(1), &v(2)]).unwrap();
        let e0 = w.metrics().total;
        for step in 0..300 {
            w.step(1.0 / 120.0).unwrap();
            let e = w.metrics().total;
            prop_assert!(e.is_finite());
            prop_assert!(e <= e0 * (1.0 + ENERGY_BAND) + 1e-12, "step {}: energy {} above start {}", step, e, e0);
        }
    }

    #[test]
    fn resume_equals_uninterrupted(rows in 2u32..12, cols in 2u32..12, split in 1u64..30, substeps in 1u32..5,
            wind in any::<bool>(), pins in any::<bool>()) {
        let wind = if wind { "[effects.wind]\nvelocity = [3.0, 0.0, 2.0]\ngust = 0.5\n" } else { "" };
        let pins = if pins { "pins = [\"first-row-corners\"]\n" } else { "" };
        let text = format!("[solver]\nsubsteps = {substeps}\n[effects]\ngravity = [0.0, -9.81, 0.0]\ndrag = 0.01\n{wind}[[cloth]]\nrows = {rows}\ncols = {cols}\nspacing = 0.05\nfabric = \"wool\"\n{pins}");
        let scene = Scene::parse(&text, "random.toml").unwrap();
        let mut full = scene.world().unwrap();
        for _ in 0..30 {
            full.step(1.0 / 60.0).unwrap();
        }
        let mut part = scene.world().unwrap();
        for _ in 0..split {
            part.step(1.0 / 60.0).unwrap();
        }
        let bytes = part.checkpoint(&text).to_bytes();
        let c = Checkpoint::from_bytes(&bytes).unwrap();
        let mut resumed = Scene::parse(&c.scene, "resumed").unwrap().world().unwrap();
        resumed.restore(&c).unwrap();
        for _ in split..30 {
            resumed.step(1.0 / 60.0).unwrap();
        }
        prop_assert_eq!(common::state_bits(&full), common::state_bits(&resumed));
    }
}
