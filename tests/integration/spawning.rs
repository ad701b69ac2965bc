//! Safe spawning, as a scene meets it: a spawn from a hook under `on_overlap: "error"` that
//! reaches into a wall fails with the spawn call's file:line:col, the hook's kind, the hook, the
//! critter and the step; the same spawn without `on_overlap` does not abort the run; a scene's own
//! spawn into a wall is an error as it always was; scene constants are `global::NAME` in helpers.

use crate::script_common;

use script_common::*;

const SCENE: &str = "let w = world(#{ dim: 2, size: vec(10, 10), seed: 1 });\n\
                     w.wall_box(vec(0, 0), vec(1, 10));\n\
                     spawn(\"walker\", #{ pos: vec(5, 5) });\n";

/// A walker whose update spawns a ball into the wall at step 2, with `policy` (or none).
fn walker(policy: &str) -> String {
    format!(
        "fn update(me, dt) {{\n    if world().step_count == 2 {{\n        spawn(\"ball\", #{{ pos: vec(0.8, 5){policy} }});\n    }}\n}}\n"
    )
}

#[test]
fn a_hook_spawn_into_a_wall_under_error_names_its_place() {
    let sandbox = Sandbox::new("spawn_error_place");
    let text = walker(", on_overlap: \"error\"");
    let kind_file = sandbox.kind("walker", &text);
    let mut scene = sandbox.load(SCENE);
    let me = of_kind(w2(&scene), "walker")[0];
    let mut failed = None;
    for n in 0..5u64 {
        if let Err(e) = scene.step() {
            failed = Some((n, e));
            break;
        }
    }
    let (n, e) = failed.expect("the spawn into the wall fails under on_overlap: \"error\"");
    assert_eq!(n, 2, "it fails in the step the hook spawned in");
    let text_of = e.to_string();
    let e = script_error(e);
    // The place of the spawn's kind argument, counted in the text itself.
    let line = text.lines().position(|l| l.contains("spawn(")).unwrap() + 1;
    let column = text
        .lines()
        .nth(line - 1)
        .unwrap()
        .find("\"ball\"")
        .unwrap()
        + 1;
    assert!(
        e.file.ends_with("walker.rhai") && kind_file.ends_with("walker.rhai"),
        "{text_of}"
    );
    assert_eq!((e.line, e.column), (Some(line), Some(column)), "{text_of}");
    assert_eq!(e.kind.as_deref(), Some("walker"), "{text_of}");
    assert_eq!(e.hook.as_deref(), Some("update"), "{text_of}");
    assert_eq!(e.critter, Some(me), "{text_of}");
    assert_eq!(e.step, Some(2), "{text_of}");
    assert!(text_of.contains("wall"), "{text_of}");
}

#[test]
fn a_hook_spawn_into_a_wall_does_not_abort_by_default() {
    let sandbox = Sandbox::new("spawn_default_push");
    sandbox.kind("walker", &walker(""));
    let mut scene = sandbox.load(SCENE);
    for _ in 0..5 {
        scene
            .step()
            .unwrap_or_else(|e| panic!("the run aborted:\n{e}"));
    }
    let balls = of_kind(w2(&scene), "ball");
    assert_eq!(balls.len(), 1);
    let ball = w2(&scene).get(balls[0]).unwrap();
    assert!(ball.pos.x - ball.radius() >= 1.0 - 1e-9, "{:?}", ball.pos);
}

#[test]
fn a_scene_spawn_into_a_wall_is_still_an_error() {
    let sandbox = Sandbox::new("spawn_scene_error");
    let e = sandbox
        .try_load(
            "let w = world(#{ dim: 2, size: vec(10, 10) });\nw.wall_box(vec(0, 0), vec(1, 10));\nspawn(\"ball\", #{ pos: vec(0.8, 5) });\n",
        )
        .err()
        .expect("a scene's spawn into a wall fails");
    let e = script_error(e);
    assert_eq!(e.line, Some(3), "{e}");
}

#[test]
fn scene_constants_are_global_names_in_helpers() {
    let sandbox = Sandbox::new("global_constants");
    let scene = sandbox.load(
        "const N = 3;\nfn how_many() { global::N }\nlet w = world(#{ dim: 2, size: vec(10, 10) });\nw.row(\"ball\", vec(2, 5), vec(2, 0), how_many(), #{});\n",
    );
    assert_eq!(of_kind(w2(&scene), "ball").len(), 3);
}

#[test]
fn a_hook_asking_for_a_name_that_is_no_kind_is_warned_of_once() {
    let sandbox = Sandbox::new("unknown_kind_warning");
    sandbox.kind(
        "asker",
        "fn update(me, dt) {\n    if me.is_kind(\"pray\") || world().count(\"pray\") > 0 {\n        me.die();\n    }\n}\n",
    );
    let mut scene = sandbox.load(
        "let w = world(#{ dim: 2, size: vec(10, 10), seed: 1 });\nspawn(\"asker\", #{ pos: vec(5, 5) });\n",
    );
    let mut warnings = Vec::new();
    for _ in 0..4 {
        scene
            .step()
            .expect("an unknown kind in a query does not stop the run");
        warnings.extend(
            w2(&scene)
                .events()
                .log
                .iter()
                .filter(|l| l.contains("no kind 'pray'"))
                .cloned(),
        );
    }
    assert_eq!(warnings.len(), 1, "warned once over 4 steps: {warnings:?}");
    assert!(warnings[0].starts_with("warning:"), "{}", warnings[0]);
    assert_eq!(
        of_kind(w2(&scene), "asker").len(),
        1,
        "the answers were false and none"
    );
}
