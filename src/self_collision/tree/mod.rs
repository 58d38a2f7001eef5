//! A box hierarchy over the particles: the self-collision broadphase of the VcCPBD
//! paper (Shapri, Sulaiman & Bade 2016, "collisions are found through a box hierarchy (depth 5)"), the alternative to the
//! spatial hash of Müller's "Ten Minute Physics".
//!
//! # Method
//! **Build** (once): the particle ids are split recursively at the median of the longest axis
//! of their bounding box (ties broken by id, so the split is deterministic) down to a fixed
//! depth `D`. The tree is complete and stored implicitly in heap order: node `k` has children
//! `2k+1` and `2k+2`, the `2^D` leaves are nodes `2^D - 1 .. 2^(D+1) - 1`, and leaf `l` holds the
//! particles `order[leaf_start[l] .. leaf_start[l+1]]` (sizes differ by at most one).
//!
//! **Refit** (each step): the topology is kept and every box recomputed bottom-up: leaf boxes
//! from their particles, then level by level each box the union of its two children. Cheaper
//! than a rebuild, but boxes grow loose as the cloth deforms far from the build state; build
//! again then. NaN coordinates are ignored by the box (it stays tight around the finite
//! ones); infinite ones make it infinite, which is correct, only slow.
//!
//! **Query**: for each particle, a depth-first walk from the root visits the nodes whose box
//! meets the particle's search box `[x_i - r, x_i + r]³` (`r` = `max_dist` plus the rounding
//! margin of [`crate::self_collision::neighbours`]) and tests the particles of the leaves reached with the
//! shared neighbour predicate, eight at a time (`f32x8`; the serial twin is scalar). Lists
//! are sorted, so the result equals the hash and the brute force exactly.
//!
//! # Shape
//! [`TreeShape::Depth`] fixes `D` (the paper uses 5: 32 leaves, so ~312 particles a leaf for a
//! 100x100 cloth); [`TreeShape::LeafSize`] picks the smallest `D` whose leaves hold at most that
//! many particles (8 to 16 is fast). `D` is at most [`MAX_DEPTH`].

use crate::data::lanes::LANES;
use crate::self_collision::neighbours::{check_positions, CHUNK};
use crate::{Result, WeftError};
use rayon::prelude::*;

mod query;

/// Deepest tree allowed (2^20 leaves).
pub const MAX_DEPTH: u32 = 20;

/// How deep to build the tree.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TreeShape {
    /// Exactly this many levels below the root (the paper: 5).
    Depth(u32),
    /// The smallest depth whose leaves hold at most this many particles (capped at
    /// [`MAX_DEPTH`]).
    LeafSize(u32),
}

/// An axis-aligned box; empty when `min > max` (the initial `+inf / -inf` box).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: [f32; 3],
    /// Upper corner.
    pub max: [f32; 3],
}

impl Aabb {
    /// The empty box.
    pub const EMPTY: Aabb = Aabb {
        min: [f32::INFINITY; 3],
        max: [f32::NEG_INFINITY; 3],
    };

    /// Grows the box to hold a point; NaN components leave it unchanged.
    #[inline(always)]
    fn grow(&mut self, p: [f32; 3]) {
        for (a, v) in p.into_iter().enumerate() {
            self.min[a] = self.min[a].min(v);
            self.max[a] = self.max[a].max(v);
        }
    }

    /// The smallest box holding both.
    #[inline(always)]
    fn union(&self, o: &Aabb) -> Aabb {
        let mut u = *self;
        for a in 0..3 {
            u.min[a] = u.min[a].min(o.min[a]);
            u.max[a] = u.max[a].max(o.max[a]);
        }
        u
    }
}

/// A complete binary box tree over particles `0..n` (see the module docs).
#[derive(Debug, Clone)]
pub struct ParticleTree {
    depth: u32,
    n: usize,
    /// Particle ids in leaf order.
    order: Vec<u32>,
    /// Length `2^depth + 1`: leaf `l` holds `order[leaf_start[l]..leaf_start[l+1]]`.
    leaf_start: Vec<u32>,
    /// Node boxes in heap order, length `2^(depth+1) - 1`.
    boxes: Vec<Aabb>,
    /// Positions in `order` (leaf) order as of the last refit: leaf scans read them
    /// contiguously.
    lx: Vec<f32>,
    ly: Vec<f32>,
    lz: Vec<f32>,
    /// Index of each particle in `order`.
    slot_of: Vec<u32>,
}

