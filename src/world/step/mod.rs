//! The step, stage by stage, top to bottom.
//!
//! ```text
//! step(dt):
//!   kinematic pins: stop last step's moves, v = (target - x) / dt    [embed::kinematic]
//!   keep a copy of x, v (guard; XPBD: chunk by chunk inside the first predict)
//!   self-collision pair lists from x (hash or AABB tree)  [self-collision] (if on)
//!   for each substep h = dt / substeps:
//!     wind forces per triangle → per particle          [effects]        (if named)
//!     predict: v += h g + h w f, drag; p = x + h v      [integrate]
//!     obstacle contacts of x -> p, back along the path  [obstacles]        (if any)
//!     speed clamp relative to the mean velocity        [self-collision]  (if on)
//!     `iterations` sweeps: distance constraints by colour, tethers   [constraints]
//!       obstacle projection                             [obstacles]        (if any)
//!       strands pushed out of their scalps              [strands::scalp] (if any)
//!     pair pass, velocity correction                    [self-collision]  (if on)
//!     update: v = (p - x) / h, damping; x = p          [integrate]
//!     obstacle velocity pass: normal part, friction     [obstacles]        (if any)
//!       (both chunk by chunk in one pass; the last substep's pass also checks that the
//!        chunk's x, v are finite, for the guard)
//!   Fused forms, the same bits (`fusion.rs` decides which run): obstacles that are
//!   all shapes run their contacts after each chunk's predict, their last projection before
//!   its update and their velocity pass after it (`obstacles::chunkwise`); a world that is
//!   one grid cloth swept once a substep runs the sweep and the update pass as one wave
//!   (`DistanceSet::solve_wave`), which also predicts each band (and runs its obstacle
//!   contacts) just before sweeping it when the bands start on whole blocks; on the pool,
//!   the tethers of a small world run range by range just before its update.
//!   (solver.method = symplectic-euler | leapfrog | implicit-euler: the force-based step of
//!    integrate::mass_spring / integrate::implicit replaces the substep loop above; its drift
//!    feeds the obstacle and self-collision stages as the prediction p, world::contacts)
//!   on a non-finite value: restore the copy, replay the step with a check after every stage
//!   to name the stage and particle, and return `Diverged`
//!
//! The guard costs no pass of its own over the particles (at 1M particles a copy of x, v
//! and a scan of them take milliseconds): the copy is made in the first predict's chunks,
//! which read x and v anyway, and the check in the last update's chunks, while they are in
//! cache. The force-based methods keep the separate copy and scan.
//!   kinematic pins land exactly on their targets                     [embed::kinematic]
//! ```

mod fusion;
pub(crate) mod stages;
mod update_pass;

use std::sync::atomic::AtomicU64;

use crate::data::particles::ParticleChunk;
use crate::error::{positive, Result, WeftError};
use crate::integrate::{predict_saving, update};
use crate::model::params::Method;
use crate::self_collision::mean::MeanParts;
use crate::world::step::fusion::Fusion;
use crate::world::step::update_pass::{add_mean, substep_predict, timed, SubstepPass};
use crate::world::World;

/// Index of the first entry below `n` that is not finite in any of `arrays`.
fn first_non_finite(arrays: &[&[f32]], n: usize) -> Option<usize> {
    (0..n).find(|&i| arrays.iter().any(|a| !a[i].is_finite()))
}

