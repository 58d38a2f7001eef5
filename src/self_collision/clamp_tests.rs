use super::*;
use crate::data::particles::Particles;
use crate::self_collision::response::tests::{bits, cloud};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// The speed clamp: SIMD == scalar twin bitwise; afterwards every free particle moves at
    /// most the limit (plus rounding) relative to the mean in a substep, or kept its velocity
    /// because the clamped one would be faster.
    #[test]
    fn clamp_simd_matches_scalar(n in prop_oneof![0usize..40, 4090usize..4110], seed in any::<u64>(), limit_milli in 1u32..50, h_milli in 1u32..60) {
        let base = cloud(n, seed);
        // Each particle its own travel, or one limit for all.
        let own: Vec<f32> = (0..base.padded_len()).map(|i| 0.25 + 0.25 * ((i as u64 ^ seed) % 8) as f32).collect();
        for travel in [&[][..], &own[..]] {
        let cp = ClampParams { mean: [0.5, -1.0, 0.25], limit: limit_milli as f32 * 1e-3, h: h_milli as f32 * 1e-3, travel };
        let run = |simd: bool, par: bool| {
            let mut p = base.clone();
            p.for_chunks(par, |c| clamp_speed(c, &cp, simd));
            p
        };
        let reference = run(false, false);
        prop_assert_eq!(bits(&reference), bits(&run(true, false)));
        prop_assert_eq!(bits(&reference), bits(&run(true, true)));
        let len = |a: [f32; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        for i in 0..n {
            let limit = cp.limit * travel.get(i).copied().unwrap_or(1.0);
            if reference.w[i] > 0.0 {
                let v = [reference.vx[i], reference.vy[i], reference.vz[i]];
                let u = [v[0] - cp.mean[0], v[1] - cp.mean[1], v[2] - cp.mean[2]];
                let m = len(u) * cp.h;
                if m > limit * 1.0001 {
                    prop_assert_eq!(v, [base.vx[i], base.vy[i], base.vz[i]], "particle {} moved on unclamped", i);
                    let clamped: [f32; 3] = std::array::from_fn(|k| cp.mean[k] + u[k] * limit / m);
                    prop_assert!(len(clamped) >= len(v) * 0.9999, "particle {} kept {:?}, slower clamped {:?}", i, v, clamped);
                }
            }
        }
        }
    }
}

/// The clamp slows a particle that outruns the mean and leaves one slower than the mean
/// (stopped by the ground while the rest still falls) alone, on both backends.
#[test]
fn the_clamp_slows_fast_particles_and_never_speeds_one_up() {
    let cp = ClampParams {
        mean: [0.0, -3.0, 0.0],
        limit: 0.001,
        h: 0.01,
        travel: &[],
    };
    for simd in [false, true] {
        let mut p = Particles::new();
        p.push([0.0; 3], [0.0, 0.0, 0.0], 1.0); // resting: clamped it would fall at 2.9 m/s
        p.push([1.0, 0.0, 0.0], [0.0, -6.0, 0.0], 1.0); // falling faster than the mean
        p.push([2.0, 0.0, 0.0], [0.0, -3.05, 0.0], 1.0); // within the limit
        p.push([3.0, 0.0, 0.0], [0.0, -6.0, 0.0], 0.0); // pinned
        p.for_chunks(false, |c| clamp_speed(c, &cp, simd));
        let v = |i: usize| [p.vx[i], p.vy[i], p.vz[i]];
        assert_eq!(v(0), [0.0, 0.0, 0.0], "simd {simd}");
        assert_eq!(p.py[0], 0.0, "simd {simd}: the resting particle's prediction is kept");
        assert!((v(1)[1] + 3.1).abs() < 1e-5, "simd {simd}: {:?}", v(1));
        assert!((p.py[1] + 0.031).abs() < 1e-6, "simd {simd}: {}", p.py[1]);
        assert_eq!(v(2), [0.0, -3.05, 0.0], "simd {simd}");
        assert_eq!(v(3), [0.0, -6.0, 0.0], "simd {simd}");
    }
}
