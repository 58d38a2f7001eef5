//! The step's broadphase behind one trait ([`Broadphase`]): the spatial hash (Müller's "Ten
//! Minute Physics") or the AABB tree (the VcCPBD paper's box hierarchy), built once a step on
//! the positions at its start. Both answer the same [`PairQuery`] with the same lists (tests
//! hold the hash, the tree and a brute force equal), so the step's list build
//! (`crate::self_collision::lists`) asks one of them without knowing which.

use crate::data::exec::Exec;
use crate::error::Result;
use crate::self_collision::neighbours::{pair_reach2, within, Neighbours};
use crate::self_collision::tree::{ParticleTree, TreeShape};
use crate::self_collision::{dist2, SpatialHash, CELL_FACTOR};

/// Leaf size of the AABB tree (the paper's depth 5 gives ~312 particles a leaf at 10 000
/// particles; 16 queries much faster and gives the same pairs).
const TREE_LEAF: u32 = 16;

/// The cloths' rest data: the rest-neighbour rule's input.
#[derive(Clone, Copy)]
pub(crate) struct RestData<'a> {
    /// Rest positions and the cloth (group) of every particle.
    pub pos: [&'a [f32]; 3],
    pub cloth_of: &'a [u32],
}

impl RestData<'_> {
    /// Whether `i` and `j` are rest neighbours: one cloth, rest distance at most `skip`. Such
    /// pairs are never contacts (the cloth's own constraints keep them apart), so the
    /// broadphase drops them when it writes the list.
    #[inline]
    pub(crate) fn skipped(&self, i: usize, j: usize, skip: f32) -> bool {
        self.cloth_of[i] == self.cloth_of[j] && dist2(&self.pos, i, j) <= skip * skip
    }
}

/// What the step asks its broadphase for: every pair `i < j` of the first `n` particles within
/// its reach at the positions `x` of the build, rest neighbours (within `skip`) dropped.
pub(crate) struct PairQuery<'a> {
    pub x: [&'a [f32]; 3],
    pub n: usize,
    /// The collision distance, m.
    pub d: f32,
    /// The search radius, m: the largest reach of a pair, or with travels at least the
    /// members' reach `d + 2 members d` (particles faster than the members reach further).
    pub reach: f32,
    /// Each particle's travel over `d`: a pair is kept within its own reach
    /// `d + (t_i + t_j) d`; `None`: every pair within `reach`.
    pub travel: Option<&'a [f32]>,
    /// With travels: the largest travel of the particles the hash's cells are sized for (the
    /// faster ones search boxes of their own, [`SpatialHash::attach_travel`]). The tree
    /// searches one radius for every particle and ignores it.
    pub members: f32,
    pub rest: RestData<'a>,
    pub skip: f32,
}

/// Which pairs a probe keeps: `keep(i, j)`.
pub(crate) type Keep<'a> = &'a (dyn Fn(usize, u32) -> bool + Sync);

