//! Tests of the near list: SIMD == scalar == brute force, the parallel rebuild == the serial
//! one on 1 and 2 threads, the block displacement check.

use super::*;
use crate::data::exec::Exec;
use crate::data::lanes::Idx8;
use crate::self_collision::near::scan::{chunk_bounds, collect, collect_near, filter_pairs, gather_xyzw8, ScanScratch, FILTER_CHUNK};
use crate::self_collision::neighbours::within;
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
    let r = 0.6;
    let (mut a, mut b) = (Vec::new(), Vec::new());
    collect_near(&cand, pr, n, r, false, &mut Vec::new(), &mut a);
    collect_near(&cand, pr, n, r, true, &mut Vec::new(), &mut b);
    assert_eq!(a, b);
    assert_eq!(a, brute_near(cand.pairs(), &p, r));
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
    let r = 0.7;
    let mut want = Vec::new();
    collect_near(&cand, pr, n, r, false, &mut Vec::new(), &mut want);
    assert!(want.len() > 1000 && want.iter().any(|&(i, _)| i == 123));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        for (simd, parallel) in [(true, true), (false, true), (true, false)] {
            let (mut scratch, mut got) = (ScanScratch::default(), Vec::new());
            pool.install(|| collect(&cand, pr, n, r, Exec::new(simd, parallel), &mut scratch, &mut got));
            assert_eq!(got, want, "{threads} threads, simd {simd}, parallel {parallel}");
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
fn gather_xyzw8_puts_entry_l_in_lane_l() {
    let xyz: Vec<[f32; 4]> = (0..40)
        .map(|i| [i as f32, 100.0 + i as f32, 200.0 + i as f32, -1.0 - i as f32])
        .collect();
    let idx: Idx8 = [3, 39, 0, 17, 17, 8, 25, 1];
    let [x, y, z, w] = gather_xyzw8(&xyz, &idx);
    for (l, &i) in idx.iter().enumerate() {
        assert_eq!(x.to_array()[l], i as f32);
        assert_eq!(y.to_array()[l], 100.0 + i as f32);
        assert_eq!(z.to_array()[l], 200.0 + i as f32);
        assert_eq!(w.to_array()[l], -1.0 - i as f32);
    }
}

/// The near list built through the mid list is the one built from the candidates directly,
/// at every rebuild, and holds every pair in contact at every update, while pairs close in
/// (the near list kept, or rebuilt from a kept mid list) and at jumps (both rebuilt). A mid
/// radius of `2 d` instead of `2.5 d` fails it.
#[test]
fn near_list_through_the_mid_list_equals_the_direct_build() {
    near_through_mid(false, false, 10.0);
}

/// With candidates reaching too little for a mid list, the near list is collected from the
/// candidates directly: the same list, holding every contact, also after the candidates
/// change halfway (a new build).
#[test]
fn near_list_without_mid_list_equals_the_scan_of_the_candidates() {
    near_through_mid(false, false, 3.0);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    pool.install(|| near_through_mid(false, true, 3.0));
}

/// The same with the mid list queried from a hash of the predicted positions (the slow steps
/// without candidate lists): the near list equals the one built from every pair (rest
/// positions far apart, so no rest neighbour is dropped), serially and in parallel.
#[test]
fn near_list_through_a_hashed_mid_list_equals_the_build_from_every_pair() {
    near_through_mid(true, false, 10.0);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    pool.install(|| near_through_mid(true, true, 10.0));
}

/// `reach`: of the candidates, over `d` (10: the mid list is used; 3: it is not).
fn near_through_mid(hashed: bool, parallel: bool, reach: f32) {
    let mut rng = signed(21);
    let (n, d) = (200usize, 0.1f32);
    let mut p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 0.3 * rng()).collect());
    let mut cand = Neighbours::new();
    cand.fill_serial(n, |i, buf| {
        buf.extend((i + 1..n).filter(|j| hashed || (i + 2 * j) % 7 != 0).map(|j| j as u32))
    })
    .unwrap();
    let rest = [(0..n).map(|i| 100.0 * i as f32).collect::<Vec<f32>>(), vec![0.0; n], vec![0.0; n]];
    let cloth_of = vec![0u32; n];
    let blocks: Vec<u32> = (0..n.div_ceil(LANES) as u32).collect();
    let mut near = NearList::default();
    let (mut scratch, mut want) = (ScanScratch::default(), Vec::new());
    let (mut checked, mut kept) = (0, 0);
    // Even particles drift along +x and odd ones along -x (0.03 d a call, so pairs close in at
    // up to 0.06 d a call: the near list is rebuilt from a kept mid list after the pairs
    // moved ~0.6 d relative to its build), with a jump of up to 0.6 d every 50 calls.
    let vel: [Vec<f32>; 3] = std::array::from_fn(|k| {
        (0..n)
            .map(|i| {
                if k == 0 {
                    if i % 2 == 0 {
                        0.03 * d
                    } else {
                        -0.03 * d
                    }
                } else {
                    0.005 * d * rng()
                }
            })
            .collect()
    });
    for call in 0..300 {
        if call == 150 && !hashed {
            // New candidates (a new build, so the near list is invalidated): every pair but
            // another subset.
            cand.fill_serial(n, |i, buf| buf.extend((i + 1..n).filter(|j| (i + j) % 5 != 0).map(|j| j as u32)))
                .unwrap();
            near.invalidate();
        }
        for (a, v) in p.iter_mut().zip(&vel) {
            for (x, dx) in a.iter_mut().zip(v) {
                *x += if call % 50 == 0 { 0.6 * d * rng() } else { *dx };
            }
        }
        let pr = [&p[0][..], &p[1][..], &p[2][..]];
        let (before, mid_before) = (near.rebuilds, near.mid_rebuilds);
        let source = if hashed {
            MidSource::Hash(RestRule {
                rest: [&rest[0], &rest[1], &rest[2]],
                cloth_of: &cloth_of,
                skip: 3.0 * d,
            })
        } else {
            MidSource::Candidates {
                cand: &cand,
                reach: reach * d,
            }
        };
        near.update(source, pr, &blocks, n, d, Exec::new(true, parallel));
        if near.rebuilds > before {
            collect(&cand, pr, n, d + near.skin, Exec::Scalar, &mut scratch, &mut want);
            assert_eq!(near.pairs, want, "call {call}");
            checked += 1;
            kept += usize::from(near.mid_rebuilds == mid_before);
        }
        assert_contacts_listed(&cand, &p, d, &near.pairs, call);
    }
    let msg = format!("{checked} near builds, {} mid, {kept} from a kept mid list", near.mid_rebuilds);
    if reach >= 10.0 {
        assert!(near.mid_rebuilds >= 6 && kept > 10, "{msg}");
    } else {
        assert!(near.mid_rebuilds == 0 && checked > 20, "{msg}");
    }
    assert!(near.pairs.len() > 20, "{} near pairs", near.pairs.len());
}

