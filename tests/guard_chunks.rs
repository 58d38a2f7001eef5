//! The divergence guard of the XPBD step, whose copy of the state is made inside the first
//! predict pass and whose check runs inside the last update pass, chunk by chunk: on a world
//! of many chunks, in parallel and serially, over an obstacle, it still restores the state
//! from before the step bit for bit and names the particle and the stage.

mod common;

use weft::model::shapes::Shape;
use weft::obstacles::Obstacle;
use weft::{ClothDesc, Effects, SolverParams, WeftError, World};

/// A 100 x 100 cloth (10 000 particles: three chunks of 4096) over a sphere, after a few
/// steps so that contacts exist.
fn world(threads: usize) -> World {
    let desc = ClothDesc {
        rows: 100,
        cols: 100,
        spacing: 0.01,
        origin: [-0.5, 0.21, -0.5],
        u: [1.0, 0.0, 0.0],
        v: [0.0, 0.0, 1.0],
        pins: vec![],
        ..Default::default()
    };
    let params = SolverParams {
        threads,
        substeps: 4,
        ..Default::default()
    };
    let mut w = common::world_with(&desc, params, Effects::gravity());
    let ball = Shape::Sphere {
        center: [0.0; 3],
        radius: 0.2,
    };
    w.add_obstacle(Obstacle::shape(ball).unwrap()).unwrap();
    for _ in 0..5 {
        w.step(1.0 / 60.0).unwrap();
    }
    assert!(w.obstacle_contacts() > 0);
    w
}

#[test]
fn guard_restores_a_many_chunk_world_and_names_particle_and_stage() {
    for threads in [1, 2] {
        let mut w = world(threads);
        let n = w.particle_count();
        let bad = 9_001;
        let mut vx = vec![0.0f32; n];
        vx[bad] = 3e38;
        let zero = vec![0.0f32; n];
        w.set_velocities([&vx, &zero, &zero]).unwrap();
        let before = common::state_bits(&w);
        let steps = w.steps();
        match w.step(1e3) {
            Err(WeftError::Diverged { particle, stage }) => {
                assert_eq!((particle, stage), (bad, "predict"), "{threads} threads");
            }
            other => panic!("expected divergence, got {other:?}"),
        }
        assert_eq!(common::state_bits(&w), before, "state before the step is kept ({threads} threads)");
        assert_eq!(w.steps(), steps);
        // the restored world steps on normally once the bad velocity is gone
        w.set_velocities([&zero, &zero, &zero]).unwrap();
        w.step(1.0 / 60.0).unwrap();
    }
}

#[test]
fn guard_on_and_off_give_the_same_bits() {
    let mut on = world(2);
    let mut off = world(2);
    let mut p = off.params().clone();
    p.guard = false;
    off.set_params(p).unwrap();
    for _ in 0..5 {
        on.step(1.0 / 60.0).unwrap();
        off.step(1.0 / 60.0).unwrap();
    }
    assert_eq!(common::state_bits(&on), common::state_bits(&off));
}
