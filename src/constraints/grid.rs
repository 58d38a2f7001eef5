//! Structured kernels for grid cloths: constraint endpoints implied by the grid.
//!
//! A grid cloth's distance constraints (see [`crate::model::cloth`]) fall into twelve
//! *classes*, each a colour (no particle twice) whose constraints share one rest length and
//! one compliance: horizontal stretch on even and on odd columns, horizontal bend on columns
//! `4k, 4k+1` and on `4k+2, 4k+3`, and the same split over rows for the anti-diagonal shear,
//! the vertical stretch, the diagonal shear and the vertical bend. A class is described by
//! its offsets, not stored: constraint `j` of row `r` joins `(r, c + a_dc)` and
//! `(r + dr, c + b_dc)`, where `c` is the `j`-th column the class takes in a row.
//!
//! The kernel walks a class row by row. Vertical and shear classes read and write two
//! contiguous runs of eight particles a block; horizontal classes read a window of sixteen
//! consecutive particles and deal them into lanes with two in-lane shuffles
//! ([`split16`](crate::data::lanes::split16)), which puts the window's eight constraints in
//! lane order `0, 1, 4, 5, 2, 3, 6, 7`; a row lists its constraints in that order (its
//! *slots*). The row's last constraints that do not fill a block run one at a time through
//! the scalar twin's arithmetic. Rest length and compliance are splatted once per row; the
//! multipliers are read and written only when the sweep keeps them.
//!
//! The four horizontal classes couple no two rows, so they run in one pass over the rows,
//! class after class on each row while it is in cache: the same bits as four passes.
//!
//! The flat arrays of a grid colour ([`Colour`](super::distance::Colour)) list its
//! constraints in the same order (rows, then slots), so the multipliers line up, the general scalar
//! twin ([`DistanceSet::solve_scalar`](super::DistanceSet::solve_scalar)) reads the explicit
//! indices, and the reference step and the other readers of the colours see every constraint.

use rayon::prelude::*;

use crate::constraints::distance::{project1, project8, CHUNK};
use crate::data::lanes::{load, merge16_vec, split16, split16_vec, store, F32s, SharedVec3, Split, LANES};

/// Cloths of fewer particles are not handed to the structured kernels by the world: they keep
/// the general colouring and with it the input-order Gauss–Seidel sweep small worlds always had
/// (the same rule as the general colouring's [`FAMILY_MIN`](super::distance::FAMILY_MIN)).
pub const GRID_MIN: u32 = 1024;

/// Where a cloth grid lies in the particle arrays: particle `(r, c)` is `first + r cols + c`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridSpec {
    /// Index of particle `(0, 0)`.
    pub first: u32,
    /// Rows.
    pub rows: u32,
    /// Columns.
    pub cols: u32,
}

/// One class of a grid's constraints (module doc). Row `r` belongs to the class when
/// `r + dr < rows` and `r mod row_mod` lies in `row_res .. row_res + row_n`; column `c` when
/// `c + max(a_dc, b_dc) < cols` and `c mod col_mod` lies in `col_res .. col_res + col_n`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Class {
    dr: u32,
    a_dc: u32,
    b_dc: u32,
    row_mod: u32,
    row_res: u32,
    row_n: u32,
    col_mod: u32,
    col_res: u32,
    col_n: u32,
}

const fn class(dr: u32, a_dc: u32, b_dc: u32, rows: (u32, u32, u32), cols: (u32, u32, u32)) -> Class {
    Class {
        dr,
        a_dc,
        b_dc,
        row_mod: rows.0,
        row_res: rows.1,
        row_n: rows.2,
        col_mod: cols.0,
        col_res: cols.1,
        col_n: cols.2,
    }
}

const ALL: (u32, u32, u32) = (1, 0, 1);

/// The twelve classes in sweep order, by index offset as the general colouring orders its
/// families: horizontal stretch, horizontal bend, anti-diagonal shear, vertical stretch,
/// diagonal shear, vertical bend.
pub const CLASSES: [Class; 12] = [
    class(0, 0, 1, ALL, (2, 0, 1)),
    class(0, 0, 1, ALL, (2, 1, 1)),
    class(0, 0, 2, ALL, (4, 0, 2)),
    class(0, 0, 2, ALL, (4, 2, 2)),
    class(1, 1, 0, (2, 0, 1), ALL),
    class(1, 1, 0, (2, 1, 1), ALL),
    class(1, 0, 0, (2, 0, 1), ALL),
    class(1, 0, 0, (2, 1, 1), ALL),
    class(1, 0, 1, (2, 0, 1), ALL),
    class(1, 0, 1, (2, 1, 1), ALL),
    class(2, 0, 0, (4, 0, 2), ALL),
    class(2, 0, 0, (4, 2, 2), ALL),
];

/// How many `x < len` have `x mod m` in `res .. res + n`.
fn count(len: u32, m: u32, res: u32, n: u32) -> u32 {
    (len / m) * n + (len % m).saturating_sub(res).min(n)
}

/// The `k`-th such `x`.
fn nth(k: u32, m: u32, res: u32, n: u32) -> u32 {
    (k / n) * m + res + k % n
}

