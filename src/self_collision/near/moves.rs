//! How far the particles of the active blocks moved since a build of the near or mid list
//! (module `self_near`): the compact copy of their positions a build keeps, and the check
//! of the largest displacement against it.

use crate::data::lanes::{load, F32s, LANES};

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
/// `blocks` (block `blocks[k]` at `at[8 k..8 k + 8]`), or infinity when one is NaN: one block
/// at a time (`f32x8`) when `simd`, else one particle at a time (the twin; same value: `max`
/// does not round).
pub(crate) fn max_disp2_blocks(p: [&[f32]; 3], at: [&[f32]; 3], blocks: &[u32], simd: bool) -> f32 {
    let mut m = 0.0f32;
    let mut nan = false;
    let len = p[0].len().min(p[1].len()).min(p[2].len());
    let compact = blocks.len() * LANES;
    if at.iter().any(|a| a.len() < compact) {
        // Not the layout of a build: report "moved too far" (a rebuild) rather than guess.
        return f32::INFINITY;
    }
    let mut mv = F32s::splat(0.0);
    let mut bad = F32s::splat(0.0);
    // The compact arrays by block (eight lanes each), so their loads need no bounds checks.
    fn chunks(a: &[f32], compact: usize) -> std::slice::ChunksExact<'_, f32> {
        a[..compact].chunks_exact(LANES)
    }
    let compact_blocks = chunks(at[0], compact).zip(chunks(at[1], compact)).zip(chunks(at[2], compact));
    for (&b, ((ax, ay), az)) in blocks.iter().zip(compact_blocks) {
        let g = b as usize * LANES;
        if simd && g + LANES <= len {
            // Written out: `[0, 1, 2].map(..)` compiled to an out-of-line call per coordinate
            // here.
            let vx = load(p[0], g) - load(ax, 0);
            let vy = load(p[1], g) - load(ay, 0);
            let vz = load(p[2], g) - load(az, 0);
            let d2 = vx * vx + vy * vy + vz * vz;
            bad |= d2.is_nan();
            // NaN lanes are flagged above, so the plain `max` (no NaN ordering) is enough.
            mv = mv.fast_max(d2);
            continue;
        }
        for l in 0..LANES.min(len.saturating_sub(g)) {
            let (vx, vy, vz) = (p[0][g + l] - ax[l], p[1][g + l] - ay[l], p[2][g + l] - az[l]);
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
