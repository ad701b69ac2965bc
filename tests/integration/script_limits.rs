//! Script limits bound work, not only operations: hostile hooks (data grown without end, a kind
//! whose every call stays just inside `--max-ops`) stop with the usual located error naming the
//! flag to raise, at the same step and critter on every run; and errors show vectors as users
//! write them.

use crate::script_common;

use critterbox::script::{load_scene, Limits, ScriptOptions};
use critterbox::{CritterId, ScriptError};
use script_common::*;
use std::path::Path;

const WORLD: &str = "let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });\n";

/// How a scene failed: the error, the steps completed before it, and the critters of the kind.
#[derive(Debug, PartialEq)]
struct Failure {
    err: ScriptError,
    steps_ok: u64,
    critters: Vec<CritterId>,
}

/// Loads and steps the scene at `path` (at most `max_steps`) until it fails.
fn fail(path: &Path, options: &ScriptOptions, kind: &str, max_steps: u64) -> Failure {
    let mut scene = load_scene(path, &[], options)
        .unwrap_or_else(|e| panic!("{} should load:\n{e}", path.display()));
    let critters = of_kind(w2(&scene), kind);
    for n in 0..max_steps {
        if let Err(e) = scene.step() {
            return Failure {
                err: script_error(e),
                steps_ok: n,
                critters,
            };
        }
    }
    panic!("{} ran {max_steps} steps without an error", path.display());
}

/// Steps the scene at `path` `steps` times, failing the test on an error.
fn runs(path: &Path, options: &ScriptOptions, steps: u64) {
    let mut scene = load_scene(path, &[], options)
        .unwrap_or_else(|e| panic!("{} should load:\n{e}", path.display()));
    for n in 0..steps {
        if let Err(e) = scene.step() {
            panic!("step {n} failed:\n{e}");
        }
    }
}

/// A scene of `n` critters of `kind` (spawned in a row, far enough apart not to touch).
fn scene_of(sandbox: &Sandbox, kind: &str, n: usize) -> std::path::PathBuf {
    sandbox.scene(
        "x",
        &format!(
            "{WORLD}for i in 0..{n} {{ spawn(\"{kind}\", #{{ pos: vec(1 + (i % 10) * 1.8, 1 + (i / 10) * 0.9), radius: 0.3 }}); }}\n"
        ),
    )
}

fn limits(f: impl FnOnce(&mut Limits)) -> ScriptOptions {
    let mut options = ScriptOptions::default();
    f(&mut options.limits);
    options
}

/// The error of a one-critter scene whose kind's `update` is `body`, run twice: both runs must
/// stop alike. Checks the place (the hook's line), kind, hook, critter, step and the flag named.
#[track_caller]
fn hostile(name: &str, body: &str, options: &ScriptOptions, flags: &[&str]) -> ScriptError {
    let sandbox = Sandbox::new(name);
    let kind = sandbox.kind(name, &format!("fn update(me, dt) {{\n{body}\n}}\n"));
    let scene = scene_of(&sandbox, name, 1);
    let first = fail(&scene, options, name, 3);
    let again = fail(&scene, options, name, 3);
    assert_eq!(
        first, again,
        "two runs stop at the same step for the same reason"
    );
    let e = &first.err;
    let file = std::fs::canonicalize(&e.file).expect("the error names an existing file");
    assert_eq!(
        file,
        std::fs::canonicalize(&kind).expect("the kind file"),
        "{e}"
    );
    assert_eq!(
        (e.line, e.column),
        (Some(1), Some(1)),
        "the hook's line:\n{e}"
    );
    assert_eq!(e.kind.as_deref(), Some(name), "{e}");
    assert_eq!(e.hook.as_deref(), Some("update"), "{e}");
    assert_eq!(e.critter, Some(first.critters[0]), "{e}");
    assert_eq!(
        (e.step, first.steps_ok),
        (Some(0), 0),
        "the first call fails:\n{e}"
    );
    assert!(
        flags.iter().any(|flag| e.to_string().contains(flag)),
        "the error names one of {flags:?}:\n{e}"
    );
    first.err
}

#[test]
fn an_array_grown_without_end_stops_at_the_array_limit() {
    let e = hostile(
        "grow_array",
        "    let a = [];\n    loop { a.push(1); }",
        &limits(|l| l.max_array_size = 1000),
        &["--max-array"],
    );
    assert!(e.message.contains("array"), "{e}");
    // At the default limits the walks after each push, charged as operations, reach --max-ops
    // before the array reaches its limit: either way the call stops after bounded work.
    hostile(
        "grow_array",
        "    let a = [];\n    loop { a.push(1); }",
        &ScriptOptions::default(),
        &["--max-array", "--max-ops"],
    );
}

#[test]
fn an_array_appended_to_itself_stops_at_the_array_limit() {
    let e = hostile(
        "self_append",
        "    let a = [1];\n    loop { a += a; }",
        &ScriptOptions::default(),
        &["--max-array"],
    );
    assert!(e.message.contains("array"), "{e}");
}

