//! What can be wrong with a sweep file, a shard or a run's result.

use std::path::PathBuf;

/// A sweep that cannot start, or a result that cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// The sweep file cannot be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not valid TOML, or a key is unknown or has the wrong type (the message names
    /// the line and column).
    #[error("{}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// The parser's message, with line, column and the offending text.
        message: String,
    },
    /// A key's value is out of range or contradicts another.
    #[error("{}: {key}: {reason}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The key (`axes.dt`, `set.SPEED`).
        key: String,
        /// What is wrong and what to do.
        reason: String,
    },
    /// A `--shard I/N` that names no shard.
    #[error("--shard {spec}: {reason}")]
    Shard {
        /// What was given.
        spec: String,
        /// What is wrong and what to write.
        reason: String,
    },
    /// A run's result file that cannot be read.
    #[error("{}: {reason}", path.display())]
    Result {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}
