//! `weft`: run a scene, look at it, keep it.
//!
//! ```text
//! weft run scenes/hanging.toml            # simulate, write out/hanging/{final.png,frames.png,summary.json}
//! weft check scenes/flag.toml             # what the scene will simulate, and its memory
//! weft run --resume out/big/checkpoint.bin
//! weft bench --self-collision [--json]    # the self-collision suite on 1 and 2 threads
//! weft reproduce nurbs [--json]           # the NURBS thesis' cost claim
//! weft reproduce landovsky --quick        # our seconds beside Landovskaya et al.'s
//! weft reproduce vccpbd --quick           # the VcCPBD paper's table, ours beside theirs
//! weft reproduce small-steps              # Macklin et al. 2019 chain: substeps against iterations
//! weft accuracy scenes/hanging.toml --plot out/hanging/accuracy.svg
//! ```

mod accuracy;
mod bench;
mod check;
mod glb;
mod pictures;
mod reproduce;
mod run;
mod scaling;

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
    /// A quick (< 60 s) speed report: ns per particle per kernel, SIMD/scalar and 2-thread/1-thread
    /// ratios, fraction of the memory bandwidth, ms per step of each shipped scene.
    Bench {
        /// Print one JSON object instead of the table.
        #[arg(long)]
        json: bool,
        /// Directory of scenes to time.
        #[arg(long, default_value = "scenes")]
        scenes: PathBuf,
        /// Instead of the report, time ms per step for 1k .. 1M particles on 1 and 2 threads and
        /// write DIR/scaling.md (table) and DIR/scaling.svg (plot).
        #[arg(long, value_name = "DIR")]
        scaling: Option<PathBuf>,
        /// Instead of the report, run the self-collision suite (`scenes/self-collision/` and
        /// the twist) on 1 and 2 threads, with and without self-collision.
        #[arg(long)]
        self_collision: bool,
        /// Steps of each suite run.
        #[arg(long, default_value_t = 240)]
        steps: u32,
        /// Directory of the suite's scene files.
        #[arg(long, default_value = "scenes/self-collision")]
        suite: PathBuf,
        /// With --self-collision: write the last state of each scene as DIR/NAME.png.
        #[arg(long, value_name = "DIR")]
        pictures: Option<PathBuf>,
        /// With --self-collision: run only these scenes (comma-separated names).
        #[arg(long, value_delimiter = ',')]
        only: Vec<String>,
        /// With --self-collision: the travel bound `T / d` of every scene (above 0, at most 2;
        /// default: each scene's own, 1 in the shipped ones). Lower is cheaper and clamps harder.
        #[arg(long)]
        travel: Option<f32>,
    },
    /// Time against error for a grid of integrators and settings, against a cached reference.
    Accuracy(accuracy::AccuracyArgs),
    /// Re-run a source paper's measurement and print its table (e.g. `weft reproduce nurbs`).
    #[command(subcommand)]
    Reproduce(reproduce::Reproduce),
}

fn main() -> ExitCode {
    // This thread steps the worlds. As a thread of the global pool it runs a step's parallel
    // passes itself; outside the pool every step would be handed to a pool thread while this
    // one sleeps, and waking it at the end cost about 7% of a 100 x 100 cloth's 1 x 1 step
    // (`docs/performance.md` describes the hand-off). The call fails only when the global pool
    // exists already, which nothing before this line makes; the steps then take the hand-off.
    let _ = rayon::ThreadPoolBuilder::new().use_current_thread().build_global();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run::run(args),
        Command::Check { scene } => check::check(&scene),
        Command::Bench { scaling: Some(dir), .. } => scaling::scaling(&dir).map(|()| ExitCode::SUCCESS),
        Command::Bench {
            self_collision: true,
            json,
            steps,
            suite,
            pictures,
            only,
            travel,
            ..
        } => bench::bench_self_collision(json, &suite, steps, pictures.as_deref(), &only, travel),
        Command::Bench { json, scenes, .. } => bench::bench(json, &scenes),
        Command::Accuracy(args) => accuracy::accuracy(args),
        Command::Reproduce(what) => reproduce::reproduce(what),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
