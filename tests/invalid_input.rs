//! Invalid parameters are typed errors that name the parameter, never panics.

use weft::{ClothDesc, Effects, Fabric, SolverParams, WeftError, World};

fn err_text(r: weft::Result<impl std::fmt::Debug>) -> String {
    match r {
        Ok(v) => panic!("expected an error, got {v:?}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn nan_and_out_of_range_solver_parameters() {
    for (params, key) in [
        (
            SolverParams {
                dt: f32::NAN,
                ..Default::default()
            },
            "solver.dt",
        ),
        (
            SolverParams {
                dt: 0.0,
                ..Default::default()
            },
            "solver.dt",
        ),
        (
            SolverParams {
                dt: -1.0,
                ..Default::default()
            },
            "solver.dt",
        ),
        (
            SolverParams {
                substeps: 0,
                ..Default::default()
            },
            "solver.substeps",
        ),
        (
            SolverParams {
                iterations: 0,
                ..Default::default()
            },
            "solver.iterations",
        ),
    ] {
        let e = err_text(World::new(params, Effects::default()).map(|_| ()));
        assert!(e.contains(key), "{e}");
    }
}

#[test]
fn bad_cloths() {
    let mut w = World::new(SolverParams::default(), Effects::default()).unwrap();
    let cases = [
        (
            ClothDesc {
                fabric: Fabric {
                    mass: -1.0,
                    ..Fabric::default()
                },
                ..Default::default()
            },
            "fabric.mass",
        ),
        (
            ClothDesc {
                fabric: Fabric {
                    mass: f32::INFINITY,
                    ..Fabric::default()
                },
                ..Default::default()
            },
            "fabric.mass",
        ),
        (
            ClothDesc {
                spacing: 0.0,
                ..Default::default()
            },
            "spacing",
        ),
        (
            ClothDesc {
                origin: [0.0, f32::NAN, 0.0],
                ..Default::default()
            },
            "origin",
        ),
        (
            ClothDesc {
                rows: 0,
                ..Default::default()
            },
            "rows x cols",
        ),
    ];
    for (desc, key) in cases {
        let e = err_text(w.add_cloth(&desc));
        assert!(e.contains(key), "{e}");
    }
    assert_eq!(w.particle_count(), 0, "failed adds leave the world unchanged");
}

#[test]
fn bad_steps_and_buffers() {
    let mut w = World::new(SolverParams::default(), Effects::gravity()).unwrap();
    w.add_cloth(&ClothDesc::default()).unwrap();
    assert!(err_text(w.step(0.0)).contains("dt"));
    assert!(err_text(w.step(f32::NAN)).contains("dt"));
    let short = vec![0.0f32; 3];
    let e = w.set_velocities([&short, &short, &short]).unwrap_err();
    assert!(matches!(e, WeftError::BufferLength { .. }), "{e}");
    assert!(matches!(w.position(1_000_000), Err(WeftError::IndexOutOfRange { .. })));
    let n = w.particle_count();
    let nan = vec![f32::NAN; n];
    assert!(w.set_velocities([&nan, &nan, &nan]).is_err());
}

#[test]
fn divergence_is_caught_and_the_state_kept() {
    // A huge velocity on a stiff cloth with a giant step overflows f32: the guard must catch it.
    let mut w = World::new(SolverParams::default(), Effects::default()).unwrap();
    w.add_cloth(&ClothDesc {
        rows: 4,
        cols: 4,
        pins: vec![],
        ..Default::default()
    })
    .unwrap();
    let n = w.particle_count();
    let big = vec![3e38f32; n];
    w.set_velocities([&big, &big, &big]).unwrap();
    let before: Vec<f32> = w.positions()[0].to_vec();
    let r = w.step(1e3);
    match r {
        Err(WeftError::Diverged { .. }) => assert_eq!(w.positions()[0], &before[..]),
        other => panic!("expected divergence, got {other:?}"),
    }
}
