//! The near list: the candidate pairs the substeps test, kept across substeps (exact, like the
//! candidate lists of [`super::self_verlet`]; the method is described in
//! [`super::self_collision`]).
//!
//! A contact needs `|p_i - p_j| < d` for the predicted positions `p`. The near list holds the
//! candidate pairs within `d + s₂` of the positions `y` of its build (a substep's `p`); while
//! every particle of the active blocks stays within `0.49 s₂` of `y`, a pair in contact is in
//! it. The substeps test only the near pairs, and a pair also has to be within `q` at the
//! step's start (in the lists of the step), exactly as the fresh path requires.
//!
//! # Cost (issue #5, `examples/self_collision_timeline.rs`, basic VcCPBD 100x100, 1 thread)
//! Measured per substep, averaged over the 1500 substeps, with timers around the parts
//! (loaded shared machine, so roughly): the near-list update 36 µs (274 rebuilds, ~180 µs
//! each over ~180 000 candidate pairs once folded, plus the displacement check), the
//! candidate test of the near pairs 15 µs (~5 600 near pairs), zeroing and storing the sums
//! 16 µs, the ~205 contacts themselves 4 µs. What changed, and why:
//! * the displacement check and the copy of the build positions cover only the active
//!   blocks ([`max_disp2_blocks`]): every near pair has both ends in them, and while the
//!   cloth falls they are a few of the 1 250 blocks (the check ran over all 10 000
//!   particles every substep);
//! * the rebuild ([`collect_near`]) tests eight candidates of a particle at a time from a
//!   `[x, y, z, 0]` copy of the positions (one 16-byte load a candidate, transposed in
//!   registers) instead of three scattered loads; measured within the noise of the shared
//!   machine (the rebuild stays bound by its ~1 ns a candidate), kept because it is not
//!   slower and the scalar twin is the same list;
//! * the eight-lane gathers are written out ([`crate::lanes::gather1`],
//!   [`crate::lanes::idx8`]): with `array::map` the compiler once emitted an out-of-line call
//!   per gather in the pair pass's candidate test, which made that test twice as slow (perf
//!   annotate).
//!
//! * session 5: the displacement check loads its three coordinates written out (with
//!   `[0, 1, 2].map(..)` each coordinate was an out-of-line `try_map` call: ~140 million
//!   instructions of the pair phase over the 1 500 substeps), a build copies the positions
//!   of a block with one slice copy and the `[x, y, z, 0]` copy without bounds checks.
//!   Callgrind over the pair phase (`self_collision_pairs_pass`, timeline example, 150 steps,
//!   1 thread): 1 600 to 1 292 million instructions, same bits; wall time of the pairs
//!   column 0.809 / 0.770 / 0.616 ms a step before against 1.235 / 0.658 / 0.586 after,
//!   alternate runs at load ~6 on two cores (noise larger than the change).
//!
//! Tried in session 5 and not kept (callgrind over the pair phase, same scene, against
//! 1 600 million instructions before the change above):
//! * **per-block references** (a block whose particle passed `0.49 s₂` takes new references
//!   alone; the owner blocks of the pairs touching it, found through a block adjacency built
//!   with the list, are tested again; the list stays exact: tested against the full build
//!   and every contact): with a fixed skin `d / 2`, 1 637 million (the partial retests cost
//!   less than the rebuilds, but the fixed skin lists ~10 000 near pairs against ~6 400 for
//!   the adaptive one, and the pair test runs every substep); with a skin per block
//!   (adapted like the global one, pair radius `d + s_i / 2 + s_j / 2`): 2 170 million with
//!   skins reset at each candidate rebuild, 2 525 million when kept across them (blocks
//!   keep the wide skins of the fall). A block that moves retests ~4 owner blocks, so the
//!   partial updates walked ~60% of the candidates the global rebuilds walk, at ~2.5 times
//!   the instructions a candidate (short per-block loops, the per-pair radius);
//! * the partial last group of a particle's candidates in the eight-lane test (masked)
//!   instead of the scalar tail: 1 230 to 1 384 million (the clamped indices slow every
//!   group);
//! * the pair pass's candidate test loading `[x, y, z, 0]` copies of the predicted
//!   positions (two transposed gathers instead of six lane gathers): 1 230 to 1 221
//!   million, the per-substep copy eats the gain; not worth its buffer;
//! * the rebuild in parallel over fixed chunks of 2 048 particles (per-chunk buffers joined
//!   in order: the same list): on two threads the pairs column measured 0.421-0.649 ms a
//!   step before against 0.433-0.647 after (seven alternate runs each, load 3.3-3.5: the
//!   second core was busy), no measurable gain on the shared machine (but see session 6).
//!
//! Session 6 (issue #5 on two threads): a rebuild runs in parallel over ranges of particles
//! of about [`NEAR_CHUNK`] candidate entries each ([`chunk_bounds`], cut from the list
//! offsets, so a folded region's long lists spread over several tasks), each range into its
//! own buffer, joined in order: the same list on any number of threads (tested). Measured
//! under the CPU lock on the otherwise idle machine, `weft reproduce vccpbd --size 100
//! --threads 2`, basic VcCPBD hash row, five alternate runs each: collision 0.704 -> 0.631
//! ms a step (medians), pairs column 0.356 -> 0.267; the rebuilds alone (timers around
//! them, timeline example, 150 steps, 240 rebuilds) 30.0 -> 18.9 ms in all. One thread: no
//! change (pairs 0.366 -> 0.368).
//!
//! Tried in session 6 and not kept: the near list kept as the ranges' buffers and each
//! rebuild run inside the pair pass's parallel candidate search (one region for both, the
//! candidate search then split by the same ranges). Timeline example, two threads, three
//! alternate runs: pairs 0.265-0.274 ms a step before against 0.287-0.302 (0.269-0.285 with
//! the search parallel from 2 048 near pairs instead of 4 096): the ranges, cut by candidate
//! entries, split the near pairs of a kept list unevenly; one region fewer a rebuild did not
//! make up for it. Without the `[x, y, z, 0]` copy (three lane gathers from `p`) 0.316-0.338.
//!
//! The skin rule is unchanged: a larger cap than `d` makes the near list approach the
//! candidate lists (radius `3 d` against `4 d`), and a cap of `d / 2` (tried: fewer near
//! pairs, more rebuilds) measured no faster (CPU of these phases over the distance solve's,
//! 0.68-0.75 against 0.64-0.70, three runs each); the remaining cost is the
//! folding phase (steps ~40-100), where the cloth moves `~d / 10` a substep and the list is rebuilt every 4-10 substeps.

