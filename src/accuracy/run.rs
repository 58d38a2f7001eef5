//! Running one setting, or a grid of them, against a reference.

use std::time::Instant;

use crate::accuracy::energy::{energy_budget, kinetic_energy, model_energy};
use crate::accuracy::reference::{MakeWorld, Reference, ReferenceKind};
use crate::accuracy::{pareto, BLOWUP_FACTOR, DIVERGED_RMS};
use crate::error::{Result, WeftError};
use crate::model::params::{Backend, Method, SolverParams};
use crate::model::self_collision::{Response, SelfBroadphase};
use crate::reference::ReferenceWorld;
use crate::World;

/// Arithmetic of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Precision {
    /// The world's f32 SIMD kernels on its thread pool.
    F32,
    /// The scalar f64 XPBD step of [`crate::reference`] (XPBD only).
    F64,
}

/// One point of the grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Setting {
    /// Self-collision response, if the scene has self-collision (`None`: the scene's).
    pub response: Option<Response>,
    /// Self-collision broadphase (`None`: the scene's).
    pub broadphase: Option<SelfBroadphase>,
    /// Integrator.
    pub method: Method,
    /// Substeps per step.
    pub substeps: u32,
    /// Iterations per substep (XPBD; 1 for the other methods).
    pub iterations: u32,
    /// Arithmetic.
    pub precision: Precision,
}

/// What one setting measured; error fields are `None` when the run diverged.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Outcome {
    /// Method name as in scene files.
    pub method: &'static str,
    /// Substeps per step.
    pub substeps: u32,
    /// Iterations per substep.
    pub iterations: u32,
    /// `"f32"` or `"f64"`.
    pub precision: Precision,
    /// Self-collision response that ran (`None`: no self-collision).
    pub response: Option<&'static str>,
    /// Self-collision broadphase that ran (`None`: no self-collision).
    pub broadphase: Option<&'static str>,
    /// `"ok"`, `"diverged"` (non-finite, or RMS error past [`DIVERGED_RMS`]) or
    /// `"diverged-bounded"` (finite, but its kinetic energy passed [`BLOWUP_FACTOR`] times the
    /// reference's energy budget; see the module docs).
    pub status: &'static str,
    /// Wall time per step, ms (until divergence for diverged runs).
    pub ms_per_step: f64,
    /// RMS position error over particles and steps, m.
    pub rms_error: Option<f64>,
    /// Largest position error over the run, m.
    pub max_error: Option<f64>,
    /// Largest relative stretch over the run.
    pub max_strain: Option<f64>,
    /// `E(T) - E(0)`, J.
    pub energy_drift: Option<f64>,
    /// Deepest obstacle penetration after any step, m (0 without obstacles).
    pub max_penetration: Option<f64>,
    /// Particles more than [`PENETRATION_COUNT_DEPTH`] inside an obstacle at the end.
    pub penetration_count: Option<u64>,
    /// Mean over the steps of the percentage of particles in self-penetration (the VcCPBD
    /// paper's "average collision"; `None` without self-collision).
    pub self_penetration_pct: Option<f64>,
    /// The run's largest kinetic energy after any step over the reference's energy budget
    /// ([`energy_budget`]); `None` when it went non-finite.
    pub kinetic_ratio: Option<f64>,
    /// On the Pareto front of (ms_per_step, rms_error).
    pub pareto: bool,
}

/// A whole report.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Report {
    /// Steps simulated.
    pub steps: usize,
    /// Step length, s.
    pub dt: f32,
    /// How the reference was computed.
    pub reference_kind: ReferenceKind,
    /// Substeps of the reference's finer run.
    pub reference_substeps: u32,
    /// The reference's own error estimate, m (see [`Reference::self_error`]).
    pub reference_self_error: f64,
    /// `E(T) - E(0)` of the reference, J.
    pub reference_drift: f64,
    /// One entry per setting.
    pub outcomes: Vec<Outcome>,
}

/// Depth past which a particle counts in [`Outcome::penetration_count`], m.
pub const PENETRATION_COUNT_DEPTH: f64 = 1e-4;

/// The grid for `world`: [`default_grid`], without the f64 rows when the f64 step lacks a
/// feature of the scene ([`ReferenceKind::F32World`]); with self-collision, XPBD at 4 and 16
/// substeps also runs every other response × broadphase (the plain rows use the scene's).
pub fn grid_for(world: &World) -> Vec<Setting> {
    let f64_ok = ReferenceKind::for_world(world) == ReferenceKind::F64Xpbd;
    let mut g: Vec<Setting> = default_grid()
        .into_iter()
        .filter(|s| f64_ok || s.precision == Precision::F32)
        .collect();
    if let Some(sc) = world.self_collision() {
        for substeps in [4, 16] {
            for response in [Response::Pbd, Response::MovementSpeed, Response::Vccpbd] {
                for broadphase in [SelfBroadphase::Hash, SelfBroadphase::AabbTree] {
                    if (response, broadphase) != (sc.response, sc.broadphase) {
                        g.push(Setting {
                            method: Method::Xpbd,
                            substeps,
                            iterations: 1,
                            precision: Precision::F32,
                            response: Some(response),
                            broadphase: Some(broadphase),
                        });
                    }
                }
            }
        }
    }
    g
}