impl ParticleTree {
    /// Builds the topology over particles `0..n` and fits the boxes (serially; done once).
    ///
    /// Errors on short arrays, `Depth(d)` with `d > MAX_DEPTH`, or `LeafSize(0)`.
    pub fn build(x: &[f32], y: &[f32], z: &[f32], n: usize, shape: TreeShape) -> Result<Self> {
        check_positions(x, y, z, n)?;
        let depth = match shape {
            TreeShape::Depth(d) if d <= MAX_DEPTH => d,
            TreeShape::Depth(d) => return Err(WeftError::param("depth", d, format!("must be at most {MAX_DEPTH}"))),
            TreeShape::LeafSize(0) => return Err(WeftError::param("leaf_size", 0, "must be at least 1")),
            TreeShape::LeafSize(k) => (0..=MAX_DEPTH)
                .find(|&d| n.div_ceil(1usize << d) <= k as usize)
                .unwrap_or(MAX_DEPTH),
        };
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut leaf_start = Vec::with_capacity((1usize << depth) + 1);
        leaf_start.push(0);
        split(&mut order, 0, x, y, z, depth, &mut leaf_start);
        let mut slot_of = vec![0u32; n];
        for (k, &j) in order.iter().enumerate() {
            slot_of[j as usize] = k as u32;
        }
        let mut tree = Self {
            depth,
            n,
            order,
            leaf_start,
            boxes: vec![Aabb::EMPTY; (2usize << depth) - 1],
            // NaN padding of LANES: lane loads stay in bounds and padded lanes never match.
            lx: vec![f32::NAN; n + LANES],
            ly: vec![f32::NAN; n + LANES],
            lz: vec![f32::NAN; n + LANES],
            slot_of,
        };
        tree.refit_serial(x, y, z, n)?;
        Ok(tree)
    }

    /// Levels below the root.
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Number of leaves, `2^depth`.
    pub fn leaf_count(&self) -> usize {
        1 << self.depth
    }

    /// Number of particles the tree was built over.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the tree holds no particles.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The particle ids of leaf `l`, or `None` if out of range.
    pub fn leaf(&self, l: usize) -> Option<&[u32]> {
        let s = *self.leaf_start.get(l)? as usize;
        let e = *self.leaf_start.get(l + 1)? as usize;
        Some(&self.order[s..e])
    }

    /// The box of node `k` (heap order), or `None` if out of range.
    pub fn node_box(&self, k: usize) -> Option<Aabb> {
        self.boxes.get(k).copied()
    }

    fn first_leaf(&self) -> usize {
        (1usize << self.depth) - 1
    }

    fn check_n(&self, x: &[f32], y: &[f32], z: &[f32], n: usize) -> Result<()> {
        check_positions(x, y, z, n)?;
        if n != self.n {
            return Err(WeftError::param(
                "n",
                n,
                format!("must equal the particle count of the build ({})", self.n),
            ));
        }
        Ok(())
    }

    /// Box of leaf `l` from the leaf-ordered positions.
    fn leaf_box(&self, l: usize) -> Aabb {
        let mut b = Aabb::EMPTY;
        let (s, e) = (self.leaf_start[l] as usize, self.leaf_start[l + 1] as usize);
        for k in s..e {
            b.grow([self.lx[k], self.ly[k], self.lz[k]]);
        }
        b
    }

    /// Whether particle `i` is where it was at the last refit (bitwise).
    #[inline]
    fn unchanged(&self, x: &[f32], y: &[f32], z: &[f32], i: usize) -> bool {
        let k = self.slot_of[i] as usize;
        x[i].to_bits() == self.lx[k].to_bits() && y[i].to_bits() == self.ly[k].to_bits() && z[i].to_bits() == self.lz[k].to_bits()
    }

    /// Errors unless the positions are those of the last refit.
    fn check_unchanged(same: bool) -> Result<()> {
        if same {
            Ok(())
        } else {
            Err(WeftError::param(
                "x, y, z",
                "moved",
                "must be the positions given to the last refit; refit the tree first",
            ))
        }
    }

