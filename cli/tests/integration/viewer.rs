//! The Rerun viewer output, read back with rerun's own reader (the pinned `rerun-sdk` Python
//! package; `CRITTERBOX_PYTHON` names a Python that has it, default `python3`).
#![cfg(feature = "rerun")]

use critterbox::recording::reader::{for_each_state, Flow};
use std::path::{Path, PathBuf};
use std::process::Command;

fn python() -> String {
    std::env::var("CRITTERBOX_PYTHON").unwrap_or_else(|_| "python3".into())
}

fn root() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// One point's coordinates at each step: (step, coordinates).
type Track = Vec<(i64, Vec<f64>)>;

/// Runs one of the Python readers in `tests/python` on an .rrd file; its standard output.
fn python_reader(script: &str, file: &Path, args: &[&str]) -> Vec<u8> {
    let out = Command::new(python())
        .arg(root().join("tests/python").join(script))
        .arg(file)
        .args(args)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "reading the .rrd failed (is rerun-sdk==0.36.3 installed? pip install rerun-sdk==0.36.3):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// (entity paths, steps on the `step` timeline, the track of one entity's n-th point).
fn read_rrd(file: &Path, entity: &str, index: usize) -> (Vec<String>, usize, Track) {
    let out = python_reader("rrd_summary.py", file, &[entity, &index.to_string()]);
    let v: serde_json::Value = serde_json::from_slice(&out).expect("the reader prints JSON");
    let entities = v["entities"]
        .as_array()
        .expect("entities")
        .iter()
        .map(|e| e.as_str().expect("path").to_string())
        .collect();
    let steps = v["steps"].as_u64().expect("steps") as usize;
    let track = v["track"]
        .as_array()
        .expect("track")
        .iter()
        .map(|p| {
            let step = p[0].as_i64().expect("step");
            let xy = p[1]
                .as_array()
                .expect("point")
                .iter()
                .map(|x| x.as_f64().expect("coordinate"))
                .collect();
            (step, xy)
        })
        .collect();
    (entities, steps, track)
}

#[test]
fn a_saved_run_has_the_entities_steps_and_positions_of_the_run() {
    let dir = std::env::temp_dir().join(format!("critterbox-viewer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let (rrd, mcap) = (dir.join("cradle.rrd"), dir.join("cradle.mcap"));
    let scene = root().join("scripts/scenes/cradle.rhai");
    let steps = 90;
    // One run, both outputs: the viewer file and a recording with every step's full state.
    let status = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args([
            "run",
            scene.to_str().expect("utf-8"),
            "--steps",
            &steps.to_string(),
            "--record-every",
            "1",
            "--record",
        ])
        .arg(&mcap)
        .arg("--rerun-save")
        .arg(&rrd)
        .status()
        .expect("critterbox runs");
    assert!(status.success());

    let (entities, seen_steps, track) = read_rrd(&rrd, "/world/critters/ball", 5);
    for path in [
        "/world/critters/ball",
        "/world/velocities/ball",
        "/world/contacts",
        "/stats/kinetic_energy",
        "/world/border",
    ] {
        assert!(
            entities.iter().any(|e| e == path),
            "{path} missing from {entities:?}"
        );
    }
    // Step 0 (the start) and every step after it.
    assert_eq!(seen_steps, steps + 1);

    // The sixth ball's positions, step by step, from the MCAP recording of the same run (the
    // viewer gets them in f32).
    let mut expected = Vec::new();
    for_each_state(&mcap, |s| {
        let i = (0..s.len())
            .filter(|&i| s.kind_name(i) == "ball")
            .nth(5)
            .expect("six balls");
        let at = |name: &str| {
            s.fields(i)
                .iter()
                .find(|(n, _)| *n == name)
                .map(|(_, x)| *x as f32 as f64)
                .expect("a coordinate")
        };
        expected.push((s.step as i64, vec![at("x"), at("y")]));
        Ok(Flow::Continue)
    })
    .expect("the recording reads");
    assert_eq!(expected.len(), steps + 1, "a full state at every step");
    assert_eq!(track, expected);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every logged value of a Rerun file, one sorted line each, leaving out the wall-clock step
/// times (`/stats/step_ms`).
fn dump_rrd(file: &Path) -> Vec<String> {
    String::from_utf8(python_reader("rrd_dump.py", file, &["/stats/step_ms"]))
        .expect("utf-8")
        .lines()
        .map(str::to_string)
        .collect()
}

#[test]
fn a_replayed_recording_sends_the_viewer_what_the_live_run_sent() {
    let dir = std::env::temp_dir().join(format!("critterbox-viewer-replay-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let (live, replayed, mcap) = (
        dir.join("live.rrd"),
        dir.join("replayed.rrd"),
        dir.join("run.mcap"),
    );
    // A scene with spawns, deaths and script log lines as well as collisions; full states only
    // every 25 steps, so the replay must re-simulate the steps between them.
    let scene = root().join("scripts/scenes/bullets_vs_player.rhai");
    let steps = 120;
    let status = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args(["run", scene.to_str().expect("utf-8"), "--steps"])
        .arg(steps.to_string())
        .args(["--record-every", "25", "--record"])
        .arg(&mcap)
        .arg("--rerun-save")
        .arg(&live)
        .status()
        .expect("critterbox runs");
    assert!(status.success());
    let status = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .arg("replay")
        .arg(&mcap)
        .arg("--rerun-save")
        .arg(&replayed)
        .status()
        .expect("critterbox replay runs");
    assert!(status.success());

    let (a, b) = (dump_rrd(&live), dump_rrd(&replayed));
    // Not vacuous: critter positions at every step, and some text log entries.
    let position_steps: std::collections::BTreeSet<String> = a
        .iter()
        .filter(|l| l.starts_with("[\"/world/critters/") && l.contains(":positions\""))
        .map(|l| l.split(',').nth(1).unwrap_or_default().trim().to_string())
        .collect();
    assert_eq!(
        position_steps.len(),
        steps + 1,
        "positions at steps 0..={steps}"
    );
    assert!(a.iter().any(|l| l.starts_with("[\"/log\"")), "log entries");
    if a != b {
        let first = a
            .iter()
            .zip(&b)
            .position(|(x, y)| x != y)
            .unwrap_or(a.len().min(b.len()));
        panic!(
            "the replay differs from the live run at line {first} of {} / {}:\n live:   {:?}\n replay: {:?}",
            a.len(),
            b.len(),
            a.get(first),
            b.get(first)
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
