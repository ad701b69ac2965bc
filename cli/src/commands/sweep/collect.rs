//! `--collect DIR...`: the table rebuilt from whatever results the folders hold (one sweep's,
//! or the union of its shards'), without running anything.

use super::{plan, write_table, SweepArgs};
use critterbox::sweep::SweepFile;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes the table to `dir`; missing or failed runs make it an error after the table is
/// written.
pub fn run(
    file: &SweepFile,
    dirs: &[PathBuf],
    dir: &Path,
    args: &SweepArgs,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    for d in dirs {
        anyhow::ensure!(
            d.join("runs").is_dir(),
            "--collect {}: no runs/ folder there; give the --out DIR of a sweep or of its shards",
            d.display()
        );
    }
    let runs = plan(file);
    let (present, failed) = write_table(file, &runs, dirs, dir, args, out)?;
    let missing = runs.len() - present;
    writeln!(
        out,
        "collected    {present} of {} runs ({failed} failed, {missing} missing)",
        runs.len()
    )?;
    anyhow::ensure!(
        missing == 0,
        "{missing} of {} runs have no result yet; run the missing shards (or the sweep with --out {}) and collect again",
        runs.len(),
        dir.display()
    );
    anyhow::ensure!(
        failed == 0,
        "{failed} of {} runs failed; their rows carry the error",
        runs.len()
    );
    Ok(())
}
