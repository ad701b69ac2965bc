//! Script-driven tests (`scripts/tests/*.rhai`): every `fn test_*()` is a test. The assertion API
//! is registered on the one engine; [`run_tests`] finds the tests, runs them on worker threads
//! (one runtime per test: rhai engines are not shared across threads), and reports each.

use super::api::{fail, num, CritterRef, Res, WorldRef};
use super::errors::eval_error;
use super::host::{with_env, Host};
use super::{Runtime, ScriptOptions};
use crate::error::{Error, ScriptError};
use crate::recording::{RunMeta, RunOverrides};
use crate::scenes::AnyWorld;
use glam::DVec3;
use rhai::{Dynamic, Engine, FnPtr, Map, NativeCallContext, Scope, INT};
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// One test found in a test script.
#[derive(Clone, Debug, PartialEq)]
pub struct TestCase {
    /// The script file.
    pub file: PathBuf,
    /// The function's name (`test_...`); empty for a file that does not compile.
    pub name: String,
}

impl TestCase {
    /// `file::name`, as printed.
    pub fn id(&self) -> String {
        if self.name.is_empty() {
            self.file.display().to_string()
        } else {
            format!("{}::{}", self.file.display(), self.name)
        }
    }
}

/// How a test ended.
#[derive(Clone, Debug, PartialEq)]
pub struct TestOutcome {
    /// The test.
    pub case: TestCase,
    /// `None` when it passed; the located failure otherwise.
    pub failure: Option<ScriptError>,
    /// How long it ran.
    pub duration: Duration,
}

/// Settings for a test run.
#[derive(Clone, Debug)]
pub struct TestOptions {
    /// Limits and paths, as for scenes.
    pub script: ScriptOptions,
    /// Only tests whose `file::name` contains this.
    pub filter: Option<String>,
    /// Worker threads.
    pub jobs: usize,
    /// Wall-clock limit per test.
    pub timeout: Duration,
    /// Record each test's run here (`<dir>/<file>-<test>.mcap`), kept only when it fails.
    pub record_failures: Option<PathBuf>,
    /// Rewrite golden recordings instead of comparing with them.
    pub bless: bool,
}

impl Default for TestOptions {
    fn default() -> Self {
        TestOptions {
            script: ScriptOptions::default(),
            filter: None,
            jobs: std::thread::available_parallelism().map_or(1, |n| n.get()),
            timeout: Duration::from_secs(60),
            record_failures: None,
            bless: false,
        }
    }
}

/// Test script files under `paths` (files as given; folders searched for `*.rhai`), sorted.
pub fn find_test_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, Error> {
    let mut files = Vec::new();
    for p in paths {
        if p.is_dir() {
            let entries = std::fs::read_dir(p).map_err(|e| {
                Error::from(ScriptError::new(
                    p.display().to_string(),
                    format!("cannot list the folder: {e}"),
                ))
            })?;
            let mut found: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "rhai"))
                .collect();
            found.sort();
            files.extend(found);
        } else {
            files.push(p.clone());
        }
    }
    Ok(files)
}

/// The tests in `files`: every `fn test_*()` without parameters. A file that does not compile
/// becomes one test that fails with its syntax error.
pub fn discover(files: &[PathBuf], filter: Option<&str>) -> Vec<TestCase> {
    let mut cases = Vec::new();
    let rt = Runtime::new(&ScriptOptions::default(), None);
    for file in files {
        let names: Vec<String> = match std::fs::read_to_string(file)
            .ok()
            .and_then(|t| rt.engine.compile(t).ok())
        {
            Some(ast) => {
                let mut names: Vec<String> = ast
                    .iter_functions()
                    .filter(|f| f.name.starts_with("test_") && f.params.is_empty())
                    .map(|f| f.name.to_string())
                    .collect();
                names.sort();
                names
            }
            None => vec![String::new()],
        };
        for name in names {
            let case = TestCase {
                file: file.clone(),
                name,
            };
            if filter.is_none_or(|f| case.id().contains(f)) {
                cases.push(case);
            }
        }
    }
    cases
}

