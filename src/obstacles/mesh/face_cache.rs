//! Per-particle candidate faces kept from step to step (a Verlet list for mesh obstacles).
//!
//! A step `x -> p` of reach `r` can touch only the faces whose box overlaps its query box
//! `Q = box(x, p) + r` ([`query_box`]), and the narrowphase tests exactly those faces
//! (`best_contact`). Asking the broadphase for them every step costs far more than the test
//! itself when the particle rests on the obstacle. So each particle keeps a **gathered box**
//! `G = Q + m` (its query box grown by a margin `m`) and the list of faces whose box overlaps
//! `G`. While a later query box lies inside `G` (`G.lo <= Q.lo` and `Q.hi <= G.hi` on every
//! axis, exact `f32` comparisons), every face overlapping `Q` overlaps `G` (intervals are
//! closed and `f32` comparisons are exact), so it is in the list; the list is filtered by
//! `Q` and handed to the same narrowphase with the same total order of contacts. The contacts
//! are therefore bit for bit those of the uncached search, whatever the broadphase and
//! whatever the order of the list. When `Q` leaves `G` the particle gathers again.
//! Each list is also sorted around a clearance ball ([`face_ball`](crate::obstacles::mesh::face_ball)): while
//! the step stays in the ball only the faces at the front of the list are tested.
//!
//! The margin bounds the motion of the coming steps: [`margin`] is `MARGIN_REACH` reaches plus
//! [`MARGIN_STEPS`] times the step's largest coordinate change, so a particle moving steadily
//! gathers at most every few steps and a resting one keeps its list. A smaller margin means
//! more gathers for a little less narrowphase; the lists stay about as long whatever the
//! margin (set by the size of the faces' boxes). A mesh that moves (a new
//! [`TriMesh::stamp`]) empties every list ([`FaceCache::sync`]). A particle owns its entry,
//! so the cache changes nothing about thread-count independence.
//!
//! **Layout (hot and cold).** The lists are kept per block of eight particles
//! ([`CacheBlock`]): the gathered boxes and list lengths of the eight particles sit together
//! as eight-lane arrays (the hot part, 224 bytes, read for every particle near the mesh), and
//! the face ids in a separate heap block (the cold part, read only when a list is not empty).
//! One entry per particle (box, length and ids together) made the load of the entry's box the
//! costliest instruction of the contact pass: the entries streamed through the caches every
//! substep, most of them for particles whose list was empty. With the split the common "kept
//! box, no face" case reads 28 bytes per particle, and the contact pass tests it for eight
//! particles at once ([`CacheBlock::held_empty`], `mesh_pass::skip_lanes_simd`).
//!
//! The list is tested face by face with the exact narrowphase: a SIMD pre-test of the list
//! (boxes and conservative planes eight faces at a time) saved narrowphase calls but no wall
//! time, and this pass is not where a mesh scene's cache misses are (the distance sweeps are).

use crate::data::lanes::LANES;
use crate::obstacles::mesh::broadphase::FaceBroadphase;
use crate::obstacles::mesh::contact::best_contact;
use crate::obstacles::mesh::face_ball::Ball;
use crate::obstacles::mesh::narrow::{query_box, Contact};
use crate::obstacles::mesh::TriMesh;

/// The gathered box reaches this many contact reaches beyond the query box.
pub const MARGIN_REACH: f32 = 1.0;
/// ... plus this many times the step's largest coordinate change.
pub const MARGIN_STEPS: f32 = 4.0;

/// The step `x -> p`'s largest coordinate change (the margins here and of the clearance
/// ball grow with it).
#[inline]
pub(crate) fn largest_change(x: [f32; 3], p: [f32; 3]) -> f32 {
    (0..3).fold(0.0f32, |m, k| m.max((p[k] - x[k]).abs()))
}

/// The margin of a gathered box for the step `x -> p` of reach `reach` (module doc).
#[inline]
pub fn margin(x: [f32; 3], p: [f32; 3], reach: f32) -> f32 {
    MARGIN_REACH * reach + MARGIN_STEPS * largest_change(x, p)
}

