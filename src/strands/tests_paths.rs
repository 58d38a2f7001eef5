//! Strand tests through scenes and against other paths: scene parsing and errors, checkpoint
//! resume, the f64 reference, a moving scalp.

use super::*;
use crate::scene::Scene;
use crate::{Effects, SolverParams, Wind, World};

const HAIR: &str = r#"
[effects]
gravity = [0.0, -9.81, 0.0]

[[strands]]
count = 50
points = 8
segment_length = 0.01
bend_compliance = 0.001
scalp = { kind = "sphere", center = [0.0, 1.6, 0.0], radius = 0.1, polar_degrees = [0.0, 100.0] }

[[strands]]
count = 20
points = 4
segment_length = 0.02
scalp = { kind = "ellipsoid", center = [0.5, 1.6, 0.0], radii = [0.08, 0.1, 0.09] }
"#;

#[test]
fn strands_scene_parses_and_builds() {
    let s = Scene::parse(HAIR, "hair.toml").unwrap();
    let w = s.world().unwrap();
    assert_eq!(w.strands().len(), 2);
    assert_eq!(w.particle_count(), 50 * 8 + 20 * 4);
    assert_eq!(w.constraint_count(), 50 * (7 + 6) + 20 * (3 + 2));
    assert_eq!(w.strands()[1].scalp.radii, [0.08, 0.1, 0.09]);
    assert_eq!(w.strands()[0].scalp.polar_degrees, [0.0, 100.0]);
    let text = s.to_toml().unwrap();
    assert_eq!(Scene::parse(&text, "back.toml").unwrap(), s);
}

#[test]
fn bad_strand_scenes_are_errors_with_line_and_column() {
    let cases = [
        ("count = 50", "count = 0", "line 6, column 9"),
        ("segment_length = 0.01", "segment_length = -0.01", "line 8, column 18"),
        ("radius = 0.1,", "radius = -0.1,", "line 10, column 63"),
        ("polar_degrees = [0.0, 100.0]", "polar_degrees = [0.0, 200.0]", "line 10, column 84"),
        // Cross-field problems: at the scalp table, or at the strands table.
        ("radius = 0.1,", "radii = [0.1, 0.1, 0.1],", "line 10, column 9"),
        ("points = 8", "points = 1", "line 5, column 1"),
        ("bend_compliance = 0.001", "bend = 0.001", "line 9, column 1"),
        ("kind = \"sphere\"", "kind = \"cube\"", "line 10, column 18"),
    ];
    for (from, to, at) in cases {
        let text = HAIR.replacen(from, to, 1);
        assert_ne!(text, HAIR);
        let e = Scene::parse(&text, "bad.toml").unwrap_err().to_string();
        assert!(e.contains(at), "{to}: {e}");
    }
}

#[test]
fn strand_step_matches_the_f64_reference() {
    // Tolerance: 1e-4 m (0.05% of the 0.2 m head) after 10 steps of draping in steady wind.
    // Measured without wind: 2.8e-6 m after 1 step, 2.6e-5 m after 10, 2.2e-4 m after 20 (the
    // strands slide over the scalp, which amplifies f32 rounding), so the run is kept short.
    const TOL: f64 = 1e-4;
    let effects = Effects {
        wind: Some(Wind {
            velocity: [3.0, 0.0, 0.5],
            ..Wind::default()
        }),
        ..Effects::gravity()
    };
    let params = SolverParams {
        substeps: 8,
        ..Default::default()
    };
    let mut w = super::tests::strand_world(60, 10, effects, params);
    let mut r = crate::reference::ReferenceWorld::new(&w.describe());
    for _ in 0..10 {
        w.step(1.0 / 60.0).unwrap();
        r.step(1.0 / 60.0);
    }
    let [x, y, z] = w.positions();
    let mut worst = 0.0f64;
    for (i, q) in r.x.iter().enumerate() {
        let d = [x[i] as f64 - q[0], y[i] as f64 - q[1], z[i] as f64 - q[2]];
        worst = worst.max((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
    }
    assert!(worst < TOL, "f32 step is {worst} m from the f64 reference");
    // And the reference's scalp stage and strand drag are not idle: the strands moved.
    let moved = (0..x.len()).any(|i| (r.x[i][0] - w.particles().x[i] as f64).abs() < TOL && r.v[i][0].abs() > 1e-3);
    assert!(moved);
}

#[test]
fn strand_scene_resumes_bitwise_from_a_checkpoint() {
    // TOML allows the sub-table before its parent.
    let text = HAIR.replacen(
        "[effects]\n",
        "[effects.wind]\nvelocity = [2.0, 0.0, 0.0]\ngust = 0.3\n\n[effects]\n",
        1,
    );
    let scene = Scene::parse(&text, "s").unwrap();
    let mut a = scene.world().unwrap();
    for _ in 0..30 {
        a.step(1.0 / 60.0).unwrap();
    }
    let mut b = scene.world().unwrap();
    for _ in 0..12 {
        b.step(1.0 / 60.0).unwrap();
    }
    let c = crate::world::checkpoint::Checkpoint::from_bytes(&b.checkpoint(&text).to_bytes()).unwrap();
    let mut r = Scene::parse(&c.scene, "s").unwrap().world().unwrap();
    r.restore(&c).unwrap();
    for _ in 12..30 {
        r.step(1.0 / 60.0).unwrap();
    }
    assert_eq!(a.checkpoint(&text), r.checkpoint(&text));
}

#[test]
fn moving_the_scalp_carries_the_roots_and_the_strands_follow() {
    let mut w = World::new(SolverParams::default(), Effects::gravity()).unwrap();
    w.add_strands(&StrandsDesc {
        count: 40,
        points: 8,
        ..Default::default()
    })
    .unwrap();
    let info = w.strands()[0].clone();
    let before: Vec<f32> = (0..info.count).map(|s| w.positions()[0][info.strand_range(s).end - 1]).collect();
    let root0 = w.positions()[0][0];
    // Slide the head 5 cm along +x over 30 steps.
    for k in 1..=30 {
        let c = info.scalp.center;
        w.set_scalp_center(0, [c[0] + 0.05 * k as f32 / 30.0, c[1], c[2]]).unwrap();
        w.step(1.0 / 60.0).unwrap();
    }
    assert!((w.positions()[0][0] - root0 - 0.05).abs() < 1e-5, "root moved with the scalp");
    let after: Vec<f32> = (0..info.count).map(|s| w.positions()[0][info.strand_range(s).end - 1]).collect();
    let mean = (0..before.len()).map(|i| after[i] - before[i]).sum::<f32>() / before.len() as f32;
    assert!(mean > 0.02, "tips followed by {mean} m");
    // The collision shape moved too: no free point inside the moved scalp.
    let moved = w.strands()[0].scalp;
    let [x, y, z] = w.positions();
    assert!((0..w.particle_count()).all(|i| moved.scaled_distance([x[i], y[i], z[i]]) >= 1.0 - 1e-5));
    assert!(w.set_scalp_center(1, [0.0; 3]).is_err());
    assert!(w.set_scalp_center(0, [f32::NAN, 0.0, 0.0]).is_err());
}
