//! Obstacles and self-collision for the force-based methods.
//!
//! The force-based methods (symplectic Euler, leapfrog, implicit Euler) end their substep with a
//! drift `x_{n+1} = x_n + h v`. When the world has obstacles, self-collision or strands with
//! scalps, that drift writes
//! the prediction `p = x_n + h v` instead of `x`, and the collision stages of the XPBD step
//! (`src/world/step/`) run on it exactly as they do after XPBD's constraint sweeps:
//!
//! ```text
//! obstacle contacts of x -> p, back along the path     [obstacles]         (if any)
//! speed clamp relative to the mean velocity            [self-collision]     (if on)
//! obstacle projection                                  [obstacles]         (if any)
//! strands pushed out of their scalps                   [strands::scalp]     (if any)
//! pair pass, velocity correction                       [self-collision]     (if on)
//! update: v += (p - p_drift) / h;  x = p                [integrate/contacts]
//! obstacle velocity pass: normal part, friction        [obstacles]         (if any)
//! ```
//!
//! The velocity changes only by what the collision stages moved the prediction: the position
//! correction becomes a velocity change, as in position-based dynamics (Müller et al. 2006,
//! section 3.5; the obstacle stages follow Landovskaya, Landovsky & Frolovsky). XPBD's update `v = (p - x) / h`
//! would be the same in exact arithmetic, but not in f32 at small substeps: when `h v` is below
//! half an ulp of `x` the drift rounds back to `x`, and recomputing `v` from positions would
//! zero the velocity every substep, so a cloth at rest would never start to fall (measured: at
//! 512 substeps of 1/60 s a dropped sheet stayed put). Keeping `v` lets it grow until the drift
//! registers, as the force-based step does without contacts. Drag and damping were already
//! applied by the method's kick, so the update applies none. Leapfrog runs the stages after its drift, before the closing half
//! kick, so the closing force is evaluated at the corrected positions. A world with neither
//! obstacles nor self-collision takes none of this path and steps bit for bit as before.

use crate::data::exec::Exec;
use crate::self_collision::Active;
use crate::world::World;

/// What the force-based substeps of one step need for contacts.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Contacts {
    /// The world has obstacles.
    obstacles: bool,
    /// Self-collision is on for this step.
    selfcol: Option<Active>,
    /// The world has strands with scalps.
    scalps: bool,
}

impl Contacts {
    /// Whether any collision stage runs: the drift must then write `p`, not `x`.
    pub(crate) fn any(&self) -> bool {
        self.obstacles || self.selfcol.is_some() || self.scalps
    }
}

impl World {
    /// Start of a step of `dt`: places the obstacles' particle data, sets the self-collision
    /// travel from `v` and builds its pair lists from `x` (as the XPBD step does).
    pub(crate) fn begin_force_contacts(&mut self, dt: f32, parallel: bool) -> Contacts {
        let n = self.particles.count();
        let obstacles = !self.obstacles.is_empty();
        if obstacles {
            self.obstacles.prepare(&self.particles, &self.cloths, &self.strands);
        }
        let selfcol = self.begin_self_collision(dt, self.exec());
        if selfcol.is_some() {
            let p = &self.particles;
            let steps = self.steps;
            self.selfcol.record_start_state([&p.x, &p.y, &p.z], n, steps, parallel);
        }
        Contacts {
            obstacles,
            selfcol,
            scalps: !self.scalps.is_empty(),
        }
    }

