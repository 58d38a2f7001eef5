//! Tests of the broadphase trait (`broadphase.rs`).

use super::*;
use crate::test_rng::signed;

/// Through the trait, the hash and the tree list the same pairs as a brute force: each pair
/// once, within its own reach (travels given) or the search radius (none), rest neighbours
/// dropped; serial with and without lanes, and parallel. Two crumpled layers of two
/// cloths, so every rule decides some pairs; a few fast particles fall outside the hash
/// cells' members.
#[test]
fn hash_and_tree_answer_a_query_alike() {
    let (side, h) = (14usize, 0.01f32);
    let mut r = signed(31);
    let (mut x, mut rest): ([Vec<f32>; 3], [Vec<f32>; 3]) = Default::default();
    let mut cloth_of = Vec::new();
    for c in 0..2u32 {
        for k in 0..side * side {
            let (a, b) = ((k % side) as f32 * h, (k / side) as f32 * h);
            let p = [a + 0.3 * h * r(), 0.6 * h * c as f32 + 0.4 * h * r(), b + 0.3 * h * r()];
            for ((xs, rs), (v, w)) in x.iter_mut().zip(&mut rest).zip(p.into_iter().zip([a, 0.0, b])) {
                xs.push(v);
                rs.push(w);
            }
            cloth_of.push(c);
        }
    }
    let n = cloth_of.len();
    let xs = [&x[0][..], &x[1][..], &x[2][..]];
    let rest = RestData {
        pos: [&rest[0][..], &rest[1][..], &rest[2][..]],
        cloth_of: &cloth_of,
    };
    let (d, skip) = (h, 2.5 * h);
    let travel: Vec<f32> = (0..n).map(|i| if i % 37 == 0 { 1.0 } else { 0.25 + 0.25 * r().abs() }).collect();
    let members = 0.5;
    for own in [true, false] {
        let reach = if own { d + (members + members) * d } else { 2.0 * d };
        let mut want = Neighbours::new();
        want.fill_brute_force(xs[0], xs[1], xs[2], n, d + 2.0 * d).unwrap();
        want.retain(|i, j| {
            let j = j as usize;
            let r2 = if own { pair_reach2(d, travel[i], travel[j]) } else { reach * reach };
            j > i && within(xs[0][i], xs[1][i], xs[2][i], xs[0][j], xs[1][j], xs[2][j], r2) && !rest.skipped(i, j, skip)
        });
        assert!(want.total() > 50, "{}", want.total());
        let q = PairQuery {
            x: xs,
            n,
            d,
            reach,
            travel: own.then_some(&travel[..]),
            members,
            rest,
            skip,
        };
        for exec in [Exec::Scalar, Exec::Simd, Exec::Parallel] {
            let (mut hash, mut tree) = (SpatialHash::new(n), Tree::default());
            for bp in [&mut hash as &mut dyn Broadphase, &mut tree] {
                let mut got = Neighbours::new();
                bp.build(xs, n, reach, rest, exec).unwrap();
                bp.pairs(&q, &mut got, exec).unwrap();
                assert_eq!(got, want, "{exec:?}, travels {own}");
            }
        }
    }
}
