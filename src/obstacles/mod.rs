//! Obstacles in the world: analytic [`Shape`](crate::model::shapes::Shape)s and triangle meshes, static or moving with a
//! constant velocity, and their part of the step (Landovskaya, Landovsky & Frolovsky).
//!
//! Per substep of length `h` ending at time `t` (`src/world/step.rs`):
//!
//! 1. **Place.** Every moving obstacle is put at `start + u t` (meshes: the base mesh
//!    translated, then the broadphase rebuilt, or refitted for a BVH). Positions are a
//!    function of time, never accumulated, so a resumed run sees the same bits.
//! 2. **Contacts** (after predict): every particle against every obstacle, in parallel over
//!    blocks of eight particles; each particle writes only its own slot, so the result does not
//!    depend on the thread count. The particle's path is taken in the obstacle's frame,
//!    `x - u h -> p`, so a moving obstacle cannot sweep through a resting particle. Contacts are
//!    kept within `reach = Th + max(Th, 3 mm)` so that the constraint solve, which moves the
//!    particles after the contacts were found, still meets a contact plane.
//!    Then the paper's response: each particle goes back along its path until it stands the
//!    thickness off the contact plane (the point lies before the first crossing, so outside).
//! 3. **Projection** in every solver iteration, after the cloth constraints: the contact planes
//!    as inequality constraints (the constraints may have pulled a particle back in).
//! 4. **Velocity pass** after the velocity update: inelastic contact with Coulomb friction
//!    relative to the obstacle's velocity, the normal impulse measured by the approach speed
//!    of the predicted velocity (`obstacle_kernels.rs`).
//!
//! When every obstacle is an analytic shape, stages 2 to 4 run chunk by chunk inside the
//! step's predict and update passes (`chunkwise`): the same bits, one pass over the
//! particles fewer for each.
//!
//! Mesh obstacles use one of three broadphases ([`BroadphaseKind`]), all giving the same
//! contacts, and optionally the paper's face memory ([`face_memory`](crate::obstacles::mesh::face_memory)): a
//! particle over the face it touched last tests only that face. Each particle keeps the
//! candidate faces of a box around its path from step to step ([`face_cache`](crate::obstacles::mesh::face_cache)) and asks the
//! broadphase again only when its path leaves that box: the same contacts for a fraction of
//! the broadphase work. A world without obstacles
//! skips all of this: no pass, no allocation.
//!
//! Checkpoints (`src/world/checkpoint.rs`) rebuild obstacles from the scene, and moving obstacles'
//! places are functions of time, so a resumed run is bitwise the uninterrupted one, except
//! that face memories are not saved: with `face_memory` on, a resumed run starts with empty
//! memories and may differ slightly. `World::restore` empties them too (and the face caches),
//! so restoring in place and resuming from a file step alike.

pub(crate) mod chunkwise;
pub mod kernels;
pub mod mesh;
pub mod obstacle;
pub mod penetration;

use crate::data::exec::Exec;
use rayon::prelude::*;

use crate::data::lanes::LANES;
use crate::data::particles::{ParticleChunk, Particles};
use crate::error::{non_negative, Result};
use crate::obstacles::kernels::{self as k, GenInput, Slots, SLOT_BLOCK};
pub use crate::obstacles::mesh::contact::{BroadphaseKind, MeshBroadphase};
use crate::obstacles::mesh::face_cache::CacheBlock;
use crate::obstacles::mesh::face_memory::NO_FACE;
use crate::obstacles::mesh::pass::MeshPass;
use crate::obstacles::obstacle::displacement;
pub use crate::obstacles::obstacle::{Geometry, MeshObstacle, Obstacle};

pub use crate::model::shapes::MIN_MARGIN;
/// Blocks of eight particles per parallel task.
const BLOCKS_PER_TASK: usize = 32;

/// The world's obstacles and their per-particle scratch (empty until the first obstacle).
#[derive(Debug, Clone, Default)]
pub struct ObstacleSet {
    list: Vec<Obstacle>,
    slots: Vec<Slots>,
    /// Whether each obstacle is a mesh (the response's rule for a path crossing a plane from
    /// inside the layer, [`k::resolve_along_path`]), set with the slots.
    mesh: Vec<bool>,
    th: Vec<f32>,
    reach: Vec<f32>,
    friction: f32,
    busy: std::time::Duration,
    /// Gather candidate faces afresh every substep instead of keeping them ([`face_cache`](crate::obstacles::mesh::face_cache)),
    /// and search blocks far from the mesh too: the reference the fast path is tested against
    /// (same contacts).
    fresh_search: bool,
}

