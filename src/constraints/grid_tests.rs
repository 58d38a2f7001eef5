//! Tests of the structured grid kernels: the classes partition a grid into colours, and the
//! SIMD sweep equals the scalar twin bit for bit on any thread count.

use super::*;
use crate::constraints::distance::{DistanceInput, DistanceSet};
use crate::data::lanes::round_up;
use crate::model::cloth::ClothDesc;

/// A cloth's constraints as world inputs, plus positions jittered off rest and masses, a few
/// of them zero (pins; the builder's pins would drop the edges between two of them).
fn cloth(rows: u32, cols: u32, seed: u64) -> (Vec<DistanceInput>, Vec<f32>, [Vec<f32>; 3]) {
    let b = ClothDesc {
        rows,
        cols,
        spacing: 0.01,
        tethers: None,
        pins: Vec::new(),
        ..Default::default()
    }
    .build()
    .unwrap();
    let mut rnd = crate::test_rng::unit(seed);
    let len = round_up(b.positions.len() + 1);
    let mut pos = [vec![0.0; len], vec![0.0; len], vec![0.0; len]];
    let mut w = vec![0.0; len];
    for (i, q) in b.positions.iter().enumerate() {
        for k in 0..3 {
            pos[k][i] = q[k] + 0.003 * (rnd() - 0.5);
        }
        w[i] = if rnd() < 0.05 { 0.0 } else { b.inv_mass[i] * (0.5 + rnd()) };
    }
    let cons = b
        .edges
        .iter()
        .map(|e| DistanceInput {
            a: e.a,
            b: e.b,
            rest: e.rest,
            compliance: e.compliance,
        })
        .collect();
    (cons, w, pos)
}

#[test]
fn classes_partition_the_grid_into_colours() {
    for (rows, cols) in [(1, 1), (1, 5), (2, 2), (3, 7), (9, 4), (17, 33)] {
        let mut seen = std::collections::HashSet::new();
        for cl in &CLASSES {
            let mut used = std::collections::HashSet::new();
            for k in 0..cl.row_count(rows, cols) {
                for j in 0..cl.per_row(cols) {
                    let (a, b) = cl.pair(cols, k, j);
                    assert!(a < rows * cols && b < rows * cols && a != b);
                    assert!(used.insert(a) && used.insert(b), "{rows}x{cols}: a class shares a particle");
                    assert!(seen.insert((a, b)), "{rows}x{cols}: a pair in two classes");
                    assert_eq!(cl.locate(rows, cols, a, b), Some((k, j)));
                }
            }
        }
        // Every builder edge is in exactly one class.
        let (cons, _, _) = cloth(rows, cols, 1);
        let all: std::collections::HashSet<_> = cons.iter().map(|c| (c.a, c.b)).collect();
        assert_eq!(all, seen, "{rows}x{cols}");
    }
}

#[test]
fn only_whole_uniform_classes_are_structured() {
    let spec = GridSpec {
        first: 0,
        rows: 6,
        cols: 6,
    };
    let (cons, _, _) = cloth(6, 6, 2);
    let quad = |c: &DistanceInput| (c.a, c.b, c.rest, c.compliance);
    assert!(classify(spec, cons.iter().map(quad)).is_some());
    assert!(classify(spec, cons[1..].iter().map(quad)).is_none(), "a missing edge");
    let mut odd = cons.clone();
    odd[3].rest *= 1.5;
    assert!(classify(spec, odd.iter().map(quad)).is_none(), "a rest length of its own");
    let mut twice = cons.clone();
    twice.push(cons[0]);
    assert!(classify(spec, twice.iter().map(quad)).is_none(), "an edge twice");
    let shifted = GridSpec { first: 1, ..spec };
    assert!(classify(shifted, cons.iter().map(quad)).is_none(), "not this grid's edges");
    for bad in [(0, 6), (6, 0), (1 << 20, 1 << 20)] {
        let spec = GridSpec {
            first: 0,
            rows: bad.0,
            cols: bad.1,
        };
        assert!(classify(spec, cons.iter().map(quad)).is_none(), "{bad:?}");
    }
}