/// The hashed mid list refreshed for the few particles that moved (module `self_mid`): at
/// every near build the near list equals the one built from every pair but the rest
/// neighbours (two cloths on one rest grid, so many pairs are dropped by the rule), while a
/// changing handful of particles moves fast and the rest drift; the stale particles pass
/// their cap, so the hash is built again from the references (a rehash), after which the
/// mid list is exactly the pairs within the mid radius of the references. Serially, in
/// parallel, on 1 and 2 threads.
#[test]
fn refreshed_mid_list_gives_the_near_list_of_every_pair() {
    for (threads, parallel) in [(1, false), (1, true), (2, true)] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| refreshed_mid(parallel));
    }
}

fn refreshed_mid(parallel: bool) {
    let mut rng = signed(33);
    let (n, d) = (400usize, 0.1f32);
    let mut p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 0.6 * rng()).collect());
    let rest: [Vec<f32>; 3] = [
        (0..n).map(|i| (i % 20) as f32 * d).collect(),
        (0..n).map(|i| (i / 20 % 10) as f32 * d).collect(),
        vec![0.0; n],
    ];
    let cloth_of: Vec<u32> = (0..n as u32).map(|i| i / 200).collect();
    let rule = RestRule {
        rest: [&rest[0], &rest[1], &rest[2]],
        cloth_of: &cloth_of,
        skip: 3.0 * d,
    };
    // Every pair the rule keeps, as candidate lists for the reference build.
    let mut all = Neighbours::new();
    all.fill_serial(n, |i, buf| buf.extend((i + 1..n).filter(|&j| !rule.skips(i, j)).map(|j| j as u32)))
        .unwrap();
    assert!(all.total() < n * (n - 1) / 2 - 1000, "the rule drops pairs");
    let blocks: Vec<u32> = (0..n.div_ceil(LANES) as u32).collect();
    let mut near = NearList::default();
    let (mut scratch, mut want) = (ScanScratch::default(), Vec::new());
    let (mut checked, mut refreshed, mut queried, mut rehashed) = (0, 0, 0, 0);
    for call in 0..900 {
        // Six fast particles (0.15 d a call along a fixed direction each), a new six every
        // 25 calls; the others drift by up to 0.004 d a call.
        let fast = |i: usize| (i + 7 * (call / 25)).is_multiple_of(67);
        for (k, a) in p.iter_mut().enumerate() {
            for (i, x) in a.iter_mut().enumerate() {
                *x += if fast(i) {
                    0.15 * d * [0.6, -0.64, 0.48][k]
                } else {
                    0.004 * d * rng()
                };
            }
        }
        let pr = [&p[0][..], &p[1][..], &p[2][..]];
        let (before, rehashes) = (near.rebuilds, near.hashed.rehashes);
        match near.update(MidSource::Hash(rule), pr, &blocks, n, d, Exec::new(true, parallel)) {
            MidUpdate::Refreshed => refreshed += 1,
            MidUpdate::Queried => queried += 1,
            MidUpdate::Kept => {}
        }
        if near.hashed.rehashes > rehashes {
            // Every pair the rule keeps within the mid radius of the references, none other.
            let r = d * (1.0 + MID_NEAR_SKIN_MAX + MID_SKIN);
            let a = &near.mid_at;
            let exact: Vec<(u32, u32)> = all
                .pairs()
                .filter(|&(i, j)| {
                    let (i, j) = (i as usize, j as usize);
                    within(a[0][i], a[1][i], a[2][i], a[0][j], a[1][j], a[2][j], r * r)
                })
                .collect();
            assert!(near.hashed.extra().is_empty(), "call {call}: extra pairs folded in");
            assert_eq!(near.mid, exact, "call {call}: the mid list after a rehash");
            rehashed += 1;
        }
        if near.rebuilds > before {
            collect(&all, pr, n, d + near.skin, Exec::Scalar, &mut scratch, &mut want);
            assert_eq!(near.pairs, want, "call {call}");
            checked += 1;
        }
    }
    let msg = format!(
        "{checked} near builds, {queried} mid queries, {refreshed} refreshes \
         ({rehashed} rehashes)"
    );
    assert!(checked > 100 && refreshed > 20 && queried >= 1 && rehashed >= 2, "{msg}");
    assert!(
        near.hashed.refreshes == refreshed && near.pairs.len() > 20,
        "{msg}, {} near pairs",
        near.pairs.len()
    );
}

