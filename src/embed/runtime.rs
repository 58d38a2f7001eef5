//! Run-time changes without a jerk: stiffness in place, snapshots, rollback and reset.
//!
//! XPBD makes changing a compliance mid-run safe: the Lagrange multipliers restart at zero every
//! substep, so a new compliance `α` acts from the next substep on through
//! `Δλ = (-C - α̃ λ) / (w_a + w_b + α̃)` with `α̃ = α / h²` and stores no history that could
//! jump (Macklin et al. 2016, "XPBD", eq. 18). [`World::set_cloth_compliance`] rewrites the
//! compliance of a cloth's constraints where they sit in the coloured arrays: the colouring,
//! the order and the padding do not change. Iteration and substep counts change through
//! [`World::set_params`] the same way (they are global to the solver, not per cloth).
//!
//! A [`Snapshot`] is the evolving state (positions, velocities, inverse masses, time, steps,
//! pending kinematic targets and the [`advance`](World::advance) accumulator), built on the
//! checkpoint machinery ([`crate::world::checkpoint`]); restoring it onto a world of the same topology
//! continues bit for bit as if the steps since had never happened.

use crate::error::{non_negative, Result, WeftError};
use crate::world::checkpoint::Checkpoint;
use crate::world::World;

/// A copy of a world's evolving state (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    state: Checkpoint,
    inv_mass: Vec<f32>,
    accumulator: f64,
    pending: Vec<(u32, [f32; 3])>,
    moving: Vec<u32>,
}

impl Snapshot {
    /// Number of particles the snapshot holds.
    pub fn particle_count(&self) -> usize {
        self.inv_mass.len()
    }

    /// Steps the world had taken.
    pub fn steps(&self) -> u64 {
        self.state.steps
    }
}

/// Which kind of grid constraint joins local grid cells `a` and `b` of a `cols`-wide cloth:
/// 0 stretch, 1 shear, 2 bend (see [`crate::model::cloth`] for the layout).
fn grid_kind(a: u32, b: u32, cols: u32) -> Option<usize> {
    let (ra, ca) = ((a / cols) as i64, (a % cols) as i64);
    let (rb, cb) = ((b / cols) as i64, (b % cols) as i64);
    match ((ra - rb).abs(), (ca - cb).abs()) {
        (0, 1) | (1, 0) => Some(0),
        (1, 1) => Some(1),
        (0, 2) | (2, 0) => Some(2),
        _ => None,
    }
}

impl World {
    /// Sets the XPBD compliance (m/N, 0 = rigid) of cloth `cloth`'s stretch, shear and bending
    /// constraints from the next substep on, in place: no re-colouring, no allocation.
    pub fn set_cloth_compliance(&mut self, cloth: usize, stretch: f32, shear: f32, bend: f32) -> Result<()> {
        let info = self.cloths.get(cloth).ok_or(WeftError::IndexOutOfRange {
            name: "cloth",
            index: cloth,
            len: self.cloths.len(),
        })?;
        let values = [
            non_negative("stretch compliance", stretch)?,
            non_negative("shear compliance", shear)?,
            non_negative("bend compliance", bend)?,
        ];
        let (first, end, cols) = (info.first, info.first + info.rows * info.cols, info.cols);
        let kind = |a: u32, b: u32| -> Option<usize> {
            let inside = (first..end).contains(&a) && (first..end).contains(&b);
            inside.then(|| grid_kind(a - first, b - first, cols)).flatten()
        };
        for col in &mut self.distance.colours {
            for k in 0..col.real {
                if let Some(t) = kind(col.a[k], col.b[k]) {
                    col.compliance[k] = values[t];
                }
            }
        }
        for c in &mut self.distance_inputs {
            if let Some(t) = kind(c.a, c.b) {
                c.compliance = values[t];
            }
        }
        self.distance.refresh_grids();
        Ok(())
    }

    /// A copy of the evolving state, to [`restore_snapshot`](World::restore_snapshot) later.
    pub fn snapshot(&self) -> Snapshot {
        let n = self.particles.count();
        Snapshot {
            state: self.checkpoint(""),
            inv_mass: self.particles.w[..n].to_vec(),
            accumulator: self.embed.accumulator,
            pending: self.embed.pending.clone(),
            moving: self.embed.moving.clone(),
        }
    }

