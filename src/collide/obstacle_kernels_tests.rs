use super::*;
use proptest::prelude::*;

fn input<'a>(v: &'a [Vec<f32>; 8], n: usize, shift: [f32; 3]) -> GenInput<'a> {
    GenInput {
        x: [&v[0], &v[1], &v[2]],
        p: [&v[3], &v[4], &v[5]],
        w: &v[6],
        th: &v[7],
        reach: &v[7],
        n,
        shift,
    }
}

fn arrays(seed: &[(f32, f32, f32, f32, f32, f32)], pinned: usize) -> [Vec<f32>; 8] {
    let len = crate::lanes::round_up(seed.len() + 1);
    let mut v: [Vec<f32>; 8] = Default::default();
    for a in v.iter_mut() {
        a.resize(len, 0.0);
    }
    for (i, s) in seed.iter().enumerate() {
        let q = [s.0, s.1, s.2, s.3, s.4, s.5];
        for k in 0..6 {
            v[k][i] = q[k];
        }
        v[6][i] = if i == pinned { 0.0 } else { 1.0 };
        v[7][i] = 0.01 + 0.001 * (i % 5) as f32;
    }
    v
}

proptest! {
    #[test]
    fn simd_generators_equal_scalar(
        seed in proptest::collection::vec((-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0), 1..40),
        pinned in 0usize..40,
        shift in (-0.1f32..0.1, -0.1f32..0.1, -0.1f32..0.1),
        r in 0.1f32..1.5,
    ) {
        let v = arrays(&seed, pinned);
        let g = input(&v, seed.len(), [shift.0, shift.1, shift.2]);
        let shapes = [
            Shape::Sphere { center: [0.1, -0.2, 0.3], radius: r },
            Shape::plane([0.0, -0.5, 0.0], [0.2, 1.0, 0.1]).unwrap(),
            Shape::Sphere { center: [0.0; 3], radius: r },
        ];
        for s in &shapes {
            for b in 0..v[0].len() / LANES {
                let (mut a, mut c) = (vec![7.0; SLOT_BLOCK], vec![7.0; SLOT_BLOCK]);
                shape_block_simd(s, &g, b, &mut a);
                shape_block_scalar(s, &g, b, &mut c);
                prop_assert_eq!(a.iter().map(|f| f.to_bits()).collect::<Vec<_>>(), c.iter().map(|f| f.to_bits()).collect::<Vec<_>>());
            }
        }
    }

    /// The SIMD approach speeds equal the scalar ones bit for bit, with and without contact,
    /// for a moving obstacle too.
    #[test]
    fn simd_approach_equals_scalar(
        slot in proptest::collection::vec(-2.0f32..2.0, 48),
        vel in proptest::collection::vec(-3.0f32..3.0, 24),
        zero_lanes in 0u8..=255,
        u in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
    ) {
        let mut out = vec![0.0; SLOT_BLOCK];
        out[..48].copy_from_slice(&slot);
        for l in 0..LANES {
            if zero_lanes & (1 << l) != 0 {
                for k in 3..6 {
                    out[k * LANES + l] = 0.0;
                }
            }
        }
        let v = [&vel[..8], &vel[8..16], &vel[16..]];
        let u = [u.0, u.1, u.2];
        let (mut a, mut c) = (out.clone(), out);
        fill_approach_simd(&mut a, 0, v, u);
        fill_approach(&mut c, 0, v, u);
        prop_assert_eq!(a.iter().map(|f| f.to_bits()).collect::<Vec<_>>(), c.iter().map(|f| f.to_bits()).collect::<Vec<_>>());
    }

    #[test]
    fn simd_projection_equals_scalar(
        seed in proptest::collection::vec((-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0), 1..40),
    ) {
        let v = arrays(&seed, usize::MAX);
        let g = input(&v, seed.len(), [0.0; 3]);
        let blocks = v[0].len() / LANES;
        let mut slots = vec![vec![0.0; blocks * SLOT_BLOCK]; 2];
        let shapes = [Shape::Sphere { center: [0.1, -0.2, 0.3], radius: 0.8 }, Shape::plane([0.0, -0.5, 0.0], [0.2, 1.0, 0.1]).unwrap()];
        for (s, out) in shapes.iter().zip(&mut slots) {
            for b in 0..blocks {
                shape_block_scalar(s, &g, b, &mut out[b * SLOT_BLOCK..(b + 1) * SLOT_BLOCK]);
            }
        }
        let (mut a, mut c) = ([v[3].clone(), v[4].clone(), v[5].clone()], [v[3].clone(), v[4].clone(), v[5].clone()]);
        {
            let [x, y, z] = &mut a;
            project_simd(&slots, &v[7], 0, [x, y, z]);
        }
        {
            let [x, y, z] = &mut c;
            project_scalar(&slots, &v[7], 0, [x, y, z]);
        }
        for k in 0..3 {
            prop_assert_eq!(a[k].iter().map(|f| f.to_bits()).collect::<Vec<_>>(), c[k].iter().map(|f| f.to_bits()).collect::<Vec<_>>());
        }
        // the last projection wins: every particle with a plane contact stands off the plane (up to rounding)
        for i in 0..seed.len() {
            let q = [a[0][i], a[1][i], a[2][i]];
            if read_slot(&slots[1], i).1 == [0.0; 3] {
                continue;
            }
            prop_assert!(shapes[1].signed_distance(q) >= v[7][i] - 1e-5, "{:?}", q);
        }
    }
}

