//! Hot reload (`run --watch`): a kind file rewritten while its run goes on replaces the kind at
//! the next step, kinds that extend it follow, a text that does not compile changes nothing,
//! and the recording of such a run verifies bit for bit with the same swaps.

use critterbox::recording::verify::verify;
use critterbox::recording::{EndMeta, Recorder, Recording, RunMeta, RunOverrides};
use critterbox::scenes::{AnyWorld, Scene};
use critterbox::script::{load_scene, ScriptOptions};
use critterbox::PropValue;
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("critterbox-reload-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("scenes")).expect("scenes dir");
    std::fs::create_dir_all(dir.join("kinds")).expect("kinds dir");
    dir
}

/// A kind that sets its critters moving along `vel` every step, with `dir` among its defaults.
fn mover(vel: &str, dir: i64) -> String {
    format!(
        "defaults(#{{ radius: 0.5, props: #{{ dir: {dir} }} }});\n\
         fn update(me, dt) {{\n    me.vel = {vel};\n}}\n"
    )
}

/// A scene of three movers and three critters of a kind that extends `mover` and adds nothing.
fn scene_in(dir: &Path) -> Scene {
    std::fs::write(dir.join("kinds/mover.rhai"), mover("vec(1.0, 0.0)", 1)).expect("kind");
    std::fs::write(dir.join("kinds/follower.rhai"), "extends \"mover\";\n").expect("kind");
    std::fs::write(
        dir.join("scenes/hot.rhai"),
        "let w = world(#{ dim: 2, size: vec(40, 40), seed: 3 });\n\
         w.walls_around();\n\
         for i in 0..3 {\n\
             spawn(\"mover\", #{ pos: vec(5.0 + 6.0 * i, 10.0) });\n\
             spawn(\"follower\", #{ pos: vec(5.0 + 6.0 * i, 30.0) });\n\
         }\n",
    )
    .expect("scene");
    load_scene(&dir.join("scenes/hot.rhai"), &[], &ScriptOptions::default()).expect("the scene")
}

/// Every critter of kind `kind`: velocity and the property `dir`.
fn critters(scene: &Scene, kind: &str) -> Vec<([f64; 2], Option<PropValue>)> {
    let AnyWorld::D2(w) = &scene.world else {
        panic!("a 2D scene")
    };
    let id = w.kinds().id(kind).expect("the kind");
    w.critters()
        .iter()
        .filter(|c| c.kind() == id)
        .map(|c| ([c.vel.x, c.vel.y], c.props().get("dir").cloned()))
        .collect()
}

fn all_move(scene: &Scene, kind: &str, vel: [f64; 2]) -> bool {
    let cs = critters(scene, kind);
    !cs.is_empty() && cs.iter().all(|(v, _)| *v == vel)
}

/// The file the scene loaded a kind from (as its sources name it).
fn kind_file(scene: &Scene, kind: &str) -> String {
    let name = format!("{kind}.rhai");
    scene
        .sources
        .iter()
        .map(|s| s.path.clone())
        .find(|p| p.ends_with(&name))
        .expect("the kind's file among the sources")
}

#[test]
fn a_rewritten_kind_replaces_its_kind_at_the_next_step_and_the_run_verifies() {
    let dir = scratch("switch");
    let mut scene = scene_in(&dir);
    let path = dir.join("hot.mcap");
    let meta = RunMeta::for_scene(&scene, &RunOverrides::default());
    let mut rec = Recorder::create(&path, &meta, &scene.sources, &scene.world).expect("create");
    let file = kind_file(&scene, "mover");
    let step = |scene: &mut Scene, rec: &mut Recorder| {
        scene.step().expect("a step");
        rec.record(&scene.world).expect("recorded");
    };
    for _ in 0..10 {
        step(&mut scene, &mut rec);
    }
    assert!(all_move(&scene, "mover", [1.0, 0.0]));
    assert!(all_move(&scene, "follower", [1.0, 0.0]));

    // The file is rewritten: up, and a new default for new critters.
    let up = mover("vec(0.0, 1.0)", 2);
    std::fs::write(&file, &up).expect("rewrite");
    let kinds = scene.reload_kind(&file, &up).expect("the new text loads");
    assert_eq!(
        kinds,
        ["mover", "follower"],
        "the kind, then the kind that extends it"
    );
    rec.reload(&scene.world, &file, &up, kinds)
        .expect("recorded");
    // Nothing moved yet: the swap is between steps.
    assert!(all_move(&scene, "mover", [1.0, 0.0]));
    step(&mut scene, &mut rec);
    assert!(all_move(&scene, "mover", [0.0, 1.0]), "the new update runs");
    assert!(all_move(&scene, "follower", [0.0, 1.0]), "and is inherited");
    // The critters keep their own state: the default they were spawned with.
    assert!(critters(&scene, "mover")
        .iter()
        .all(|(_, dir)| *dir == Some(PropValue::Int(1))));

    // A text that does not compile changes nothing, and the old (new) version runs on.
    let broken = "fn update(me, dt) {\n    me.vel = vec(0.0, \n}\n";
    let err = scene
        .reload_kind(&file, broken)
        .expect_err("a syntax error");
    let message = err.to_string();
    assert!(
        message.contains("mover.rhai:3:1"),
        "file:line:col in {message}"
    );
    for _ in 0..5 {
        step(&mut scene, &mut rec);
    }
    assert!(all_move(&scene, "mover", [0.0, 1.0]));
    assert!(all_move(&scene, "follower", [0.0, 1.0]));

    let end = EndMeta {
        steps: scene.world.step_count(),
        outcome: "completed".into(),
        hash: scene.world.state_hash(),
        ..EndMeta::default()
    };
    rec.finish(&scene.world, end).expect("finish");

    let recording = Recording::open(&path).expect("the recording reads");
    assert_eq!(
        recording.reloads.len(),
        1,
        "the broken edit is not recorded"
    );
    assert_eq!(recording.reloads[0].step, 10);
    assert_eq!(recording.reloads[0].kinds, ["mover", "follower"]);
    let report = verify(&recording, |_| {}).expect("verifies");
    assert!(report.passed(), "{report:?}");
    assert_eq!(report.steps, 16);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Without the reload the replay departs from the recording: verify really replays the swap.
#[test]
fn a_replay_without_the_swap_would_depart_from_the_run() {
    let dir = scratch("depart");
    let mut scene = scene_in(&dir);
    let file = kind_file(&scene, "mover");
    let mut plain = scene_in(&scratch("depart-plain"));
    for _ in 0..3 {
        scene.step().expect("a step");
        plain.step().expect("a step");
    }
    assert_eq!(scene.world.state_hash(), plain.world.state_hash());
    scene
        .reload_kind(&file, &mover("vec(0.0, 1.0)", 1))
        .expect("reloads");
    scene.step().expect("a step");
    plain.step().expect("a step");
    assert_ne!(scene.world.state_hash(), plain.world.state_hash());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_file_of_no_loaded_kind_or_a_built_in_scene_cannot_be_reloaded() {
    let dir = scratch("none");
    let mut scene = scene_in(&dir);
    let err = scene
        .reload_kind("kinds/elsewhere.rhai", &mover("vec(0.0, 1.0)", 1))
        .expect_err("no such kind file");
    assert!(err.to_string().contains("defines no kind loaded"), "{err}");
    let params = critterbox::scenes::SceneParams::default();
    let mut gas = critterbox::scenes::builtin("gas", &params).expect("gas");
    assert!(gas.reload_kind("kinds/mover.rhai", "").is_err());
    let _ = std::fs::remove_dir_all(&dir);
}
