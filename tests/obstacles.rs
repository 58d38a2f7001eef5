//! Obstacles in the step: no particle ends a step inside a closed obstacle (fast particles
//! included), cloth comes to rest on a sphere and on the dress form, results do not depend on
//! the thread count or the backend.

mod common;

use proptest::prelude::*;
use weft::model::shapes::Shape;
use weft::obstacles::mesh::dressform::dress_form;
use weft::obstacles::{BroadphaseKind, Obstacle};
use weft::{Backend, ClothDesc, Effects, Fabric, SolverParams, World};

/// Deepest accepted penetration at the end of a step, m (the stand-off is the 1 mm cotton
/// thickness; this allows rounding only).
const TOL: f32 = 1e-4;
/// Deepest accepted penetration of the dress form, m: [`TOL`] plus the documented bound of a
/// particle dragged across a concave crease (`obstacles::mesh::response`): contacts are found
/// once a substep, so a drag along the form that the solver's sweeps carry over a crease can
/// end up to ~0.15 mm inside the neighbouring face for that substep (worst case found: 0.14 mm
/// at ~80 m/s); the next substep puts it out.
const CREASE_TOL: f32 = 3e-4;

fn obstacle(which: usize) -> Obstacle {
    match which {
        0 => Obstacle::shape(Shape::plane([0.0, 0.0, 0.0], [0.1, 1.0, 0.0]).unwrap()).unwrap(),
        1 => Obstacle::shape(Shape::Sphere {
            center: [0.0, 0.4, 0.0],
            radius: 0.3,
        })
        .unwrap(),
        2 => Obstacle::shape(Shape::Box {
            center: [0.0, 0.4, 0.0],
            half: [0.3, 0.1, 0.2],
            axes: Shape::axes_from_euler_deg([10.0, 30.0, 0.0]),
        })
        .unwrap(),
        _ => Obstacle::mesh(dress_form(800).unwrap(), BroadphaseKind::Grid(None), which == 4).unwrap(),
    }
}

/// Sixteen free particles joined by very soft constraints (the obstacle stage alone decides).
fn loose_world(substeps: u32) -> World {
    let mut fabric = Fabric::preset("cotton").unwrap();
    fabric.stretch_compliance = 1e3;
    let desc = ClothDesc {
        rows: 4,
        cols: 4,
        spacing: 0.1,
        fabric,
        shear: false,
        bend: false,
        tethers: None,
        pins: vec![],
        ..Default::default()
    };
    let params = SolverParams {
        substeps,
        iterations: 2,
        threads: 1,
        ..Default::default()
    };
    common::world_with(&desc, params, Effects::gravity())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(common::cases(64)))]
    #[test]
    fn no_particle_ends_a_step_inside_a_closed_obstacle(
        which in 0usize..5,
        substeps in 1u32..3,
        start in proptest::collection::vec((-0.6f32..0.6, -0.2f32..1.2, -0.6f32..0.6), 16),
        vel in proptest::collection::vec((-60.0f32..60.0, -60.0f32..60.0, -60.0f32..60.0), 16),
    ) {
        let mut w = loose_world(substeps);
        w.add_obstacle(obstacle(which)).unwrap();
        // particles that start inside are moved above everything
        let mut probe = loose_world(1);
        let (mut x, mut y, mut z) = (vec![], vec![], vec![]);
        for s in &start {
            x.push(s.0); y.push(s.1); z.push(s.2);
        }
        probe.set_positions([&x, &y, &z]).unwrap();
        probe.add_obstacle(obstacle(which)).unwrap();
        for i in 0..16 {
            let mut one = loose_world(1);
            let mut xs = vec![3.0; 16];
            xs[i] = x[i];
            let (mut ys, mut zs) = (vec![3.0; 16], vec![3.0; 16]);
            ys[i] = y[i];
            zs[i] = z[i];
            one.set_positions([&xs, &ys, &zs]).unwrap();
            one.add_obstacle(obstacle(which)).unwrap();
            if one.max_penetration() > 0.0 || which == 0 && y[i] < 0.1 {
                y[i] = 2.0;
            }
        }
        w.set_positions([&x, &y, &z]).unwrap();
        let (vx, vy, vz): (Vec<f32>, Vec<f32>, Vec<f32>) = (vel.iter().map(|v| v.0).collect(), vel.iter().map(|v| v.1).collect(), vel.iter().map(|v| v.2).collect());
        w.set_velocities([&vx, &vy, &vz]).unwrap();
        for _ in 0..3 {
            w.step(1.0 / 60.0).unwrap();
            let d = w.max_penetration();
            let tol = if which >= 3 { CREASE_TOL } else { TOL };
            prop_assert!(d <= tol, "obstacle {} penetration {} m", which, d);
        }
    }
}