/// Runs one test in a fresh runtime.
pub fn run_one(case: &TestCase, options: &TestOptions) -> TestOutcome {
    let started = Instant::now();
    let failure = run_case(case, options).err().map(|e| match e {
        Error::Script(s) => *s,
        other => ScriptError::new(case.file.display().to_string(), other.to_string()),
    });
    TestOutcome {
        case: case.clone(),
        failure,
        duration: started.elapsed(),
    }
}

fn run_case(case: &TestCase, options: &TestOptions) -> Result<(), Error> {
    let file = case.file.display().to_string();
    let text = super::read_script(&case.file)?;
    let rt = Runtime::new(&options.script, case.file.parent());
    let ast = rt.compile(&file, &text)?;
    if case.name.is_empty() {
        return Err(Error::from(ScriptError::new(
            file,
            "the file failed to compile when its tests were listed, and compiles now: was it changed during the run?",
        )));
    }
    rt.host.testing.set(true);
    rt.host.deadline.set(Some(Instant::now() + options.timeout));
    rt.host.bless.set(options.bless);
    let record_path = options.record_failures.as_ref().map(|dir| {
        let stem = case
            .file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        dir.join(format!("{stem}-{}.mcap", case.name))
    });
    *rt.host.test_record_path.borrow_mut() = record_path.clone().map(|p| (p, case.id()));
    let mut scope = Scope::new();
    let result = rt.engine.call_fn_with_options::<Dynamic>(
        rhai::CallFnOptions::new(),
        &mut scope,
        &ast,
        &case.name,
        (),
    );
    let scene = rt.host.take_scene();
    let recorder = rt.host.test_recorder.borrow_mut().take();
    let kept = match (recorder, &scene, &result) {
        (Some(rec), Some(scene), Err(e)) => {
            let end = crate::recording::EndMeta {
                steps: scene.world.step_count(),
                outcome: "error".into(),
                reason: e.to_string(),
                hash: scene.world.state_hash(),
            };
            rec.finish(&scene.world, end)
                .ok()
                .map(|w| w.path.display().to_string())
        }
        (Some(rec), Some(scene), Ok(_)) => {
            // Passed: the run is not kept.
            let path = rec.path().to_path_buf();
            let end = crate::recording::EndMeta {
                steps: scene.world.step_count(),
                outcome: "completed".into(),
                reason: String::new(),
                hash: scene.world.state_hash(),
            };
            drop(rec.finish(&scene.world, end));
            let _ = std::fs::remove_file(path);
            None
        }
        _ => None,
    };
    result.map(drop).map_err(|e| {
        let mut err = rt.host.locate(&e, || {
            eval_error(
                &file,
                Some(&case.name),
                super::errors::fn_location(&text, &case.name),
                &e,
                rt.engine.max_operations(),
            )
        });
        if err.step.is_none() {
            err.step = scene.as_ref().map(|s| s.world.step_count());
        }
        if let Some(path) = kept {
            let replay = format!("the run is recorded: critterbox replay {path}");
            err.hint = Some(match err.hint.take() {
                Some(h) => format!("{h}\n  {replay}"),
                None => replay,
            });
        }
        Error::from(err)
    })
}

/// Runs `cases` on `options.jobs` threads; `report` sees each outcome, on the calling thread, as
/// it finishes. Returns the outcomes in the order of `cases`.
pub fn run_tests(
    cases: &[TestCase],
    options: &TestOptions,
    report: &mut dyn FnMut(&TestOutcome),
) -> Vec<TestOutcome> {
    let next = AtomicUsize::new(0);
    let jobs = options.jobs.clamp(1, cases.len().max(1));
    let (tx, rx) = std::sync::mpsc::channel();
    let mut results: Vec<Option<TestOutcome>> = vec![None; cases.len()];
    std::thread::scope(|s| {
        for _ in 0..jobs {
            let tx = tx.clone();
            let next = &next;
            s.spawn(move || loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(case) = cases.get(i) else { break };
                if tx.send((i, run_one(case, options))).is_err() {
                    break;
                }
            });
        }
        drop(tx);
        for (i, outcome) in rx {
            report(&outcome);
            results[i] = Some(outcome);
        }
    });
    results.into_iter().flatten().collect()
}