    /// Puts the world back into the state of `s`, taken from this world (or one with the same
    /// particle count). Errors, changing nothing, if the particle counts differ.
    pub fn restore_snapshot(&mut self, s: &Snapshot) -> Result<()> {
        let n = self.particles.count();
        if s.inv_mass.len() != n {
            return Err(WeftError::BufferLength {
                name: "snapshot particles",
                got: s.inv_mass.len(),
                expected: n,
            });
        }
        self.restore(&s.state)?;
        self.particles.w[..n].copy_from_slice(&s.inv_mass);
        self.damp_h = f32::NAN;
        self.embed.accumulator = s.accumulator;
        self.embed.pending.clone_from(&s.pending);
        self.embed.moving.clone_from(&s.moving);
        self.embed.prev_steps = None;
        Ok(())
    }

    /// Back to the state before the first step since the last topology change (the last
    /// [`add_cloth`](World::add_cloth)); does nothing if no step has been taken since.
    pub fn reset(&mut self) -> Result<()> {
        if let Some(init) = self.embed.initial.take() {
            let r = self.restore_snapshot(&init);
            self.embed.initial = Some(init);
            r?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ClothDesc, Effects, Fabric, PinSpec, SolverParams};

    fn desc(fabric: Fabric) -> ClothDesc {
        ClothDesc {
            rows: 9,
            cols: 7,
            spacing: 0.05,
            fabric,
            pins: vec![PinSpec::FirstRowCorners],
            ..Default::default()
        }
    }

    fn world(fabric: Fabric) -> World {
        let mut w = World::new(SolverParams::default(), Effects::gravity()).unwrap();
        w.add_cloth(&desc(fabric)).unwrap();
        w
    }

    #[test]
    fn compliance_change_equals_a_world_built_with_it() {
        let soft = Fabric::preset("wool").unwrap();
        let stiff = Fabric {
            stretch_compliance: 0.0,
            shear_compliance: 1e-5,
            bend_compliance: 3e-3,
            ..soft.clone()
        };
        let mut a = world(soft);
        for _ in 0..10 {
            a.step(1.0 / 60.0).unwrap();
        }
        let mut b = world(stiff.clone());
        b.restore_snapshot(&a.snapshot()).unwrap();
        a.set_cloth_compliance(0, stiff.stretch_compliance, stiff.shear_compliance, stiff.bend_compliance)
            .unwrap();
        let layout = |w: &World| -> Vec<_> {
            w.distance_set()
                .colours
                .iter()
                .map(|c| (c.a.clone(), c.b.clone(), c.rest.clone(), c.compliance.clone()))
                .collect()
        };
        assert!(layout(&a) == layout(&b), "same colours, same order, new compliances");
        for _ in 0..10 {
            a.step(1.0 / 60.0).unwrap();
            b.step(1.0 / 60.0).unwrap();
        }
        assert_eq!(a.state_bits(), b.state_bits());
        assert!(a.set_cloth_compliance(1, 0.0, 0.0, 0.0).is_err());
        assert!(a.set_cloth_compliance(0, -1.0, 0.0, 0.0).is_err());
        assert!(a.set_cloth_compliance(0, 0.0, f32::NAN, 0.0).is_err());
    }

    #[test]
    fn rollback_and_reset_replay_bitwise() {
        let mut w = world(Fabric::default());
        let start = w.state_bits();
        for _ in 0..5 {
            w.step(1.0 / 60.0).unwrap();
        }
        let snap = w.snapshot();
        for _ in 0..7 {
            w.step(1.0 / 60.0).unwrap();
        }
        let after = w.state_bits();
        w.restore_snapshot(&snap).unwrap();
        assert_eq!(w.steps(), 5);
        for _ in 0..7 {
            w.step(1.0 / 60.0).unwrap();
        }
        assert_eq!(w.state_bits(), after);
        w.reset().unwrap();
        assert_eq!(w.state_bits(), start);
        assert_eq!((w.steps(), w.time()), (0, 0.0));
        let mut other = World::new(SolverParams::default(), Effects::gravity()).unwrap();
        assert!(other.restore_snapshot(&snap).is_err());
        other.reset().unwrap();
    }
}
