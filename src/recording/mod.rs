//! Recordings: every run written to one MCAP file that holds everything needed to rerun it and
//! everything needed to look at it. The format is documented for readers in
//! `docs/recording-format.md`.
//!
//! - **Self-contained.** A `critterbox` metadata record says how the run was made (scene, seed,
//!   dt, parameters, `--set` values, limits, command line); every script is an attachment.
//!   [`rebuild`] makes the scene again from the file alone.
//! - **Every step checked, full states when cheap.** Each step gets its state hash, totals and
//!   events; full states (columnar JSON) are written every step for small scenes and every K
//!   steps otherwise ([`keyframes`]). Runs are deterministic, so [`replay`] shows any step
//!   exactly by re-simulating, and [`verify`] proves a file by re-simulating all of it.
//! - **Off the simulation thread.** [`writer::Recorder`] captures on the simulation thread and
//!   encodes and compresses on its own thread.
//! - **Crash safe.** Chunks are closed every few hundred milliseconds; [`reader`] walks the file
//!   record by record ([`scan`]), so cut-off files read up to their last complete chunk, a
//!   damaged chunk loses only itself, and [`recover`] rewrites what is left whole.

pub mod capture;
pub mod compare;
pub mod diff;
mod error;
pub mod export;
pub mod foxglove;
pub mod keyframes;
pub mod meta;
pub mod path;
pub mod reader;
pub mod rebuild;
pub mod recover;
pub mod replay;
pub mod scan;
pub mod schema;
pub mod story;
pub mod verify;
pub mod writer;

pub use error::RecordingError;
pub use meta::{EndMeta, RunMeta, RunOverrides, SceneSource, SETUP_FAILED};
pub use reader::Recording;
pub use writer::{write_failed_setup, Recorder, Written};