/// A case the property test above found (a local run's random seed; CI's fixed seed does not
/// reach it): one particle thrown at ~85 m/s at the dress form, two substeps. The first
/// substep stops it on the form; in the second it starts inside the thickness layer of the
/// face it then crosses, and the response pushed its prediction, 2 mm behind that face but
/// 20 mm behind a neighbouring one, along the first face's normal only: it ended 2.3 mm
/// inside. A mesh contact crossed from inside the layer now returns the particle to its start
/// (`obstacles::mesh::response`).
#[test]
fn fast_particle_sliding_on_the_dress_form_stays_outside() {
    let thrown = (
        3,
        [0.236_155_91, 0.776_302_04, 0.270_187_6],
        [-42.985_718, -50.062_504, -54.631_275],
    );
    thrown_at_the_form_stays_outside(2, &[(2, [0.162_332_79, 0.0, 0.0])], thrown, TOL);
}

/// A second case the property test found: a particle thrown at the dress form comes to rest
/// near the crease of the neck and the shoulder, and the soft constraints to the other
/// particles (which fall from the origin) then drag it ~6 cm a step along the form. The
/// contacts are found once a substep and the solver's projections use their planes only, so
/// the drag across the crease ends 0.14 mm inside the neighbouring face; the next substep
/// puts it out. The test holds the documented bound [`CREASE_TOL`].
#[test]
fn particle_dragged_across_the_neck_crease_stays_outside() {
    let thrown = (6, [0.499_123_07, 1.085_768_6, -0.231_846_42], [-56.157_734, -58.222_22, 29.142_21]);
    thrown_at_the_form_stays_outside(1, &[], thrown, CREASE_TOL);
}

/// The loose world with `substeps` and the dress form, every particle at the origin but
/// those `placed` and the `thrown` one (index, position, velocity): three steps, none ends
/// deeper than `tol` inside.
fn thrown_at_the_form_stays_outside(substeps: u32, placed: &[(usize, [f32; 3])], thrown: (usize, [f32; 3], [f32; 3]), tol: f32) {
    let mut w = loose_world(substeps);
    w.add_obstacle(obstacle(3)).unwrap();
    let (mut p, mut v) = (
        [vec![0.0f32; 16], vec![0.0; 16], vec![0.0; 16]],
        [vec![0.0f32; 16], vec![0.0; 16], vec![0.0; 16]],
    );
    for &(i, at) in placed.iter().chain([&(thrown.0, thrown.1)]) {
        for (c, a) in p.iter_mut().zip(at) {
            c[i] = a;
        }
    }
    for (c, a) in v.iter_mut().zip(thrown.2) {
        c[thrown.0] = a;
    }
    w.set_positions([&p[0], &p[1], &p[2]]).unwrap();
    w.set_velocities([&v[0], &v[1], &v[2]]).unwrap();
    for step in 0..3 {
        w.step(1.0 / 60.0).unwrap();
        let d = w.max_penetration();
        assert!(d <= tol, "step {step}: penetration {d} m");
    }
}

fn drape(obstacle: Obstacle, rows: u32, spacing: f32, origin: [f32; 3], steps: usize) -> World {
    let desc = ClothDesc {
        rows,
        cols: rows,
        spacing,
        origin,
        u: [1.0, 0.0, 0.0],
        v: [0.0, 0.0, 1.0],
        fabric: Fabric::preset("cotton").unwrap(),
        pins: vec![],
        tethers: None,
        ..Default::default()
    };
    let params = SolverParams {
        dt: 1.0 / 60.0,
        substeps: 8,
        iterations: 1,
        ..Default::default()
    };
    let mut w = common::world_with(&desc, params, Effects::gravity());
    w.set_friction(0.6).unwrap();
    w.add_obstacle(obstacle).unwrap();
    w.add_obstacle(Obstacle::shape(Shape::plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]).unwrap()).unwrap())
        .unwrap();
    for _ in 0..steps {
        w.step(1.0 / 60.0).unwrap();
    }
    w
}

