//! Script errors: every mistake in a scene or kind script comes back as a `ScriptError` (never a
//! panic) that names the file, the line and column, and for hooks the kind, hook, critter and step,
//! with a hint; and `check` accepts every shipped script and rejects a broken one with its place.

use crate::script_common;

use critterbox::script::{check, load_scene, Limits, ScriptOptions};
use critterbox::{CritterId, Error, ScriptError};
use script_common::*;
use std::ops::RangeInclusive;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const WORLD: &str = "let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });\n";

/// How a scene failed: the error, the steps that completed before it, and the critters of the
/// kind under test as they were after loading.
struct Failure {
    err: ScriptError,
    steps_ok: u64,
    critters: Vec<CritterId>,
}

/// Runs `f`, failing the test if it panics (the script layer must return errors, not panic).
fn no_panic<T>(what: &str, f: impl FnOnce() -> T) -> T {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(v) => v,
        Err(_) => panic!("{what}: the script layer panicked instead of returning an error"),
    }
}

/// Loads the scene at `path` and steps it (at most `max_steps`) until it fails.
fn fail(path: &Path, options: &ScriptOptions, kind: &str, max_steps: u64) -> Failure {
    let outcome = no_panic(&path.display().to_string(), || {
        let mut scene = match load_scene(path, &[], options) {
            Ok(scene) => scene,
            Err(e) => return Ok((e, 0, Vec::new())),
        };
        let critters = of_kind(w2(&scene), kind);
        for n in 0..max_steps {
            if let Err(e) = scene.step() {
                return Ok((e, n, critters));
            }
        }
        Err(format!(
            "{} ran {max_steps} steps without an error",
            path.display()
        ))
    });
    match outcome {
        Ok((e, steps_ok, critters)) => Failure {
            err: script_error(e),
            steps_ok,
            critters,
        },
        Err(msg) => panic!("{msg}"),
    }
}

/// Loads a scene that must fail while loading.
fn fail_load(path: &Path, sets: &[(&str, &str)]) -> ScriptError {
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let loaded = no_panic(&path.display().to_string(), || {
        load_scene(path, &sets, &ScriptOptions::default()).map(drop)
    });
    match loaded {
        Ok(()) => panic!("{} should fail to load", path.display()),
        Err(e) => script_error(e),
    }
}

/// The 1-based column of `needle` in line `line` (1-based) of `text`.
#[track_caller]
fn col_of(text: &str, line: usize, needle: &str) -> usize {
    let l = text.lines().nth(line - 1).expect("the line exists");
    l.find(needle)
        .unwrap_or_else(|| panic!("{needle:?} is not in line {line}: {l:?}"))
        + 1
}

/// The 1-based line of the first line of `text` containing `needle`.
#[track_caller]
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("{needle:?} is not in the text"))
        + 1
}

/// The columns `needle` covers in line `line`.
fn span_of(text: &str, line: usize, needle: &str) -> RangeInclusive<usize> {
    let start = col_of(text, line, needle);
    start..=start + needle.len() - 1
}

