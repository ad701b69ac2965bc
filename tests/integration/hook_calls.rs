//! A kind's hooks run as bytecode on a virtual machine kept from one call to the next
//! (`Vm::call_fn_kept`), or on the AST with its resolutions kept (`call_fn_cached`): what the
//! calls find must be the kind's own, also for a hook it inherits, and read as the AST would.

use crate::script_common;

use critterbox::PropValue;
use script_common::*;

#[test]
fn inherited_hook_calls_each_kinds_own_helper_when_parent_and_child_alternate() {
    let sandbox = Sandbox::new("hook_calls_inherited");
    sandbox.kind(
        "base",
        r#"
defaults(#{ props: #{ got: 0 } });
fn score() { 1 }
fn update(me, dt) { me.got += score(); }
"#,
    );
    sandbox.kind(
        "derived",
        r#"
extends "base";
fn score() { 10 }
"#,
    );
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(40, 10), seed: 1 });
for i in 0..6 {
    let kind = if i % 2 == 0 { "base" } else { "derived" };
    spawn(kind, #{ pos: vec(3 + 5 * i, 5), fixed: true, props: #{ tag: `c${i}` } });
}
"#,
    );
    let steps = 4;
    for _ in 0..steps {
        assert_eq!(step(&mut scene), None);
    }
    let w = w2(&scene);
    for i in 0..6 {
        let c = tagged(w, &format!("c{i}"));
        let per_step = if i % 2 == 0 { 1 } else { 10 };
        assert_eq!(prop_int(w, c, "got"), per_step * steps, "critter c{i}");
    }
}

/// Lines using a property `Vec` has neither as a field nor by indexer, and the error each gives.
const MISSING_PROPERTY: [(&str, &str); 3] = [
    (
        "v.foo = 3;",
        "No writable property 'foo' - a setter is not registered for type 'Vec' to handle 'i64'",
    ),
    (
        "let a = v.foo;",
        "Unknown property 'foo' - a getter is not registered for type 'Vec'",
    ),
    (
        "v.foo += 1;",
        "Unknown property 'foo' - a getter is not registered for type 'Vec'",
    ),
];

/// A property neither a getter, a setter nor an indexer answers is reported as the getter or
/// setter that is missing: the error is made late (only once the indexer is missing too), but
/// reads as before.
#[test]
fn property_of_a_type_with_no_indexer_names_the_missing_getter_or_setter() {
    let sandbox = Sandbox::new("hook_calls_missing_property");
    for (line, want) in MISSING_PROPERTY {
        let text = format!(
            "let w = world(#{{ dim: 2, size: vec(20, 10), seed: 1 }});\nlet v = vec(1.0, 2.0);\n{line}\n"
        );
        let Err(e) = sandbox.try_load(&text) else {
            panic!("`{line}` should fail");
        };
        let e = script_error(e);
        assert!(e.to_string().contains(want), "`{line}`: {e}");
    }
}

/// A kind's hooks of the same arity (`update(me, dt)`, `collide(me, other)`) share the kind's
/// kept resolutions, and each call still runs its own function.
#[test]
fn hooks_of_one_arity_each_run_their_own_function() {
    let sandbox = Sandbox::new("hook_calls_same_arity");
    sandbox.kind(
        "counter",
        r#"
defaults(#{ props: #{ ups: 0, hits: 0 } });
fn update(me, dt) { me.ups += 1; }
fn collide(me, other) { me.hits += 1; me.collide_default(other); }
"#,
    );
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(40, 10), seed: 1 });
spawn("counter", #{ pos: vec(10, 5), vel: vec(6, 0), props: #{ tag: "a" } });
spawn("counter", #{ pos: vec(30, 5), vel: vec(-6, 0), props: #{ tag: "b" } });
"#,
    );
    let steps = 180;
    for _ in 0..steps {
        assert_eq!(step(&mut scene), None);
    }
    let w = w2(&scene);
    let mut hits = 0;
    for tag in ["a", "b"] {
        let c = tagged(w, tag);
        assert_eq!(prop_int(w, c, "ups"), steps, "update calls of {tag}");
        hits += prop_int(w, c, "hits");
    }
    // A pair's `collide` is called for one of the two.
    assert!((1..steps).contains(&hits), "collide ran {hits} times");
}

