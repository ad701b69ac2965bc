//! `critterbox check FILE...`: compile and validate scripts without running them.

use clap::Args;
use critterbox::script::{check, ScriptOptions};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `critterbox check`.
#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Scene or kind scripts to check (scenes are set up but not stepped).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
}

/// Checks each file; the first error ends the command with a non-zero exit.
pub fn run(args: &CheckArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    for file in &args.files {
        let lines = check(std::slice::from_ref(file), &ScriptOptions::default())?;
        for line in lines {
            writeln!(out, "{line}")?;
        }
    }
    Ok(())
}
