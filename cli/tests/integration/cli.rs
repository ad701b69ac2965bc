//! The `critterbox` command as a user meets it: exit codes, messages, the default scene.

/// The repository, where the scripts are.
const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

use std::process::{Command, Output};

fn critterbox(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args(args)
        // Runs record by default: keep their recordings out of the source tree.
        .env(
            "CRITTERBOX_RECORDINGS",
            std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-recordings"),
        )
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
        for stage in ["update", "move", "pairs", "response", "lifecycle", "total"] {
            assert!(
                stdout(&o).contains(&format!("  {stage:<12} ")),
                "--stats prints the time of the {stage} stage"
            );
        }
        // Runs record by default, so the recording's own time is there too.
        assert!(
            stdout(&o).contains("  record       "),
            "--stats prints the recording's time: {}",
            stdout(&o)
        );
    }
    let o = critterbox(&["run", "gas", "--steps", "5", "--stats", "--no-record"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stdout(&o).contains("  record       "), "nothing recorded");
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

/// More critters than memory holds (2^32 of them, about 300 GB) is an error naming the count,
/// not an allocation failure that aborts the process.
#[test]
fn more_critters_than_memory_holds_is_an_error_not_an_abort() {
    let o = critterbox(&["run", "gas", "-n", "4294967296", "--no-record"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("4294967296") && err.contains("memory"),
        "{err}"
    );
    assert!(!err.contains("allocation"), "{err}");
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

/// `critterbox stability --bullets` is documented in the subcommand's help and prints the
/// bullet sweep: a row per speed (1 to 1e6, four per decade), in 2D and in 3D.
#[test]
fn stability_prints_the_bullet_sweep_on_request() {
    let help = critterbox(&["stability", "--help"]);
    assert!(help.status.success());
    assert!(stdout(&help).contains("--bullets"), "{}", stdout(&help));
    let o = critterbox(&["stability", "--bullets"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let speed_rows = out
        .lines()
        .filter(|l| {
            l.strip_prefix("| ")
                .is_some_and(|r| r.starts_with(|c: char| c.is_ascii_digit()))
        })
        .count();
    assert_eq!(speed_rows, 2 * 25, "{out}");
    assert_eq!(out.lines().filter(|l| l.contains("ends past")).count(), 2);
}

#[test]
fn every_shipped_scene_script_runs_from_the_command_line() {
    let dir = std::path::Path::new(ROOT).join("scripts/scenes");
    let mut ran = 0;
    for entry in std::fs::read_dir(&dir).expect("scripts/scenes exists") {
        let path = entry.expect("a directory entry").path();
        let o = critterbox(&["run", path.to_str().expect("utf-8 path"), "--steps", "50"]);
        assert!(o.status.success(), "{}: {}", path.display(), stderr(&o));
        assert!(
            field(&stdout(&o), "scene").contains("2D")
                || field(&stdout(&o), "scene").contains("3D")
        );
        ran += 1;
    }
    assert!(ran >= 5, "expected the lecture's five scenes, found {ran}");
}

#[test]
fn set_overrides_a_scene_constant_and_rejects_unknown_ones() {
    let cradle = concat!(env!("CARGO_MANIFEST_DIR"), "/../scripts/scenes/cradle.rhai");
    let o = critterbox(&["run", cradle, "--set", "SPEED=2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Five balls of mass 0.125 struck at 2: the momentum is 0.25 whichever ball carries it.
    assert!(
        field(&stdout(&o), "momentum").starts_with("(2.500000e-1,"),
        "{}",
        stdout(&o)
    );
    let o = critterbox(&["run", cradle, "--set", "NOPE=1"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("no constant NOPE") && err.contains("SPEED"),
        "{err}"
    );
}

#[test]
fn check_passes_shipped_scripts_and_fails_a_broken_one_with_its_line() {
    let root = ROOT;
    let mut args = vec!["check".to_string()];
    for sub in ["scripts/scenes", "scripts/kinds"] {
        for entry in std::fs::read_dir(format!("{root}/{sub}")).expect("scripts exist") {
            args.push(entry.expect("entry").path().display().to_string());
        }
    }
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = critterbox(&refs);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        stdout(&o)
            .lines()
            .filter(|l| l.ends_with(")") && l.contains(" ok "))
            .count(),
        args.len() - 1
    );

    let dir = std::env::temp_dir().join(format!("critterbox-cli-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let broken = dir.join("broken.rhai");
    std::fs::write(&broken, "fn collide(me, other) {\n    let x = ;\n}\n").expect("write");
    let o = critterbox(&["check", broken.to_str().expect("utf-8")]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("broken.rhai:2:"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_method_runs_every_shipped_scene_script_and_calls_its_hooks() {
    // bullets_vs_player: bullets' collide hooks kill them and damage players; under every method
    // some bullets must have died (the hooks ran) and the run must succeed.
    let scene = concat!(
        concat!(env!("CARGO_MANIFEST_DIR"), "/.."),
        "/scripts/scenes/bullets_vs_player.rhai"
    );
    for m in ["discrete", "substep:2", "swept", "event", "auto"] {
        let o = critterbox(&["run", scene, "--steps", "200", "--method", m]);
        assert!(o.status.success(), "{m}: {}", stderr(&o));
        let out = stdout(&o);
        assert_eq!(field(&out, "method"), m, "{out}");
        assert!(field(&out, "critters").contains("bullet"), "{out}");
    }
    // The default gas without gravity, too slow to tunnel: the exact event step, its flight kept.
    let o = critterbox(&["run", "gas", "--steps", "5", "--method", "auto"]);
    assert!(
        field(&stdout(&o), "auto chose").starts_with("event"),
        "{}",
        stdout(&o)
    );
    // Under gravity auto solves, and says how many critters sleep: the whole pile has come to
    // rest after 600 steps (10 s).
    let pile = concat!(env!("CARGO_MANIFEST_DIR"), "/../scripts/scenes/pile.rhai");
    let o = critterbox(&["run", pile, "--steps", "600", "--method", "auto"]);
    let out = stdout(&o);
    assert!(field(&out, "auto chose").starts_with("solve:8"), "{out}");
    assert!(field(&out, "asleep").starts_with("240 critters"), "{out}");
}

#[test]
fn bad_methods_are_clear_errors() {
    for bad in ["fast", "substep:0", "substep:x"] {
        let o = critterbox(&["run", "gas", "--steps", "1", "--method", bad]);
        assert_eq!(o.status.code(), Some(2), "{bad}");
        assert!(stderr(&o).contains("method"), "{}", stderr(&o));
    }
    let dir = std::env::temp_dir().join(format!("critterbox-method-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let scene = dir.join("m.rhai");
    std::fs::write(&scene, "world(#{ method: \"warp\" });\n").expect("write");
    let o = critterbox(&["run", scene.to_str().expect("utf-8")]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("unknown method 'warp'"),
        "{}",
        stderr(&o)
    );
    std::fs::write(
        &scene,
        "world(#{ dim: 2, method: \"substep:3\" });\nspawn(\"ball\", #{ pos: vec(5, 5) });\n",
    )
    .expect("write");
    let o = critterbox(&["run", scene.to_str().expect("utf-8"), "--steps", "3"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(field(&stdout(&o), "method"), "substep:3");
}

/// A scratch folder for scene files written by a test.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("critterbox-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

#[test]
fn an_impossible_radius_is_an_error_naming_the_radius_and_the_box() {
    let dir = scratch("radius");
    let scene = dir.join("big.rhai");
    std::fs::write(
        &scene,
        "const R = 0.5;\nworld(#{ dim: 2, size: vec(10, 10) });\nspawn(\"ball\", #{ pos: vec(5, 5), radius: R });\n",
    )
    .expect("write");
    let path = scene.to_str().expect("utf-8");
    let o = critterbox(&["run", path, "--steps", "1", "--no-record"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for (r, says) in [
        ("100.0", "radius 100 does not fit in the world box 10 x 10"),
        ("1e300", "radius 1e300 is too large"),
        ("1e-300", "radius 1e-300 is too small"),
    ] {
        let set = format!("R={r}");
        let o = critterbox(&["run", path, "--set", &set, "--steps", "1", "--no-record"]);
        assert_eq!(o.status.code(), Some(1), "{r}");
        let err = stderr(&o);
        assert!(err.contains(says), "{err}");
        assert!(err.contains("big.rhai:3"), "{err}");
        assert!(!err.contains("mass ="), "{err}");
    }
}

#[test]
fn a_wall_through_a_critter_is_an_error_in_either_order() {
    let dir = scratch("wall-order");
    let spawn = "spawn(\"ball\", #{ pos: vec(5, 5), radius: 0.5 });\n";
    let wall = "w.wall(vec(2, 5.2), vec(8, 5.2));\n";
    for (name, body) in [
        ("after", format!("{spawn}{wall}")),
        ("before", format!("{wall}{spawn}")),
    ] {
        let scene = dir.join(format!("{name}.rhai"));
        std::fs::write(
            &scene,
            format!("let w = world(#{{ dim: 2, size: vec(10, 10) }});\n{body}"),
        )
        .expect("write");
        let o = critterbox(&[
            "run",
            scene.to_str().expect("utf-8"),
            "--steps",
            "1",
            "--no-record",
        ]);
        assert_eq!(o.status.code(), Some(1), "{name}");
        let err = stderr(&o);
        assert!(
            err.contains("overlaps") && err.contains("by 0.400"),
            "{name}: {err}"
        );
        assert!(err.contains(&format!("{name}.rhai:3")), "{name}: {err}");
    }
}

#[test]
fn exact_methods_at_a_huge_dt_finish_their_steps_or_fail_naming_the_step() {
    for method in ["event", "swept", "auto"] {
        let args = [
            "run",
            "billiards",
            "--dt",
            "1e9",
            "--method",
            method,
            "--steps",
            "3",
            "--no-record",
        ];
        let o = critterbox(&args);
        let err = stderr(&o);
        if o.status.success() {
            let warned = err.matches("ran out of its event budget").count();
            assert_eq!(warned, 1, "{method}: {err}");
            assert!(err.contains("[step 1] warning:"), "{method}: {err}");
        } else {
            assert_eq!(o.status.code(), Some(1), "{method}: {err}");
            assert!(
                err.contains("gave up after") && err.contains("step "),
                "{method}: {err}"
            );
        }
    }
}

#[test]
fn discrete_at_a_large_dt_warns_of_tunnelling_once_and_a_normal_run_not_at_all() {
    for method in ["discrete", "substep:2"] {
        let args = [
            "run",
            "billiards",
            "--dt",
            "1",
            "--method",
            method,
            "--steps",
            "20",
            "--no-record",
        ];
        let o = critterbox(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let err = stderr(&o);
        assert_eq!(err.matches("tunnelling").count(), 1, "{method}: {err}");
        assert!(
            err.contains("(ball) moved") && err.contains("--method swept"),
            "{err}"
        );
    }
    let o = critterbox(&[
        "run",
        "billiards",
        "--method",
        "discrete",
        "--steps",
        "200",
        "--no-record",
    ]);
    assert!(o.status.success());
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}
