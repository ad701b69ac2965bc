//! `critterbox sweep` as users meet it: the table's rows, resuming, failed runs, shards and
//! collecting, the scheduler files, plots, signals, and `critterbox test --shard`.

use crate::common;
use common::{critterbox, critterbox_in, text, ROOT};

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant, SystemTime};

fn tmp(name: &str) -> PathBuf {
    common::tmp_in("sweep-tests", name)
}

/// Two methods by two seeds on a small built-in gas: four runs of a few milliseconds.
const SMALL: &str = "scene = \"gas\"\nn = 20\nsteps = 50\n[axes]\nmethod = [\"discrete\", \"event\"]\nseed = [1, 2]\n";

fn write_sweep(dir: &Path, text: &str) -> PathBuf {
    let file = dir.join("sweep.toml");
    std::fs::write(&file, text).expect("write sweep file");
    file
}

fn sweep(dir: &Path, args: &[&str]) -> Output {
    let mut all = vec!["sweep"];
    all.extend_from_slice(args);
    critterbox_in(dir, &all)
}

/// The table as rows of (column, cell) maps.
fn table(path: &Path) -> Vec<Vec<(String, String)>> {
    let text = std::fs::read_to_string(path).expect("results.csv");
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .expect("header")
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| header.iter().cloned().zip(split_csv(l)).collect())
        .collect()
}

/// A CSV line's cells (quoted cells may hold commas).
fn split_csv(line: &str) -> Vec<String> {
    let (mut cells, mut cell, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cell.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => cells.push(std::mem::take(&mut cell)),
            _ => cell.push(c),
        }
    }
    cells.push(cell);
    cells
}

fn cell<'a>(row: &'a [(String, String)], column: &str) -> &'a str {
    row.iter()
        .find(|(c, _)| c == column)
        .map(|(_, v)| v.as_str())
        .unwrap_or_else(|| panic!("no column {column} in {row:?}"))
}

/// The rows without the wall time, which differs from run to run.
fn comparable(rows: &[Vec<(String, String)>]) -> Vec<Vec<(String, String)>> {
    rows.iter()
        .map(|r| r.iter().filter(|(c, _)| c != "wall_s").cloned().collect())
        .collect()
}

#[test]
fn a_small_sweep_gives_one_row_per_run_with_the_hash_of_a_plain_run() {
    let dir = tmp("small");
    let file = write_sweep(&dir, SMALL);
    let o = sweep(
        &dir,
        &[file.to_str().unwrap(), "--out", "out", "--jobs", "2"],
    );
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("4 runs; 0 done already, 4 to run"),
        "{}",
        text(&o)
    );
    let rows = table(&dir.join("out/results.csv"));
    assert_eq!(rows.len(), 4);
    let order: Vec<(&str, &str)> = rows
        .iter()
        .map(|r| (cell(r, "method"), cell(r, "seed")))
        .collect();
    assert_eq!(
        order,
        [
            ("discrete", "1"),
            ("discrete", "2"),
            ("event", "1"),
            ("event", "2")
        ]
    );
    for row in &rows {
        assert_eq!(cell(row, "outcome"), "completed");
        assert_eq!(cell(row, "steps_done"), "50");
        assert!(cell(row, "collisions").parse::<u64>().is_ok());
        let hash = cell(row, "hash");
        assert!(dir.join(format!("out/runs/{hash}.mcap")).is_file());
        // The same run alone, on every thread, ends in the same state.
        let alone = critterbox_in(
            &dir,
            &[
                "run",
                "gas",
                "-n",
                "20",
                "--steps",
                "50",
                "--seed",
                cell(row, "seed"),
                "--method",
                cell(row, "method"),
                "--no-record",
            ],
        );
        let printed = text(&alone);
        assert!(
            printed.contains(&format!("state hash   {}", cell(row, "state_hash"))),
            "{printed}\n{row:?}"
        );
    }
}

fn mtimes(dir: &Path) -> Vec<(PathBuf, SystemTime)> {
    let mut v: Vec<_> = std::fs::read_dir(dir.join("runs"))
        .expect("runs/")
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "json"))
        .map(|e| {
            (
                e.path(),
                e.metadata().and_then(|m| m.modified()).expect("mtime"),
            )
        })
        .collect();
    v.sort();
    v
}

