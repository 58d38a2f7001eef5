//! The update pass of a substep with its fused forms ([`Fusion`]): the tethers, the update,
//! the obstacle stages of all-shape obstacles, the guard's finite check (last substep), the
//! next substep's predict (and its obstacle contacts and clamp mean), chunk by chunk; as the
//! sweep's wave when the step runs one. Element-wise, so the same bits as separate passes
//! (`fusion_tests.rs`).

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crate::data::particles::{chunk_finite_simd, ParticleChunk, RawParticles, RawSaved};
use crate::integrate::wind::WindState;
use crate::integrate::{predict, predict_saving, update, PredictParams};
use crate::obstacles::chunkwise::ChunkObstacles;
use crate::obstacles::ObstacleSet;
use crate::self_collision::mean::MeanParts;
use crate::world::step::fusion::Fusion;
use crate::world::World;

/// What the update pass of substep `s` of `n_sub` reads besides the world.
pub(super) struct SubstepPass<'a> {
    pub s: u32,
    pub n_sub: u32,
    /// The substep and `1 / h²`.
    pub h: f32,
    pub inv_h2: f32,
    /// Particles, and how the step runs.
    pub n: usize,
    pub simd: bool,
    pub parallel: bool,
    pub fusion: Fusion,
    /// Whether the wave predicts this substep (its bands, just before it sweeps them).
    pub wave_predicts: bool,
    /// Where the predict passes add the clamp's mean velocity, and their time.
    pub mean_sink: Option<(&'a MeanParts, &'a AtomicU64)>,
    /// Time of the obstacle stages run inside the chunks, summed over them.
    pub obstacle_ns: &'a AtomicU64,
    /// Cleared when the guard's check (last substep) finds a non-finite value.
    pub all_finite: &'a AtomicBool,
}

