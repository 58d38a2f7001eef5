use super::*;
use proptest::prelude::*;

fn input<'a>(v: &'a [Vec<f32>; 8], n: usize, shift: [f32; 3]) -> GenInput<'a> {
    input_reach(v, 7, n, shift)
}

/// The contact search's input from arrays `x`, `y`, `z`, `px`, `py`, `pz`, `w`, `th` (indices
/// 0 to 7), the reach being array `reach`.
fn input_reach(v: &[Vec<f32>], reach: usize, n: usize, shift: [f32; 3]) -> GenInput<'_> {
    GenInput {
        x: [&v[0], &v[1], &v[2]],
        p: [&v[3], &v[4], &v[5]],
        w: &v[6],
        th: &v[7],
        reach: &v[reach],
        n,
        shift,
    }
}

fn arrays(seed: &[(f32, f32, f32, f32, f32, f32)], pinned: usize) -> [Vec<f32>; 8] {
    let len = crate::data::lanes::round_up(seed.len() + 1);
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
        let mut data = vec![vec![0.0; blocks * SLOT_BLOCK]; 2];
        let shapes = [Shape::Sphere { center: [0.1, -0.2, 0.3], radius: 0.8 }, Shape::plane([0.0, -0.5, 0.0], [0.2, 1.0, 0.1]).unwrap()];
        for (s, out) in shapes.iter().zip(&mut data) {
            for b in 0..blocks {
                shape_block_scalar(s, &g, b, &mut out[b * SLOT_BLOCK..(b + 1) * SLOT_BLOCK]);
            }
        }
        let slots: Vec<Slots> = data.into_iter().map(Slots::from_data).collect();
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
            if read_slot(&slots[1].data, i).1 == [0.0; 3] {
                continue;
            }
            prop_assert!(shapes[1].signed_distance(q) >= v[7][i] - 1e-5, "{:?}", q);
        }
    }
}

/// One obstacle's slots for one block: a floor contact (point at the origin, normal `+y`) at
/// each of `lanes`.
fn floor_slots(lanes: &[usize]) -> Vec<Slots> {
    let mut s = Slots::new(1);
    for &l in lanes {
        s.write(l, [0.0; 3], [0.0, 1.0, 0.0]);
    }
    vec![s]
}