/// What a run of the XPBD substeps found.
enum Ran {
    /// Nothing wrong (or nothing checked).
    Clean,
    /// The guard's check in the last update found a non-finite value.
    NonFinite,
    /// The stage-by-stage check (a replay) found the first non-finite value.
    Found(usize, &'static str),
}

impl World {
    /// Advances the world by `dt` seconds.
    ///
    /// With [`guard`](crate::SolverParams::guard) on (the default), a step that produces a
    /// non-finite value restores the state from before the step and returns
    /// [`WeftError::Diverged`] naming the first bad particle and the stage that produced it;
    /// the user's state is never overwritten with NaN.
    pub fn step(&mut self, dt: f32) -> Result<()> {
        positive("dt", dt)?;
        self.clock.start();
        self.begin_kinematic(dt);
        let guard = self.params.guard;
        let method = self.params.method;
        // XPBD saves the state inside its first predict pass.
        if guard && method != Method::Xpbd {
            self.save_backup();
        }
        self.begin_thread_choice();
        self.clock.lap("pins, guard backup");
        let ran = match method {
            Method::Xpbd => Ok(self.in_pool(|w| w.run_substeps(dt, false))),
            m => self.in_pool(|w| w.run_mass_spring(dt, m)).map(|_| Ran::Clean),
        };
        if guard && method != Method::Xpbd && (ran.is_err() || self.particles.first_non_finite().is_some()) {
            let particle = self.particles.first_non_finite().unwrap_or(0);
            self.restore_backup();
            return Err(ran.err().unwrap_or(WeftError::Diverged {
                particle,
                stage: method.name(),
            }));
        }
        let ran = ran?;
        self.clock.lap("leave pool");
        if matches!(ran, Ran::NonFinite) {
            self.restore_backup();
            let found = self.in_pool(|w| w.run_substeps(dt, true));
            self.restore_backup();
            let (particle, stage) = match found {
                Ran::Found(i, stage) => (i, stage),
                _ => (self.particles.first_non_finite().unwrap_or(0), "step"),
            };
            return Err(WeftError::Diverged { particle, stage });
        }
        self.clock.lap("guard check");
        self.finish_kinematic();
        self.time += dt as f64;
        self.steps += 1;
        self.end_thread_choice();
        self.clock.stop("step end");
        Ok(())
    }

    fn save_backup(&mut self) {
        let p = &self.particles;
        for (dst, src) in self.backup.iter_mut().zip([&p.x, &p.y, &p.z, &p.vx, &p.vy, &p.vz]) {
            dst.resize(src.len(), 0.0);
            dst.copy_from_slice(src);
        }
    }

    fn restore_backup(&mut self) {
        let p = &mut self.particles;
        for (src, dst) in self
            .backup
            .iter()
            .zip([&mut p.x, &mut p.y, &mut p.z, &mut p.vx, &mut p.vy, &mut p.vz])
        {
            dst.copy_from_slice(src);
        }
        p.px.copy_from_slice(&p.x);
        p.py.copy_from_slice(&p.y);
        p.pz.copy_from_slice(&p.z);
    }

