//! The plane's and the sphere's lane kernels: the pre-tests that skip far blocks never reject
//! a contact and do reject far blocks; the sphere's lane contacts equal the scalar ones in
//! every case.

use super::*;

/// A point at distance `r + off` from `center` in direction `dir` (normalised).
fn around(center: [f32; 3], dir: (f32, f32, f32), r: f32, off: f32) -> [f32; 3] {
    let l = (dir.0 * dir.0 + dir.1 * dir.1 + dir.2 * dir.2).sqrt().max(1e-3);
    let d = [dir.0 / l, dir.1 / l, dir.2 / l];
    [0, 1, 2].map(|k| center[k] + d[k] * (r + off))
}

/// The pre-test of block `b` for `shape` (asserting that the lanes and the scalar twin agree)
/// and whether the full test, in lanes and in the twin, finds a contact in the block.
fn pretest_and_contacts(shape: &Shape, g: &GenInput, b: usize) -> (bool, [bool; 2]) {
    let may = shape_may_touch_simd(shape, g, b);
    assert_eq!(may, shape_may_touch_scalar(shape, g, b), "block {b}: lanes and twin disagree");
    let (mut a, mut c) = (vec![7.0; SLOT_BLOCK], vec![7.0; SLOT_BLOCK]);
    shape_block_simd(shape, g, b, &mut a);
    shape_block_scalar(shape, g, b, &mut c);
    (may, [block_nonzero(&a), block_nonzero(&c)])
}

proptest! {
    /// The sphere pre-test: SIMD equals scalar, and a block it rejects gets no contact from
    /// the full test (SIMD or scalar), for paths that start and end right around the sphere's
    /// proximity and thickness shells, moving in and out, fast and slow, shifted or not.
    #[test]
    fn sphere_pretest_never_rejects_a_contact(
        lanes in proptest::collection::vec(((-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0), -0.05f32..0.08, (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0), -0.05f32..0.08, 0.0f32..0.02, 0.0f32..0.02), 24),
        r in 0.2f32..1.0,
        shift in (-0.01f32..0.01, -0.01f32..0.01, -0.01f32..0.01),
    ) {
        let center = [0.1, 0.4, -0.2];
        let len = 4 * LANES;
        let mut v: [Vec<f32>; 9] = std::array::from_fn(|_| vec![0.0; len]);
        for (i, &(dx, ox, dp, op, th, extra)) in lanes.iter().enumerate() {
            let (x, p) = (around(center, dx, r, ox), around(center, dp, r, op));
            for k in 0..3 {
                v[k][i] = x[k];
                v[3 + k][i] = p[k];
            }
            v[6][i] = 1.0;
            v[7][i] = th;
            v[8][i] = th + extra;
        }
        let g = input_reach(&v, 8, lanes.len(), [shift.0, shift.1, shift.2]);
        let sphere = Shape::Sphere { center, radius: r };
        for b in 0..len / LANES {
            let (may, touched) = pretest_and_contacts(&sphere, &g, b);
            prop_assert!(may || touched == [false; 2], "block {} rejected but touched {:?}", b, touched);
        }
    }

    /// The plane pre-test: SIMD equals scalar, a block it rejects gets no contact from the full
    /// test (SIMD or scalar), and it keeps exactly the blocks with a lane below the reach, for
    /// predictions spread on both sides of a tilted plane, some exactly at the reach.
    #[test]
    fn plane_pretest_keeps_exactly_the_blocks_in_reach(
        lanes in proptest::collection::vec((-0.05f32..0.3, -1.0f32..1.0, -1.0f32..1.0, 0.0f32..0.02, any::<bool>()), 32),
    ) {
        let (point, normal) = ([0.2f32, -0.1, 0.3], [0.6f32, 0.8, 0.0]);
        let len = 4 * LANES;
        let mut v: [Vec<f32>; 9] = std::array::from_fn(|_| vec![0.0; len]);
        for (i, &(h, a, b, reach, at_reach)) in lanes.iter().enumerate() {
            // height `h` (or the reach itself) above the plane, moved along it by `a, b`
            let h = if at_reach { reach } else { h };
            let p = [point[0] + 0.8 * a + h * normal[0], point[1] - 0.6 * a + h * normal[1], point[2] + b];
            for k in 0..3 {
                v[k][i] = p[k];
                v[3 + k][i] = p[k];
            }
            v[6][i] = 1.0;
            v[7][i] = reach;
            v[8][i] = reach;
        }
        let g = input_reach(&v, 8, lanes.len(), [0.0; 3]);
        let plane = Shape::plane(point, normal).expect("a unit normal");
        for b in 0..len / LANES {
            let (may, touched) = pretest_and_contacts(&plane, &g, b);
            prop_assert_eq!(touched, [may; 2], "block {}", b);
        }
    }
}

/// The plane pre-test rejects a block far above the plane and keeps one within reach.
#[test]
fn plane_pretest_rejects_far_blocks_only() {
    let len = 2 * LANES;
    let mut v: [Vec<f32>; 9] = std::array::from_fn(|_| vec![0.0; len]);
    // block 0 rests 1 mm above the floor (reach 5 mm), block 1 is 0.5 m above it
    let y = |i: usize| if i < LANES { 0.001 } else { 0.5 };
    for (k, fill) in [(1, None), (4, None), (6, Some(1.0)), (7, Some(0.002)), (8, Some(0.005))] {
        v[k] = (0..len).map(|i| fill.unwrap_or_else(|| y(i))).collect();
    }
    let g = input_reach(&v, 8, len, [0.0; 3]);
    let floor = Shape::plane([0.0; 3], [0.0, 1.0, 0.0]).expect("a unit normal");
    assert!(shape_may_touch_simd(&floor, &g, 0) && shape_may_touch_scalar(&floor, &g, 0));
    assert!(!shape_may_touch_simd(&floor, &g, 1) && !shape_may_touch_scalar(&floor, &g, 1));
}