/// Position of `x` among them, if it is one.
fn rank(x: u32, m: u32, res: u32, n: u32) -> Option<u32> {
    let q = (x % m).checked_sub(res).filter(|&q| q < n)?;
    Some((x / m) * n + q)
}

impl Class {
    fn span(&self) -> u32 {
        self.a_dc.max(self.b_dc)
    }

    /// Number of rows of a `rows x cols` grid that hold constraints of this class.
    pub fn row_count(&self, rows: u32, cols: u32) -> u32 {
        if self.per_row(cols) == 0 {
            return 0;
        }
        count(rows.saturating_sub(self.dr), self.row_mod, self.row_res, self.row_n)
    }

    /// Constraints per row.
    pub fn per_row(&self, cols: u32) -> u32 {
        count(cols.saturating_sub(self.span()), self.col_mod, self.col_res, self.col_n)
    }

    /// The grid row of the class's `k`-th row.
    pub fn row(&self, k: u32) -> u32 {
        nth(k, self.row_mod, self.row_res, self.row_n)
    }

    /// The column `c` of a row's `j`-th constraint in column order.
    fn col(&self, j: u32) -> u32 {
        nth(j, self.col_mod, self.col_res, self.col_n)
    }

    /// How a horizontal class deals a window into lanes (`None`: a vertical or shear class).
    fn split(&self) -> Option<Split> {
        match self.col_mod {
            2 => Some(Split::Pairs),
            4 => Some(Split::Quads),
            _ => None,
        }
    }

    /// Whole sixteen-particle windows in a row of a horizontal class.
    fn windows(&self, cols: u32) -> u32 {
        cols.saturating_sub(self.col_res) / 16
    }

    /// Slot `j` of a row holds the constraint of column rank `slot_rank(j)`, and the other
    /// way round: inside whole windows the lane order `0, 1, 4, 5, 2, 3, 6, 7`, which is its
    /// own inverse; elsewhere column order.
    fn slot_rank(&self, cols: u32, j: u32) -> u32 {
        const LANE: [u32; LANES] = [0, 1, 4, 5, 2, 3, 6, 7];
        let whole = self.split().map_or(0, |_| self.windows(cols) * LANES as u32);
        if j < whole {
            j - j % 8 + LANE[(j % 8) as usize]
        } else {
            j
        }
    }

    /// The grid-local particles `(a, b)` of slot `j` of the class's `k`-th row.
    pub fn pair(&self, cols: u32, k: u32, j: u32) -> (u32, u32) {
        let (r, c) = (self.row(k), self.col(self.slot_rank(cols, j)));
        (r * cols + c + self.a_dc, (r + self.dr) * cols + c + self.b_dc)
    }

    /// `(k, j)` of the grid-local pair `(a, b)` if it is a constraint of this class.
    fn locate(&self, rows: u32, cols: u32, a: u32, b: u32) -> Option<(u32, u32)> {
        let (r, ca) = (a / cols, a % cols);
        let c = ca.checked_sub(self.a_dc)?;
        let fits = r + self.dr < rows && c + self.span() < cols;
        if !fits || b != (r + self.dr) * cols + c + self.b_dc {
            return None;
        }
        let k = rank(r, self.row_mod, self.row_res, self.row_n)?;
        let j = rank(c, self.col_mod, self.col_res, self.col_n)?;
        Some((k, self.slot_rank(cols, j)))
    }

    /// Whether the class couples no two rows (its rows are all rows, its pairs within one).
    fn row_local(&self) -> bool {
        self.dr == 0 && self.row_mod == 1
    }
}

/// What a colour of grid constraints needs to run without reading its index arrays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridColour {
    /// The grid.
    pub spec: GridSpec,
    /// Index into [`CLASSES`].
    pub class: u8,
    /// The class's rest length, m.
    pub rest: f32,
    /// The class's compliance, m/N.
    pub compliance: f32,
}

impl GridColour {
    /// The colour of `class` on grid `spec` with one rest length and compliance.
    pub fn new(spec: GridSpec, class: u8, rest: f32, compliance: f32) -> Self {
        GridColour {
            spec,
            class,
            rest,
            compliance,
        }
    }

    fn cl(&self) -> &'static Class {
        &CLASSES[self.class as usize]
    }

    /// Number of the class's rows.
    pub fn rows(&self) -> u32 {
        self.cl().row_count(self.spec.rows, self.spec.cols)
    }

    /// Constraints per row.
    pub fn per_row(&self) -> u32 {
        self.cl().per_row(self.spec.cols)
    }

    /// Whether the colour's class couples no two rows.
    pub fn row_local(&self) -> bool {
        self.cl().row_local()
    }
}