impl ObstacleSet {
    /// Is there no obstacle?
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// Number of obstacles.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// Adds an obstacle (its shape validated); returns its index.
    pub fn add(&mut self, obstacle: Obstacle) -> Result<usize> {
        if let Geometry::Shape(s) = &obstacle.geometry {
            s.validate()?;
        }
        self.list.push(obstacle);
        self.th.clear();
        Ok(self.list.len() - 1)
    }

    /// The obstacles, in the order they were added.
    pub fn list(&self) -> &[Obstacle] {
        &self.list
    }

    /// Sets the Coulomb friction coefficient of obstacles that have none of their own.
    pub fn set_friction(&mut self, mu: f32) -> Result<()> {
        non_negative("friction", mu)?;
        self.friction = mu;
        Ok(())
    }

    /// The default friction coefficient.
    pub fn friction(&self) -> f32 {
        self.friction
    }

    /// Wall time spent in the obstacle stages so far.
    pub fn busy(&self) -> std::time::Duration {
        self.busy
    }

    /// How many of the first `n` particles hold a contact with at least one obstacle.
    pub fn contact_count(&self, n: usize) -> usize {
        (0..n)
            .filter(|&i| {
                self.slots
                    .iter()
                    .any(|s| i / LANES < s.blocks() && k::read_slot(&s.data, i).1 != [0.0; 3])
            })
            .count()
    }

    /// Gathers candidate faces afresh every substep (`true`) or keeps them while they still
    /// cover the step (`false`, the default); both give the same contacts.
    #[cfg(test)]
    pub(crate) fn set_fresh_search(&mut self, on: bool) {
        self.fresh_search = on;
    }

    /// Adds the time since `t0` to the time spent in obstacle stages.
    pub(crate) fn add_busy(&mut self, t0: std::time::Instant) {
        self.busy += t0.elapsed();
    }

    /// Adds `d` to the time spent in obstacle stages.
    pub(crate) fn add_duration(&mut self, d: std::time::Duration) {
        self.busy += d;
    }

    /// Forgets the per-particle arrays (the particle count changed).
    pub(crate) fn invalidate(&mut self) {
        self.th.clear();
    }

    /// Forgets what mesh obstacles kept from earlier steps: the face caches' lists (their
    /// storage stays) and the face memories. [`World::restore`](crate::World::restore) calls
    /// it, so a restored world steps exactly as a resumed run does (which builds its obstacles
    /// afresh), whatever it stepped before.
    pub(crate) fn forget_history(&mut self) {
        for o in &mut self.list {
            if let Geometry::Mesh(m) = &mut o.geometry {
                m.memory.fill(NO_FACE);
                m.cache.blocks_mut().iter_mut().for_each(CacheBlock::clear_all);
            }
        }
    }

    /// Whether every obstacle is an analytic shape and there are at most
    /// [`chunkwise::MAX_OBSTACLES`]: the step then runs the obstacle stages chunk by chunk
    /// inside its element-wise passes (`chunkwise`).
    pub(crate) fn runs_chunkwise(&self) -> bool {
        self.list.len() <= chunkwise::MAX_OBSTACLES && self.list.iter().all(|o| matches!(o.geometry, Geometry::Shape(_)))
    }

    /// Sizes the per-particle arrays (thickness per cloth, contact slots, face memory).
    pub(crate) fn prepare(
        &mut self,
        particles: &Particles,
        cloths: &[crate::model::layout::ClothInfo],
        strands: &[crate::model::layout::StrandInfo],
    ) {
        let len = particles.padded_len();
        if self.th.len() == len && self.slots.len() == self.list.len() {
            return;
        }
        self.th = vec![0.0; len];
        for c in cloths {
            let first = c.first as usize;
            let end = (first + (c.rows * c.cols) as usize).min(len);
            self.th[first..end].fill(c.thickness);
        }
        // Strand points stand off obstacles by half their diameter.
        for g in strands {
            let first = g.first as usize;
            let end = (first + (g.count * g.points) as usize).min(len);
            self.th[first..end].fill(0.5 * g.thickness);
        }
        self.reach = self.th.iter().map(|&t| t + t.max(MIN_MARGIN)).collect();
        self.slots = vec![Slots::new(len / LANES); self.list.len()];
        self.mesh = self.list.iter().map(|o| matches!(o.geometry, Geometry::Mesh(_))).collect();
        for o in &mut self.list {
            if let Geometry::Mesh(m) = &mut o.geometry {
                m.memory = if m.face_memory { vec![NO_FACE; len] } else { Vec::new() };
            }
        }
    }