fn same_file(reported: &str, expected: &Path) -> bool {
    match (
        std::fs::canonicalize(reported),
        std::fs::canonicalize(expected),
    ) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// Asserts the error is located in `file` at `line`, with a column in `cols`, and that its
/// Display starts with `file:line:col`.
#[track_caller]
fn assert_place(e: &ScriptError, file: &Path, line: usize, cols: RangeInclusive<usize>) {
    assert!(
        same_file(&e.file, file),
        "the error should name {}, names {:?}:\n{e}",
        file.display(),
        e.file
    );
    assert_eq!(e.line, Some(line), "line of:\n{e}");
    let col = e.column.unwrap_or_else(|| panic!("a column for:\n{e}"));
    assert!(
        cols.contains(&col),
        "column {col} should be in {cols:?}:\n{e}"
    );
    let place = format!("{}:{line}:{col}", e.file);
    assert!(
        e.to_string().starts_with(&place),
        "Display should start with {place}:\n{e}"
    );
}

/// Asserts the error names the kind, hook, critter and step.
#[track_caller]
fn assert_hook(f: &Failure, kind: &str, hook: &str) {
    let e = &f.err;
    assert_eq!(e.kind.as_deref(), Some(kind), "kind of:\n{e}");
    assert_eq!(e.hook.as_deref(), Some(hook), "hook of:\n{e}");
    assert_eq!(f.critters.len(), 1, "one critter of kind {kind}");
    assert_eq!(e.critter, Some(f.critters[0]), "critter of:\n{e}");
    assert_eq!(
        e.step,
        Some(f.steps_ok),
        "the step that failed ({} completed before it):\n{e}",
        f.steps_ok
    );
    let shown = e.to_string();
    for part in [
        format!("kind '{kind}'"),
        format!("in {hook}"),
        format!("critter {}", f.critters[0]),
        format!("step {}", f.steps_ok),
    ] {
        assert!(shown.contains(&part), "Display should say {part}:\n{shown}");
    }
}

// ----- syntax errors -------------------------------------------------------------------------

#[test]
fn syntax_error_in_a_scene_file_is_located_at_the_bad_token() {
    let sandbox = Sandbox::new("syntax_scene");
    let text = format!("{WORLD}let x = 1 +;\n");
    let path = sandbox.scene("x", &text);
    let e = fail_load(&path, &[]);
    let col = col_of(&text, 2, ";");
    assert_place(&e, &path, 2, col..=col);
    assert!(e.message.contains("syntax error"), "{e}");
    assert!(e.hint.is_some(), "a hint: {e}");
    assert_eq!(e.kind, None, "a scene is not a kind");
}

const BAD_KIND: &str =
    "// a kind with a syntax error\nfn collide(me, other) {\n    let x = ;\n    true\n}\n";

#[test]
fn syntax_error_in_a_kind_file_is_located_by_check() {
    let sandbox = Sandbox::new("syntax_kind_check");
    let path = sandbox.kind("bad", BAD_KIND);
    let result = no_panic("check", || {
        check(std::slice::from_ref(&path), &ScriptOptions::default())
    });
    let e = script_error(result.expect_err("a broken kind fails the check"));
    let col = col_of(BAD_KIND, 3, ";");
    assert_place(&e, &path, 3, col..=col);
    assert!(e.message.contains("syntax error"), "{e}");
}

/// Loaded from a scene (by spawning it or by load_kind), the kind's syntax error at least shows
/// the kind file's place in the text of the error.
#[test]
fn syntax_error_in_a_kind_file_loaded_by_a_scene_shows_the_kinds_place() {
    let sandbox = Sandbox::new("syntax_kind_scene");
    sandbox.kind("bad", BAD_KIND);
    let place = format!("bad.rhai:3:{}", col_of(BAD_KIND, 3, ";"));
    for how in [
        "spawn(\"bad\", #{ pos: vec(5, 5) });",
        "load_kind(\"bad\");",
    ] {
        let path = sandbox.scene("x", &format!("{WORLD}{how}\n"));
        let e = fail_load(&path, &[]);
        let shown = e.to_string();
        assert!(
            shown.contains(&place),
            "{how}: should show {place}:\n{shown}"
        );
        assert!(shown.contains("syntax error"), "{how}:\n{shown}");
    }
}

#[test]

fn syntax_error_in_a_kind_file_loaded_by_a_scene_is_an_error_of_that_kind_file() {
    let sandbox = Sandbox::new("syntax_kind_scene_strict");
    let kind = sandbox.kind("bad", BAD_KIND);
    let col = col_of(BAD_KIND, 3, ";");
    for how in [
        "spawn(\"bad\", #{ pos: vec(5, 5) });",
        "load_kind(\"bad\");",
    ] {
        let path = sandbox.scene("x", &format!("{WORLD}{how}\n"));
        let e = fail_load(&path, &[]);
        assert_place(&e, &kind, 3, col..=col);
        assert_eq!(e.kind.as_deref(), Some("bad"), "{how}: kind of:\n{e}");
    }
}

#[test]

fn init_error_at_scene_setup_names_the_kind_hook_and_critter() {
    let sandbox = Sandbox::new("init_error");
    let text = "fn init(me) {\n    me.nothing_here += 1;\n}\n";
    let kind = sandbox.kind("badinit", text);
    let path = sandbox.scene(
        "x",
        &format!("{WORLD}spawn(\"badinit\", #{{ pos: vec(5, 5) }});\n"),
    );
    let e = fail_load(&path, &[]);
    assert_place(&e, &kind, 2, span_of(text, 2, "me.nothing_here"));
    assert_eq!(e.kind.as_deref(), Some("badinit"), "{e}");
    assert_eq!(e.hook.as_deref(), Some("init"), "{e}");
    assert!(e.critter.is_some(), "{e}");
}

#[test]
fn hook_with_the_wrong_number_of_parameters_is_located_by_check() {
    let sandbox = Sandbox::new("arity");
    let text = "\nfn update(me) {\n}\n";
    let path = sandbox.kind("lazy", text);
    let result = no_panic("check", || {
        check(std::slice::from_ref(&path), &ScriptOptions::default())
    });
    let e = script_error(result.expect_err("update takes (me, dt)"));
    assert_place(&e, &path, 2, 1..=1);
    assert_eq!(e.kind.as_deref(), Some("lazy"));
    assert!(
        e.message.contains("update") && e.message.contains('2'),
        "{e}"
    );
}

// ----- errors in hooks -----------------------------------------------------------------------

/// A scene where a critter of `kind` moving right meets a resting ball after a few steps.
fn meeting_scene(sandbox: &Sandbox, kind: &str, extra: &str) -> PathBuf {
    sandbox.scene(
        "x",
        &format!(
            "{WORLD}spawn(\"{kind}\", #{{ pos: vec(5, 5), vel: vec(1, 0){extra} }});\n\
             spawn(\"ball\", #{{ pos: vec(6.2, 5) }});\n"
        ),
    )
}

#[test]
fn unknown_function_in_collide_names_kind_hook_critter_step_and_place() {
    let sandbox = Sandbox::new("unknown_fn");
    let text = "fn collide(me, other) {\n    me.frobnicate(other)\n}\n";
    let kind = sandbox.kind("unk", text);
    let f = fail(
        &meeting_scene(&sandbox, "unk", ""),
        &ScriptOptions::default(),
        "unk",
        60,
    );
    assert_place(&f.err, &kind, 2, span_of(text, 2, "me.frobnicate"));
    assert_hook(&f, "unk", "collide");
    assert!(f.steps_ok > 0, "it fails when they touch, not before");
    assert!(f.err.message.contains("frobnicate"), "{}", f.err);
    assert!(
        f.err
            .hint
            .as_deref()
            .is_some_and(|h| h.contains("frobnicate")),
        "a hint naming the function: {}",
        f.err
    );
}

#[test]
fn collides_with_returning_7_points_at_its_fn_line() {
    let sandbox = Sandbox::new("rule_7");
    let text =
        "// answers with a number that is no rule\nfn collides_with(me, other) {\n    7\n}\n";
    let kind = sandbox.kind("seven", text);
    let f = fail(
        &meeting_scene(&sandbox, "seven", ""),
        &ScriptOptions::default(),
        "seven",
        60,
    );
    let line = line_of(text, "fn collides_with");
    assert_place(&f.err, &kind, line, 1..=1);
    assert_hook(&f, "seven", "collides_with");
    assert!(f.err.message.contains('7'), "{}", f.err);
    assert!(
        f.err
            .hint
            .as_deref()
            .is_some_and(|h| h.contains("rule constants")),
        "a hint: {}",
        f.err
    );
}

#[test]
fn collides_with_returning_a_string_points_at_its_indented_fn_line() {
    let sandbox = Sandbox::new("rule_string");
    let text = "const X = 1;\n  fn collides_with(me, other) {\n    \"yes\"\n}\n";
    let kind = sandbox.kind("wordy", text);
    let f = fail(
        &meeting_scene(&sandbox, "wordy", ""),
        &ScriptOptions::default(),
        "wordy",
        60,
    );
    let col = col_of(text, 2, "fn");
    assert_place(&f.err, &kind, 2, col..=col);
    assert_hook(&f, "wordy", "collides_with");
    assert!(f.err.message.contains("string"), "{}", f.err);
    assert!(f.err.hint.is_some(), "a hint: {}", f.err);
}

#[test]
fn collide_returning_a_string_points_at_its_fn_line_with_a_hint() {
    let sandbox = Sandbox::new("collide_string");
    let text = "\nfn collide(me, other) {\n    \"handled\"\n}\n";
    let kind = sandbox.kind("chatty", text);
    // At CP_PLAYER it calls on the ball.
    let f = fail(
        &meeting_scene(&sandbox, "chatty", ", priority: CP_PLAYER"),
        &ScriptOptions::default(),
        "chatty",
        60,
    );
    assert_place(&f.err, &kind, 2, 1..=1);
    assert_hook(&f, "chatty", "collide");
    assert!(f.err.message.contains("true or false"), "{}", f.err);
    assert!(
        f.err
            .hint
            .as_deref()
            .is_some_and(|h| h.contains("collide_default")),
        "a hint: {}",
        f.err
    );
}

#[test]
fn endless_loop_in_update_stops_at_the_operation_limit() {
    let sandbox = Sandbox::new("endless");
    let text = "fn update(me, dt) {\n    let i = 0;\n    loop { i += 1; }\n}\n";
    let kind = sandbox.kind("spinner", text);
    let scene = sandbox.scene(
        "x",
        &format!("{WORLD}spawn(\"spinner\", #{{ pos: vec(5, 5) }});\n"),
    );
    let options = ScriptOptions {
        limits: Limits {
            max_operations: 100_000,
            ..Default::default()
        },
        ..Default::default()
    };
    let start = Instant::now();
    let f = fail(&scene, &options, "spinner", 5);
    let took = start.elapsed();
    assert!(took < Duration::from_secs(10), "stopped after {took:?}");
    assert_place(&f.err, &kind, 1, 1..=1);
    assert_hook(&f, "spinner", "update");
    assert_eq!(f.steps_ok, 0, "the first update never ends");
    assert!(
        f.err.message.contains("operations") && f.err.message.contains("100000"),
        "{}",
        f.err
    );
    assert!(f.err.hint.is_some(), "a hint: {}", f.err);
}

/// A property no kind declared and no field is near (`me.velocity` gets "did you mean `vel`?",
/// `scripts/tests/field_typos.rhai`).
const TYPO_KIND: &str = "fn update(me, dt) {\n    me.heading = vec(1, 0);\n}\n";

#[test]
fn typo_in_a_property_set_is_an_error_suggesting_set_prop() {
    let sandbox = Sandbox::new("typo");
    let kind = sandbox.kind("typo", TYPO_KIND);
    let scene = sandbox.scene(
        "x",
        &format!("{WORLD}spawn(\"typo\", #{{ pos: vec(5, 5) }});\n"),
    );
    let f = fail(&scene, &ScriptOptions::default(), "typo", 5);
    assert_place(&f.err, &kind, 2, span_of(TYPO_KIND, 2, "me.heading"));
    assert_hook(&f, "typo", "update");
    assert!(f.err.message.contains("heading"), "{}", f.err);
    assert!(f.err.to_string().contains("set_prop"), "{}", f.err);
}

#[test]

fn typo_in_a_property_set_has_a_hint_mentioning_set_prop() {
    let sandbox = Sandbox::new("typo_hint");
    sandbox.kind("typo", TYPO_KIND);
    let scene = sandbox.scene(
        "x",
        &format!("{WORLD}spawn(\"typo\", #{{ pos: vec(5, 5) }});\n"),
    );
    let f = fail(&scene, &ScriptOptions::default(), "typo", 5);
    assert!(
        f.err
            .hint
            .as_deref()
            .is_some_and(|h| h.contains("set_prop")),
        "{}",
        f.err
    );
}

#[test]
fn error_in_on_step_names_the_scene_line_hook_and_step() {
    let sandbox = Sandbox::new("on_step");
    let text = format!(
        "{WORLD}fn on_step(world) {{\n    if world.step_count == 3 {{ world.explode(); }}\n}}\n"
    );
    let path = sandbox.scene("x", &text);
    let f = fail(&path, &ScriptOptions::default(), "ball", 10);
    assert_place(&f.err, &path, 3, span_of(&text, 3, "world.explode"));
    assert_eq!(f.err.hook.as_deref(), Some("on_step"));
    // on_step runs after the step: the world it sees has counted that step.
    assert_eq!(f.steps_ok + 1, 3, "the third on_step fails");
    assert_eq!(
        f.err.step,
        Some(3),
        "the step_count on_step saw:\n{}",
        f.err
    );
}

// ----- errors in scene setup -----------------------------------------------------------------

#[test]
fn spawn_map_with_an_unknown_field_is_an_error_listing_the_fields() {
    let sandbox = Sandbox::new("spawn_field");
    let path = sandbox.scene(
        "x",
        &format!("{WORLD}spawn(\"ball\", #{{ pos: vec(5, 5), colour: \"red\" }});\n"),
    );
    let e = fail_load(&path, &[]);
    assert!(same_file(&e.file, &path), "{e}");
    assert!(e.message.contains("'colour'"), "{e}");
    for field in ["pos", "vel", "radius", "props"] {
        assert!(e.message.contains(field), "lists {field}: {e}");
    }
}

#[test]
fn spawning_an_unknown_kind_is_an_error_naming_it_and_where_kinds_are_looked_for() {
    let sandbox = Sandbox::new("spawn_kind");
    let path = sandbox.scene(
        "x",
        &format!("{WORLD}spawn(\"dragon\", #{{ pos: vec(5, 5) }});\n"),
    );
    let e = fail_load(&path, &[]);
    assert!(same_file(&e.file, &path), "{e}");
    assert!(e.message.contains("'dragon'"), "{e}");
    assert!(
        e.message.contains("dragon.rhai"),
        "says which file it looked for: {e}"
    );
}

#[test]

fn errors_inside_spawn_name_the_line_of_the_spawn() {
    let sandbox = Sandbox::new("spawn_line");
    for bad in [
        "spawn(\"ball\", #{ pos: vec(5, 5), colour: \"red\" });",
        "spawn(\"dragon\", #{ pos: vec(5, 5) });",
        "spawn(\"ball\", 42);",
    ] {
        let text = format!("{WORLD}\n{bad}\n");
        let path = sandbox.scene("x", &text);
        let e = fail_load(&path, &[]);
        assert_place(&e, &path, 3, 1..=bad.len());
    }
}

#[test]
fn scene_that_never_calls_world_is_an_error_saying_how_to_start() {
    let sandbox = Sandbox::new("no_world");
    let path = sandbox.scene("x", "let x = 1;\nconst Y = 2;\n");
    let e = fail_load(&path, &[]);
    assert!(same_file(&e.file, &path), "{e}");
    assert!(e.message.contains("never made a world"), "{e}");
    assert!(
        e.hint.as_deref().is_some_and(|h| h.contains("world(#{")),
        "{e}"
    );
}

#[test]
fn set_of_a_constant_the_scene_lacks_lists_its_constants() {
    let path = shipped_scene("cradle");
    let e = fail_load(&path, &[("NOPE", "1")]);
    assert!(same_file(&e.file, &path), "{e}");
    assert!(e.message.contains("NOPE"), "{e}");
    let text = std::fs::read_to_string(&path).unwrap();
    let consts: Vec<&str> = text
        .lines()
        .filter_map(|l| l.trim_start().strip_prefix("const "))
        .filter_map(|r| r.split(|c: char| c == '=' || c.is_whitespace()).next())
        .collect();
    assert!(!consts.is_empty(), "the cradle has constants");
    let shown = e.to_string();
    for c in consts {
        assert!(shown.contains(c), "lists {c}:\n{shown}");
    }
}

#[test]
fn eval_is_refused() {
    let sandbox = Sandbox::new("eval");
    let text = format!("{WORLD}let x = eval(\"1\");\n");
    let path = sandbox.scene("x", &text);
    let e = fail_load(&path, &[]);
    let col = col_of(&text, 2, "eval");
    assert_place(&e, &path, 2, col..=col);
    assert!(e.message.contains("eval"), "{e}");
}

#[test]
fn eval_is_refused_inside_a_hook_too() {
    let sandbox = Sandbox::new("eval_hook");
    let text = "fn update(me, dt) {\n    eval(\"me.vel = vec(1, 0)\");\n}\n";
    let kind = sandbox.kind("sneaky", text);
    let result = no_panic("check", || {
        check(std::slice::from_ref(&kind), &ScriptOptions::default())
    });
    let e = script_error(result.expect_err("eval does not compile"));
    let col = col_of(text, 2, "eval");
    assert_place(&e, &kind, 2, col..=col);
}

#[test]
fn import_cannot_read_files() {
    let sandbox = Sandbox::new("import");
    // The module exists next to the scene: only the sandbox keeps it out.
    sandbox.scene("helper", "fn f() { 1 }\n");
    let text = format!("import \"helper\" as h;\n{WORLD}");
    let path = sandbox.scene("x", &text);
    let e = fail_load(&path, &[]);
    assert_place(&e, &path, 1, span_of(&text, 1, "import \"helper\""));
    assert!(e.message.contains("helper"), "{e}");
}

// ----- check ---------------------------------------------------------------------------------

#[test]
fn check_passes_on_every_shipped_script() {
    let mut files = shipped("scenes");
    files.extend(shipped("kinds"));
    assert!(files.len() >= 11, "six scenes and five kinds at least");
    let report = no_panic("check", || check(&files, &ScriptOptions::default()))
        .unwrap_or_else(|e| panic!("the shipped scripts should pass the check:\n{e}"));
    assert_eq!(report.len(), files.len(), "one line per file");
    for (line, file) in report.iter().zip(&files) {
        assert!(
            line.starts_with(&file.display().to_string()) && line.contains(" ok"),
            "{line}"
        );
    }
}

#[test]
fn check_fails_on_a_broken_scene_among_good_ones_with_file_and_line() {
    let sandbox = Sandbox::new("check_scene");
    let text = format!("{WORLD}spawn(\"ball\", #{{ pos: vec(5, 5) }}\n");
    let broken = sandbox.scene("broken", &text);
    let files = vec![shipped_scene("cradle"), broken.clone()];
    let result = no_panic("check", || check(&files, &ScriptOptions::default()));
    let e = script_error(result.expect_err("the broken scene fails the check"));
    assert!(same_file(&e.file, &broken), "{e}");
    assert!(e.line.is_some_and(|l| l >= 2), "a line: {e}");
    assert!(
        e.to_string()
            .contains(&format!("broken.rhai:{}", e.line.unwrap())),
        "{e}"
    );
}

#[test]
fn errors_are_script_errors_not_other_variants() {
    // One representative of each family, to make sure none is reported as another error type.
    let sandbox = Sandbox::new("variants");
    let path = sandbox.scene("x", "let x = ;\n");
    let loaded = no_panic("load", || load_scene(&path, &[], &ScriptOptions::default()));
    assert!(matches!(loaded, Err(Error::Script(_))), "a syntax error");
    let missing = sandbox.dir.join("scenes/none.rhai");
    let loaded = no_panic("load", || {
        load_scene(&missing, &[], &ScriptOptions::default())
    });
    match loaded {
        Err(Error::Script(e)) => {
            assert!(same_file_name(&e.file, "none.rhai"), "{e}");
            assert!(e.message.contains("cannot read"), "{e}");
        }
        Err(other) => panic!("a missing file should be a script error: {other}"),
        Ok(_) => panic!("a missing file should not load"),
    }
}

fn same_file_name(reported: &str, name: &str) -> bool {
    Path::new(reported)
        .file_name()
        .is_some_and(|n| n.to_string_lossy() == name)
}