#[test]
fn velocity_pass_removes_approach_and_applies_friction() {
    let mut slots = floor_slots(&[0, 1]);
    let th = vec![0.01; LANES];
    let (x, y, z) = (vec![0.0; LANES], vec![0.01, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], vec![0.0; LANES]);
    let (mut vx, mut vy, mut vz) = (vec![3.0; LANES], vec![-1.0; LANES], vec![0.0; LANES]);
    velocity_pass(&slots, &[([0.0; 3], 0.5)], &th, 0, [&x, &y, &z], [&mut vx, &mut vy, &mut vz]);
    assert_eq!((vx[0], vy[0]), (2.5, 0.0));
    // the approach speed measured before the projection sets the friction
    let (vx2, vy2, vz2) = (vec![3.0; LANES], vec![0.0; LANES], vec![0.0; LANES]);
    fill_approach(&mut slots[0].data, 0, [&[0.0; LANES], &[-4.0; LANES], &[0.0; LANES]], [0.0; 3]);
    assert_eq!(read_approach(&slots[0].data, 0), 4.0);
    let w = contact_velocity([vx2[0], vy2[0], vz2[0]], [0.0, 1.0, 0.0], 4.0, 0.5);
    assert!((w[0] - 1.0).abs() < 1e-6 && w[1] == 0.0 && w[2] == 0.0, "{w:?}");
    assert_eq!(contact_velocity([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 4.0, 0.5), [0.0; 3]);
    assert_eq!(contact_velocity([1.0, 2.0, 0.0], [0.0, 1.0, 0.0], 0.0, 0.5), [1.0, 2.0, 0.0]);
    // not touching (0.5 m above): unchanged; no slot: unchanged
    assert_eq!((vx[1], vy[1]), (3.0, -1.0));
    assert_eq!((vx[2], vy[2]), (3.0, -1.0));
}

/// Skipping whole blocks without contact changes nothing: a pass over the whole range, one
/// particle at a time or eight (which also skip an obstacle without contact in the block),
/// equals passes over one particle at a time (which never skip), for sparse random contacts in
/// two obstacles.
#[test]
fn block_skipping_passes_equal_particle_by_particle() {
    let n = 8 * LANES;
    let mut r = crate::test_rng::signed(5);
    let mut slots = vec![Slots::new(n / LANES); 2];
    for (k, s) in slots.iter_mut().enumerate() {
        for i in (0..n).filter(|i| (i / LANES) % 3 == k && i % 3 != 1) {
            let nrm = [r(), 1.0 + r().abs(), r()];
            let l = (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]).sqrt();
            s.write(i, [r() * 0.1, r() * 0.01, r() * 0.1], nrm.map(|c| c / l));
        }
        for b in 0..n / LANES {
            let v = [&vec![0.5; n][..], &vec![-1.0; n][..], &vec![0.0; n][..]];
            fill_approach(&mut s.data[b * SLOT_BLOCK..(b + 1) * SLOT_BLOCK], b, v, [0.0; 3]);
        }
        assert!(s.flags_consistent());
    }
    let th = vec![0.01; n];
    let shifts = [[0.0; 3], [0.001, 0.0, 0.0]];
    let motion = [([0.0; 3], 0.4), ([0.001, 0.0, 0.0], 0.2)];
    let x: [Vec<f32>; 3] = [0, 1, 2].map(|_| (0..n).map(|_| r() * 0.02).collect());
    let p0: [Vec<f32>; 3] = [0, 1, 2].map(|_| (0..n).map(|_| r() * 0.02).collect());
    // The three passes over the whole range, one particle at a time or eight (`lanes`).
    let passes = |lanes: bool| {
        let mut v = p0.clone();
        let xs = [&x[0][..], &x[1][..], &x[2][..]];
        let [a, b, c] = &mut v;
        if lanes {
            resolve_simd(&slots, &shifts, &[true, false], &th, 0, xs, [a, b, c]);
            project_simd(&slots, &th, 0, [a, b, c]);
            velocity_pass_simd(&slots, &motion, &th, 0, xs, [a, b, c]);
        } else {
            resolve_along_path(&slots, &shifts, &[true, false], &th, 0, xs, [a, b, c]);
            project_scalar(&slots, &th, 0, [a, b, c]);
            velocity_pass(&slots, &motion, &th, 0, xs, [a, b, c]);
        }
        v
    };
    let (whole, mut single) = (passes(false), p0.clone());
    for i in 0..n {
        let [a, b, c] = &mut single;
        let xs = [&x[0][i..i + 1], &x[1][i..i + 1], &x[2][i..i + 1]];
        resolve_along_path(
            &slots,
            &shifts,
            &[true, false],
            &th,
            i,
            xs,
            [&mut a[i..i + 1], &mut b[i..i + 1], &mut c[i..i + 1]],
        );
        project_scalar(&slots, &th, i, [&mut a[i..i + 1], &mut b[i..i + 1], &mut c[i..i + 1]]);
        velocity_pass(&slots, &motion, &th, i, xs, [&mut a[i..i + 1], &mut b[i..i + 1], &mut c[i..i + 1]]);
    }
    assert_eq!(whole, single);
    // The lanes skip each obstacle's untouched blocks too (here every touched block holds one
    // obstacle's contacts, not the other's): the same bits.
    assert_eq!(bits(&passes(true)), bits(&single));
    assert_ne!(whole, p0, "some particles must move");
    assert!(!block_touched(&slots, 2) && block_touched(&slots, 0) && !block_touched(&slots[..1], 1));
}

/// Two obstacles' slots over `n` particles from `seed` (one tuple per particle and obstacle:
/// point, normal direction, approach speed, and whether the slot holds a contact).
#[allow(clippy::type_complexity)]
fn random_slots(seed: &[((f32, f32, f32), (f32, f32, f32), f32, bool)], n: usize) -> Vec<Slots> {
    let mut slots = vec![Slots::new(n / LANES); 2];
    for (j, &((cx, cy, cz), (nx, ny, nz), a, set)) in seed.iter().enumerate().take(2 * n) {
        let (k, i) = (j % 2, j / 2);
        let l = (nx * nx + ny * ny + nz * nz).sqrt();
        if set && l > 1e-3 {
            slots[k].write(i, [cx, cy, cz], [nx / l, ny / l, nz / l]);
            slots[k].set_approach(i, a);
        }
    }
    slots
}