use super::neighbours::Neighbours;
use super::self_verlet::SAFE;
use crate::lanes::{idx8, load, F32s, Idx8, LANES};
use rayon::prelude::*;

/// Near pairs of the candidate lists for the substeps (see the module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct NearList {
    /// Pairs `(i, j)`, `i < j`, ordered by `i` then `j`.
    pub(crate) pairs: Vec<(u32, u32)>,
    /// Positions of the build (particle arrays, padded like them).
    at: [Vec<f32>; 3],
    skin: f32,
    valid: bool,
    subs_since: u32,
    /// Builds so far.
    pub(crate) rebuilds: u64,
    /// Scratch: the positions of the build as `[x, y, z, 0]` (one load per candidate).
    xyz: Vec<[f32; 4]>,
    /// Particle ranges of the parallel rebuild ([`chunk_bounds`]).
    bounds: Vec<usize>,
    /// The near pairs of each range (joined in order into `pairs`).
    chunks: Vec<Vec<(u32, u32)>>,
}

impl NearList {
    /// Forgets the list (new candidate lists).
    pub(crate) fn invalidate(&mut self) {
        self.valid = false;
    }

    /// Makes the list hold for the predicted positions `p`: kept if no particle of the active
    /// `blocks` (ascending; every near pair has both ends in them) moved more than `0.49 s₂`
    /// since the build, else rebuilt from `cand` (first `n` lists) with a new skin. Only the
    /// active blocks are checked and copied: before the fold they are a few, and the
    /// particles outside them have no candidate. A rebuild runs in parallel over ranges of
    /// particles when `parallel` ([`NearList::collect`]: the same list).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn update(&mut self, cand: &Neighbours, p: [&[f32]; 3], blocks: &[u32], n: usize, d: f32, simd: bool, parallel: bool) {
        if self.valid && self.at[0].len() == blocks.len() * LANES {
            let at = [&self.at[0][..], &self.at[1][..], &self.at[2][..]];
            let m2 = max_disp2_blocks(p, at, blocks, simd);
            let lim = 0.5 * SAFE * self.skin;
            self.subs_since += 1;
            if m2 <= lim * lim {
                return;
            }
            // Aim at about 20 substeps between builds, within [d / 8, d].
            let rate = if m2.is_finite() { m2.sqrt() / self.subs_since as f32 } else { d };
            self.skin = (20.0 * rate).clamp(0.125 * d, d);
        } else if !self.valid {
            self.skin = 0.25 * d;
        }
        for (a, src) in self.at.iter_mut().zip(p) {
            a.clear();
            for &b in blocks {
                let g = b as usize * LANES;
                match src.get(g..g + LANES) {
                    Some(s) => a.extend_from_slice(s),
                    None => a.extend((g..g + LANES).map(|i| src.get(i).copied().unwrap_or(0.0))),
                }
            }
        }
        let r = d + self.skin;
        self.collect(cand, p, n, r * r, simd, parallel);
        self.valid = true;
        self.subs_since = 0;
        self.rebuilds += 1;
    }

    /// Number of particle ranges of the last parallel build (0 or 1: built serially).
    #[cfg(test)]
    pub(crate) fn ranges(&self) -> usize {
        self.bounds.len().saturating_sub(1)
    }

    /// [`collect_near`] into `pairs`; when `parallel`, over the ranges of [`chunk_bounds`],
    /// each into its own buffer, the buffers joined in range order: the same list as the
    /// serial walk whatever the number of threads.
    fn collect(&mut self, cand: &Neighbours, p: [&[f32]; 3], n: usize, r2: f32, simd: bool, parallel: bool) {
        let n = near_len(cand, p, n);
        chunk_bounds(cand, n, &mut self.bounds);
        let m = self.bounds.len() - 1;
        if !parallel || m < 2 {
            return collect_near(cand, p, n, r2, simd, &mut self.xyz, &mut self.pairs);
        }
        if simd {
            fill_xyz(p, n, true, &mut self.xyz);
        }
        if self.chunks.len() < m {
            self.chunks.resize_with(m, Vec::new);
        }
        let (bounds, xyz) = (&self.bounds, &self.xyz[..]);
        self.chunks[..m].par_iter_mut().enumerate().for_each(|(c, buf)| {
            buf.clear();
            collect_range(cand, p, bounds[c]..bounds[c + 1], r2, simd, xyz, buf);
        });
        self.pairs.clear();
        for c in &self.chunks[..m] {
            self.pairs.extend_from_slice(c);
        }
    }
}

