//! The mean velocity of the free particles (`w > 0`), for the speed clamp and the travels:
//! summed over fixed chunks so that it has the same bits on any number of threads, and in a
//! predict pass chunk by chunk while the velocities are in cache ([`MeanParts`]).

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use crate::data::exec::Exec;
use crate::data::lanes::{load, F32s, LANES};

/// Particles a partial sum of the mean velocity covers (the sums are added in this order): the
/// element-wise passes' chunks start on its multiples, so they fill whole partial sums.
pub(crate) const MEAN_CHUNK: usize = 256;

const _: () = assert!(crate::data::particles::CHUNK_ALIGN.is_multiple_of(MEAN_CHUNK));

/// Mean velocity of the free particles (`w > 0`) among the first `n`: f64 sums over fixed
/// chunks of [`MEAN_CHUNK`] particles, added in chunk order, so parallel and serial give the
/// same bits ([`MeanParts`]; the step also fills them inside its predict pass).
///
/// Within a chunk the particles are summed in eight lanes, `f32` over blocks of 64 particles
/// and `f64` across blocks ([`chunk_sums`]); every path uses this one summation.
#[cfg(test)]
pub(crate) fn mean_velocity(v: [&[f32]; 3], w: &[f32], n: usize, exec: Exec) -> [f32; 3] {
    mean_velocity_in(&mut MeanParts::default(), v, w, n, exec)
}

/// [`mean_velocity`] with its chunk sums in `parts` (resized, reused: no allocation once it has
/// held `n` particles).
pub(crate) fn mean_velocity_in(parts: &mut MeanParts, v: [&[f32]; 3], w: &[f32], n: usize, exec: Exec) -> [f32; 3] {
    let (parallel, simd) = (exec.parallel(), exec.simd());
    parts.reset(n);
    let parts = &*parts;
    let chunks = n.div_ceil(MEAN_CHUNK);
    let one = |k: usize| {
        let (lo, hi) = (k * MEAN_CHUNK, ((k + 1) * MEAN_CHUNK).min(n));
        parts.add(lo, [&v[0][lo..hi], &v[1][lo..hi], &v[2][lo..hi]], &w[lo..hi], n, simd);
    };
    if parallel && chunks > 1 {
        (0..chunks).into_par_iter().for_each(one);
    } else {
        (0..chunks).for_each(one);
    }
    parts.mean()
}

/// The per-chunk partial sums of [`mean_velocity`] (`Σ vx, Σ vy, Σ vz, count` of the free
/// particles of each [`MEAN_CHUNK`]-particle chunk, as f64 bits), filled by the chunks of a
/// pass in any order and on any thread, then added in chunk order by [`MeanParts::mean`].
#[derive(Debug, Default)]
pub(crate) struct MeanParts(Vec<[AtomicU64; 4]>);

/// A clone is empty scratch: the sums live only within one pass.
impl Clone for MeanParts {
    fn clone(&self) -> Self {
        MeanParts::default()
    }
}

impl MeanParts {
    /// Zero sums for `n` particles.
    #[cfg(test)]
    pub(crate) fn new(n: usize) -> Self {
        MeanParts((0..n.div_ceil(MEAN_CHUNK)).map(|_| Default::default()).collect())
    }

    /// Zero sums for `n` particles, reusing the storage (it grows only past its largest `n`).
    pub(crate) fn reset(&mut self, n: usize) {
        self.0.resize_with(n.div_ceil(MEAN_CHUNK), Default::default);
        for slot in &mut self.0 {
            for a in slot.iter_mut() {
                *a.get_mut() = 0;
            }
        }
    }

    /// Adds the particles of a range starting at particle `start` (a multiple of
    /// [`MEAN_CHUNK`]; `v`, `w` the range's slices), those below `n` only. Every chunk must be
    /// added by exactly one call. Eight particles at a time when `simd` (the same bits).
    pub(crate) fn add(&self, start: usize, v: [&[f32]; 3], w: &[f32], n: usize, simd: bool) {
        let len = w.len().min(n.saturating_sub(start));
        for lo in (0..len).step_by(MEAN_CHUNK) {
            let hi = (lo + MEAN_CHUNK).min(len);
            let sums = chunk_sums([&v[0][lo..hi], &v[1][lo..hi], &v[2][lo..hi]], &w[lo..hi], simd);
            if let Some(slot) = self.0.get((start + lo) / MEAN_CHUNK) {
                for (a, s) in slot.iter().zip(sums) {
                    a.store(s.to_bits(), Ordering::Relaxed);
                }
            }
        }
    }

