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
//! *slots*). The row's last constraints that do not fill a block run as one more block that
//! ends at the row's end, whose lanes already solved keep their values (`grid_row.rs`); the
//! rare constraints that block cannot reach, and rows too short for a block, run one at a
//! time through the scalar twin's arithmetic. Rest length and compliance are splatted once
//! per row; the multipliers are read and written only when the sweep keeps them.
//!
//! The grid is cut into bands of rows ([`layout`]): one parallel pass sweeps each band through
//! all twelve classes while it is in cache, a second sweeps the constraints that cross band
//! boundaries ([`grid_sweep`](super::grid_sweep)).
//!
//! The flat arrays of a grid colour ([`Colour`](super::distance::Colour)) list its
//! constraints in the same order (rows, then slots), so the multipliers line up, the general scalar
//! twin ([`DistanceSet::solve_scalar`](super::DistanceSet::solve_scalar)) reads the explicit
//! indices, and the reference step and the other readers of the colours see every constraint.

use crate::data::lanes::{Split, LANES};

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
    pub(crate) fn col(&self, j: u32) -> u32 {
        nth(j, self.col_mod, self.col_res, self.col_n)
    }

    /// How a horizontal class deals a window into lanes (`None`: a vertical or shear class).
    pub(crate) fn split(&self) -> Option<Split> {
        match self.col_mod {
            2 => Some(Split::Pairs),
            4 => Some(Split::Quads),
            _ => None,
        }
    }

    /// Whole sixteen-particle windows in a row of a horizontal class.
    pub(crate) fn windows(&self, cols: u32) -> u32 {
        cols.saturating_sub(self.col_res) / 16
    }

    /// The last sixteen-particle window a row of a horizontal class holds, by its first column
    /// and the column rank of its first constraint (`None` when the row holds no window).
    pub(crate) fn last_window(&self, cols: u32) -> Option<(u32, u32)> {
        let top = cols.checked_sub(16)?.checked_sub(self.col_res)?;
        let s = top - top % self.col_mod + self.col_res;
        Some((s, s / self.col_mod * self.col_n))
    }

    /// Slot `j` of a row holds the constraint of column rank `slot_rank(j)`, and the other
    /// way round: inside whole windows the lane order `0, 1, 4, 5, 2, 3, 6, 7`, which is its
    /// own inverse; elsewhere column order.
    fn slot_rank(&self, cols: u32, j: u32) -> u32 {
        let whole = self.split().map_or(0, |_| self.windows(cols) * LANES as u32);
        if j < whole {
            j - j % 8 + WINDOW_LANES[(j % 8) as usize]
        } else {
            j
        }
    }

    /// The grid-local particles `(a, b)` of slot `j` of the class's `k`-th row.
    pub fn pair(&self, cols: u32, k: u32, j: u32) -> (u32, u32) {
        let (r, c) = (self.row(k), self.col(self.slot_rank(cols, j)));
        (r * cols + c + self.a_dc, (r + self.dr) * cols + c + self.b_dc)
    }

    /// Rows between a constraint's two particles.
    pub(crate) fn dr(&self) -> u32 {
        self.dr
    }

    /// Column offsets of a constraint's particles from its column `c`.
    pub(crate) fn dc(&self) -> (u32, u32) {
        (self.a_dc, self.b_dc)
    }

    /// The first column a row's constraints start from (residue), for windows.
    pub(crate) fn col_res(&self) -> u32 {
        self.col_res
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
}

/// The rank, within its window, of the constraint lane `l` of a window holds (its own inverse).
pub(crate) const WINDOW_LANES: [u32; LANES] = [0, 1, 4, 5, 2, 3, 6, 7];

/// Rows per band of a grid with `cols` columns (see [`layout`]): at most 16 and about 16k
/// particles, at least 4 so that the seams of two boundaries share no particle.
pub fn band_rows(cols: u32) -> u32 {
    (BAND_PARTICLES / cols.max(1)).clamp(4, 16)
}

/// About how many particles a band holds (256 KB of predictions and inverse masses: L2).
const BAND_PARTICLES: u32 = 16_384;

/// What a colour of grid constraints needs to run without reading its index arrays.
#[derive(Clone, Debug, PartialEq)]
pub struct GridColour {
    /// The grid.
    pub spec: GridSpec,
    /// Index into [`CLASSES`].
    pub class: u8,
    /// The constraints that cross a band boundary (else those inside a band).
    pub seam: bool,
    /// The class's rest length, m.
    pub rest: f32,
    /// The class's compliance, m/N.
    pub compliance: f32,
    /// The grid rows this colour holds constraints of, ascending.
    rows: Vec<u32>,
    /// Group `g` (band `g`, or the seam below band `g`) holds rows `groups[g] .. groups[g + 1]`
    /// of [`rows`](Self::rows).
    groups: Vec<u32>,
}

