//! The structured sweep of grid colours ([`grid`](super::grid)): one pass over a grid's band
//! colours or its seam colours, a task per band or seam, row by row.

use rayon::prelude::*;

use crate::constraints::distance::{project1, project8, Colour};
use crate::constraints::grid::GridColour;
use crate::data::lanes::{load, merge16_vec, split16, split16_vec, store, F32s, SharedVec3, LANES};

/// A pass's constraints below which it runs on one thread: a fork and join costs more than the
/// second thread saves.
pub const SERIAL_MAX: usize = 16_384;

/// Most colours one pass holds: the twelve classes.
const MAX_COLOURS: usize = 12;

/// A colour's multipliers as a raw view: the tasks of a pass write disjoint rows of it.
#[derive(Clone, Copy)]
pub(crate) struct Multipliers {
    ptr: *mut f32,
    len: usize,
}

// SAFETY: a pointer and a length; rows are handed to one task each (see `row`).
unsafe impl Send for Multipliers {}
// SAFETY: as above.
unsafe impl Sync for Multipliers {}

impl Multipliers {
    const EMPTY: Multipliers = Multipliers {
        ptr: std::ptr::null_mut(),
        len: 0,
    };

    fn new(lambda: &mut [f32]) -> Self {
        Multipliers {
            ptr: lambda.as_mut_ptr(),
            len: lambda.len(),
        }
    }

    /// Row `k` of `per_row` multipliers.
    ///
    /// # Safety
    /// No other live reference covers this row (each row belongs to one task of a pass), and
    /// the slice is dropped before the pass ends (the colour outlives the pass).
    unsafe fn row<'a>(self, k: u32, per_row: u32) -> &'a mut [f32] {
        let (s, n) = (k as usize * per_row as usize, per_row as usize);
        assert!(s + n <= self.len);
        // SAFETY: in bounds (checked above) and exclusive by the caller's guarantee.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(s), n) }
    }
}

/// Per-sweep settings shared by every row.
#[derive(Clone, Copy)]
pub(crate) struct Sweep<'a> {
    pub p: SharedVec3,
    pub w: &'a [f32],
    pub inv_h2: f32,
}

/// One pass over colours of one grid that share their groups (its band colours, or its seam
/// colours): a task per group runs each colour's rows of that group, colour after colour.
/// `RESET`: the multipliers read as zero; `STORE`: they are written.
pub(crate) fn run_pass<const RESET: bool, const STORE: bool>(colours: &mut [Colour], s: &Sweep<'_>, parallel: bool) {
    assert!(colours.len() <= MAX_COLOURS && colours.iter().all(|c| c.grid.is_some()));
    let mut lambdas = [Multipliers::EMPTY; MAX_COLOURS];
    for (m, c) in lambdas.iter_mut().zip(colours.iter_mut()) {
        *m = Multipliers::new(&mut c.lambda);
    }
    let colours: &[Colour] = colours;
    let Some(groups) = colours.first().and_then(|c| c.grid.as_ref()).map(GridColour::group_count) else {
        return;
    };
    // SAFETY: a group's rows hold constraints of that group only; groups (bands, or seams of
    // boundaries at least four rows apart) share no particle, and each multiplier row
    // belongs to one group, so tasks touch disjoint particles and multipliers.
    let task = |q: usize| {
        for (c, lambda) in colours.iter().zip(&lambdas) {
            let Some(g) = &c.grid else { continue };
            for i in g.group(q) {
                unsafe { row::<RESET, STORE>(g, i, lambda, s) };
            }
        }
    };
    let work: usize = colours.iter().map(|c| c.real).sum();
    if parallel && groups > 1 && work > SERIAL_MAX {
        (0..groups).into_par_iter().for_each(task);
    } else {
        (0..groups).for_each(task);
    }
}

/// Solves the row at position `at` of a grid colour: whole blocks in SIMD, the rest one at a
/// time.
///
/// # Safety
/// No other task touches the row's particles or multipliers.
#[inline(always)]
unsafe fn row<const RESET: bool, const STORE: bool>(g: &GridColour, at: usize, lambda: &Multipliers, s: &Sweep<'_>) {
    let cl = g.cl();
    let (per_row, cols) = (g.per_row(), g.spec.cols);
    // SAFETY: the caller owns this row.
    let lam = unsafe { lambda.row(at as u32, per_row) };
    let r = g.row_at(at);
    let row_start = (g.spec.first + r * cols) as usize;
    let (a_dc, b_dc) = cl.dc();
    let off = (cl.dr() * cols + b_dc) as usize - a_dc as usize;
    let inv_h2 = F32s::splat(s.inv_h2);
    let rest = F32s::splat(g.rest);
    let alpha = F32s::splat(g.compliance) * inv_h2;
    let (p, w) = (&s.p, s.w);
    // SAFETY (loads and stores): every index is a particle of this row's constraints (inside
    // the grid, so below the array length) and owned by the caller. A run block's `a` run is
    // in row `r`, its `b` run in row `r + dr > r`: disjoint. A window block owns its sixteen
    // particles.
    let done = match cl.split() {
        None => {
            let blocks = per_row as usize / LANES;
            for q in 0..blocks {
                let i = row_start + a_dc as usize + q * LANES;
                let (pa, pb) = unsafe { (p.load_run(i), p.load_run(i + off)) };
                let l0 = if RESET { F32s::ZERO } else { load(lam, q * LANES) };
                let (pa, pb, l1) = project8::<true>(pa, pb, load(w, i), load(w, i + off), rest, alpha, l0);
                unsafe {
                    p.store_run(i, pa);
                    p.store_run(i + off, pb);
                }
                if STORE {
                    store(lam, q * LANES, l1);
                }
            }
            blocks * LANES
        }
        Some(split) => {
            let whole = cl.windows(cols) as usize;
            for q in 0..whole {
                let i = row_start + cl.col_res() as usize + 16 * q;
                let (lo, hi) = unsafe { (p.load_run(i), p.load_run(i + LANES)) };
                let (pa, pb) = split16_vec(lo, hi, split);
                let (wa, wb) = split16(load(w, i), load(w, i + LANES), split);
                let l0 = if RESET { F32s::ZERO } else { load(lam, q * LANES) };
                let (pa, pb, l1) = project8::<true>(pa, pb, wa, wb, rest, alpha, l0);
                let (lo, hi) = merge16_vec(pa, pb, split);
                unsafe {
                    p.store_run(i, lo);
                    p.store_run(i + LANES, hi);
                }
                if STORE {
                    store(lam, q * LANES, l1);
                }
            }
            whole * LANES
        }
    };
    let alpha = g.compliance * s.inv_h2;
    for (j, l) in lam.iter_mut().enumerate().skip(done) {
        let c = cl.col(j as u32);
        let a = row_start + (c + a_dc) as usize;
        let b = a + off;
        let l0 = if RESET { 0.0 } else { *l };
        // SAFETY: as above.
        let (pa, pb) = unsafe { (p.get(a), p.get(b)) };
        let (pa, pb, l1) = project1::<true>(pa, pb, w[a], w[b], g.rest, alpha, l0);
        unsafe {
            p.set(a, pa);
            p.set(b, pb);
        }
        if STORE {
            *l = l1;
        }
    }
}
