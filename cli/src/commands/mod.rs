//! The command line: argument definitions and one module per subcommand.
//!
//! `src/main.rs` parses, calls [`execute`], and turns the outcome into an exit code.

pub mod chart;
pub mod check;
pub mod diff;
pub mod export;
pub mod inspect;
pub mod record;
pub mod recover;
pub mod replay;
pub mod run;
pub mod stability;
pub mod sweep;
pub mod test;
pub mod view;
pub mod watch;

use clap::{Parser, Subcommand};

/// critterbox: a sandbox for critters that collide.
#[derive(Parser, Debug)]
#[command(name = "critterbox", version, about, long_about = None)]
pub struct Cli {
    /// What to do (default: run the default scene).
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run a scene headless and print a summary.
    Run(run::RunArgs),
    /// Compile and check scene and kind scripts without running them (for editors and CI).
    Check(check::CheckArgs),
    /// Run script tests: every `fn test_*()` in scripts/tests/*.rhai.
    Test(test::TestArgs),
    /// Play a recording back: a summary, any step's exact state, or a full re-simulation check.
    Replay(replay::ReplayArgs),
    /// Show what a recording holds: scene, critters, collisions, energy and momentum over time.
    Inspect(inspect::InspectArgs),
    /// Compare what two recordings recorded: the first step, critter and field that differ.
    Diff(diff::DiffArgs),
    /// Write a recording's states and events as CSV files.
    Export(export::ExportArgs),
    /// Make a readable, complete file from a cut-off or damaged recording (good chunks kept).
    Recover(recover::RecoverArgs),
    /// Chart cost against error for every method; writes docs/speed-vs-accuracy.svg and .png.
    Chart(chart::ChartArgs),
    /// Run the stress scenes under every collision method and print the error table.
    Stability(stability::StabilityArgs),
    /// Many runs from one TOML file: on all cores, one shard of them, or a scheduler's job.
    Sweep(sweep::SweepArgs),
}

/// Runs the parsed command line. Output goes to `out`; progress to stderr.
pub fn execute(cli: Cli, out: &mut dyn std::io::Write) -> anyhow::Result<()> {
    match cli.command {
        Some(Command::Run(args)) => run::run(&args, out),
        Some(Command::Check(args)) => check::run(&args, out),
        Some(Command::Test(args)) => test::run(&args, out),
        Some(Command::Replay(args)) => replay::run(&args, out),
        Some(Command::Inspect(args)) => inspect::run(&args, out),
        Some(Command::Diff(args)) => diff::run(&args, out),
        Some(Command::Export(args)) => export::run(&args, out),
        Some(Command::Recover(args)) => recover::run(&args, out),
        Some(Command::Chart(args)) => chart::run(&args, out),
        Some(Command::Stability(args)) => stability::run(&args, out),
        Some(Command::Sweep(args)) => sweep::run(&args, out),
        None => run::run(&run::RunArgs::default(), out),
    }
}