/// JUnit XML for CI systems.
pub fn junit_xml(outcomes: &[TestOutcome]) -> String {
    fn esc(s: &str) -> String {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
            .replace('"', "&quot;")
    }
    let failures = outcomes.iter().filter(|o| o.failure.is_some()).count();
    let total: f64 = outcomes.iter().map(|o| o.duration.as_secs_f64()).sum();
    let mut xml = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites tests=\"{}\" failures=\"{failures}\" time=\"{total:.3}\">\n  <testsuite name=\"critterbox\" tests=\"{}\" failures=\"{failures}\" time=\"{total:.3}\">\n",
        outcomes.len(),
        outcomes.len()
    );
    for o in outcomes {
        xml.push_str(&format!(
            "    <testcase classname=\"{}\" name=\"{}\" time=\"{:.3}\"",
            esc(&o.case.file.display().to_string()),
            esc(if o.case.name.is_empty() {
                "(compile)"
            } else {
                &o.case.name
            }),
            o.duration.as_secs_f64()
        ));
        match &o.failure {
            None => xml.push_str("/>\n"),
            Some(f) => xml.push_str(&format!(
                ">\n      <failure message=\"{}\">{}</failure>\n    </testcase>\n",
                esc(&f.message),
                esc(&f.to_string())
            )),
        }
    }
    xml.push_str("  </testsuite>\n</testsuites>\n");
    xml
}

// ----- the assertion API ----------------------------------------------------------------------

/// Runs `f` on the test's scene.
fn with_scene<R>(host: &Host, f: impl FnOnce(&mut crate::scenes::Scene) -> R) -> Res<R> {
    let raw = host.scene_world.get();
    if raw.is_null() {
        return fail("no world yet: make one with world(#{ ... }) or load_scene(\"path\")");
    }
    // SAFETY: the scene is owned by the host until the test ends; no other reference to it is
    // live while a test function calls in here, and `f`'s borrow ends before this returns.
    Ok(f(unsafe { &mut *raw }))
}

fn check_deadline(host: &Host) -> Res<()> {
    match host.deadline.get() {
        Some(d) if Instant::now() > d => fail("the test ran out of time (--timeout)"),
        _ => Ok(()),
    }
}

fn step_scene(host: &Host, n: INT) -> Res<()> {
    if !host.testing.get() {
        return fail("world.step(n) works in test scripts (scripts/tests/); a scene runs with `critterbox run`");
    }
    for _ in 0..n.max(0) {
        check_deadline(host)?;
        let (step, outcome) = with_scene(host, |scene| (scene.world.step_count(), scene.step()))?;
        if outcome.is_ok() {
            record_step(host)?;
        }
        match outcome {
            Ok(None) => {}
            Ok(Some(_reason)) => return Ok(()),
            Err(e) => return fail(format!("step {step} failed: {}", flat(&e))),
        }
    }
    Ok(())
}

/// Starts recording a test's inline world (see [`start_recording`]).
pub(crate) fn start_recording_pub(host: &Host) -> Res<()> {
    start_recording(host)
}

/// Starts recording the test's scene, if failures are to be recorded.
fn start_recording(host: &Host) -> Res<()> {
    let Some((path, case)) = host.test_record_path.borrow().clone() else {
        return Ok(());
    };
    let limits = runner_limits(host)?;
    let rec = with_scene(host, |scene| {
        let overrides = RunOverrides {
            limits: limits.clone(),
            ..RunOverrides::default()
        };
        let mut meta = RunMeta::for_scene(scene, &overrides);
        if scene.sources.is_empty() {
            // Built by the test function itself: no scene to rebuild it from.
            meta.source = crate::recording::SceneSource::Test { case: case.clone() };
        }
        crate::recording::Recorder::create(&path, &meta, &scene.sources, &scene.world)
    })?;
    match rec {
        Ok(rec) => *host.test_recorder.borrow_mut() = Some(rec),
        // Not being able to record is not the test's failure; say so and go on.
        Err(e) => eprintln!(
            "warning: cannot record the test's run at {}: {e}",
            path.display()
        ),
    }
    Ok(())
}