#[test]
fn a_string_doubled_without_end_stops_at_the_string_limit() {
    let e = hostile(
        "double_string",
        "    let s = \"x\";\n    loop { s += s; }",
        &ScriptOptions::default(),
        &["--max-string"],
    );
    assert!(e.message.contains("string"), "{e}");
}

#[test]
fn a_map_grown_without_end_stops() {
    // rhai does not measure a map after `m[key] = value` adds a key: the operation limit stops
    // this one, and as nothing measures the map, each operation stays cheap.
    hostile(
        "grow_map",
        "    let m = #{};\n    let i = 0;\n    loop { m[`k${i}`] = i; i += 1; }",
        &ScriptOptions::default(),
        &["--max-map", "--max-ops"],
    );
}

#[test]
fn a_map_merged_into_without_end_stops_at_the_map_limit() {
    let e = hostile(
        "mixin_map",
        "    let m = #{};\n    let i = 0;\n    loop { let one = #{}; one[`k${i}`] = i; m.mixin(one); i += 1; }",
        &limits(|l| l.max_map_size = 1000),
        &["--max-map"],
    );
    assert!(e.message.contains("map"), "{e}");
}

/// A loop of method calls on an array held at the array limit: rhai walks the whole array after
/// each call, so the walk is charged as operations. Uncharged, these 10,000 loops are about
/// 20,000 operations and pass; charged (10,000 items walked per call), they pass `--max-ops`
/// after a few hundred loops, so the call's time stays bounded by the count.
#[test]
fn method_calls_on_a_full_array_are_charged_for_the_walk() {
    let limit = ScriptOptions::default().limits.max_array_size;
    let e = hostile(
        "walk_array",
        &format!("    let a = [];\n    a.pad({limit}, 0);\n    for i in 0..10000 {{ a.len(); }}"),
        &ScriptOptions::default(),
        &["--max-ops"],
    );
    assert!(e.message.contains("operations in one call"), "{e}");
}

/// The charge is for the items walked, not for the calls: 1,000 calls on a 3-item array stay
/// inside a budget of 10,000 operations that the same calls on a 1,000-item array pass.
#[test]
fn the_charge_grows_with_the_items_walked() {
    let body = |n: usize| {
        format!("fn update(me, dt) {{\n    let a = [];\n    a.pad({n}, 0);\n    for i in 0..1000 {{ a.len(); }}\n}}\n")
    };
    let options = limits(|l| l.max_operations = 10_000);
    let small = Sandbox::new("walk_small");
    small.kind("walk_small", &body(3));
    runs(&scene_of(&small, "walk_small", 1), &options, 3);
    let large = Sandbox::new("walk_large");
    large.kind("walk_large", &body(1000));
    let failure = fail(
        &scene_of(&large, "walk_large", 1),
        &options,
        "walk_large",
        3,
    );
    assert!(
        failure.err.message.contains("more than 10000 operations"),
        "{}",
        failure.err
    );
}

#[test]
fn nested_arrays_grown_without_end_stop_at_the_array_limit() {
    hostile(
        "nested_array",
        "    let a = [];\n    loop { a.push([1, 2, 3, 4]); }",
        &ScriptOptions::default(),
        &["--max-array"],
    );
}

#[test]
fn items_of_nested_arrays_count_toward_the_array_limit() {
    // Each pushed [1, 2, 3, 4] is 5 items (itself and its 4): 20 pushes are 100 items, 21 are 105.
    let options = limits(|l| l.max_array_size = 100);
    let sandbox = Sandbox::new("nested_count");
    let push = |n: u32| {
        format!("fn update(me, dt) {{\n    let a = [];\n    for i in 0..{n} {{ a.push([1, 2, 3, 4]); }}\n}}\n")
    };
    sandbox.kind("fits", &push(20));
    sandbox.kind("overflows", &push(21));
    runs(&scene_of(&sandbox, "fits", 1), &options, 2);
    let f = fail(
        &scene_of(&sandbox, "overflows", 1),
        &options,
        "overflows",
        2,
    );
    assert!(f.err.to_string().contains("--max-array"), "{}", f.err);
}

/// A kind whose `update` counts to `n` (the same operations on every call).
fn counting_kind(n: u32) -> String {
    format!("fn update(me, dt) {{\n    let i = 0;\n    while i < {n} {{ i += 1; }}\n}}\n")
}

