//! The update pass that also runs the next substep's predict gives the same bits as the two
//! separate passes.

use crate::model::params::Backend;
use crate::model::shapes::Shape;
use crate::obstacles::Obstacle;
use crate::{ClothDesc, Effects, Fabric, SolverParams, World};

/// A 90 x 90 damped cloth (8100 particles: two chunks) falling onto a sphere, with gravity and
/// drag, 4 substeps.
fn world(threads: usize, backend: Backend, fuse: bool) -> World {
    let desc = ClothDesc {
        rows: 90,
        cols: 90,
        spacing: 0.01,
        origin: [-0.45, 0.23, -0.45],
        u: [1.0, 0.0, 0.0],
        v: [0.0, 0.0, 1.0],
        pins: vec![],
        fabric: Fabric {
            damping: 0.5,
            ..Fabric::preset("cotton").unwrap()
        },
        ..Default::default()
    };
    let params = SolverParams {
        threads,
        substeps: 4,
        backend,
        ..Default::default()
    };
    let effects = Effects {
        drag: Some(0.01),
        ..Effects::gravity()
    };
    let mut w = World::new(params, effects).unwrap();
    w.add_cloth(&desc).unwrap();
    let ball = Shape::Sphere {
        center: [0.0; 3],
        radius: 0.2,
    };
    w.add_obstacle(Obstacle::shape(ball).unwrap()).unwrap();
    w.fuse_predict = fuse;
    w
}

#[test]
fn fused_next_predict_equals_separate_passes_bitwise() {
    for (threads, backend) in [(1, Backend::Simd), (2, Backend::Simd), (1, Backend::Scalar)] {
        let mut fused = world(threads, backend, true);
        let mut split = world(threads, backend, false);
        for step in 0..12 {
            fused.step(1.0 / 60.0).unwrap();
            split.step(1.0 / 60.0).unwrap();
            assert_eq!(
                fused.state_bits(),
                split.state_bits(),
                "{threads} thread(s), {backend:?}, step {step}"
            );
        }
        assert!(fused.obstacle_contacts() > 0, "the sheet reached the sphere");
    }
}

/// A 70 x 70 cloth (4900 particles: two mean-velocity chunks) hung over its middle row with
/// self-collision (VcCPBD): the halves swing under, so the speed clamp acts.
fn hung(threads: usize, backend: Backend, fuse: bool) -> World {
    use crate::model::self_collision::{Response, SelfCollision};
    let params = SolverParams {
        threads,
        substeps: 10,
        iterations: 1,
        backend,
        ..Default::default()
    };
    let sc = SelfCollision {
        response: Response::Vccpbd,
        ..SelfCollision::default()
    };
    let (mut w, _) = crate::perf::fold_world(70, Fabric::preset("basic").unwrap(), params, sc).unwrap();
    w.fuse_predict = fuse;
    w
}

/// The mean velocity summed inside the predict pass (and the fused next predict) gives the
/// speed clamp the bits of the separate `mean_velocity` pass, 1 and 2 threads and scalar.
#[test]
fn self_collision_mean_summed_in_predict_equals_separate_pass_bitwise() {
    for (threads, backend) in [(1, Backend::Simd), (2, Backend::Simd), (1, Backend::Scalar)] {
        let mut fused = hung(threads, backend, true);
        let mut split = hung(threads, backend, false);
        let dt = fused.params.dt;
        for step in 0..40 {
            fused.step(dt).unwrap();
            split.step(dt).unwrap();
            assert_eq!(
                fused.state_bits(),
                split.state_bits(),
                "{threads} thread(s), {backend:?}, step {step}"
            );
        }
        assert!(
            fused.selfcol.touched_blocks() + fused.selfcol.pair_count() > 0,
            "no self-collision work"
        );
    }
}
