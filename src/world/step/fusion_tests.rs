//! The update pass that also runs the next substep's predict, and the obstacle stages run
//! chunk by chunk inside the predict and update passes, give the same bits as separate passes.

use crate::model::params::Backend;
use crate::model::shapes::Shape;
use crate::obstacles::Obstacle;
use crate::{ClothDesc, Effects, Fabric, SolverParams, World};

/// A 90 x 90 damped cloth (8100 particles: two chunks) falling onto a sphere, with gravity and
/// drag, 4 substeps of `iterations`; with `more`, wind (so each substep predicts in a pass of
/// its own) and a rising plane with friction beside the ball.
fn world_with(threads: usize, backend: Backend, fuse: bool, iterations: u32, more: bool) -> World {
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
        iterations,
        backend,
        ..Default::default()
    };
    let effects = Effects {
        drag: Some(0.01),
        wind: more.then(|| crate::model::effects::Wind {
            velocity: [1.0, 0.0, 0.5],
            ..Default::default()
        }),
        ..Effects::gravity()
    };
    let mut w = World::new(params, effects).unwrap();
    w.add_cloth(&desc).unwrap();
    let ball = Shape::Sphere {
        center: [0.0; 3],
        radius: 0.2,
    };
    w.add_obstacle(Obstacle::shape(ball).unwrap()).unwrap();
    if more {
        let floor = Shape::plane([0.0, 0.1, 0.0], [0.0, 1.0, 0.0]).unwrap();
        let floor = Obstacle::shape(floor).unwrap().with_velocity([0.1, 0.3, 0.0]).unwrap();
        w.add_obstacle(floor.with_friction(0.4).unwrap()).unwrap();
    }
    w.fuse_predict = fuse;
    w
}

