//! Kinematic (pinned) particles moved by the host each frame.
//!
//! A pinned particle has inverse mass `w = 0`: constraints never move it, gravity skips it, but
//! the predict kernel still carries it along its velocity, `p = x + h v`. Setting a target `t`
//! for the next step of length `dt` therefore means giving the pin the velocity
//! `v = (t - x) / dt`: over the `n` substeps of `h = dt / n` it moves in equal increments,
//! so the cloth is pulled smoothly (a teleport would put the whole displacement into the first
//! substep's constraint error and show as a jerk). At the end of the step the pin is set exactly
//! to `t` (removing the rounding of `n` additions). A pin that is not moved again in the next
//! step gets its velocity set back to zero, so it stays where it was put.

use crate::error::{finite3, Result, WeftError};
use crate::world::World;

impl World {
    /// Moves pinned particle `i` to `p` over the next step (see the module docs).
    ///
    /// Errors if `i` is out of range, `p` is not finite, or the particle is not pinned
    /// (inverse mass > 0; pin it first with [`set_inverse_masses`](World::set_inverse_masses)
    /// or a [`PinSpec`](crate::PinSpec)). Calling it again before the step replaces the target.
    /// If the step fails (e.g. diverges), the target stays pending for the next step.
    pub fn set_pin_position(&mut self, i: usize, p: mint::Point3<f32>) -> Result<()> {
        let t = self.check_pin(i, p)?;
        self.embed.pending.push((i as u32, t));
        Ok(())
    }

    /// Batch form of [`set_pin_position`](World::set_pin_position): `indices[k]` moves to
    /// `positions[k]`. Checks everything first; on error nothing is changed.
    pub fn set_kinematic_positions(&mut self, indices: &[u32], positions: &[mint::Point3<f32>]) -> Result<()> {
        if positions.len() != indices.len() {
            return Err(WeftError::BufferLength {
                name: "kinematic positions",
                got: positions.len(),
                expected: indices.len(),
            });
        }
        for (&i, &p) in indices.iter().zip(positions) {
            self.check_pin(i as usize, p)?;
        }
        for (&i, &p) in indices.iter().zip(positions) {
            self.embed.pending.push((i, [p.x, p.y, p.z]));
        }
        Ok(())
    }

    /// Number of kinematic targets waiting for the next step.
    pub fn pending_kinematic_count(&self) -> usize {
        self.embed.pending.len()
    }

    fn check_pin(&self, i: usize, p: mint::Point3<f32>) -> Result<[f32; 3]> {
        let n = self.particles.count();
        if i >= n {
            return Err(WeftError::IndexOutOfRange {
                name: "particle",
                index: i,
                len: n,
            });
        }
        let t = finite3("pin position", [p.x, p.y, p.z])?;
        if self.particles.w[i] != 0.0 {
            return Err(WeftError::param(
                "pin particle",
                i,
                "is not pinned (inverse mass > 0): only pinned particles can be moved kinematically",
            ));
        }
        Ok(t)
    }

    /// Start of a step: stop last step's kinematic motion, give this step's targets their
    /// velocity `(t - x) / dt`; remember the initial state on the very first step.
    pub(crate) fn begin_kinematic(&mut self, dt: f32) {
        if self.embed.initial.is_none() {
            self.embed.initial = Some(Box::new(self.snapshot()));
        }
        let p = &mut self.particles;
        for &i in &self.embed.moving {
            let i = i as usize;
            (p.vx[i], p.vy[i], p.vz[i]) = (0.0, 0.0, 0.0);
        }
        self.embed.moving.clear();
        for &(i, t) in &self.embed.pending {
            let i = i as usize;
            p.vx[i] = (t[0] - p.x[i]) / dt;
            p.vy[i] = (t[1] - p.y[i]) / dt;
            p.vz[i] = (t[2] - p.z[i]) / dt;
        }
    }

    /// End of a successful step: put each moved pin exactly on its target.
    pub(crate) fn finish_kinematic(&mut self) {
        let p = &mut self.particles;
        for &(i, t) in &self.embed.pending {
            let i = i as usize;
            (p.x[i], p.y[i], p.z[i]) = (t[0], t[1], t[2]);
            (p.px[i], p.py[i], p.pz[i]) = (t[0], t[1], t[2]);
            self.embed.moving.push(i as u32);
        }
        self.embed.pending.clear();
    }
}

#[cfg(test)]
mod tests {
    use crate::{ClothDesc, Effects, PinSpec, SolverParams, World};

    fn world() -> World {
        let mut w = World::new(SolverParams::default(), Effects::gravity()).unwrap();
        w.add_cloth(&ClothDesc {
            rows: 6,
            cols: 5,
            spacing: 0.1,
            pins: vec![PinSpec::FirstRowCorners],
            ..Default::default()
        })
        .unwrap();
        w
    }

    #[test]
    fn pin_lands_on_target_with_implied_velocity_then_stops() {
        let mut w = world();
        let x0 = w.position(0).unwrap();
        let dt = w.params().dt;
        let t = mint::Point3 {
            x: x0.x + 0.06,
            y: x0.y + 0.03,
            z: x0.z,
        };
        w.set_pin_position(0, t).unwrap();
        assert_eq!(w.pending_kinematic_count(), 1);
        w.step(dt).unwrap();
        assert_eq!(w.position(0).unwrap(), t);
        let v = w.velocities();
        assert!((v[0][0] - 0.06 / dt).abs() < 1e-3 * (0.06 / dt), "{}", v[0][0]);
        assert!((v[1][0] - 0.03 / dt).abs() < 1e-3 * (0.03 / dt), "{}", v[1][0]);
        // Not moved again: it stays and its velocity is zero.
        w.step(dt).unwrap();
        assert_eq!(w.position(0).unwrap(), t);
        assert_eq!([w.velocities()[0][0], w.velocities()[1][0]], [0.0, 0.0]);
    }

    #[test]
    fn bad_pins_are_errors_and_change_nothing() {
        let mut w = world();
        let p = mint::Point3 { x: 0.0, y: 0.0, z: 0.0 };
        assert!(w.set_pin_position(7, p).is_err(), "particle 7 is free");
        assert!(w.set_pin_position(1000, p).is_err());
        assert!(w
            .set_pin_position(
                0,
                mint::Point3 {
                    x: f32::NAN,
                    y: 0.0,
                    z: 0.0
                }
            )
            .is_err());
        assert!(w.set_kinematic_positions(&[0, 4], &[p]).is_err());
        assert!(w.set_kinematic_positions(&[0, 7], &[p, p]).is_err());
        assert_eq!(w.pending_kinematic_count(), 0);
        w.set_kinematic_positions(&[0, 4], &[p, p]).unwrap();
        assert_eq!(w.pending_kinematic_count(), 2);
    }
}