/// Largest squared distance between `p_i` and its compact copy `at` over the particles of
/// `blocks` (block `blocks[k]` at `at[8 k..8 k + 8]`), or infinity when one is NaN: one block
/// at a time (`f32x8`) when `simd`, else one particle at a time (the twin; same value: `max`
/// does not round).
pub(crate) fn max_disp2_blocks(p: [&[f32]; 3], at: [&[f32]; 3], blocks: &[u32], simd: bool) -> f32 {
    let mut m = 0.0f32;
    let mut nan = false;
    let len = p[0].len().min(p[1].len()).min(p[2].len());
    let mut mv = F32s::splat(0.0);
    let mut bad = F32s::splat(0.0);
    for (k, &b) in blocks.iter().enumerate() {
        let g = b as usize * LANES;
        let c = k * LANES;
        if simd && g + LANES <= len {
            // Written out: `[0, 1, 2].map(..)` compiled to an out-of-line call per coordinate
            // here (callgrind: ~110 of the ~1600 million instructions of the pair phase).
            let vx = load(p[0], g) - load(at[0], c);
            let vy = load(p[1], g) - load(at[1], c);
            let vz = load(p[2], g) - load(at[2], c);
            let d2 = vx * vx + vy * vy + vz * vz;
            bad |= d2.is_nan();
            mv = mv.max(d2);
            continue;
        }
        for l in 0..LANES.min(len.saturating_sub(g)) {
            let (vx, vy, vz) = (p[0][g + l] - at[0][c + l], p[1][g + l] - at[1][c + l], p[2][g + l] - at[2][c + l]);
            let d2 = vx * vx + vy * vy + vz * vz;
            nan |= d2.is_nan();
            m = m.max(d2);
        }
    }
    nan |= bad.any();
    m = mv.to_array().into_iter().fold(m, f32::max);
    if nan {
        f32::INFINITY
    } else {
        m
    }
}