impl World {
    /// Runs the update pass of substep `u.s` (see the module docs); returns whether it also
    /// predicted the next substep.
    pub(super) fn fused_update_pass(&mut self, u: &SubstepPass<'_>) -> bool {
        let (h, inv_h2, n, simd, parallel) = (u.h, u.inv_h2, u.n, u.simd, u.parallel);
        let obstacle_ns = u.obstacle_ns;
        let damp = self.has_damping.then_some(&self.damp_factor[..]);
        // update, the obstacle velocity pass and (last substep) the guard's check,
        // chunk by chunk: element-wise, so the same bits as three passes
        let last = u.fusion.fused_guard && u.s + 1 == u.n_sub;
        let ahead = u.fusion.fuse_next && u.s + 1 < u.n_sub;
        let finite = u.all_finite;
        // the next substep's contacts (the shapes placed at its end) when it is
        // predicted here
        let t_next = self.time + ((u.s + 2) as f64) * (h as f64);
        // and this substep's contacts (the shapes placed at its end) when the wave
        // predicts it, on the same slots
        let t_now = self.time + ((u.s + 1) as f64) * (h as f64);
        let mut co_now = None;
        let stages = if u.fusion.chunk_obstacles && u.wave_predicts {
            let [now, next] = self.obstacles.chunkwise_at([t_now, t_next], h, n);
            co_now = Some(now);
            Obstacles::Chunkwise(next)
        } else if u.fusion.chunk_obstacles {
            Obstacles::Chunkwise(self.obstacles.chunkwise(t_next, h, n))
        } else if !self.obstacles.is_empty() {
            Obstacles::Whole(&self.obstacles)
        } else {
            Obstacles::None
        };
        let tethers_in_update = u.fusion.tethers_in_update;
        let pp = substep_predict(h, &self.effects, self.wind.as_ref());
        if tethers_in_update {
            let p = &self.particles;
            if u.wave_predicts {
                // the wave predicts the anchors' bands later: their predictions ahead of it
                let (x, v) = ([&p.x[..], &p.y, &p.z], [&p.vx[..], &p.vy, &p.vz]);
                self.tethers.predict_anchors(x, v, &p.w, |c| predict(c, &pp, simd));
            } else {
                self.tethers.take_anchors(&p.px, &p.py, &p.pz);
            }
        }
        let (particles, distance, backup) = (&mut self.particles, &mut self.distance, &mut self.backup);
        let tethers = &self.tethers;
        // `pp`: this substep's predict when the wave runs it (see `wave_predicts`), and the
        // next substep's when this pass runs it (only without wind: the same settings)
        let mut run = |motion: &[([f32; 3], f32)]| {
            let body = |mut c: ParticleChunk<'_>| {
                if tethers_in_update {
                    let r = c.start..c.start + c.px.len();
                    tethers.solve_range(r, c.px, c.py, c.pz);
                }
                if let (Obstacles::Chunkwise(co), true) = (&stages, u.fusion.fuse_project) {
                    timed(obstacle_ns, || co.project(&mut c, simd));
                }
                update(c.reborrow(), h, damp, simd);
                match &stages {
                    Obstacles::Chunkwise(co) => timed(obstacle_ns, || co.velocity(&mut c, simd)),
                    Obstacles::Whole(o) => timed(obstacle_ns, || o.velocity_pass_chunk(motion, &mut c, simd)),
                    Obstacles::None => {}
                }
                if last {
                    let real = n.saturating_sub(c.start).min(c.x.len());
                    if !chunk_finite_simd(&c.state(), real) {
                        finite.store(false, Ordering::Relaxed);
                    }
                }
                if ahead {
                    predict(c.reborrow(), &pp, simd);
                    add_mean(u.mean_sink, &c, n, simd);
                    if let Obstacles::Chunkwise(co) = &stages {
                        timed(obstacle_ns, || co.contacts(&mut c, simd));
                    }
                }
            };
            if u.fusion.wave {
                let len = particles.padded_len();
                let saved = (u.wave_predicts && u.fusion.fused_guard && u.s == 0).then(|| RawSaved::new(backup, len));
                let raw = RawParticles::new(particles);
                // SAFETY (both closures): the wave hands each range to one call, before
                // the sweep reaches its particles or once it is done with them, while no
                // other task touches them.
                let predict_band = |r: std::ops::Range<usize>| {
                    let mut c = unsafe { raw.chunk(r.clone()) };
                    let keep = saved.as_ref().map(|s| unsafe { s.range(r) });
                    predict_saving(c.reborrow(), keep, &pp, simd);
                    if let Some(co) = &co_now {
                        timed(obstacle_ns, || co.contacts(&mut c, simd));
                    }
                };
                let before: Option<&(dyn Fn(std::ops::Range<usize>) + Sync)> = if u.wave_predicts { Some(&predict_band) } else { None };
                distance.solve_wave(&raw, inv_h2, parallel, before, &|r| body(unsafe { raw.chunk(r) }));
            } else {
                particles.for_chunks(parallel, body);
            }
        };
        match &stages {
            Obstacles::Whole(o) => o.with_motion(run),
            _ => run(&[]),
        }
        ahead
    }
}

/// How the update pass runs the obstacle stages of its chunks. It lives on the stack for one
/// pass; boxing the large variant would allocate every substep.
#[allow(clippy::large_enum_variant)]
enum Obstacles<'a> {
    /// No obstacle.
    None,
    /// All shapes: the projection, the velocity pass and the next contacts, chunk by chunk.
    Chunkwise(ChunkObstacles<'a>),
    /// The velocity pass only (the other stages run in passes of their own).
    Whole(&'a ObstacleSet),
}

/// A substep's predict settings: gravity, drag and, when wind blows, its forces.
pub(super) fn substep_predict<'a>(h: f32, effects: &crate::Effects, wind: Option<&'a WindState>) -> PredictParams<'a> {
    PredictParams {
        h,
        gravity: effects.gravity,
        drag: effects.drag,
        force: wind.map(|w| [&w.fx[..], &w.fy[..], &w.fz[..]]),
    }
}

/// Runs `f` and adds the nanoseconds it took to `ns`.
pub(super) fn timed(ns: &AtomicU64, f: impl FnOnce()) {
    let t0 = std::time::Instant::now();
    f();
    ns.fetch_add(t0.elapsed().as_nanos() as u64, Ordering::Relaxed);
}

/// Adds a chunk's predicted velocities to the mean-velocity sums, when they are kept, and
/// the time it took to the nanoseconds counter beside them.
pub(super) fn add_mean(sink: Option<(&MeanParts, &AtomicU64)>, c: &crate::data::particles::ParticleChunk<'_>, n: usize, simd: bool) {
    if let Some((m, ns)) = sink {
        timed(ns, || m.add(c.start, [&c.vx[..], &c.vy[..], &c.vz[..]], c.w, n, simd));
    }
}
