//! Wall time per stage of the real step.
//!
//! Timing a stage alone, repeated on the same data, would measure it with warm caches: at 1M particles the particle arrays (40 MB) and contact slots (28 MB) partly
//! fit a 32 MB last-level cache when one kernel runs over and over, but not when the whole
//! step, with its 80 MB of constraints, runs between two visits. The sum of such stage times
//! then falls well short of the step time. The clock answers "where does the step's time go"
//! instead: [`World::step`] reads the time at every stage boundary (a lap) and adds the time
//! since the last lap to the stage just finished, so the stages add up to the step's wall time
//! by construction. Off by default; when off a lap is one branch and the step allocates
//! nothing for it.

use std::time::{Duration, Instant};

use crate::world::World;

/// Accumulated wall time per stage over the steps taken while the clock was on.
#[derive(Clone, Debug, Default)]
pub struct StageClock {
    on: bool,
    mark: Option<Instant>,
    stages: Vec<(&'static str, Duration)>,
    steps: u64,
}

impl StageClock {
    /// Starts timing one step (no-op while off).
    #[inline]
    pub(crate) fn start(&mut self) {
        if self.on {
            self.mark = Some(Instant::now());
        }
    }

    /// Adds the time since the previous lap (or [`start`](Self::start)) to `stage`.
    #[inline]
    pub(crate) fn lap(&mut self, stage: &'static str) {
        if let Some(mark) = self.mark.as_mut() {
            let now = Instant::now();
            let d = now - *mark;
            *mark = now;
            match self.stages.iter_mut().find(|(s, _)| *s == stage) {
                Some((_, t)) => *t += d,
                None => self.stages.push((stage, d)),
            }
        }
    }

    /// Ends one step: its last stage is `stage`.
    #[inline]
    pub(crate) fn stop(&mut self, stage: &'static str) {
        if self.mark.is_some() {
            self.lap(stage);
            self.mark = None;
            self.steps += 1;
        }
    }

    /// Whether the clock is on.
    pub fn is_on(&self) -> bool {
        self.on
    }

    /// Steps timed so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Total wall time per stage, in the order the stages first ran.
    pub fn stages(&self) -> &[(&'static str, Duration)] {
        &self.stages
    }

    /// Sum of all stages: the wall time of the timed steps.
    pub fn total(&self) -> Duration {
        self.stages.iter().map(|(_, t)| *t).sum()
    }
}

impl World {
    /// Turns the per-stage clock of [`step`](World::step) on or off; turning it on clears what
    /// it measured before. See [`stage_clock`](crate::world::stage_clock).
    pub fn set_stage_clock(&mut self, on: bool) {
        self.clock = StageClock { on, ..Default::default() };
    }

    /// What the per-stage clock measured since it was turned on.
    pub fn stage_clock(&self) -> &StageClock {
        &self.clock
    }
}

#[cfg(test)]
mod tests {
    use crate::model::shapes::Shape;
    use crate::obstacles::Obstacle;
    use crate::{ClothDesc, Effects, SolverParams, World};

    #[test]
    fn stages_add_up_to_the_step_and_cover_the_obstacle_stages() {
        // one thread: the tethers keep their pass (on the pool they run in the update pass)
        let one = SolverParams {
            threads: 1,
            ..Default::default()
        };
        let mut w = World::new(one, Effects::gravity()).unwrap();
        w.add_cloth(&ClothDesc::default()).unwrap();
        w.add_obstacle(Obstacle::shape(Shape::plane([0.0, -1.0, 0.0], [0.0, 1.0, 0.0]).unwrap()).unwrap())
            .unwrap();
        w.step(1.0 / 60.0).unwrap();
        assert_eq!(w.stage_clock().steps(), 0, "off by default");
        assert!(w.stage_clock().stages().is_empty());
        w.set_stage_clock(true);
        let t0 = std::time::Instant::now();
        for _ in 0..3 {
            w.step(1.0 / 60.0).unwrap();
        }
        let wall = t0.elapsed();
        let c = w.stage_clock();
        assert_eq!(c.steps(), 3);
        assert!(c.total() <= wall && c.total() > wall / 2, "{:?} of {wall:?}", c.total());
        // a shape's contacts run inside predict, its projection and velocity pass inside
        // the update pass (`obstacles::chunkwise`)
        for s in [
            "predict, obstacle contacts",
            "distance constraints",
            "tethers",
            "update, obstacle velocity, next predict",
        ] {
            assert!(c.stages().iter().any(|(n, _)| *n == s), "{s} missing from {:?}", c.stages());
        }
        w.set_stage_clock(false);
        w.step(1.0 / 60.0).unwrap();
        assert_eq!(w.stage_clock().steps(), 0);
    }
}
