//! Tests of the kept candidate lists (`face_cache.rs`).

use super::*;
use crate::obstacles::mesh::broadphase::BruteForce;
use crate::obstacles::mesh::contact::step_contact;
use crate::obstacles::mesh::dressform::dress_form;

#[test]
fn cached_contacts_equal_the_uncached_search_along_random_walks() {
    let m = dress_form(1200).unwrap();
    let bp = BruteForce::new(&m);
    let (lo, hi) = m.bounds();
    let mut rng = crate::test_rng::unit(7);
    let mut scratch = Vec::new();
    let (mut hits, mut kept) = (0, 0);
    for _ in 0..60 {
        let mut c = CacheBlock::default();
        let mut x = [0, 1, 2].map(|k| lo[k] + (hi[k] - lo[k]) * rng());
        for _ in 0..80 {
            let d = [0; 3].map(|_| (rng() - 0.5) * 0.006);
            let p = [0, 1, 2].map(|k| x[k] + d[k]);
            let before = c.faces(0).len();
            let got = c.step_contact(0, &m, &bp, x, p, 0.004, true, &mut scratch);
            let want = step_contact(&m, &bp, x, p, 0.004, &mut Vec::new());
            assert_eq!(got, want, "x {x:?} p {p:?}");
            hits += got.is_some() as usize;
            kept += (before == c.faces(0).len()) as usize;
            x = p;
        }
    }
    assert!(hits > 100, "the walks must meet the surface: {hits}");
    assert!(kept > 1000, "the lists must be reused: {kept}");
}

#[test]
fn sync_empties_on_a_new_stamp_and_nan_gives_the_uncached_answer() {
    let m = dress_form(600).unwrap();
    let bp = BruteForce::new(&m);
    let mut cache = FaceCache::default();
    cache.sync(2, m.stamp());
    let e = &mut cache.blocks_mut()[0];
    let top = [0.0, crate::obstacles::mesh::dressform::HEIGHT + 0.001, 0.0];
    e.step_contact(0, &m, &bp, top, top, 0.004, true, &mut Vec::new());
    assert!(!e.faces(0).is_empty());
    cache.sync(2, m.stamp());
    assert!(!cache.blocks_mut()[0].faces(0).is_empty());
    cache.sync(2, m.stamp() + 1);
    assert!(cache.blocks_mut()[0].faces(0).is_empty());
    let e = &mut cache.blocks_mut()[0];
    for (x, p) in [([f32::NAN; 3], top), (top, [f32::NAN; 3]), (top, top)] {
        let got = e.step_contact(1, &m, &bp, x, p, 0.004, true, &mut Vec::new());
        assert_eq!(got, step_contact(&m, &bp, x, p, 0.004, &mut Vec::new()));
    }
}

/// A cloth draped on a form gives bitwise the same run with the kept lists (and the
/// particles skipped as far from the mesh, `mesh_pass.rs`) as with a fresh broadphase search for every particle every
/// substep (on one thread against two), for every broadphase, with and without face
/// memory.
#[test]
fn a_draping_world_runs_bitwise_alike_with_and_without_the_cache() {
    use crate::obstacles::{BroadphaseKind, Obstacle};
    use crate::SolverParams;
    let run = |kind, memory, fresh| {
        let params = SolverParams {
            dt: 1.0 / 400.0,
            substeps: 2,
            iterations: 1,
            // the reference runs on one thread, the fast path on two
            threads: if fresh { 1 } else { 2 },
            ..SolverParams::default()
        };
        // wider than the form: blocks at the row ends lie outside the mesh box
        let mut w = sheet_over_form(params, [24, 48], 0.012, [-0.282, -0.138]);
        w.add_obstacle(Obstacle::mesh(dress_form(600).unwrap(), kind, memory).unwrap())
            .unwrap();
        w.obstacles.set_fresh_search(fresh);
        let mut touched = 0;
        for _ in 0..120 {
            w.step(1.0 / 400.0).unwrap();
            touched = touched.max(w.obstacle_contacts());
        }
        let mut pos = Vec::new();
        w.positions_interleaved(&mut pos);
        (pos, touched)
    };
    for kind in [BroadphaseKind::Grid(Some([5, 9, 5])), BroadphaseKind::Bvh, BroadphaseKind::Hash] {
        for memory in [false, true] {
            let (kept, touched) = run(kind, memory, false);
            assert!(touched > 50, "the cloth must land on the form: {touched}");
            let (fresh, _) = run(kind, memory, true);
            assert!(
                kept.iter().zip(&fresh).all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits)),
                "{kind:?} memory {memory}"
            );
        }
    }
}

/// A horizontal cotton sheet of `rows x cols` released 5 mm above the dress form's top,
/// its corner at `(x, z)`, friction 0.3; the caller adds the form.
fn sheet_over_form(params: crate::SolverParams, [rows, cols]: [u32; 2], spacing: f32, [x, z]: [f32; 2]) -> crate::World {
    use crate::{ClothDesc, Effects, Fabric, World};
    let mut w = World::new(params, Effects::gravity()).unwrap();
    w.add_cloth(&ClothDesc {
        rows,
        cols,
        spacing,
        origin: [x, crate::obstacles::mesh::dressform::HEIGHT + 0.005, z],
        u: [1.0, 0.0, 0.0],
        v: [0.0, 0.0, 1.0],
        fabric: Fabric::preset("cotton").unwrap(),
        ..ClothDesc::default()
    })
    .unwrap();
    w.set_friction(0.3).unwrap();
    w
}

/// `weft reproduce landovsky` counts one step of `h` with one substep as one iteration
/// and says the physics is bit for bit that of steps of `4 h` with four substeps: the
/// obstacle stages (and their kept lists) see the same substeps either way.
#[test]
fn steps_of_one_substep_equal_a_quarter_of_steps_of_four() {
    use crate::obstacles::{BroadphaseKind, Obstacle};
    use crate::SolverParams;
    let run = |dt: f32, substeps: u32, steps: usize| {
        let params = SolverParams {
            dt,
            substeps,
            iterations: 1,
            ..SolverParams::default()
        };
        let mut w = sheet_over_form(params, [40, 30], 0.009, [-0.13, -0.18]);
        let form = Obstacle::mesh(dress_form(4800).unwrap(), BroadphaseKind::Grid(Some([15, 30, 15])), false);
        w.add_obstacle(form.unwrap()).unwrap();
        for _ in 0..steps {
            w.step(dt).unwrap();
        }
        let mut pos = Vec::new();
        w.positions_interleaved(&mut pos);
        (pos, w.obstacle_contacts())
    };
    let (four, touched) = run(1.0 / 200.0, 4, 40);
    let (one, touched_one) = run(1.0 / 800.0, 1, 160);
    assert!(touched > 20, "the sheet must land on the form: {touched}");
    assert_eq!(touched, touched_one);
    assert!(four.iter().zip(&one).all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits)));
}