/// A self-collision broadphase: built on the positions at the step's start, it lists the
/// step's pairs and the metric's partners.
pub(crate) trait Broadphase {
    /// Builds (or refits) the structure on the first `n` of `x` for queries up to `reach`, in
    /// parallel when `exec` is.
    fn build(&mut self, x: [&[f32]; 3], n: usize, reach: f32, rest: RestData<'_>, exec: Exec) -> Result<()>;

    /// The pairs of `q` (each once, in the list of its smaller id) into `out`.
    fn pairs(&mut self, q: &PairQuery<'_>, out: &mut Neighbours, exec: Exec) -> Result<()>;

    /// For every particle, its partners within `lim` with `keep(i, j)`, each pair in both
    /// lists (the metric's probe, `x` the positions of the build).
    fn partners(&self, x: [&[f32]; 3], n: usize, lim: f32, keep: Keep<'_>, out: &mut Neighbours, exec: Exec) -> Result<()>;
}

impl Broadphase for SpatialHash {
    /// Cells of `reach` (times [`CELL_FACTOR`], widened to [`SpatialHash::member_spacing`] so
    /// that particles on a cell's faces are members of it), with the rest data attached for
    /// the rest rule of the cell query.
    fn build(&mut self, x: [&[f32]; 3], n: usize, reach: f32, rest: RestData<'_>, exec: Exec) -> Result<()> {
        let spacing = SpatialHash::member_spacing(reach) * CELL_FACTOR;
        if exec.parallel() {
            SpatialHash::build(self, x[0], x[1], x[2], n, spacing)?;
        } else {
            self.build_serial(x[0], x[1], x[2], n, spacing)?;
        }
        self.attach_rest(rest.pos, rest.cloth_of)
    }

    fn pairs(&mut self, q: &PairQuery<'_>, out: &mut Neighbours, exec: Exec) -> Result<()> {
        if let Some(t) = q.travel {
            self.attach_travel(q.d, t, q.members)?;
        }
        self.query_upper_unskipped_cells_exec(q.reach, q.skip, out, exec)
    }

    fn partners(&self, x: [&[f32]; 3], n: usize, lim: f32, keep: Keep<'_>, out: &mut Neighbours, exec: Exec) -> Result<()> {
        if exec.parallel() {
            self.query_filtered(x[0], x[1], x[2], n, lim, &keep, out)
        } else {
            self.query_filtered_serial(x[0], x[1], x[2], n, lim, &keep, out)
        }
    }
}

/// The AABB tree, once built (refitted on later builds of as many particles).
#[derive(Clone, Debug, Default)]
pub(crate) struct Tree(Option<ParticleTree>);

impl Broadphase for Tree {
    fn build(&mut self, x: [&[f32]; 3], n: usize, _reach: f32, _rest: RestData<'_>, exec: Exec) -> Result<()> {
        let t = match self.0.take() {
            Some(mut t) if t.len() == n && exec.parallel() => t.refit(x[0], x[1], x[2], n).map(|_| t),
            Some(mut t) if t.len() == n => t.refit_serial(x[0], x[1], x[2], n).map(|_| t),
            _ => ParticleTree::build(x[0], x[1], x[2], n, TreeShape::LeafSize(TREE_LEAF)),
        }?;
        self.0 = Some(t);
        Ok(())
    }

    /// The particles' query of radius `reach`, or with travels the largest pair reach
    /// `d + 2 max(t) d` if that is more, each pair kept (in its filter) within its own reach and
    /// unless the rest rule drops it.
    fn pairs(&mut self, q: &PairQuery<'_>, out: &mut Neighbours, exec: Exec) -> Result<()> {
        let tree = self.built()?;
        let (x, d, rest, skip) = (q.x, q.d, q.rest, q.skip);
        let reach = q.travel.map_or(q.reach, |t| {
            let top = t.iter().take(q.n).copied().fold(0.0f32, f32::max);
            q.reach.max(d + (top + top) * d)
        });
        let keep = |i: usize, j: u32| {
            let j = j as usize;
            let within_own = |t: &[f32]| within(x[0][i], x[1][i], x[2][i], x[0][j], x[1][j], x[2][j], pair_reach2(d, t[i], t[j]));
            !rest.skipped(i, j, skip) && q.travel.is_none_or(within_own)
        };
        tree.query_exec(x[0], x[1], x[2], q.n, reach, out, exec, true, &keep)
    }

    fn partners(&self, x: [&[f32]; 3], n: usize, lim: f32, keep: Keep<'_>, out: &mut Neighbours, exec: Exec) -> Result<()> {
        self.built()?.query_exec(x[0], x[1], x[2], n, lim, out, exec, false, &keep)
    }
}

impl Tree {
    /// The tree of the last build (an error before the first: the step always builds first).
    fn built(&self) -> Result<&ParticleTree> {
        self.0
            .as_ref()
            .ok_or_else(|| crate::WeftError::param("broadphase", "aabb-tree", "queried before its first build"))
    }
}

#[cfg(test)]
#[path = "broadphase_tests.rs"]
mod tests;
