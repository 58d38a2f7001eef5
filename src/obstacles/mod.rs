//! Obstacles in the world: analytic [`Shape`](crate::model::shapes::Shape)s and triangle meshes, static or moving with a
//! constant velocity, and their part of the step (Landovskaya, Landovsky & Frolovsky).
//!
//! Per substep of length `h` ending at time `t` (`src/world/step/`):
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
//!    of the predicted velocity (`kernels/`).
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

mod blocks;
pub(crate) mod chunkwise;
pub mod kernels;
pub mod mesh;
pub mod obstacle;
pub mod penetration;

use crate::data::exec::Exec;

use crate::data::lanes::LANES;
use crate::data::particles::{ParticleChunk, Particles};
use crate::error::{non_negative, Result};
use crate::obstacles::kernels::{self as k, GenInput, Slots};
pub use crate::obstacles::mesh::contact::{BroadphaseKind, MeshBroadphase};
use crate::obstacles::mesh::face_cache::CacheBlock;
use crate::obstacles::mesh::face_memory::NO_FACE;
use crate::obstacles::mesh::pass::MeshPass;
use crate::obstacles::obstacle::displacement;
pub use crate::obstacles::obstacle::{Geometry, MeshObstacle, Obstacle};

pub use crate::model::shapes::MIN_MARGIN;
pub(crate) use blocks::shape_block;
use blocks::{for_blocks, on_stack};

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
