//! The `critterbox` command as a user meets it: exit codes, messages, the default scene.

use std::process::{Command, Output};

fn critterbox(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args(args)
        .output()
        .expect("the critterbox binary runs")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn field<'a>(out: &'a str, name: &str) -> &'a str {
    out.lines()
        .find_map(|l| l.strip_prefix(name))
        .map(str::trim)
        .unwrap_or_else(|| panic!("no '{name}' line in:\n{out}"))
}

#[test]
fn no_arguments_runs_the_default_scene() {
    let o = critterbox(&[]);
    assert!(o.status.success(), "stderr: {}", stderr(&o));
    let out = stdout(&o);
    assert!(field(&out, "scene").starts_with("gas (2D"), "{out}");
    assert_eq!(field(&out, "critters"), "ball 1000, wall 4");
    assert!(field(&out, "steps").starts_with("600 "), "{out}");
    // Not a terminal: the progress bar stays hidden, and nothing else goes to stderr.
    assert_eq!(stderr(&o), "");
}

#[test]
fn the_default_gas_keeps_its_energy() {
    let o = critterbox(&["run", "gas", "--steps", "300"]);
    assert!(o.status.success());
    let out = stdout(&o);
    let energy = field(&out, "energy");
    let change: f64 = energy
        .rsplit("relative change ")
        .next()
        .and_then(|s| s.trim_end_matches(')').parse().ok())
        .unwrap_or_else(|| panic!("no relative change in '{energy}'"));
    assert!(
        change.abs() < 1e-12,
        "elastic gas changed its energy by {change}"
    );
}

#[test]
fn list_names_every_scene() {
    let o = critterbox(&["run", "--list"]);
    assert!(o.status.success());
    let out = stdout(&o);
    for s in critterbox::scenes::SCENES {
        assert!(out.contains(s.name), "{} missing from:\n{out}", s.name);
    }
}

#[test]
fn every_scene_runs_from_the_command_line() {
    for s in critterbox::scenes::SCENES {
        let o = critterbox(&["run", s.name, "--steps", "20", "--stats"]);
        assert!(o.status.success(), "{}: {}", s.name, stderr(&o));
        assert!(
            stdout(&o).contains("broad phase"),
            "--stats prints stage times"
        );
    }
}

#[test]
fn unknown_scene_is_a_clear_error() {
    let o = critterbox(&["run", "nosuch"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.contains("unknown scene 'nosuch'"), "{err}");
    assert!(err.contains("gas") && err.contains("--list"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn bad_numbers_are_clear_errors_not_panics() {
    for args in [
        &["run", "--dt", "-1"][..],
        &["run", "--dt", "0"],
        &["run", "--dt", "NaN"],
        &["run", "gas", "-n", "0"],
    ] {
        let o = critterbox(args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let err = stderr(&o);
        assert!(err.starts_with("error: "), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    let o = critterbox(&["run", "--steps", "many"]);
    assert_eq!(o.status.code(), Some(2), "usage errors exit 2");
}

#[test]
fn same_seed_same_hash_other_seed_other_hash() {
    let hash = |seed: &str| {
        let o = critterbox(&["run", "gas", "-n", "200", "--steps", "100", "--seed", seed]);
        assert!(o.status.success());
        field(&stdout(&o), "state hash").to_string()
    };
    assert_eq!(hash("7"), hash("7"));
    assert_ne!(hash("7"), hash("8"));
}

#[test]
fn help_explains_the_run_options() {
    let o = critterbox(&["run", "--help"]);
    assert!(o.status.success());
    let out = stdout(&o);
    for flag in ["--steps", "--dt", "--seed", "--list", "--stats"] {
        assert!(out.contains(flag), "{flag} missing from --help");
    }
}
