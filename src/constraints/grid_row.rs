//! One row of a grid colour ([`grid`](super::grid)): its constraints in blocks of eight, from
//! two runs of particles (vertical and shear classes) or from a window of sixteen (horizontal
//! classes).

use crate::constraints::distance::{project1, project8};
use crate::constraints::grid::{GridColour, WINDOW_LANES};
use crate::constraints::grid_sweep::{Multipliers, Sweep};
use crate::data::lanes::{load, merge16_vec, split16, split16_vec, store, F32s, SharedVec3, Split, Vec3x8, LANES};

/// Solves the row at position `at` of a grid colour in SIMD blocks: first the row's last
/// constraints, as a block that ends at the row's end whose other lanes keep their values
/// (first, so that no load waits on the overlapping store of the block before it), then the
/// whole blocks; what the last block cannot reach, one at a time.
///
/// # Safety
/// No other task touches the row's particles or multipliers.
#[inline(always)]
pub(crate) unsafe fn row<const RESET: bool, const STORE: bool, const CHECK_DENOM: bool>(
    g: &GridColour,
    at: usize,
    lambda: &Multipliers,
    s: &Sweep<'_>,
) {
    let cl = g.cl();
    let (per_row, cols) = (g.per_row() as usize, g.spec.cols);
    // SAFETY: the caller owns this row.
    let lam = unsafe { lambda.row(at as u32, per_row as u32) };
    let r = g.row_at(at);
    let row_start = (g.spec.first + r * cols) as usize;
    let (a_dc, b_dc) = cl.dc();
    let off = (cl.dr() * cols + b_dc) as usize - a_dc as usize;
    // `α / h²`, one rounding: the lanes and the scalar loop below use the same value
    let alpha = g.alpha(s.inv_h2);
    let k = Kernel::<CHECK_DENOM> {
        rest: F32s::splat(g.rest),
        alpha: F32s::splat(alpha),
        p: &s.p,
        w: s.w,
    };
    // lane `l` of a block holds the constraint `l` places after the block's first (runs) or
    // that of rank `WINDOW_LANES[l]` in its window (windows)
    let order = |ranks: [u32; LANES]| F32s::from(ranks.map(|r| r as f32));
    // SAFETY (the blocks): every index is a particle of this row's constraints (inside the
    // grid, so below the array length) and owned by the caller. A run block's `a` run is in
    // row `r`, its `b` run in row `r + dr > r`: disjoint. A window lies inside row `r`, whose
    // particles the caller owns (horizontal classes never cross a band boundary).
    let done = match cl.split() {
        None => {
            let blocks = per_row / LANES;
            let first = row_start + a_dc as usize;
            let tail = blocks > 0 && !per_row.is_multiple_of(LANES);
            if tail {
                let j = per_row - LANES;
                let fresh = order(std::array::from_fn(|l| l as u32)).simd_ge(F32s::splat((blocks * LANES - j) as f32));
                unsafe { k.run::<RESET, STORE>(first, off, lam, j, Some(fresh)) };
            }
            for q in 0..blocks {
                unsafe { k.run::<RESET, STORE>(first, off, lam, q * LANES, None) };
            }
            if tail {
                per_row
            } else {
                blocks * LANES
            }
        }
        Some(split) => {
            let whole = cl.windows(cols) as usize;
            let last = cl.last_window(cols).filter(|_| whole > 0 && whole * LANES < per_row);
            if let Some((c, rank)) = last {
                let fresh = order(WINDOW_LANES).simd_ge(F32s::splat((whole * LANES) as f32 - rank as f32));
                unsafe { k.window::<RESET, STORE>(row_start + c as usize, split, lam, rank as usize, Some(fresh)) };
            }
            for q in 0..whole {
                let i = row_start + cl.col_res() as usize + 16 * q;
                unsafe { k.window::<RESET, STORE>(i, split, lam, q * LANES, None) };
            }
            last.map_or(whole * LANES, |(_, rank)| (rank as usize + LANES).max(whole * LANES))
        }
    };
    let (p, w) = (k.p, k.w);
    for (j, l) in lam.iter_mut().enumerate().skip(done) {
        let c = cl.col(j as u32);
        let a = row_start + (c + a_dc) as usize;
        let b = a + off;
        let l0 = if RESET { 0.0 } else { *l };
        // SAFETY: as above.
        let (pa, pb) = unsafe { (p.get(a), p.get(b)) };
        let (pa, pb, l1) = project1::<true, RESET>(pa, pb, w[a], w[b], g.rest, alpha, l0);
        unsafe {
            p.set(a, pa);
            p.set(b, pb);
        }
        if STORE {
            *l = l1;
        }
    }
}

