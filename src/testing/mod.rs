//! Script-driven tests (`scripts/tests/*.rhai`): every `fn test_*()` is a test.
//!
//! [`discover`] lists the tests of the files [`find_test_files`] finds; [`run_tests`] runs them
//! on worker threads, each in a fresh runtime (rhai engines are not shared across threads) whose
//! engine also has the test API (`asserts.rs`; the test's world, `world.rs`); each test's run is
//! recorded and kept if it fails (`record.rs`), and what it prints is kept with its outcome
//! (`output.rs`); [`junit_xml`] reports for CI systems. This layer
//! sits above scripts and recordings: it adds its functions to a runtime through the script
//! layer's extension point, and keeps its own state.

mod asserts;
mod discover;
mod junit;
mod output;
mod record;
mod run;
mod world;

pub use discover::{discover, find_test_files};
pub use junit::junit_xml;
pub use run::{run_one, run_tests};

use crate::error::ScriptError;
use crate::script::ScriptOptions;
use std::path::PathBuf;
use std::time::Duration;

/// One test found in a test script.
#[derive(Clone, Debug, PartialEq)]
pub struct TestCase {
    /// The script file.
    pub file: PathBuf,
    /// The function's name (`test_...`); empty for a file that does not compile.
    pub name: String,
}

impl TestCase {
    /// `file::name`, as printed.
    pub fn id(&self) -> String {
        if self.name.is_empty() {
            self.file.display().to_string()
        } else {
            format!("{}::{}", self.file.display(), self.name)
        }
    }
}

/// How a test ended.
#[derive(Clone, Debug, PartialEq)]
pub struct TestOutcome {
    /// The test.
    pub case: TestCase,
    /// `None` when it passed; the located failure otherwise.
    pub failure: Option<ScriptError>,
    /// How long it ran.
    pub duration: Duration,
    /// What it printed: the `print`, `debug` and `log` lines of the test, its scene and its
    /// kinds' hooks, in order; a line logged in a step is prefixed `[step k]`, as `run` prints
    /// it. At most [`MAX_OUTPUT_LINES`] are kept, then a line saying how many more there were.
    pub output: Vec<String>,
}

/// The most output lines kept of one test: a test that logs in every hook of a big world
/// would otherwise hold them all in memory.
pub const MAX_OUTPUT_LINES: usize = 10_000;

/// Settings for a test run.
#[derive(Clone, Debug)]
pub struct TestOptions {
    /// Limits and paths, as for scenes.
    pub script: ScriptOptions,
    /// Only tests whose `file::name` contains this.
    pub filter: Option<String>,
    /// Worker threads.
    pub jobs: usize,
    /// Wall-clock limit per test.
    pub timeout: Duration,
    /// Record each test's run here (`<dir>/<file>-<test>.mcap`), kept only when it fails.
    pub record_failures: Option<PathBuf>,
    /// Rewrite golden recordings instead of comparing with them.
    pub bless: bool,
}

impl Default for TestOptions {
    fn default() -> Self {
        TestOptions {
            script: ScriptOptions::default(),
            filter: None,
            jobs: std::thread::available_parallelism().map_or(1, |n| n.get()),
            timeout: Duration::from_secs(60),
            record_failures: None,
            bless: false,
        }
    }
}
