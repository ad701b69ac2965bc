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

/// A suite whose tests print: from the test before and after it makes its world, from a kind's
/// hook in each step, and between steps; one passes, one fails, one prints nothing.
fn talking_suite(test: &str) -> PathBuf {
    let dir = temp_dir(&format!("talk-{test}"));
    std::fs::create_dir_all(dir.join("kinds")).expect("kinds folder");
    write(
        &dir.join("kinds"),
        "chatty.rhai",
        "fn update(me, dt) {\n    log(`chatty ${me.id} in a step from ${world().step_count}`);\n}\n",
    );
    write(
        &dir,
        "talk.rhai",
        r#"
fn test_passes_and_talks() {
    print("before the world");
    let w = world(#{ dim: 2, size: 10 });
    spawn("chatty", #{ pos: vec(5, 5) });
    print("made the world");
    w.step(2);
    log("after two steps");
}

fn test_fails_and_talks() {
    let w = world(#{ dim: 2, size: 10 });
    print("about to fail");
    assert(false, "on purpose");
}

fn test_quiet() {
    let w = world(#{ dim: 2, size: 10 });
    w.step(1);
}
"#,
    );
    dir
}

/// The lines printed under `---- ID output ----`, up to the next test's line or the totals;
/// `None` when there is no such block.
fn output_of(out: &str, id: &str) -> Option<Vec<String>> {
    let header = format!("---- {id} output ----");
    let mut lines = out.lines().skip_while(|l| *l != header);
    lines.next()?;
    Some(
        lines
            .take_while(|l| {
                !(l.starts_with("ok     ")
                    || l.starts_with("FAIL   ")
                    || l.starts_with("---- ")
                    || l.ends_with(" failed"))
            })
            .map(str::to_string)
            .collect(),
    )
}

#[test]
fn a_failing_test_prints_its_own_output_and_a_passing_one_does_not() {
    let dir = talking_suite("default");
    let file = dir.join("talk.rhai").display().to_string();
    let (code, out, err) = critterbox(&["test", &file, "--record-failures", "none"]);
    assert_eq!(code, Some(1), "{out}{err}");
    assert_eq!(
        output_of(&out, &format!("{file}::test_fails_and_talks")),
        Some(vec!["about to fail".to_string()]),
        "{out}"
    );
    assert_eq!(
        output_of(&out, &format!("{file}::test_passes_and_talks")),
        None,
        "{out}"
    );
    assert!(!out.contains("made the world"), "{out}");
    assert_eq!(out.lines().last(), Some("2 passed, 1 failed"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn show_output_prints_every_tests_lines_under_its_name_in_order() {
    let dir = talking_suite("show");
    let file = dir.join("talk.rhai").display().to_string();
    let junit = dir.join("junit.xml");
    let (code, out, err) = critterbox(&[
        "test",
        &file,
        "--show-output",
        "--jobs",
        "2",
        "--record-failures",
        "none",
        "--junit",
        junit.to_str().expect("utf-8"),
    ]);
    assert_eq!(code, Some(1), "{out}{err}");
    // The hook's lines carry their step (k), whose hooks see step_count k - 1, as `run` prints.
    let want: Vec<String> = [
        "before the world",
        "made the world",
        "[step 1] chatty #0 in a step from 0",
        "[step 2] chatty #0 in a step from 1",
        "after two steps",
    ]
    .map(String::from)
    .to_vec();
    assert_eq!(
        output_of(&out, &format!("{file}::test_passes_and_talks")),
        Some(want),
        "{out}"
    );
    assert_eq!(
        output_of(&out, &format!("{file}::test_fails_and_talks")),
        Some(vec!["about to fail".to_string()]),
        "{out}"
    );
    assert_eq!(
        output_of(&out, &format!("{file}::test_quiet")),
        None,
        "nothing printed: {out}"
    );
    // Each block follows its own test's line.
    let pass_line = out
        .lines()
        .position(|l| l.starts_with("ok     ") && l.contains("test_passes_and_talks"))
        .expect("the passing test's line");
    assert_eq!(
        out.lines().nth(pass_line + 1),
        Some(format!("---- {file}::test_passes_and_talks output ----").as_str()),
        "{out}"
    );
    let xml = std::fs::read_to_string(&junit).expect("junit written");
    assert_eq!(xml.matches("<system-out>").count(), 2, "{xml}");
    assert!(xml.contains("[step 2] chatty #0 in a step from 1"), "{xml}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `critterbox test ARGS` in `dir`.
fn test_in(dir: &Path, args: &[&str]) -> (Option<i32>, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .arg("test")
        .args(args)
        .current_dir(dir)
        .output()
        .expect("critterbox runs");
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn nothing_to_run_fails_and_says_what_it_looked_for_and_where() {
    let dir = temp_dir("nothing");
    let here = std::fs::canonicalize(&dir).expect("the folder");
    // No scripts/tests where it runs.
    let (code, err) = test_in(&here, &[]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("nothing to run: scripts/tests is not there")
            && err.contains(&here.display().to_string())
            && err.contains("fn test_*()"),
        "{err}"
    );
    assert!(!err.contains("cannot read the script"), "{err}");
    assert!(
        !err.contains("kind"),
        "no hint about scenes and kinds: {err}"
    );

    // A folder with no scripts.
    std::fs::create_dir_all(here.join("empty")).expect("empty folder");
    let (code, err) = test_in(&here, &["empty"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("nothing to run: no test scripts (*.rhai) in empty"),
        "{err}"
    );

    // Scripts with no tests in them.
    write(
        &here.join("empty"),
        "helpers.rhai",
        "fn helper(x) { x + 1 }\nfn test_takes_one(x) {}\n",
    );
    let (code, err) = test_in(&here, &["empty"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("nothing to run: no tests in empty/helpers.rhai")
            && err.contains("takes no parameters"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
