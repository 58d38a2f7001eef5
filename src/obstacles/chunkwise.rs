//! The obstacle stages of one chunk of particles, for worlds whose obstacles are all analytic
//! shapes.
//!
//! A shape's contacts, the response along the path, the projection and the velocity pass of
//! a particle read only that particle and its own slot. So the step can run them inside its
//! element-wise passes while a chunk is in cache, instead of in passes of their own:
//! - the contacts of a substep and their response right after the chunk's predict;
//! - the last iteration's projection before the chunk's update;
//! - the velocity pass after the chunk's update.
//!
//! Each chunk takes the slot blocks of its own particles ([`SlotsPtr`]; chunks start and end
//! on whole blocks), so the bits are those of the separate passes whatever the thread count
//! (`world::step::fusion_tests`). A mesh's contact search keeps per-task face caches and a
//! broadphase of its own, so a world with a mesh keeps the separate passes.

use std::marker::PhantomData;

use crate::data::lanes::LANES;
use crate::data::particles::ParticleChunk;
use crate::model::shapes::Shape;
use crate::obstacles::kernels::{self as k, GenInput, SlotsPtr, SlotsView};
use crate::obstacles::obstacle::displacement;
use crate::obstacles::{shape_block, Geometry, ObstacleSet};

/// Most obstacles the chunk-by-chunk stages take (their settings live on the stack).
pub const MAX_OBSTACLES: usize = 8;

/// One shape obstacle as a chunk's stages need it.
#[derive(Clone, Copy)]
struct Placed {
    /// The shape at the end of the substep whose contacts are searched.
    shape: Shape,
    /// Its velocity and its displacement during the substep.
    u: [f32; 3],
    shift: [f32; 3],
    /// Its friction coefficient.
    mu: f32,
    slots: SlotsPtr,
}

/// The obstacle stages of a substep for one chunk at a time (module doc). Built by
/// [`ObstacleSet::chunkwise`]; it holds the obstacles' slots for as long as it lives.
pub struct ChunkObstacles<'a> {
    list: [Option<Placed>; MAX_OBSTACLES],
    count: usize,
    th: &'a [f32],
    reach: &'a [f32],
    /// Real particles.
    n: usize,
    _slots: PhantomData<&'a mut ()>,
}

impl ObstacleSet {
    /// The chunk-by-chunk stages of the substep of length `h` ending at time `t_end`. Only for a
    /// set that [`runs_chunkwise`](Self::runs_chunkwise) (the step checks it once and then
    /// runs no separate obstacle pass, so a set that did not would lose its stages: asserted).
    /// The arrays must be sized ([`prepare`](Self::prepare)).
    pub(crate) fn chunkwise(&mut self, t_end: f64, h: f32, n: usize) -> ChunkObstacles<'_> {
        let [c] = self.chunkwise_at([t_end], h, n);
        c
    }

    /// [`chunkwise`](Self::chunkwise) for the substeps ending at each of `t_ends`, on the same
    /// contact slots: for a pass that runs one substep's contacts and the next substep's
    /// stages on the same particles, one after the other, each chunk's blocks in one task
    /// (the views' own rule).
    pub(crate) fn chunkwise_at<const K: usize>(&mut self, t_ends: [f64; K], h: f32, n: usize) -> [ChunkObstacles<'_>; K] {
        assert!(
            self.runs_chunkwise(),
            "chunkwise obstacle stages need at most {MAX_OBSTACLES} shapes"
        );
        let mut lists = [[None; MAX_OBSTACLES]; K];
        for (k, (o, slots)) in self.list.iter().zip(&mut self.slots).enumerate() {
            let Geometry::Shape(s) = &o.geometry else {
                unreachable!("runs_chunkwise: every obstacle is a shape")
            };
            let (u, slots) = (o.velocity, SlotsPtr::new(slots));
            for (list, &t_end) in lists.iter_mut().zip(&t_ends) {
                list[k] = Some(Placed {
                    shape: s.translated(displacement(u, t_end)),
                    u,
                    shift: u.map(|c| c * h),
                    mu: o.friction.unwrap_or(self.friction),
                    slots,
                });
            }
        }
        lists.map(|list| ChunkObstacles {
            list,
            count: self.list.len(),
            th: &self.th,
            reach: &self.reach,
            n,
            _slots: PhantomData,
        })
    }
}

