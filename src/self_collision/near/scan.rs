//! The scans of the near list (module `self_near`): the candidate pairs of CSR lists closer
//! than a radius at the predicted positions, eight candidates of a particle at a time, serial
//! or in parallel over ranges of particles cut by candidate entries (the same list either
//! way). Used twice: the mid list from the candidate lists, the near list from the mid list.

use crate::data::exec::Exec;
use crate::data::lanes::{idx8, F32s, Idx8, LANES};
use crate::self_collision::neighbours::Neighbours;
use rayon::prelude::*;

/// Reused buffers of the scans.
#[derive(Clone, Debug, Default)]
pub(crate) struct ScanScratch {
    /// The positions as `[x, y, z, 0]` (one 16-byte load per candidate).
    pub(crate) xyz: Vec<[f32; 4]>,
    /// Particle ranges of the parallel scan ([`chunk_bounds`]).
    pub(crate) bounds: Vec<usize>,
    /// Parts the last scan ran in (1: serially).
    pub(crate) parts: usize,
    /// The pairs of each range (joined in order).
    chunks: Vec<Vec<(u32, u32)>>,
}

/// [`collect_near`] into `out`; when `parallel`, over the ranges of [`chunk_bounds`], each
/// into its own buffer, the buffers joined in range order: the same list as the serial walk
/// whatever the number of threads.
#[allow(clippy::too_many_arguments)]
pub(crate) fn collect(cand: &Neighbours, p: [&[f32]; 3], n: usize, r: f32, exec: Exec, s: &mut ScanScratch, out: &mut Vec<(u32, u32)>) {
    let (parallel, simd) = (exec.parallel(), exec.simd());
    let n = near_len(cand, p, n);
    chunk_bounds(cand, n, &mut s.bounds);
    let m = s.bounds.len() - 1;
    if !parallel || m < 2 {
        s.parts = 1;
        return collect_near(cand, p, n, r, simd, &mut s.xyz, out);
    }
    s.parts = m;
    if simd {
        fill_xyz(p, n, true, &mut s.xyz);
    }
    let (bounds, xyz) = (&s.bounds, &s.xyz[..]);
    join_chunks(&mut s.chunks, m, out, |c, buf| {
        collect_range(cand, p, bounds[c]..bounds[c + 1], r, simd, xyz, buf)
    });
}

/// Runs `f(c, buf)` for the chunks `c < m` in parallel, each into its own kept buffer
/// (cleared first), and joins the buffers in chunk order into `out`.
fn join_chunks(chunks: &mut Vec<Vec<(u32, u32)>>, m: usize, out: &mut Vec<(u32, u32)>, f: impl Fn(usize, &mut Vec<(u32, u32)>) + Sync) {
    if chunks.len() < m {
        chunks.resize_with(m, Vec::new);
    }
    chunks[..m].par_iter_mut().enumerate().for_each(|(c, buf)| {
        buf.clear();
        f(c, buf);
    });
    out.clear();
    for c in &chunks[..m] {
        out.extend_from_slice(c);
    }
}

/// Pairs one parallel task of [`filter_pairs`] tests (fixed, so the split does not depend on
/// the number of threads; the list does not either).
pub(crate) const FILTER_CHUNK: usize = 8192;

/// Replaces `out` with the pairs of `pairs` within `r` of each other at `p`, or with a NaN
/// distance, in their order (the test of [`collect_near`], pair by pair: the mid list to the
/// near list). With `simd`, eight pairs at a time from an `[x, y, z, 0]` copy of `p` (its first
/// `n` particles; every id must be below `n`); in parallel over fixed chunks of pairs when
/// `parallel`, joined in order: the same list either way.
#[allow(clippy::too_many_arguments)]
pub(crate) fn filter_pairs(
    pairs: &[(u32, u32)],
    p: [&[f32]; 3],
    n: usize,
    r: f32,
    exec: Exec,
    s: &mut ScanScratch,
    out: &mut Vec<(u32, u32)>,
) {
    let (parallel, simd) = (exec.parallel(), exec.simd());
    out.clear();
    if simd {
        let n = n.min(p[0].len()).min(p[1].len()).min(p[2].len());
        fill_xyz(p, n, parallel, &mut s.xyz);
    }
    let m = pairs.len().div_ceil(FILTER_CHUNK);
    if !parallel || m < 2 {
        s.parts = 1;
        return filter_range(pairs, p, r, simd, &s.xyz, out);
    }
    s.parts = m;
    let xyz = &s.xyz[..];
    join_chunks(&mut s.chunks, m, out, |c, buf| {
        let part = &pairs[c * FILTER_CHUNK..((c + 1) * FILTER_CHUNK).min(pairs.len())];
        filter_range(part, p, r, simd, xyz, buf)
    });
}

