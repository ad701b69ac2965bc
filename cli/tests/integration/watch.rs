//! `run --watch` as users meet it: a kind file edited while the run goes on is reloaded at a
//! step boundary (and recorded, so `replay --verify` passes and `inspect` lists it), a broken
//! edit is reported while the old kind runs on, and an edited scene file runs the scene again.

use crate::common;

use critterbox::recording::verify::verify;
use critterbox::recording::Recording;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

const KIND: &str =
    "defaults(#{ radius: 0.5 });\nfn update(me, dt) {\n    me.vel = vec(1.0, 0.0);\n}\n";

fn setup(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir.join("scenes")).expect("dir");
    std::fs::create_dir_all(dir.join("kinds")).expect("dir");
    std::fs::write(dir.join("kinds/mover.rhai"), KIND).expect("kind");
    let scene = dir.join("scenes/hot.rhai");
    std::fs::write(
        &scene,
        "let w = world(#{ dim: 2, size: vec(40, 40), seed: 3 });\nw.walls_around();\n\
         for i in 0..3 { spawn(\"mover\", #{ pos: vec(5.0 + 6.0 * i, 20.0) }); }\n",
    )
    .expect("scene");
    scene
}

/// Waits for a line of stderr containing `what`, up to a minute.
fn wait_for(lines: &Receiver<String>, what: &str, seen: &mut Vec<String>) {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(60) {
        if let Ok(line) = lines.recv_timeout(Duration::from_millis(100)) {
            let hit = line.contains(what);
            seen.push(line);
            if hit {
                return;
            }
        }
    }
    panic!("no line with {what:?} on stderr; saw {seen:#?}");
}

#[test]
fn an_edited_kind_is_reloaded_recorded_and_verified_and_a_scene_edit_restarts() {
    let dir = common::tmp_in("watch-tests", "reload");
    let scene = setup(&dir);
    let file = dir.join("run.mcap");
    let mut child = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args(["run", scene.to_str().expect("utf-8"), "--watch"])
        .args([
            "--steps",
            "100000000",
            "--record",
            file.to_str().expect("utf-8"),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let stderr = child.stderr.take().expect("stderr");
    let (tx, lines) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    // Stepping once the recording has started.
    common::wait_until_stepping(&file);
    let kind = dir.join("kinds/mover.rhai");
    let mut seen = Vec::new();
    std::fs::write(&kind, KIND.replace("vec(1.0, 0.0)", "vec(0.0, 1.0)")).expect("edit");
    wait_for(&lines, "reloaded (kind mover)", &mut seen);
    std::fs::write(&kind, "fn update(me, dt) {\n    me.vel = vec(0.0, \n}\n").expect("edit");
    wait_for(&lines, "not reloaded, the old version runs on", &mut seen);
    assert!(
        seen.last().is_some_and(|l| l.contains("mover.rhai:3:1")),
        "the error names file, line and column: {seen:#?}"
    );
    // Fixed again: reloaded again.
    std::fs::write(&kind, KIND.replace("vec(1.0, 0.0)", "vec(-1.0, 0.0)")).expect("edit");
    wait_for(&lines, "reloaded (kind mover)", &mut seen);
    // The scene file: the run ends, recorded, and starts again from step 0.
    let text = std::fs::read_to_string(&scene).expect("scene") + "// edited\n";
    std::fs::write(&scene, text).expect("edit");
    wait_for(&lines, "running it again from step 0", &mut seen);
    std::thread::sleep(Duration::from_millis(300));
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let status = child.wait().expect("ends");
    assert_eq!(status.code(), Some(130), "Ctrl-C during a run: {seen:#?}");

    // The first run's file: ended by the scene edit, the reload recorded, and it verifies. The
    // second run has a file of its own.
    assert!(dir.join("run-2.mcap").is_file(), "the second run's file");
    let rec = Recording::open(&file).expect("reads");
    assert_eq!(
        rec.reloads.len(),
        2,
        "two reloads (the broken edit is not one)"
    );
    assert_eq!(rec.reloads[0].kinds, ["mover"]);
    assert!(rec.reloads[0].step < rec.reloads[1].step);
    let report = verify(&rec, |_| {}).expect("verifies");
    assert!(report.passed(), "{report:?}");
    let out = common::critterbox_in(&dir, &["inspect", "run.mcap"]);
    let shown = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        shown.contains(&format!("after step {}", rec.reloads[0].step)),
        "inspect lists the reload: {shown}"
    );
}

#[test]
fn test_watch_reruns_only_the_tests_an_edit_affects() {
    let dir = common::tmp_in("watch-tests", "tests");
    let tests = dir.join("tests");
    std::fs::create_dir_all(tests.join("kinds")).expect("dir");
    std::fs::write(
        tests.join("kinds/pebble.rhai"),
        "defaults(#{ radius: 0.5 });\n",
    )
    .expect("kind");
    std::fs::write(
        tests.join("uses_pebble.rhai"),
        "fn test_a_pebble() {\n    let w = world(#{ dim: 2, size: vec(10, 10), seed: 1 });\n    \
         spawn(\"pebble\", #{ pos: vec(5.0, 5.0) });\n    assert_eq(w.count(\"pebble\"), 1);\n}\n",
    )
    .expect("test");
    std::fs::write(
        tests.join("plain.rhai"),
        "fn test_plain() {\n    assert_eq(1 + 1, 2);\n}\n",
    )
    .expect("test");
    let mut child = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args(["test", "tests", "--watch", "--record-failures", "none"])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let (tx, lines) = mpsc::channel();
    let stdout = child.stdout.take().expect("stdout");
    let stderr = child.stderr.take().expect("stderr");
    for pipe in [
        Box::new(stdout) as Box<dyn std::io::Read + Send>,
        Box::new(stderr),
    ] {
        let tx = tx.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                let _ = tx.send(line);
            }
        });
    }
    let mut seen = Vec::new();
    wait_for(&lines, "watching", &mut seen);
    assert!(seen.iter().any(|l| l == "2 passed, 0 failed"), "{seen:#?}");
    // The kind: only the test file that names it.
    std::fs::write(
        tests.join("kinds/pebble.rhai"),
        "defaults(#{ radius: 0.25 });\n",
    )
    .expect("edit");
    wait_for(
        &lines,
        "changed: 1 tests in tests/uses_pebble.rhai",
        &mut seen,
    );
    wait_for(&lines, "1 passed, 0 failed", &mut seen);
    // A test file: its own tests.
    std::fs::write(
        tests.join("plain.rhai"),
        "fn test_plain() {\n    assert_eq(1 + 1, 3);\n}\n",
    )
    .expect("edit");
    wait_for(&lines, "changed: 1 tests in tests/plain.rhai", &mut seen);
    wait_for(&lines, "0 passed, 1 failed", &mut seen);
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let status = child.wait().expect("ends");
    assert_eq!(status.code(), Some(0), "Ctrl-C ends the watch: {seen:#?}");
}