#[test]
fn velocity_pass_removes_approach_and_applies_friction() {
    let mut slots = vec![vec![0.0; SLOT_BLOCK]];
    write_slot(&mut slots[0], 0, [0.0; 3], [0.0, 1.0, 0.0]);
    write_slot(&mut slots[0], 1, [0.0; 3], [0.0, 1.0, 0.0]);
    let th = vec![0.01; LANES];
    let (x, y, z) = (vec![0.0; LANES], vec![0.01, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], vec![0.0; LANES]);
    let (mut vx, mut vy, mut vz) = (vec![3.0; LANES], vec![-1.0; LANES], vec![0.0; LANES]);
    velocity_pass(&slots, &[([0.0; 3], 0.5)], &th, 0, [&x, &y, &z], [&mut vx, &mut vy, &mut vz]);
    assert_eq!((vx[0], vy[0]), (2.5, 0.0));
    // the approach speed measured before the projection sets the friction
    let (vx2, vy2, vz2) = (vec![3.0; LANES], vec![0.0; LANES], vec![0.0; LANES]);
    fill_approach(&mut slots[0], 0, [&[0.0; LANES], &[-4.0; LANES], &[0.0; LANES]], [0.0; 3]);
    assert_eq!(read_approach(&slots[0], 0), 4.0);
    let w = contact_velocity([vx2[0], vy2[0], vz2[0]], [0.0, 1.0, 0.0], 4.0, 0.5);
    assert!((w[0] - 1.0).abs() < 1e-6 && w[1] == 0.0 && w[2] == 0.0, "{w:?}");
    assert_eq!(contact_velocity([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 4.0, 0.5), [0.0; 3]);
    assert_eq!(contact_velocity([1.0, 2.0, 0.0], [0.0, 1.0, 0.0], 0.0, 0.5), [1.0, 2.0, 0.0]);
    // not touching (0.5 m above): unchanged; no slot: unchanged
    assert_eq!((vx[1], vy[1]), (3.0, -1.0));
    assert_eq!((vx[2], vy[2]), (3.0, -1.0));
}

/// Skipping whole blocks without contact changes nothing: a pass over the whole range equals
/// passes over one particle at a time (which never skip), for sparse random contacts in two
/// obstacles.
#[test]
fn block_skipping_passes_equal_particle_by_particle() {
    let n = 8 * LANES;
    let mut r = crate::test_rng::signed(5);
    let mut slots = vec![vec![0.0; n / LANES * SLOT_BLOCK]; 2];
    for (k, s) in slots.iter_mut().enumerate() {
        for i in (0..n).filter(|i| (i / LANES) % 3 == k && i % 3 != 1) {
            let nrm = [r(), 1.0 + r().abs(), r()];
            let l = (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]).sqrt();
            write_slot(s, i, [r() * 0.1, r() * 0.01, r() * 0.1], nrm.map(|c| c / l));
        }
        fill_approach(s, 0, [&vec![0.5; n], &vec![-1.0; n], &vec![0.0; n]], [0.0; 3]);
    }
    let th = vec![0.01; n];
    let shifts = [[0.0; 3], [0.001, 0.0, 0.0]];
    let motion = [([0.0; 3], 0.4), ([0.001, 0.0, 0.0], 0.2)];
    let x: [Vec<f32>; 3] = [0, 1, 2].map(|_| (0..n).map(|_| r() * 0.02).collect());
    let p0: [Vec<f32>; 3] = [0, 1, 2].map(|_| (0..n).map(|_| r() * 0.02).collect());
    let (mut whole, mut single) = (p0.clone(), p0.clone());
    let [a, b, c] = &mut whole;
    resolve_along_path(&slots, &shifts, &th, 0, [&x[0], &x[1], &x[2]], [a, b, c]);
    let [vw0, vw1, vw2] = &mut whole;
    velocity_pass(&slots, &motion, &th, 0, [&x[0], &x[1], &x[2]], [vw0, vw1, vw2]);
    for i in 0..n {
        let [a, b, c] = &mut single;
        let xs = [&x[0][i..i + 1], &x[1][i..i + 1], &x[2][i..i + 1]];
        resolve_along_path(&slots, &shifts, &th, i, xs, [&mut a[i..i + 1], &mut b[i..i + 1], &mut c[i..i + 1]]);
        velocity_pass(&slots, &motion, &th, i, xs, [&mut a[i..i + 1], &mut b[i..i + 1], &mut c[i..i + 1]]);
    }
    assert_eq!(whole, single);
    assert_ne!(whole, p0, "some particles must move");
    assert!(!block_touched(&slots, 2) && block_touched(&slots, 0) && !block_touched(&slots[..1], 1));
}
