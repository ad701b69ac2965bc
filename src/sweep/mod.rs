//! Sweeps: many runs of one scene from one TOML file (`critterbox sweep`, `docs/sweeps.md`).
//!
//! The file ([`SweepFile`]) names a scene, the values each run fixes and the axes it varies.
//! [`SweepFile::runs`] expands the axes into an ordered list of [`RunParams`], each named by a
//! hash of its parameters; a [`Shard`] takes a deterministic slice of that list; a run's
//! [`RunResult`] (its [`RunSummary`] or its error) is one file per run; a [`Table`] assembles
//! the results present into one CSV. Processes, progress and schedulers belong to the CLI.

mod error;
mod expand;
mod file;
mod params;
mod result;
mod shard;
mod summary;
mod table;

pub use error::SweepError;
pub use file::{Axes, SweepFile};
pub use params::RunParams;
pub use result::RunResult;
pub use shard::Shard;
pub use summary::{prop_to_json, RunSummary};
pub use table::Table;

/// Writes `bytes` to `path` through a temporary file renamed over it, so a reader never sees a
/// half-written file (a run killed mid-write leaves only the temporary behind).
pub fn write_atomic(path: &std::path::Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(".tmp{}", std::process::id()));
    let tmp = std::path::PathBuf::from(tmp);
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path)
}
