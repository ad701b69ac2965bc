//! A kind's hooks keep what their calls resolved function names to from one call to the next
//! (`call_fn_cached`): the answers must be the kind's own, also for a hook it inherits.

mod script_common;

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

/// A property neither a getter, a setter nor an indexer answers is reported as the getter or
/// setter that is missing: the error is made late (only once the indexer is missing too), but
/// reads as before.
#[test]
fn property_of_a_type_with_no_indexer_names_the_missing_getter_or_setter() {
    let sandbox = Sandbox::new("hook_calls_missing_property");
    let cases = [
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
    for (line, want) in cases {
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