/// Writing a property the value it already holds changes nothing; a value that compares equal
/// but differs in its bits (`-0.0` over `0.0`) is still written.
#[test]
fn a_property_written_with_equal_but_different_bits_takes_them() {
    let sandbox = Sandbox::new("hook_calls_same_bits");
    sandbox.kind(
        "writer",
        r#"
defaults(#{ props: #{ z: 0.0, n: 3, again: 0.0 } });
fn update(me, dt) { me.z = -0.0; me.n = 3; me.again = 0.0; }
"#,
    );
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
spawn("writer", #{ pos: vec(5, 5), fixed: true, props: #{ tag: "w" } });
"#,
    );
    assert_eq!(step(&mut scene), None);
    let w = w2(&scene);
    let c = tagged(w, "w");
    let bits = |name: &str| match prop(w, c, name) {
        PropValue::Float(x) => x.to_bits(),
        other => panic!("{name} should be a number, is {other:?}"),
    };
    assert_eq!(bits("z"), (-0.0f64).to_bits());
    assert_eq!(bits("again"), 0.0f64.to_bits());
    assert_eq!(prop_int(w, c, "n"), 3);
}

/// In a hook (run as bytecode), a property no getter, setter or indexer answers is reported as
/// the getter or setter that is missing, as it is in a scene's script.
#[test]
fn a_missing_property_in_a_hook_names_the_missing_getter_or_setter() {
    let sandbox = Sandbox::new("hook_calls_missing_property_in_hook");
    for (i, (line, want)) in MISSING_PROPERTY.into_iter().enumerate() {
        let kind = format!("prober{i}");
        sandbox.kind(
            &kind,
            &format!("fn update(me, dt) {{\n    let v = vec(1.0, 2.0);\n    {line}\n}}\n"),
        );
        let mut scene = sandbox.load(&format!(
            "let w = world(#{{ dim: 2, size: vec(20, 10), seed: 1 }});\nspawn(\"{kind}\", #{{ pos: vec(5, 5) }});\n"
        ));
        let e = scene
            .step()
            .expect_err("the hook fails the step")
            .to_string();
        assert!(e.contains(want), "`{line}`: {e}");
        assert!(
            e.contains(&format!("{kind}.rhai:3")),
            "`{line}`: no line: {e}"
        );
    }
}

/// A hook that hands closures and function pointers to native functions (`map`, `reduce`,
/// `call`) runs them: such a kind's hooks run on the AST, where the natives find them.
#[test]
fn hooks_that_hand_closures_to_natives_run_them() {
    let sandbox = Sandbox::new("hook_calls_closures");
    sandbox.kind(
        "folder",
        r#"
defaults(#{ props: #{ sum: 0 } });
fn double(x) { x * 2 }
fn update(me, dt) {
    let doubled = [1, 2, 3].map(|x| x * 2);
    me.sum = doubled.reduce(|s, x| s + x, 0) + Fn("double").call(10);
}
"#,
    );
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
spawn("folder", #{ pos: vec(5, 5), fixed: true, props: #{ tag: "f" } });
"#,
    );
    assert_eq!(step(&mut scene), None);
    let w = w2(&scene);
    assert_eq!(prop_int(w, tagged(w, "f"), "sum"), 2 + 4 + 6 + 20);
}

/// A hook's parameters are in its scope by name, and a function it calls sees its own
/// parameters and not the hook's, on every call of the hook.
#[test]
fn a_hook_and_the_functions_it_calls_see_their_own_parameters() {
    let sandbox = Sandbox::new("hook_calls_parameters");
    sandbox.kind(
        "namer",
        r#"
defaults(#{ props: #{ hook_sees: 0, helper_sees: 0, diff: 0 } });
fn helper(a, b) {
    if is_def_var("a") && is_def_var("b") && !is_def_var("dt") { a - b } else { -1000 }
}
fn update(me, dt) {
    if is_def_var("me") && is_def_var("dt") && !is_def_var("a") { me.hook_sees += 1; }
    me.diff = helper(5, 3);
    if me.diff == 2 { me.helper_sees += 1; }
}
"#,
    );
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
spawn("namer", #{ pos: vec(5, 5), fixed: true, props: #{ tag: "n" } });
spawn("namer", #{ pos: vec(15, 5), fixed: true, props: #{ tag: "m" } });
"#,
    );
    let steps = 3;
    for _ in 0..steps {
        assert_eq!(step(&mut scene), None);
    }
    let w = w2(&scene);
    for tag in ["n", "m"] {
        let c = tagged(w, tag);
        assert_eq!(prop_int(w, c, "hook_sees"), steps, "{tag}");
        assert_eq!(prop_int(w, c, "helper_sees"), steps, "{tag}");
    }
}