/// The limits the test's scene runs under (the test runner's, not `run`'s defaults), for its
/// recordings, so that a replay rebuilds the scene under them.
fn runner_limits(host: &Host) -> Res<crate::script::Limits> {
    Ok(host
        .runtime
        .borrow()
        .upgrade()
        .map_or_else(|| fail("the script runtime is gone"), Ok)?
        .limits
        .clone())
}

fn record_step(host: &Host) -> Res<()> {
    let mut slot = host.test_recorder.borrow_mut();
    if let Some(rec) = slot.as_mut() {
        let failed = with_scene(host, |scene| rec.record(&scene.world).is_err())?;
        if failed {
            *slot = None; // stop recording; the test itself goes on
        }
    }
    Ok(())
}

/// `expect_matches_recording(path)`: the run from here matches the golden recording's state
/// hash at every step; with `--bless`, the run is recorded as the new golden file instead.
fn expect_matches_recording(host: &Host, path: &str) -> Res<()> {
    let file = PathBuf::from(path);
    if host.bless.get() {
        let steps = with_scene(host, |s| s.default_steps)?;
        let limits = runner_limits(host)?;
        let rec = with_scene(host, |scene| {
            let overrides = RunOverrides {
                steps: Some(steps),
                limits: limits.clone(),
                // Only the hashes are compared: full states at the start and the end keep it small.
                record_every: Some(steps.max(1)),
                ..RunOverrides::default()
            };
            let meta = RunMeta::for_scene(scene, &overrides);
            crate::recording::Recorder::create(&file, &meta, &scene.sources, &scene.world)
        })?;
        let mut rec = rec.map_or_else(
            |e| fail(format!("cannot write the golden recording {path}: {e}")),
            Ok,
        )?;
        while with_scene(host, |s| s.world.step_count())? < steps {
            check_deadline(host)?;
            let stop = with_scene(host, |s| s.step())?
                .map_err(|e| super::api::fail::<()>(flat(&e)).unwrap_err())?;
            with_scene(host, |s| rec.record(&s.world))?.map_or_else(|e| fail(e.to_string()), Ok)?;
            if stop.is_some() {
                break;
            }
        }
        with_scene(host, |s| {
            let end = crate::recording::EndMeta {
                steps: s.world.step_count(),
                outcome: "completed".into(),
                reason: String::new(),
                hash: s.world.state_hash(),
            };
            rec.finish(&s.world, end)
        })?
        .map_or_else(|e| fail(e.to_string()), Ok)?;
        return Ok(());
    }
    let golden = crate::recording::Recording::open(&file).map_or_else(
        |e| fail(format!("cannot read the golden recording {path}: {e:#} (make it with `critterbox test --bless`)")),
        Ok,
    )?;
    if let Err(e) = golden.check_state_hash() {
        return fail(format!("{e:#}: rerun with --bless"));
    }
    let Some(&last) = golden.hashes.keys().next_back() else {
        return fail(format!("the golden recording {path} holds no steps"));
    };
    loop {
        let (step, hash) = with_scene(host, |s| (s.world.step_count(), s.world.state_hash()))?;
        if let Some(&want) = golden.hashes.get(&step) {
            if want != hash {
                return fail(format!(
                    "the run differs from {path} at step {step} (state hash {hash:016x}, recorded {want:016x}); if the change is intended, rerun with --bless"
                ));
            }
        }
        if step >= last {
            return Ok(());
        }
        check_deadline(host)?;
        let stop = with_scene(host, |s| s.step())?
            .map_err(|e| super::api::fail::<()>(flat(&e)).unwrap_err())?;
        if stop.is_some() && step + 1 < last {
            return fail(format!(
                "the scene stopped at step {} but {path} goes on to step {last}",
                step + 1
            ));
        }
    }
}

fn flat(e: &Error) -> String {
    match e {
        Error::Script(s) => s.to_string(),
        other => other.to_string(),
    }
}

fn describe(host: &Host, c: CritterRef) -> String {
    let kind: Res<String> = with_env!(host, env => Ok(match env.critter(c.0) {
        Some(x) => format!("critter {} ({})", c.0, env.kinds().name(x.kind())),
        None => format!("critter {} (gone)", c.0),
    }));
    kind.unwrap_or_else(|_| format!("critter {}", c.0))
}

fn step_count(host: &Host) -> u64 {
    with_scene(host, |s| s.world.step_count()).unwrap_or(0)
}

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