/// A few particles that jump back and forth (0.2 d a call) among a slowly drifting crowd (the
/// movement-speed fold's edge particles): on the mid path the skin stays at its floor `d / 8`,
/// the jumpers force rebuilds, the list built at each rebuild is the one of that radius from
/// every pair, and every contact is in the list at every call.
#[test]
fn jumping_particles_keep_every_contact_listed() {
    let mut rng = signed(41);
    let (n, d) = (400usize, 0.1f32);
    let mut p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 0.6 * rng()).collect());
    let rest = [(0..n).map(|i| 100.0 * i as f32).collect::<Vec<f32>>(), vec![0.0; n], vec![0.0; n]];
    let cloth_of = vec![0u32; n];
    let rule = RestRule {
        rest: [&rest[0], &rest[1], &rest[2]],
        cloth_of: &cloth_of,
        skip: 3.0 * d,
    };
    let mut all = Neighbours::new();
    all.fill_serial(n, |i, buf| buf.extend((i + 1..n).map(|j| j as u32))).unwrap();
    let blocks: Vec<u32> = (0..n.div_ceil(LANES) as u32).collect();
    let jumpers = [5u32, 77, 222, 391];
    let mut near = NearList::default();
    let (mut scratch, mut want) = (ScanScratch::default(), Vec::new());
    let (mut jumping, mut after) = (0, 0);
    // The jumpers stop at call 300; the crowd drifts on.
    for call in 0..500 {
        let sign = if call % 2 == 0 { 1.0 } else { -1.0 };
        for (k, a) in p.iter_mut().enumerate() {
            for (i, x) in a.iter_mut().enumerate() {
                *x += if jumpers.contains(&(i as u32)) && call < 300 {
                    sign * 0.2 * d * [0.6, -0.64, 0.48][k]
                } else {
                    0.004 * d * rng()
                };
            }
        }
        let pr = [&p[0][..], &p[1][..], &p[2][..]];
        let before = near.rebuilds;
        near.update(MidSource::Hash(rule), pr, &blocks, n, d, Exec::Simd);
        if near.rebuilds > before {
            collect(&all, pr, n, d + near.skin, Exec::Scalar, &mut scratch, &mut want);
            assert_eq!(near.pairs, want, "call {call}");
            if call > 0 {
                assert_eq!(near.skin, MID_NEAR_SKIN_MAX * d, "call {call}: the mid path's skin");
            }
            if call < 300 {
                jumping += 1;
            } else {
                after += 1;
            }
        }
        assert_contacts_listed(&all, &p, d, &near.pairs, call);
    }
    // 0.2 d a call against a bound of 0.49 d / 8: a rebuild every call while they jump, few
    // once only the crowd drifts (0.004 d a call).
    assert!(jumping >= 290 && after < 60, "{jumping} rebuilds while jumping, {after} after");
}