/// The pre-test rejects far blocks and keeps near ones (it is not vacuous), and the padding
/// block of a cloth far from the sphere is rejected too.
#[test]
#[allow(clippy::needless_range_loop)] // `i` indexes nine arrays alike
fn sphere_pretest_rejects_far_blocks_only() {
    let len = 2 * LANES;
    let mut v: [Vec<f32>; 9] = std::array::from_fn(|_| vec![0.0; len]);
    for i in 0..len {
        // block 0 rests 1 mm above the unit sphere's top, block 1 is 0.5 m above it
        let y = if i < LANES { 1.001 } else { 1.5 };
        v[1][i] = y;
        v[4][i] = y - 1e-4;
        v[6][i] = 1.0;
        v[7][i] = 0.002;
        v[8][i] = 0.005;
        v[0][i] = 1e-3 * i as f32;
        v[3][i] = 1e-3 * i as f32;
    }
    let g = input_reach(&v, 8, len, [0.0; 3]);
    let sphere = Shape::Sphere {
        center: [0.0; 3],
        radius: 1.0,
    };
    assert!(shape_may_touch_simd(&sphere, &g, 0) && shape_may_touch_scalar(&sphere, &g, 0));
    assert!(!shape_may_touch_simd(&sphere, &g, 1) && !shape_may_touch_scalar(&sphere, &g, 1));
    let mut out = vec![0.0; SLOT_BLOCK];
    shape_block_simd(&sphere, &g, 0, &mut out);
    assert!(normals_set(&out), "the near block touches");
}

/// The sphere's SIMD contacts equal the scalar ones in every case the test tells apart, in one
/// block: in proximity, predicted exactly at the centre (normal from the start, or `up` when
/// the start is at the centre too), a path crossing the ball, a miss, and a pinned particle.
#[test]
fn sphere_lanes_equal_scalar_in_every_case() {
    let c = [0.25f32, -0.5, 1.0];
    let at = |d: [f32; 3]| [c[0] + d[0], c[1] + d[1], c[2] + d[2]];
    // (start, prediction) per lane
    let paths = [
        (at([0.0, 1.3, 0.0]), at([0.01, 1.002, 0.0])), // proximity
        (at([0.3, 0.4, 0.1]), c),                      // at the centre, normal from the start
        (c, c),                                        // at the centre, start there too: up
        (at([-1.5, 0.2, 0.0]), at([1.5, 0.25, 0.0])),  // crosses the ball
        (at([0.0, 2.0, 0.0]), at([0.0, 1.9, 0.0])),    // a miss
        (at([0.0, 1.2, 0.0]), at([0.0, -1.2, 0.0])),   // straight through the centre
        (at([0.9, 0.0, 0.0]), at([0.99, 0.0, 0.0])),   // inside, near the surface
        (at([0.0, 1.001, 0.0]), at([0.0, 1.0, 0.0])),  // pinned below
    ];
    let mut v: [Vec<f32>; 8] = std::array::from_fn(|_| vec![0.0; LANES]);
    for (i, (x, p)) in paths.iter().enumerate() {
        for k in 0..3 {
            v[k][i] = x[k];
            v[3 + k][i] = p[k];
        }
        v[6][i] = if i == 7 { 0.0 } else { 1.0 };
        v[7][i] = 0.005;
    }
    let g = input(&v, LANES, [0.0; 3]);
    let sphere = Shape::Sphere { center: c, radius: 1.0 };
    let (mut a, mut s) = (vec![7.0; SLOT_BLOCK], vec![7.0; SLOT_BLOCK]);
    shape_block_simd(&sphere, &g, 0, &mut a);
    shape_block_scalar(&sphere, &g, 0, &mut s);
    let bits = |o: &[f32]| o.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a), bits(&s));
    let normal = |l: usize| [3, 4, 5].map(|k| s[k * LANES + l]);
    for l in [0, 1, 2, 3, 5, 6] {
        assert_ne!(normal(l), [0.0; 3], "lane {l} touches");
    }
    assert_eq!(normal(2), [0.0, 1.0, 0.0], "start and prediction at the centre: up");
    assert_eq!(normal(4), [0.0; 3], "the miss");
    assert_eq!(normal(7), [0.0; 3], "pinned");
}

/// A short path grazing the ball: it starts and ends outside the proximity shell (reach equal
/// to the thickness) and dips just inside the thickness shell between. The full test finds the
/// crossing, and the pre-test keeps the block: its bound `|p - c| <= R + |p - x|` is nearly
/// tight here, where a bound a tenth smaller would reject the block.
#[test]
fn sphere_pretest_keeps_a_short_grazing_crossing() {
    let (r, th, y) = (0.5f32, 0.01f32, 0.50995f32);
    // every lane along +x at height y: |x| = |p| = 0.510048 > r + th, the closest point
    // 0.50995 < r + th
    let value = [-0.01, y, 0.0, 0.01, y, 0.0, 1.0, th];
    let v: [Vec<f32>; 8] = std::array::from_fn(|k| vec![value[k]; LANES]);
    let g = input_reach(&v, 7, LANES, [0.0; 3]);
    let sphere = Shape::Sphere {
        center: [0.0; 3],
        radius: r,
    };
    let (may, touched) = pretest_and_contacts(&sphere, &g, 0);
    assert_eq!(touched, [true; 2], "the path crosses the thickness shell");
    assert!(may, "the pre-test keeps a crossing block");
}
