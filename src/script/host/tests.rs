//! The host's borrows, exercised as scripts use them: a scene put into the host, scripts calling
//! back into it, hooks run by steps taken through `with_scene` in between, and the scene taken
//! back. Small enough for Miri (`cargo +nightly miri test -p critterbox --lib script::host`),
//! which checks that no pointer into the world outlives the borrow it came from.

use crate::scenes::Scene;
use crate::script::kind_file::define;
use crate::script::{Runtime, ScriptOptions};
use rhai::{Dynamic, Scope, INT};
use std::rc::Rc;

/// A kind with every hook, each calling back into the world.
const BOUNCER: &str = r#"
defaults(#{ radius: 0.25, props: #{ hits: 0, updates: 0, born: false } });
fn init(me) { me.born = true; }
fn update(me, dt) { me.updates += 1; }
fn collides_with(me, other) { if other.alive { COLLIDE_AS_CALLER } else { DONT_COLLIDE } }
fn collide(me, other) { me.hits += 1; me.collide_default(other) }
"#;

/// A bouncer's child with the hooks that call back in from deeper places: the parent's hooks
/// from inside its own, touch events and `on_death` from the touch and lifecycle stages (and from
/// a scene's `die`), a neighbour query, and the shared vars.
const CHILD: &str = r#"
extends "bouncer";
defaults(#{ props: #{ impulse: 0.0 } });
fn update(me, dt) { me.parent_update(dt); let w = world(); w.vars.near += me.nearby(2.0).len(); }
fn collide(me, other, contact) { let hit = me.parent_collide(other, contact); me.impulse = contact.impulse; hit }
fn touch_begin(me, other, contact) { let w = world(); w.vars.begins += 1; }
fn touch_end(me, other) { let w = world(); w.vars.ends += 1; }
fn on_death(me) { let w = world(); w.vars.deaths += 1; spawn("ball", #{ pos: me.pos, radius: 0.1 }); }
"#;

/// A runtime that knows the bouncer, and a scope holding `w`, `a` (a bouncer heading right) and
/// `b` (a ball just right of it), made by a scene-like top level.
fn setup() -> (Rc<Runtime>, Scope<'static>) {
    let rt = Runtime::new(&ScriptOptions::default(), None);
    define(&rt, "bouncer.rhai".into(), "bouncer".into(), BOUNCER.into()).expect("the kind loads");
    define(&rt, "child.rhai".into(), "child".into(), CHILD.into()).expect("the child loads");
    let mut scope = Scope::new();
    let _ = run(
        &rt,
        &mut scope,
        r#"
        let w = world(#{ dim: 2, size: 4 });
        let a = spawn("bouncer", #{ pos: vec(1.0, 2.0), vel: vec(3.0, 0.0) });
        let b = spawn("ball", #{ pos: vec(1.55, 2.0), radius: 0.25 });
        "#,
    );
    (rt, scope)
}

fn run(rt: &Runtime, scope: &mut Scope<'static>, script: &str) -> Dynamic {
    rt.engine
        .eval_with_scope::<Dynamic>(scope, script)
        .unwrap_or_else(|e| panic!("{script}: {e}"))
}

fn step(rt: &Runtime) {
    let stop = rt
        .host
        .with_scene(Scene::step)
        .expect("the host holds the scene");
    assert_eq!(stop.expect("the step runs"), None);
}

// One test, one runtime: building a rhai engine is most of the time Miri takes.
#[test]
fn scripts_hooks_and_with_scene_take_turns_at_the_scene() {
    let (rt, mut scope) = setup();
    assert!(
        run(&rt, &mut scope, "a.born").as_bool().unwrap(),
        "init ran"
    );

    // A spawn inside a script function (`row` holds the scene) runs `init` through a nested
    // `enter`, on a pointer derived from the one `row` holds.
    let born = run(
        &rt,
        &mut scope,
        r#"let r = w.row("bouncer", vec(0.5, 0.5), vec(0.6, 0.0), 3, #{}); r.filter(|c| c.born).len()"#,
    );
    assert_eq!(born.as_int().unwrap(), 3);

    // While `with_scene` lends the scene, a script cannot reach it (a hook stepping its own
    // world would alias it)...
    let inner = rt
        .host
        .with_scene(|_| rt.engine.eval_with_scope::<INT>(&mut scope, "w.step_count"))
        .expect("the host holds the scene");
    assert!(inner.unwrap_err().to_string().contains("busy"));

    // ...and between the steps `with_scene` takes, where hooks run on the world, scripts read
    // and write what the steps changed.
    for _ in 0..3 {
        step(&rt);
        let _ = run(&rt, &mut scope, "a.vel = a.vel * 1.0; b.pos.x");
    }
    let hits = run(&rt, &mut scope, "a.hits").as_int().unwrap();
    let updates = run(&rt, &mut scope, "a.updates").as_int().unwrap();
    assert_eq!(
        (hits, updates),
        (1, 3),
        "a collided once and updated every step"
    );
    let vel = run(&rt, &mut scope, "b.vel.x").as_float().unwrap();
    assert!(vel > 0.0, "b was hit: {vel}");
    assert_eq!(
        run(&rt, &mut scope, "w.count(\"bouncer\")")
            .as_int()
            .unwrap(),
        4
    );

    // The child's hooks reach the world through nested lending (a parent's hook inside its own,
    // a spawn inside `on_death`) and from the touch and lifecycle stages.
    let _ = run(
        &rt,
        &mut scope,
        r#"
        w.vars.near = 0; w.vars.begins = 0; w.vars.ends = 0; w.vars.deaths = 0;
        let c = spawn("child", #{ pos: vec(3.0, 1.0), vel: vec(0.0, 3.0) });
        let d = spawn("ball", #{ pos: vec(3.0, 1.55), radius: 0.25 });
        "#,
    );
    for _ in 0..4 {
        step(&rt);
    }
    let mut got = |e: &str| run(&rt, &mut scope, e);
    assert!(
        got("c.impulse").as_float().unwrap() > 0.0,
        "the parent's collide bounced them"
    );
    assert!(
        got("c.updates").as_int().unwrap() >= 4,
        "parent_update ran each step"
    );
    let _ = got("c.die()");
    assert!(
        got("w.vars.near").as_int().unwrap() >= 1,
        "nearby saw the ball"
    );
    assert_eq!(got("w.vars.begins").as_int().unwrap(), 1, "one spell began");
    assert_eq!(
        got("w.vars.deaths").as_int().unwrap(),
        1,
        "on_death ran once"
    );
    assert_eq!(got("w.count(\"child\")").as_int().unwrap(), 0);

    // Taken back (as every run does: its kinds hold the runtime, which holds the host), the
    // scene is out of the scripts' reach.
    let scene = rt.host.take_scene().expect("the scene is handed back");
    assert_eq!(scene.world.step_count(), 7);
    let err = rt.engine.eval_with_scope::<INT>(&mut scope, "w.step_count");
    assert!(err.unwrap_err().to_string().contains("no world yet"));
}
