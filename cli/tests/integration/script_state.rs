//! What scripts keep and show beside the physics, as users meet it through the command:
//! `world().vars` in the state hash and the recording (so `replay --verify` checks it),
//! `me.color` in the Foxglove channel, the script profiler in `run --stats` and the recording's
//! end metadata, the log's step numbers, and a failing test's recording.

use crate::common;
use common::{critterbox, critterbox_in, text, ROOT};

use critterbox::recording::reader::{read_items, Flow, Item};
use critterbox::recording::recover::rewrite;
use critterbox::recording::replay::{state_at_step, StateSource};
use critterbox::recording::schema::{self, LogMsg, StateMsg};
use critterbox::recording::verify::verify;
use critterbox::recording::Recording;
use critterbox::PropValue;
use std::path::{Path, PathBuf};
use std::process::Output;

/// A fresh folder for one test.
fn tmp(name: &str) -> PathBuf {
    common::tmp_in("script-state-tests", name)
}

const SCENE: &str = "scripts/tests/scenes/vars_score.rhai";
/// The scene's critters (its constant N) and their kind.
const N: i64 = 6;

/// Every message of `topic`, as JSON.
fn messages(path: &Path, topic: &str) -> Vec<serde_json::Value> {
    let mut out = Vec::new();
    read_items(path, |item| {
        if let Item::Message { topic: t, data, .. } = item {
            if t == topic {
                out.push(serde_json::from_slice(data).expect("json"));
            }
        }
        Ok(Flow::Continue)
    })
    .expect("readable");
    out
}

fn states(path: &Path) -> Vec<StateMsg> {
    messages(path, schema::STATE)
        .into_iter()
        .map(|v| serde_json::from_value(v).expect("a state"))
        .collect()
}

fn int(v: Option<&PropValue>) -> i64 {
    match v {
        Some(PropValue::Int(i)) => *i,
        other => panic!("expected an integer var, got {other:?}"),
    }
}

/// Runs the vars scene `steps` steps with `extra` arguments, recorded to `file`.
fn run_scene(file: &Path, steps: u64, extra: &[&str]) -> Output {
    let steps = steps.to_string();
    let mut args = vec!["run", SCENE, "--steps", &steps, "--record"];
    args.push(file.to_str().expect("utf-8"));
    args.extend_from_slice(extra);
    let o = critterbox(&args);
    assert!(o.status.success(), "{}", text(&o));
    o
}

#[test]
fn vars_are_recorded_and_checked_by_replay_verify_and_a_tampered_value_is_caught() {
    let dir = tmp("vars");
    let file = dir.join("vars.mcap");
    let steps = 90;
    run_scene(&file, steps, &[]);

    // Every recorded state carries the vars as the hooks left them: on_step adds one per
    // step and each critter's update one per step.
    let states = states(&file);
    assert_eq!(
        states.len() as u64,
        steps + 1,
        "a small scene records every state"
    );
    for s in &states {
        assert_eq!(int(s.vars.get("steps")), s.step as i64, "step {}", s.step);
        assert_eq!(int(s.vars.get("updates")), N * s.step as i64);
        assert!(matches!(s.vars.get("best"), Some(PropValue::Map(_))));
    }

    let rec = Recording::open(&file).expect("open");
    let report = verify(&rec, |_| {}).expect("verify runs");
    assert!(report.passed(), "{report:?}");
    let o = critterbox(&["replay", file.to_str().unwrap(), "--verify"]);
    assert!(o.status.success(), "{}", text(&o));

    // One var changed in one recorded state: verify names that step.
    let tampered = dir.join("tampered.mcap");
    let at = 40;
    rewrite(&file, &tampered, |topic, data| {
        let mut s: StateMsg = serde_json::from_slice(data).ok()?;
        if topic != schema::STATE || s.step != at {
            return None;
        }
        s.vars.insert("steps".into(), PropValue::Int(1000));
        Some(serde_json::to_vec(&s).expect("encode"))
    })
    .expect("rewrite");
    let rec = Recording::open(&tampered).expect("open");
    let report = verify(&rec, |_| {}).expect("verify runs");
    let mismatch = report.mismatch.expect("the tampered var is caught");
    assert_eq!(mismatch.step, at, "{mismatch:?}");
    let o = critterbox(&["replay", tampered.to_str().unwrap(), "--verify"]);
    assert!(!o.status.success(), "{}", text(&o));

    // A step between full states is shown from the state before it: the vars come back with
    // the critters, and the re-simulated step has the right ones.
    let sparse = dir.join("sparse.mcap");
    run_scene(&sparse, steps, &["--record-every", "20"]);
    let rec = Recording::open(&sparse).expect("open");
    let (s, source) = state_at_step(&rec, 35).expect("step 35");
    assert_eq!(source, StateSource::Restored { keyframe: 20 });
    assert_eq!(int(s.vars.get("steps")), 35);
    assert_eq!(int(s.vars.get("updates")), N * 35);
}

