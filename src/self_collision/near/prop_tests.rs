//! Property test of the near list's exactness under random motion: a drifting crowd, a few
//! particles jumping back and forth, and now and then a jump of everyone; from the hash (the mid list refreshed per particle) or from
//! candidate lists with and without a mid list.

use super::*;
use crate::data::exec::Exec;
use crate::self_collision::near::scan::{collect, ScanScratch};
use crate::test_rng::signed;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]
    /// At every call every pair closer than `d` is in the near list, and at every build the
    /// list is the one built from every candidate with the list's radius.
    #[test]
    fn near_list_holds_every_contact_under_random_motion(n in 40usize..200, seed in 1u64..u64::MAX,
            jumpers in 0usize..6, jump_pct in 5u32..45, drift_pct in 0u32..3, source in 0u8..3) {
        let mut rng = signed(seed);
        let d = 0.1f32;
        let mut p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 0.4 * rng()).collect());
        let rest = [(0..n).map(|i| 100.0 * i as f32).collect::<Vec<f32>>(), vec![0.0; n], vec![0.0; n]];
        let cloth_of = vec![0u32; n];
        let rule = RestRule { rest: [&rest[0], &rest[1], &rest[2]], cloth_of: &cloth_of, skip: 3.0 * d };
        let mut all = Neighbours::new();
        all.fill_serial(n, |i, buf| buf.extend((i + 1..n).map(|j| j as u32))).unwrap();
        let blocks: Vec<u32> = (0..n.div_ceil(LANES) as u32).collect();
        let jumping: Vec<usize> = (0..jumpers).map(|k| (k * 37 + seed as usize) % n).collect();
        let dirs: Vec<[f32; 3]> = jumping.iter().map(|_| [rng(), rng(), rng()]).collect();
        let (jump, drift) = (jump_pct as f32 / 100.0 * d, drift_pct as f32 / 100.0 * d);
        let mut near = NearList::default();
        let (mut scratch, mut want) = (ScanScratch::default(), Vec::new());
        for call in 0..80usize {
            let sign = if call % 2 == 0 { 1.0 } else { -1.0 };
            for i in 0..n {
                let k = jumping.iter().position(|&j| j == i);
                for (a, c) in p.iter_mut().enumerate() {
                    c[i] += match k {
                        _ if call % 30 == 29 => 0.6 * d * rng(),
                        Some(k) => sign * jump * dirs[k][a],
                        None => drift * rng(),
                    };
                }
            }
            let pr = [&p[0][..], &p[1][..], &p[2][..]];
            let before = near.rebuilds;
            let src = match source {
                0 => MidSource::Hash(rule),
                1 => MidSource::Candidates { cand: &all, reach: 10.0 * d },
                _ => MidSource::Candidates { cand: &all, reach: 3.0 * d },
            };
            near.update(src, pr, &blocks, n, d, Exec::Simd);
            if near.rebuilds > before {
                collect(&all, pr, n, d + near.skin, Exec::Scalar, &mut scratch, &mut want);
                prop_assert_eq!(&near.pairs, &want, "call {}", call);
            }
            for (i, j) in all.pairs() {
                let (iu, ju) = (i as usize, j as usize);
                let d2: f32 = (0..3).map(|k| (p[k][iu] - p[k][ju]).powi(2)).sum();
                if d2 < d * d {
                    prop_assert!(near.pairs.binary_search(&(i, j)).is_ok(), "call {}: contact ({}, {}) missed", call, i, j);
                }
            }
        }
    }
}
