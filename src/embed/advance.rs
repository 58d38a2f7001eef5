//! Frame-rate independence: fixed steps from an accumulator.
//!
//! A host calls [`World::advance`] once per rendered frame with the frame's wall-clock length.
//! The time is added to an accumulator `A` (f64), and whole steps of the fixed length
//! `dt = params.dt` are taken while `A >= dt`, each subtracting `dt`. Every step therefore has
//! the same `dt` whatever the frame times were, so the physics after `k` steps is the same bits
//! for 60 even frames or 60 ragged ones; only *when* a step happens moves. (A step within
//! [`STEP_SLACK`] of being owed is taken, so rounding between an f64 frame time and the f32
//! `dt` does not skip a frame.) What is left, `alpha = A / dt` in `[0, 1)`, tells how far the
//! display time has gone past the last step, and [`World::interpolated_positions`] blends the
//! last two states by it.
//!
//! Spiral of death: if steps take longer than the frames they simulate, the debt grows
//! without bound. A call takes at most `max_steps_per_advance` steps (default
//! [`DEFAULT_MAX_STEPS_PER_ADVANCE`](super::DEFAULT_MAX_STEPS_PER_ADVANCE)); the whole steps
//! beyond the cap are dropped from the accumulator (the simulation runs slower than real time
//! for that frame) and the report says so.

use crate::error::{Result, WeftError};
use crate::world::World;

/// Fraction of a step by which the accumulator may fall short and still owe that step.
pub const STEP_SLACK: f64 = 1e-6;

/// What one [`World::advance`] call did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdvanceReport {
    /// Fixed steps taken.
    pub steps: u32,
    /// Whether the cap on steps per call was reached.
    pub capped: bool,
    /// Simulated time dropped because of the cap, s (0 if not capped).
    pub dropped_time: f64,
    /// Accumulator left over as a fraction of `dt`, in `[0, 1)`: the blend factor for
    /// [`World::interpolated_positions`].
    pub alpha: f32,
}

impl World {
    /// Adds `frame_dt` seconds of display time and takes the whole fixed steps of
    /// `params.dt` it owes (see the module docs). `frame_dt` must be finite and `>= 0`.
    ///
    /// If a step fails (e.g. [`WeftError::Diverged`]), the error is returned at once; the steps
    /// before it stand and the accumulator still holds the time not yet simulated.
    pub fn advance(&mut self, frame_dt: f64) -> Result<AdvanceReport> {
        self.advance_with(frame_dt, |_| Ok(()))
    }

    /// [`advance`](World::advance) that calls `before_step` before every fixed step, so inputs
    /// that should follow simulated time (kinematic pins, wind changes) are set per step, not
    /// per frame: then the whole run is independent of the frame times. An error from
    /// `before_step` stops the call and is returned.
    pub fn advance_with(&mut self, frame_dt: f64, mut before_step: impl FnMut(&mut World) -> Result<()>) -> Result<AdvanceReport> {
        if !(frame_dt.is_finite() && frame_dt >= 0.0) {
            return Err(WeftError::param("frame_dt", frame_dt, "must be a finite number, zero or greater"));
        }
        let dt = self.params.dt;
        let dt64 = dt as f64;
        self.embed.accumulator += frame_dt;
        // A millionth of a step of slack: 60 Hz frames (1/60 in f64) with dt = 1/60 in f32
        // (larger by 7e-10 s) take one step each instead of none on the first frame.
        let owed = (self.embed.accumulator / dt64 + STEP_SLACK).floor();
        let cap = self.embed.max_steps;
        let (n, capped) = if owed > cap as f64 { (cap, true) } else { (owed as u32, false) };
        let mut dropped_time = 0.0;
        if capped {
            let drop = owed - cap as f64;
            dropped_time = drop * dt64;
            self.embed.accumulator -= dropped_time;
        }
        for k in 0..n {
            before_step(self)?;
            if k + 1 == n {
                self.save_previous_positions();
            }
            self.step(dt)?;
            self.embed.accumulator -= dt64;
        }
        // Rounding can leave the accumulator a hair outside [0, dt).
        self.embed.accumulator = self.embed.accumulator.max(0.0);
        let alpha = ((self.embed.accumulator / dt64) as f32).clamp(0.0, 1.0);
        Ok(AdvanceReport {
            steps: n,
            capped,
            dropped_time,
            alpha,
        })
    }

