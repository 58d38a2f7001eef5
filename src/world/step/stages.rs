//! The stages of a substep as the world runs them: each picks the world's arrays apart and
//! calls its kernel. The XPBD step (`step.rs`) and the force-based step (`contacts.rs`) both
//! call these, each in its own order (the force-based methods have no constraint sweeps).

use crate::data::exec::Exec;
use crate::self_collision::clamp::{clamp_speed, ClampParams};
use crate::self_collision::mean::mean_velocity_in;
use crate::self_collision::Active;
use crate::world::World;

impl World {
    /// Obstacle contacts of the path `x -> p` over substep `s` of length `h`, and the response
    /// back along the path (stage 1 and 2 of the obstacle step).
    pub(crate) fn obstacle_contacts_stage(&mut self, s: u32, h: f32, exec: Exec) {
        let t0 = std::time::Instant::now();
        let t_end = self.time + ((s + 1) as f64) * (h as f64);
        self.obstacles.generate(&self.particles, t_end, h, exec);
        self.obstacles.resolve(&mut self.particles, h, exec);
        self.obstacles.add_busy(t0);
    }

    /// Projection of the predictions out of the obstacles (after each constraint sweep).
    pub(crate) fn obstacle_projection_stage(&mut self, exec: Exec) {
        let t0 = std::time::Instant::now();
        self.obstacles.project(&mut self.particles, exec);
        self.obstacles.add_busy(t0);
    }

    /// The obstacle velocity pass on its own (the fast XPBD path runs it inside the update).
    pub(crate) fn obstacle_velocity_stage(&mut self, exec: Exec) {
        let t0 = std::time::Instant::now();
        self.obstacles.velocity_pass(&mut self.particles, exec);
        self.obstacles.add_busy(t0);
    }

    /// One sweep of the distance constraints, colour by colour.
    pub(crate) fn distance_stage(&mut self, inv_h2: f32, exec: Exec) {
        let p = &mut self.particles;
        if exec.simd() {
            self.distance
                .solve_simd(&mut p.px, &mut p.py, &mut p.pz, &p.w, inv_h2, exec.parallel());
        } else {
            self.distance.solve_scalar(&mut p.px, &mut p.py, &mut p.pz, &p.w, inv_h2);
        }
    }

    /// One sweep of the tethers.
    pub(crate) fn tether_stage(&mut self, exec: Exec) {
        let p = &mut self.particles;
        if exec.simd() {
            self.tethers.solve_simd(&mut p.px, &mut p.py, &mut p.pz, exec.parallel());
        } else {
            self.tethers.solve_scalar(&mut p.px, &mut p.py, &mut p.pz);
        }
    }

    /// Strand points pushed out of their scalps.
    pub(crate) fn scalp_stage(&mut self, exec: Exec) {
        let p = &mut self.particles;
        if exec.parallel() {
            self.scalps.solve(&mut p.px, &mut p.py, &mut p.pz, &p.w);
        } else {
            self.scalps.solve_scalar(&mut p.px, &mut p.py, &mut p.pz, &p.w);
        }
    }
    /// The self-collision speed clamp (relative to the mean velocity, at most
    /// `travel d / substeps` per substep), then the predictions kept as box centres.
    /// `mean` is the mean velocity when the predict pass summed it already.
    pub(crate) fn self_collision_clamp(&mut self, a: Active, n_sub: u32, h: f32, exec: Exec, mean: Option<[f32; 3]>) {
        let (parallel, simd) = (exec.parallel(), exec.simd());
        let n = self.particles.count();
        let p = &self.particles;
        let parts = &mut self.selfcol.mean_parts;
        let mean = mean.unwrap_or_else(|| mean_velocity_in(parts, [&p.vx, &p.vy, &p.vz], &p.w, n, exec));
        // Each particle's travel (the step set them; padding and unset ones the step's).
        let mut travel = std::mem::take(&mut self.selfcol.travel_of);
        if travel.len() < self.particles.padded_len() {
            travel.resize(self.particles.padded_len(), a.travel);
        }
        let cp = ClampParams {
            mean,
            limit: a.d / n_sub as f32,
            h,
            travel: &travel,
        };
        // Each chunk also copies its predictions as VcCPBD's box centres (one parallel pass),
        // unless the correction derives them (no obstacles).
        let sink = self.selfcol.prediction_sink(self.obstacles.is_empty());
        self.particles.for_chunks(parallel, |mut c| {
            clamp_speed(c.reborrow(), &cp, simd);
            if let Some(s) = &sink {
                s.keep(c.start, [&*c.px, &*c.py, &*c.pz]);
            }
        });
        self.selfcol.travel_of = travel;
    }

    /// The self-collision pair pass and its correction of the predictions `p`.
    pub(crate) fn self_collision_pairs_pass(&mut self, a: Active, h: f32, exec: Exec) {
        let p = &self.particles;
        self.selfcol.pair_pass([&p.x, &p.y, &p.z], [&p.px, &p.py, &p.pz], &p.w, exec);
        let ap = a.apply_params(h);
        let derive = self.selfcol.derives_centres(self.obstacles.is_empty());
        let p = &mut self.particles;
        let v = derive.then_some([&p.vx[..], &p.vy[..], &p.vz[..]]);
        self.selfcol
            .apply([&p.x, &p.y, &p.z], &p.w, v, [&mut p.px, &mut p.py, &mut p.pz], ap, exec);
    }
}
