//! Block plans: how the SIMD distance kernel moves eight constraints' particles in and out of
//! registers without a gather or scatter when the indices allow it.
//!
//! The kernel solves constraints eight at a time (one lane group, a *block*). In general it
//! must gather `p_a`, `p_b`, `w_a`, `w_b` element by element and scatter the results back, and
//! on x86 that data movement, not the arithmetic, is most of the cost. Structured meshes (the
//! cloth grid) have much more regular indices once each colour is sorted by index offset
//! `b − a` and then by `a` (see [`DistanceSet::new`](super::DistanceSet::new)):
//!
//! - **run**: `a_l = a_0 + l` and `b_l = b_0 + l` (vertical stretch and bend edges, shear
//!   diagonals): six contiguous loads and six contiguous stores;
//! - **window**: the sixteen indices `{a_l} ∪ {b_l}` are exactly `s, s+1, …, s+15` (horizontal
//!   stretch `(i, i+1)` with `i = s, s+2, …`; horizontal bend `(i, i+2)` in pairs): two
//!   contiguous loads per coordinate and a fixed permutation ([`pick16`])
//!   to put each particle in its lane, and the inverse permutation on the way back. Since the
//!   block owns all sixteen particles, writing the whole window back is safe under the
//!   colouring guarantee (no particle in two constraints of a colour);
//! - **gather**: anything else, including the padding on the sink particle.
//!
//! The plan only changes how values travel, never the arithmetic, so the kernel still equals
//! the scalar twin bit for bit. The kernel that follows a plan (`solve_block_simd`) lives
//! here with it; the sweep over colours that calls it is [`DistanceSet`](super::DistanceSet)'s.

use std::collections::HashMap;

use crate::constraints::project::project8;
use crate::data::lanes::{gather1, load, load_idx, pick16, pick16_vec, store, F32s, Pos8, SharedVec3, Vec3x8, LANES};

/// [`Block::kind`] of a block that gathers and scatters.
pub const GATHER: u32 = 0;
/// [`Block::kind`] of a block of two contiguous runs.
pub const RUN: u32 = 1;
/// [`Block::kind`] of the first window permutation; `kind − WINDOW` indexes the colour's
/// window table.
pub const WINDOW: u32 = 2;

/// How one block of eight constraints reaches its particles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Block {
    /// [`RUN`]: the first `a` index; window: the first index `s` of the window; else unused.
    pub first: u32,
    /// [`RUN`]: the first `b` index; else unused.
    pub second: u32,
    /// [`GATHER`], [`RUN`], or `WINDOW + k` for window permutation `k`.
    pub kind: u32,
}

/// The permutations of one window pattern (positions in `0..16` relative to `s`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Window {
    /// Lane `l` of `p_a` is window element `pos_a[l]`.
    pub pos_a: Pos8,
    /// Lane `l` of `p_b` is window element `pos_b[l]`.
    pub pos_b: Pos8,
    /// Window element `q < 8` comes from lane `src_lo[q] % 8` of `p_a` (`< 8`) or `p_b`.
    pub src_lo: Pos8,
    /// Window element `8 + q` comes from lane `src_hi[q] % 8` of `p_a` (`< 8`) or `p_b`.
    pub src_hi: Pos8,
}

/// The window pattern of one block, if its sixteen indices are exactly `s..s + 16`.
fn window_of(a: &[u32], b: &[u32]) -> Option<(u32, Window)> {
    let s = a.iter().chain(b).copied().min()?;
    let mut src = [u32::MAX; 2 * LANES];
    let mut w = Window {
        pos_a: [0; LANES],
        pos_b: [0; LANES],
        src_lo: [0; LANES],
        src_hi: [0; LANES],
    };
    for l in 0..LANES {
        for (side, idx, pos) in [(0, a[l], &mut w.pos_a), (1, b[l], &mut w.pos_b)] {
            let q = idx.checked_sub(s).filter(|&q| q < 16)? as usize;
            if src[q] != u32::MAX {
                return None;
            }
            src[q] = side * LANES as u32 + l as u32;
            pos[l] = q as u32;
        }
    }
    w.src_lo.copy_from_slice(&src[..LANES]);
    w.src_hi.copy_from_slice(&src[LANES..]);
    Some((s, w))
}

