//! `weft reproduce PAPER`: rerun a source paper's experiment and print our figures beside the
//! paper's. One file per paper.

use std::process::ExitCode;

use clap::Subcommand;

mod vccpbd;

/// The papers that can be reproduced.
#[derive(Subcommand)]
pub enum Reproduce {
    /// Shapri et al. 2016 (SEEDS.md A): collision time per step and average collision of the
    /// three responses on 34x34, 50x50 and 100x100 cloths, four fabrics, hash and AABB tree.
    Vccpbd(vccpbd::VccpbdArgs),
}

/// Runs one reproduction.
pub fn run(which: Reproduce) -> weft::Result<ExitCode> {
    match which {
        Reproduce::Vccpbd(a) => vccpbd::run(a),
    }
}
