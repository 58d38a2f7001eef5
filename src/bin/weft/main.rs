//! `weft`: run a scene, look at it, keep it.
//!
//! ```text
//! weft run scenes/hanging.toml            # simulate, write out/hanging/{final.png,frames.png,summary.json}
//! weft check scenes/flag.toml             # what the scene will simulate, and its memory
//! weft run --resume out/big/checkpoint.bin
//! weft accuracy scenes/hanging.toml --plot out/hanging/accuracy.svg
//! weft reproduce small-steps
//! ```

mod accuracy;
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
    /// Time against error for a grid of integrators and settings, against a cached reference.
    Accuracy(accuracy::AccuracyArgs),
    /// Rerun an experiment from a source paper, ours beside theirs.
    #[command(subcommand)]
    Reproduce(reproduce::Reproduce),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run::run(args),
        Command::Check { scene } => check::check(&scene),
        Command::Accuracy(args) => accuracy::accuracy(args),
        Command::Reproduce(r) => reproduce::reproduce(r),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