#[test]
fn a_built_in_scene_has_nothing_to_watch_and_the_watch_ends() {
    let dir = common::tmp_in("watch-tests", "builtin");
    let out = common::critterbox_in(
        &dir,
        &[
            "run",
            "gas",
            "-n",
            "20",
            "--steps",
            "5",
            "--no-record",
            "--watch",
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("nothing to watch"), "{err}");
}

/// Starts `critterbox run SCENE --watch` for a long run, recorded to `file`; its stderr lines
/// come through the receiver.
fn watching(scene: &Path, file: &Path) -> (std::process::Child, Receiver<String>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args(["run", scene.to_str().expect("utf-8"), "--watch"])
        .args([
            "--steps",
            "100000000",
            "--record",
            file.to_str().expect("utf-8"),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let stderr = child.stderr.take().expect("stderr");
    let (tx, lines) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    (child, lines)
}

#[test]
fn an_unclosed_brace_in_an_edit_is_placed_at_the_brace_not_the_end_of_the_file() {
    let dir = common::tmp_in("watch-tests", "unclosed");
    let scene = setup(&dir);
    let file = dir.join("run.mcap");
    let (mut child, lines) = watching(&scene, &file);
    common::wait_until_stepping(&file);
    let kind = dir.join("kinds/mover.rhai");
    let mut seen = Vec::new();
    // The `if` on line 3 is never closed; rhai notices only at the end of the file (line 6).
    std::fs::write(
        &kind,
        "defaults(#{ radius: 0.5 });\nfn update(me, dt) {\n    if me.pos.x > 1.0 {\n        \
         me.vel = vec(0.0, 1.0);\n}\n",
    )
    .expect("edit");
    wait_for(&lines, "not reloaded, the old version runs on", &mut seen);
    let line = seen.last().cloned().unwrap_or_default();
    assert!(
        line.contains("mover.rhai:3:23") && line.contains("never closed"),
        "the error is at the `if`'s brace: {seen:#?}"
    );
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let status = child.wait().expect("ends");
    assert_eq!(status.code(), Some(130), "{seen:#?}");
}

#[test]
fn a_reloaded_kind_that_fails_at_run_time_stops_the_run_and_an_edit_runs_it_again() {
    let dir = common::tmp_in("watch-tests", "runtime");
    let scene = setup(&dir);
    let file = dir.join("run.mcap");
    let (mut child, lines) = watching(&scene, &file);
    common::wait_until_stepping(&file);
    let kind = dir.join("kinds/mover.rhai");
    let mut seen = Vec::new();
    // It compiles, so it is reloaded; its update then reads a property nobody declared.
    std::fs::write(
        &kind,
        "fn update(me, dt) {\n    me.vel = vec(1.0, 0.0) * me.missing;\n}\n",
    )
    .expect("edit");
    wait_for(&lines, "reloaded (kind mover)", &mut seen);
    wait_for(&lines, "its new version failed", &mut seen);
    let line = seen.last().cloned().unwrap_or_default();
    assert!(
        line.contains("the run stopped") && line.contains("mover.rhai:2:"),
        "names the reload and where its new version failed: {seen:#?}"
    );
    wait_for(&lines, "watching", &mut seen);
    // The failed run is recorded as failed, the reload in it.
    let rec = Recording::open(&file).expect("reads");
    assert_eq!(rec.reloads.len(), 1, "{seen:#?}");
    // Fixed: the scene runs again from step 0, with the fixed kind.
    std::fs::write(&kind, KIND).expect("edit");
    wait_for(&lines, "running the scene again", &mut seen);
    common::wait_until_stepping(&dir.join("run-2.mcap"));
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let status = child.wait().expect("ends");
    assert_eq!(
        status.code(),
        Some(130),
        "Ctrl-C during the second run: {seen:#?}"
    );
}
