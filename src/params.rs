//! Solver parameters: one plain struct with units and defaults.

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

/// How a step is solved.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverParams {
    /// Time step of one `step`, s.
    pub dt: f32,
    /// Substeps per step (XPBD small steps). PBD is `substeps = 1` with zero compliance.
    pub substeps: u32,
    /// Solver sweeps per substep.
    pub iterations: u32,
    /// Worker threads: 0 = the global rayon pool, k > 0 = a pool of k threads owned by the
    /// world. Results are identical for every value.
    pub threads: usize,
    /// Kernel implementation.
    pub backend: Backend,
    /// Keep a copy of the state at the start of each step and restore it, with an error, if the
    /// step produces a non-finite value (costs one copy of positions and velocities per step).
    pub guard: bool,
}

impl Default for SolverParams {
    fn default() -> Self {
        SolverParams {
            dt: 1.0 / 60.0,
            substeps: 8,
            iterations: 1,
            threads: 0,
            backend: Backend::Simd,
            guard: true,
        }
    }
}

/// Largest number of substeps or iterations accepted (a typo guard, not a physical limit).
pub const MAX_SWEEPS: u32 = 100_000;

impl SolverParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        positive("solver.dt", self.dt)?;
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
                "must be at most 1024 (0 = all cores)",
            ));
        }
        Ok(())
    }
}