    /// Recomputes every box for new positions of the same particles, bottom-up, in parallel:
    /// copies the positions into leaf order, fits the leaves, then each level up. Errors if `n`
    /// differs from the build or an array is short.
    pub fn refit(&mut self, x: &[f32], y: &[f32], z: &[f32], n: usize) -> Result<()> {
        self.check_n(x, y, z, n)?;
        let fl = self.first_leaf();
        self.lx[..n]
            .par_chunks_mut(CHUNK)
            .zip(self.ly[..n].par_chunks_mut(CHUNK))
            .zip(self.lz[..n].par_chunks_mut(CHUNK))
            .zip(self.order.par_chunks(CHUNK))
            .for_each(|(((cx, cy), cz), ids)| {
                for (k, &j) in ids.iter().enumerate() {
                    let j = j as usize;
                    (cx[k], cy[k], cz[k]) = (x[j], y[j], z[j]);
                }
            });
        let mut boxes = std::mem::take(&mut self.boxes);
        let this = &*self;
        boxes[fl..]
            .par_iter_mut()
            .with_min_len(64)
            .enumerate()
            .for_each(|(l, b)| *b = this.leaf_box(l));
        for level in (0..self.depth).rev() {
            let (lo, hi) = ((1usize << level) - 1, (2usize << level) - 1);
            let (upper, lower) = boxes.split_at_mut(hi);
            upper[lo..].par_iter_mut().with_min_len(64).enumerate().for_each(|(m, b)| {
                let c = 2 * (lo + m) + 1 - hi;
                *b = lower[c].union(&lower[c + 1]);
            });
        }
        self.boxes = boxes;
        Ok(())
    }

    /// Serial twin of [`ParticleTree::refit`]; produces identical boxes.
    pub fn refit_serial(&mut self, x: &[f32], y: &[f32], z: &[f32], n: usize) -> Result<()> {
        self.check_n(x, y, z, n)?;
        let fl = self.first_leaf();
        for (k, &j) in self.order.iter().enumerate() {
            let j = j as usize;
            (self.lx[k], self.ly[k], self.lz[k]) = (x[j], y[j], z[j]);
        }
        for l in 0..self.leaf_count() {
            self.boxes[fl + l] = self.leaf_box(l);
        }
        for k in (0..fl).rev() {
            self.boxes[k] = self.boxes[2 * k + 1].union(&self.boxes[2 * k + 2]);
        }
        Ok(())
    }

    /// Boxes as last refitted (heap order), for inspection and tests.
    pub fn boxes(&self) -> &[Aabb] {
        &self.boxes
    }
}

/// Splits `ids` (a node's particles) at the median of the longest axis of their box, down to
/// `depth`, appending each leaf's end offset to `leaf_start` (leaves left to right).
fn split(ids: &mut [u32], level: u32, x: &[f32], y: &[f32], z: &[f32], depth: u32, leaf_start: &mut Vec<u32>) {
    if level == depth {
        let end = leaf_start.last().copied().unwrap_or(0) + ids.len() as u32;
        leaf_start.push(end);
        return;
    }
    let mut b = Aabb::EMPTY;
    for &j in ids.iter() {
        let j = j as usize;
        b.grow([x[j], y[j], z[j]]);
    }
    let ext = [b.max[0] - b.min[0], b.max[1] - b.min[1], b.max[2] - b.min[2]];
    let mut axis = 0;
    for a in 1..3 {
        if ext[a] > ext[axis] {
            axis = a;
        }
    }
    let c = [x, y, z][axis];
    let mid = ids.len() / 2;
    if mid > 0 {
        ids.select_nth_unstable_by(mid, |&a, &b| c[a as usize].total_cmp(&c[b as usize]).then(a.cmp(&b)));
    }
    let (left, right) = ids.split_at_mut(mid);
    split(left, level + 1, x, y, z, depth, leaf_start);
    split(right, level + 1, x, y, z, depth, leaf_start);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::exec::Exec;
    use crate::self_collision::neighbours::Neighbours;

    /// The query with each `Exec` (parallel, serial with and without lanes) gives the brute
    /// force's lists, and the upper query their upper halves.
    #[test]
    fn every_exec_gives_the_brute_force_lists() {
        let mut r = crate::test_rng::unit(5);
        let n = 700;
        let p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 0.3 * r()).collect());
        let d = 0.02;
        let mut want = Neighbours::new();
        want.fill_brute_force(&p[0], &p[1], &p[2], n, d).unwrap();
        let tree = ParticleTree::build(&p[0], &p[1], &p[2], n, TreeShape::LeafSize(8)).unwrap();
        let mut got = Neighbours::new();
        let mut upper = want.clone();
        upper.retain(|i, j| j as usize > i);
        for exec in [Exec::Scalar, Exec::Simd, Exec::Parallel, Exec::ScalarParallel] {
            tree.query_exec(&p[0], &p[1], &p[2], n, d, &mut got, exec, false, &|_, _| true)
                .unwrap();
            assert_eq!(got, want, "{exec:?}");
            tree.query_exec(&p[0], &p[1], &p[2], n, d, &mut got, exec, true, &|_, _| true)
                .unwrap();
            assert_eq!(got, upper, "upper, {exec:?}");
        }
        assert!(
            want.total() > 100 && upper.total() * 2 == want.total(),
            "{} {}",
            want.total(),
            upper.total()
        );
    }
}