/// Candidate entries one parallel task of the near-list rebuild tests, about (a chunk ends at
/// the first particle boundary past this many entries, so a task's work does not depend on
/// how the candidates are spread over the particles).
pub(crate) const NEAR_CHUNK: usize = 8192;

/// Replaces `out` with the candidate pairs `(i, j)` of `cand` (first `n` lists) closer than
/// `sqrt(r2)` at `p`, or with a NaN distance (the exact test rejects those later, as the fresh
/// path does), in list order. With `simd`, eight candidates of one particle at a time: their
/// positions come from `xyz`, a copy of `p` as `[x, y, z, 0]` made here (one 16-byte load a
/// candidate instead of three scattered ones, transposed to `f32x8` in registers by
/// [`gather_xyz8`]); the same operations as the scalar twin, so the same list.
pub(crate) fn collect_near(
    cand: &Neighbours,
    p: [&[f32]; 3],
    n: usize,
    r2: f32,
    simd: bool,
    xyz: &mut Vec<[f32; 4]>,
    out: &mut Vec<(u32, u32)>,
) {
    out.clear();
    let n = near_len(cand, p, n);
    if simd {
        fill_xyz(p, n, false, xyz);
    }
    collect_range(cand, p, 0..n, r2, simd, xyz, out);
}

/// The particles [`collect_near`] walks: the first `n` with a list and a position.
fn near_len(cand: &Neighbours, p: [&[f32]; 3], n: usize) -> usize {
    n.min(cand.len()).min(p[0].len()).min(p[1].len()).min(p[2].len())
}

/// Replaces `xyz` with `[x, y, z, 0]` of the first `n` particles of `p` (element-wise, in
/// parallel over fixed blocks when `parallel`: the same values either way).
fn fill_xyz(p: [&[f32]; 3], n: usize, parallel: bool, xyz: &mut Vec<[f32; 4]>) {
    const BLOCK: usize = 2048;
    xyz.clear();
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
    r2: f32,
    simd: bool,
    xyz: &[[f32; 4]],
    out: &mut Vec<(u32, u32)>,
) {
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
            while k + LANES <= list.len() {
                let js = &list[k..k + LANES];
                let idx = idx8(|l| js[l]);
                let q = gather_xyz8(xyz, &idx);
                let v = [piv[0] - q[0], piv[1] - q[1], piv[2] - q[2]];
                let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
                let mut bits = (d2.simd_lt(r2v) | d2.is_nan()).to_bitmask();
                while bits != 0 {
                    out.push((i as u32, js[bits.trailing_zeros() as usize]));
                    bits &= bits - 1;
                }
                k += LANES;
            }
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

/// The x, y and z of eight entries of `xyz` (indices `idx`, bounds-checked) as three vectors,
/// lane `l` from entry `idx[l]`. On AVX: eight 16-byte loads and an 8x4 transpose in
/// registers (unpack and shuffle); elsewhere a portable array version. Pure data movement.
#[inline(always)]
pub(crate) fn gather_xyz8(xyz: &[[f32; 4]], idx: &Idx8) -> [F32s; 3] {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use std::arch::x86_64::{__m128, __m256, _mm256_set_m128, _mm256_shuffle_ps, _mm256_unpackhi_ps, _mm256_unpacklo_ps};
        // Written out (no array `map`, which can end up as an out-of-line call).
        let row = |l: usize| -> __m128 { bytemuck::cast(xyz[idx[l] as usize]) };
        let r = [row(0), row(1), row(2), row(3), row(4), row(5), row(6), row(7)];
        // SAFETY: the cfg guarantees AVX at compile time; register-only intrinsics.
        let (x, y, z) = unsafe {
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
            )
        };
        let c = |v: __m256| -> F32s { bytemuck::cast(v) };
        [c(x), c(y), c(z)]
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    {
        let rows: [[f32; 4]; LANES] = std::array::from_fn(|l| xyz[idx[l] as usize]);
        [0, 1, 2].map(|a| F32s::from(rows.map(|r| r[a])))
    }
}

#[cfg(test)]
#[path = "self_near_tests.rs"]
mod tests;
