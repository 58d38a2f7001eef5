//! Contract: results do not depend on the number of threads (bitwise).

mod common;

use proptest::prelude::*;
use weft::{ClothDesc, Effects, SolverParams, Wind};

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    /// Cloths big enough to split into several parallel chunks (> 4096 particles, > 2048
    /// constraints per colour), 1 vs 2 vs 3 threads.
    #[test]
    fn one_two_three_threads_bitwise_equal(rows in 60u32..90, cols in 60u32..90, substeps in 1u32..4, wind in any::<bool>()) {
        let desc = ClothDesc { rows, cols, spacing: 0.02, ..common::hanging(rows, cols) };
        let effects = Effects { gravity: Some([0.0, -9.81, 0.0]), drag: Some(0.01), wind: wind.then(|| Wind { velocity: [3.0, 0.0, 4.0], gust: 0.5, ..Wind::default() }) };
        let run = |threads: usize| {
            let params = SolverParams { dt: 1.0 / 60.0, substeps, iterations: 2, threads, ..Default::default() };
            let mut w = common::world_with(&desc, params, effects.clone());
            for _ in 0..4 {
                w.step(1.0 / 60.0).unwrap();
            }
            common::state_bits(&w)
        };
        let one = run(1);
        prop_assert_eq!(&one, &run(2));
        prop_assert_eq!(&one, &run(3));
    }
}