/// Sorts a grid's constraints (global indices) into classes: for each class, its constraints'
/// input positions in row-major order, or `None` when the constraints are not exactly a set of
/// whole classes, each with one rest length and one compliance.
pub fn classify(spec: GridSpec, pairs: impl Iterator<Item = (u32, u32, f32, f32)>) -> Option<Vec<Vec<usize>>> {
    let GridSpec { first, rows, cols } = spec;
    let mut slots: Vec<Vec<usize>> = CLASSES.iter().map(|_| Vec::new()).collect();
    let mut values: Vec<Option<(u32, u32)>> = vec![None; CLASSES.len()];
    for (pos, (a, b, rest, compliance)) in pairs.enumerate() {
        let (a, b) = (a.checked_sub(first)?, b.checked_sub(first)?);
        if a >= rows * cols || b >= rows * cols {
            return None;
        }
        let (t, k, j) = CLASSES
            .iter()
            .enumerate()
            .find_map(|(t, cl)| cl.locate(rows, cols, a, b).map(|(k, j)| (t, k, j)))?;
        let bits = (rest.to_bits(), compliance.to_bits());
        if *values[t].get_or_insert(bits) != bits {
            return None;
        }
        let cl = &CLASSES[t];
        let slot = &mut slots[t];
        if slot.is_empty() {
            slot.resize((cl.row_count(rows, cols) * cl.per_row(cols)) as usize, usize::MAX);
        }
        let at = &mut slot[(k * cl.per_row(cols) + j) as usize];
        if *at != usize::MAX {
            return None;
        }
        *at = pos;
    }
    slots.iter().all(|s| s.iter().all(|&p| p != usize::MAX)).then_some(slots)
}

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
    pub(crate) fn new(lambda: &mut [f32]) -> Self {
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

/// One pass over the rows of one or more colours of one grid (all row-local, or a single
/// colour; unused slots are `None`), `RESET`: the multipliers read as zero; `STORE`: they are written.
pub(crate) fn run_pass<const RESET: bool, const STORE: bool>(colours: &[Option<(GridColour, Multipliers)>], s: &Sweep<'_>, parallel: bool) {
    let rows = colours.iter().flatten().map(|(g, _)| g.rows()).max().unwrap_or(0);
    let work: u32 = colours.iter().flatten().map(|(g, _)| g.per_row()).sum();
    if rows == 0 || work == 0 {
        return;
    }
    let task_rows = (CHUNK as u32 / work).max(1);
    let rows_of = |t: u32| t * task_rows..((t + 1) * task_rows).min(rows);
    // SAFETY (both arms): within one colour no particle repeats; a row-local pass's colours
    // touch only their own row, and a pass of several colours is row-local, so tasks that
    // own disjoint rows touch disjoint particles and multipliers.
    let task = |t: u32| {
        for k in rows_of(t) {
            for (g, lambda) in colours.iter().flatten() {
                unsafe { row::<RESET, STORE>(g, k, lambda, s) };
            }
        }
    };
    let tasks = rows.div_ceil(task_rows);
    if parallel && tasks > 1 {
        (0..tasks).into_par_iter().for_each(task);
    } else {
        (0..tasks).for_each(task);
    }
}

/// Solves row `k` of a grid colour: whole blocks in SIMD, the rest one at a time.
///
/// # Safety
/// No other task touches the row's particles or multipliers.
#[inline(always)]
unsafe fn row<const RESET: bool, const STORE: bool>(g: &GridColour, k: u32, lambda: &Multipliers, s: &Sweep<'_>) {
    let cl = g.cl();
    let (per_row, cols) = (g.per_row(), g.spec.cols);
    if k >= g.rows() {
        return;
    }
    // SAFETY: the caller owns row `k`.
    let lam = unsafe { lambda.row(k, per_row) };
    let r = cl.row(k);
    let row_start = (g.spec.first + r * cols) as usize;
    let off = (cl.dr * cols + cl.b_dc) as usize - cl.a_dc as usize;
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
                let i = row_start + cl.a_dc as usize + q * LANES;
                let (pa, pb) = unsafe { (p.load_run(i), p.load_run(i + off)) };
                let l0 = if RESET { F32s::ZERO } else { load(lam, q * LANES) };
                let (pa, pb, l1) = project8(pa, pb, load(w, i), load(w, i + off), rest, alpha, l0);
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
                let i = row_start + cl.col_res as usize + 16 * q;
                let (lo, hi) = unsafe { (p.load_run(i), p.load_run(i + LANES)) };
                let (pa, pb) = split16_vec(lo, hi, split);
                let (wa, wb) = split16(load(w, i), load(w, i + LANES), split);
                let l0 = if RESET { F32s::ZERO } else { load(lam, q * LANES) };
                let (pa, pb, l1) = project8(pa, pb, wa, wb, rest, alpha, l0);
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
        let a = row_start + (c + cl.a_dc) as usize;
        let b = a + off;
        let l0 = if RESET { 0.0 } else { *l };
        // SAFETY: as above.
        let (pa, pb) = unsafe { (p.get(a), p.get(b)) };
        let (pa, pb, l1) = project1(pa, pb, w[a], w[b], g.rest, alpha, l0);
        unsafe {
            p.set(a, pa);
            p.set(b, pb);
        }
        if STORE {
            *l = l1;
        }
    }
}

#[cfg(test)]
#[path = "grid_tests.rs"]
mod tests;
