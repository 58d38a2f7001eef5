//! Checks of a self-collision result that do not use the pipeline they check: the deepest
//! violation of the collision distance between non-neighbours, the share of particles closer
//! than a limit to a non-neighbour, and a count of layer crossings between two states.
//!
//! All three share one plain uniform grid (positions sorted by cell, looked up by binary
//! search) and one reading of "non-neighbour", the pipeline's rest-distance rule
//! ([`RestRule`]): two particles are neighbours when they belong to the same cloth and their
//! rest distance is at most `REST_SKIP_FACTOR d`; such pairs are left to the cloth's own
//! constraints and never collide.
//!
//! # Crossings
//! A *crossing* between two states `before` and `after` (typically two consecutive steps) is
//! a particle `p` and a triangle `t`, every vertex of `t` a non-neighbour of `p`, such that in
//! both states `p` lies within `reach` of the plane of `t` and projects inside `t`, and the
//! signed distance of `p` to that plane changes sign. A particle that passes through a layer
//! of cloth within one step does exactly this; a particle resting on a layer, sliding over it
//! or wrapping around its free edge (it leaves the triangle's prism) does not. A particle
//! landing exactly on a plane (signed distance zero) is not counted until it is on the other
//! side.
//!
//! ```
//! use weft::self_collision::audit::{count_crossings, RestRule};
//! // One triangle (cloth 0) and one particle (cloth 1) that goes through it.
//! let rest = [vec![0.0, 1.0, 0.0, 0.2], vec![0.0, 0.0, 1.0, 0.2], vec![0.0, 0.0, 0.0, 5.0]];
//! let group = [0, 0, 0, 1];
//! let rule = RestRule::new([&rest[0], &rest[1], &rest[2]], &group, 0.03).unwrap();
//! let (x, y) = (vec![0.0, 1.0, 0.0, 0.2], vec![0.0, 0.0, 1.0, 0.2]);
//! let before = [&x[..], &y[..], &[0.0, 0.0, 0.0, 0.01][..]];
//! let after = [&x[..], &y[..], &[0.0, 0.0, 0.0, -0.01][..]];
//! assert_eq!(count_crossings(before, after, &[[0, 1, 2]], &rule, 0.05).unwrap(), 1);
//! assert_eq!(count_crossings(before, before, &[[0, 1, 2]], &rule, 0.05).unwrap(), 0);
//! ```

use crate::error::{Result, WeftError};

/// The rest-distance rule: which pairs are neighbours (never collide).
#[derive(Clone, Copy, Debug)]
pub struct RestRule<'a> {
    rest: [&'a [f32]; 3],
    group: &'a [u32],
    skip2: f32,
}

