//! The paper's "average collision" metric of self-collision (the definition is in
//! [`super`]): the share of particles with a non-neighbour closer than
//! `(1 - PENETRATION_TOLERANCE) d`, measured outside the timed stage.
//!
//! After every step only when the settings ask for it ([`crate::self_collision::SelfCollision::measure`]): on
//! a folded cloth it costs a large share of the step. It reuses the step's broadphase.

use crate::data::exec::Exec;
use rayon::prelude::*;

use crate::error::Result;
use crate::self_collision::{dist2, SelfCollisionData, PENETRATION_TOLERANCE};

impl SelfCollisionData {
    /// Measures the penetration of the state the lists were just built from (once per step
    /// count `steps`, skipping the initial state) when the settings ask for it
    /// ([`crate::self_collision::SelfCollision::measure`]). Kept out of the timed collision stage.
    pub(crate) fn record_start_state(&mut self, x: [&[f32]; 3], n: usize, steps: u64, parallel: bool) {
        let on = self.config.as_ref().is_some_and(|c| c.measure);
        if on && steps > 0 && self.last_measured != Some(steps) {
            let pct = self.penetration_pct(x, n, parallel);
            self.stats.record(pct);
            self.last_measured = Some(steps);
        }
    }

    /// Measures (and records, once per step count) the penetration of the state `x`.
    pub(crate) fn measure(&mut self, x: [&[f32]; 3], n: usize, steps: u64, parallel: bool) -> Result<f64> {
        if self.last_measured == Some(steps) {
            return Ok(self.stats.last_pct);
        }
        if !self.build_lists(x, n, Exec::new(true, parallel))? {
            return Ok(0.0);
        }
        let pct = self.penetration_pct(x, n, parallel);
        self.stats.record(pct);
        self.last_measured = Some(steps);
        Ok(pct)
    }

    /// Fills the metric lists (non-neighbours within the penetration limit) from the
    /// broadphase of the same positions `x` (built here if the step kept older candidates).
    fn probe_lists(&mut self, x: [&[f32]; 3], n: usize, parallel: bool) -> Result<()> {
        // Ready lists mean self-collision is active (the step built them from its settings).
        let Some(a) = self.active() else { return Ok(()) };
        let d = a.d;
        let lim = d * (1.0 - PENETRATION_TOLERANCE);
        let Some(mut st) = self.state.take().filter(|s| s.ready) else {
            return Ok(());
        };
        let broadphase = self.config.as_ref().map(|c| c.broadphase).unwrap_or_default();
        let rest = self.rest_data();
        // Non-neighbours: another cloth, or more than `1.5 d` apart at rest.
        let keep = |i: usize, j: u32| !rest.skipped(i, j as usize, 1.5 * d);
        let exec = Exec::new(true, parallel);
        let fresh = st.fresh;
        let (bp, [_, _, probe]) = st.broadphase(broadphase);
        // The step's broadphase, unless it kept older candidates.
        let built = if fresh { Ok(()) } else { bp.build(x, n, a.q, rest, exec) };
        let ok = built.is_ok();
        let r = built.and_then(|_| bp.partners(x, n, lim, &keep, probe, exec));
        st.fresh = ok;
        self.state = Some(st);
        r
    }

    /// Percentage of particles in penetration in the state the lists were built from.
    fn penetration_pct(&mut self, x: [&[f32]; 3], n: usize, parallel: bool) -> f64 {
        if self.probe_lists(x, n, parallel).is_err() {
            return 0.0;
        }
        let Some(st) = self.state.as_ref().filter(|s| s.ready) else {
            return 0.0;
        };
        let d = self.distance();
        let lim = d * (1.0 - PENETRATION_TOLERANCE);
        let hit = |i: usize| -> bool { st.probe.of(i).iter().any(|&j| dist2(&x, i, j as usize) < lim * lim) };
        let count = if parallel {
            (0..n).into_par_iter().filter(|&i| hit(i)).count()
        } else {
            (0..n).filter(|&i| hit(i)).count()
        };
        if n == 0 {
            0.0
        } else {
            100.0 * count as f64 / n as f64
        }
    }
}
