//! The scalar reference step: plain loops, `f64`, no SIMD, no threads.
//!
//! It follows the same stages as [`World::step`](crate::World::step) on a copy of a world's
//! state and topology, so the fast kernels can be held to it with a stated tolerance. It is
//! deliberately naive: a second, independent reading of the method, not a copy of the kernels.
//!
//! ```text
//! step(dt):
//!   self-collision pair lists from x (brute-force grid)             [self_collision]
//!   for each substep h = dt / substeps:
//!     wind, predict: v += h g + h w f, drag; p = x + h v
//!     analytic obstacles: contact of x -> p, back along the path     [obstacles]
//!     self-collision speed clamp                                     [self_collision]
//!     iterations: distance constraints by colour (XPBD, Macklin et al. 2016 eq. 18),
//!                 tethers, obstacle projection, scalp
//!     self-collision pair pass and response                          [self_collision]
//!     update: v = (p - x) / h, damping; x = p
//!     obstacle velocity pass: normal part, Coulomb friction          [obstacles]
//! ```
//!
//! Triangle-mesh obstacles and the force-based methods are not represented:
//! [`ReferenceWorld::missing_feature`] says so, and the accuracy report keeps the f32 world as
//! the reference for such scenes.

// Plain index loops are the point of this module: it is the naive reading of the method.
#![allow(clippy::needless_range_loop)]

mod obstacles;
mod self_collision;
#[cfg(test)]
mod tests;

use crate::model::description::WorldDescription;
use crate::model::effects::Effects;
use obstacles::{Contact, Obstacle64};
use self_collision::SelfCollision64;

/// One constraint of the reference (global indices).
#[derive(Clone, Copy, Debug)]
struct Dist {
    a: usize,
    b: usize,
    rest: f64,
    compliance: f64,
}

/// A world copied into f64.
#[derive(Clone, Debug)]
pub struct ReferenceWorld {
    /// Positions.
    pub x: Vec<[f64; 3]>,
    /// Velocities.
    pub v: Vec<[f64; 3]>,
    w: Vec<f64>,
    damping: Vec<f64>,
    colours: Vec<Vec<Dist>>,
    tethers: Vec<(usize, usize, f64)>,
    triangles: Vec<[usize; 3]>,
    strand_area: Vec<f64>,
    scalps: Vec<(usize, usize, [f64; 3], [f64; 3])>,
    effects: Effects,
    obstacles: Vec<Obstacle64>,
    /// Obstacle thickness per particle (cloth thickness, half a strand's diameter).
    th: Vec<f64>,
    selfcol: Option<SelfCollision64>,
    missing: Option<&'static str>,
    substeps: u32,
    iterations: u32,
    time: f64,
    /// Multipliers of the last substep's solve (per colour) and its length, for the energy.
    lambda: Vec<Vec<f64>>,
    last_h: f64,
}

impl ReferenceWorld {
    /// Copies a world's description (see [`World::describe`](crate::World::describe)):
    /// state, topology (constraints in the world's colour order), analytic obstacles and
    /// self-collision. Self-collision takes the cloths' rest shapes from the positions now, so
    /// describe a world before its first step. Features it cannot represent are left out and
    /// named by [`missing_feature`](Self::missing_feature).
    pub fn new(d: &WorldDescription) -> Self {
        let n = d.positions.len();
        let obstacles: Vec<Option<Obstacle64>> = d.obstacles.iter().map(|o| Obstacle64::from_desc(o, d.friction)).collect();
        let mut missing = obstacles.iter().any(Option::is_none).then_some("triangle-mesh obstacles");
        if d.method != crate::model::params::Method::Xpbd {
            missing = Some("force-based methods");
        }
        let selfcol = SelfCollision64::from_desc(d).unwrap_or_else(|e| {
            missing = missing.or(Some(e));
            None
        });
        let mut th = vec![0.0; n];
        for c in &d.cloths {
            let r = c.first as usize..(c.first + c.rows * c.cols) as usize;
            th[r.start.min(n)..r.end.min(n)].fill(c.thickness as f64);
        }
        for g in &d.strands {
            let r = g.first as usize..(g.first + g.count * g.points) as usize;
            th[r.start.min(n)..r.end.min(n)].fill(0.5 * g.thickness as f64);
        }
        let colours = d
            .colours
            .iter()
            .map(|c| {
                c.iter()
                    .map(|k| Dist {
                        a: k.a as usize,
                        b: k.b as usize,
                        rest: k.rest as f64,
                        compliance: k.compliance as f64,
                    })
                    .collect()
            })
            .collect();
        ReferenceWorld {
            x: d.positions.iter().map(|p| p.map(f64::from)).collect(),
            v: d.velocities.iter().map(|v| v.map(f64::from)).collect(),
            w: d.inv_mass.iter().map(|&w| w as f64).collect(),
            damping: d.damping.iter().map(|&c| c as f64).collect(),
            colours,
            tethers: d
                .tethers
                .iter()
                .map(|t| (t.particle as usize, t.anchor as usize, t.max_len as f64))
                .collect(),
            triangles: d.triangles.iter().map(|t| t.map(|i| i as usize)).collect(),
            strand_area: d.strand_area.iter().map(|&a| a as f64).collect(),
            scalps: d
                .scalps
                .iter()
                .map(|r| (r.start, r.end, r.center.map(f64::from), r.radii.map(f64::from)))
                .collect(),
            effects: d.effects.clone(),
            obstacles: obstacles.into_iter().flatten().collect(),
            th,
            selfcol,
            missing,
            substeps: d.substeps,
            iterations: d.iterations,
            time: d.time,
            lambda: Vec::new(),
            last_h: 0.0,
        }
    }