    /// Places every obstacle at time `t` and finds the contacts of the step `x -> p` of
    /// length `h` (module doc, stages 1 and 2).
    pub(crate) fn generate(&mut self, particles: &Particles, t: f64, h: f32, exec: Exec) {
        let (parallel, simd) = (exec.parallel(), exec.simd());
        let n = particles.count();
        let vel = [&particles.vx[..], &particles.vy[..], &particles.vz[..]];
        for (o, slots) in self.list.iter_mut().zip(&mut self.slots) {
            let u = o.velocity;
            let g = GenInput {
                x: [&particles.x, &particles.y, &particles.z],
                p: [&particles.px, &particles.py, &particles.pz],
                w: &particles.w,
                th: &self.th,
                reach: &self.reach,
                n,
                shift: u.map(|c| c * h),
            };
            match &mut o.geometry {
                Geometry::Shape(s) => {
                    let shape = s.translated(displacement(u, t));
                    for_blocks(slots, &mut [], &mut [], parallel, 0, |b, out, was, _, _, _| {
                        shape_block(&shape, &g, b, out, was, vel, u, simd)
                    });
                }
                Geometry::Mesh(m) => {
                    m.place(displacement(u, t));
                    m.cache.sync(self.th.len(), m.mesh.stamp());
                    let pass = MeshPass {
                        mesh: &m.mesh,
                        bp: &m.broadphase,
                        input: g,
                        vel,
                        u,
                        remember: !m.memory.is_empty(),
                        fresh: self.fresh_search,
                        simd,
                    };
                    for_blocks(
                        slots,
                        &mut m.memory,
                        m.cache.blocks_mut(),
                        parallel,
                        m.mesh.face_count(),
                        |b, out, was, mem, cache, scratch| match cache.first_mut() {
                            Some(cache) => pass.block(b, out, was, mem, cache, scratch),
                            // the cache is synced to every block above; were one missing, a
                            // list of its own (gathers every substep) gives the same contacts
                            None => pass.block(b, out, was, mem, &mut CacheBlock::default(), scratch),
                        },
                    );
                }
            }
        }
    }

    /// Moves every particle back along its path out of its contacts (stage 2, the paper's
    /// response; [`k::resolve_along_path`]).
    pub(crate) fn resolve(&self, particles: &mut Particles, h: f32, exec: Exec) {
        let (parallel, simd) = (exec.parallel(), exec.simd());
        let (slots, th, mesh) = (&self.slots, &self.th, &self.mesh);
        on_stack(self.list.iter().map(|o| o.velocity.map(|c| c * h)), |shifts| {
            particles.for_chunks(parallel, |c| {
                let (x, p) = ([&*c.x, &*c.y, &*c.z], [c.px, c.py, c.pz]);
                if simd {
                    k::resolve_simd(slots, shifts, mesh, th, c.start, x, p)
                } else {
                    k::resolve_along_path(slots, shifts, mesh, th, c.start, x, p)
                }
            })
        });
    }

    /// Projects every particle's prediction out of its contacts (stage 3).
    pub(crate) fn project(&self, particles: &mut Particles, exec: Exec) {
        let (parallel, simd) = (exec.parallel(), exec.simd());
        let (slots, th) = (&self.slots, &self.th);
        particles.for_chunks(parallel, |c| {
            if simd {
                k::project_simd(slots, th, c.start, [c.px, c.py, c.pz])
            } else {
                k::project_scalar(slots, th, c.start, [c.px, c.py, c.pz])
            }
        });
    }