/// SIMD (serial, parallel on 1, 2 and 3 threads) equals the scalar twin over the explicit
/// arrays, bit for bit, in positions and multipliers, through kept and unkept resets. The
/// grid of 4100 columns has bands of four rows that end inside blocks of eight particles,
/// seven of them: on three threads a wave part lies between two others. The grid of 200 rows
/// has 13 bands: six parts on two and three threads, so a thread runs neighbouring parts one
/// after the other.
#[test]
fn structured_sweep_matches_scalar_bitwise() {
    for (rows, cols) in [
        (2, 3),
        (5, 17),
        (7, 23),
        (9, 35),
        (40, 37),
        (64, 64),
        (70, 100),
        (26, 4100),
        (200, 40),
    ] {
        assert_sweep_matches_scalar(rows, cols, 3 + rows as u64, &[(false, 1), (true, 1), (true, 2), (true, 3)]);
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
    /// The same on random grid shapes: every row length meets the row's last block (runs and
    /// both window splits, with and without a constraint beyond the last window).
    #[test]
    fn structured_sweep_matches_scalar_on_any_shape(rows in 2u32..14, cols in 2u32..90, seed in 0u64..1000) {
        assert_sweep_matches_scalar(rows, cols, seed, &[(false, 1), (true, 2)]);
    }
}

/// Five sweeps of a `rows x cols` cloth by the scalar twin and by SIMD on each
/// `(parallel, threads)` of `runs`: the same bits in positions and multipliers.
fn assert_sweep_matches_scalar(rows: u32, cols: u32, seed: u64, runs: &[(bool, usize)]) {
    let (cons, w, pos) = cloth(rows, cols, seed);
    let n = (rows * cols) as usize;
    let spec = GridSpec { first: 0, rows, cols };
    let sink = (round_up(n + 1) - 1) as u32;
    let set = DistanceSet::with_grids(&cons, n, sink, &[(spec, 0..cons.len())]);
    assert!(set.colours.iter().all(|c| c.grid.is_some()), "{rows}x{cols}: all structured");
    assert_eq!(set.len(), cons.len());
    let run = |simd: bool, parallel: bool, threads: usize| {
        let (mut s, mut p) = (set.clone(), pos.clone());
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            for sweep in 0..5 {
                match sweep {
                    1 => s.reset_lambda_unkept(),
                    2 | 4 => s.reset_lambda(),
                    _ => {}
                }
                let [x, y, z] = &mut p;
                if simd {
                    s.solve_simd(x, y, z, &w, 3.6e5, parallel);
                } else {
                    s.solve_scalar(x, y, z, &w, 3.6e5);
                }
            }
        });
        let bits = p.iter().flat_map(|a| a.iter().map(|f| f.to_bits())).collect::<Vec<_>>();
        let lambda = s
            .colours
            .iter()
            .flat_map(|c| c.lambda.iter().map(|l| l.to_bits()))
            .collect::<Vec<_>>();
        (bits, lambda)
    };
    let want = run(false, false, 1);
    let start = pos.iter().flat_map(|a| a.iter().map(|f| f.to_bits())).collect::<Vec<_>>();
    assert!(want.0 != start, "the sweeps moved the particles");
    // The stretch classes (no compliance) keep no multipliers: theirs stay zero, the others'
    // are written.
    let mut at = 0;
    let (mut rigid, mut soft) = (0, 0);
    for c in &set.colours {
        let lam = &want.1[at..at + c.lambda.len()];
        at += c.lambda.len();
        if c.grid.as_ref().is_some_and(|g| !g.keeps_multipliers()) {
            assert!(lam.iter().all(|&l| l == 0), "{rows}x{cols}: a rigid colour's multipliers");
            rigid += 1;
        } else if lam.iter().any(|&l| l != 0) {
            soft += 1;
        }
    }
    assert!(
        rigid > 0 && soft > 0,
        "{rows}x{cols}: {rigid} rigid colours, {soft} with multipliers"
    );
    for &(parallel, threads) in runs {
        assert!(
            want == run(true, parallel, threads),
            "{rows}x{cols} parallel {parallel} threads {threads}"
        );
    }
}

/// Each laid-out colour shares no particle between its constraints, and the groups a pass
/// runs in parallel (bands, or seams) share no particle across all the pass's colours.
#[test]
fn bands_and_seams_share_no_particle() {
    for (rows, cols) in [(40, 37), (70, 100), (9, 300), (33, 2000)] {
        let (cons, _, _) = cloth(rows, cols, 5);
        let spec = GridSpec { first: 0, rows, cols };
        let classes = classify(spec, cons.iter().map(|c| (c.a, c.b, c.rest, c.compliance))).unwrap();
        let colours = layout(spec, &classes);
        assert_eq!(colours.iter().map(|(_, p)| p.len()).sum::<usize>(), cons.len());
        for seam in [false, true] {
            let pass: Vec<_> = colours.iter().filter(|(g, _)| g.seam == seam).collect();
            let Some((first, _)) = pass.first() else { continue };
            let mut owner = std::collections::HashMap::new();
            for (g, pos) in &pass {
                assert_eq!(g.group_count(), first.group_count());
                let per_row = g.per_row() as usize;
                let mut used = std::collections::HashSet::new();
                for q in 0..g.group_count() {
                    for at in g.group(q) {
                        for &k in &pos[at * per_row..(at + 1) * per_row] {
                            let (a, b) = (cons[k].a, cons[k].b);
                            assert!(used.insert(a) && used.insert(b), "{rows}x{cols}: colour repeats a particle");
                            for p in [a, b] {
                                assert_eq!(*owner.entry(p).or_insert(q), q, "{rows}x{cols} seam {seam}: two groups share {p}");
                            }
                        }
                    }
                }
            }
        }
    }
}

/// A compliance changed for a whole colour is taken by its structured kernel; a colour whose
/// values no longer agree runs through its block plan; either way SIMD equals scalar.
#[test]
fn refreshed_colours_keep_simd_equal_to_scalar() {
    let (rows, cols) = (40, 40);
    let (cons, w, pos) = cloth(rows, cols, 11);
    let n = (rows * cols) as usize;
    let spec = GridSpec { first: 0, rows, cols };
    let mut set = DistanceSet::with_grids(&cons, n, (round_up(n + 1) - 1) as u32, &[(spec, 0..cons.len())]);
    let real = set.colours[0].real;
    set.colours[0].compliance[..real].fill(2e-4);
    set.colours[1].compliance[0] = 5e-4;
    set.refresh_grids();
    assert_eq!(set.colours[0].grid.as_ref().map(|g| g.compliance), Some(2e-4));
    assert!(set.colours[1].grid.is_none() && set.colours[2].grid.is_some());
    let run = |simd: bool| {
        let (mut s, mut p) = (set.clone(), pos.clone());
        let [x, y, z] = &mut p;
        for _ in 0..2 {
            if simd {
                s.solve_simd(x, y, z, &w, 1e5, true);
            } else {
                s.solve_scalar(x, y, z, &w, 1e5);
            }
        }
        p
    };
    assert!(run(true) == run(false));
}