    /// Runs the substeps. With `check`, stops at the first stage that leaves a non-finite
    /// value and returns it as [`Ran::Found`]; without (the fast path), with the guard on, saves
    /// the state in the first predict and checks the end state in the last update
    /// ([`Ran::NonFinite`]).
    fn run_substeps(&mut self, dt: f32, check: bool) -> Ran {
        self.clock.lap("enter pool");
        let n = self.particles.count();
        let n_sub = self.params.substeps;
        let h = dt / n_sub as f32;
        let exec = self.exec();
        let (simd, parallel) = (exec.simd(), exec.parallel());
        if self.has_damping && self.damp_h != h {
            // In place (no allocation once sized). Pinned particles are kinematic: not damped.
            let (rate, w) = (&self.damping_rate, &self.particles.w);
            self.damp_factor.resize(self.particles.padded_len(), 1.0);
            for (i, f) in self.damp_factor.iter_mut().enumerate() {
                let c = rate.get(i).copied().unwrap_or(0.0);
                *f = if w[i] > 0.0 { 1.0 / (1.0 + c * h) } else { 1.0 };
            }
            self.damp_h = h;
        }
        let inv_h2 = 1.0 / (h * h);
        self.last_h = h;
        macro_rules! checkpoint {
            ($stage:literal, $($a:expr),+) => {
                if check {
                    if let Some(i) = first_non_finite(&[$(&$a[..]),+], n) {
                        return Ran::Found(i, $stage);
                    }
                }
            };
        }
        let has_obstacles = !self.obstacles.is_empty();
        let all_finite = std::sync::atomic::AtomicBool::new(true);
        if has_obstacles {
            self.obstacles.prepare(&self.particles, &self.cloths, &self.strands);
        }
        self.clock.lap("step setup");
        let sc_start = std::time::Instant::now();
        let sc = self.begin_self_collision(h * n_sub as f32, exec);
        let mut sc_time = sc_start.elapsed();
        if sc.is_some() {
            self.clock.lap("self-collision lists");
            let p = &self.particles;
            let steps = self.steps;
            self.selfcol.record_start_state([&p.x, &p.y, &p.z], n, steps, parallel);
            self.clock.lap("self-collision measure");
        }
        let fusion = self.fusion(check, sc.is_some(), simd, parallel, n);
        let Fusion {
            fused_guard,
            fused_mean,
            chunk_obstacles,
            fuse_project,
            wave,
            wave_can_predict,
            ..
        } = fusion;
        // The clamp's mean velocity summed inside predict (`Fusion::fused_mean`) is
        // self-collision time: summed over the chunks, shared by the threads (like the
        // obstacles' velocity pass below), and added to the stage's.
        let mean_ns = AtomicU64::new(0);
        // Taken out of the world for the substeps (and put back after them) so that the predict
        // passes can fill it while the stages borrow the world.
        let mut parts = if fused_mean {
            std::mem::take(&mut self.selfcol.mean_parts)
        } else {
            MeanParts::default()
        };
        if fused_mean {
            parts.reset(n);
        }
        let mean_parts = fused_mean.then_some(&parts);
        let mean_sink = mean_parts.map(|m| (m, &mean_ns));
        let obstacle_ns = AtomicU64::new(0);
        let mut predicted_ahead = false;
        for s in 0..n_sub {
            let wave_predicts = wave_can_predict && !predicted_ahead;
            let t = self.time + (s as f64) * (h as f64);
            if let (Some(w), Some(state)) = (&self.effects.wind, &mut self.wind) {
                let p = &self.particles;
                state.compute(w, t, &self.triangles, [&p.x, &p.y, &p.z], [&p.vx, &p.vy, &p.vz], exec);
                checkpoint!("wind", state.fx, state.fy, state.fz);
                self.clock.lap("wind");
            }
            {
                let pp = substep_predict(h, &self.effects, self.wind.as_ref());
                let t_end = self.time + ((s + 1) as f64) * (h as f64);
                let co = (chunk_obstacles && !predicted_ahead && !wave_predicts).then(|| self.obstacles.chunkwise(t_end, h, n));
                // A chunk's predict (with the guard's copy when given), mean sums and contacts.
                let chunk = |mut c: ParticleChunk<'_>, saved: Option<[&mut [f32]; 6]>| {
                    predict_saving(c.reborrow(), saved, &pp, simd);
                    add_mean(mean_sink, &c, n, simd);
                    if let Some(co) = &co {
                        timed(&obstacle_ns, || co.contacts(&mut c, simd));
                    }
                };
                if predicted_ahead || wave_predicts {
                    // done by the previous substep's update pass, or by the wave below
                } else if fused_guard && s == 0 {
                    self.particles
                        .for_chunks_saving(parallel, &mut self.backup, |c, saved| chunk(c, Some(saved)));
                } else {
                    self.particles.for_chunks(parallel, |c| chunk(c, None));
                }
            }
            {
                let p = &self.particles;
                checkpoint!("predict", p.px, p.py, p.pz, p.vx, p.vy, p.vz);
            }
            self.clock
                .lap(if chunk_obstacles { "predict, obstacle contacts" } else { "predict" });
            if has_obstacles && !chunk_obstacles {
                self.obstacle_contacts_stage(s, h, exec);
                let p = &self.particles;
                checkpoint!("obstacles", p.px, p.py, p.pz);
                self.clock.lap("obstacle contacts");
            }
            if let Some(a) = sc {
                let t0 = std::time::Instant::now();
                let mean = mean_parts.map(MeanParts::mean);
                self.self_collision_clamp(a, n_sub, h, exec, mean);
                sc_time += t0.elapsed();
                let p = &self.particles;
                checkpoint!("self-collision clamp", p.px, p.py, p.pz, p.vx, p.vy, p.vz);
                self.clock.lap("self-collision clamp");
            }
            // With one sweep a substep, only the last substep's multipliers are read (the
            // elastic energy of `metrics`), so the others are not stored.
            if self.params.iterations == 1 && s + 1 < n_sub {
                self.distance.reset_lambda_unkept();
            } else {
                self.distance.reset_lambda();
            }
            for it in 0..self.params.iterations {
                if !wave {
                    self.distance_stage(inv_h2, exec);
                    let p = &self.particles;
                    checkpoint!("constraints", p.px, p.py, p.pz);
                    self.clock.lap("distance constraints");
                }
                if !self.tethers.is_empty() && !fusion.tethers_in_update {
                    self.tether_stage(exec);
                    let p = &self.particles;
                    checkpoint!("tethers", p.px, p.py, p.pz);
                    self.clock.lap("tethers");
                }
                if has_obstacles && !(fuse_project && it + 1 == self.params.iterations) {
                    self.obstacle_projection_stage(exec);
                    let p = &self.particles;
                    checkpoint!("obstacles", p.px, p.py, p.pz);
                    self.clock.lap("obstacle projection");
                }
                if !self.scalps.is_empty() {
                    self.scalp_stage(exec);
                    let p = &self.particles;
                    checkpoint!("scalp", p.px, p.py, p.pz);
                    self.clock.lap("scalp");
                }
            }
            if let Some(a) = sc {
                let t0 = std::time::Instant::now();
                self.self_collision_pairs_pass(a, h, exec);
                sc_time += t0.elapsed();
                let p = &self.particles;
                checkpoint!("self-collision", p.px, p.py, p.pz);
                self.clock.lap("self-collision pairs");
            }
            if !check {
                let pass = SubstepPass {
                    s,
                    n_sub,
                    h,
                    inv_h2,
                    n,
                    simd,
                    parallel,
                    fusion,
                    wave_predicts,
                    mean_sink,
                    obstacle_ns: &obstacle_ns,
                    all_finite: &all_finite,
                };
                predicted_ahead = self.fused_update_pass(&pass);
                self.clock.lap(match (wave, fusion.tethers_in_update) {
                    (true, false) => "distance constraints, update, obstacles, next predict (one wave)",
                    (true, true) => "distance constraints, tethers, update, obstacles, next predict (one wave)",
                    (false, false) => "update, obstacle velocity, next predict",
                    (false, true) => "tethers, update, obstacle velocity, next predict",
                });
                continue;
            }
            let damp = self.has_damping.then_some(&self.damp_factor[..]);
            self.particles.for_chunks(parallel, |c| update(c, h, damp, simd));
            let p = &self.particles;
            checkpoint!("update", p.x, p.y, p.z, p.vx, p.vy, p.vz);
            self.clock.lap("update");
            if has_obstacles {
                self.obstacle_velocity_stage(exec);
                let p = &self.particles;
                checkpoint!("obstacles", p.vx, p.vy, p.vz);
                self.clock.lap("obstacle velocity");
            }
        }
        if has_obstacles {
            // the obstacle stages run inside the chunk passes: their time summed over the
            // chunks, shared by the threads
            let threads = if parallel { rayon::current_num_threads() as u64 } else { 1 };
            let ns = obstacle_ns.into_inner() / threads.max(1);
            self.obstacles.add_duration(std::time::Duration::from_nanos(ns));
        }
        if fused_mean {
            self.selfcol.mean_parts = parts;
        }
        if sc.is_some() && !check {
            let threads = if parallel { rayon::current_num_threads() as u64 } else { 1 };
            sc_time += std::time::Duration::from_nanos(mean_ns.into_inner() / threads.max(1));
            self.selfcol.stats.time_s += sc_time.as_secs_f64();
            self.selfcol.stats.steps += 1;
        }
        if all_finite.into_inner() {
            Ran::Clean
        } else {
            Ran::NonFinite
        }
    }
}

#[cfg(test)]
mod fusion_tests;
