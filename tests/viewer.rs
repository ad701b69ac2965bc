//! The Rerun viewer output, read back with rerun's own reader (the pinned `rerun-sdk` Python
//! package; `CRITTERBOX_PYTHON` names a Python that has it, default `python3`).
#![cfg(feature = "rerun")]

use critterbox::scenes::AnyWorld;
use critterbox::script::{load_scene, ScriptOptions};
use std::path::{Path, PathBuf};
use std::process::Command;

fn python() -> String {
    std::env::var("CRITTERBOX_PYTHON").unwrap_or_else(|_| "python3".into())
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// (entity paths, steps on the `step` timeline, the track of one entity's n-th point).
fn read_rrd(file: &Path, entity: &str, index: usize) -> (Vec<String>, usize, Vec<(i64, Vec<f64>)>) {
    let out = Command::new(python())
        .arg(root().join("tests/python/rrd_summary.py"))
        .arg(file)
        .arg(entity)
        .arg(index.to_string())
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "reading the .rrd failed (is rerun-sdk==0.36.3 installed? pip install rerun-sdk==0.36.3):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("the reader prints JSON");
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
    let rrd = dir.join("cradle.rrd");
    let scene = root().join("scripts/scenes/cradle.rhai");
    let steps = 90;
    let status = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args([
            "run",
            scene.to_str().expect("utf-8"),
            "--steps",
            &steps.to_string(),
            "--rerun-save",
        ])
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

    // The last ball's positions, step by step, as the library computes them (in f32, as logged).
    let mut expected = Vec::new();
    let mut scene = load_scene(&scene, &[], &ScriptOptions::default()).expect("the scene loads");
    let pos = |s: &critterbox::scenes::Scene| match &s.world {
        AnyWorld::D2(w) => {
            let c = w
                .critters()
                .iter()
                .filter(|c| !c.is_wall())
                .nth(5)
                .expect("six balls");
            vec![c.pos.x as f32 as f64, c.pos.y as f32 as f64]
        }
        AnyWorld::D3(_) => unreachable!("the cradle is 2D"),
    };
    expected.push((0i64, pos(&scene)));
    for step in 1..=steps {
        scene.step().expect("steps");
        expected.push((step as i64, pos(&scene)));
    }
    assert_eq!(track, expected);
    let _ = std::fs::remove_dir_all(&dir);
}