type Triple = (f32, f32, f32);

fn columns(v: &[Triple], n: usize) -> [Vec<f32>; 3] {
    let mut out = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
    for (i, t) in v.iter().enumerate().take(n) {
        (out[0][i], out[1][i], out[2][i]) = (t.0, t.1, t.2);
    }
    out
}

fn bits(v: &[Vec<f32>; 3]) -> Vec<u32> {
    v.iter().flatten().map(|f| f.to_bits()).collect()
}

proptest! {
    /// The SIMD response and velocity pass equal their scalar twins bit for bit, over random
    /// sparse contacts of two (moving) obstacles, random paths, thicknesses and friction;
    /// also over a chunk that starts at a later block.
    #[test]
    fn simd_resolve_and_velocity_equal_scalar(
        seed in proptest::collection::vec(((-0.2f32..0.2, -0.2f32..0.2, -0.2f32..0.2), (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0), 0.0f32..2.0, any::<bool>()), 48),
        xs in proptest::collection::vec((-0.2f32..0.2, -0.2f32..0.2, -0.2f32..0.2), 24),
        ps in proptest::collection::vec((-0.2f32..0.2, -0.2f32..0.2, -0.2f32..0.2), 24),
        vs in proptest::collection::vec((-3.0f32..3.0, -3.0f32..3.0, -3.0f32..3.0), 24),
        th in proptest::collection::vec(0.0f32..0.05, 24),
        shift in (-0.05f32..0.05, -0.05f32..0.05, -0.05f32..0.05),
        mu in 0.0f32..1.5,
        from in 0usize..3,
        mesh in (any::<bool>(), any::<bool>()),
    ) {
        let n = 24;
        let slots = random_slots(&seed, n);
        let shifts = [[0.0; 3], [shift.0, shift.1, shift.2]];
        let motion = [([0.0; 3], mu), ([shift.0 * 30.0, shift.1 * 30.0, shift.2 * 30.0], 0.5 * mu)];
        let x = columns(&xs, n);
        let s = from * LANES;
        let xr = [&x[0][s..], &x[1][s..], &x[2][s..]];
        let run = |simd: bool, p0: &[Vec<f32>; 3], v0: &[Vec<f32>; 3]| {
            let (mut p, mut v) = (p0.clone(), v0.clone());
            let [a, b, c] = &mut p;
            let pp = [&mut a[s..], &mut b[s..], &mut c[s..]];
            let [d, e, f] = &mut v;
            let vv = [&mut d[s..], &mut e[s..], &mut f[s..]];
            if simd {
                resolve_simd(&slots, &shifts, &[mesh.0, mesh.1], &th, s, xr, pp);
                velocity_pass_simd(&slots, &motion, &th, s, xr, vv);
            } else {
                resolve_along_path(&slots, &shifts, &[mesh.0, mesh.1], &th, s, xr, pp);
                velocity_pass(&slots, &motion, &th, s, xr, vv);
            }
            (p, v)
        };
        let (p0, v0) = (columns(&ps, n), columns(&vs, n));
        let (ps_, vs_) = run(false, &p0, &v0);
        let (pv, vv) = run(true, &p0, &v0);
        prop_assert_eq!(bits(&ps_), bits(&pv));
        prop_assert_eq!(bits(&vs_), bits(&vv));
        // positions at rest on the contact planes make the velocity pass act
        let (_, vs2) = run(false, &ps_, &v0);
        let (_, vv2) = run(true, &ps_, &v0);
        prop_assert_eq!(bits(&vs2), bits(&vv2));
    }
}

