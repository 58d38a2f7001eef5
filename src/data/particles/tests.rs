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

/// The element-wise chunks cut any particle count into chunks of whole [`CHUNK_ALIGN`] runs
/// (the last one shorter) that two threads share about evenly: the first half of the chunks
/// (rounded up) holds at most 57% of the particles, and up to four times [`CHUNK`] makes two
/// chunks (one join). Up to [`CHUNK`] particles are one chunk.
#[test]
fn chunks_are_aligned_and_split_evenly_between_two_threads() {
    for len in (8..128 * CHUNK).step_by(8) {
        let c = chunk_len(len);
        let count = len.div_ceil(c);
        if len <= CHUNK {
            assert_eq!(c, len);
            continue;
        }
        assert!(c.is_multiple_of(CHUNK_ALIGN) && c <= 2 * CHUNK, "{len}: chunks of {c}");
        let larger = (c * count.div_ceil(2)).min(len);
        assert!(larger * 100 <= 57 * len, "{len}: {count} chunks of {c}");
        if len <= 4 * CHUNK {
            assert_eq!(count, 2, "{len}");
        }
    }
}

/// A pass over two chunks (one join) and one over more hand out the same particles as the
/// serial pass, with the right starts.
#[test]
fn parallel_chunks_cover_every_particle_once() {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    for n in [CHUNK + 8, 2 * CHUNK, 4 * CHUNK + 24, 9 * CHUNK + 8] {
        let mut p = Particles::new();
        for i in 0..n {
            p.push([i as f32, 0.0, 0.0], [0.0; 3], 1.0);
        }
        pool.install(|| {
            p.for_chunks(true, |c| {
                // The padding past `n` holds zeros.
                for (k, x) in c.x.iter_mut().enumerate().filter(|(k, _)| c.start + k < n) {
                    assert_eq!(*x, (c.start + k) as f32);
                    *x = -*x - 1.0;
                }
            })
        });
        assert!(p.x[..n].iter().enumerate().all(|(i, x)| *x == -(i as f32) - 1.0), "{n}");
    }
}
