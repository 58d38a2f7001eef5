//! The obstacle slots' touched flags in a running world (`obstacle_slots.rs`).

use crate::{ClothDesc, Effects, SolverParams, World};

/// After steps of a cloth falling onto a sphere (touching some blocks, leaving others, and
/// blocks touched earlier coming free), every touched flag equals its block's contents,
/// and the contacts found with the sphere pre-test equal those of the scalar backend.
#[test]
fn touched_flags_follow_the_slots() {
    use crate::{Backend, PinSpec};
    let run = |backend: Backend| {
        let params = SolverParams {
            backend,
            substeps: 4,
            ..Default::default()
        };
        let mut w = World::new(params, Effects::gravity()).unwrap();
        w.add_cloth(&ClothDesc {
            rows: 30,
            cols: 30,
            spacing: 0.02,
            origin: [-0.3, 0.205, -0.3],
            u: [1.0, 0.0, 0.0],
            v: [0.0, 0.0, 1.0],
            pins: vec![PinSpec::FirstRowCorners],
            ..Default::default()
        })
        .unwrap();
        let ball = crate::model::shapes::Shape::Sphere {
            center: [0.0, 0.0, 0.0],
            radius: 0.2,
        };
        w.add_obstacle(super::Obstacle::shape(ball).unwrap().with_velocity([0.3, 0.0, 0.0]).unwrap())
            .unwrap();
        let mut seen = 0;
        for _ in 0..40 {
            w.step(1.0 / 60.0).unwrap();
            assert!(w.obstacles.slots.iter().all(|s| s.flags_consistent()));
            seen += w.obstacles.slots[0].touched.iter().filter(|&&t| t).count();
        }
        assert!(seen > 0 && w.obstacles.slots[0].touched.iter().any(|&t| !t));
        (w.obstacles.slots.clone(), w.particles.clone())
    };
    let (simd, scalar) = (run(Backend::Simd), run(Backend::Scalar));
    assert_eq!(simd.0, scalar.0);
    assert_eq!(simd.1, scalar.1);
}