#[test]
fn hooks_each_inside_max_ops_stop_at_the_step_budget_on_the_same_critter_each_run() {
    // Every call stays inside --max-ops, but 30 of them pass the step's budget.
    let sandbox = Sandbox::new("step_budget");
    sandbox.kind("busy", &counting_kind(10_000));
    let scene = scene_of(&sandbox, "busy", 30);
    let options = limits(|l| l.max_step_operations = 300_000);
    let first = fail(&scene, &options, "busy", 3);
    let again = fail(&scene, &options, "busy", 3);
    assert_eq!(
        first, again,
        "two runs stop at the same critter, step and message"
    );
    let e = &first.err;
    assert_eq!((e.step, first.steps_ok), (Some(0), 0), "{e}");
    assert_eq!(e.hook.as_deref(), Some("update"), "{e}");
    let at = first
        .critters
        .iter()
        .position(|&c| Some(c) == e.critter)
        .unwrap_or_else(|| panic!("the error names one of the critters:\n{e}"));
    // The calls before it fit: the budget is shared, not per call.
    assert!(at > 0, "the first call alone fits the budget:\n{e}");
    assert!(
        e.message.contains("300000") && e.message.contains("step 0"),
        "{e}"
    );
    assert!(e.to_string().contains("--max-step-ops"), "{e}");
    // Without the budget, the same scene runs.
    runs(&scene, &limits(|l| l.max_step_operations = 0), 2);
}

#[test]
fn the_step_budget_starts_anew_each_step() {
    // Half the budget per step: over 4 steps the calls run twice the budget, and never fail.
    let sandbox = Sandbox::new("step_budget_reset");
    sandbox.kind("busy", &counting_kind(10_000));
    let scene = scene_of(&sandbox, "busy", 30);
    // Find one step's total: the least budget the scene runs one step under, by bisection.
    let runs_one = |max: u64| {
        let options = limits(|l| l.max_step_operations = max);
        let mut scene = load_scene(&scene, &[], &options).expect("the scene loads");
        scene.step().is_ok()
    };
    let (mut lo, mut hi) = (1u64, 10_000_000u64);
    assert!(runs_one(hi), "a step fits a budget of {hi}");
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if runs_one(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    // `hi` is one step's operations: two steps' worth runs 4 steps, a step's worth minus 1 fails.
    runs(&scene, &limits(|l| l.max_step_operations = 2 * hi), 4);
    runs(&scene, &limits(|l| l.max_step_operations = hi), 4);
    assert!(!runs_one(hi - 1), "one operation less stops the step");
}

#[test]
fn the_default_limits_run_every_shipped_scene() {
    for scene in shipped("scenes") {
        let mut loaded = load_scene(&scene, &[], &ScriptOptions::default())
            .unwrap_or_else(|e| panic!("{} should load:\n{e}", scene.display()));
        for n in 0..5 {
            if let Err(e) = loaded.step() {
                panic!("{} step {n}:\n{e}", scene.display());
            }
        }
    }
}

// ----- values as users write them ------------------------------------------------------------

#[test]
fn a_non_finite_velocity_is_shown_as_users_write_vectors() {
    let sandbox = Sandbox::new("nan_vel");
    sandbox.kind(
        "nan",
        "fn update(me, dt) {\n    me.vel = vec(5, sqrt(-1.0));\n}\n",
    );
    let f = fail(
        &scene_of(&sandbox, "nan", 1),
        &ScriptOptions::default(),
        "nan",
        2,
    );
    let shown = f.err.to_string();
    assert!(
        shown.contains("(5, NaN)"),
        "x then y, two components in 2D:\n{shown}"
    );
    assert!(!shown.contains("DVec") && !shown.contains('['), "{shown}");
}

#[test]
fn a_spawn_at_a_non_finite_position_is_shown_as_users_write_vectors() {
    let sandbox = Sandbox::new("nan_pos");
    let e = sandbox
        .try_load(&format!(
            "{WORLD}spawn(\"ball\", #{{ pos: vec(5, sqrt(-1.0)) }});\n"
        ))
        .err()
        .expect("a spawn at NaN fails");
    let shown = e.to_string();
    assert!(shown.contains("(5, NaN)"), "{shown}");
    assert!(!shown.contains("DVec"), "{shown}");
}

#[test]
fn a_vec_where_a_number_belongs_is_shown_with_its_script_type() {
    let sandbox = Sandbox::new("vec_for_number");
    let e = sandbox
        .try_load(&format!(
            "{WORLD}spawn(\"ball\", #{{ pos: vec(5, 5), radius: vec(1, 2) }});\n"
        ))
        .err()
        .expect("a Vec radius fails");
    let shown = e.to_string();
    assert!(shown.contains("got (1, 2) (Vec)"), "{shown}");
    assert!(!shown.contains("glam"), "{shown}");
}

#[test]
fn vectors_print_with_the_worlds_components() {
    // A scene's error text is built by the script: print's text is the same `to_string`.
    let sandbox = Sandbox::new("vec_text");
    for (dim, want) in [(2, "(5, 0.5)"), (3, "(5, 0.5, 0)")] {
        let e = sandbox
            .try_load(&format!(
                "let w = world(#{{ dim: {dim}, size: 10, seed: 1 }});\nthrow `${{vec(5, 0.5)}}`;\n"
            ))
            .err()
            .expect("the scene throws");
        let e = script_error(e);
        assert_eq!(e.message, want, "{dim}D:\n{e}");
    }
}
