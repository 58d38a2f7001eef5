//! `weft reproduce ...`: rerun an experiment of a source paper and print ours beside theirs.

pub mod small_steps;

use std::process::ExitCode;

use clap::Subcommand;

/// Experiments `weft reproduce` knows.
#[derive(Subcommand)]
pub enum Reproduce {
    /// Macklin et al. 2019 "Small Steps in Physics Simulation": the hanging chain with a
    /// 1:100000 mass ratio, 100 iterations x 1 substep against 1 iteration x 100 substeps.
    SmallSteps(small_steps::SmallStepsArgs),
}

/// Runs one experiment.
pub fn reproduce(r: Reproduce) -> weft::Result<ExitCode> {
    match r {
        Reproduce::SmallSteps(a) => small_steps::small_steps(a),
    }
}