    /// Removes approaching normal velocity and applies friction (stage 4).
    pub(crate) fn velocity_pass(&self, particles: &mut Particles, exec: Exec) {
        let (parallel, simd) = (exec.parallel(), exec.simd());
        self.with_motion(|motion| particles.for_chunks(parallel, |mut c| self.velocity_pass_chunk(motion, &mut c, simd)));
    }

    /// Runs `f` with each obstacle's velocity and friction coefficient, for
    /// [`velocity_pass_chunk`](Self::velocity_pass_chunk) (held on the stack for up to 8
    /// obstacles, so a substep allocates nothing).
    pub(crate) fn with_motion<R>(&self, f: impl FnOnce(&[([f32; 3], f32)]) -> R) -> R {
        on_stack(self.list.iter().map(|o| (o.velocity, o.friction.unwrap_or(self.friction))), f)
    }

    /// Stage 4 on one chunk (element-wise: the step runs it right after the chunk's update,
    /// while the chunk is in cache; the same bits as a pass of its own).
    pub(crate) fn velocity_pass_chunk(&self, motion: &[([f32; 3], f32)], c: &mut ParticleChunk<'_>, simd: bool) {
        let (x, v) = ([&*c.x, &*c.y, &*c.z], [&mut *c.vx, &mut *c.vy, &mut *c.vz]);
        if simd {
            k::velocity_pass_simd(&self.slots, motion, &self.th, c.start, x, v)
        } else {
            k::velocity_pass(&self.slots, motion, &self.th, c.start, x, v)
        }
    }
}

/// The contacts of block `b` (its slots `out`, its flag `was`) with a placed shape, and their
/// approach speeds from the velocities `vel` (indexed as `g`'s arrays); returns the block's
/// new flag. A block the pre-test finds far gets exactly the empty block the full test writes.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn shape_block(
    shape: &crate::model::shapes::Shape,
    g: &GenInput,
    b: usize,
    out: &mut [f32],
    was: bool,
    vel: [&[f32]; 3],
    u: [f32; 3],
    simd: bool,
) -> bool {
    let may = if simd {
        k::shape_may_touch_simd(shape, g, b)
    } else {
        k::shape_may_touch_scalar(shape, g, b)
    };
    if !may {
        if was {
            out.fill(0.0);
        }
        return false;
    }
    if simd {
        k::shape_block_simd(shape, g, b, out);
        k::fill_approach_simd(out, b, vel, u);
    } else {
        k::shape_block_scalar(shape, g, b, out);
        k::fill_approach(out, b, vel, u);
    }
    k::block_nonzero(out)
}