fn mean_speed(w: &World) -> f32 {
    let [vx, vy, vz] = w.velocities();
    (0..vx.len())
        .map(|i| (vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i]).sqrt())
        .sum::<f32>()
        / vx.len() as f32
}

#[test]
fn cloth_drapes_over_a_sphere_and_rests() {
    let w = drape(
        Obstacle::shape(Shape::Sphere {
            center: [0.0, 0.5, 0.0],
            radius: 0.25,
        })
        .unwrap(),
        25,
        0.03,
        [-0.36, 0.85, -0.36],
        240,
    );
    let top = w.positions()[1][12 * 25 + 12];
    assert!(top > 0.75 && top < 0.76, "centre of the cloth rests on the sphere: y = {top}");
    assert!(w.max_penetration() < TOL, "penetration {}", w.max_penetration());
    assert!(mean_speed(&w) < 0.02, "still moving: {} m/s", mean_speed(&w));
}

#[test]
fn cloth_drapes_over_the_dress_form_and_rests() {
    let form = Obstacle::mesh(dress_form(2000).unwrap(), BroadphaseKind::Grid(None), false).unwrap();
    let w = drape(form, 30, 0.025, [-0.3625, 0.85, -0.3625], 240);
    let [_, y, _] = w.positions();
    let top = y[15 * 30 + 15];
    assert!(top > 0.79 && top < 0.82, "centre of the cloth rests on the neck: y = {top}");
    assert!(w.max_penetration() < TOL, "penetration {}", w.max_penetration());
    assert!(mean_speed(&w) < 0.05, "still moving: {} m/s", mean_speed(&w));
}

fn busy_world(threads: usize, backend: Backend) -> World {
    let desc = ClothDesc {
        rows: 72,
        cols: 72,
        spacing: 0.012,
        origin: [-0.43, 0.83, -0.43],
        u: [1.0, 0.0, 0.0],
        v: [0.0, 0.0, 1.0],
        fabric: Fabric::preset("cotton").unwrap(),
        ..Default::default()
    };
    let params = SolverParams {
        substeps: 2,
        iterations: 2,
        threads,
        backend,
        ..Default::default()
    };
    let mut w = common::world_with(&desc, params, Effects::gravity());
    w.set_friction(0.4).unwrap();
    w.add_obstacle(Obstacle::mesh(dress_form(1200).unwrap(), BroadphaseKind::Grid(Some([4, 6, 4])), true).unwrap())
        .unwrap();
    w.add_obstacle(
        Obstacle::mesh(dress_form(600).unwrap(), BroadphaseKind::Hash, false)
            .unwrap()
            .with_velocity([0.0, 0.0, 1.0])
            .unwrap(),
    )
    .unwrap();
    w.add_obstacle(
        Obstacle::shape(Shape::Sphere {
            center: [0.2, 0.8, 0.0],
            radius: 0.1,
        })
        .unwrap()
        .with_velocity([0.0, 1.0, 0.0])
        .unwrap(),
    )
    .unwrap();
    w.add_obstacle(
        Obstacle::shape(Shape::plane([0.0, 0.78, 0.0], [0.0, 1.0, 0.2]).unwrap())
            .unwrap()
            .with_friction(0.9)
            .unwrap(),
    )
    .unwrap();
    w.add_obstacle(
        Obstacle::shape(Shape::Capsule {
            a: [-0.3, 0.8, 0.0],
            b: [0.3, 0.8, 0.1],
            radius: 0.03,
        })
        .unwrap(),
    )
    .unwrap();
    w
}

#[test]
fn obstacles_one_two_threads_and_scalar_backend_bitwise_equal() {
    let run = |threads, backend| {
        let mut w = busy_world(threads, backend);
        for _ in 0..6 {
            w.step(1.0 / 60.0).unwrap();
        }
        common::state_bits(&w)
    };
    let one = run(1, Backend::Simd);
    assert_eq!(one, run(2, Backend::Simd));
    assert_eq!(one, run(1, Backend::Scalar));
}

