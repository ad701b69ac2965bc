//! Assertions and expectations: `assert`, `assert_eq`, `assert_near`, `expect_dead`,
//! `expect_alive`, `expect_collision`. A failure names the critters involved and the step.

use super::run::TestRun;
use super::world::{step_count, step_scene, with_scene};
use crate::scenes::AnyWorld;
use crate::script::api::{fail, num, CritterRef, Res};
use crate::script::host::{with_env, Host};
use glam::DVec3;
use rhai::{Dynamic, Engine, NativeCallContext, INT};
use std::rc::Rc;

/// `critter 3 (bullet)`, or `critter 3 (gone)`.
fn describe(host: &Host, c: CritterRef) -> String {
    let kind: Res<String> = with_env!(host, env => Ok(match env.critter(c.0) {
        Some(x) => format!("critter {} ({})", c.0, env.kinds().name(x.kind())),
        None => format!("critter {} (gone)", c.0),
    }));
    kind.unwrap_or_else(|_| format!("critter {}", c.0))
}

/// True when `a` and `b` collided in the last step, either calling.
fn collided(world: &AnyWorld, a: CritterRef, b: CritterRef) -> bool {
    fn hit<V>(events: &[crate::context::CollisionEvent<V>], a: CritterRef, b: CritterRef) -> bool {
        events
            .iter()
            .any(|e| (e.caller == a.0 && e.arg == b.0) || (e.caller == b.0 && e.arg == a.0))
    }
    match world {
        AnyWorld::D2(w) => hit(&w.events().collisions, a, b),
        AnyWorld::D3(w) => hit(&w.events().collisions, a, b),
    }
}

fn assert_eq(ctx: &NativeCallContext, a: &Dynamic, b: &Dynamic, msg: Option<&Dynamic>) -> Res<()> {
    let equal = ctx
        .call_native_fn::<bool>("==", (a.clone(), b.clone()))
        .unwrap_or(false);
    if equal {
        return Ok(());
    }
    let why = msg.map(|m| format!(": {m}")).unwrap_or_default();
    fail(format!(
        "assert_eq failed{why}: left {} != right {}",
        show(ctx, a),
        show(ctx, b)
    ))
}

fn show(ctx: &NativeCallContext, v: &Dynamic) -> String {
    ctx.call_native_fn::<String>("to_debug", (v.clone(),))
        .unwrap_or_else(|_| v.to_string())
}

fn assert_near(a: &Dynamic, b: &Dynamic, tol: &Dynamic) -> Res<()> {
    let tol = num(tol).map_or_else(|| fail("assert_near's tolerance must be a number"), Ok)?;
    let gap = match (
        num(a),
        num(b),
        a.clone().try_cast::<DVec3>(),
        b.clone().try_cast::<DVec3>(),
    ) {
        (Some(x), Some(y), _, _) => (x - y).abs(),
        (_, _, Some(x), Some(y)) => x.distance(y),
        _ => {
            return fail(format!(
                "assert_near compares two numbers or two Vecs, not {} and {}",
                a.type_name(),
                b.type_name()
            ))
        }
    };
    if gap <= tol {
        Ok(())
    } else {
        fail(format!(
            "assert_near failed: {a} and {b} differ by {gap:e}, more than {tol:e}"
        ))
    }
}

/// `expect_dead(c)` (`want_alive` false) or `expect_alive(c)`.
fn expect_state(host: &Host, c: CritterRef, want_alive: bool) -> Res<()> {
    let alive = with_env!(host, env => Ok(env.critter(c.0).is_some_and(|x| x.is_alive())))?;
    if alive == want_alive {
        return Ok(());
    }
    let (want, is) = if want_alive {
        ("alive", "dead")
    } else {
        ("dead", "alive")
    };
    fail(format!(
        "expected {} to be {want} at step {}, but it is {is}",
        describe(host, c),
        step_count(host)
    ))
}

pub(super) fn register(engine: &mut Engine, host: &Rc<Host>, run: &Rc<TestRun>) {
    engine.register_fn("assert", |cond: bool| -> Res<()> {
        if cond {
            Ok(())
        } else {
            fail("assertion failed")
        }
    });
    engine.register_fn("assert", |cond: bool, msg: Dynamic| -> Res<()> {
        if cond {
            Ok(())
        } else {
            fail(format!("assertion failed: {msg}"))
        }
    });
    engine.register_fn(
        "assert_eq",
        |ctx: NativeCallContext, a: Dynamic, b: Dynamic| -> Res<()> {
            assert_eq(&ctx, &a, &b, None)
        },
    );
    engine.register_fn(
        "assert_eq",
        |ctx: NativeCallContext, a: Dynamic, b: Dynamic, msg: Dynamic| -> Res<()> {
            assert_eq(&ctx, &a, &b, Some(&msg))
        },
    );
    engine.register_fn(
        "assert_near",
        |a: Dynamic, b: Dynamic, tol: Dynamic| -> Res<()> { assert_near(&a, &b, &tol) },
    );
    let h = host.clone();
    engine.register_fn("expect_dead", move |c: CritterRef| -> Res<()> {
        expect_state(&h, c, false)
    });
    let h = host.clone();
    engine.register_fn("expect_alive", move |c: CritterRef| -> Res<()> {
        expect_state(&h, c, true)
    });
    let (h, test) = (host.clone(), run.clone());
    engine.register_fn("expect_collision", move |a: CritterRef, b: CritterRef, within: INT| -> Res<INT> {
        let start = step_count(&h);
        let (da, db) = (describe(&h, a), describe(&h, b));
        for taken in 1..=within.max(0) {
            step_scene(&h, &test, 1)?;
            if with_scene(&h, |s| collided(&s.world, a, b))? {
                return Ok(taken);
            }
        }
        fail(format!(
            "expected {da} and {db} to collide within {within} steps (steps {start} to {}), but they did not",
            step_count(&h)
        ))
    });
}