#[test]
fn filter_pairs_simd_and_parallel_equal_the_scalar_filter() {
    let mut rng = signed(17);
    let n = 500;
    let mut p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| rng()).collect());
    p[2][77] = f32::NAN;
    let pairs: Vec<(u32, u32)> = (0..n as u32)
        .flat_map(|i| (i + 1..n as u32).filter(move |j| (i + j) % 5 == 0).map(move |j| (i, j)))
        .collect();
    assert!(pairs.len() > 3 * FILTER_CHUNK, "{} pairs", pairs.len());
    let pr = [&p[0][..], &p[1][..], &p[2][..]];
    let r = 0.5;
    let want = brute_near(pairs.iter().copied(), &p, r);
    assert!(want.len() > 100 && want.len() < pairs.len() && want.iter().any(|&(i, j)| i == 77 || j == 77));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        for (simd, parallel) in [(false, false), (true, false), (true, true), (false, true)] {
            let (mut s, mut got) = (ScanScratch::default(), vec![(9, 9)]);
            pool.install(|| filter_pairs(&pairs, pr, n, r, Exec::new(simd, parallel), &mut s, &mut got));
            assert_eq!(got, want, "{threads} threads, simd {simd}, parallel {parallel}");
        }
    }
}

/// The pairs of `pairs` closer than `r` at `p`, or at a NaN distance (the scans' rule), in
/// their order: the reference the scans are held to.
fn brute_near(pairs: impl Iterator<Item = (u32, u32)>, p: &[Vec<f32>; 3], r: f32) -> Vec<(u32, u32)> {
    pairs
        .filter(|&(i, j)| {
            let (i, j) = (i as usize, j as usize);
            let d2: f32 = (0..3).map(|k| (p[k][i] - p[k][j]) * (p[k][i] - p[k][j])).sum();
            d2 < r * r || d2.is_nan()
        })
        .collect()
}

/// Every pair of `cand` closer than `d` at `p` is in the (ordered) near list.
fn assert_contacts_listed(cand: &Neighbours, p: &[Vec<f32>; 3], d: f32, near: &[(u32, u32)], call: usize) {
    for (i, j) in cand.pairs() {
        let (iu, ju) = (i as usize, j as usize);
        let d2: f32 = (0..3).map(|k| (p[k][iu] - p[k][ju]).powi(2)).sum();
        if d2 < d * d {
            assert!(near.binary_search(&(i, j)).is_ok(), "call {call}: contact ({i}, {j}) missed");
        }
    }
}
