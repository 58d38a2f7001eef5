//! The cloth builder: a rectangular particle grid with stretch, shear and bending distance
//! constraints, pins, long-range attachments (tethers) and render/collision triangles.
//!
//! Particle `(r, c)` of a `rows x cols` grid sits at `origin + c * spacing * u + r * spacing * v`
//! and has index `first + r * cols + c`. Constraints (all XPBD distance constraints):
//! - stretch: `(r,c)-(r,c+1)` and `(r,c)-(r+1,c)`;
//! - shear: both diagonals of every quad;
//! - bend: `(r,c)-(r,c+2)` and `(r,c)-(r+2,c)` (distance bending).
//!
//! Tethers (long-range attachments, Kim et al. 2012): each free particle is tied to its nearest
//! pinned particle by a one-sided constraint `|p - anchor| <= (1 + slack) * rest distance`.
//! They stop the rubbery over-stretch that low iteration counts otherwise show.

use crate::error::{finite3, positive, Result, WeftError};
use crate::model::fabric::Fabric;

/// Which particles of a grid are pinned (inverse mass 0).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum PinSpec {
    /// Particle indices within this cloth (`r * cols + c`).
    Indices(Vec<u32>),
    /// Grid cells `[row, col]`.
    Cells(Vec<[u32; 2]>),
    /// The four corners: `"first-row"` corners are `(0,0)` and `(0,cols-1)`.
    FirstRowCorners,
    /// A whole row.
    Row(u32),
    /// Every particle whose rest position lies inside the axis-aligned box.
    Region {
        /// Box minimum corner, m.
        min: [f32; 3],
        /// Box maximum corner, m.
        max: [f32; 3],
    },
}

/// A rectangular cloth to build.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClothDesc {
    /// Rows of particles (along `v`).
    pub rows: u32,
    /// Columns of particles (along `u`).
    pub cols: u32,
    /// Rest distance between grid neighbours, m.
    pub spacing: f32,
    /// Position of particle `(0, 0)`, m.
    pub origin: [f32; 3],
    /// Direction of increasing column (normalised on build).
    pub u: [f32; 3],
    /// Direction of increasing row (normalised on build).
    pub v: [f32; 3],
    /// Material.
    pub fabric: Fabric,
    /// Pinned particles.
    pub pins: Vec<PinSpec>,
    /// Include shear constraints.
    pub shear: bool,
    /// Include bending constraints.
    pub bend: bool,
    /// Tether slack (fraction of rest distance) or `None` for no tethers.
    pub tethers: Option<f32>,
}

impl Default for ClothDesc {
    fn default() -> Self {
        ClothDesc {
            rows: 20,
            cols: 20,
            spacing: 0.05,
            origin: [0.0, 1.0, 0.0],
            u: [1.0, 0.0, 0.0],
            v: [0.0, -1.0, 0.0],
            fabric: Fabric::default(),
            pins: vec![PinSpec::FirstRowCorners],
            shear: true,
            bend: true,
            tethers: Some(0.02),
        }
    }
}

/// Kind of a distance constraint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ConstraintKind {
    /// Grid neighbours.
    Stretch,
    /// Quad diagonals.
    Shear,
    /// Distance-two neighbours.
    Bend,
}

/// One distance constraint before colouring (indices local to the cloth).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Rest length, m.
    pub rest: f32,
    /// XPBD compliance, m/N.
    pub compliance: f32,
    /// What the constraint models.
    pub kind: ConstraintKind,
}

/// A one-sided long-range attachment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tether {
    /// The free particle.
    pub particle: u32,
    /// The pinned particle it is tied to.
    pub anchor: u32,
    /// Largest allowed distance, m.
    pub max_len: f32,
}

/// The output of [`ClothDesc::build`]: everything with cloth-local indices.
#[derive(Clone, Debug, Default)]
pub struct ClothBuild {
    /// Rest positions.
    pub positions: Vec<[f32; 3]>,
    /// Inverse masses (0 for pins).
    pub inv_mass: Vec<f32>,
    /// Distance constraints.
    pub edges: Vec<Edge>,
    /// Tethers.
    pub tethers: Vec<Tether>,
    /// Triangles (two per quad), counter-clockwise seen from `u x v`.
    pub triangles: Vec<[u32; 3]>,
}

fn normalize(name: &str, v: [f32; 3]) -> Result<[f32; 3]> {
    let v = finite3(name, v)?;
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if l.is_finite() && l > 1e-12 {
        Ok([v[0] / l, v[1] / l, v[2] / l])
    } else {
        Err(WeftError::param(name, format!("{v:?}"), "must be a non-zero direction"))
    }
}