    /// The collision stages of substep `s` (length `h`) on the prediction `p`, then
    /// `v = (p - x) / h`, `x = p` and the obstacle velocity pass (module docs).
    pub(crate) fn force_contact_stages(&mut self, c: Contacts, s: u32, h: f32, exec: Exec) {
        let n_sub = self.params.substeps;
        let n = self.particles.count();
        {
            let p = &self.particles;
            for (dst, src) in self.ms.predicted.iter_mut().zip([&p.px, &p.py, &p.pz]) {
                dst.clear();
                dst.extend_from_slice(&src[..n]);
            }
        }
        if c.obstacles {
            self.obstacle_contacts_stage(s, h, exec);
        }
        if let Some(a) = c.selfcol {
            {
                let p = &self.particles;
                for (dst, src) in self.ms.before_clamp.iter_mut().zip([&p.vx, &p.vy, &p.vz]) {
                    dst.clear();
                    dst.extend_from_slice(&src[..n]);
                }
            }
            self.self_collision_clamp(a, n_sub, h, exec, None);
            self.rebase_clamped_predictions(n);
        }
        if c.obstacles {
            self.obstacle_projection_stage(exec);
        }
        if c.scalps {
            self.scalp_stage(exec);
        }
        if let Some(a) = c.selfcol {
            self.self_collision_pairs_pass(a, h, exec);
        }
        let inv_h = 1.0 / h;
        let p = &mut self.particles;
        let [qx, qy, qz] = &self.ms.predicted;
        for i in 0..n {
            p.vx[i] += (p.px[i] - qx[i]) * inv_h;
            p.vy[i] += (p.py[i] - qy[i]) * inv_h;
            p.vz[i] += (p.pz[i] - qz[i]) * inv_h;
            (p.x[i], p.y[i], p.z[i]) = (p.px[i], p.py[i], p.pz[i]);
        }
        if c.obstacles {
            self.obstacle_velocity_stage(exec);
        }
    }
}