/// Plans every block of a colour whose (padded) index arrays are `a`, `b`; returns the blocks
/// and the colour's table of distinct window permutations.
pub fn plan(a: &[u32], b: &[u32]) -> (Vec<Block>, Vec<Window>) {
    let mut table: HashMap<Window, u32> = HashMap::new();
    let mut windows = Vec::new();
    let blocks = a
        .chunks_exact(LANES)
        .zip(b.chunks_exact(LANES))
        .map(|(a, b)| {
            let run = (0..LANES).all(|l| a[0].checked_add(l as u32) == Some(a[l]) && b[0].checked_add(l as u32) == Some(b[l]));
            let disjoint = a[0].abs_diff(b[0]) >= LANES as u32;
            if run && disjoint {
                return Block {
                    first: a[0],
                    second: b[0],
                    kind: RUN,
                };
            }
            match window_of(a, b) {
                Some((s, w)) => {
                    let k = *table.entry(w).or_insert_with(|| {
                        windows.push(w);
                        windows.len() as u32 - 1
                    });
                    Block {
                        first: s,
                        second: 0,
                        kind: WINDOW + k,
                    }
                }
                None => Block::default(),
            }
        })
        .collect();
    (blocks, windows)
}

/// One chunk of a colour's constraint arrays (a multiple of the lane width long).
pub(crate) struct Cons<'a> {
    pub(crate) a: &'a [u32],
    pub(crate) b: &'a [u32],
    pub(crate) rest: &'a [f32],
    pub(crate) comp: &'a [f32],
    pub(crate) blocks: &'a [Block],
}

/// One chunk of a colour, eight constraints at a time; `RESET`: the multipliers read as zero;
/// `STORE`: they are written.
#[inline]
pub(crate) fn solve_block_simd<const RESET: bool, const STORE: bool>(
    cons: &Cons<'_>,
    lambda: &mut [f32],
    windows: &[Window],
    p: &SharedVec3,
    w: &[f32],
    inv_h2: f32,
) {
    let inv_h2 = F32s::splat(inv_h2);
    for (k, bl) in cons.blocks.iter().enumerate() {
        let i = k * LANES;
        let s = bl.first as usize;
        // SAFETY (all particle accesses below): every index or run of indices comes from this
        // block's constraints, which are below the padded particle count, and within one
        // colour no particle appears in two constraints, so no other task touches them. A run
        // block's `a` and `b` runs are disjoint; a window block owns all sixteen particles.
        let (pa, pb, wa, wb) = match bl.kind {
            GATHER => {
                let (ia, ib) = (load_idx(cons.a, i), load_idx(cons.b, i));
                unsafe { (p.gather(&ia), p.gather(&ib), gather1(w, &ia), gather1(w, &ib)) }
            }
            RUN => {
                let t = bl.second as usize;
                unsafe { (p.load_run(s), p.load_run(t), load(w, s), load(w, t)) }
            }
            kind => {
                let win = &windows[(kind - WINDOW) as usize];
                let (lo, hi) = unsafe { (p.load_run(s), p.load_run(s + LANES)) };
                let (wl, wh) = (load(w, s), load(w, s + LANES));
                let pa = pick16_vec(lo, hi, &win.pos_a);
                let pb = pick16_vec(lo, hi, &win.pos_b);
                (pa, pb, pick16(wl, wh, &win.pos_a), pick16(wl, wh, &win.pos_b))
            }
        };
        let alpha = load(cons.comp, i) * inv_h2;
        let lam = if RESET { F32s::ZERO } else { load(lambda, i) };
        let (pa, pb, lam) = project8::<false, true, RESET>(pa, pb, wa, wb, load(cons.rest, i), alpha, lam);
        if STORE {
            store(lambda, i, lam);
        }
        write_back(bl, windows, p, cons, i, pa, pb);
    }
}

