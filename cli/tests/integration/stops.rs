//! Every stop leaves a finished file: a run ended by SIGINT, SIGTERM or SIGHUP (while stepping
//! or while its scene is built) finishes its recording and names the signal, and a scene that
//! cannot be built is recorded with its scripts and its error.

use crate::common;
use common::{critterbox_in, text};

use critterbox::recording::verify::verify;
use critterbox::recording::{Recording, SETUP_FAILED};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// A fresh folder for one test.
fn tmp(name: &str) -> PathBuf {
    common::tmp_in("stop-tests", name)
}

/// Starts a run that would go on for hours, sends it `signal` once it is stepping, and checks
/// the exit code (128 + the signal's number), the summary, and the finished file.
fn interrupt_with(signal: &str, number: i32) {
    let dir = tmp(signal);
    let file = dir.join("run.mcap");
    let child = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args(["run", "gas", "-n", "20", "--steps", "100000000"])
        .args(["--record", file.to_str().expect("utf-8 path")])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    // The signals are watched before the file is created, so once it exists they are caught.
    common::wait_until_stepping(&file);
    let sent = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(sent.success());
    let o = child.wait_with_output().expect("wait");
    let out = text(&o);
    assert_eq!(o.status.code(), Some(128 + number), "{out}");
    let name = format!("SIG{signal}");
    assert!(
        out.contains(&format!("ended: interrupted ({name})")),
        "{out}"
    );
    assert!(out.contains("interrupted by "), "{out}");
    assert!(out.contains(&name), "{out}");

    let rec = Recording::open(&file).expect("open");
    assert_eq!(rec.truncated, None, "{name} finishes the file");
    let end = rec.end.clone().expect("end record");
    assert_eq!(
        (end.outcome.as_str(), end.reason.as_str(), end.steps),
        ("interrupted", name.as_str(), rec.last_step())
    );
    assert!(rec.last_step() > 0, "the run was stepping");
    assert_eq!(rec.keyframes.last(), Some(&rec.last_step()));
    let report = verify(&rec, |_| {}).expect("verify");
    assert!(report.passed(), "{:?}", report.mismatch);

    let shown = critterbox_in(&dir, &["inspect", file.to_str().expect("utf-8")]);
    assert!(shown.status.success(), "{}", text(&shown));
    assert!(
        text(&shown).contains(&format!("interrupted ({name})")),
        "{}",
        text(&shown)
    );
}

#[test]
fn sigterm_finishes_the_file_and_exits_143() {
    interrupt_with("TERM", 15);
}

#[test]
fn sighup_finishes_the_file_and_exits_129() {
    interrupt_with("HUP", 1);
}

#[test]
fn sigint_finishes_the_file_and_exits_130() {
    interrupt_with("INT", 2);
}

/// A signal while the scene is still being built: the set-up ends, no step is taken, and the
/// file is finished as interrupted at step 0, with the scene's script attached.
#[test]
fn a_signal_during_the_set_up_stops_before_the_first_step_with_a_finished_file() {
    let dir = tmp("setup-signal");
    let file = dir.join("run.mcap");
    let scene = Path::new(common::ROOT).join("tests/scenes/slow_setup.rhai");
    let child = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args(["run", scene.to_str().expect("utf-8 path")])
        .args(["--max-ops", "100000000", "--max-step-ops", "0"])
        .args(["--record", file.to_str().expect("utf-8 path")])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    // The set-up's loop runs for seconds; the signals are watched from the run's start.
    std::thread::sleep(Duration::from_millis(400));
    assert_eq!(
        std::fs::metadata(&file).ok().map(|m| m.len()),
        None,
        "still building the scene: no file yet"
    );
    let sent = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(sent.success());
    let o = child.wait_with_output().expect("wait");
    let out = text(&o);
    assert_eq!(o.status.code(), Some(128 + 15), "{out}");
    assert!(out.contains("ended: interrupted (SIGTERM)"), "{out}");
    let rec = Recording::open(&file).expect("open");
    assert_eq!(rec.truncated, None, "the file is finished");
    let end = rec.end.clone().expect("end record");
    assert_eq!(
        (end.outcome.as_str(), end.reason.as_str(), end.steps),
        ("interrupted", "SIGTERM", 0)
    );
    assert!(
        rec.scripts
            .iter()
            .any(|(path, _)| path.ends_with("slow_setup.rhai")),
        "the scene's script is attached"
    );
}

/// A folder with `scripts/scenes/scene.rhai` holding `scene` and `scripts/kinds/NAME.rhai` for
/// each kind.
fn project(name: &str, scene: &str, kinds: &[(&str, &str)]) -> PathBuf {
    let dir = tmp(name);
    std::fs::create_dir_all(dir.join("scripts/scenes")).expect("dir");
    std::fs::create_dir_all(dir.join("scripts/kinds")).expect("dir");
    std::fs::write(dir.join("scripts/scenes/scene.rhai"), scene).expect("write");
    for (kind, text) in kinds {
        std::fs::write(dir.join(format!("scripts/kinds/{kind}.rhai")), text).expect("write");
    }
    dir
}