/// Largest number of particles one cloth may have (indices are `u32`).
pub const MAX_PARTICLES: u64 = 1 << 28;

impl ClothDesc {
    /// Upper bounds of what [`build`](Self::build) makes, from the grid size alone (nothing is
    /// built): the counts of the memory estimate ([`crate::model::budget`]).
    pub fn memory_counts(&self) -> crate::model::budget::MemoryCounts {
        let (r, c) = (self.rows as u64, self.cols as u64);
        // Sums of products of u32 values, each term below 2^64; two terms can overflow.
        let pair = |a: u64, b: u64, x: u64, y: u64| (a * b).saturating_add(x * y);
        let n = r * c;
        let quads = r.saturating_sub(1) * c.saturating_sub(1);
        let stretch = pair(r, c.saturating_sub(1), r.saturating_sub(1), c);
        let shear = if self.shear { quads.saturating_mul(2) } else { 0 };
        let bend = if self.bend {
            pair(r, c.saturating_sub(2), r.saturating_sub(2), c)
        } else {
            0
        };
        crate::model::budget::MemoryCounts {
            particles: n,
            constraints: stretch.saturating_add(shear).saturating_add(bend),
            tethers: if self.tethers.is_some() { n } else { 0 },
            triangles: quads.saturating_mul(2),
            ..Default::default()
        }
    }

    /// Validates the description and builds the grid.
    pub fn build(&self) -> Result<ClothBuild> {
        let (rows, cols) = (self.rows as usize, self.cols as usize);
        if rows == 0 || cols == 0 {
            return Err(WeftError::param(
                "rows x cols",
                format!("{rows} x {cols}"),
                "a cloth needs at least one row and one column",
            ));
        }
        if (rows as u64) * (cols as u64) > MAX_PARTICLES {
            return Err(WeftError::param(
                "rows x cols",
                format!("{rows} x {cols}"),
                format!("at most {MAX_PARTICLES} particles per cloth"),
            ));
        }
        let s = positive("spacing", self.spacing)?;
        let origin = finite3("origin", self.origin)?;
        let u = normalize("u", self.u)?;
        let v = normalize("v", self.v)?;
        let cr = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        if (cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]).sqrt() < 1e-3 {
            return Err(WeftError::param(
                "u, v",
                format!("{u:?}, {v:?}"),
                "the grid directions must not be parallel",
            ));
        }
        self.fabric.validate()?;
        if let Some(slack) = self.tethers {
            if !(slack.is_finite() && slack >= 0.0) {
                return Err(WeftError::param("tethers", slack, "slack must be a finite number, zero or greater"));
            }
        }
        let n = rows * cols;
        let mut out = ClothBuild {
            positions: Vec::with_capacity(n),
            inv_mass: vec![1.0 / self.fabric.mass; n],
            ..Default::default()
        };
        for r in 0..rows {
            for c in 0..cols {
                let (fc, fr) = (c as f32 * s, r as f32 * s);
                out.positions.push([
                    origin[0] + fc * u[0] + fr * v[0],
                    origin[1] + fc * u[1] + fr * v[1],
                    origin[2] + fc * u[2] + fr * v[2],
                ]);
            }
        }
        self.apply_pins(&mut out)?;
        let id = |r: usize, c: usize| (r * cols + c) as u32;
        let f = &self.fabric;
        // The shear diagonals' rest lengths are measured on the built grid, so a cloth whose
        // directions u and v are not perpendicular starts at rest too (s * sqrt 2 holds only for
        // perpendicular directions; assuming it would make such cloths move by themselves).
        let len = |a: [f32; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        let diag_down = s * len([u[0] + v[0], u[1] + v[1], u[2] + v[2]]);
        let diag_up = s * len([u[0] - v[0], u[1] - v[1], u[2] - v[2]]);
        let mut push = |a: u32, b: u32, rest: f32, compliance: f32, kind| {
            out.edges.push(Edge {
                a,
                b,
                rest,
                compliance,
                kind,
            });
        };
        for r in 0..rows {
            for c in 0..cols {
                if c + 1 < cols {
                    push(id(r, c), id(r, c + 1), s, f.stretch_compliance, ConstraintKind::Stretch);
                }
                if r + 1 < rows {
                    push(id(r, c), id(r + 1, c), s, f.stretch_compliance, ConstraintKind::Stretch);
                }
                if self.shear && r + 1 < rows && c + 1 < cols {
                    push(id(r, c), id(r + 1, c + 1), diag_down, f.shear_compliance, ConstraintKind::Shear);
                    push(id(r, c + 1), id(r + 1, c), diag_up, f.shear_compliance, ConstraintKind::Shear);
                }
                if self.bend && c + 2 < cols {
                    push(id(r, c), id(r, c + 2), 2.0 * s, f.bend_compliance, ConstraintKind::Bend);
                }
                if self.bend && r + 2 < rows {
                    push(id(r, c), id(r + 2, c), 2.0 * s, f.bend_compliance, ConstraintKind::Bend);
                }
            }
        }
        // Edges between two pinned particles move nothing (the projection skips a constraint
        // whose inverse masses and compliance sum to zero, and scales by zero masses
        // otherwise) but are kept: the grid stays complete for the structured kernels
        // (`constraints::grid`), which a pinned row would otherwise lock out.
        for r in 0..rows.saturating_sub(1) {
            for c in 0..cols.saturating_sub(1) {
                out.triangles.push([id(r, c), id(r, c + 1), id(r + 1, c + 1)]);
                out.triangles.push([id(r, c), id(r + 1, c + 1), id(r + 1, c)]);
            }
        }
        if let Some(slack) = self.tethers {
            out.tethers = tethers_to_nearest_pin(&out.positions, &out.inv_mass, rows, cols, slack);
        }
        Ok(out)
    }