/// Writes a block's new positions back the way its plan read them.
#[inline(always)]
fn write_back(bl: &Block, windows: &[Window], p: &SharedVec3, cons: &Cons<'_>, i: usize, pa: Vec3x8, pb: Vec3x8) {
    let s = bl.first as usize;
    // SAFETY: as in `solve_block_simd`; for gathers `a` is scattered before `b`, and
    // `a != b` for real constraints.
    unsafe {
        match bl.kind {
            GATHER => {
                p.scatter(&load_idx(cons.a, i), pa);
                p.scatter(&load_idx(cons.b, i), pb);
            }
            RUN => {
                p.store_run(s, pa);
                p.store_run(bl.second as usize, pb);
            }
            kind => {
                let win = &windows[(kind - WINDOW) as usize];
                p.store_run(s, pick16_vec(pa, pb, &win.src_lo));
                p.store_run(s + LANES, pick16_vec(pa, pb, &win.src_hi));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rebuilds the block's `(a, b)` pairs from its plan.
    fn replay(bl: &Block, windows: &[Window]) -> Option<Vec<(u32, u32)>> {
        match bl.kind {
            GATHER => None,
            RUN => Some((0..LANES as u32).map(|l| (bl.first + l, bl.second + l)).collect()),
            k => {
                let w = &windows[(k - WINDOW) as usize];
                Some((0..LANES).map(|l| (bl.first + w.pos_a[l], bl.first + w.pos_b[l])).collect())
            }
        }
    }

    #[test]
    fn grid_edges_plan_as_runs_and_windows_and_replay_exactly() {
        // Horizontal pairs (window), a vertical run, a stride-4 set (gather), padding (gather).
        let mut a: Vec<u32> = (0..8).map(|l| 100 + 2 * l).collect();
        let mut b: Vec<u32> = a.iter().map(|i| i + 1).collect();
        a.extend(0..8u32);
        b.extend(50..58u32);
        a.extend((0..8).map(|l| 200 + 4 * l));
        b.extend((0..8).map(|l| 201 + 4 * l));
        a.extend([9; 8]);
        b.extend([9; 8]);
        let (blocks, windows) = plan(&a, &b);
        let kinds: Vec<u32> = blocks.iter().map(|b| b.kind).collect();
        assert_eq!(kinds, [WINDOW, RUN, GATHER, GATHER]);
        for (k, bl) in blocks.iter().enumerate() {
            if let Some(pairs) = replay(bl, &windows) {
                let want: Vec<(u32, u32)> = (0..LANES).map(|l| (a[8 * k + l], b[8 * k + l])).collect();
                assert_eq!(pairs, want, "block {k}");
            }
        }
        // The inverse permutation sends every lane back to its own window slot.
        let w = &windows[0];
        for l in 0..LANES {
            let q = w.pos_a[l] as usize;
            let src = if q < LANES { w.src_lo[q] } else { w.src_hi[q - LANES] };
            assert_eq!(src, l as u32);
        }
    }

    #[test]
    fn overlapping_runs_and_short_windows_are_not_planned() {
        // b = a + 1 for consecutive a: runs overlap (not a valid colour, but never mis-planned).
        let a: Vec<u32> = (0..8).collect();
        let b: Vec<u32> = (1..9).collect();
        assert_eq!(plan(&a, &b).0[0].kind, GATHER);
        // Pairs with a gap: indices span 17 elements.
        let a: Vec<u32> = [0, 2, 4, 6, 8, 10, 12, 16].to_vec();
        let b: Vec<u32> = a.iter().map(|i| i + 1).collect();
        assert_eq!(plan(&a, &b).0[0].kind, GATHER);
    }
}
