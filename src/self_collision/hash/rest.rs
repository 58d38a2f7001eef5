//! Rest data for the self-collision query of the spatial hash (module `hash::cells`): each pair
//! once, rest neighbours dropped, both decided inside the eight-lane mask.
//!
//! # What the query computes
//! For every particle `i`, the ids `j` with
//!
//! ```text
//! j > i  and  (dx*dx + dy*dy) + dz*dz <= max_dist²         (the shared predicate, x_j - x_i)
//!        and  not (cloth_j == cloth_i and |r_i - r_j|² <= skip²)     (r: rest positions)
//! ```
//!
//! (with the particles' travels attached, [`SpatialHash::attach_travel`], each pair's own
//! reach `(d + (t_i + t_j) d)²` stands for `max_dist²`), sorted ascending: the rest-neighbour
//! rule of Müller's "Ten Minute Physics" self-collision
//! as the self-collision stage applies it (`RestData::skipped` in `crate::self_collision::broadphase`; the
//! rest distance is computed there as `(r_i - r_j)` per axis, squared and summed in the same
//! order, no FMA, so both decide alike).
//!
//! # Why a copy
//! In a flat cloth every pair within the reach `q` is a rest neighbour. Reading rest positions
//! from scattered ids for every candidate would cost three scalar gathers each; instead
//! [`SpatialHash::attach_rest`] copies the rest positions, cloth ids and particle ids into
//! `cell_entries` order once per build (a gather of `n` particles), so the three tests are lane
//! operations on contiguous data and only kept pairs reach scalar code. The query reads the
//! positions from the build's cell-ordered copy, so unlike [`SpatialHash::query_all`] it needs
//! no pass checking that it was given the build's positions.

use crate::data::lanes::LANES;
use crate::self_collision::hash::SpatialHash;
use crate::{Result, WeftError};

/// Rest data in `cell_entries` order, padded with [`LANES`] entries (NaN positions, id 0), so
/// lane loads never leave the arrays and padding lanes are never kept.
#[derive(Debug, Clone, Default)]
pub(super) struct RestCopy {
    pub(super) x: Vec<f32>,
    pub(super) y: Vec<f32>,
    pub(super) z: Vec<f32>,
    pub(super) cloth: Vec<u32>,
    pub(super) ids: Vec<u32>,
    /// Each particle's travel in cell order and the collision distance, when attached
    /// ([`SpatialHash::attach_travel`]): the query then keeps a pair within its own reach.
    pub(super) travel: Vec<f32>,
    pub(super) d: Option<f32>,
    /// With travels attached: the largest travel of a cell's members, and the largest of all.
    pub(super) cell: f32,
    pub(super) top: f32,
    /// Whether the copy belongs to the current build (cleared by every build).
    pub(super) valid: bool,
}

impl SpatialHash {
    /// Copies the rest positions `rest` and cloth ids `cloth` of particles `0..n` (the last
    /// build's) into cell order, for [`SpatialHash::query_upper_unskipped_cells`]. Errors if an
    /// array is shorter than the build's particle count.
    pub fn attach_rest(&mut self, rest: [&[f32]; 3], cloth: &[u32]) -> Result<()> {
        let n = self.n;
        for (name, len) in [
            ("rest x", rest[0].len()),
            ("rest y", rest[1].len()),
            ("rest z", rest[2].len()),
            ("cloth", cloth.len()),
        ] {
            if len < n {
                return Err(WeftError::BufferLength {
                    name,
                    got: len,
                    expected: n,
                });
            }
        }
        let placed = self.cell_entries.len();
        let rc = &mut self.rest;
        for v in [&mut rc.x, &mut rc.y, &mut rc.z] {
            v.clear();
            v.resize(placed + LANES, f32::NAN);
        }
        rc.cloth.clear();
        rc.cloth.resize(placed + LANES, 0);
        rc.ids.clear();
        rc.ids.resize(placed + LANES, 0);
        for (k, &i) in self.cell_entries.iter().enumerate() {
            let i = i as usize;
            (rc.x[k], rc.y[k], rc.z[k]) = (rest[0][i], rest[1][i], rest[2][i]);
            rc.cloth[k] = cloth[i];
            rc.ids[k] = i as u32;
        }
        rc.travel.clear();
        rc.d = None;
        rc.valid = true;
        Ok(())
    }

    /// Copies each particle's travel `t` over the collision distance `d` into cell order
    /// (after [`SpatialHash::attach_rest`], which forgets them): the self-collision query then
    /// keeps the pair `(i, j)` only within its own reach `d + (t_i + t_j) d`. The particles of
    /// travel at most `cell` are searched over the half shell of their cell (the query's
    /// `max_dist` must be at least their largest reach, `d + 2 cell d`, and the cells at least
    /// that wide); each faster one searches its own box, of radius `d + (t_i + t_max) d`. A
    /// `cell` at or above the largest travel makes every particle a member of its cell as
    /// without travels. Errors if `t` is shorter than the build's particle count, or `d`,
    /// `cell` or a travel is negative or not finite.
    pub fn attach_travel(&mut self, d: f32, t: &[f32], cell: f32) -> Result<()> {
        crate::error::non_negative("d", d)?;
        crate::error::non_negative("cell", cell)?;
        if t.len() < self.n {
            return Err(WeftError::BufferLength {
                name: "travel",
                got: t.len(),
                expected: self.n,
            });
        }
        if let Some(&bad) = t[..self.n].iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(WeftError::param("travel", bad, "must be finite and not negative"));
        }
        let placed = self.cell_entries.len();
        let rc = &mut self.rest;
        rc.travel.clear();
        rc.travel.resize(placed + LANES, 0.0);
        let mut top = 0.0f32;
        for (k, &i) in self.cell_entries.iter().enumerate() {
            rc.travel[k] = t[i as usize];
            top = top.max(t[i as usize]);
        }
        rc.d = Some(d);
        rc.cell = cell;
        rc.top = top;
        Ok(())
    }

    /// Checks the arguments; returns `max_dist²` and `skip²`.
    pub(super) fn check_rest_query(&self, max_dist: f32, skip: f32) -> Result<(f32, f32)> {
        crate::error::non_negative("skip", skip)?;
        let md2 = self.check_reach(max_dist)?;
        if !self.rest.valid {
            return Err(WeftError::param(
                "rest",
                "missing",
                "attach the rest data after each build (attach_rest)",
            ));
        }
        Ok((md2, skip * skip))
    }
}

#[cfg(test)]
pub(super) mod tests {
    use crate::test_rng::signed;

    /// Positions, rest positions and cloth ids of a test scene.
    pub(crate) type Scene = ([Vec<f32>; 3], [Vec<f32>; 3], Vec<u32>);

    /// Two `side x side` lattices of rest spacing `h`, the second lifted by `lift h`,
    /// positions displaced by `noise h` (zero noise: particles exactly on cell faces).
    pub(crate) fn lattices(side: usize, h: f32, noise: f32, lift: f32, seed: u64) -> Scene {
        let mut rng = signed(seed);
        let (mut p, mut rest): ([Vec<f32>; 3], [Vec<f32>; 3]) = Default::default();
        let mut cloth = Vec::new();
        for c in 0..2u32 {
            for a in 0..side {
                for b in 0..side {
                    let r = [a as f32 * h, b as f32 * h, 0.0];
                    for k in 0..3 {
                        rest[k].push(r[k]);
                        let up = if k == 2 { lift * h * c as f32 } else { 0.0 };
                        p[k].push(r[k] + noise * h * rng() + up);
                    }
                    cloth.push(c);
                }
            }
        }
        (p, rest, cloth)
    }
}
