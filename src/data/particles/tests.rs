//! Tests of the particle arrays, the chunked passes and the finite check.

use super::*;
use crate::data::lanes::LANES;

#[test]
fn padding_always_leaves_a_sink() {
    let mut p = Particles::new();
    assert_eq!(p.padded_len(), LANES);
    for i in 0..20 {
        p.push([i as f32, 0.0, 0.0], [0.0; 3], 1.0);
        assert_eq!(p.count(), i + 1);
        assert!(p.padded_len() > p.count());
        assert_eq!(p.padded_len() % LANES, 0);
        assert_eq!(p.w[p.sink() as usize], 0.0);
    }
    assert_eq!(p.x[19], 19.0);
    assert_eq!(p.px, p.x);
}

/// The SIMD finite check equals its scalar twin, for a NaN or an infinity at every place in
/// every array (the four sums' runs, the groups after them and the tail included) and past
/// the checked length.
#[test]
fn finite_check_finds_every_bad_value() {
    let n = 11 * LANES + 5;
    let base: Vec<Vec<f32>> = (0..6).map(|k| (0..n + 3).map(|i| (i * 7 + k) as f32 * -0.37).collect()).collect();
    let views = |v: &Vec<Vec<f32>>| -> Vec<Vec<f32>> { v.clone() };
    let check = |v: &Vec<Vec<f32>>| {
        let r: Vec<&[f32]> = v.iter().map(|a| &a[..]).collect();
        (chunk_finite_simd(&r, n), chunk_finite_scalar(&r, n))
    };
    assert_eq!(check(&base), (true, true));
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        for k in 0..6 {
            for i in 0..n + 3 {
                let mut v = views(&base);
                v[k][i] = bad;
                let expect = i >= n;
                assert_eq!(check(&v), (expect, expect), "{bad} in array {k} at {i}");
            }
        }
    }
}

/// The chunks that `for_chunks_saving` hands out hold the state before the kernel changes
/// it, serially and in parallel.
#[test]
fn saving_pass_keeps_the_state_before_the_kernel() {
    let mut p = Particles::new();
    for i in 0..3 * CHUNK + 11 {
        p.push([i as f32, -(i as f32), 0.5], [1.0, 2.0, i as f32], 1.0);
    }
    let before = p.clone();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    for parallel in [false, true] {
        let mut q = before.clone();
        let mut saved: [Vec<f32>; 6] = Default::default();
        pool.install(|| {
            q.for_chunks_saving(parallel, &mut saved, |mut c, s| {
                c.save_state(s);
                let c = c.reborrow();
                c.x.iter_mut().for_each(|x| *x += 1.0);
                c.vz.iter_mut().for_each(|v| *v = -*v);
            })
        });
        assert_eq!(
            saved,
            [&before.x, &before.y, &before.z, &before.vx, &before.vy, &before.vz].map(|a| a.clone())
        );
        assert_eq!(q.x[5], before.x[5] + 1.0);
        assert_eq!(q.vz[CHUNK + 3], -before.vz[CHUNK + 3]);
    }
}
