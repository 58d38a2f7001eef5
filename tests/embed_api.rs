//! The embedding contract: uneven frames do not change the physics, thread use does not change
//! the bits, kinematic pins pull smoothly.

mod common;

use std::collections::BTreeMap;
use std::sync::Arc;

use weft::{Backend, ClothDesc, Effects, SolverParams, Wind, World};

fn effects() -> Effects {
    Effects {
        gravity: Some([0.0, -9.81, 0.0]),
        drag: Some(0.02),
        wind: Some(Wind {
            velocity: [1.0, 0.0, 4.0],
            gust: 0.5,
            ..Wind::default()
        }),
    }
}

fn world(rows: u32, params: SolverParams) -> World {
    common::world_with(&common::hanging(rows, rows), params, effects())
}

/// A frame loop: per frame, advance by `frame`; before every fixed step the first pin is moved
/// on a circle as a function of simulated time. Returns the state bits after every step count
/// reached.
fn run(frames: &[f64], max_steps: u32) -> BTreeMap<u64, Vec<u32>> {
    let params = SolverParams {
        dt: 1.0 / 120.0,
        substeps: 4,
        ..Default::default()
    };
    let mut w = world(12, params);
    w.set_max_steps_per_advance(max_steps).unwrap();
    let start = w.position(0).unwrap();
    let mut out = BTreeMap::new();
    for &f in frames {
        let r = w
            .advance_with(f, |w| {
                let s = w.steps() as f32;
                let t = mint::Point3 {
                    x: start.x + 0.05 * (s * 0.1).sin(),
                    y: start.y,
                    z: start.z + 0.05 * (s * 0.1).cos(),
                };
                w.set_pin_position(0, t)
            })
            .unwrap();
        assert!((0.0..1.0).contains(&r.alpha));
        out.insert(w.steps(), common::state_bits(&w));
    }
    out
}

#[test]
fn uneven_frames_give_bitwise_the_same_physics() {
    let even = vec![1.0 / 60.0; 60];
    let mut s = 0x9e3779b97f4a7c15u64;
    let uneven: Vec<f64> = (0..90)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 0.03
        })
        .collect();
    let a = run(&even, 100);
    let b = run(&uneven, 100);
    let c = run(&uneven, 2); // capped: fewer steps, same physics per step
    let mut common_counts = 0;
    for (k, bits) in &a {
        for other in [&b, &c] {
            if let Some(o) = other.get(k) {
                assert!(o == bits, "state after {k} steps differs");
                common_counts += 1;
            }
        }
    }
    assert!(common_counts >= 10, "only {common_counts} step counts in common");
    // Whole steps owed: floor(total time / dt), dt being the f32 step widened to f64.
    let dt = (1.0f32 / 120.0) as f64;
    for (frames, run) in [(&even, &a), (&uneven, &b)] {
        let owed = (frames.iter().sum::<f64>() / dt).floor() as u64;
        let took = *run.keys().last().unwrap();
        assert!(took.abs_diff(owed) <= 1, "took {took} steps, owed {owed}");
    }
}

#[test]
fn every_thread_mode_gives_the_same_bits() {
    // 80 x 80 particles: big enough for the parallel chunked paths.
    let run = |mode: &str| {
        let params = SolverParams {
            threads: match mode {
                "own-1" => 1,
                "own-3" => 3,
                _ => 0,
            },
            backend: if mode == "scalar" { Backend::Scalar } else { Backend::Simd },
            iterations: 2,
            substeps: 3,
            ..Default::default()
        };
        let mut w = world(80, params);
        match mode {
            "caller-thread" => w.set_caller_thread_only(true),
            "given-pool" => w.set_thread_pool(Arc::new(rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap())),
            _ => {}
        }
        for k in 0..4 {
            let mut p = w.position(79).unwrap();
            p.y += 0.01 * k as f32;
            w.set_pin_position(79, p).unwrap();
            w.step(1.0 / 60.0).unwrap();
        }
        common::state_bits(&w)
    };
    let global = run("global");
    for mode in ["own-1", "own-3", "given-pool", "caller-thread", "scalar"] {
        assert!(run(mode) == global, "{mode} differs from the global pool");
    }
}

#[test]
fn kinematic_move_kicks_less_than_a_teleport() {
    // Drag a corner 3 cm in one step: as a kinematic move (spread over the substeps) and as a
    // teleport (set_positions). Both end with the pin on the target.
    let desc = ClothDesc {
        tethers: None,
        ..common::hanging(10, 10)
    };
    let params = SolverParams {
        substeps: 8,
        ..Default::default()
    };
    let mut a = common::world_with(&desc, params.clone(), Effects::gravity());
    let mut b = common::world_with(&desc, params, Effects::gravity());
    let target = {
        let p = a.position(0).unwrap();
        mint::Point3 {
            x: p.x - 0.03,
            y: p.y + 0.03,
            z: p.z,
        }
    };
    a.set_pin_position(0, target).unwrap();
    a.step(1.0 / 60.0).unwrap();
    let [x, y, z] = b.positions().map(|s| s.to_vec());
    let (mut x, mut y) = (x, y);
    x[0] = target.x;
    y[0] = target.y;
    b.set_positions([&x, &y, &z]).unwrap();
    b.step(1.0 / 60.0).unwrap();
    assert_eq!(a.position(0).unwrap(), b.position(0).unwrap());
    let vmax = |w: &World| {
        let v = w.velocities();
        (1..w.particle_count())
            .map(|i| (v[0][i].powi(2) + v[1][i].powi(2) + v[2][i].powi(2)).sqrt())
            .fold(0.0f32, f32::max)
    };
    // The teleport kicks the neighbours within the first substep; the kinematic move does not.
    let (ka, kb) = (a.metrics().kinetic, b.metrics().kinetic);
    assert!(ka < 0.75 * kb, "kinetic energy: kinematic {ka} J vs teleport {kb} J");
    assert!(
        vmax(&a) < vmax(&b),
        "fastest free particle: kinematic {} vs teleport {}",
        vmax(&a),
        vmax(&b)
    );
}
