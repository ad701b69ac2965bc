//! Running a sweep's runs on this machine: a pool of `--jobs` workers, each starting one child
//! `critterbox run` at a time; a progress bar of done, failed and left; no result for a run a
//! signal stopped (`signals`).

use super::{finished, plan, result_path, signals, write_table, Planned, SweepArgs};
use crate::commands::record;
use anyhow::Context;
use critterbox::sweep::{RunResult, RunSummary, SweepFile};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::Write;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;

/// A sweep stopped by a signal: `main` exits with 128 + its number, as `run` does.
#[derive(Debug)]
pub struct Interrupted {
    /// The signal's number.
    pub signal: i32,
    /// Runs finished before it came.
    pub done: usize,
    /// Runs left to do.
    pub left: usize,
}

impl Interrupted {
    /// The exit code.
    pub fn exit_code(&self) -> u8 {
        u8::try_from(128 + self.signal).unwrap_or(1)
    }
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "sweep interrupted by {} with {} runs done and {} left; run the same command again to do the rest",
            record::signal_name(self.signal),
            self.done,
            self.left
        )
    }
}

impl std::error::Error for Interrupted {}

/// How one run ended, as a worker reports it.
enum Ended {
    Ok,
    Failed,
    /// Stopped by the sweep's signal: no result written.
    Stopped,
}

/// Runs what is missing of the sweep (or of its shard), then writes the table.
pub fn run(
    file: &SweepFile,
    dir: &Path,
    args: &SweepArgs,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.shard.is_none() || args.plot.is_none(),
        "--plot draws the whole table: run the shards, then critterbox sweep FILE --collect DIR --plot ..."
    );
    let all = plan(file);
    let mine = match args.shard {
        Some(s) => s.select(all.iter().cloned()),
        None => all.clone(),
    };
    let (done, todo): (Vec<Planned>, Vec<Planned>) = mine.iter().cloned().partition(|r| {
        finished(dir, &r.hash).is_some_and(|res| !(args.retry_failed && res.failed()))
    });
    for sub in ["runs", "tmp"] {
        let d = dir.join(sub);
        std::fs::create_dir_all(&d).with_context(|| format!("creating {}", d.display()))?;
    }
    let jobs = args.jobs.map_or_else(
        || std::thread::available_parallelism().map_or(1, |n| n.get()),
        |j| j as usize,
    );
    let shard = args
        .shard
        .map_or(String::new(), |s| format!(", shard {s} has {}", mine.len()));
    writeln!(
        out,
        "sweep        {}: {} runs{shard}; {} done already, {} to run ({jobs} at once)",
        file.path.display(),
        all.len(),
        done.len(),
        todo.len()
    )?;
    out.flush()?;
    signals::watch();
    let (ok, failed, stopped) = execute(file, dir, &todo, jobs)?;
    writeln!(
        out,
        "runs         {ok} ok, {failed} failed, {stopped} not run"
    )?;
    if args.shard.is_none() {
        write_table(file, &all, &[dir.to_path_buf()], dir, args, out)?;
    } else {
        writeln!(
            out,
            "collect      critterbox sweep {} --collect {} (once every shard is done)",
            file.path.display(),
            dir.display()
        )?;
    }
    if let Some(signal) = signals::interrupted() {
        return Err(Interrupted {
            signal,
            done: done.len() + ok + failed,
            left: stopped,
        }
        .into());
    }
    let failed_in_all = mine
        .iter()
        .filter(|r| finished(dir, &r.hash).is_some_and(|res| res.failed()))
        .count();
    anyhow::ensure!(
        failed_in_all == 0,
        "{failed_in_all} of {} runs failed; their rows carry the error (--retry-failed runs them again)",
        mine.len()
    );
    Ok(())
}

/// Runs `todo` with `jobs` workers; gives (ok, failed, not run).
fn execute(
    file: &SweepFile,
    dir: &Path,
    todo: &[Planned],
    jobs: usize,
) -> anyhow::Result<(usize, usize, usize)> {
    let exe = std::env::current_exe().context("finding the critterbox executable")?;
    let next = AtomicUsize::new(0);
    let (tx, rx) = mpsc::channel::<Ended>();
    let bar = progress_bar(todo.len());
    let (mut ok, mut failed) = (0, 0);
    std::thread::scope(|scope| {
        for _ in 0..jobs.min(todo.len()) {
            let tx = tx.clone();
            let (next, exe) = (&next, &exe);
            scope.spawn(move || loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(run) = todo.get(i) else { break };
                let ended = run_one(exe, file, dir, run);
                if matches!(ended, Ended::Stopped) || tx.send(ended).is_err() {
                    break;
                }
            });
        }
        drop(tx);
        for ended in rx {
            match ended {
                Ended::Ok => ok += 1,
                Ended::Failed => failed += 1,
                Ended::Stopped => {}
            }
            bar.set_position((ok + failed) as u64);
            bar.set_message(format!(
                "{ok} ok, {failed} failed, {} left",
                todo.len() - ok - failed
            ));
        }
    });
    bar.finish_and_clear();
    // Runs a signal stopped, or never started, are not run.
    Ok((ok, failed, todo.len() - ok - failed))
}