/// Faces a list keeps inline (in the cold block itself); longer lists live in their own heap
/// vector.
pub const INLINE_FACES: usize = 12;

/// One particle's face ids (the cold part of its entry).
#[derive(Debug, Clone, Default)]
pub struct FaceList {
    inline: [u32; INLINE_FACES],
    spill: Vec<u32>,
    /// The list's clearance ball ([`face_ball`](crate::obstacles::mesh::face_ball)): its near faces are at
    /// the front.
    ball: Ball,
}

/// The kept lists of one block of eight particles (module doc): gathered boxes and list
/// lengths lane by lane, the face ids in a separate heap block.
#[derive(Debug, Clone)]
pub struct CacheBlock {
    lo: [[f32; LANES]; 3],
    hi: [[f32; LANES]; 3],
    len: [u32; LANES],
    /// Centres and clearances of the lanes' balls that have no near face (clearance `-inf`
    /// otherwise): the hot copy of [`Ball::empty_part`] for the eight-lane skip test.
    empty_o: [[f32; LANES]; 3],
    empty_c: [f32; LANES],
    lists: Box<[FaceList; LANES]>,
}

impl Default for CacheBlock {
    /// Empty entries: their boxes contain nothing, so the first query of each lane gathers.
    fn default() -> Self {
        CacheBlock {
            lo: [[f32::INFINITY; LANES]; 3],
            hi: [[f32::NEG_INFINITY; LANES]; 3],
            len: [0; LANES],
            empty_o: [[0.0; LANES]; 3],
            empty_c: [f32::NEG_INFINITY; LANES],
            lists: Box::default(),
        }
    }
}

impl CacheBlock {
    /// Forgets lane `l`'s list (keeps its storage).
    pub fn clear(&mut self, l: usize) {
        for k in 0..3 {
            self.lo[k][l] = f32::INFINITY;
            self.hi[k][l] = f32::NEG_INFINITY;
        }
        self.len[l] = 0;
        self.lists[l].spill.clear();
        self.set_ball(l, Ball::default());
    }

    /// Sets lane `l`'s ball and its hot copy.
    fn set_ball(&mut self, l: usize, ball: Ball) {
        self.lists[l].ball = ball;
        let (o, c) = ball.empty_part();
        (0..3).for_each(|k| self.empty_o[k][l] = o[k]);
        self.empty_c[l] = c;
    }

    /// The lanes (bit `l`) whose ball has no near face and vouches for the step `x -> p` of
    /// reach `reach` ([`face_ball`](crate::obstacles::mesh::face_ball)): their step has no contact. Scalar.
    pub fn ball_empty(&self, x: [[f32; LANES]; 3], p: [[f32; LANES]; 3], reach: [f32; LANES]) -> u32 {
        (0..LANES).fold(0, |m, l| {
            let q = |a: [[f32; LANES]; 3]| [a[0][l], a[1][l], a[2][l]];
            let o = q(self.empty_o);
            m | (crate::obstacles::mesh::face_ball::vouches(o, self.empty_c[l], q(x), q(p), reach[l]) as u32) << l
        })
    }

    /// [`ball_empty`](Self::ball_empty) eight lanes at once (the same bits).
    pub fn ball_empty_simd(&self, x: crate::data::lanes::Vec3x8, p: crate::data::lanes::Vec3x8, reach: crate::data::lanes::F32s) -> u32 {
        use crate::data::lanes::{F32s, Vec3x8};
        let g = |a: [f32; LANES]| F32s::from(a);
        let o = Vec3x8 {
            x: g(self.empty_o[0]),
            y: g(self.empty_o[1]),
            z: g(self.empty_o[2]),
        };
        crate::obstacles::mesh::face_ball::vouches_simd(o, g(self.empty_c), x, p, reach)
    }

    /// Forgets every lane's list.
    pub fn clear_all(&mut self) {
        (0..LANES).for_each(|l| self.clear(l));
    }

