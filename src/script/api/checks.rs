//! Checks a script may make anywhere (tests use them most): `assert`, `assert_eq`,
//! `assert_near`, `expect_dead`, `expect_alive`. A failure names the critters involved and the
//! step.

use super::critter::CritterRef;
use super::registry::Api;
use super::values::num;
use super::{fail, Res};
use crate::script::host::{with_env, Host};
use glam::DVec3;
use rhai::{Dynamic, NativeCallContext};

/// `critter 3 (bullet)`, or `critter 3 (gone)`.
pub(crate) fn describe(host: &Host, c: CritterRef) -> String {
    let kind: Res<String> = with_env!(host, env => Ok(match env.critter(c.0) {
        Some(x) => format!("critter {} ({})", c.0, env.kinds().name(x.kind())),
        None => format!("critter {} (gone)", c.0),
    }));
    kind.unwrap_or_else(|_| format!("critter {}", c.0))
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

fn assert_near(a: &Dynamic, b: &Dynamic, tol: &Dynamic, msg: Option<&Dynamic>) -> Res<()> {
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
        let why = msg.map(|m| format!(": {m}")).unwrap_or_default();
        fail(format!(
            "assert_near failed{why}: {a} and {b} differ by {gap:e}, more than {tol:e}"
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
        step_now(host)
    ))
}

/// The step of the world scripts act on, 0 without one.
fn step_now(host: &Host) -> u64 {
    let step: Res<u64> = with_env!(host, env => Ok(env.step_count()));
    step.unwrap_or(0)
}

pub(super) fn register(api: &mut Api) {
    api.engine.register_fn("assert", |cond: bool| -> Res<()> {
        if cond {
            Ok(())
        } else {
            fail("assertion failed")
        }
    });
    api.engine
        .register_fn("assert", |cond: bool, msg: Dynamic| -> Res<()> {
            if cond {
                Ok(())
            } else {
                fail(format!("assertion failed: {msg}"))
            }
        });
    api.engine.register_fn(
        "assert_eq",
        |ctx: NativeCallContext, a: Dynamic, b: Dynamic| -> Res<()> {
            assert_eq(&ctx, &a, &b, None)
        },
    );
    api.engine.register_fn(
        "assert_eq",
        |ctx: NativeCallContext, a: Dynamic, b: Dynamic, msg: Dynamic| -> Res<()> {
            assert_eq(&ctx, &a, &b, Some(&msg))
        },
    );
    api.engine.register_fn(
        "assert_near",
        |a: Dynamic, b: Dynamic, tol: Dynamic| -> Res<()> { assert_near(&a, &b, &tol, None) },
    );
    api.engine.register_fn(
        "assert_near",
        |a: Dynamic, b: Dynamic, tol: Dynamic, msg: Dynamic| -> Res<()> {
            assert_near(&a, &b, &tol, Some(&msg))
        },
    );
    api.func("expect_dead", |h| {
        move |c: CritterRef| -> Res<()> { expect_state(&h, c, false) }
    });
    api.func("expect_alive", |h| {
        move |c: CritterRef| -> Res<()> { expect_state(&h, c, true) }
    });
}