/// Deepest obstacle penetration of `w`'s particles (m, 0 when none) and how many sit deeper
/// than [`PENETRATION_COUNT_DEPTH`].
pub fn obstacle_penetration(w: &World) -> (f64, u64) {
    use crate::obstacles::penetration::mesh_signed_distance;
    use crate::obstacles::Geometry;
    let [x, y, z] = w.positions();
    let mut depth = vec![0.0f32; w.particle_count()];
    let mut scratch = Vec::new();
    for o in w.obstacles() {
        let shape = o.shape_at(w.time());
        for (i, d) in depth.iter_mut().enumerate() {
            let q = [x[i], y[i], z[i]];
            let s = match (&shape, o.geometry()) {
                (Some(s), _) => Some(s.signed_distance(q)),
                (None, Geometry::Mesh(m)) => mesh_signed_distance(m.mesh(), m.broadphase(), q, &mut scratch),
                _ => None,
            };
            *d = d.max(-s.unwrap_or(0.0));
        }
    }
    let max = depth.iter().copied().fold(0.0f32, f32::max) as f64;
    (max, depth.iter().filter(|&&d| d as f64 > PENETRATION_COUNT_DEPTH).count() as u64)
}

/// The default grid: XPBD (f32: substeps 1–64 × iterations 1–16; f64: substeps 1–64),
/// symplectic Euler and leapfrog (64–4096 substeps) and implicit Euler (1–16 substeps).
pub fn default_grid() -> Vec<Setting> {
    let s = |method, substeps, iterations, precision| Setting {
        response: None,
        broadphase: None,
        method,
        substeps,
        iterations,
        precision,
    };
    let mut g = Vec::new();
    for sub in [1, 4, 16, 64] {
        for it in [1, 4, 16] {
            g.push(s(Method::Xpbd, sub, it, Precision::F32));
        }
    }
    for sub in [1, 4, 16, 64] {
        g.push(s(Method::Xpbd, sub, 1, Precision::F64));
    }
    for m in [Method::SymplecticEuler, Method::Leapfrog] {
        for sub in [64, 512, 4096] {
            g.push(s(m, sub, 1, Precision::F32));
        }
    }
    for sub in [1, 4, 16] {
        g.push(s(Method::ImplicitEuler, sub, 1, Precision::F32));
    }
    g
}

pub(super) fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

pub(super) fn state64(w: &World) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let p = w.particles();
    let n = w.particle_count();
    (
        (0..n).map(|i| p.position(i).map(f64::from)).collect(),
        (0..n).map(|i| p.velocity(i).map(f64::from)).collect(),
    )
}

fn max_strain(w: &World, x: &[[f64; 3]]) -> f64 {
    w.stretch
        .iter()
        .map(|&(a, b, rest)| (dist(x[a as usize], x[b as usize]) - rest as f64) / rest as f64)
        .fold(0.0, f64::max)
}

