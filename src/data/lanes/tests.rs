use super::*;

#[test]
fn round_up_pads_to_lanes() {
    assert_eq!(round_up(0), 0);
    assert_eq!(round_up(1), 8);
    assert_eq!(round_up(8), 8);
    assert_eq!(round_up(9), 16);
}

#[test]
fn gather1_puts_entry_idx_l_in_lane_l() {
    let s: Vec<f32> = (0..40).map(|i| 0.5 + i as f32).collect();
    let idx = idx8(|l| [3, 39, 0, 17, 17, 8, 25, 1][l]);
    let want: Vec<f32> = idx.iter().map(|&i| s[i as usize]).collect();
    assert_eq!(gather1(&s, &idx).to_array().to_vec(), want);
    // SAFETY: every index is below 40.
    assert_eq!(unsafe { gather1_unchecked(&s, &idx) }.to_array().to_vec(), want);
}

#[test]
fn unchecked_loads_read_what_the_checked_ones_read() {
    let s: Vec<f32> = (0..20).map(|i| 0.25 * i as f32).collect();
    let u: Vec<u32> = (0..20).map(|i| 3 * i).collect();
    for i in 0..=20 - LANES {
        // SAFETY: `i + LANES <= 20`.
        let (a, b) = unsafe { (load_unchecked(&s, i), load_idx_unchecked(&u, i)) };
        assert_eq!(a.to_array(), load(&s, i).to_array());
        assert_eq!(b, load_idx(&u, i));
    }
}

#[test]
fn pick16_reads_the_named_window_element() {
    let lo = F32s::from([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
    let hi = F32s::from([8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0, 15.0]);
    let pos: Pos8 = [15, 0, 9, 7, 8, 3, 12, 1];
    let want: Vec<f32> = pos.iter().map(|&q| q as f32).collect();
    assert_eq!(pick16(lo, hi, &pos).to_array().to_vec(), want);
}

#[test]
fn run_load_store_roundtrip() {
    let mut x: Vec<f32> = (0..20).map(|i| i as f32).collect();
    let mut y = x.clone();
    let mut z = x.clone();
    let s = SharedVec3::new(&mut x, &mut y, &mut z);
    // SAFETY: single thread, 3 + 8 <= 20.
    let v = unsafe { s.load_run(3) };
    assert_eq!(v.y.to_array(), [3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0]);
    // SAFETY: as above.
    unsafe { s.store_run(3, v + Vec3x8::splat([1.0, 2.0, 3.0])) };
    assert_eq!((x[2], x[3], y[10], z[11]), (2.0, 4.0, 12.0, 11.0));
}

#[test]
fn gather_scatter_roundtrip() {
    let mut x: Vec<f32> = (0..16).map(|i| i as f32).collect();
    let mut y: Vec<f32> = (0..16).map(|i| 100.0 + i as f32).collect();
    let mut z: Vec<f32> = (0..16).map(|i| -(i as f32)).collect();
    let s = SharedVec3::new(&mut x, &mut y, &mut z);
    let idx: Idx8 = [15, 3, 7, 0, 9, 1, 2, 11];
    // SAFETY: single thread, indices in range.
    let v = unsafe { s.gather(&idx) };
    assert_eq!(v.x.to_array(), [15.0, 3.0, 7.0, 0.0, 9.0, 1.0, 2.0, 11.0]);
    let w = v + Vec3x8::splat([1.0, 1.0, 1.0]);
    // SAFETY: as above.
    unsafe { s.scatter(&idx, w) };
    assert_eq!(x[15], 16.0);
    assert_eq!(y[0], 101.0);
    assert_eq!(z[11], -10.0);
    assert_eq!(x[4], 4.0);
}

#[test]
fn split16_deals_the_named_elements_and_merge16_inverts_it() {
    let lo = F32s::from(std::array::from_fn::<f32, LANES, _>(|q| q as f32));
    let hi = F32s::from(std::array::from_fn::<f32, LANES, _>(|q| (LANES + q) as f32));
    for split in [Split::Pairs, Split::Quads] {
        let (a, b) = split16(lo, hi, split);
        let mut seen = [false; 2 * LANES];
        for l in 0..LANES {
            let q = split_a(split, l);
            assert_eq!(a.to_array()[l], q as f32, "{split:?} a lane {l}");
            assert_eq!(b.to_array()[l], (q + split_stride(split)) as f32, "{split:?} b lane {l}");
            seen[q] = true;
            seen[q + split_stride(split)] = true;
        }
        assert!(seen.iter().all(|&s| s), "{split:?} covers the window");
        let (l2, h2) = merge16(a, b, split);
        assert_eq!((l2.to_array(), h2.to_array()), (lo.to_array(), hi.to_array()));
    }
}

/// `mul_add` rounds once in every lane, as `f32::mul_add` does, on any build: a case whose
/// product needs more than 24 bits (the fused result keeps what the twice-rounded one loses),
/// signed zeros, infinities, NaN and random values.
#[test]
fn mul_add_rounds_once_like_the_scalar_mul_add() {
    let e = f32::EPSILON;
    let (a, b, c) = (1.0 + e, 1.0 - e, -1.0f32);
    assert_eq!(a.mul_add(b, c), -e * e, "f32::mul_add is fused");
    assert_eq!(a * b + c, 0.0, "the product alone rounds to one");
    let mut rng = crate::test_rng::signed(41);
    let specials = [
        a,
        b,
        c,
        -0.0,
        0.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        f32::MAX,
        f32::from_bits(1),
    ];
    let mut values: Vec<f32> = specials.to_vec();
    values.extend((0..54).map(|_| 1e3 * rng()));
    for w in values.chunks_exact(3 * LANES) {
        let [x, y, z] = [0, 1, 2].map(|k| F32s::from(<[f32; LANES]>::try_from(&w[k * LANES..(k + 1) * LANES]).unwrap()));
        let got = mul_add(x, y, z).to_array();
        for l in 0..LANES {
            let want = w[l].mul_add(w[LANES + l], w[2 * LANES + l]);
            assert_eq!(
                got[l].to_bits(),
                want.to_bits(),
                "lane {l}: {} * {} + {}",
                w[l],
                w[LANES + l],
                w[2 * LANES + l]
            );
        }
    }
}