    /// Does lane `l`'s gathered box contain `[lo, hi]`?
    #[inline]
    fn holds(&self, l: usize, lo: [f32; 3], hi: [f32; 3]) -> bool {
        // `&` rather than `&&`: one branch for the six comparisons
        (self.lo[0][l] <= lo[0])
            & (self.lo[1][l] <= lo[1])
            & (self.lo[2][l] <= lo[2])
            & (hi[0] <= self.hi[0][l])
            & (hi[1] <= self.hi[1][l])
            & (hi[2] <= self.hi[2][l])
    }

    /// The lanes (bit `l`) whose gathered box contains the query box `[lo[k][l], hi[k][l]]`
    /// and whose list is empty: their step has no contact ([`step_contact`](Self::step_contact)
    /// returns `None` without reading anything else). Scalar.
    pub fn held_empty(&self, lo: [[f32; LANES]; 3], hi: [[f32; LANES]; 3]) -> u32 {
        (0..LANES).fold(0, |m, l| {
            let q = |a: [[f32; LANES]; 3]| [a[0][l], a[1][l], a[2][l]];
            m | (((self.len[l] == 0) & self.holds(l, q(lo), q(hi))) as u32) << l
        })
    }

    /// [`held_empty`](Self::held_empty) with the query boxes in SIMD lanes: the same six
    /// exact comparisons per lane, so the same bits.
    pub fn held_empty_simd(&self, lo: crate::data::lanes::Vec3x8, hi: crate::data::lanes::Vec3x8) -> u32 {
        use crate::data::lanes::F32s;
        let g = |a: [f32; LANES]| F32s::from(a);
        let held = g(self.lo[0]).simd_le(lo.x)
            & g(self.lo[1]).simd_le(lo.y)
            & g(self.lo[2]).simd_le(lo.z)
            & hi.x.simd_le(g(self.hi[0]))
            & hi.y.simd_le(g(self.hi[1]))
            & hi.z.simd_le(g(self.hi[2]));
        let empty = (0..LANES).fold(0u32, |m, l| m | ((self.len[l] == 0) as u32) << l);
        held.to_bitmask() & empty
    }

    /// The faces gathered for lane `l` (at least every face overlapping its gathered box).
    pub fn faces(&self, l: usize) -> &[u32] {
        let list = &self.lists[l];
        match self.len[l] as usize {
            n if n <= INLINE_FACES => &list.inline[..n],
            _ => &list.spill,
        }
    }

    /// Lane `l`'s list, to sort it.
    fn faces_mut(&mut self, l: usize) -> &mut [u32] {
        let list = &mut self.lists[l];
        match self.len[l] as usize {
            n if n <= INLINE_FACES => &mut list.inline[..n],
            _ => &mut list.spill,
        }
    }

    /// Sorts lane `l`'s list for the clearance ball around `p` (margin `m`).
    fn sort_ball(&mut self, l: usize, mesh: &TriMesh, p: [f32; 3], reach: f32, m: f32) {
        let gathered = ([0, 1, 2].map(|k| self.lo[k][l]), [0, 1, 2].map(|k| self.hi[k][l]));
        let ball = Ball::sort(mesh, self.faces_mut(l), p, reach, m, gathered);
        self.set_ball(l, ball);
    }

    /// Keeps `faces` as lane `l`'s list.
    fn store(&mut self, l: usize, faces: &[u32]) {
        self.len[l] = faces.len() as u32;
        self.set_ball(l, Ball::default());
        let list = &mut self.lists[l];
        list.spill.clear();
        if faces.len() <= INLINE_FACES {
            list.inline[..faces.len()].copy_from_slice(faces);
        } else {
            list.spill.extend_from_slice(faces);
        }
    }

    /// The contact of lane `l`'s step `x -> p` within `reach`: exactly
    /// [`step_contact`](crate::obstacles::mesh::contact::step_contact), using and refreshing the list
    /// (module doc). A new gathering grows the query box by [`margin`] when `keep`, by
    /// nothing otherwise (a fresh search every step, the reference).
    #[allow(clippy::too_many_arguments)]
    pub fn step_contact<B: FaceBroadphase + ?Sized>(
        &mut self,
        l: usize,
        mesh: &TriMesh,
        bp: &B,
        x: [f32; 3],
        p: [f32; 3],
        reach: f32,
        keep: bool,
        scratch: &mut Vec<u32>,
    ) -> Option<Contact> {
        self.contact_in(l, mesh, bp, x, p, reach, query_box(x, p, reach), keep, scratch)
    }