/// The next predict inside the update pass, the chunkwise obstacle stages and (one iteration,
/// SIMD) the wave, against separate passes.
#[test]
fn fused_passes_equal_separate_passes_bitwise() {
    for (threads, backend) in [(1, Backend::Simd), (2, Backend::Simd), (1, Backend::Scalar)] {
        for (iterations, more) in [(1, false), (1, true), (2, false), (3, true)] {
            let mut fused = world_with(threads, backend, true, iterations, more);
            let mut split = world_with(threads, backend, false, iterations, more);
            assert!(fused.obstacles.runs_chunkwise());
            for step in 0..12 {
                fused.step(1.0 / 60.0).unwrap();
                split.step(1.0 / 60.0).unwrap();
                assert_eq!(
                    fused.state_bits(),
                    split.state_bits(),
                    "{threads} thread(s), {backend:?}, {iterations} iterations, more {more}, step {step}"
                );
            }
            assert!(fused.obstacle_contacts() > 100, "the sheet reached the obstacles");
        }
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

/// A damped `rows x cols` cloth hanging from two corners under `effects`, 3 substeps of one
/// sweep: a world that runs the wave (`DistanceSet::solve_wave`).
fn grid_world(rows: u32, cols: u32, threads: usize, effects: &Effects) -> World {
    tethered_grid_world(rows, cols, threads, effects, None)
}

/// [`grid_world`] with tethers of slack `tethers` to the pinned corners.
fn tethered_grid_world(rows: u32, cols: u32, threads: usize, effects: &Effects, tethers: Option<f32>) -> World {
    let desc = ClothDesc {
        rows,
        cols,
        spacing: 0.005,
        pins: vec![crate::PinSpec::FirstRowCorners],
        tethers,
        fabric: Fabric {
            damping: 0.3,
            ..Fabric::preset("cotton").unwrap()
        },
        ..Default::default()
    };
    let params = SolverParams {
        threads,
        substeps: 3,
        iterations: 1,
        ..Default::default()
    };
    let mut w = World::new(params, effects.clone()).unwrap();
    w.add_cloth(&desc).unwrap();
    assert!(w.distance.wave_ready(w.particle_count()), "one grid: the wave runs");
    w
}

/// [`grid_world`]: the wave on 1, 2 and 3 threads against the sweep and update as passes,
/// bit for bit over six steps.
fn wave_equals_passes(rows: u32, cols: u32, effects: &Effects) {
    let make = |threads: usize, fuse: bool| {
        let mut w = grid_world(rows, cols, threads, effects);
        w.fuse_predict = fuse;
        w
    };
    let mut split = make(1, false);
    let mut fused: Vec<World> = [1, 2, 3].into_iter().map(|t| make(t, true)).collect();
    for step in 0..6 {
        split.step(1.0 / 60.0).unwrap();
        for w in &mut fused {
            w.step(1.0 / 60.0).unwrap();
            let t = w.params().threads;
            assert_eq!(w.state_bits(), split.state_bits(), "{rows} x {cols}, {t} thread(s), step {step}");
        }
    }
    assert!(split.metrics().max_strain > 0.0, "the cloth moved");
}

/// 2050 columns: bands of seven rows, whose ends fall inside blocks of eight particles, in
/// four bands (two parts of the wave, so a seam between parts).
#[test]
fn wave_over_unaligned_bands_equals_separate_passes_bitwise() {
    assert_eq!(crate::constraints::grid::band_rows(2050), 7);
    assert!(!crate::constraints::grid_sweep::bands_on_blocks(2050));
    wave_equals_passes(22, 2050, &Effects::gravity());
}

/// 1024 columns: bands of 16 rows start on whole blocks, so the wave predicts each band
/// itself; with wind every substep does, without only the first. With drag.
#[test]
fn wave_predicting_its_bands_equals_separate_passes_bitwise() {
    assert!(crate::constraints::grid_sweep::bands_on_blocks(1024));
    for wind in [false, true] {
        let mut effects = Effects::gravity();
        effects.drag = Some(0.2);
        if wind {
            effects.wind = Some(crate::model::effects::Wind {
                velocity: [1.5, 0.0, 0.5],
                ..Default::default()
            });
        }
        wave_equals_passes(40, 1024, &effects);
    }
}

/// The guard's copy, made band by band when the wave predicts: a step that diverges leaves
/// the state of before the step, bit for bit, on one and two threads.
#[test]
fn wave_predicting_its_bands_keeps_the_guard_copy() {
    for threads in [1, 2] {
        let mut w = grid_world(40, 1024, threads, &Effects::gravity());
        assert!(w.distance.bands_on_blocks());
        w.step(1.0 / 60.0).unwrap();
        let n = w.particle_count();
        let mut vx = vec![0.0f32; n];
        vx[30_000] = 3e38;
        let zero = vec![0.0f32; n];
        w.set_velocities([&vx, &zero, &zero]).unwrap();
        let before = w.state_bits();
        assert!(matches!(w.step(1e3), Err(crate::WeftError::Diverged { .. })), "{threads} threads");
        assert_eq!(w.state_bits(), before, "{threads} threads");
    }
}

/// Tethers run in the wave's update ranges (`Fusion::tethers_in_update`), against the tether
/// sweep as a pass of its own, on 1, 2 and 3 threads, while one pinned corner moves each step
/// (a kinematic anchor: predicted ahead of the wave in the first substep, and in the others
/// replaced by the next substep's prediction in ranges already done while the wave runs):
/// bit for bit over six steps. 160 rows of 50: ten bands in four parts on two threads and
/// three on three, so boundaries between parts run both beside and after one another.
#[test]
fn tethers_in_the_wave_equal_a_tether_pass_bitwise() {
    for drag in [None, Some(0.3)] {
        assert_tethers_in_the_wave_equal_a_pass(drag, false);
    }
}

/// The same with a ball the cloth hangs against: the wave does not predict (the ball's
/// contacts follow the predict), and the ball's projection runs after the tethers.
#[test]
fn tethers_in_the_wave_beside_a_ball_equal_a_tether_pass_bitwise() {
    assert_tethers_in_the_wave_equal_a_pass(None, true);
}

fn assert_tethers_in_the_wave_equal_a_pass(drag: Option<f32>, ball: bool) {
    let effects = Effects {
        drag,
        ..Effects::gravity()
    };
    let make = |threads: usize, fuse: bool| {
        let mut w = tethered_grid_world(160, 50, threads, &effects, Some(0.0));
        if ball {
            // the cloth hangs in the plane z = 0, 5 cm from the centre of a ball of 6 cm
            let s = Shape::Sphere {
                center: [0.125, 0.5, 0.05],
                radius: 0.06,
            };
            w.add_obstacle(Obstacle::shape(s).unwrap()).unwrap();
        }
        w.fuse_predict = fuse;
        w
    };
    let mut split = make(1, false);
    let mut fused: Vec<World> = [1, 2, 3].into_iter().map(|t| make(t, true)).collect();
    let f = fused[1].fusion(false, false, true, true, 8000);
    assert!(f.tethers_in_update && f.wave && f.wave_can_predict != ball);
    let corner = |step: usize| mint::Point3 {
        x: 0.25 + 0.02 * step as f32,
        y: 0.01 * step as f32,
        z: 0.0,
    };
    let mut pulled = 0;
    for step in 0..6 {
        split.set_pin_position(49, corner(step)).unwrap();
        split.step(1.0 / 60.0).unwrap();
        for w in &mut fused {
            w.set_pin_position(49, corner(step)).unwrap();
            w.step(1.0 / 60.0).unwrap();
            let t = w.params().threads;
            assert_eq!(
                w.state_bits(),
                split.state_bits(),
                "{t} thread(s), drag {drag:?}, ball {ball}, step {step}"
            );
        }
        // tethers without slack bind once the cloth falls: count the particles at their limit
        let p = split.positions();
        let tethers = &split.tethers;
        pulled = (0..tethers.len())
            .filter(|&k| {
                let (i, a) = (tethers.particle[k] as usize, tethers.anchor[k] as usize);
                let d: f32 = (0..3).map(|c| (p[c][i] - p[c][a]).powi(2)).sum::<f32>().sqrt();
                d >= tethers.max_len[k] * (1.0 - 1e-5)
            })
            .count();
    }
    assert!(pulled > 100, "{pulled} particles held by their tethers");
    if ball {
        assert!(split.obstacle_contacts() > 10, "the ball touched the cloth");
    }
}

/// An anchor made free after the cloth was built moves in the sweep, so its tethers keep the
/// pass after the sweep: 1, 2 and 3 threads give the bits of the pass.
#[test]
fn a_freed_anchor_keeps_the_tether_pass() {
    let make = |threads: usize| {
        let mut w = tethered_grid_world(160, 50, threads, &Effects::gravity(), Some(0.0));
        let mut inv = w.particles.w[..w.particle_count()].to_vec();
        inv[49] = inv[100];
        w.set_inverse_masses(&inv).unwrap();
        w
    };
    let mut worlds: Vec<World> = [1, 2, 3].into_iter().map(make).collect();
    assert!(!worlds[1].fusion(false, false, true, true, 8000).tethers_in_update);
    let y0 = worlds[0].positions()[1][49];
    for step in 0..6 {
        for w in &mut worlds {
            w.step(1.0 / 60.0).unwrap();
        }
        for w in &worlds[1..] {
            let t = w.params().threads;
            assert_eq!(w.state_bits(), worlds[0].state_bits(), "{t} threads, step {step}");
        }
    }
    let y = worlds[0].positions()[1][49];
    assert!(y < y0 - 0.01, "the freed corner fell: y = {y} from {y0}");
}