impl World {
    /// The speed clamp sets a fast particle's velocity to `v_c` and its prediction to
    /// `p = x + h v_c` itself. The update adds `(p - p_drift) / h` to `v`, which must then count
    /// only what later stages move `p`: for every particle whose velocity the clamp changed, the
    /// drift prediction is replaced by the clamped one. Without this the clamp was counted
    /// twice, `v <- 2 v_c - v`: a fast particle was reflected instead of slowed (found by the
    /// accuracy report's bounded blow-ups of explicit methods on the fold).
    fn rebase_clamped_predictions(&mut self, n: usize) {
        let p = &self.particles;
        let [bx, by, bz] = &self.ms.before_clamp;
        let [qx, qy, qz] = &mut self.ms.predicted;
        for i in 0..n {
            let changed =
                p.vx[i].to_bits() != bx[i].to_bits() || p.vy[i].to_bits() != by[i].to_bits() || p.vz[i].to_bits() != bz[i].to_bits();
            if changed {
                (qx[i], qy[i], qz[i]) = (p.px[i], p.py[i], p.pz[i]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::model::shapes::Shape;
    use crate::obstacles::Obstacle;
    use crate::{ClothDesc, Effects, Fabric, Method, SolverParams, World};

    /// Penetration allowed at the end of a step, m (the obstacle stages leave particles the
    /// thickness off the surface; this is rounding).
    const TOL: f32 = 1e-4;

    const CENTER: [f32; 3] = [0.0, 0.3, 0.0];
    const RADIUS: f32 = 0.15;

    /// A soft 12 x 12 sheet (k = 1e4 N/m stretch) dropped from 5 cm above a ball.
    fn drape(method: Method, substeps: u32, ball: bool) -> World {
        drape_on(method, substeps, ball, 0)
    }

    /// [`drape`] on `threads` threads (0: the global pool).
    fn drape_on(method: Method, substeps: u32, ball: bool, threads: usize) -> World {
        let fabric = Fabric {
            stretch_compliance: 1e-4,
            shear_compliance: 1e-3,
            bend_compliance: 1e-2,
            ..Fabric::preset("cotton").unwrap()
        };
        let desc = ClothDesc {
            rows: 12,
            cols: 12,
            spacing: 0.03,
            origin: [-0.165, CENTER[1] + RADIUS + 0.05, -0.165],
            u: [1.0, 0.0, 0.0],
            v: [0.0, 0.0, 1.0],
            fabric,
            pins: vec![],
            tethers: None,
            ..Default::default()
        };
        let params = SolverParams {
            dt: 1.0 / 60.0,
            substeps,
            method,
            threads,
            ..Default::default()
        };
        let mut w = World::new(params, Effects::gravity()).unwrap();
        w.add_cloth(&desc).unwrap();
        if ball {
            let sphere = Shape::Sphere {
                center: CENTER,
                radius: RADIUS,
            };
            w.add_obstacle(Obstacle::shape(sphere).unwrap()).unwrap();
        }
        w
    }

    /// Lowest particle height, m.
    fn lowest(w: &World) -> f32 {
        w.positions()[1].iter().copied().fold(f32::MAX, f32::min)
    }

    #[test]
    fn force_based_drape_on_a_sphere_stays_outside() {
        for (method, substeps) in [(Method::SymplecticEuler, 64), (Method::Leapfrog, 64), (Method::ImplicitEuler, 4)] {
            let mut with = drape(method, substeps, true);
            let mut without = drape(method, substeps, false);
            let mut worst = 0.0f32;
            for _ in 0..60 {
                with.step(1.0 / 60.0).unwrap();
                without.step(1.0 / 60.0).unwrap();
                worst = worst.max(with.max_penetration());
            }
            assert!(worst <= TOL, "{method:?}: penetration {worst} m");
            // Without the ball the sheet falls through where the ball is; with it, the centre
            // rests on top (thickness above the surface) and the edges hang down its sides.
            assert!(lowest(&without) < CENTER[1] - RADIUS, "{method:?}: the sheet did fall");
            let [x, y, z] = with.positions();
            let k = 6 * 12 + 6;
            let gap = ((x[k] - CENTER[0]).powi(2) + (y[k] - CENTER[1]).powi(2) + (z[k] - CENTER[2]).powi(2)).sqrt() - RADIUS;
            assert!(gap > -TOL && gap < 0.01, "{method:?}: centre {gap} m off the surface");
            let top = CENTER[1] + RADIUS;
            assert!(lowest(&with) < top - 0.05, "{method:?}: edges drape, lowest {}", lowest(&with));
        }
    }

    /// The speed clamp limits a fast particle; it must not reflect it. Two 4 x 4 soft sheets
    /// 2 cm apart at rest in zero gravity, one corner thrown at 10 m/s along x, one step of symplectic Euler
    /// with self-collision on (d = 1 cm, so the clamp allows 0.6 m/s relative to the mean
    /// velocity at 1/60 s). Counting the clamp twice gave `2 v_c - v`, about -8.8 m/s.
    #[test]
    fn the_speed_clamp_slows_a_fast_particle_instead_of_reflecting_it() {
        use crate::model::self_collision::SelfCollision;
        for method in [Method::SymplecticEuler, Method::Leapfrog, Method::ImplicitEuler] {
            let fabric = Fabric {
                stretch_compliance: 1e3,
                shear_compliance: 1e3,
                bend_compliance: 1e3,
                ..Fabric::preset("cotton").unwrap()
            };
            let desc = ClothDesc {
                rows: 4,
                cols: 4,
                spacing: 0.1,
                fabric,
                pins: vec![],
                ..Default::default()
            };
            let params = SolverParams {
                dt: 1.0 / 60.0,
                substeps: 1,
                method,
                ..Default::default()
            };
            let mut w = World::new(params, Effects::default()).unwrap();
            w.add_cloth(&desc).unwrap();
            // A second sheet 2 cm above, so every particle has candidate partners (within 3d).
            w.add_cloth(&ClothDesc {
                origin: [0.0, 0.02, 0.0],
                ..desc.clone()
            })
            .unwrap();
            let sc = SelfCollision {
                distance: Some(0.01),
                ..Default::default()
            };
            w.set_self_collision(Some(sc)).unwrap();
            let n = w.particle_count();
            let mut vx = vec![0.0f32; n];
            vx[0] = 10.0;
            let zero = vec![0.0f32; n];
            w.set_velocities([&vx, &zero, &zero]).unwrap();
            w.step(1.0 / 60.0).unwrap();
            let v = w.velocities()[0][0];
            // Mean 10/32 m/s plus the 0.6 m/s limit; the soft springs add well under 0.1 m/s.
            let clamped = 10.0 / 32.0 + 0.6;
            assert!(
                v > 0.0 && (v - clamped).abs() < 0.1,
                "{method:?}: v = {v} m/s, expected about {clamped}"
            );
        }
    }

    #[test]
    fn force_based_contacts_do_not_depend_on_the_thread_count() {
        for method in [Method::SymplecticEuler, Method::Leapfrog, Method::ImplicitEuler] {
            let run = |threads| {
                let mut w = drape_on(method, 64, true, threads);
                for _ in 0..20 {
                    w.step(1.0 / 60.0).unwrap();
                }
                let [x, y, z] = w.positions();
                x.iter().chain(y).chain(z).map(|v| v.to_bits()).collect::<Vec<_>>()
            };
            assert_eq!(run(1), run(2), "{method:?}");
        }
    }
}