impl ChunkObstacles<'_> {
    fn placed(&self) -> impl Iterator<Item = &Placed> {
        self.list[..self.count].iter().flatten()
    }

    /// The chunk's blocks of every obstacle's slots, read-only, with the obstacles' shifts and
    /// motions, on the stack: `f(slots, shifts, motion)`.
    /// `start`, `len`: the chunk's particles.
    fn with_views<R>(&self, start: usize, len: usize, f: impl FnOnce(&[SlotsView<'_>], &[[f32; 3]], &[([f32; 3], f32)]) -> R) -> R {
        let (first, count) = (start / LANES, len / LANES);
        let mut views = [SlotsView::default(); MAX_OBSTACLES];
        let mut shifts = [[0.0; 3]; MAX_OBSTACLES];
        let mut motion = [([0.0; 3], 0.0); MAX_OBSTACLES];
        for (k, o) in self.placed().enumerate() {
            // SAFETY: the chunk's blocks belong to this chunk's task alone (chunks are
            // disjoint), the view does not outlive this call, and the set's slots are borrowed
            // by `self` for its whole life.
            let (data, touched) = unsafe { o.slots.blocks(first, count) };
            views[k] = SlotsView { data, touched };
            shifts[k] = o.shift;
            motion[k] = (o.u, o.mu);
        }
        f(&views[..self.count], &shifts[..self.count], &motion[..self.count])
    }

    /// Contacts of the chunk's paths `x -> p` with every shape, then the response along the
    /// path (the step's contact stage, [`ObstacleSet::generate`] and
    /// [`ObstacleSet::resolve`], on one chunk).
    pub fn contacts(&self, c: &mut ParticleChunk<'_>, simd: bool) {
        let (start, len) = (c.start, c.x.len());
        let th = &self.th[start..start + len];
        for o in self.placed() {
            let g = GenInput {
                x: [&*c.x, &*c.y, &*c.z],
                p: [&*c.px, &*c.py, &*c.pz],
                w: c.w,
                th,
                reach: &self.reach[start..start + len],
                n: self.n.saturating_sub(start),
                shift: o.shift,
            };
            let vel = [&*c.vx, &*c.vy, &*c.vz];
            // SAFETY: as in `with_views`; no view of these blocks is alive.
            let (data, touched) = unsafe { o.slots.blocks(start / LANES, len / LANES) };
            for (b, (out, flag)) in data.chunks_mut(k::SLOT_BLOCK).zip(touched.iter_mut()).enumerate() {
                *flag = shape_block(&o.shape, &g, b, out, *flag, vel, o.u, simd);
            }
        }
        self.with_views(start, len, |slots, shifts, _| {
            let mesh = [false; MAX_OBSTACLES];
            let (x, p) = ([&*c.x, &*c.y, &*c.z], [&mut *c.px, &mut *c.py, &mut *c.pz]);
            if simd {
                k::resolve_simd(slots, shifts, &mesh[..slots.len()], th, 0, x, p)
            } else {
                k::resolve_along_path(slots, shifts, &mesh[..slots.len()], th, 0, x, p)
            }
        });
    }

    /// The projection of the chunk's predictions out of their contacts
    /// ([`ObstacleSet::project`] on one chunk).
    pub fn project(&self, c: &mut ParticleChunk<'_>, simd: bool) {
        let (start, len) = (c.start, c.x.len());
        let th = &self.th[start..start + len];
        self.with_views(start, len, |slots, _, _| {
            let p = [&mut *c.px, &mut *c.py, &mut *c.pz];
            if simd {
                k::project_simd(slots, th, 0, p)
            } else {
                k::project_scalar(slots, th, 0, p)
            }
        });
    }

    /// The velocity pass of the chunk ([`ObstacleSet::velocity_pass`] on one chunk).
    pub fn velocity(&self, c: &mut ParticleChunk<'_>, simd: bool) {
        let (start, len) = (c.start, c.x.len());
        let th = &self.th[start..start + len];
        self.with_views(start, len, |slots, _, motion| {
            let (x, v) = ([&*c.x, &*c.y, &*c.z], [&mut *c.vx, &mut *c.vy, &mut *c.vz]);
            if simd {
                k::velocity_pass_simd(slots, motion, th, 0, x, v)
            } else {
                k::velocity_pass(slots, motion, th, 0, x, v)
            }
        });
    }
}
