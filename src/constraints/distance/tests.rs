//! Tests of the distance constraints: SIMD against the scalar twin, block plans, lazy reset.

use super::*;
use proptest::prelude::*;

fn random_set(n: usize, m: usize, seed: u64) -> (Vec<DistanceInput>, Vec<f32>, [Vec<f32>; 3]) {
    let mut rnd = crate::test_rng::unit(seed);
    let len = round_up(n + 1);
    let mut pos = [vec![0.0; len], vec![0.0; len], vec![0.0; len]];
    let mut w = vec![0.0; len];
    for i in 0..n {
        for p in pos.iter_mut() {
            p[i] = rnd() * 2.0 - 1.0;
        }
        w[i] = if rnd() < 0.1 { 0.0 } else { 0.1 + rnd() * 10.0 };
    }
    let mut cons = Vec::new();
    for _ in 0..m {
        let a = (rnd() * n as f32) as u32 % n as u32;
        let b = (rnd() * n as f32) as u32 % n as u32;
        if a != b {
            cons.push(DistanceInput {
                a,
                b,
                rest: rnd(),
                compliance: if rnd() < 0.3 { 0.0 } else { rnd() * 1e-3 },
            });
        }
    }
    (cons, w, pos)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// The SIMD kernel (serial and parallel) equals the scalar twin bit for bit.
    #[test]
    fn simd_matches_scalar_bitwise(n in 2usize..300, m in 0usize..2000, seed in 1u64..u64::MAX, inv_h2 in 1.0f32..1e6) {
        let (cons, w, pos) = random_set(n, m, seed);
        let set = DistanceSet::new(&cons, n, (round_up(n + 1) - 1) as u32);
        let mut s = (set.clone(), pos.clone());
        let mut v = (set.clone(), pos.clone());
        let mut par = (set, pos);
        for sweep in 0..3 {
            if sweep == 1 {
                // A new substep between sweeps: the lazy reset must act like zeroing.
                s.0.reset_lambda();
                v.0.reset_lambda();
                par.0.reset_lambda();
            }
            let [x, y, z] = &mut s.1;
            s.0.solve_scalar(x, y, z, &w, inv_h2);
            let [x, y, z] = &mut v.1;
            v.0.solve_simd(x, y, z, &w, inv_h2, false);
            let [x, y, z] = &mut par.1;
            par.0.solve_simd(x, y, z, &w, inv_h2, true);
        }
        for k in 0..3 {
            let bits = |a: &Vec<f32>| a.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
            prop_assert_eq!(bits(&s.1[k]), bits(&v.1[k]));
            prop_assert_eq!(bits(&s.1[k]), bits(&par.1[k]));
        }
    }
}

/// Grid edges as the cloth builder makes them: stretch, shear and bend.
fn grid_set(side: u32, seed: u64) -> (Vec<DistanceInput>, Vec<f32>, [Vec<f32>; 3]) {
    let mut rnd = crate::test_rng::unit(seed);
    let n = (side * side) as usize;
    let len = round_up(n + 1);
    let mut pos = [vec![0.0; len], vec![0.0; len], vec![0.0; len]];
    let mut w = vec![0.0; len];
    let mut cons = Vec::new();
    for r in 0..side {
        for c in 0..side {
            let i = (r * side + c) as usize;
            pos[0][i] = c as f32 * 0.01 + 0.002 * rnd();
            pos[1][i] = 0.002 * rnd();
            pos[2][i] = r as f32 * 0.01 + 0.002 * rnd();
            w[i] = if r == 0 { 0.0 } else { 1.0 + rnd() };
            let id = |r: u32, c: u32| r * side + c;
            let mut push = |a, b, rest| {
                cons.push(DistanceInput {
                    a,
                    b,
                    rest,
                    compliance: 1e-6 * rnd(),
                })
            };
            for (dr, dc, rest) in [(0, 1, 0.01), (1, 0, 0.01), (1, 1, 0.014), (0, 2, 0.02), (2, 0, 0.02)] {
                if r + dr < side && c + dc < side {
                    push(id(r, c), id(r + dr, c + dc), rest);
                }
            }
            if r + 1 < side && c + 1 < side {
                push(id(r, c + 1), id(r + 1, c), 0.014);
            }
        }
    }
    (cons, w, pos)
}