/// Runs the project's scene, which fails during its set-up with an error containing `needle`,
/// and checks the recording it leaves: the scripts named in `attached`, the error, an end record
/// saying the set-up failed, shown by `inspect`, and refused by `replay --verify`.
fn fails_in_setup(dir: &Path, needle: &str, attached: &[&str]) {
    let file = dir.join("failed.mcap");
    let o = critterbox_in(
        dir,
        &[
            "run",
            "scripts/scenes/scene.rhai",
            "--record",
            file.to_str().expect("utf-8"),
        ],
    );
    let out = text(&o);
    assert!(!o.status.success(), "{out}");
    assert!(out.contains(needle), "{out}");
    assert!(out.contains("ended: failed during set-up"), "{out}");

    let rec = Recording::open(&file).expect("a finished recording");
    assert_eq!(rec.truncated, None);
    let end = rec.end.clone().expect("end record");
    assert_eq!(end.outcome, SETUP_FAILED);
    assert!(end.reason.contains(needle), "{}", end.reason);
    let error = rec.error.clone().expect("error record");
    assert!(error.message.contains(needle), "{}", error.message);
    assert_eq!(rec.last_step(), 0);
    assert!(rec.hashes.is_empty(), "no step was taken");
    let names: Vec<&str> = rec.scripts.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names.len(), attached.len(), "{names:?}");
    for (name, want) in names.iter().zip(attached) {
        assert!(name.ends_with(want), "{names:?}");
        let on_disk = std::fs::read_to_string(dir.join(name)).expect("the script");
        let kept = &rec.scripts.iter().find(|(n, _)| n == name).expect("kept").1;
        // A scene's text is attached as loaded: line by line, as `--set` rewrites it.
        assert_eq!(
            kept.trim_end(),
            on_disk.trim_end(),
            "{name} is attached as it was read"
        );
    }

    let shown = critterbox_in(dir, &["inspect", file.to_str().expect("utf-8")]);
    assert!(shown.status.success(), "{}", text(&shown));
    assert!(
        text(&shown).contains("failed during set-up") && text(&shown).contains(needle),
        "{}",
        text(&shown)
    );
    let verified = critterbox_in(dir, &["replay", "--verify", file.to_str().expect("utf-8")]);
    assert!(!verified.status.success(), "{}", text(&verified));
}

#[test]
fn a_kind_whose_init_fails_at_spawn_leaves_a_recording() {
    let dir = project(
        "init_fails",
        "let w = world(#{ dim: 2, size: vec(10, 10) });\n\
         spawn(\"ball\", #{ pos: vec(2, 2), radius: 0.5 });\n\
         spawn(\"grumpy\", #{ pos: vec(5, 5), radius: 0.5 });\n",
        &[(
            "grumpy",
            "fn init(me) { throw \"grumpy refuses to start\"; }\n",
        )],
    );
    fails_in_setup(
        &dir,
        "grumpy refuses to start",
        &["scene.rhai", "grumpy.rhai"],
    );
}

#[test]
fn a_kind_that_does_not_compile_leaves_a_recording_with_its_text() {
    let dir = project(
        "kind_syntax",
        "let w = world(#{ dim: 2, size: vec(10, 10) });\n\
         spawn(\"broken\", #{ pos: vec(5, 5), radius: 0.5 });\n",
        &[("broken", "fn collide(me, other) { let x = ; }\n")],
    );
    fails_in_setup(&dir, "broken.rhai:1:", &["scene.rhai", "broken.rhai"]);
}

#[test]
fn a_bad_spawn_leaves_a_recording() {
    let dir = project(
        "bad_spawn",
        "let w = world(#{ dim: 2, size: vec(10, 10) });\n\
         spawn(\"ball\", #{ pos: vec(5, 5), radius: -1.0 });\n",
        &[],
    );
    fails_in_setup(&dir, "radius", &["scene.rhai"]);
}

#[test]
fn a_scene_script_error_leaves_a_recording() {
    let dir = project(
        "scene_throws",
        "let w = world(#{ dim: 2, size: vec(10, 10) });\n\
         throw \"the scene gives up\";\n",
        &[],
    );
    fails_in_setup(&dir, "the scene gives up", &["scene.rhai"]);
    let dir = project(
        "scene_syntax",
        "let w = world(#{ dim: 2, size: vec(10, 10) ;\n",
        &[],
    );
    fails_in_setup(&dir, "scene.rhai:1:", &["scene.rhai"]);
}

#[test]
fn a_mistyped_scene_or_path_writes_no_file() {
    let dir = tmp("mistyped");
    for args in [
        &["run", "no_such_scene"][..],
        &["run", "scripts/scenes/no_such_file.rhai"],
    ] {
        let o = critterbox_in(&dir, args);
        assert!(!o.status.success(), "{}", text(&o));
        assert!(!dir.join("recordings").exists(), "{}", text(&o));
    }
}

#[test]
fn run_help_gives_the_exit_codes_of_the_signals() {
    let o = critterbox_in(&tmp("help"), &["run", "--help"]);
    let out = text(&o);
    assert!(o.status.success(), "{out}");
    for code in ["SIGINT (130)", "SIGTERM (143)", "SIGHUP (129)"] {
        assert!(out.contains(code), "{out}");
    }
}