    /// [`step_contact`](Self::step_contact) given the step's query box `q`
    /// (`query_box(x, p, reach)`).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub(crate) fn contact_in<B: FaceBroadphase + ?Sized>(
        &mut self,
        l: usize,
        mesh: &TriMesh,
        bp: &B,
        x: [f32; 3],
        p: [f32; 3],
        reach: f32,
        (lo, hi): ([f32; 3], [f32; 3]),
        keep: bool,
        scratch: &mut Vec<u32>,
    ) -> Option<Contact> {
        if keep && self.holds(l, lo, hi) {
            if self.len[l] == 0 {
                return None;
            }
            let ball = self.lists[l].ball;
            if !ball.holds(x, p, reach) {
                self.sort_ball(l, mesh, p, reach, crate::obstacles::mesh::face_ball::ball_margin(x, p, reach));
                return best_contact(mesh, self.faces(l), x, p, reach, lo, hi);
            }
            return best_contact(mesh, &self.faces(l)[..ball.near()], x, p, reach, lo, hi);
        }
        self.gather(l, mesh, bp, x, p, reach, (lo, hi), keep, scratch)
    }

    /// [`contact_in`](Self::contact_in) when the list does not cover the query box (or is
    /// not kept): gathers afresh.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn gather<B: FaceBroadphase + ?Sized>(
        &mut self,
        l: usize,
        mesh: &TriMesh,
        bp: &B,
        x: [f32; 3],
        p: [f32; 3],
        reach: f32,
        (lo, hi): ([f32; 3], [f32; 3]),
        keep: bool,
        scratch: &mut Vec<u32>,
    ) -> Option<Contact> {
        let margin = if keep { margin(x, p, reach) } else { 0.0 };
        let (glo, ghi) = (lo.map(|v| v - margin), hi.map(|v| v + margin));
        bp.candidates(mesh, glo, ghi, scratch);
        // A NaN or a margin lost to rounding leaves a box that does not hold the query: then
        // this step uses the fresh candidates and keeps nothing (so does a fresh search).
        if !(keep && margin >= 0.0 && (0..3).all(|k| glo[k] <= lo[k] && hi[k] <= ghi[k])) {
            self.clear(l);
            return best_contact(mesh, scratch, x, p, reach, lo, hi);
        }
        scratch.retain(|&f| mesh.face_overlaps(f, glo, ghi));
        self.store(l, scratch);
        for k in 0..3 {
            (self.lo[k][l], self.hi[k][l]) = (glo[k], ghi[k]);
        }
        self.sort_ball(l, mesh, p, reach, crate::obstacles::mesh::face_ball::ball_margin(x, p, reach));
        best_contact(mesh, self.faces(l), x, p, reach, lo, hi)
    }
}

/// The candidate lists of every particle against one mesh obstacle, one [`CacheBlock`] per
/// block of eight particles.
#[derive(Debug, Clone, Default)]
pub struct FaceCache {
    stamp: u64,
    blocks: Vec<CacheBlock>,
}

impl FaceCache {
    /// Sizes the cache to `n` particles (rounded up to whole blocks) and empties every list
    /// if the mesh state (`stamp`) or the particle count changed.
    pub fn sync(&mut self, n: usize, stamp: u64) {
        let blocks = n.div_ceil(LANES);
        if self.blocks.len() != blocks {
            self.blocks = vec![CacheBlock::default(); blocks];
        } else if self.stamp != stamp {
            self.blocks.iter_mut().for_each(CacheBlock::clear_all);
        }
        self.stamp = stamp;
    }

    /// The blocks (block `b` holds particles `8 b .. 8 b + 8`).
    pub fn blocks_mut(&mut self) -> &mut [CacheBlock] {
        &mut self.blocks
    }
}
#[cfg(test)]
#[path = "face_cache_tests.rs"]
mod tests;