    fn apply_pins(&self, out: &mut ClothBuild) -> Result<()> {
        let (rows, cols) = (self.rows, self.cols);
        let n = out.positions.len();
        let positions = std::mem::take(&mut out.positions);
        let mut pin = |i: u64, what: &str| -> Result<()> {
            if i >= n as u64 {
                return Err(WeftError::param("pins", what, format!("outside the {rows} x {cols} grid")));
            }
            out.inv_mass[i as usize] = 0.0;
            Ok(())
        };
        for p in &self.pins {
            match p {
                PinSpec::Indices(ix) => {
                    for &i in ix {
                        pin(i as u64, &format!("index {i}"))?;
                    }
                }
                PinSpec::Cells(cells) => {
                    for &[r, c] in cells {
                        if r >= rows || c >= cols {
                            return Err(WeftError::param(
                                "pins",
                                format!("cell [{r}, {c}]"),
                                format!("outside the {rows} x {cols} grid"),
                            ));
                        }
                        pin(r as u64 * cols as u64 + c as u64, "cell")?;
                    }
                }
                PinSpec::FirstRowCorners => {
                    pin(0, "corner")?;
                    pin(cols as u64 - 1, "corner")?;
                }
                PinSpec::Row(r) => {
                    if *r >= rows {
                        return Err(WeftError::param(
                            "pins",
                            format!("row {r}"),
                            format!("outside the {rows} x {cols} grid"),
                        ));
                    }
                    for c in 0..cols {
                        pin(*r as u64 * cols as u64 + c as u64, "row")?;
                    }
                }
                PinSpec::Region { min, max } => {
                    finite3("pins.region.min", *min)?;
                    finite3("pins.region.max", *max)?;
                    for (i, q) in positions.iter().enumerate() {
                        if (0..3).all(|k| q[k] >= min[k] && q[k] <= max[k]) {
                            pin(i as u64, "region")?;
                        }
                    }
                }
            }
        }
        out.positions = positions;
        Ok(())
    }
}

/// For each free particle, a tether to the nearest pinned particle (ties: lowest index).
/// Grid-aware: the search is over the pinned list, which is short in practice; with many
/// pins the cost is `O(free x pinned)`, bounded here by sampling at most 256 pins evenly.
fn tethers_to_nearest_pin(pos: &[[f32; 3]], w: &[f32], _rows: usize, _cols: usize, slack: f32) -> Vec<Tether> {
    let pinned: Vec<usize> = (0..pos.len()).filter(|&i| w[i] == 0.0).collect();
    if pinned.is_empty() {
        return Vec::new();
    }
    let step = pinned.len().div_ceil(256).max(1);
    let anchors: Vec<usize> = pinned.iter().copied().step_by(step).collect();
    let mut out = Vec::with_capacity(pos.len() - pinned.len());
    for i in 0..pos.len() {
        if w[i] == 0.0 {
            continue;
        }
        let mut best = (f32::INFINITY, 0usize);
        for &a in &anchors {
            let d = [pos[i][0] - pos[a][0], pos[i][1] - pos[a][1], pos[i][2] - pos[a][2]];
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if l < best.0 {
                best = (l, a);
            }
        }
        out.push(Tether {
            particle: i as u32,
            anchor: best.1 as u32,
            max_len: best.0 * (1.0 + slack),
        });
    }
    out
}

#[cfg(test)]
#[path = "cloth_tests.rs"]
mod tests;
