//! The command line: argument definitions and one module per subcommand.
//!
//! `src/main.rs` parses, calls [`execute`], and turns the outcome into an exit code.

pub mod check;
pub mod run;
pub mod test;
pub mod view;

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
}

/// Runs the parsed command line. Output goes to `out`; progress to stderr.
pub fn execute(cli: Cli, out: &mut dyn std::io::Write) -> anyhow::Result<()> {
    match cli.command {
        Some(Command::Run(args)) => run::run(&args, out),
        Some(Command::Check(args)) => check::run(&args, out),
        Some(Command::Test(args)) => test::run(&args, out),
        None => run::run(&run::RunArgs::default(), out),
    }
}
