//! The test's world: `load_scene(path)`, `w.step(n)`, `w.run_until(|w| ..., max_steps)`,
//! `w.kinetic_energy()`, `w.momentum()`. A test makes one world, with `world(#{ ... })` as a
//! scene does or with `load_scene`; the runtime's host owns it.

use super::record;
use super::run::TestRun;
use crate::error::Error;
use crate::scenes::Scene;
use crate::script::api::Api;
use crate::script::api::{error, fail, Res, WorldRef};
use crate::script::host::{Host, NoScene};
use crate::script::ScriptOptions;
use glam::DVec3;
use rhai::{Dynamic, FnPtr, Map, NativeCallContext, INT};
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Runs `f` on the test's scene.
pub(super) fn with_scene<R>(host: &Host, f: impl FnOnce(&mut Scene) -> R) -> Res<R> {
    host.with_scene(f).or_else(|e| match e {
        NoScene::Missing => {
            fail("no world yet: make one with world(#{ ... }) or load_scene(\"path\")")
        }
        NoScene::Busy => fail(
            "the test's world is in the middle of a step: a kind's hook cannot step or measure it",
        ),
    })
}

/// The test's world's step, 0 without one.
pub(super) fn step_count(host: &Host) -> u64 {
    with_scene(host, |s| s.world.step_count()).unwrap_or(0)
}

/// A library error's text, for a script error.
pub(super) fn flat(e: &Error) -> String {
    match e {
        Error::Script(s) => s.to_string(),
        other => other.to_string(),
    }
}

/// One step of the test's scene (and its `on_step`), keeping the lines logged before it and in
/// it for the test's output. Gives the steps taken before it, and the step's outcome.
pub(super) fn step_once(host: &Host, run: &TestRun) -> Res<(u64, Result<Option<String>, Error>)> {
    with_scene(host, |scene| {
        let step = scene.world.step_count();
        run.output.keep(scene.world.log(), None);
        run.output.log_cleared();
        let outcome = scene.step();
        // Kept when the step failed too: what it logged on the way explains the failure.
        run.output.keep(scene.world.log(), Some(step + 1));
        (step, outcome)
    })
}

/// Steps the test's world `n` times (recording each step), or until its scene stops it.
pub(super) fn step_scene(host: &Host, run: &TestRun, n: INT) -> Res<()> {
    for _ in 0..n.max(0) {
        run.check_deadline()?;
        let (step, outcome) = step_once(host, run)?;
        if outcome.is_ok() {
            record::step(host, run)?;
        }
        match outcome {
            Ok(None) => {}
            Ok(Some(_reason)) => return Ok(()),
            Err(e) => return fail(format!("step {step} failed: {}", flat(&e))),
        }
    }
    Ok(())
}

/// `load_scene(path, sets)`: the scene file, set up, as the test's world.
fn load_scene(host: &Rc<Host>, path: &str, sets: &Map) -> Res<WorldRef> {
    if host.has_scene() {
        return fail("this test already has a world; one test, one world");
    }
    let rt = host.runtime()?;
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    // Paths are relative to the working directory, or else to the test file's folder.
    let mut p = PathBuf::from(path);
    if !p.exists() {
        if let Some(dir) = rt
            .kind_dirs
            .iter()
            .find_map(|d| d.parent().map(Path::to_path_buf))
        {
            let alt = dir.join(path);
            if alt.exists() {
                p = alt;
            }
        }
    }
    let options = ScriptOptions {
        limits: rt.limits.clone(),
        ..ScriptOptions::default()
    };
    let scene = crate::script::load_scene(&p, &sets, &options).map_err(|e| error(flat(&e)))?;
    host.put_scene(scene)?;
    Ok(WorldRef)
}

pub(super) fn register(api: &mut Api, run: &Rc<TestRun>) {
    api.func("load_scene", |h| {
        move |path: &str| -> Res<WorldRef> { load_scene(&h, path, &Map::new()) }
    });
    api.func("load_scene", |h| {
        move |path: &str, sets: Map| -> Res<WorldRef> { load_scene(&h, path, &sets) }
    });
    let test = run.clone();
    api.func("step", |h| {
        move |_: &mut WorldRef| -> Res<()> { step_scene(&h, &test, 1) }
    });
    let test = run.clone();
    api.func("step", |h| {
        move |_: &mut WorldRef, n: INT| -> Res<()> { step_scene(&h, &test, n) }
    });
    let test = run.clone();
    api.func("run_until", |h| {
        move |ctx: NativeCallContext, w: &mut WorldRef, cond: FnPtr, max_steps: INT| -> Res<INT> {
            for taken in 0..=max_steps.max(0) {
                let met = cond.call_within_context::<Dynamic>(&ctx, (*w,))?;
                match met.as_bool() {
                    Ok(true) => return Ok(taken),
                    Ok(false) => {}
                    Err(t) => {
                        return fail(format!(
                            "run_until's condition must return true or false, not {t}"
                        ))
                    }
                }
                if taken < max_steps {
                    step_scene(&h, &test, 1)?;
                }
            }
            fail(format!(
                "run_until: the condition did not hold within {max_steps} steps (now at step {})",
                step_count(&h)
            ))
        }
    });
    api.func("kinetic_energy", |h| {
        move |_: &mut WorldRef| -> Res<f64> { with_scene(&h, |s| s.world.kinetic_energy()) }
    });
    api.func("momentum", |h| {
        move |_: &mut WorldRef| -> Res<DVec3> {
            with_scene(&h, |s| DVec3::from_array(s.world.momentum()))
        }
    });
}
