//! `critterbox test`: run the script tests (`fn test_*()` in `scripts/tests/*.rhai`).

use anyhow::Context;
use clap::Args;
use critterbox::script::{Limits, ScriptOptions};
use critterbox::sweep::Shard;
use critterbox::testing::{
    discover, find_test_files, junit_xml, run_tests, TestOptions, TestOutcome,
};
use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `critterbox test`.
#[derive(Args, Debug)]
pub struct TestArgs {
    /// Test scripts or folders of them (default: scripts/tests).
    pub paths: Vec<PathBuf>,
    /// Run only the tests whose `file::name` contains this text (matching none is a failure).
    #[arg(long)]
    pub filter: Option<String>,
    /// Tests run at once (default: the number of cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Write JUnit XML here, for CI systems.
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
    /// Seconds one test may run before it fails.
    #[arg(long, default_value_t = 60)]
    pub timeout: u64,
    /// Rewrite the golden recordings that tests compare with (`expect_matches_recording`).
    #[arg(long)]
    pub bless: bool,
    /// Where failing tests' runs are recorded (default: recordings/test-failures; "none" to skip).
    #[arg(long, value_name = "DIR")]
    pub record_failures: Option<PathBuf>,
    /// Run only the I-th of N slices of the tests (I from 1; test k of the list, in file and
    /// name order, belongs to shard (k mod N) + 1), as `cargo nextest --partition count:I/N`.
    #[arg(long, value_name = "I/N", value_parser = parse_shard)]
    pub shard: Option<Shard>,
    /// Most operations one script call may run (endless-loop guard).
    #[arg(long, default_value_t = Limits::default().max_operations)]
    pub max_ops: u64,
}

/// Runs the tests; any failure is an error (non-zero exit) after every test has run.
pub fn run(args: &TestArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let paths = if args.paths.is_empty() {
        vec![PathBuf::from("scripts/tests")]
    } else {
        args.paths.clone()
    };
    let files = find_test_files(&paths)?;
    anyhow::ensure!(
        !files.is_empty(),
        "no test scripts in {}",
        show_paths(&paths)
    );
    let cases = discover(&files, args.filter.as_deref());
    if let (Some(filter), true) = (&args.filter, cases.is_empty()) {
        let all = discover(&files, None).len();
        anyhow::bail!(
            "--filter {filter:?} matches none of the {all} tests in {}: nothing ran",
            show_paths(&files)
        );
    }
    let cases = match args.shard {
        Some(shard) => {
            let all = cases.len();
            let mine = shard.select(cases);
            writeln!(out, "shard {shard}: {} of {all} tests", mine.len())?;
            mine
        }
        None => cases,
    };
    let options = TestOptions {
        script: ScriptOptions {
            limits: Limits {
                max_operations: args.max_ops,
                ..Limits::default()
            },
            ..ScriptOptions::default()
        },
        filter: args.filter.clone(),
        jobs: args.jobs.unwrap_or(TestOptions::default().jobs),
        timeout: Duration::from_secs(args.timeout),
        record_failures: match &args.record_failures {
            Some(dir) if dir.as_os_str() == "none" => None,
            Some(dir) => Some(dir.clone()),
            None => Some(critterbox::recording::path::default_dir().join("test-failures")),
        },
        bless: args.bless,
    };
    let mut report = |o: &TestOutcome| {
        let ms = o.duration.as_secs_f64() * 1e3;
        let _ = match &o.failure {
            None => writeln!(out, "ok     {} ({ms:.0} ms)", o.case.id()),
            Some(f) => writeln!(
                out,
                "FAIL   {} ({ms:.0} ms)\n       {}",
                o.case.id(),
                f.to_string().replace('\n', "\n       ")
            ),
        };
    };
    let outcomes = run_tests(&cases, &options, &mut report);
    let failed = outcomes.iter().filter(|o| o.failure.is_some()).count();
    let passed = outcomes.len() - failed;
    if let Some(path) = &args.junit {
        std::fs::write(path, junit_xml(&outcomes))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    writeln!(out, "{passed} passed, {failed} failed")?;
    anyhow::ensure!(
        failed == 0,
        "{failed} script test{} failed",
        if failed == 1 { "" } else { "s" }
    );
    Ok(())
}

fn parse_shard(s: &str) -> Result<Shard, String> {
    s.parse().map_err(|e: critterbox::sweep::SweepError| {
        e.to_string()
            .trim_start_matches(&format!("--shard {s}: "))
            .to_string()
    })
}

fn show_paths(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}