#[test]
fn a_rerun_does_only_what_is_missing() {
    let dir = tmp("resume");
    let file = write_sweep(&dir, SMALL);
    let f = file.to_str().unwrap();
    assert!(sweep(&dir, &[f, "--out", "out"]).status.success());
    let before = mtimes(&dir.join("out"));
    assert_eq!(before.len(), 4);
    let o = sweep(&dir, &[f, "--out", "out"]);
    assert!(o.status.success());
    assert!(
        text(&o).contains("4 done already, 0 to run"),
        "{}",
        text(&o)
    );
    assert_eq!(mtimes(&dir.join("out")), before, "nothing ran again");
    // One result gone: that run alone is done again.
    std::fs::remove_file(&before[1].0).expect("remove");
    std::thread::sleep(Duration::from_millis(20));
    let o = sweep(&dir, &[f, "--out", "out"]);
    assert!(
        text(&o).contains("3 done already, 1 to run"),
        "{}",
        text(&o)
    );
    let after = mtimes(&dir.join("out"));
    assert_eq!(after.len(), 4);
    for (i, (a, b)) in before.iter().zip(&after).enumerate() {
        assert_eq!(a.0, b.0);
        assert_eq!(a.1 == b.1, i != 1, "only the removed run is rewritten");
    }
    assert_eq!(table(&dir.join("out/results.csv")).len(), 4);
}