#[test]
fn add_obstacle_rejects_bad_input() {
    let mut w = World::new(SolverParams::default(), Effects::gravity()).unwrap();
    assert!(Obstacle::shape(Shape::Sphere {
        center: [f32::NAN, 0.0, 0.0],
        radius: 1.0
    })
    .is_err());
    assert!(w
        .add_obstacle(
            Obstacle::shape(Shape::Sphere {
                center: [0.0; 3],
                radius: 0.0
            })
            .unwrap_or_else(|_| Obstacle::shape(Shape::Sphere {
                center: [0.0; 3],
                radius: 1.0
            })
            .unwrap())
        )
        .is_ok());
    assert!(Obstacle::shape(Shape::Sphere {
        center: [0.0; 3],
        radius: 1.0
    })
    .unwrap()
    .with_velocity([f32::INFINITY, 0.0, 0.0])
    .is_err());
    assert!(Obstacle::shape(Shape::Sphere {
        center: [0.0; 3],
        radius: 1.0
    })
    .unwrap()
    .with_friction(-1.0)
    .is_err());
    assert!(w.set_friction(f32::NAN).is_err());
    assert!(Obstacle::mesh(dress_form(400).unwrap(), BroadphaseKind::Grid(Some([0, 1, 1])), false).is_err());
    // an obstacle with no cloth: stepping is fine
    w.step(1.0 / 60.0).unwrap();
    assert_eq!(w.obstacles().len(), 1);
}

#[test]
fn moving_obstacles_push_particles_without_penetration() {
    let desc = ClothDesc {
        rows: 1,
        cols: 8,
        spacing: 0.05,
        origin: [0.0, 0.3, 0.0],
        shear: false,
        bend: false,
        tethers: None,
        pins: vec![],
        fabric: Fabric::preset("cotton").unwrap(),
        ..Default::default()
    };
    let params = SolverParams {
        substeps: 2,
        iterations: 1,
        threads: 1,
        ..Default::default()
    };
    let mut w = common::world_with(&desc, params, Effects::default());
    // a ball sweeping along the row at 6 m/s and a dress form crossing it at 3 m/s, meeting particles at rest
    w.add_obstacle(
        Obstacle::shape(Shape::Sphere {
            center: [-0.3, 0.35, 0.0],
            radius: 0.1,
        })
        .unwrap()
        .with_velocity([6.0, 0.0, 0.0])
        .unwrap(),
    )
    .unwrap();
    let mut form = dress_form(400).unwrap();
    form.translate([0.0, 0.0, 0.5]).unwrap();
    w.add_obstacle(
        Obstacle::mesh(form, BroadphaseKind::Bvh, false)
            .unwrap()
            .with_velocity([0.0, 0.0, -3.0])
            .unwrap(),
    )
    .unwrap();
    let mut pushed = false;
    for _ in 0..20 {
        w.step(1.0 / 60.0).unwrap();
        assert!(
            w.max_penetration() <= TOL,
            "penetration {} at t = {}",
            w.max_penetration(),
            w.time()
        );
        pushed |= w.positions()[1].iter().any(|&y| (y - 0.3).abs() > 0.01) || w.positions()[2].iter().any(|&z| z.abs() > 0.01);
    }
    assert!(pushed, "the moving obstacles moved no particle");
}

/// Strands collide with the scene's obstacles too: hair long enough to reach the floor lies on a
/// plane instead of passing through it, standing off by half its diameter.
#[test]
fn strands_rest_on_an_obstacle_without_passing_through() {
    use weft::strands::hair::StrandsDesc;
    use weft::strands::scalp::Scalp;
    let mut w = World::new(
        SolverParams {
            substeps: 8,
            ..Default::default()
        },
        Effects::gravity(),
    )
    .unwrap();
    let desc = StrandsDesc {
        scalp: Scalp::sphere([0.0, 0.25, 0.0], 0.1),
        count: 40,
        points: 16,
        segment_length: 0.03,
        ..StrandsDesc::default()
    };
    let thickness = desc.thickness;
    w.add_strands(&desc).unwrap();
    w.add_obstacle(Obstacle::shape(Shape::plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]).unwrap()).unwrap())
        .unwrap();
    let mut lowest = f32::MAX;
    for _ in 0..180 {
        w.step(1.0 / 60.0).unwrap();
        let y = w.positions()[1];
        for &v in y {
            lowest = lowest.min(v);
        }
    }
    assert!(lowest >= 0.5 * thickness - 1e-4, "a strand point went to y = {lowest}");
    // Some strands do reach the floor (the test is not vacuous).
    let on_floor = w.positions()[1].iter().filter(|&&v| v < 0.5 * thickness + 2e-3).count();
    assert!(on_floor > 0, "no strand reached the floor");
}
