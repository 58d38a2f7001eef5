//! Tests of the four integrators on the same model: order of convergence on a spring with an
//! exact solution, stability, pinned particles, scalar twin and thread independence.

use crate::model::cloth::{ClothDesc, PinSpec};
use crate::model::effects::{Effects, Wind};
use crate::model::fabric::Fabric;
use crate::model::params::{Backend, Method, SolverParams};
use crate::WeftError;
use crate::World;

/// One free particle of mass 1 kg on a spring of stiffness `k` to a pinned particle, pulled
/// 0.5 m past its rest length of 1 m: `x(t) = 1 + 0.5 cos(√k t)`.
fn oscillator(method: Method, k: f32, dt: f32) -> World {
    let params = SolverParams {
        dt,
        substeps: 1,
        iterations: 1,
        method,
        ..SolverParams::default()
    };
    let mut w = World::new(params, Effects::default()).unwrap();
    let fabric = Fabric {
        mass: 1.0,
        stretch_compliance: 1.0 / k,
        damping: 0.0,
        ..Fabric::default()
    };
    w.add_cloth(&ClothDesc {
        rows: 1,
        cols: 2,
        spacing: 1.0,
        origin: [0.0; 3],
        u: [1.0, 0.0, 0.0],
        v: [0.0, -1.0, 0.0],
        fabric,
        pins: vec![PinSpec::Indices(vec![0])],
        shear: false,
        bend: false,
        tethers: None,
    })
    .unwrap();
    w.set_positions([&[0.0, 1.5], &[0.0, 0.0], &[0.0, 0.0]]).unwrap();
    w
}

/// |x(1 s) - exact| with `n` steps.
fn oscillator_error(method: Method, n: u32) -> f64 {
    let k = 100.0f32;
    let mut w = oscillator(method, k, 1.0 / n as f32);
    for _ in 0..n {
        w.step(1.0 / n as f32).unwrap();
    }
    let exact = 1.0 + 0.5 * (k as f64).sqrt().cos();
    (w.positions()[0][1] as f64 - exact).abs()
}

#[test]
fn each_method_converges_at_its_order() {
    // (method, order, coarse step count)
    for (method, order, n) in [
        (Method::SymplecticEuler, 1, 400),
        (Method::Leapfrog, 2, 100),
        (Method::ImplicitEuler, 1, 400),
        (Method::Xpbd, 1, 400),
    ] {
        let e1 = oscillator_error(method, n);
        let e2 = oscillator_error(method, 2 * n);
        let e4 = oscillator_error(method, 4 * n);
        let expect = 2f64.powi(order);
        for (a, b) in [(e1, e2), (e2, e4)] {
            let ratio = a / b;
            assert!(
                ratio > 0.75 * expect && ratio < 1.3 * expect,
                "{}: halving h divides the error by {ratio:.2} (errors {e1:.3e} {e2:.3e} {e4:.3e}), expected ~{expect}",
                method.name()
            );
        }
    }
}

#[test]
fn explicit_euler_with_stiff_spring_and_big_step_is_reported_diverged() {
    for method in [Method::SymplecticEuler, Method::Leapfrog] {
        let mut w = oscillator(method, 1e8, 1.0 / 30.0);
        let mut err = None;
        for _ in 0..200 {
            if let Err(e) = w.step(1.0 / 30.0) {
                err = Some(e);
                break;
            }
        }
        match err {
            Some(WeftError::Diverged { stage, .. }) => assert_eq!(stage, method.name()),
            other => panic!("{}: expected Diverged, got {other:?}", method.name()),
        }
        assert!(w.positions().iter().all(|a| a.iter().all(|v| v.is_finite())), "state restored");
    }
}

#[test]
fn implicit_euler_is_stable_with_a_stiff_spring_at_a_big_step() {
    let mut w = oscillator(Method::ImplicitEuler, 1e8, 1.0 / 30.0);
    for _ in 0..300 {
        w.step(1.0 / 30.0).unwrap();
    }
    let x = w.positions()[0][1];
    assert!((x - 1.0).abs() < 1e-3, "settles at the rest length, x = {x}");
}

fn cloth_world(method: Method, threads: usize, backend: Backend) -> World {
    let params = SolverParams {
        dt: 1.0 / 60.0,
        substeps: if method == Method::ImplicitEuler { 2 } else { 40 },
        method,
        threads,
        backend,
        ..SolverParams::default()
    };
    let effects = Effects {
        gravity: Some([0.0, -9.81, 0.0]),
        drag: Some(0.01),
        wind: Some(Wind {
            velocity: [1.0, 0.0, 2.0],
            gust: 0.3,
            ..Wind::default()
        }),
    };
    let mut w = World::new(params, effects).unwrap();
    // Soft enough (k = 1e3 N/m, 2.1 g) for the explicit methods at 40 substeps of 1/60 s.
    let fabric = Fabric {
        stretch_compliance: 1e-3,
        shear_compliance: 1e-3,
        bend_compliance: 1e-3,
        ..Fabric::preset("cotton").unwrap()
    };
    w.add_cloth(&ClothDesc {
        rows: 48,
        cols: 48,
        spacing: 0.02,
        origin: [0.0, 1.0, 0.0],
        u: [1.0, 0.0, 0.0],
        v: [0.0, 0.0, 1.0],
        fabric,
        pins: vec![PinSpec::FirstRowCorners],
        shear: true,
        bend: true,
        tethers: None,
    })
    .unwrap();
    w
}

#[test]
fn every_method_gives_the_same_bits_on_1_and_2_threads_and_pins_stay_fixed() {
    for method in Method::ALL {
        let run = |threads: usize, backend: Backend| {
            let mut w = cloth_world(method, threads, backend);
            let pinned: Vec<[f32; 3]> = (0..w.particle_count())
                .filter(|&i| w.particles().w[i] == 0.0)
                .map(|i| w.particles().position(i))
                .collect();
            for _ in 0..10 {
                w.step(1.0 / 60.0).unwrap();
            }
            let after: Vec<[f32; 3]> = (0..w.particle_count())
                .filter(|&i| w.particles().w[i] == 0.0)
                .map(|i| w.particles().position(i))
                .collect();
            assert_eq!(pinned.len(), 2);
            assert_eq!(pinned, after, "{}: pinned particles moved", method.name());
            w.state_bits()
        };
        let one = run(1, Backend::Simd);
        assert_eq!(one, run(2, Backend::Simd), "{}: 1 vs 2 threads", method.name());
        if method != Method::Xpbd {
            // The force kernels and the kick have scalar twins: the whole step matches.
            assert_eq!(one, run(1, Backend::Scalar), "{}: SIMD vs scalar", method.name());
        }
    }
}

#[test]
fn metrics_use_the_spring_energy_for_force_methods() {
    let w = oscillator(Method::SymplecticEuler, 100.0, 0.01);
    let e = w.metrics().elastic;
    assert!((e - 0.5 * 100.0 * 0.25).abs() < 1e-3, "{e}");
}