/// A particle that starts inside the thickness layer of a contact plane and whose path
/// crosses it goes back to its start when the obstacle is a mesh (a push along one face's
/// normal can enter a non-convex mesh through a neighbour) and is pushed along the normal
/// for a convex shape; both backends alike. One that stays in front of the plane is pushed.
#[test]
fn a_crossing_from_inside_the_layer_returns_to_the_start_on_meshes_only() {
    let slots = floor_slots(&[2, 5]);
    let th = vec![0.01; LANES];
    // Lane 2 starts 4 mm above the plane (inside the 10 mm layer) and ends 30 mm behind it,
    // 0.2 m along; lane 5 ends 4 mm above it (inside the layer, no crossing).
    let x = [vec![0.0; LANES], vec![0.004; LANES], vec![0.0; LANES]];
    let p0 = [
        vec![0.2; LANES],
        vec![-0.03, -0.03, -0.03, -0.03, -0.03, 0.004, -0.03, -0.03],
        vec![0.0; LANES],
    ];
    for mesh in [true, false] {
        for simd in [false, true] {
            let mut p = p0.clone();
            let [a, b, c] = &mut p;
            let xr = [&x[0][..], &x[1][..], &x[2][..]];
            if simd {
                resolve_simd(&slots, &[[0.0; 3]], &[mesh], &th, 0, xr, [a, b, c]);
            } else {
                resolve_along_path(&slots, &[[0.0; 3]], &[mesh], &th, 0, xr, [a, b, c]);
            }
            let lane = |l: usize| [p[0][l], p[1][l], p[2][l]];
            if mesh {
                assert_eq!(lane(2), [0.0, 0.004, 0.0], "simd {simd}: back to the start");
            } else {
                assert_eq!(lane(2), [0.2, 0.01, 0.0], "simd {simd}: pushed along the normal");
            }
            assert_eq!(lane(5), [0.2, 0.01, 0.0], "mesh {mesh}, simd {simd}: no crossing, pushed");
            assert_eq!(lane(0), [0.2, -0.03, 0.0], "no contact");
        }
    }
}

/// The SIMD passes (response, projection, velocity) keep untouched lanes exactly, signed
/// zeros included, and do change touched ones.
#[test]
fn simd_passes_keep_untouched_lanes_bitwise() {
    let mut slots = floor_slots(&[3]);
    slots[0].set_approach(3, 1.0);
    let th = vec![0.01; LANES];
    let x = [vec![-0.0; LANES], vec![0.5; LANES], vec![-0.0; LANES]];
    let xr = [&x[0][..], &x[1][..], &x[2][..]];
    let mut p = [vec![-0.0; LANES], vec![-0.1; LANES], vec![-0.0; LANES]];
    let [a, b, c] = &mut p;
    resolve_simd(&slots, &[[0.0; 3]], &[true], &th, 0, xr, [a, b, c]);
    let [a, b, c] = &mut p;
    project_simd(&slots, &th, 0, [a, b, c]);
    let mut v = [vec![-0.0; LANES], vec![-1.0; LANES], vec![-0.0; LANES]];
    let x2 = [vec![-0.0; LANES], vec![0.01; LANES], vec![-0.0; LANES]];
    let [d, e, f] = &mut v;
    velocity_pass_simd(&slots, &[([0.0; 3], 0.3)], &th, 0, [&x2[0], &x2[1], &x2[2]], [d, e, f]);
    for l in (0..LANES).filter(|&l| l != 3) {
        assert_eq!([p[0][l], p[2][l], v[0][l], v[2][l]].map(f32::to_bits), [(-0.0f32).to_bits(); 4]);
        assert_eq!((p[1][l], v[1][l]), (-0.1, -1.0));
    }
    assert!(p[1][3] > 0.0 && v[1][3] == 0.0, "{} {}", p[1][3], v[1][3]);
}

/// The branch-free test of a block's normals equals "any component `!= 0.0`": signed zeros
/// are unset, NaN, infinities and the smallest subnormal are set, in every normal position.
#[test]
fn normals_set_equals_any_nonzero_component() {
    for v in [0.0f32, -0.0, f32::NAN, f32::INFINITY, -f32::MIN_POSITIVE, f32::from_bits(1), 1.0] {
        for at in 0..SLOT_BLOCK {
            let mut block = vec![0.0f32; SLOT_BLOCK];
            block[at] = v;
            let expect = block[3 * LANES..6 * LANES].iter().any(|&c| c != 0.0);
            assert_eq!(normals_set(&block), expect, "{v} at {at}");
            // the touched flag is "not all +0.0": a signed zero anywhere counts
            assert_eq!(block_touched(&[Slots::from_data(block)], 0), v.to_bits() != 0);
        }
    }
}

#[path = "shape_tests.rs"]
mod shape;
