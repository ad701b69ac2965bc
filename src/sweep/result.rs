//! A run's result file (`runs/<hash>.json`): its parameters and either its summary or its
//! error. Its presence is what "finished" means: written whole (through a rename) once the run
//! ended, never for a run a signal stopped.

use super::{write_atomic, RunParams, RunSummary, SweepError};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One finished run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    /// The run's hash ([`RunParams::hash`]).
    pub hash: String,
    /// Its parameters.
    pub params: RunParams,
    /// The summary, when the run got to the end (completed, or stopped by its scene).
    pub summary: Option<RunSummary>,
    /// Why the run failed (the command's error message), when it did.
    pub error: Option<String>,
}

impl RunResult {
    /// True when the run failed.
    pub fn failed(&self) -> bool {
        self.error.is_some()
    }

    /// Reads a result file.
    pub fn read(path: &Path) -> Result<RunResult, SweepError> {
        let bad = |reason: String| SweepError::Result {
            path: path.to_path_buf(),
            reason,
        };
        let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
        serde_json::from_str(&text).map_err(|e| bad(format!("not a run result: {e}")))
    }

    /// Writes the file whole or not at all.
    pub fn write(&self, path: &Path) -> Result<(), SweepError> {
        let bad = |reason: String| SweepError::Result {
            path: path.to_path_buf(),
            reason,
        };
        let text = serde_json::to_string_pretty(self).map_err(|e| bad(e.to_string()))?;
        write_atomic(path, text.as_bytes()).map_err(|e| bad(e.to_string()))
    }
}
