//! How far the particles of the active blocks moved since a build of the near or mid list
//! (module `self_near`): the compact copy of their positions a build keeps, and the check
//! of the largest displacement against it.

use crate::lanes::{load, F32s, LANES};

/// The three coordinate arrays as slices.
pub(crate) fn as_refs(a: &[Vec<f32>; 3]) -> [&[f32]; 3] {
    [&a[0][..], &a[1][..], &a[2][..]]
}

/// Copies the positions of the particles of `blocks` into `dst`, block by block (the layout
/// [`max_disp2_blocks`] reads; past the arrays' end, zeros).
pub(crate) fn copy_blocks(p: [&[f32]; 3], blocks: &[u32], dst: &mut [Vec<f32>; 3]) {
    for (a, src) in dst.iter_mut().zip(p) {
        a.clear();
        for &b in blocks {
            let g = b as usize * LANES;
            match src.get(g..g + LANES) {
                Some(s) => a.extend_from_slice(s),
                None => a.extend((g..g + LANES).map(|i| src.get(i).copied().unwrap_or(0.0))),
            }
        }
    }
}

/// Largest squared distance between `p_i` and its compact copy `at` over the particles of
/// `blocks` (block `blocks[k]` at `at[8 k..8 k + 8]`), each times its entry of `mask` (the
/// layout of `at`; 0 leaves a particle out, 1 keeps it) when there is one, or infinity when
/// one is NaN: one block at a time (`f32x8`) when `simd`, else one particle at a time (the
/// twin; same value: `max` does not round, nor do the products by 0 and 1).
pub(crate) fn max_disp2_blocks(p: [&[f32]; 3], at: [&[f32]; 3], blocks: &[u32], mask: Option<&[f32]>, simd: bool) -> f32 {
    // Two loops, so the check without a mask costs what it did before there was one.
    match mask {
        Some(w) => max_disp2_with::<true>(p, at, blocks, w, simd),
        None => max_disp2_with::<false>(p, at, blocks, &[], simd),
    }
}

fn max_disp2_with<const MASKED: bool>(p: [&[f32]; 3], at: [&[f32]; 3], blocks: &[u32], mask: &[f32], simd: bool) -> f32 {
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
            let mut d2 = vx * vx + vy * vy + vz * vz;
            if MASKED {
                d2 *= load(mask, c);
            }
            bad |= d2.is_nan();
            mv = mv.max(d2);
            continue;
        }
        for l in 0..LANES.min(len.saturating_sub(g)) {
            let (vx, vy, vz) = (p[0][g + l] - at[0][c + l], p[1][g + l] - at[1][c + l], p[2][g + l] - at[2][c + l]);
            let mut d2 = vx * vx + vy * vy + vz * vz;
            if MASKED {
                d2 *= mask[c + l];
            }
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
