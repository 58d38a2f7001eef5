use super::*;
use crate::data::particles::Particles;

/// `n` particles, every seventh pinned, with velocities in [-5, 5).
fn cloud(n: usize, seed: u64) -> Particles {
    let mut p = Particles::new();
    let mut r = crate::test_rng::signed(seed | 1);
    for i in 0..n {
        let w = if i % 7 == 0 { 0.0 } else { 1.0 + r().abs() * 10.0 };
        p.push([r(), r(), r()], [r() * 5.0, r() * 5.0, r() * 5.0], w);
    }
    p
}

/// The mean velocity: the same bits serial, parallel on one and two threads, SIMD and scalar,
/// and within the bound of its `f32` block sums of an `f64` running sum over the free
/// particles (pinned ones left out), for sizes around the lane width, the `f32` block and the
/// chunk size. The bound: each `f32` block sum of a lane (at most `F32_RUN` terms) is within
/// `F32_RUN` ulps of the sum of its terms' magnitudes, so the mean is within
/// `F32_RUN ε Σ|v| / count`, plus the `f32` rounding of the result.
#[test]
fn mean_velocity_is_deterministic_and_averages_the_free_particles() {
    for n in [0usize, 1, 3, 5, 9, 63, 64, 65, 520, 4095, 4097, 9001] {
        let p = cloud(n, n as u64 + 3);
        let v = [&p.vx[..], &p.vy[..], &p.vz[..]];
        let serial = mean_velocity(v, &p.w, n, Exec::Simd);
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            for simd in [false, true] {
                let par = pool.install(|| mean_velocity(v, &p.w, n, Exec::new(simd, true)));
                assert_eq!(
                    serial.map(f32::to_bits),
                    par.map(f32::to_bits),
                    "n {n}, {threads} threads, simd {simd}"
                );
            }
        }
        let free: Vec<usize> = (0..n).filter(|&i| p.w[i] > 0.0).collect();
        for (a, got) in serial.iter().enumerate() {
            let (want, bound) = if free.is_empty() {
                (0.0, 0.0)
            } else {
                let k = free.len() as f64;
                let abs = free.iter().map(|&i| (v[a][i] as f64).abs()).sum::<f64>();
                let want = free.iter().map(|&i| v[a][i] as f64).sum::<f64>() / k;
                (
                    want,
                    F32_RUN as f64 * f32::EPSILON as f64 * abs / k + f32::EPSILON as f64 * want.abs(),
                )
            };
            assert!((*got as f64 - want).abs() <= bound, "n {n}: {got} vs {want} (bound {bound})");
        }
    }
}

/// The eight-lane sums of a chunk and their scalar twin give the same bits, with pinned
/// particles, non-finite velocities and every tail length.
#[test]
fn chunk_sums_simd_equals_scalar() {
    for n in [0usize, 1, 7, 8, 9, 63, 64, 65, 71, 130, 4096] {
        let mut p = cloud(n.max(1), n as u64 + 29);
        if n > 40 {
            p.vx[40] = f32::INFINITY;
            p.vy[33] = f32::NAN;
            p.w[33] = 0.0;
        }
        let v = [&p.vx[..n], &p.vy[..n], &p.vz[..n]];
        let (a, b) = (chunk_sums(v, &p.w[..n], true), chunk_sums(v, &p.w[..n], false));
        assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits), "n {n}");
        if n > 40 {
            assert!(a[0].is_infinite() && a[1].is_finite(), "n {n}: {a:?}");
        }
    }
}

/// The mean-velocity sums filled as the step's predict pass fills them (ranges of whole
/// chunks, in any order, the arrays padded past `n`) give the bits of `mean_velocity`; a
/// changed velocity in one chunk changes the result (the sums are overwritten, not kept).
#[test]
fn mean_parts_filled_by_chunk_ranges_equal_mean_velocity() {
    for n in [1usize, 4096, 4097, 9001, 12_289] {
        let mut p = cloud(n, n as u64 + 11);
        let len = p.vx.len();
        let want = mean_velocity([&p.vx[..], &p.vy[..], &p.vz[..]], &p.w, n, Exec::Simd);
        // One range for everything (the serial pass) and single chunks in reverse order.
        let whole = MeanParts::new(n);
        whole.add(0, [&p.vx[..], &p.vy[..], &p.vz[..]], &p.w, n, true);
        assert_eq!(whole.mean().map(f32::to_bits), want.map(f32::to_bits), "n {n}");
        // The chunk from `lo`, every other chunk with the lanes.
        let add_chunk = |parts: &MeanParts, p: &Particles, lo: usize| {
            let hi = (lo + MEAN_CHUNK).min(len);
            let v = [&p.vx[lo..hi], &p.vy[lo..hi], &p.vz[lo..hi]];
            parts.add(lo, v, &p.w[lo..hi], n, (lo / MEAN_CHUNK).is_multiple_of(2));
        };
        let parts = MeanParts::new(n);
        for lo in (0..len).step_by(MEAN_CHUNK).rev() {
            add_chunk(&parts, &p, lo);
        }
        assert_eq!(parts.mean().map(f32::to_bits), want.map(f32::to_bits), "n {n}");
        let i = n - 1;
        p.vx[i] += 1000.0;
        p.w[i] = 1.0;
        add_chunk(&parts, &p, i / MEAN_CHUNK * MEAN_CHUNK);
        let moved = mean_velocity([&p.vx[..], &p.vy[..], &p.vz[..]], &p.w, n, Exec::Simd);
        assert_eq!(parts.mean().map(f32::to_bits), moved.map(f32::to_bits), "n {n}");
        assert_ne!(moved[0], want[0], "n {n}");
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
    /// On random clouds of any length up to two chunks, with random pinned particles and
    /// special velocities (NaN, infinities, 1e30, -0.0, a subnormal) at random places, the
    /// eight-lane sums of a chunk give the scalar twin's bits.
    #[test]
    fn chunk_sums_lanes_equal_the_scalar_twin_on_random_clouds(
        n in 0usize..8200,
        seed in proptest::prelude::any::<u64>(),
        specials in crate::test_rng::specials(4),
    ) {
        let mut p = cloud(n.max(1), seed);
        for (i, a, k) in specials {
            let i = i as usize % n.max(1);
            let v = crate::test_rng::SPECIAL_F32[k];
            match a {
                0 => p.vx[i] = v,
                1 => p.vy[i] = v,
                2 => p.vz[i] = v,
                _ => p.w[i] = 0.0,
            }
        }
        let v = [&p.vx[..n], &p.vy[..n], &p.vz[..n]];
        let (a, b) = (chunk_sums(v, &p.w[..n], true), chunk_sums(v, &p.w[..n], false));
        proptest::prop_assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
    }
}