/// Appends to `out` the pairs of `pairs` within the radius (the work of [`filter_pairs`]):
/// the difference `p_i - p_j` and its squared length computed as [`collect_range`] does.
pub(crate) fn filter_range(pairs: &[(u32, u32)], p: [&[f32]; 3], r: f32, simd: bool, xyz: &[[f32; 4]], out: &mut Vec<(u32, u32)>) {
    let mut done = 0;
    let r2 = r * r;
    // Every index below the copy's length, checked once, so the gathers need no checks
    // (as in the pair pass's: see `PairCtx::near_candidates`).
    let top = largest_id(pairs);
    if simd && (top as usize) < xyz.len() {
        let r2v = F32s::splat(r2);
        let groups = pairs.as_chunks::<LANES>().0;
        for c in groups {
            // SAFETY (both gathers): every index of `pairs` is at most `top < xyz.len()`.
            // Sorted by `i`, eight pairs mostly share it: then one load, broadcast (the same
            // values as the gather).
            let a = if c.iter().all(|q| q.0 == c[0].0) {
                xyz[c[0].0 as usize].map(F32s::splat)
            } else {
                unsafe { gather_xyzw8_unchecked(xyz, &idx8(|l| c[l].0)) }
            };
            let b = unsafe { gather_xyzw8_unchecked(xyz, &idx8(|l| c[l].1)) };
            let v = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
            let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            let mut bits = (d2.simd_lt(r2v) | d2.is_nan()).to_bitmask();
            while bits != 0 {
                out.push(c[bits.trailing_zeros() as usize]);
                bits &= bits - 1;
            }
        }
        done = groups.len() * LANES;
    }
    for &(i, j) in &pairs[done..] {
        let (i, j) = (i as usize, j as usize);
        let v = [p[0][i] - p[0][j], p[1][i] - p[1][j], p[2][i] - p[2][j]];
        let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if d2 < r2 || d2.is_nan() {
            out.push((i as u32, j as u32));
        }
    }
}

/// Candidate entries one parallel task of the near-list rebuild tests, about (a chunk ends at
/// the first particle boundary past this many entries, so a task's work does not depend on
/// how the candidates are spread over the particles).
pub(crate) const NEAR_CHUNK: usize = 8192;

/// Replaces `out` with the candidate pairs `(i, j)` of `cand` (first `n` lists) closer than
/// `r` at `p`, or with a NaN distance (the exact test rejects those later, as the fresh
/// path does), in list order. With `simd`, eight candidates of one particle at a time: their
/// positions come from `xyz`, a copy of `p` as `[x, y, z, 0]` made here (one 16-byte load a
/// candidate instead of three scattered ones, transposed to `f32x8` in registers by
/// [`gather_xyzw8`]); the same operations as the scalar twin, so the same list.
pub(crate) fn collect_near(
    cand: &Neighbours,
    p: [&[f32]; 3],
    n: usize,
    r: f32,
    simd: bool,
    xyz: &mut Vec<[f32; 4]>,
    out: &mut Vec<(u32, u32)>,
) {
    out.clear();
    let n = near_len(cand, p, n);
    if simd {
        fill_xyz(p, n, false, xyz);
    }
    collect_range(cand, p, 0..n, r, simd, xyz, out);
}

/// The particles [`collect_near`] walks: the first `n` with a list and a position.
fn near_len(cand: &Neighbours, p: [&[f32]; 3], n: usize) -> usize {
    n.min(cand.len()).min(p[0].len()).min(p[1].len()).min(p[2].len())
}

/// Replaces `xyz` with `[x, y, z, 0]` of the first `n` particles of `p` (element-wise, in
/// parallel over fixed blocks when `parallel`: the same
/// values either way).
fn fill_xyz(p: [&[f32]; 3], n: usize, parallel: bool, xyz: &mut Vec<[f32; 4]>) {
    const BLOCK: usize = 2048;
    // Every entry is overwritten below: zero only new entries.
    xyz.resize(n, [0.0; 4]);
    let (x, y, z) = (&p[0][..n], &p[1][..n], &p[2][..n]);
    let one = |b: usize, dst: &mut [[f32; 4]]| {
        let o = b * BLOCK;
        for (k, d) in dst.iter_mut().enumerate() {
            *d = [x[o + k], y[o + k], z[o + k], 0.0];
        }
    };
    if parallel && n > BLOCK {
        xyz.par_chunks_mut(BLOCK).enumerate().for_each(|(b, d)| one(b, d));
    } else {
        xyz.chunks_mut(BLOCK).enumerate().for_each(|(b, d)| one(b, d));
    }
}

/// Splits particles `0..n` into consecutive ranges of about [`NEAR_CHUNK`] candidate entries
/// (from the list offsets): `bounds` becomes `0 = b_0 < b_1 < .. < b_m = n`.
pub(crate) fn chunk_bounds(cand: &Neighbours, n: usize, bounds: &mut Vec<usize>) {
    bounds.clear();
    bounds.push(0);
    let first = &cand.first[..=n];
    let mut lo = 0;
    while lo < n {
        let goal = first[lo] as usize + NEAR_CHUNK;
        // The first particle whose list starts at or past the goal (at least one particle on).
        let hi = (lo + 1).max(first.partition_point(|&f| (f as usize) < goal)).min(n);
        bounds.push(hi);
        lo = hi;
    }
}