/// Runs `f(block, slots of the block, its touched flag, face memory of the block, face cache
/// of the block, scratch)` over every block of eight particles, in parallel tasks of
/// [`BLOCKS_PER_TASK`] blocks or serially, and sets the block's flag to what `f` returns (`f`
/// returns [`k::block_nonzero`] of the block, or `false` for a block it leaves or makes empty).
/// `memory` is empty or one entry per particle, `cache` empty or one [`CacheBlock`] per block
/// (handed to `f` as a slice of one). Each thread's scratch holds at least `faces` entries
/// (the mesh's face count, the most candidates a query can give but for a broadphase's
/// duplicates), reserved once, so its size does not depend on which thread ran which block.
fn for_blocks<F>(slots: &mut Slots, memory: &mut [u32], cache: &mut [CacheBlock], parallel: bool, faces: usize, f: F)
where
    F: Fn(usize, &mut [f32], bool, &mut [u32], &mut [CacheBlock], &mut Vec<u32>) -> bool + Sync + Send,
{
    let task = SLOT_BLOCK * BLOCKS_PER_TASK;
    let per_task = LANES * BLOCKS_PER_TASK;
    let tasks = slots.data.len().div_ceil(task);
    let run = |t: usize, chunk: &mut [f32], flags: &mut [bool], mem: &mut [u32], cache: &mut [CacheBlock], scratch: &mut Vec<u32>| {
        for (j, (out, flag)) in chunk.chunks_mut(SLOT_BLOCK).zip(flags.iter_mut()).enumerate() {
            let lanes = j * LANES..(j + 1) * LANES;
            let m = if mem.is_empty() { &mut [][..] } else { &mut mem[lanes.clone()] };
            let c = if cache.is_empty() { &mut [][..] } else { &mut cache[j..j + 1] };
            *flag = f(t * BLOCKS_PER_TASK + j, out, *flag, m, c, scratch);
        }
    };
    // `memory` and `cache` cut into one piece per task, or one empty piece per task when empty,
    // without collecting the pieces (a step allocates nothing).
    fn pieces<T: Send>(v: &mut [T], per_task: usize, tasks: usize) -> impl IndexedParallelIterator<Item = &mut [T]> + '_ {
        if v.is_empty() {
            rayon::iter::Either::Left((0..tasks).into_par_iter().map(|_| <&mut [T]>::default()))
        } else {
            rayon::iter::Either::Right(v.par_chunks_mut(per_task))
        }
    }
    fn pieces_serial<T>(v: &mut [T], per_task: usize, tasks: usize) -> impl Iterator<Item = &mut [T]> + '_ {
        if v.is_empty() {
            rayon::iter::Either::Left((0..tasks).map(|_| <&mut [T]>::default()))
        } else {
            rayon::iter::Either::Right(v.chunks_mut(per_task))
        }
    }
    let Slots { data, touched } = slots;
    if parallel {
        let mems = pieces(memory, per_task, tasks);
        let caches = pieces(cache, BLOCKS_PER_TASK, tasks);
        data.par_chunks_mut(task)
            .zip(touched.par_chunks_mut(BLOCKS_PER_TASK))
            .zip(mems.zip(caches))
            .enumerate()
            .for_each(|(t, ((chunk, flags), (mem, c)))| with_scratch(faces, |s| run(t, chunk, flags, mem, c, s)));
    } else {
        let blocks = data.chunks_mut(task).zip(touched.chunks_mut(BLOCKS_PER_TASK));
        let mems = pieces_serial(memory, per_task, tasks);
        let caches = pieces_serial(cache, BLOCKS_PER_TASK, tasks);
        for (t, ((chunk, flags), (mem, c))) in blocks.zip(mems.zip(caches)).enumerate() {
            with_scratch(faces, |s| run(t, chunk, flags, mem, c, s));
        }
    }
}

/// Runs `f` on the items, held in a stack array when there are at most 8 (so a substep with
/// a few obstacles allocates nothing), else in a `Vec`.
fn on_stack<T: Copy + Default, R>(items: impl ExactSizeIterator<Item = T>, f: impl FnOnce(&[T]) -> R) -> R {
    let n = items.len();
    if n <= 8 {
        let mut buf = [T::default(); 8];
        for (b, v) in buf.iter_mut().zip(items) {
            *b = v;
        }
        f(&buf[..n])
    } else {
        f(&items.collect::<Vec<T>>())
    }
}

thread_local! {
    /// Each thread's candidate-face scratch for [`for_blocks`], kept across steps so that a
    /// step allocates nothing once it has grown.
    static SCRATCH: std::cell::Cell<Vec<u32>> = const { std::cell::Cell::new(Vec::new()) };
}

/// Runs `f` with this thread's scratch (taken out, so a nested call gets a fresh one), holding
/// at least `reserve` entries.
fn with_scratch<R>(reserve: usize, f: impl FnOnce(&mut Vec<u32>) -> R) -> R {
    let mut s = SCRATCH.with(|c| c.take());
    if s.capacity() < reserve {
        s.reserve(reserve - s.len());
    }
    let r = f(&mut s);
    SCRATCH.with(|c| c.set(s));
    r
}

#[cfg(test)]
mod tests {
    use crate::{ClothDesc, Effects, SolverParams, World};

    #[test]
    fn a_world_without_obstacles_allocates_nothing_for_them() {
        let mut w = World::new(SolverParams::default(), Effects::gravity()).unwrap();
        w.add_cloth(&ClothDesc::default()).unwrap();
        w.step(1.0 / 60.0).unwrap();
        let o = &w.obstacles;
        assert!(o.is_empty() && o.th.capacity() == 0 && o.reach.capacity() == 0 && o.slots.capacity() == 0);
        w.add_obstacle(super::Obstacle::shape(crate::model::shapes::Shape::plane([0.0; 3], [0.0, 1.0, 0.0]).unwrap()).unwrap())
            .unwrap();
        w.step(1.0 / 60.0).unwrap();
        assert_eq!(w.obstacles.th.len(), w.particles.padded_len());
    }
}

#[cfg(test)]
mod flags_tests;