#[test]
fn a_colour_set_in_a_hook_is_in_the_state_and_the_foxglove_scene() {
    let dir = tmp("color");
    let file = dir.join("color.mcap");
    run_scene(&file, 200, &[]);
    let states = states(&file);
    let last = states.last().expect("states");
    // vars_counter turns red in its collide hook; the tally of hits says how many ran.
    let hits = int(last.vars.get("hits"));
    assert!(hits > 0, "test setup: the scene has collisions");
    assert!(!last.colors.is_empty() && last.colors.len() as i64 <= hits.min(N));
    assert!(
        last.colors.values().all(|c| c == "#ff0000"),
        "{:?}",
        last.colors
    );
    // The Foxglove scene of the same step: red spheres exactly for those critters.
    let scenes = messages(&file, schema::SCENE);
    let scene = scenes.last().expect("a Foxglove scene");
    let spheres = scene["entities"][0]["spheres"].as_array().expect("spheres");
    let red = spheres
        .iter()
        .filter(|s| s["color"]["r"] == 1.0 && s["color"]["g"] == 0.0 && s["color"]["b"] == 0.0)
        .count();
    assert_eq!(red, last.colors.len(), "{spheres:?}");
    assert_eq!(spheres.len() as i64, N);
}

#[test]
fn the_profile_counts_every_hook_call_in_stats_and_in_the_recording() {
    let dir = tmp("profile");
    let file = dir.join("profile.mcap");
    let steps = 50;
    let o = run_scene(&file, steps, &["--stats"]);
    let out = text(&o);
    let row = |kind: &str, hook: &str| -> u64 {
        let line = out
            .lines()
            .find(|l| {
                let w: Vec<&str> = l.split_whitespace().collect();
                w.len() == 5 && w[0] == kind && w[1] == hook
            })
            .unwrap_or_else(|| panic!("no {kind} {hook} row in:\n{out}"));
        line.split_whitespace()
            .nth(2)
            .unwrap()
            .parse()
            .expect("calls")
    };
    assert_eq!(row("vars_counter", "update"), N as u64 * steps);
    assert_eq!(row("scene", "on_step"), steps);

    let rec = Recording::open(&file).expect("open");
    let end = rec.end.as_ref().expect("end record");
    let updates = end
        .profile
        .iter()
        .find(|r| r.kind == "vars_counter" && r.hook == "update")
        .expect("the profile is in the end record");
    assert_eq!(updates.calls, N as u64 * steps);
    // The collide row counts what the vars counted: one call per hit.
    let hits = states(&file)
        .last()
        .map(|s| int(s.vars.get("hits")))
        .expect("a state");
    let collides = end
        .profile
        .iter()
        .find(|r| r.hook == "collide")
        .map_or(0, |r| r.calls);
    assert_eq!(collides as i64, hits);

    // Without --stats nothing is timed and the end record has no profile.
    let plain = dir.join("plain.mcap");
    run_scene(&plain, 5, &[]);
    let rec = Recording::open(&plain).expect("open");
    assert!(rec.end.as_ref().expect("end").profile.is_empty());
}

