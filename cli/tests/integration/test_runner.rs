//! `critterbox test`: a failing, throwing, looping or broken test script is one failure with its
//! file and line; the other tests still run; the closing line counts them.

use std::path::{Path, PathBuf};
use std::process::Command;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("critterbox-runner-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).expect("write test script");
}

fn critterbox(args: &[&str]) -> (Option<i32>, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args(args)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("critterbox runs");
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// The suite in a folder of the calling test's own (tests may share a process).
fn suite(test: &str) -> PathBuf {
    let dir = temp_dir(&format!("suite-{test}"));
    write(
        &dir,
        "good.rhai",
        r#"
fn test_two_balls_swap_velocities() {
    let w = world(#{ dim: 2, size: 10 });
    let a = spawn("ball", #{ pos: vec(3, 5), vel: vec(1, 0) });
    let b = spawn("ball", #{ pos: vec(5, 5) });
    expect_collision(a, b, 120);
    assert_eq(a.vel, vec(0, 0));
    assert_eq(b.vel, vec(1, 0));
}

fn test_energy_of_one_ball() {
    let w = world(#{ dim: 2, size: 10 });
    spawn("ball", #{ pos: vec(3, 5), vel: vec(2, 0), mass: 3.0 });
    assert_near(w.kinetic_energy(), 6.0, 1e-12);
}
"#,
    );
    write(
        &dir,
        "bad.rhai",
        r#"
fn test_wrong_expectation() {
    let w = world(#{ dim: 2, size: 10 });
    let a = spawn("ball", #{ pos: vec(3, 5) });
    w.step(3);
    assert_eq(a.pos, vec(4, 5), "the ball should have moved");
}

fn test_throws() {
    throw "something broke";
}

fn test_loops_forever() {
    let i = 0;
    loop { i += 1; }
}
"#,
    );
    write(
        &dir,
        "broken.rhai",
        "fn test_broken() {\n    let x = ;\n}\n",
    );
    dir
}

#[test]
fn failures_name_file_and_line_and_the_rest_still_run() {
    let dir = suite("failures");
    let junit = dir.join("junit.xml");
    let runs = dir.join("runs");
    let (code, out, _err) = critterbox(&[
        "test",
        dir.to_str().expect("utf-8"),
        "--max-ops",
        "100000",
        "--junit",
        junit.to_str().expect("utf-8"),
        "--record-failures",
        runs.to_str().expect("utf-8"),
    ]);
    assert_eq!(code, Some(1), "{out}");
    assert!(
        out.contains("ok     ") && out.contains("good.rhai::test_two_balls_swap_velocities"),
        "{out}"
    );
    assert!(out.contains("good.rhai::test_energy_of_one_ball"), "{out}");
    assert!(
        out.contains("bad.rhai:6:"),
        "the failed assert_eq's line:\n{out}"
    );
    assert!(
        out.contains("the ball should have moved") && out.contains("step 3"),
        "{out}"
    );
    assert!(
        out.contains("bad.rhai:10:") && out.contains("something broke"),
        "{out}"
    );
    assert!(
        out.contains("test_loops_forever") && out.contains("operations"),
        "{out}"
    );
    assert!(
        out.contains("broken.rhai:2:"),
        "the syntax error's line:\n{out}"
    );
    assert_eq!(out.lines().last(), Some("2 passed, 4 failed"), "{out}");

    let xml = std::fs::read_to_string(&junit).expect("junit written");
    assert!(xml.contains("tests=\"6\" failures=\"4\""), "{xml}");
    assert_eq!(xml.matches("<testcase ").count(), 6);
    assert_eq!(xml.matches("<failure ").count(), 4);

    // The failed test's run is recorded under the runner's limits, as a world the test built.
    let file = runs.join("bad-test_wrong_expectation.mcap");
    let rec = critterbox::recording::Recording::open(&file).expect("the failed run is recorded");
    assert_eq!(rec.meta().limits.max_operations, 100_000);
    let case = format!("{}::test_wrong_expectation", dir.join("bad.rhai").display());
    assert_eq!(
        rec.meta().source,
        critterbox::recording::SceneSource::Test { case: case.clone() }
    );
    let (code, _, err) = critterbox(&["replay", file.to_str().expect("utf-8")]);
    assert_eq!(code, Some(0), "{err}");
    let (code, _, err) = critterbox(&["replay", file.to_str().expect("utf-8"), "--verify"]);
    assert_eq!(code, Some(1));
    assert!(
        err.contains(&case) && err.contains("without --verify"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn filter_runs_only_matching_tests_and_all_passing_exits_zero() {
    let dir = suite("filter");
    let (code, out, _) = critterbox(&[
        "test",
        dir.to_str().expect("utf-8"),
        "--filter",
        "good.rhai",
    ]);
    assert_eq!(code, Some(0), "{out}");
    assert_eq!(out.lines().last(), Some("2 passed, 0 failed"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_shipped_script_tests_pass() {
    let (code, out, err) = critterbox(&["test", "--jobs", "2", "--record-failures", "none"]);
    assert_eq!(code, Some(0), "{out}{err}");
    let last = out.lines().last().unwrap_or_default().to_string();
    assert!(last.ends_with(" passed, 0 failed"), "{last}");
    let passed: usize = last
        .split(' ')
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    assert!(passed >= 10, "{out}");
}
