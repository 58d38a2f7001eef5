//! `weft reproduce PAPER`: rebuild a source paper's experiment and print our figures beside
//! the paper's. One file per paper.

mod landovsky;

use std::process::ExitCode;

use clap::Subcommand;

/// The papers whose experiments can be reproduced.
#[derive(Subcommand)]
pub enum Reproduce {
    /// Landovskaya, Landovsky & Frolovsky (SEEDS.md section D): cloth dropped on dress forms,
    /// time per broadphase, the paper's five rows plus our BVH, hash and face-memory rows.
    Landovsky(landovsky::Args),
}

/// Runs the chosen reproduction.
pub fn run(r: Reproduce) -> weft::Result<ExitCode> {
    match r {
        Reproduce::Landovsky(args) => landovsky::run(&args),
    }
}
