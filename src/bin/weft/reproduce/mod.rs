//! `weft reproduce PAPER`: re-run a source paper's measurement and print its table.
//!
//! One file per paper (SEEDS.md section in brackets):
//! - `nurbs` ([`nurbs`], B): NURBS global against local evaluation cost.

pub mod nurbs;

use std::process::ExitCode;

use clap::Subcommand;

/// The papers that can be reproduced.
#[derive(Subcommand)]
pub enum Reproduce {
    /// NURBS curves and surfaces (SEEDS.md B): time per evaluated point, global (all n control
    /// points) against local (the k+1 non-zero basis functions), for n = 8 .. 4096 and degree 2..4.
    Nurbs(nurbs::NurbsArgs),
}

/// Runs one reproduction.
pub fn reproduce(what: Reproduce) -> weft::Result<ExitCode> {
    match what {
        Reproduce::Nurbs(args) => nurbs::run(args),
    }
}
