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
#[command(after_help = "\
Exit codes: 0 every test passed; 1 a test failed, or there was nothing to run (a path that is not \
there, no test files, no fn test_*() in them, a --filter that matches none); 2 bad arguments.")]
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
    /// Print every test's output (its `print`, `debug` and `log` lines, and its kinds' and
    /// scene's), passing or failing, under the test's name; a failing test's is printed always.
    #[arg(long)]
    pub show_output: bool,
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
    /// After the run, watch the test files and the kind and scene files beside them: an edit
    /// re-runs the tests it affects (a test file's own tests; for a kind or scene file, the
    /// tests of the files that name it, or all when none does). Ctrl-C stops.
    #[arg(long)]
    pub watch: bool,
}

/// Runs the tests; any failure is an error (non-zero exit) after every test has run, and so is
/// finding nothing to run (no such path, no test files, no tests in them, a filter that
/// matches none): a run that tested nothing must not pass.
pub fn run(args: &TestArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let paths = if args.paths.is_empty() {
        vec![PathBuf::from("scripts/tests")]
    } else {
        args.paths.clone()
    };
    let missing: Vec<PathBuf> = paths.iter().filter(|p| !p.exists()).cloned().collect();
    if !missing.is_empty() {
        anyhow::bail!(
            "nothing to run: {} {} not there (in {}); {LOOKS_FOR}",
            show_paths(&missing),
            if missing.len() == 1 { "is" } else { "are" },
            here()
        );
    }
    let files = find_test_files(&paths)?;
    anyhow::ensure!(
        !files.is_empty(),
        "nothing to run: no test scripts (*.rhai) in {} (in {}); {LOOKS_FOR}",
        show_paths(&paths),
        here()
    );
    let cases = discover(&files, args.filter.as_deref());
    if args.filter.is_none() && cases.is_empty() {
        anyhow::bail!(
            "nothing to run: no tests in {} (in {}): a test is a function named test_... \
             that takes no parameters, e.g. `fn test_ball_bounces() {{ ... }}`",
            show_paths(&files),
            here()
        );
    }
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
    let failed = run_cases(
        &cases,
        &options,
        args.junit.as_deref(),
        args.show_output,
        out,
    )?;
    if args.watch {
        return watch_tests(args, &files, &options, out);
    }
    anyhow::ensure!(
        failed == 0,
        "{failed} script test{} failed",
        if failed == 1 { "" } else { "s" }
    );
    Ok(())
}

/// Runs `cases`, printing a line per test and the totals (and JUnit XML to `junit`); a failing
/// test's output follows its line, and every test's under `show_output`. Returns how many
/// failed.
fn run_cases(
    cases: &[critterbox::testing::TestCase],
    options: &TestOptions,
    junit: Option<&std::path::Path>,
    show_output: bool,
    out: &mut dyn Write,
) -> anyhow::Result<usize> {
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
        if (show_output || o.failure.is_some()) && !o.output.is_empty() {
            // Grouped under the test's name, as `cargo test` prints a test's stdout.
            let _ = writeln!(out, "---- {} output ----", o.case.id());
            for line in &o.output {
                let _ = writeln!(out, "{line}");
            }
        }
    };
    let outcomes = run_tests(cases, options, &mut report);
    let failed = outcomes.iter().filter(|o| o.failure.is_some()).count();
    let passed = outcomes.len() - failed;
    if let Some(path) = junit {
        std::fs::write(path, junit_xml(&outcomes))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    writeln!(out, "{passed} passed, {failed} failed")?;
    out.flush()?;
    Ok(failed)
}

/// `test --watch`: waits for edits of the test files and the script files beside them, and
/// re-runs the tests each edit affects, until a stop signal.
fn watch_tests(
    args: &TestArgs,
    files: &[PathBuf],
    options: &TestOptions,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    super::record::watch_signals();
    let mut watch = super::watch::Watch::new()?;
    let watched = beside(files);
    watch.add(&watched)?;
    loop {
        eprintln!(
            "test --watch: watching {} script files; an edit re-runs the tests it affects (Ctrl-C to stop)",
            watch.len()
        );
        let Some(changed) = watch.wait() else {
            eprintln!("test --watch: stopped");
            return Ok(());
        };
        let changed: Vec<String> = changed.into_iter().map(|(file, _)| file).collect();
        let affected = affected(files, &changed);
        let mut cases = discover(&affected, args.filter.as_deref());
        if let Some(shard) = args.shard {
            cases = shard.select(cases);
        }
        writeln!(
            out,
            "-- {} changed: {} tests in {}",
            changed.join(", "),
            cases.len(),
            show_paths(&affected)
        )?;
        run_cases(
            &cases,
            options,
            args.junit.as_deref(),
            args.show_output,
            out,
        )?;
    }
}