    /// What of the world this copy lacks (`None`: everything is represented): triangle-mesh
    /// obstacles, a force-based method (the copy steps XPBD), or self-collision of particles
    /// outside cloths.
    pub fn missing_feature(&self) -> Option<&'static str> {
        self.missing
    }

    /// Advances by `dt` seconds.
    pub fn step(&mut self, dt: f64) {
        let h = dt / self.substeps as f64;
        let n = self.x.len();
        if let Some(sc) = &mut self.selfcol {
            sc.begin_step(&self.x, &self.v, &self.w, dt);
        }
        let mut contacts = vec![vec![Contact::default(); n]; self.obstacles.len()];
        for s in 0..self.substeps {
            let t = self.time + s as f64 * h;
            let mut p = self.predict(t, h);
            let t_end = self.time + (s + 1) as f64 * h;
            for (o, cs) in self.obstacles.iter().zip(contacts.iter_mut()) {
                for i in 0..n {
                    cs[i] = if self.w[i] > 0.0 {
                        o.contact(self.x[i], p[i], self.v[i], self.th[i], t_end, h)
                    } else {
                        Contact::default()
                    };
                }
            }
            for i in 0..n {
                for (o, cs) in self.obstacles.iter().zip(&contacts) {
                    o.resolve(&cs[i], self.x[i], &mut p[i], self.th[i], h);
                }
            }
            if let Some(sc) = &mut self.selfcol {
                sc.clamp(&self.x, &mut self.v, &mut p, &self.w, self.substeps, h);
            }
            self.lambda = self.sweeps(&mut p, &contacts, h);
            self.last_h = h;
            if let Some(sc) = &self.selfcol {
                sc.respond(&self.x, &mut p, &self.w, &self.damping, h);
            }
            for i in 0..n {
                let kd = if self.damping.is_empty() {
                    1.0
                } else {
                    1.0 / (1.0 + self.damping[i] * h)
                };
                for k in 0..3 {
                    self.v[i][k] = (p[i][k] - self.x[i][k]) / h * kd;
                    self.x[i][k] = p[i][k];
                }
                for (o, cs) in self.obstacles.iter().zip(&contacts) {
                    o.velocity(&cs[i], self.x[i], &mut self.v[i], self.th[i]);
                }
            }
        }
        self.time += dt;
    }

    /// Wind, gravity, drag: the velocities and predictions of the substep starting at `t`.
    fn predict(&mut self, t: f64, h: f64) -> Vec<[f64; 3]> {
        let force = self.wind_forces(t);
        let mut p = vec![[0.0f64; 3]; self.x.len()];
        for i in 0..self.x.len() {
            let w = self.w[i];
            if let Some(g) = self.effects.gravity {
                if w > 0.0 {
                    for k in 0..3 {
                        self.v[i][k] += h * g[k] as f64;
                    }
                }
            }
            if let Some(f) = &force {
                for k in 0..3 {
                    self.v[i][k] += h * w * f[i][k];
                }
            }
            if let Some(c) = self.effects.drag {
                let kd = 1.0 / (1.0 + h * c as f64 * w);
                for k in 0..3 {
                    self.v[i][k] *= kd;
                }
            }
            for k in 0..3 {
                p[i][k] = self.x[i][k] + h * self.v[i][k];
            }
        }
        p
    }

    /// The solver iterations: constraints by colour, tethers, obstacle projection, scalps.
    fn sweeps(&self, p: &mut [[f64; 3]], contacts: &[Vec<Contact>], h: f64) -> Vec<Vec<f64>> {
        let mut lambda: Vec<Vec<f64>> = self.colours.iter().map(|c| vec![0.0; c.len()]).collect();
        for _ in 0..self.iterations {
            for (col, lam) in self.colours.iter().zip(lambda.iter_mut()) {
                for (c, l) in col.iter().zip(lam.iter_mut()) {
                    let d = sub(p[c.b], p[c.a]);
                    let len = norm(d);
                    let alpha = c.compliance / (h * h);
                    let denom = self.w[c.a] + self.w[c.b] + alpha;
                    if len <= crate::model::params::MIN_LENGTH as f64 || denom <= 0.0 {
                        continue;
                    }
                    let dl = (-(len - c.rest) - alpha * *l) / denom;
                    for k in 0..3 {
                        let nk = d[k] / len;
                        p[c.a][k] -= self.w[c.a] * dl * nk;
                        p[c.b][k] += self.w[c.b] * dl * nk;
                    }
                    *l += dl;
                }
            }
            for &(i, a, max_len) in &self.tethers {
                let d = sub(p[i], p[a]);
                let len = norm(d);
                if len > max_len {
                    for k in 0..3 {
                        p[i][k] = p[a][k] + d[k] * max_len / len;
                    }
                }
            }
            for cs in contacts {
                for (i, c) in cs.iter().enumerate() {
                    Obstacle64::project(c, &mut p[i], self.th[i]);
                }
            }
            // Scalp: strand points outside the inflated ellipsoid, along the scaled ray.
            for &(start, end, c, r) in &self.scalps {
                for i in start..end {
                    if self.w[i] <= 0.0 {
                        continue;
                    }
                    let d = sub(p[i], c);
                    let s = norm([d[0] / r[0], d[1] / r[1], d[2] / r[2]]);
                    if s < 1e-6 {
                        p[i] = [c[0], c[1] + r[1], c[2]];
                    } else if s < 1.0 {
                        p[i] = std::array::from_fn(|k| c[k] + d[k] / s);
                    }
                }
            }
        }
        lambda
    }

    /// Total energy now, J: kinetic energy of the free particles, gravitational potential
    /// relative to the origin, and the elastic energy `Σ ½ α f²` of the constraints with the
    /// force `f = λ / h²` of the last substep's solve (the measure
    /// [`World::metrics`](crate::World::metrics) reports for XPBD, computed independently).
    pub fn energy(&self) -> f64 {
        let mut e = 0.0;
        for (i, (x, v)) in self.x.iter().zip(&self.v).enumerate() {
            if self.w[i] <= 0.0 {
                continue;
            }
            let m = 1.0 / self.w[i];
            e += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            if let Some(g) = self.effects.gravity {
                e -= m * (g[0] as f64 * x[0] + g[1] as f64 * x[1] + g[2] as f64 * x[2]);
            }
        }
        if self.last_h > 0.0 {
            let inv_h2 = 1.0 / (self.last_h * self.last_h);
            for (col, lam) in self.colours.iter().zip(&self.lambda) {
                for (c, l) in col.iter().zip(lam) {
                    let f = l * inv_h2;
                    e += 0.5 * c.compliance * f * f;
                }
            }
        }
        e
    }

    /// Deepest penetration into the analytic obstacles now, m (0 when none), and how many
    /// particles sit deeper than `count_depth`.
    pub fn obstacle_penetration(&self, count_depth: f64) -> (f64, u64) {
        let (mut max, mut count) = (0.0f64, 0u64);
        for x in &self.x {
            let depth = self
                .obstacles
                .iter()
                .map(|o| -o.signed_distance(*x, self.time))
                .fold(0.0f64, f64::max);
            max = max.max(depth);
            count += (depth > count_depth) as u64;
        }
        (max, count)
    }

    /// Percentage of particles in self-penetration now (another cloth's particle, or one of the
    /// same cloth more than `1.5 d` away at rest, closer than `0.9 d`); `None` without
    /// self-collision.
    pub fn self_penetration_pct(&self) -> Option<f64> {
        self.selfcol.as_ref().map(|s| s.penetration_pct(&self.x))
    }

    fn wind_forces(&self, t: f64) -> Option<Vec<[f64; 3]>> {
        let wind = self.effects.wind.as_ref()?;
        let s = 1.0 + wind.gust as f64 * (2.0 * std::f64::consts::PI * wind.gust_frequency as f64 * t).sin();
        let air = wind.velocity.map(|c| c as f64 * s);
        let k = 0.5 * wind.air_density as f64 * wind.drag_coefficient as f64;
        let mut f = vec![[0.0f64; 3]; self.x.len()];
        for &[a, b, c] in &self.triangles {
            let n = cross(sub(self.x[b], self.x[a]), sub(self.x[c], self.x[a]));
            let n2 = norm(n);
            if n2 <= 1e-20 {
                continue;
            }
            let nh = n.map(|c| c / n2);
            let vt: [f64; 3] = std::array::from_fn(|k| (self.v[a][k] + self.v[b][k] + self.v[c][k]) / 3.0);
            let rel: [f64; 3] = std::array::from_fn(|k| air[k] - vt[k]);
            let vn = nh[0] * rel[0] + nh[1] * rel[1] + nh[2] * rel[2];
            let m = k * 0.5 * n2 * vn * vn.abs() / 3.0;
            for i in [a, b, c] {
                for k in 0..3 {
                    f[i][k] += nh[k] * m;
                }
            }
        }
        // Strand points: quadratic drag on their cross-section.
        for (i, &area) in self.strand_area.iter().enumerate() {
            if area > 0.0 {
                let rel = sub(air, self.v[i]);
                let m = k * area * norm(rel);
                for c in 0..3 {
                    f[i][c] += rel[c] * m;
                }
            }
        }
        Some(f)
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
