//! Measures of a world's state: energy, strain, finiteness.

use crate::world::World;

/// A snapshot of what a world's state measures.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Metrics {
    /// Kinetic energy of free particles, J.
    pub kinetic: f64,
    /// Gravitational potential energy relative to the origin, J (0 without gravity).
    pub potential: f64,
    /// Elastic energy stored in compliant constraints, J: `Σ ½ α f²` with the constraint force
    /// `f = λ / h²` the solver applied in the last substep. For a converged solve this equals
    /// `Σ C² / (2α)`; unlike that form it stays meaningful (and bounded) for stiff constraints
    /// that a few iterations leave slightly violated. With a force-based
    /// [`Method`](crate::model::params::Method) it is the springs' `Σ ½ k (l - rest)²`.
    pub elastic: f64,
    /// Sum of the three, J.
    pub total: f64,
    /// Largest relative stretch `(|x_a - x_b| - rest) / rest` over stretch constraints.
    pub max_strain: f64,
    /// Mean absolute relative stretch over stretch constraints.
    pub mean_strain: f64,
}

impl World {
    /// Measures the current state (f64 sums, serial: the same numbers on any thread count).
    pub fn metrics(&self) -> Metrics {
        let p = &self.particles;
        let n = p.count();
        let mut m = Metrics::default();
        let g = self.effects.gravity.map(|g| g.map(f64::from));
        for i in 0..n {
            if p.w[i] <= 0.0 {
                continue;
            }
            let mass = 1.0 / p.w[i] as f64;
            let v2 = (p.vx[i] as f64).powi(2) + (p.vy[i] as f64).powi(2) + (p.vz[i] as f64).powi(2);
            m.kinetic += 0.5 * mass * v2;
            if let Some(g) = g {
                m.potential -= mass * (g[0] * p.x[i] as f64 + g[1] * p.y[i] as f64 + g[2] * p.z[i] as f64);
            }
        }
        let len = |a: u32, b: u32| {
            let (a, b) = (a as usize, b as usize);
            ((p.x[b] as f64 - p.x[a] as f64).powi(2) + (p.y[b] as f64 - p.y[a] as f64).powi(2) + (p.z[b] as f64 - p.z[a] as f64).powi(2))
                .sqrt()
        };
        if self.params.method != crate::model::params::Method::Xpbd {
            // Force-based methods: the springs' energy at the current positions.
            let p = &self.particles;
            m.elastic = crate::integrate::springs::spring_energy(&self.distance, [&p.x, &p.y, &p.z], self.params.stiffness);
        } else if self.last_h > 0.0 {
            let inv_h2 = 1.0 / (self.last_h as f64 * self.last_h as f64);
            for col in &self.distance.colours {
                // A constraint without compliance stores no energy (and its colour may keep
                // no multipliers: `GridColour::keeps_multipliers`).
                for k in (0..col.real).filter(|&k| col.compliance[k] > 0.0) {
                    let f = col.lambda[k] as f64 * inv_h2;
                    m.elastic += 0.5 * col.compliance[k] as f64 * f * f;
                }
            }
        }
        let mut sum = 0.0;
        for &(a, b, rest) in &self.stretch {
            let s = (len(a, b) - rest as f64) / rest as f64;
            m.max_strain = m.max_strain.max(s);
            sum += s.abs();
        }
        if !self.stretch.is_empty() {
            m.mean_strain = sum / self.stretch.len() as f64;
        }
        m.total = m.kinetic + m.potential + m.elastic;
        m
    }
}