/// Runs one child to its end and writes its result (none when the sweep's signal stopped it).
fn run_one(exe: &Path, file: &SweepFile, dir: &Path, run: &Planned) -> Ended {
    let summary_path = dir.join("tmp").join(format!("{}.summary.json", run.hash));
    let _ = std::fs::remove_file(&summary_path);
    let mut cmd = Command::new(exe);
    cmd.args(run.params.run_args(&file.scene_arg()));
    if file.record {
        cmd.arg("--record")
            .arg(dir.join("runs").join(format!("{}.mcap", run.hash)));
    } else {
        cmd.arg("--no-record");
    }
    cmd.arg("--summary-json").arg(&summary_path);
    // One thread per run: runs, not threads, fill the machine (a run's bits do not depend on it).
    cmd.env("RAYON_NUM_THREADS", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        // Its own process group: signals reach it through the sweep alone (`signals`).
        .process_group(0);
    let child = match signals::spawn(&mut cmd) {
        None => return Ended::Stopped,
        Some(Ok(child)) => child,
        Some(Err(e)) => {
            return write(
                dir,
                run,
                None,
                Some(format!("starting {}: {e}", exe.display())),
            )
        }
    };
    let pid = child.id();
    let output = child.wait_with_output();
    signals::forget(pid);
    let output = match output {
        Ok(o) => o,
        Err(e) => return write(dir, run, None, Some(format!("waiting for the run: {e}"))),
    };
    if output.status.success() {
        let summary = std::fs::read_to_string(&summary_path)
            .map_err(|e| e.to_string())
            .and_then(|t| serde_json::from_str::<RunSummary>(&t).map_err(|e| e.to_string()));
        let _ = std::fs::remove_file(&summary_path);
        return match summary {
            Ok(s) => write(dir, run, Some(s), None),
            Err(e) => write(dir, run, None, Some(format!("the run's summary: {e}"))),
        };
    }
    if signals::interrupted().is_some() {
        return Ended::Stopped;
    }
    write(dir, run, None, Some(error_text(&output)))
}

/// The child's error: its `error:` lines, or how it ended.
fn error_text(output: &std::process::Output) -> String {
    use std::os::unix::process::ExitStatusExt;
    let stderr = String::from_utf8_lossy(&output.stderr);
    // The last `error:` line and what follows it (hints), as `main` prints it.
    let at = stderr
        .rfind("\nerror: ")
        .map(|i| i + 1)
        .or_else(|| stderr.starts_with("error: ").then_some(0));
    if let Some(at) = at {
        return stderr[at + "error: ".len()..].trim().to_string();
    }
    let how = match (output.status.code(), output.status.signal()) {
        (Some(code), _) => format!("exit code {code}"),
        (None, Some(sig)) => format!("killed by signal {sig}"),
        _ => "ended abnormally".to_string(),
    };
    let tail: Vec<&str> = stderr.lines().rev().take(3).collect();
    let tail: Vec<&str> = tail.into_iter().rev().collect();
    format!(
        "{how}{}{}",
        if tail.is_empty() { "" } else { ": " },
        tail.join(" / ")
    )
}

fn write(dir: &Path, run: &Planned, summary: Option<RunSummary>, error: Option<String>) -> Ended {
    let failed = error.is_some();
    let result = RunResult {
        hash: run.hash.clone(),
        params: run.params.clone(),
        summary,
        error,
    };
    let path: PathBuf = result_path(dir, &run.hash);
    if let Err(e) = result.write(&path) {
        eprintln!("warning: {e} (the run will be done again)");
        return Ended::Failed;
    }
    if failed {
        Ended::Failed
    } else {
        Ended::Ok
    }
}

fn progress_bar(runs: usize) -> ProgressBar {
    let bar =
        ProgressBar::with_draw_target(Some(runs as u64), ProgressDrawTarget::stderr_with_hz(4));
    bar.set_style(
        ProgressStyle::with_template("{spinner} runs {pos}/{len} [{bar:30}] {msg} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar
}
