//! `critterbox export FILE --csv DIR`: a recording's states and events as CSV files.

use clap::Args;
use critterbox::recording::export::export_csv;
use critterbox::recording::Recording;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `critterbox export`.
#[derive(Args, Debug)]
#[command(after_help = super::replay::EXIT_CODES)]
pub struct ExportArgs {
    /// The recording (.mcap).
    pub file: PathBuf,
    /// Folder for the CSV files (states, steps, collisions, lifecycle, log).
    #[arg(long, value_name = "DIR", required = true)]
    pub csv: PathBuf,
    /// Write every step's state, re-simulating between the recorded full states (checked
    /// against every recorded hash).
    #[arg(long)]
    pub every_step: bool,
}

/// Runs the command.
pub fn run(args: &ExportArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let rec = Recording::open(&args.file)?;
    let done = export_csv(&rec, &args.csv, args.every_step)?;
    for (path, rows) in &done.files {
        writeln!(out, "{:<40} {rows} rows", path.display())?;
    }
    writeln!(out, "states       {} steps", done.states)?;
    super::replay::damage_outcome(&rec)
}