/// The test files, and the script files a test may load beside them: each test folder's own,
/// its `kinds/` and `scenes/`, those of its parent (`../kinds`, `../scenes`), and
/// `scripts/kinds`.
fn beside(files: &[PathBuf]) -> Vec<critterbox::scenes::SourceFile> {
    let mut dirs = std::collections::BTreeSet::new();
    dirs.insert(PathBuf::from("scripts/kinds"));
    for f in files {
        let dir = f.parent().unwrap_or(std::path::Path::new("."));
        for d in [dir.to_path_buf(), dir.join("kinds"), dir.join("scenes")] {
            dirs.insert(d);
        }
        if let Some(up) = dir.parent() {
            dirs.insert(up.join("kinds"));
            dirs.insert(up.join("scenes"));
        }
    }
    let mut paths: std::collections::BTreeSet<PathBuf> = files.iter().cloned().collect();
    for d in dirs {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.extension().is_some_and(|x| x == "rhai") {
                paths.insert(p);
            }
        }
    }
    paths
        .into_iter()
        .map(|p| critterbox::scenes::SourceFile {
            path: p.display().to_string(),
            text: String::new(),
        })
        .collect()
}

/// The test files an edit of `changed` affects: a changed test file itself; for any other
/// script, the test files whose text names it (its file name, or its stem in quotes, as kinds
/// and scenes are named), directly or through a scene file that names it; all of them when
/// none does.
fn affected(files: &[PathBuf], changed: &[String]) -> Vec<PathBuf> {
    let same =
        |f: &PathBuf, c: &str| std::fs::canonicalize(f).ok() == std::fs::canonicalize(c).ok();
    let text = |p: &std::path::Path| std::fs::read_to_string(p).unwrap_or_default();
    let names = |c: &str, t: &str| {
        let p = std::path::Path::new(c);
        let stem = p.file_stem().map(|s| s.to_string_lossy().into_owned());
        let name = p.file_name().map(|s| s.to_string_lossy().into_owned());
        stem.is_some_and(|s| t.contains(&format!("\"{s}\"")))
            || name.is_some_and(|n| t.contains(&n))
    };
    let mut out = Vec::new();
    for f in files {
        let t = text(f);
        let hit = changed.iter().any(|c| {
            same(f, c) || names(c, &t) || scenes_named(f, &t).iter().any(|s| names(c, &text(s)))
        });
        if hit {
            out.push(f.clone());
        }
    }
    if out.is_empty() {
        return files.to_vec();
    }
    out
}

/// The scene files a test file's text names (by file name, beside it or in `../scenes`).
fn scenes_named(test: &std::path::Path, text: &str) -> Vec<PathBuf> {
    let dir = test.parent().unwrap_or(std::path::Path::new("."));
    let mut found = Vec::new();
    for d in [dir.join("scenes"), dir.join("../scenes"), dir.to_path_buf()] {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            let named = p
                .file_name()
                .is_some_and(|n| text.contains(&*n.to_string_lossy()));
            if p.extension().is_some_and(|x| x == "rhai") && named && p != test {
                found.push(p);
            }
        }
    }
    found
}

/// What `critterbox test` runs, for the errors that found nothing to run.
const LOOKS_FOR: &str =
    "critterbox test runs every fn test_*() in the .rhai files it is given, or \
    in those of the folders it is given (default: scripts/tests, relative to where it runs); give \
    test files or folders, or run it in the project's root";

/// The working directory, which relative paths are read from.
fn here() -> String {
    std::env::current_dir().map_or_else(|_| ".".to_string(), |d| d.display().to_string())
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