/// The scene logs `tally K HITS` from on_step at every 50th step, K being `w.step_count`
/// there: the run prints it as `[step K]` and the recording keeps it under step K.
#[test]
fn a_line_logged_in_step_k_is_step_k_in_the_log_and_in_the_recording() {
    let dir = tmp("log");
    let file = dir.join("log.mcap");
    let o = run_scene(&file, 150, &[]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    let printed: Vec<(u64, u64)> = err
        .lines()
        .filter_map(|l| {
            let rest = l.strip_prefix("[step ")?;
            let (n, line) = rest.split_once("] tally ")?;
            let k = line.split_whitespace().next()?;
            Some((n.parse().ok()?, k.parse().ok()?))
        })
        .collect();
    assert_eq!(printed, [(50, 50), (100, 100), (150, 150)], "{err}");
    let logs: Vec<LogMsg> = messages(&file, schema::LOG)
        .into_iter()
        .map(|v| serde_json::from_value(v).expect("a log message"))
        .collect();
    let recorded: Vec<(u64, u64)> = logs
        .iter()
        .flat_map(|m| {
            m.lines.iter().filter_map(move |l| {
                let k = l.strip_prefix("tally ")?.split_whitespace().next()?;
                Some((m.step, k.parse().ok()?))
            })
        })
        .collect();
    assert_eq!(recorded, printed);
}

/// A failing test of 300 critters over 600 steps: its recording holds the test file and the
/// kind it spawned, full states only every few dozen steps, and stays small.
#[test]
fn a_failing_tests_recording_has_its_scripts_and_stays_small() {
    let dir = tmp("test-recording");
    std::fs::create_dir_all(dir.join("kinds")).expect("kinds dir");
    std::fs::copy(
        Path::new(ROOT).join("scripts/tests/kinds/vars_counter.rhai"),
        dir.join("kinds/vars_counter.rhai"),
    )
    .expect("copy the kind");
    std::fs::write(
        dir.join("big.rhai"),
        r#"
fn test_fails_after_a_long_run() {
    let w = world(#{ dim: 2, size: vec(60, 60), seed: 2 });
    w.walls_around();
    w.vars.hits = 0;
    w.vars.updates = 0;
    for i in 0..300 {
        spawn("vars_counter", #{ pos: vec(2 + (i % 20) * 2.8, 2 + (i / 20) * 2.8),
                                 vel: vec(rand(-2.0, 2.0), rand(-2.0, 2.0)), radius: 0.5 });
    }
    w.step(600);
    assert(false, "fails on purpose");
}
"#,
    )
    .expect("write the test");
    let o = critterbox_in(
        &dir,
        &[
            "test",
            "big.rhai",
            "--record-failures",
            "failures",
            "--timeout",
            "600",
        ],
    );
    assert!(!o.status.success(), "{}", text(&o));
    let file = dir.join("failures/big-test_fails_after_a_long_run.mcap");
    let rec = Recording::open(&file).unwrap_or_else(|e| panic!("{e}\n{}", text(&o)));
    let names: Vec<&str> = rec.scripts.iter().map(|(n, _)| n.as_str()).collect();
    assert!(names.contains(&"big.rhai"), "{names:?}");
    assert!(
        names.iter().any(|n| n.ends_with("vars_counter.rhai")),
        "{names:?}"
    );
    assert_eq!(rec.last_step(), 600);
    let states = states(&file).len();
    assert!(states <= 600 / 30 + 2, "{states} full states");
    let bytes = std::fs::metadata(&file).expect("file").len();
    assert!(bytes < 2 << 20, "{bytes} bytes");
    // It can be inspected, and a recorded step shown.
    let o = critterbox_in(&dir, &["inspect", file.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let o = critterbox_in(&dir, &["replay", file.to_str().unwrap(), "--step", "60"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("vars_counter"), "{}", text(&o));
}