/// Appends to `out` the near pairs of the particles in `range` (the work of [`collect_near`]
/// on a part of the lists; `xyz` filled when `simd`).
fn collect_range(
    cand: &Neighbours,
    p: [&[f32]; 3],
    range: std::ops::Range<usize>,
    r: f32,
    simd: bool,
    xyz: &[[f32; 4]],
    out: &mut Vec<(u32, u32)>,
) {
    let r2 = r * r;
    let r2v = F32s::splat(r2);
    for i in range {
        let list = cand.of(i);
        if list.is_empty() {
            continue;
        }
        let pi = [p[0][i], p[1][i], p[2][i]];
        let mut k = 0;
        if simd {
            let piv = [F32s::splat(pi[0]), F32s::splat(pi[1]), F32s::splat(pi[2])];
            let groups = list.as_chunks::<LANES>().0;
            for js in groups {
                let idx = idx8(|l| js[l]);
                // Checked here: a per-list check before the loop costs more (the lists are
                // short).
                let q = gather_xyzw8(xyz, &idx);
                let v = [piv[0] - q[0], piv[1] - q[1], piv[2] - q[2]];
                let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
                let mut bits = (d2.simd_lt(r2v) | d2.is_nan()).to_bitmask();
                while bits != 0 {
                    out.push((i as u32, js[bits.trailing_zeros() as usize]));
                    bits &= bits - 1;
                }
            }
            k = groups.len() * LANES;
        }
        for &j in &list[k..] {
            let ju = j as usize;
            let v = [pi[0] - p[0][ju], pi[1] - p[1][ju], pi[2] - p[2][ju]];
            let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            if d2 < r2 || d2.is_nan() {
                out.push((i as u32, j));
            }
        }
    }
}

/// The largest particle id of `pairs` (0 when empty): one check of a scan's gathers.
#[inline]
pub(crate) fn largest_id(pairs: &[(u32, u32)]) -> u32 {
    pairs.iter().fold(0u32, |m, &(i, j)| m.max(i).max(j))
}

/// The four components of eight entries of `xyz` (indices `idx`, bounds-checked) as four
/// vectors, lane `l` from entry `idx[l]` (see [`gather_xyzw8_unchecked`]).
#[inline(always)]
pub(crate) fn gather_xyzw8(xyz: &[[f32; 4]], idx: &Idx8) -> [F32s; 4] {
    let top = idx.iter().fold(0u32, |m, &i| m.max(i));
    assert!((top as usize) < xyz.len(), "entry {top} of {}", xyz.len());
    // SAFETY: every index is at most `top`, below the length (asserted).
    unsafe { gather_xyzw8_unchecked(xyz, idx) }
}

/// [`gather_xyzw8`] without the bounds checks: on AVX, eight 16-byte loads and an 8x4
/// transpose in registers (unpack and shuffle); elsewhere a portable array version. Pure data
/// movement.
///
/// # Safety
/// Every index of `idx` must be below `xyz.len()`.
#[inline(always)]
pub(crate) unsafe fn gather_xyzw8_unchecked(xyz: &[[f32; 4]], idx: &Idx8) -> [F32s; 4] {
    // SAFETY: the caller guarantees every index is in bounds.
    let entry = |l: usize| unsafe { *xyz.get_unchecked(idx[l] as usize) };
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use std::arch::x86_64::{__m128, __m256, _mm256_set_m128, _mm256_shuffle_ps, _mm256_unpackhi_ps, _mm256_unpacklo_ps};
        // Written out (no array `map`, which can end up as an out-of-line call).
        let row = |l: usize| -> __m128 { bytemuck::cast(entry(l)) };
        let r = [row(0), row(1), row(2), row(3), row(4), row(5), row(6), row(7)];
        // SAFETY: the cfg guarantees AVX at compile time; register-only intrinsics.
        let (x, y, z, w) = unsafe {
            // Low halves hold rows 0..4, high halves rows 4..8.
            let a = _mm256_set_m128(r[4], r[0]);
            let b = _mm256_set_m128(r[5], r[1]);
            let c = _mm256_set_m128(r[6], r[2]);
            let d = _mm256_set_m128(r[7], r[3]);
            let t0 = _mm256_unpacklo_ps(a, b); // x0 x1 y0 y1 | x4 x5 y4 y5
            let t1 = _mm256_unpacklo_ps(c, d); // x2 x3 y2 y3 | x6 x7 y6 y7
            let t2 = _mm256_unpackhi_ps(a, b); // z0 z1 w0 w1 | z4 z5 w4 w5
            let t3 = _mm256_unpackhi_ps(c, d); // z2 z3 w2 w3 | z6 z7 w6 w7
            (
                _mm256_shuffle_ps::<0x44>(t0, t1),
                _mm256_shuffle_ps::<0xEE>(t0, t1),
                _mm256_shuffle_ps::<0x44>(t2, t3),
                _mm256_shuffle_ps::<0xEE>(t2, t3),
            )
        };
        let c = |v: __m256| -> F32s { bytemuck::cast(v) };
        [c(x), c(y), c(z), c(w)]
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    {
        let rows: [[f32; 4]; LANES] = std::array::from_fn(entry);
        [0, 1, 2, 3].map(|a| F32s::from(rows.map(|r| r[a])))
    }
}
