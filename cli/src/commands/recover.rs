//! `critterbox recover FILE`: a complete, readable copy of a cut-off or damaged recording (a run
//! that was killed, a flipped bit): every good chunk's messages, the attachments and the
//! metadata are kept; damaged chunks are left out and the steps they held named. Exits 3 when
//! the source lacked anything (the copy is written all the same).

use clap::Args;
use critterbox::recording::recover::rewrite;
use critterbox::recording::RecordingError;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `critterbox recover`.
#[derive(Args, Debug)]
#[command(after_help = super::replay::EXIT_CODES)]
pub struct RecoverArgs {
    /// The cut-off or damaged recording.
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
    if r.lost_data() {
        writeln!(
            out,
            "recovered    {} -> {}: {} messages up to step {}, {} attachments",
            args.file.display(),
            output.display(),
            r.messages,
            r.last_step.map_or("-".into(), |s| s.to_string()),
            r.attachments
        )?;
        for g in &r.gaps {
            eprintln!("warning: {g}");
        }
        if let Some(reason) = &r.truncated {
            eprintln!("warning: {reason}");
        }
        let missing: u64 = r
            .gaps
            .iter()
            .filter_map(|g| g.missing())
            .map(|(a, b)| b.map_or(0, |b| b + 1 - a))
            .sum();
        return Err(RecordingError::Damaged {
            path: args.file.clone(),
            what: format!(
                "{} damaged stretch(es) left out ({missing} steps missing){}; the copy {} holds \
                 everything else",
                r.gaps.len(),
                if r.truncated.is_some() {
                    ", cut off"
                } else {
                    ""
                },
                output.display()
            ),
        }
        .into());
    }
    writeln!(
        out,
        "copied       {} -> {}: the file was complete ({} messages{})",
        args.file.display(),
        output.display(),
        r.messages,
        if r.had_end { "" } else { ", but no end record" }
    )?;
    Ok(())
}
