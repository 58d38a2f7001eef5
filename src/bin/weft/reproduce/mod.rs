//! `weft reproduce PAPER`: rebuild a source paper's experiment and print our figures beside
//! the paper's. One file per paper:
//! - `landovsky` ([`landovsky`], Landovskaya, Landovsky & Frolovsky): cloth dropped on dress forms, time per broadphase.
//! - `nurbs` ([`nurbs`], the NURBS strands and surfaces thesis): NURBS global against local evaluation cost.
//! - `vccpbd` ([`vccpbd`], Shapri, Sulaiman & Bade 2016, with Müller's hash): self-collision responses on the paper's cloths.
//! - `small-steps` ([`small_steps`], Macklin et al. 2019): substeps against iterations on a chain.

mod landovsky;
pub mod nurbs;
pub mod small_steps;
mod vccpbd;

use std::process::ExitCode;

use clap::Subcommand;

/// The papers whose experiments can be reproduced.
#[derive(Subcommand)]
pub enum Reproduce {
    /// Landovskaya, Landovsky & Frolovsky: cloth dropped on dress forms,
    /// time per broadphase, the paper's five rows plus our BVH, hash and face-memory rows.
    Landovsky(landovsky::Args),
    /// NURBS curves and surfaces (the thesis on NURBS strands): time per evaluated point, global (all n control
    /// points) against local (the k+1 non-zero basis functions), for n = 8 .. 4096 and degree 2..4.
    Nurbs(nurbs::NurbsArgs),
    /// Shapri, Sulaiman & Bade 2016 (VcCPBD, with Müller's hash): collision ms per step of
    /// PBD, movement-speed and VcCPBD responses on the paper's 12 cloths, ours beside theirs.
    Vccpbd(vccpbd::VccpbdArgs),
    /// Macklin et al. 2019 "Small Steps in Physics Simulation": a 20-particle chain with a
    /// 1:100000 mass ratio, 100 iterations x 1 substep against 1 iteration x 100 substeps.
    SmallSteps(small_steps::SmallStepsArgs),
}

/// Runs the chosen reproduction.
pub fn reproduce(what: Reproduce) -> weft::Result<ExitCode> {
    match what {
        Reproduce::Landovsky(args) => landovsky::run(&args),
        Reproduce::Nurbs(args) => nurbs::run(args),
        Reproduce::Vccpbd(args) => vccpbd::run(args),
        Reproduce::SmallSteps(args) => small_steps::small_steps(args),
    }
}