    /// The mean: the chunks' sums added in chunk order, then divided by the count (zero when
    /// no particle is free).
    pub(crate) fn mean(&self) -> [f32; 3] {
        let mut t = [0.0f64; 4];
        for slot in &self.0 {
            for (t, a) in t.iter_mut().zip(slot) {
                *t += f64::from_bits(a.load(Ordering::Relaxed));
            }
        }
        if t[3] > 0.0 {
            [(t[0] / t[3]) as f32, (t[1] / t[3]) as f32, (t[2] / t[3]) as f32]
        } else {
            [0.0; 3]
        }
    }
}

/// Lane-width groups a lane sums in `f32` before the sums are added to the `f64` ones
/// ([`chunk_sums`]: a block of `F32_RUN LANES` particles).
const F32_RUN: usize = 8;

/// `Σ vx, Σ vy, Σ vz, count` over the free particles of one chunk (see [`mean_velocity`]):
/// eight particles at a time when `simd`, else one by one (the twin; the same bits).
///
/// Particle `i` of the chunk goes to lane `i mod LANES`. The lanes add in `f32` over a block
/// of `F32_RUN` groups, then each lane's block sum is added to the lane's `f64` sum; the
/// lanes are combined at the end as a pairwise tree. A pinned particle adds `+0` (its bits
/// masked, no branch). Each `f32` block sum has at most `F32_RUN` terms a lane, so the mean
/// is within a few `f32` ulps of the velocities' magnitude of the exact mean: the order of
/// the rounding of the clamp's own `v - mean`.
fn chunk_sums(v: [&[f32]; 3], w: &[f32], simd: bool) -> [f64; 4] {
    let mut s = [[0.0f64; LANES]; 3];
    let mut count = 0u32;
    let full = w.len() / LANES * LANES;
    let mut acc = [[0.0f32; LANES]; 3];
    let keep = |free: bool, v: f32| f32::from_bits(v.to_bits() & u32::from(free).wrapping_neg());
    let flush = |acc: &mut [[f32; LANES]; 3], s: &mut [[f64; LANES]; 3]| {
        for (sc, ac) in s.iter_mut().zip(acc.iter_mut()) {
            for (a, b) in sc.iter_mut().zip(ac.iter_mut()) {
                *a += f64::from(*b);
                *b = 0.0;
            }
        }
    };
    let mut i = 0;
    while i < full {
        let end = (i + F32_RUN * LANES).min(full);
        if simd {
            let mut a = acc.map(F32s::from);
            while i < end {
                let free = load(w, i).simd_gt(F32s::ZERO);
                count += free.to_bitmask().count_ones();
                for (a, c) in a.iter_mut().zip(v) {
                    *a += free & load(c, i);
                }
                i += LANES;
            }
            acc = a.map(|a| a.to_array());
        } else {
            while i < end {
                for l in 0..LANES {
                    let free = w[i + l] > 0.0;
                    count += u32::from(free);
                    for (a, c) in acc.iter_mut().zip(v) {
                        a[l] += keep(free, c[i + l]);
                    }
                }
                i += LANES;
            }
        }
        flush(&mut acc, &mut s);
    }
    for (l, i) in (full..w.len()).enumerate() {
        let free = w[i] > 0.0;
        count += u32::from(free);
        for (a, c) in acc.iter_mut().zip(v) {
            a[l] += keep(free, c[i]);
        }
    }
    flush(&mut acc, &mut s);
    let sum = |a: &[f64; LANES]| {
        let mut a = *a;
        let mut k = LANES;
        while k > 1 {
            k /= 2;
            for j in 0..k {
                a[j] = a[2 * j] + a[2 * j + 1];
            }
        }
        a[0]
    };
    [sum(&s[0]), sum(&s[1]), sum(&s[2]), f64::from(count)]
}

#[cfg(test)]
#[path = "mean_tests.rs"]
mod tests;