    /// Sets the most fixed steps one [`advance`](World::advance) call may take (at least 1).
    pub fn set_max_steps_per_advance(&mut self, max: u32) -> Result<()> {
        if max == 0 {
            return Err(WeftError::param("max_steps_per_advance", max, "must be at least 1"));
        }
        self.embed.max_steps = max;
        Ok(())
    }

    /// The time owed by [`advance`](World::advance) that no step has simulated yet, s.
    pub fn accumulated_time(&self) -> f64 {
        self.embed.accumulator
    }

    fn save_previous_positions(&mut self) {
        let n = self.particles.count();
        let p = &self.particles;
        for (dst, src) in self.embed.prev.iter_mut().zip([&p.x, &p.y, &p.z]) {
            dst.clear();
            dst.extend_from_slice(&src[..n]);
        }
        self.embed.prev_steps = Some(self.steps);
    }
}

#[cfg(test)]
mod tests {
    use crate::{ClothDesc, Effects, SolverParams, World};

    fn world() -> World {
        let params = SolverParams {
            dt: 0.01,
            substeps: 2,
            ..Default::default()
        };
        let mut w = World::new(params, Effects::gravity()).unwrap();
        w.add_cloth(&ClothDesc {
            rows: 5,
            cols: 5,
            ..Default::default()
        })
        .unwrap();
        w
    }

    #[test]
    fn cap_drops_whole_steps_and_reports_it() {
        let mut w = world();
        w.set_max_steps_per_advance(3).unwrap();
        let r = w.advance(0.1049).unwrap();
        assert_eq!(r.steps, 3);
        assert!(r.capped);
        assert!((r.dropped_time - 0.07).abs() < 1e-6, "{}", r.dropped_time);
        assert!((w.accumulated_time() - 0.0049).abs() < 1e-6);
        assert!((r.alpha - 0.49).abs() < 1e-4, "{}", r.alpha);
        assert_eq!(w.steps(), 3);
        let r = w.advance(0.0).unwrap();
        assert_eq!((r.steps, r.capped), (0, false));
    }

    #[test]
    fn sixty_hertz_frames_take_one_step_each() {
        let params = SolverParams {
            dt: 1.0 / 60.0,
            substeps: 1,
            ..Default::default()
        };
        let mut w = World::new(params, Effects::gravity()).unwrap();
        w.add_cloth(&ClothDesc::default()).unwrap();
        for _ in 0..100 {
            assert_eq!(w.advance(1.0 / 60.0).unwrap().steps, 1);
        }
    }

    #[test]
    fn bad_frame_times_are_errors() {
        let mut w = world();
        assert!(w.advance(-0.01).is_err());
        assert!(w.advance(f64::NAN).is_err());
        assert!(w.advance(f64::INFINITY).is_err());
        assert!(w.set_max_steps_per_advance(0).is_err());
        assert_eq!(w.steps(), 0);
    }

    #[test]
    fn interpolation_spans_the_last_step() {
        let mut w = world();
        let n = w.particle_count();
        w.advance(0.025).unwrap(); // two steps, 0.005 left
        let mut prev = vec![[0.0f32; 3]; n];
        let mut cur = vec![[0.0f32; 3]; n];
        let mut half = vec![[0.0f32; 3]; n];
        w.interpolated_positions(0.0, &mut prev[..]).unwrap();
        w.interpolated_positions(1.0, &mut cur[..]).unwrap();
        w.interpolated_positions(0.5, &mut half[..]).unwrap();
        let mut now = vec![[0.0f32; 3]; n];
        w.read_positions(&mut now[..]).unwrap();
        assert_eq!(cur, now);
        assert_ne!(prev, now, "the cloth fell during the last step");
        for i in 0..n {
            for k in 0..3 {
                let lo = prev[i][k].min(now[i][k]);
                let hi = prev[i][k].max(now[i][k]);
                assert!(half[i][k] >= lo && half[i][k] <= hi);
            }
        }
        // A direct step makes the saved state stale: interpolation gives current positions.
        w.step(0.01).unwrap();
        w.interpolated_positions(0.0, &mut prev[..]).unwrap();
        w.read_positions(&mut now[..]).unwrap();
        assert_eq!(prev, now);
    }
}
