//! `weft`: run a scene, look at it, keep it.
//!
//! ```text
//! weft run scenes/hanging.toml            # simulate, write out/hanging/{final.png,frames.png,summary.json}
//! weft check scenes/flag.toml             # what the scene will simulate, and its memory
//! weft run --resume out/big/checkpoint.bin
//! weft reproduce vccpbd --quick           # the VcCPBD paper's table, ours beside theirs
//! ```

mod check;
mod pictures;
mod reproduce;
mod run;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Cloth and hair as particles, fast.
#[derive(Parser)]
#[command(name = "weft", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene: progress bar, PNG pictures, a JSON summary, optional OBJ/GIF frames
    /// and checkpoints.
    Run(run::RunArgs),
    /// Validate a scene and print what it will simulate (counts, effects, memory).
    Check {
        /// The scene file (TOML).
        scene: PathBuf,
    },
    /// Rerun a source paper's experiment; print our figures beside the paper's.
    #[command(subcommand)]
    Reproduce(reproduce::Reproduce),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run::run(args),
        Command::Check { scene } => check::check(&scene),
        Command::Reproduce(which) => reproduce::run(which),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