/// Registers the test API: worlds from scenes, stepping, and assertions.
pub(crate) fn register(engine: &mut Engine, host: &Rc<Host>) {
    let h = host.clone();
    engine.on_progress(move |ops| {
        if ops % 4096 == 0 {
            if let Some(d) = h.deadline.get() {
                if Instant::now() > d {
                    return Some(Dynamic::from(
                        "the test ran out of time (--timeout)".to_string(),
                    ));
                }
            }
        }
        None
    });

    let h = host.clone();
    engine.register_fn("load_scene", move |path: &str| -> Res<WorldRef> {
        load_scene(&h, path, &Map::new())
    });
    let h = host.clone();
    engine.register_fn(
        "load_scene",
        move |path: &str, sets: Map| -> Res<WorldRef> { load_scene(&h, path, &sets) },
    );
    let h = host.clone();
    engine.register_fn("step", move |_: &mut WorldRef| -> Res<()> {
        step_scene(&h, 1)
    });
    let h = host.clone();
    engine.register_fn("step", move |_: &mut WorldRef, n: INT| -> Res<()> {
        step_scene(&h, n)
    });
    let h = host.clone();
    engine.register_fn(
        "run_until",
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
                    step_scene(&h, 1)?;
                }
            }
            fail(format!(
                "run_until: the condition did not hold within {max_steps} steps (now at step {})",
                step_count(&h)
            ))
        },
    );
    let h = host.clone();
    engine.register_fn("kinetic_energy", move |_: &mut WorldRef| -> Res<f64> {
        with_scene(&h, |s| s.world.kinetic_energy())
    });
    let h = host.clone();
    engine.register_fn("momentum", move |_: &mut WorldRef| -> Res<DVec3> {
        with_scene(&h, |s| DVec3::from_array(s.world.momentum()))
    });

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
        |a: Dynamic, b: Dynamic, tol: Dynamic| -> Res<()> {
            let tol =
                num(&tol).map_or_else(|| fail("assert_near's tolerance must be a number"), Ok)?;
            let gap = match (
                num(&a),
                num(&b),
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
        },
    );
    let h = host.clone();
    engine.register_fn("expect_dead", move |c: CritterRef| -> Res<()> {
        let alive = with_env!(h, env => Ok(env.critter(c.0).is_some_and(|x| x.is_alive())))?;
        if alive {
            fail(format!(
                "expected {} to be dead at step {}, but it is alive",
                describe(&h, c),
                step_count(&h)
            ))
        } else {
            Ok(())
        }
    });
    let h = host.clone();
    engine.register_fn("expect_alive", move |c: CritterRef| -> Res<()> {
        let alive = with_env!(h, env => Ok(env.critter(c.0).is_some_and(|x| x.is_alive())))?;
        if alive {
            Ok(())
        } else {
            fail(format!(
                "expected {} to be alive at step {}, but it is dead",
                describe(&h, c),
                step_count(&h)
            ))
        }
    });
    let h = host.clone();
    engine.register_fn("expect_matches_recording", move |path: &str| -> Res<()> {
        expect_matches_recording(&h, path)
    });
    let h = host.clone();
    engine.register_fn("expect_collision", move |a: CritterRef, b: CritterRef, within: INT| -> Res<INT> {
        let start = step_count(&h);
        let (da, db) = (describe(&h, a), describe(&h, b));
        for taken in 1..=within.max(0) {
            step_scene(&h, 1)?;
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

fn load_scene(host: &Rc<Host>, path: &str, sets: &Map) -> Res<WorldRef> {
    if !host.testing.get() {
        return fail("load_scene works in test scripts (scripts/tests/)");
    }
    if !host.scene_world.get().is_null() {
        return fail("this test already has a world; one test, one world");
    }
    let rt = host
        .runtime
        .borrow()
        .upgrade()
        .map_or_else(|| fail("the script runtime is gone"), Ok)?;
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
    let scene = super::load_scene(&p, &sets, &options)
        .map_err(|e| super::api::fail::<()>(flat(&e)).unwrap_err())?;
    host.put_scene(scene);
    start_recording(host)?;
    Ok(WorldRef)
}