/// On a grid most blocks read contiguous runs or windows, and the SIMD kernel (serial and
/// in parallel chunks, 1 and 2 threads) still equals the scalar twin bit for bit.
#[test]
fn grid_blocks_are_planned_and_match_scalar_bitwise() {
    use crate::constraints::blocks::{GATHER, RUN};
    let side = 110;
    let (cons, w, pos) = grid_set(side, 7);
    let n = (side * side) as usize;
    let set = DistanceSet::new(&cons, n, (round_up(n + 1) - 1) as u32);
    let blocks: Vec<_> = set.colours.iter().flat_map(|c| c.blocks.iter().map(|b| b.kind)).collect();
    let count = |f: &dyn Fn(u32) -> bool| blocks.iter().filter(|&&k| f(k)).count();
    let (runs, windows, gathers) = (count(&|k| k == RUN), count(&|k| k > RUN), count(&|k| k == GATHER));
    assert!(
        runs > blocks.len() / 3 && windows > blocks.len() / 4,
        "runs {runs} windows {windows} of {}",
        blocks.len()
    );
    assert!(gathers < blocks.len() / 4, "gathers {gathers} of {}", blocks.len());
    assert!(set.colours.iter().any(|c| c.a.len() > 2 * CHUNK), "parallel chunks exercised");
    let bits = |p: &[Vec<f32>; 3]| p.iter().flat_map(|a| a.iter().map(|f| f.to_bits())).collect::<Vec<_>>();
    let run = |simd: bool, parallel: bool, threads: usize| {
        let (mut s, mut p) = (set.clone(), pos.clone());
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            for sweep in 0..3 {
                if sweep == 2 {
                    s.reset_lambda();
                }
                let [x, y, z] = &mut p;
                if simd {
                    s.solve_simd(x, y, z, &w, 3.6e5, parallel);
                } else {
                    s.solve_scalar(x, y, z, &w, 3.6e5);
                }
            }
        });
        (
            bits(&p),
            s.colours
                .iter()
                .flat_map(|c| c.lambda.iter().map(|l| l.to_bits()))
                .collect::<Vec<_>>(),
        )
    };
    let want = run(false, false, 1);
    assert_eq!(want, run(true, false, 1));
    assert_eq!(want, run(true, true, 1));
    assert_eq!(want, run(true, true, 2));
}

/// The lazy reset gives the bits of explicitly zeroed multipliers, SIMD and scalar.
#[test]
fn lazy_reset_equals_zeroed_multipliers() {
    let (cons, w, pos) = grid_set(40, 3);
    let n = 1600;
    let mut set = DistanceSet::new(&cons, n, (round_up(n + 1) - 1) as u32);
    let mut p0 = pos.clone();
    let [x, y, z] = &mut p0;
    set.solve_simd(x, y, z, &w, 1e4, false);
    for simd in [false, true] {
        let (mut lazy, mut eager) = (set.clone(), set.clone());
        let (mut pl, mut pe) = (p0.clone(), p0.clone());
        lazy.reset_lambda();
        eager.colours.iter_mut().for_each(|c| c.lambda.fill(0.0));
        for (s, p) in [(&mut lazy, &mut pl), (&mut eager, &mut pe)] {
            let [x, y, z] = p;
            if simd {
                s.solve_simd(x, y, z, &w, 1e4, false);
            } else {
                s.solve_scalar(x, y, z, &w, 1e4);
            }
        }
        assert!(pl == pe && lazy.colours == eager.colours, "simd {simd}");
    }
}

#[test]
fn rigid_constraint_converges_to_rest_length() {
    let cons = [DistanceInput {
        a: 0,
        b: 1,
        rest: 1.0,
        compliance: 0.0,
    }];
    let set = DistanceSet::new(&cons, 2, 7);
    let mut s = set.clone();
    let mut x = vec![0.0; 8];
    let mut y = vec![0.0; 8];
    let mut z = vec![0.0; 8];
    x[1] = 3.0;
    let w = [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    s.solve_simd(&mut x, &mut y, &mut z, &w, 1.0, false);
    assert!((x[1] - x[0] - 1.0).abs() < 1e-6);
    assert!((x[0] - 1.0).abs() < 1e-6, "equal masses move equally: {}", x[0]);
}

#[test]
fn coincident_particles_stay_finite() {
    let cons = [DistanceInput {
        a: 0,
        b: 1,
        rest: 1.0,
        compliance: 0.0,
    }];
    let mut s = DistanceSet::new(&cons, 2, 7);
    let (mut x, mut y, mut z) = (vec![0.5; 8], vec![0.5; 8], vec![0.5; 8]);
    let w = [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    s.solve_simd(&mut x, &mut y, &mut z, &w, 1.0, false);
    assert!(x.iter().chain(&y).chain(&z).all(|v| v.is_finite()));
}
