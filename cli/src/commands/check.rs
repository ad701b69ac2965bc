//! `critterbox check FILE...`: load and lint scripts without running them.

use clap::Args;
use critterbox::script::{check_files, ScriptOptions, Severity};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `critterbox check`.
#[derive(Args, Debug)]
#[command(after_help = "\
Every file is checked and every problem reported in one pass, each with a verdict of its own: \
errors first (the file does not load; a hook with the wrong number of parameters, each one; a \
scene's spawn with a bad field, which is left out so the rest of the scene is checked; a kind \
name in a scene's string literal that names no kind), then warnings (a function named like a \
hook, e.g. `colide`; a kind name in a kind's or test's string literal that names no kind).

Exit codes: 0 no errors (warnings allowed, unless --strict); 1 an error in some file, or a \
warning under --strict; 2 bad arguments.")]
pub struct CheckArgs {
    /// Scene, kind or test scripts to check (scenes are set up but not stepped; a file with
    /// `fn test_...` functions is a test file, one that makes a world a scene, any other a kind).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Warnings fail the check too.
    #[arg(long)]
    pub strict: bool,
}

/// Checks every file, printing what each is and its problems; fails if any has an error (or a
/// warning, under `--strict`).
pub fn run(args: &CheckArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let reports = check_files(&args.files, &ScriptOptions::default());
    let (mut errors, mut warnings) = (0, 0);
    for report in &reports {
        if let Some(summary) = &report.summary {
            writeln!(out, "{summary}")?;
        }
        for problem in &report.problems {
            eprintln!("{problem}");
        }
        errors += report.count(Severity::Error);
        warnings += report.count(Severity::Warning);
    }
    let files = |n: usize| if n == 1 { "file" } else { "files" };
    let bad = reports.iter().filter(|r| !r.problems.is_empty()).count();
    if errors > 0 || (args.strict && warnings > 0) {
        anyhow::bail!(
            "check found {errors} error{} and {warnings} warning{} in {bad} {}{}",
            if errors == 1 { "" } else { "s" },
            if warnings == 1 { "" } else { "s" },
            files(bad),
            if errors == 0 { " (--strict)" } else { "" }
        );
    }
    if warnings > 0 {
        eprintln!(
            "check: {warnings} warning{} in {bad} {} (--strict makes them fail)",
            if warnings == 1 { "" } else { "s" },
            files(bad)
        );
    }
    Ok(())
}
