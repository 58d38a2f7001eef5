use super::*;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::Llt;
use faer::sparse::{SparseColMat, Triplet};

/// The reusable solver (its own value placement, factor and workspace) gives faer's
/// one-shot sparse Cholesky solution to rounding, with duplicate entries summed.
#[test]
fn reused_solver_matches_a_fresh_factorisation() {
    let n = 40;
    let mut idx = Vec::new();
    let mut vals = Vec::new();
    let mut r = crate::test_rng::unit(3);
    for i in 0..n {
        idx.push(Pair { row: i, col: i });
        vals.push(1.0 + r() as f64);
    }
    // Chain and skip couplings, each written twice (as the spring loop writes them).
    for (a, b) in (0..n - 1).map(|i| (i + 1, i)).chain((0..n - 3).map(|i| (i + 3, i))) {
        for _ in 0..2 {
            let k = 0.1 + 0.2 * r() as f64;
            for (row, col, v) in [(a, a, k), (b, b, k), (a, b, -k)] {
                idx.push(Pair { row, col });
                vals.push(v);
            }
        }
    }
    let rhs: Vec<f64> = (0..n).map(|_| r() as f64 - 0.5).collect();
    let mut solver = Solver::new(n, &idx).unwrap();
    for round in 0..2 {
        let scaled: Vec<f64> = vals.iter().map(|v| v * (1.0 + round as f64)).collect();
        let mut got = rhs.clone();
        solver.solve(&scaled, &mut got).unwrap();
        let t: Vec<_> = idx.iter().zip(&scaled).map(|(e, &v)| Triplet::new(e.row, e.col, v)).collect();
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &t).unwrap();
        let llt = Llt::try_new_with_symbolic(
            faer::sparse::linalg::solvers::SymbolicLlt::try_new(a.symbolic(), Side::Lower).unwrap(),
            a.as_ref(),
            Side::Lower,
        )
        .unwrap();
        let mut want = rhs.clone();
        llt.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut want, n, 1));
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() <= 1e-12 * (1.0 + w.abs()), "round {round}: {g} vs {w}");
        }
    }
}