/// What a row's blocks share: its class's rest length and compliance (`alpha = α / h²`), the
/// particles and their inverse masses; `CHECK_DENOM` as in [`project8`].
struct Kernel<'a, const CHECK_DENOM: bool> {
    rest: F32s,
    alpha: F32s,
    p: &'a SharedVec3,
    w: &'a [f32],
}

impl<const CHECK_DENOM: bool> Kernel<'_, CHECK_DENOM> {
    /// The block of eight constraints joining the runs at `i` and `i + off`, whose multipliers
    /// are `lam[j..j + 8]`. With `fresh`, only its true lanes are solved; the others keep their
    /// particles and multipliers.
    ///
    /// # Safety
    /// Both runs lie inside the particle arrays, apart, and no other task touches them or
    /// `lam[j..j + 8]`.
    #[inline(always)]
    unsafe fn run<const RESET: bool, const STORE: bool>(&self, first: usize, off: usize, lam: &mut [f32], j: usize, fresh: Option<F32s>) {
        let (i, p) = (first + j, self.p);
        let (pa, pb) = unsafe { (p.load_run(i), p.load_run(i + off)) };
        let l0 = if RESET { F32s::ZERO } else { load(lam, j) };
        let (mut na, mut nb, mut l1) =
            project8::<true, CHECK_DENOM, RESET>(pa, pb, load(self.w, i), load(self.w, i + off), self.rest, self.alpha, l0);
        if let Some(m) = fresh {
            (na, nb) = (Vec3x8::select(m, na, pa), Vec3x8::select(m, nb, pb));
            if STORE {
                l1 = m.select(l1, load(lam, j));
            }
        }
        unsafe {
            p.store_run(i, na);
            p.store_run(i + off, nb);
        }
        if STORE {
            store(lam, j, l1);
        }
    }

    /// The window of sixteen particles at `i`, dealt by `split`. Without `fresh`, its
    /// multipliers are `lam[j..j + 8]` in lane order; with, only the true lanes are solved, and
    /// lane `l`'s multiplier is `lam[j + WINDOW_LANES[l]]` (slots in column order).
    ///
    /// # Safety
    /// The window lies inside the particle arrays, and no other task touches it or its
    /// multipliers.
    #[inline(always)]
    unsafe fn window<const RESET: bool, const STORE: bool>(&self, i: usize, split: Split, lam: &mut [f32], j: usize, fresh: Option<F32s>) {
        let p = self.p;
        let (lo, hi) = unsafe { (p.load_run(i), p.load_run(i + LANES)) };
        let (pa, pb) = split16_vec(lo, hi, split);
        let (wa, wb) = split16(load(self.w, i), load(self.w, i + LANES), split);
        let Some(m) = fresh else {
            let l0 = if RESET { F32s::ZERO } else { load(lam, j) };
            let (pa, pb, l1) = project8::<true, CHECK_DENOM, RESET>(pa, pb, wa, wb, self.rest, self.alpha, l0);
            let (lo, hi) = merge16_vec(pa, pb, split);
            unsafe {
                p.store_run(i, lo);
                p.store_run(i + LANES, hi);
            }
            if STORE {
                store(lam, j, l1);
            }
            return;
        };
        let live = m.to_array().map(|v| v.to_bits() != 0);
        let slot = |l: usize| j + WINDOW_LANES[l] as usize;
        let l0: [f32; LANES] = std::array::from_fn(|l| if RESET || !live[l] { 0.0 } else { lam[slot(l)] });
        let (na, nb, l1) = project8::<true, CHECK_DENOM, RESET>(pa, pb, wa, wb, self.rest, self.alpha, F32s::from(l0));
        let (lo, hi) = merge16_vec(Vec3x8::select(m, na, pa), Vec3x8::select(m, nb, pb), split);
        unsafe {
            p.store_run(i, lo);
            p.store_run(i + LANES, hi);
        }
        if STORE {
            for (l, v) in l1.to_array().into_iter().enumerate() {
                if live[l] {
                    lam[slot(l)] = v;
                }
            }
        }
    }
}