/// Runs one setting for `steps` steps against `reference`.
pub fn run_setting(make: MakeWorld<'_>, reference: &Reference, setting: Setting, steps: usize) -> Result<Outcome> {
    if reference.frames.len() < steps + 1 {
        return Err(WeftError::param("steps", steps, "the reference is shorter than the run"));
    }
    let mut w = make()?;
    let params = SolverParams {
        method: setting.method,
        substeps: setting.substeps,
        iterations: setting.iterations,
        backend: Backend::Simd,
        guard: true,
        ..w.params().clone()
    };
    let dt = params.dt;
    w.set_params(params)?;
    if let Some(mut sc) = w.self_collision().cloned() {
        sc.response = setting.response.unwrap_or(sc.response);
        sc.broadphase = setting.broadphase.unwrap_or(sc.broadphase);
        w.set_self_collision(Some(sc))?;
    } else if setting.response.is_some() || setting.broadphase.is_some() {
        return Err(WeftError::param(
            "self-collision response",
            "set",
            "the scene has no self-collision",
        ));
    }
    let selfcol = w.self_collision().map(|c| (c.response.name(), c.broadphase.name()));
    let (x0, v0) = state64(&w);
    let e0 = model_energy(&w, &x0, &v0);
    let mut f64_world = match setting.precision {
        Precision::F32 => None,
        Precision::F64 if ReferenceKind::for_world(&w) == ReferenceKind::F32World => {
            return Err(WeftError::param(
                "precision",
                "f64",
                "lacks a feature of this scene (mesh obstacles or strand self-collision)",
            ))
        }
        Precision::F64 if setting.method == Method::Xpbd => Some(ReferenceWorld::new(&w.describe())),
        Precision::F64 => return Err(WeftError::param("precision", "f64", "is available for the xpbd method only")),
    };
    let (mut sum2, mut max_err, mut strain, mut seconds) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut done = 0usize;
    let (mut depth, mut self_pct) = (0.0f64, 0.0f64);
    let mut diverged = false;
    let budget = energy_budget(&w, reference);
    let mut peak_kinetic = kinetic_energy(&w, &v0);
    let mut last = (x0, v0);
    for k in 0..steps {
        let t0 = Instant::now();
        let ok = match &mut f64_world {
            Some(r) => {
                r.step(dt as f64);
                r.x.iter().flatten().all(|v| v.is_finite())
            }
            None => match w.step(dt) {
                Ok(()) => true,
                Err(WeftError::Diverged { .. }) => false,
                Err(e) => return Err(e),
            },
        };
        seconds += t0.elapsed().as_secs_f64();
        done += 1;
        if !ok {
            diverged = true;
            break;
        }
        last = match &f64_world {
            Some(r) => (r.x.clone(), r.v.clone()),
            None => state64(&w),
        };
        for (a, b) in last.0.iter().zip(&reference.frames[k + 1]) {
            let d = dist(*a, *b);
            sum2 += d * d;
            max_err = max_err.max(d);
        }
        strain = strain.max(max_strain(&w, &last.0));
        peak_kinetic = peak_kinetic.max(kinetic_energy(&w, &last.1));
        match &f64_world {
            None => {
                depth = depth.max(obstacle_penetration(&w).0);
                if selfcol.is_some() {
                    self_pct += w.measure_self_collision()?;
                }
            }
            Some(r) => {
                depth = depth.max(r.obstacle_penetration(PENETRATION_COUNT_DEPTH).0);
                self_pct += r.self_penetration_pct().unwrap_or(0.0);
            }
        }
    }
    let n = w.particle_count().max(1);
    let rms = (sum2 / (n * done.max(1)) as f64).sqrt();
    diverged |= rms.is_nan() || rms >= DIVERGED_RMS;
    let kinetic_ratio = (!diverged && peak_kinetic.is_finite()).then_some(peak_kinetic / budget);
    let bounded = kinetic_ratio.is_some_and(|k| k > BLOWUP_FACTOR);
    let status = match (diverged, bounded) {
        (true, _) => "diverged",
        (false, true) => "diverged-bounded",
        _ => "ok",
    };
    diverged |= bounded;
    let some = |v: f64| (!diverged).then_some(v);
    Ok(Outcome {
        method: setting.method.name(),
        substeps: setting.substeps,
        iterations: setting.iterations,
        precision: setting.precision,
        response: selfcol.map(|s| s.0),
        broadphase: selfcol.map(|s| s.1),
        status,
        ms_per_step: 1e3 * seconds / done.max(1) as f64,
        rms_error: some(rms),
        max_error: some(max_err),
        max_strain: some(strain),
        energy_drift: some(model_energy(&w, &last.0, &last.1) - e0),
        max_penetration: some(depth),
        penetration_count: (!diverged).then(|| match &f64_world {
            Some(r) => r.obstacle_penetration(PENETRATION_COUNT_DEPTH).1,
            None => obstacle_penetration(&w).1,
        }),
        self_penetration_pct: selfcol.and(some(self_pct / done.max(1) as f64)),
        kinetic_ratio,
        pareto: false,
    })
}

/// Runs every setting, calling `progress(i, outcome)` after each, and marks the Pareto front.
pub fn run_grid(
    make: MakeWorld<'_>,
    reference: &Reference,
    grid: &[Setting],
    steps: usize,
    mut progress: impl FnMut(usize, &Outcome),
) -> Result<Vec<Outcome>> {
    let mut out = Vec::with_capacity(grid.len());
    for (i, s) in grid.iter().enumerate() {
        let o = run_setting(make, reference, *s, steps)?;
        progress(i, &o);
        out.push(o);
    }
    let front = pareto(&out.iter().map(|o| o.rms_error.map(|e| (o.ms_per_step, e))).collect::<Vec<_>>());
    for (o, f) in out.iter_mut().zip(front) {
        o.pareto = f;
    }
    Ok(out)
}

/// `E(T) - E(0)` of the reference, J.
pub fn reference_drift(make: MakeWorld<'_>, reference: &Reference) -> Result<f64> {
    let w = make()?;
    let (x0, v0) = state64(&w);
    let last = reference
        .frames
        .last()
        .ok_or_else(|| WeftError::param("reference", "empty", "has no frames"))?;
    Ok(model_energy(&w, last, &reference.final_velocity) - model_energy(&w, &x0, &v0))
}