impl<'a> RestRule<'a> {
    /// Particles `i` and `j` are neighbours when `group[i] == group[j]` and their rest
    /// positions are at most `skip` apart (the pipeline uses `REST_SKIP_FACTOR d`). Errors
    /// when the slices differ in length, a rest position is not finite or `skip` is negative
    /// or not finite.
    pub fn new(rest: [&'a [f32]; 3], group: &'a [u32], skip: f32) -> Result<Self> {
        let n = group.len();
        for r in rest {
            if r.len() != n {
                return Err(WeftError::BufferLength {
                    name: "rest positions",
                    got: r.len(),
                    expected: n,
                });
            }
            if r.iter().any(|v| !v.is_finite()) {
                return Err(WeftError::param("rest positions", "non-finite", "must be finite"));
            }
        }
        if !(skip.is_finite() && skip >= 0.0) {
            return Err(WeftError::param("skip", skip, "must be finite and at least 0"));
        }
        Ok(RestRule {
            rest,
            group,
            skip2: skip * skip,
        })
    }

    /// Number of particles the rule covers.
    pub fn len(&self) -> usize {
        self.group.len()
    }

    /// Whether the rule covers no particle.
    pub fn is_empty(&self) -> bool {
        self.group.is_empty()
    }

    /// Whether `i` and `j` are non-neighbours (pairs that must keep the collision distance).
    pub fn far(&self, i: usize, j: usize) -> bool {
        self.group[i] != self.group[j] || dist2(self.rest, i, j) > self.skip2
    }
}

fn dist2(x: [&[f32]; 3], i: usize, j: usize) -> f32 {
    let (dx, dy, dz) = (x[0][i] - x[0][j], x[1][i] - x[1][j], x[2][i] - x[2][j]);
    dx * dx + dy * dy + dz * dz
}

fn point(x: [&[f32]; 3], i: usize) -> [f32; 3] {
    [x[0][i], x[1][i], x[2][i]]
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Positions sorted by the cell of side `cell` they fall in.
struct Grid {
    cell: f32,
    keys: Vec<[i64; 3]>,
    order: Vec<u32>,
}

/// Cell coordinates stay far from `i64` overflow for any finite `f32` over a positive cell.
fn key_of(v: f32, cell: f32) -> i64 {
    ((v / cell).floor() as f64).clamp(-1e15, 1e15) as i64
}

impl Grid {
    fn new(x: [&[f32]; 3], n: usize, cell: f32) -> Result<Grid> {
        if !(cell.is_finite() && cell > 0.0) {
            return Err(WeftError::param("reach", cell, "must be positive and finite"));
        }
        for a in x {
            if a.len() < n {
                return Err(WeftError::BufferLength {
                    name: "positions",
                    got: a.len(),
                    expected: n,
                });
            }
            if a[..n].iter().any(|v| !v.is_finite()) {
                return Err(WeftError::param("positions", "non-finite", "must be finite"));
            }
        }
        let u32_max = u32::MAX as usize;
        if n > u32_max {
            return Err(WeftError::param("particles", n, "at most u32::MAX"));
        }
        let mut pairs: Vec<([i64; 3], u32)> = (0..n)
            .map(|i| ([key_of(x[0][i], cell), key_of(x[1][i], cell), key_of(x[2][i], cell)], i as u32))
            .collect();
        pairs.sort_unstable();
        let (keys, order) = pairs.into_iter().unzip();
        Ok(Grid { cell, keys, order })
    }

    /// Calls `f` with every particle in the cells `lo ..= hi` (inclusive key boxes); when the
    /// box holds more cells than particles, with every particle.
    fn for_each_in(&self, lo: [i64; 3], hi: [i64; 3], mut f: impl FnMut(usize)) {
        let span = |k: usize| (hi[k] - lo[k] + 1).max(0) as u128;
        if span(0) * span(1) * span(2) > self.order.len() as u128 {
            self.order.iter().for_each(|&j| f(j as usize));
            return;
        }
        for kx in lo[0]..=hi[0] {
            for ky in lo[1]..=hi[1] {
                let a = self.keys.partition_point(|k| *k < [kx, ky, lo[2]]);
                let b = a + self.keys[a..].partition_point(|k| *k <= [kx, ky, hi[2]]);
                self.order[a..b].iter().for_each(|&j| f(j as usize));
            }
        }
    }

    /// The key box of the points within `r` of the box `lo ..= hi`.
    fn key_box(&self, lo: [f32; 3], hi: [f32; 3], r: f32) -> ([i64; 3], [i64; 3]) {
        (
            [0, 1, 2].map(|k| key_of(lo[k] - r, self.cell)),
            [0, 1, 2].map(|k| key_of(hi[k] + r, self.cell)),
        )
    }
}

/// Calls `f(i, j, distance)` once for every pair `i < j` of non-neighbours (by `rule`) closer
/// than `reach` in `x` (slices of at least `rule.len()` entries). Errors on non-finite
/// positions or a reach that is not positive and finite.
pub fn close_pairs(x: [&[f32]; 3], rule: &RestRule<'_>, reach: f32, mut f: impl FnMut(usize, usize, f32)) -> Result<()> {
    let n = rule.len();
    let grid = Grid::new(x, n, reach)?;
    for i in 0..n {
        let p = point(x, i);
        let (lo, hi) = grid.key_box(p, p, reach);
        grid.for_each_in(lo, hi, |j| {
            if j > i {
                let d2 = dist2(x, i, j);
                if d2 < reach * reach && rule.far(i, j) {
                    f(i, j, d2.sqrt());
                }
            }
        });
    }
    Ok(())
}

/// The deepest violation of the collision distance `d` between non-neighbours in `x`:
/// `max(d - |x_i - x_j|)` over non-neighbour pairs closer than `d`, 0 when there is none.
pub fn deepest_violation(x: [&[f32]; 3], rule: &RestRule<'_>, d: f32) -> Result<f32> {
    let mut deepest = 0.0f32;
    close_pairs(x, rule, d, |_, _, dist| deepest = deepest.max(d - dist))?;
    Ok(deepest)
}

/// Percentage of the particles that have a non-neighbour closer than `limit` in `x` (the
/// average-collision measure of one state, with the non-neighbours of `rule`).
pub fn share_closer(x: [&[f32]; 3], rule: &RestRule<'_>, limit: f32) -> Result<f64> {
    let n = rule.len();
    let mut hit = vec![false; n];
    close_pairs(x, rule, limit, |i, j, _| {
        hit[i] = true;
        hit[j] = true;
    })?;
    Ok(if n == 0 {
        0.0
    } else {
        100.0 * hit.iter().filter(|&&h| h).count() as f64 / n as f64
    })
}

/// Signed distance of `p` to the plane of `(a, b, c)` (normal `(b - a) x (c - a)`) if `p`
/// projects inside the triangle; `None` outside or for a degenerate triangle.
fn side_inside(a: [f32; 3], b: [f32; 3], c: [f32; 3], p: [f32; 3]) -> Option<f32> {
    let (e0, e1, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let nrm = cross(e0, e1);
    let len = dot(nrm, nrm).sqrt();
    let (d00, d01, d11) = (dot(e0, e0), dot(e0, e1), dot(e1, e1));
    let denom = d00 * d11 - d01 * d01;
    if len <= 0.0 || denom <= 0.0 || !denom.is_finite() {
        return None;
    }
    let (d20, d21) = (dot(ap, e0), dot(ap, e1));
    let v = (d11 * d20 - d01 * d21) / denom;
    let w = (d00 * d21 - d01 * d20) / denom;
    (v >= 0.0 && w >= 0.0 && v + w <= 1.0).then(|| dot(nrm, ap) / len)
}

/// Counts the layer crossings between the states `before` and `after` (see the module docs):
/// particle–triangle pairs of non-neighbours where the particle stays within `reach` of the
/// triangle's plane and inside its prism and changes side. `triangles` index the particles
/// of `rule`. Errors on non-finite positions, a bad reach or a triangle index out of range.
pub fn count_crossings(before: [&[f32]; 3], after: [&[f32]; 3], triangles: &[[u32; 3]], rule: &RestRule<'_>, reach: f32) -> Result<usize> {
    let n = rule.len();
    let grid = Grid::new(after, n, reach)?;
    for a in before {
        if a.len() < n || a[..n].iter().any(|v| !v.is_finite()) {
            return Err(WeftError::param(
                "positions before",
                "non-finite or short",
                "must be finite, one per particle",
            ));
        }
    }
    let mut count = 0usize;
    for t in triangles {
        let [a, b, c] = t.map(|i| i as usize);
        if a.max(b).max(c) >= n {
            return Err(WeftError::IndexOutOfRange {
                name: "triangle vertex",
                index: a.max(b).max(c),
                len: n,
            });
        }
        let (a1, b1, c1) = (point(after, a), point(after, b), point(after, c));
        let lo = [0, 1, 2].map(|k| a1[k].min(b1[k]).min(c1[k]));
        let hi = [0, 1, 2].map(|k| a1[k].max(b1[k]).max(c1[k]));
        let (klo, khi) = grid.key_box(lo, hi, reach);
        let (a0, b0, c0) = (point(before, a), point(before, b), point(before, c));
        grid.for_each_in(klo, khi, |p| {
            if p == a || p == b || p == c || !(rule.far(p, a) && rule.far(p, b) && rule.far(p, c)) {
                return;
            }
            let Some(s1) = side_inside(a1, b1, c1, point(after, p)).filter(|s| s.abs() < reach) else {
                return;
            };
            let Some(s0) = side_inside(a0, b0, c0, point(before, p)).filter(|s| s.abs() < reach) else {
                return;
            };
            if (s0 > 0.0 && s1 < 0.0) || (s0 < 0.0 && s1 > 0.0) {
                count += 1;
            }
        });
    }
    Ok(count)
}

#[cfg(test)]
#[path = "audit_tests.rs"]
mod tests;
