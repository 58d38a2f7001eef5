//! Whole runs of the fold world of `weft reproduce vccpbd` with self-collision: the hash and the
//! tree give the same lists and bits, the derived box centres equal the kept copy, and the
//! pass in parallel chunks gives the same bits on any thread count.

use super::*;

/// The cloth of `weft reproduce vccpbd` at `size x size`: hung over its middle row, both
/// halves fall and fold face to face.
fn hung(size: u32, response: Response, broadphase: SelfBroadphase, threads: usize) -> (crate::World, f32) {
    let params = crate::SolverParams {
        substeps: 10,
        iterations: 1,
        threads,
        ..Default::default()
    };
    let sc = SelfCollision {
        response,
        broadphase,
        measure: true,
        ..SelfCollision::default()
    };
    crate::perf::fold_world(size, crate::Fabric::preset("wool").unwrap(), params, sc).unwrap()
}

/// The hash and the AABB tree list the same pairs every step of the fold (each pair once,
/// rest neighbours dropped), and the two runs give the same bits.
#[test]
fn hash_and_tree_give_the_same_lists_and_bits() {
    for response in [Response::Vccpbd, Response::MovementSpeed, Response::Pbd] {
        let (mut hash, dt) = hung(24, response, SelfBroadphase::Hash, 1);
        let (mut tree, _) = hung(24, response, SelfBroadphase::AabbTree, 2);
        let mut contacts = 0;
        for step in 0..100 {
            hash.step(dt).unwrap();
            tree.step(dt).unwrap();
            contacts += hash.selfcol.touched_blocks();
            assert_eq!(
                tree.self_collision_pairs().unwrap(),
                hash.self_collision_pairs().unwrap(),
                "{response:?} step {step}"
            );
            for (a, b) in tree.positions().iter().zip(hash.positions()) {
                assert!(a.iter().zip(b).all(|(u, v)| u.to_bits() == v.to_bits()), "{response:?} step {step}");
            }
        }
        assert!(contacts > 0, "{response:?}: no contact in the run");
        assert_eq!(tree.self_collision_stats().average_pct, hash.self_collision_stats().average_pct);
    }
}

/// VcCPBD's box centres derived from the velocities (`x + h v`, no obstacles) give the bits
/// of the copy the clamp keeps, on 1 and 2 threads, through the fall and the fold.
#[test]
fn derived_box_centres_equal_the_kept_copy() {
    for threads in [1, 2] {
        let (mut copy, dt) = hung(24, Response::Vccpbd, SelfBroadphase::Hash, threads);
        copy.selfcol.copy_centres = true;
        let (mut derive, _) = hung(24, Response::Vccpbd, SelfBroadphase::Hash, threads);
        let mut touched = 0;
        for step in 0..100 {
            copy.step(dt).unwrap();
            derive.step(dt).unwrap();
            touched += derive.selfcol.touched_blocks();
            for (a, b) in derive.positions().iter().zip(copy.positions()) {
                assert!(
                    a.iter().zip(b).all(|(u, v)| u.to_bits() == v.to_bits()),
                    "{threads} threads, step {step}"
                );
            }
        }
        assert!(touched > 0, "no contact corrected");
    }
}

/// The fold at 64 x 64 (its pair list spans several chunks once folded, so the pass runs in
/// parallel): 1 and 2 threads and the scalar backend (serial) give the same bits every step,
/// and count the same pairs and contacts.
#[test]
fn fold_with_parallel_pair_chunks_is_bitwise_on_any_thread_count() {
    let make = |threads: usize, backend: crate::Backend| {
        let params = crate::SolverParams {
            substeps: 10,
            iterations: 1,
            threads,
            backend,
            ..Default::default()
        };
        let sc = SelfCollision {
            response: Response::Vccpbd,
            ..SelfCollision::default()
        };
        crate::perf::fold_world(64, crate::Fabric::preset("basic").unwrap(), params, sc).unwrap()
    };
    let (mut one, dt) = make(1, crate::Backend::Simd);
    let mut others = [make(2, crate::Backend::Simd).0, make(1, crate::Backend::Scalar).0];
    let mut ranged = 0;
    for step in 0..80 {
        one.step(dt).unwrap();
        ranged += usize::from(one.selfcol.pair_count() > crate::self_collision::pass::PAIR_CHUNK);
        for w in &mut others {
            w.step(dt).unwrap();
            for (a, b) in w.positions().iter().zip(one.positions()) {
                assert!(a.iter().zip(b).all(|(u, v)| u.to_bits() == v.to_bits()), "step {step}");
            }
        }
    }
    assert!(ranged > 4, "the pair list spanned several chunks in {ranged} steps");
    // The lists' and the contacts' means count the same pairs whichever path the pass took.
    let st = one.self_collision_stats();
    assert!(
        st.contacts_per_substep > 0.0 && st.contacts_per_substep < st.pairs_per_step,
        "{st:?}"
    );
    for w in &others {
        let o = w.self_collision_stats();
        assert_eq!(
            (o.pairs_per_step, o.contacts_per_substep),
            (st.pairs_per_step, st.contacts_per_substep)
        );
    }
}
