//! Solver parameters: one plain struct with units and defaults.

/// Below this length a distance constraint has no direction and is skipped for the substep.
pub const MIN_LENGTH: f32 = 1e-9;

use crate::error::{positive, Result, WeftError};

/// Which implementation of the kernels a world runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Backend {
    /// `f32x8` SIMD kernels, parallel chunks on the world's thread pool.
    #[default]
    Simd,
    /// The scalar f32 twins, one thread. Same bits as `Simd`, slower; for tests and benches.
    Scalar,
}

/// Which integrator advances the cloth. All four run on the same particles and the same
/// distance constraints; the three force-based methods read each constraint as a spring (see
/// [`integrate::mass_spring`](crate::integrate::mass_spring)). Tethers are position limits and
/// only the XPBD method applies them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// XPBD with `substeps` substeps of `iterations` sweeps (PBD = one substep, zero compliance).
    #[default]
    Xpbd,
    /// Explicit mass-spring, symplectic (semi-implicit) Euler: kick with `F(x_n)`, then drift.
    SymplecticEuler,
    /// Explicit mass-spring, leapfrog (kick-drift-kick, second order).
    Leapfrog,
    /// Implicit (backward) Euler on the mass-spring model, Baraff–Witkin linearisation, solved
    /// with a sparse Cholesky factorisation (faer).
    ImplicitEuler,
}

impl Method {
    /// Every method, in the order reports list them.
    pub const ALL: [Method; 4] = [Method::Xpbd, Method::SymplecticEuler, Method::Leapfrog, Method::ImplicitEuler];

    /// The scene-file name (`"xpbd"`, `"symplectic-euler"`, `"leapfrog"`, `"implicit-euler"`).
    pub fn name(self) -> &'static str {
        match self {
            Method::Xpbd => "xpbd",
            Method::SymplecticEuler => "symplectic-euler",
            Method::Leapfrog => "leapfrog",
            Method::ImplicitEuler => "implicit-euler",
        }
    }
}

/// How a step is solved.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverParams {
    /// Time step of one `step`, s.
    pub dt: f32,
    /// Substeps per step (XPBD small steps). PBD is `substeps = 1` with zero compliance.
    pub substeps: u32,
    /// Solver sweeps per substep (XPBD only; the force-based methods ignore it).
    pub iterations: u32,
    /// The integrator.
    pub method: Method,
    /// Spring stiffness, N/m, that the force-based methods give constraints of zero compliance
    /// (rigid in XPBD); a constraint of compliance `α > 0` becomes a spring of stiffness `1/α`.
    pub stiffness: f32,
    /// Worker threads: 0 = the global rayon pool or the caller's thread, whichever the world
    /// measures faster ([`crate::world::threads`]), 1 = the caller's thread (no pool), k > 1 =
    /// a pool of k threads owned by the world. Results are identical for every value.
    pub threads: usize,
    /// Kernel implementation.
    pub backend: Backend,
    /// Keep a copy of the state at the start of each step and restore it, with an error, if the
    /// step produces a non-finite value (costs one copy of positions and velocities per step; the
    /// XPBD step makes it inside its first predict pass and checks inside its last update pass).
    /// On a 100 x 100 cloth with one substep it adds 4% to 19% to the step (runs on different
    /// days), with five at most 6% (`examples/guard_cost.rs`).
    pub guard: bool,
}

impl Default for SolverParams {
    fn default() -> Self {
        SolverParams {
            dt: 1.0 / 60.0,
            substeps: 8,
            iterations: 1,
            method: Method::Xpbd,
            stiffness: DEFAULT_STIFFNESS,
            threads: 0,
            backend: Backend::Simd,
            guard: true,
        }
    }
}

/// Spring stiffness of rigid constraints in the force-based methods when none is given, N/m.
pub const DEFAULT_STIFFNESS: f32 = 1e4;

/// Largest number of substeps or iterations accepted (a typo guard, not a physical limit).
pub const MAX_SWEEPS: u32 = 100_000;

impl SolverParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        positive("solver.dt", self.dt)?;
        positive("solver.stiffness", self.stiffness)?;
        if self.substeps == 0 || self.substeps > MAX_SWEEPS {
            return Err(WeftError::param(
                "solver.substeps",
                self.substeps,
                format!("must be between 1 and {MAX_SWEEPS}"),
            ));
        }
        if self.iterations == 0 || self.iterations > MAX_SWEEPS {
            return Err(WeftError::param(
                "solver.iterations",
                self.iterations,
                format!("must be between 1 and {MAX_SWEEPS}"),
            ));
        }
        if self.threads > 1024 {
            return Err(WeftError::param(
                "solver.threads",
                self.threads,
                "must be at most 1024 (0 = all cores or one, measured)",
            ));
        }
        Ok(())
    }
}
