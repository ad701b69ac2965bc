//! `critterbox recover FILE`: a complete, readable copy of a cut-off recording (a run that was
//! killed): every complete chunk's messages, the attachments and the metadata are kept.

use clap::Args;
use critterbox::recording::recover::rewrite;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `critterbox recover`.
#[derive(Args, Debug)]
pub struct RecoverArgs {
    /// The cut-off recording.
    pub file: PathBuf,
    /// Where to write the copy (default: FILE with `.recovered.mcap`).
    #[arg(short = 'o', long, value_name = "OUT")]
    pub output: Option<PathBuf>,
}

/// Runs the command.
pub fn run(args: &RecoverArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let output = args.output.clone().unwrap_or_else(|| {
        let stem = args
            .file
            .file_stem()
            .map_or("recording".into(), |s| s.to_string_lossy().into_owned());
        args.file.with_file_name(format!("{stem}.recovered.mcap"))
    });
    let r = rewrite(&args.file, &output, |_, _| None)?;
    match &r.truncated {
        Some(reason) => writeln!(
            out,
            "recovered    {} -> {}: {} messages up to step {}, {} attachments ({reason})",
            args.file.display(),
            output.display(),
            r.messages,
            r.last_step.map_or("-".into(), |s| s.to_string()),
            r.attachments
        )?,
        None => writeln!(
            out,
            "copied       {} -> {}: the file was complete ({} messages{})",
            args.file.display(),
            output.display(),
            r.messages,
            if r.had_end { "" } else { ", but no end record" }
        )?,
    }
    Ok(())
}
