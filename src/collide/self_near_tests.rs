//! Tests of the near list: SIMD == scalar == brute force, the parallel rebuild == the serial
//! one on 1 and 2 threads, the block displacement check.

use super::*;
use crate::test_rng::signed;

#[test]
fn simd_near_list_equals_scalar_and_brute_force() {
    let mut rng = signed(5);
    let n = 301;
    let p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| rng()).collect());
    let mut cand = Neighbours::new();
    cand.fill_serial(n, |i, buf| buf.extend((i + 1..n).filter(|j| (i + j) % 3 != 0).map(|j| j as u32)))
        .unwrap();
    let mut p = p;
    p[1][17] = f32::NAN;
    let pr = [&p[0][..], &p[1][..], &p[2][..]];
    let r2 = 0.6f32 * 0.6;
    let (mut a, mut b) = (Vec::new(), Vec::new());
    collect_near(&cand, pr, n, r2, false, &mut Vec::new(), &mut a);
    collect_near(&cand, pr, n, r2, true, &mut Vec::new(), &mut b);
    assert_eq!(a, b);
    let want: Vec<(u32, u32)> = cand
        .pairs()
        .filter(|&(i, j)| {
            let (i, j) = (i as usize, j as usize);
            let d2: f32 = (0..3).map(|k| (p[k][i] - p[k][j]) * (p[k][i] - p[k][j])).sum();
            d2 < r2 || d2.is_nan()
        })
        .collect();
    assert_eq!(a, want);
    assert!(a.len() > 100 && a.len() < cand.total(), "{} of {}", a.len(), cand.total());
    assert!(a.iter().any(|&(i, j)| i == 17 || j == 17), "NaN pairs are kept");
}

#[test]
fn parallel_rebuild_over_ranges_equals_the_serial_list_on_1_and_2_threads() {
    let mut rng = signed(11);
    let n = 400;
    let mut p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| rng()).collect());
    p[0][123] = f32::NAN;
    let mut cand = Neighbours::new();
    // Uneven lists: long ones in the middle, empty ones at both ends.
    cand.fill_serial(n, |i, buf| {
        if (40..360).contains(&i) {
            buf.extend((i + 1..n).filter(|j| (i * j) % 5 != 1).map(|j| j as u32));
        }
    })
    .unwrap();
    let mut bounds = Vec::new();
    chunk_bounds(&cand, n, &mut bounds);
    assert!(bounds.len() > 4, "{bounds:?}");
    assert!(bounds.windows(2).all(|w| w[0] < w[1]) && bounds[0] == 0 && bounds[bounds.len() - 1] == n);
    let pr = [&p[0][..], &p[1][..], &p[2][..]];
    let r2 = 0.7f32 * 0.7;
    let mut want = Vec::new();
    collect_near(&cand, pr, n, r2, false, &mut Vec::new(), &mut want);
    assert!(want.len() > 1000 && want.iter().any(|&(i, _)| i == 123));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        for (simd, parallel) in [(true, true), (false, true), (true, false)] {
            let mut near = NearList::default();
            pool.install(|| near.collect(&cand, pr, n, r2, simd, parallel));
            assert_eq!(near.pairs, want, "{threads} threads, simd {simd}, parallel {parallel}");
        }
    }
    chunk_bounds(&cand, 0, &mut bounds);
    assert_eq!(bounds, [0]);
}

#[test]
fn block_displacement_simd_equals_scalar_and_flags_nan() {
    let mut rng = signed(9);
    let n = 8 * 9 + 3; // the last block is partial
    let p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| rng()).collect());
    let blocks = [0u32, 2, 3, 7, 9];
    let mut at: [Vec<f32>; 3] = std::array::from_fn(|_| vec![0.0; blocks.len() * LANES]);
    for (k, &b) in blocks.iter().enumerate() {
        for l in 0..LANES {
            let i = b as usize * LANES + l;
            for a in 0..3 {
                at[a][k * LANES + l] = p[a].get(i).map_or(0.0, |v| v + 0.01 * rng());
            }
        }
    }
    let pr = [&p[0][..], &p[1][..], &p[2][..]];
    let ar = [&at[0][..], &at[1][..], &at[2][..]];
    let s = max_disp2_blocks(pr, ar, &blocks, false);
    assert_eq!(s.to_bits(), max_disp2_blocks(pr, ar, &blocks, true).to_bits());
    // The largest over the listed particles only (block 1 is left out and moved far).
    let mut want = 0.0f32;
    for (k, &b) in blocks.iter().enumerate() {
        for l in 0..LANES {
            let i = b as usize * LANES + l;
            if i < n {
                let d2: f32 = (0..3).map(|a| (p[a][i] - at[a][k * LANES + l]).powi(2)).sum();
                want = want.max(d2);
            }
        }
    }
    assert!(s > 0.0 && (s - want).abs() <= 1e-6 * want, "{s} {want}");
    let mut q = p.clone();
    q[0][8 + 1] = 50.0;
    let qr = [&q[0][..], &q[1][..], &q[2][..]];
    assert_eq!(
        max_disp2_blocks(qr, ar, &blocks, true).to_bits(),
        s.to_bits(),
        "block 1 is not checked"
    );
    q[2][3 * 8 + 5] = f32::NAN;
    for simd in [false, true] {
        let qr = [&q[0][..], &q[1][..], &q[2][..]];
        assert_eq!(max_disp2_blocks(qr, ar, &blocks, simd), f32::INFINITY);
    }
}

#[test]
fn gather_xyz8_puts_entry_l_in_lane_l() {
    let xyz: Vec<[f32; 4]> = (0..40).map(|i| [i as f32, 100.0 + i as f32, 200.0 + i as f32, -1.0]).collect();
    let idx: Idx8 = [3, 39, 0, 17, 17, 8, 25, 1];
    let [x, y, z] = gather_xyz8(&xyz, &idx);
    for (l, &i) in idx.iter().enumerate() {
        assert_eq!(x.to_array()[l], i as f32);
        assert_eq!(y.to_array()[l], 100.0 + i as f32);
        assert_eq!(z.to_array()[l], 200.0 + i as f32);
    }
}