impl GridColour {
    /// Whether the sweeps read and write this colour's multipliers: not for a colour without
    /// compliance, whose multipliers neither move a particle (they enter as `α̃ λ`) nor count
    /// in [`World::metrics`](crate::World::metrics)' elastic energy (`½ α f²`). Its sweeps read
    /// them as zero, as a reset does, and store none.
    pub fn keeps_multipliers(&self) -> bool {
        self.compliance != 0.0
    }

    /// The class's `α̃ = α / h²` for `inv_h2 = 1 / h²`, one rounding: what its rows project
    /// with and what picks their kernel.
    pub(crate) fn alpha(&self, inv_h2: f32) -> f32 {
        self.compliance * inv_h2
    }

    pub(crate) fn cl(&self) -> &'static Class {
        &CLASSES[self.class as usize]
    }

    /// Constraints per row.
    pub fn per_row(&self) -> u32 {
        self.cl().per_row(self.spec.cols)
    }

    /// Number of groups (bands or seams) the colour's rows fall in.
    pub fn group_count(&self) -> usize {
        self.groups.len() - 1
    }

    /// The positions in [`rows`](Self::rows) of group `g`'s rows.
    pub(crate) fn group(&self, g: usize) -> std::ops::Range<usize> {
        self.groups[g] as usize..self.groups[g + 1] as usize
    }

    /// The grid row at position `i`.
    pub(crate) fn row_at(&self, i: usize) -> u32 {
        self.rows[i]
    }
}

/// The colours of a grid whose constraints [`classify`] sorted into `classes`, in sweep order,
/// each with the input positions of its constraints in its order (rows, then slots).
///
/// The grid is cut into bands of [`band_rows`] rows. First every class's constraints inside a
/// band (one colour per class; a task sweeps one band through all twelve while it is in
/// cache), then the vertical and shear classes' constraints that cross a band boundary (one
/// colour per class; a task sweeps one boundary). Bands share no particle, nor do the seams of
/// two boundaries, so running the colours one after the other gives the same bits as running
/// bands (then seams) in parallel. Rest length and compliance are left at zero for the caller.
pub fn layout(spec: GridSpec, classes: &[Vec<usize>]) -> Vec<(GridColour, Vec<usize>)> {
    let GridSpec { rows, cols, .. } = spec;
    let b = band_rows(cols);
    let bands = rows.div_ceil(b) as usize;
    let mut out = Vec::new();
    for seam in [false, true] {
        for (t, (cl, slots)) in CLASSES.iter().zip(classes).enumerate() {
            if slots.is_empty() || (seam && cl.dr == 0) {
                continue;
            }
            let per_row = cl.per_row(cols) as usize;
            let mut g = GridColour {
                spec,
                class: t as u8,
                seam,
                rest: 0.0,
                compliance: 0.0,
                rows: Vec::new(),
                groups: vec![0; if seam { bands } else { bands + 1 }],
            };
            let mut pos = Vec::new();
            for k in 0..cl.row_count(rows, cols) {
                let r = cl.row(k);
                if (r / b != (r + cl.dr) / b) != seam {
                    continue;
                }
                g.rows.push(r);
                g.groups[(r / b) as usize + 1] += 1;
                pos.extend_from_slice(&slots[k as usize * per_row..(k as usize + 1) * per_row]);
            }
            for q in 1..g.groups.len() {
                g.groups[q] += g.groups[q - 1];
            }
            if !g.rows.is_empty() {
                out.push((g, pos));
            }
        }
    }
    out
}

/// Sorts a grid's constraints (global indices) into classes: for each class, its constraints'
/// input positions in row-major order, or `None` when the constraints are not exactly a set of
/// whole classes, each with one rest length and one compliance.
pub fn classify(spec: GridSpec, pairs: impl Iterator<Item = (u32, u32, f32, f32)>) -> Option<Vec<Vec<usize>>> {
    let GridSpec { first, rows, cols } = spec;
    let n = rows.checked_mul(cols).filter(|&n| n > 0)?;
    first.checked_add(n)?;
    let mut slots: Vec<Vec<usize>> = CLASSES.iter().map(|_| Vec::new()).collect();
    let mut values: Vec<Option<(u32, u32)>> = vec![None; CLASSES.len()];
    for (pos, (a, b, rest, compliance)) in pairs.enumerate() {
        let (a, b) = (a.checked_sub(first)?, b.checked_sub(first)?);
        if a >= n || b >= n {
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

#[cfg(test)]
#[path = "grid_tests.rs"]
mod tests;