#[test]
fn a_failing_run_is_a_row_with_its_error_and_the_sweep_goes_on() {
    let dir = tmp("failing");
    let scene = Path::new(ROOT).join("scripts/tests/scenes/vars_score.rhai");
    let file = write_sweep(
        &dir,
        &format!(
            "scene = {:?}\nsteps = 30\n[axes.set]\nN = [3, \"many\"]\n",
            scene.to_str().unwrap()
        ),
    );
    let o = sweep(&dir, &[file.to_str().unwrap(), "--out", "out"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("1 of 2 runs failed"), "{}", text(&o));
    let rows = table(&dir.join("out/results.csv"));
    assert_eq!(rows.len(), 2);
    assert_eq!(cell(&rows[0], "outcome"), "completed");
    assert_eq!(cell(&rows[0], "error"), "");
    // What the scene's scripts keep in world().vars is collected too.
    assert_eq!(cell(&rows[0], "vars.steps"), "30");
    assert_eq!(cell(&rows[0], "vars.name"), "score");
    assert_eq!(cell(&rows[1], "outcome"), "error");
    assert!(
        cell(&rows[1], "error").contains("vars_score.rhai"),
        "{:?}",
        rows[1]
    );
    // A failed run counts as finished; --retry-failed runs it again.
    let o = sweep(&dir, &[file.to_str().unwrap(), "--out", "out"]);
    assert!(text(&o).contains("0 to run"), "{}", text(&o));
    let o = sweep(
        &dir,
        &[file.to_str().unwrap(), "--out", "out", "--retry-failed"],
    );
    assert!(
        text(&o).contains("1 done already, 1 to run"),
        "{}",
        text(&o)
    );
}

#[test]
fn shards_collected_give_the_table_of_the_whole_sweep() {
    let dir = tmp("shards");
    let file = write_sweep(&dir, SMALL);
    let f = file.to_str().unwrap();
    assert!(sweep(&dir, &[f, "--out", "full"]).status.success());
    for (shard, out) in [("1/2", "a"), ("2/2", "b")] {
        let o = sweep(&dir, &[f, "--out", out, "--shard", shard]);
        assert!(o.status.success(), "{}", text(&o));
        assert!(
            text(&o).contains("shard ") && text(&o).contains(" has 2"),
            "{}",
            text(&o)
        );
    }
    // One shard alone is not the whole sweep: collecting it says what is missing.
    let o = sweep(&dir, &[f, "--collect", "a"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("2 of 4 runs have no result"),
        "{}",
        text(&o)
    );
    let o = sweep(&dir, &[f, "--collect", "a", "b", "--out", "all"]);
    assert!(o.status.success(), "{}", text(&o));
    let full = table(&dir.join("full/results.csv"));
    let collected = table(&dir.join("all/results.csv"));
    assert_eq!(comparable(&collected), comparable(&full));
    // Shard 1/2 holds runs 0 and 2: run k goes to shard (k mod N) + 1.
    let a: BTreeSet<String> = table(&dir.join("a/results.csv"))
        .iter()
        .map(|r| cell(r, "run").to_string())
        .collect();
    assert_eq!(a, BTreeSet::from(["0".to_string(), "2".to_string()]));
}

#[test]
fn bad_shards_and_bad_files_are_clear_errors() {
    let dir = tmp("bad");
    let file = write_sweep(&dir, SMALL);
    let f = file.to_str().unwrap();
    for bad in ["0/2", "3/2", "1/0", "one/2"] {
        let o = sweep(&dir, &[f, "--out", "out", "--shard", bad]);
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", text(&o));
        assert!(text(&o).contains(bad), "{}", text(&o));
    }
    let o = sweep(&dir, &[f, "--out", "out", "--shard", "3/2"]);
    assert!(text(&o).contains("between 1 and 2"), "{}", text(&o));
    let file = write_sweep(&dir, "scene = \"gas\"\n[axes]\nspeed = [1, 2]\n");
    let o = sweep(&dir, &[file.to_str().unwrap(), "--out", "out"]);
    assert_eq!(o.status.code(), Some(1));
    let t = text(&o);
    assert!(
        t.contains("sweep.toml") && t.contains("line 3") && t.contains("speed"),
        "{t}"
    );
    assert!(!t.contains("panicked"), "{t}");
}

#[test]
fn emitted_jobs_run_one_shard_per_task() {
    let dir = tmp("emit");
    let file = write_sweep(&dir, SMALL);
    let f = file.to_str().unwrap();
    let o = sweep(
        &dir,
        &[
            f, "--out", "out", "--emit", "slurm", "--shards", "2", "--cpus", "2",
        ],
    );
    assert!(o.status.success(), "{}", text(&o));
    let script = std::fs::read_to_string(dir.join("out/sweep.sbatch")).expect("sbatch file");
    for needle in [
        "#!/bin/bash",
        "#SBATCH --array=1-2",
        "#SBATCH --cpus-per-task=2",
        "--shard \"${SLURM_ARRAY_TASK_ID}/2\"",
        "--collect",
    ] {
        assert!(script.contains(needle), "{needle}:\n{script}");
    }
    let o = sweep(&dir, &[f, "--out", "out", "--emit", "k8s", "--shards", "3"]);
    assert!(o.status.success(), "{}", text(&o));
    let yaml = std::fs::read_to_string(dir.join("out/sweep-job.yaml")).expect("job file");
    for needle in [
        "kind: Job",
        "completionMode: Indexed",
        "completions: 3",
        "$((JOB_COMPLETION_INDEX + 1))/3",
        "--out",
    ] {
        assert!(yaml.contains(needle), "{needle}:\n{yaml}");
    }
    assert!(!dir.join("out/runs").exists(), "emitting runs nothing");
}

#[test]
fn plot_draws_a_chart_from_the_table() {
    let dir = tmp("plot");
    let file = write_sweep(&dir, SMALL);
    let f = file.to_str().unwrap();
    let o = sweep(
        &dir,
        &[f, "--out", "out", "--plot", "seed:collisions:method"],
    );
    assert!(o.status.success(), "{}", text(&o));
    let svg = std::fs::read_to_string(dir.join("out/plot-seed-collisions.svg")).expect("svg");
    assert!(svg.contains("<svg") && svg.contains("discrete") && svg.contains("event"));
    assert!(
        std::fs::metadata(dir.join("out/plot-seed-collisions.png"))
            .expect("png")
            .len()
            > 1000
    );
    let o = sweep(&dir, &[f, "--collect", "out", "--plot", "seed:speed"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("no column 'speed'"), "{}", text(&o));
}

#[test]
fn sigterm_stops_the_sweep_with_no_result_half_written() {
    let dir = tmp("sigterm");
    let file = write_sweep(
        &dir,
        "scene = \"gas\"\nn = 20\nsteps = 100000000\n[axes]\nseed = [1, 2, 3]\n",
    );
    let child = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args([
            "sweep",
            file.to_str().unwrap(),
            "--out",
            "out",
            "--jobs",
            "2",
        ])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let start = Instant::now();
    let recordings = || {
        std::fs::read_dir(dir.join("out/runs")).map_or(0, |d| {
            d.filter_map(|e| e.ok())
                .filter(|e| e.metadata().is_ok_and(|m| m.len() > 0))
                .count()
        })
    };
    while recordings() < 2 {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the runs never started"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(300));
    let sent = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(sent.success());
    let o = child.wait_with_output().expect("wait");
    assert_eq!(o.status.code(), Some(143), "{}", text(&o));
    assert!(text(&o).contains("interrupted by SIGTERM"), "{}", text(&o));
    let results = std::fs::read_dir(dir.join("out/runs"))
        .expect("runs")
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "json"))
        .count();
    assert_eq!(
        results, 0,
        "a stopped run leaves no result: it is done again next time"
    );
}

/// The tests `critterbox test` ran, by `file::name`.
fn tests_run(o: &Output) -> Vec<String> {
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter_map(|l| {
            l.strip_prefix("ok     ")
                .or_else(|| l.strip_prefix("FAIL   "))
        })
        .map(|l| l.split(" (").next().unwrap_or(l).to_string())
        .collect()
}

#[test]
fn test_shards_run_every_test_exactly_once() {
    let files = ["scripts/tests/vars.rhai", "scripts/tests/spawning.rhai"];
    let run = |shard: Option<&str>| {
        let mut args = vec!["test", "--record-failures", "none"];
        args.extend(files);
        if let Some(s) = shard {
            args.extend(["--shard", s]);
        }
        let o = critterbox(&args);
        assert!(o.status.success(), "{}", text(&o));
        tests_run(&o)
    };
    let all = run(None);
    let (a, b) = (run(Some("1/2")), run(Some("2/2")));
    assert!(!a.is_empty() && !b.is_empty());
    let mut both: Vec<String> = a.iter().chain(&b).cloned().collect();
    both.sort();
    let mut all_sorted = all.clone();
    all_sorted.sort();
    assert_eq!(
        both, all_sorted,
        "every test once, in one shard or the other"
    );
    let o = critterbox(&["test", "scripts/tests/vars.rhai", "--shard", "0/2"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
}
