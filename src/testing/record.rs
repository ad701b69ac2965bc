//! A test's run as a recording: every test's run is recorded while it runs and kept only when
//! it fails; `expect_matches_recording(path)` compares the run with a golden recording, or
//! with `--bless` writes it.

use super::run::TestRun;
use super::world::{flat, step_once, with_scene};
use crate::recording::keyframes::default_record_every;
use crate::recording::{EndMeta, Recorder, Recording, RunMeta, RunOverrides, SceneSource};
use crate::scenes::{AnyWorld, Scene, SourceFile};
use crate::script::api::Api;
use crate::script::api::{error, fail, Res};
use crate::script::host::Host;
use rhai::EvalAltResult;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// How a recording of `world` ends: `outcome` ("completed", "error") and why.
fn end_meta(world: &AnyWorld, outcome: &str, reason: String) -> EndMeta {
    EndMeta {
        steps: world.step_count(),
        outcome: outcome.into(),
        reason,
        hash: world.state_hash(),
        ..EndMeta::default()
    }
}

/// Full states of a test's recording are at least this many steps apart: a test often starts
/// from an empty world and spawns into it, so the scene's size at the start says nothing.
pub const TEST_RECORD_EVERY: u64 = 30;

/// The script file of test `case` (`file::name`), to attach to a world the test built itself.
fn test_file(case: &str) -> Vec<SourceFile> {
    let file = case.rsplit_once("::").map_or(case, |(file, _)| file);
    std::fs::read_to_string(file).map_or_else(
        |_| Vec::new(),
        |text| {
            vec![SourceFile {
                path: file.to_string(),
                text,
            }]
        },
    )
}

/// Attaches the script files loaded since the last call: the scene's (a scene script and its
/// kinds) and the test runtime's (kinds a test's spawn loaded).
fn attach_loaded(host: &Host, scene: &Scene, rec: &mut Recorder) -> Res<()> {
    rec.attach_since(0, |n| scene.sources_since(n))
        .map_err(|e| error(e.to_string()))?;
    let rt = host.runtime()?;
    rec.attach_since(1, |n| {
        rt.sources
            .borrow()
            .get(n..)
            .map(<[_]>::to_vec)
            .unwrap_or_default()
    })
    .map_err(|e| error(e.to_string()))
}

/// Starts recording the test's scene, if failures are to be recorded.
pub(super) fn start(host: &Host, run: &TestRun) -> Res<()> {
    let Some((path, case)) = run.record_to.clone() else {
        return Ok(());
    };
    let rec = with_scene(host, |scene| {
        let overrides = RunOverrides {
            limits: run.limits.clone(),
            record_every: Some(default_record_every(scene.world.len()).max(TEST_RECORD_EVERY)),
            ..RunOverrides::default()
        };
        let mut meta = RunMeta::for_scene(scene, &overrides);
        let mut sources = scene.sources.clone();
        if scene.sources.is_empty() {
            // Built by the test function itself: no scene to rebuild it from; the test's own
            // file says how it was built.
            meta.source = SceneSource::Test { case: case.clone() };
            sources = test_file(&case);
        }
        Recorder::create(&path, &meta, &sources, &scene.world)
    })?;
    match rec {
        Ok(rec) => *run.recorder.borrow_mut() = Some(rec),
        // Not being able to record is not the test's failure; say so and go on.
        Err(e) => eprintln!(
            "warning: cannot record the test's run at {}: {e}",
            path.display()
        ),
    }
    Ok(())
}

/// Records the step just taken.
pub(super) fn step(host: &Host, run: &TestRun) -> Res<()> {
    let mut slot = run.recorder.borrow_mut();
    if let Some(rec) = slot.as_mut() {
        let failed = with_scene(host, |scene| {
            rec.record(&scene.world).is_err() || attach_loaded(host, scene, rec).is_err()
        })?;
        if failed {
            *slot = None; // stop recording; the test itself goes on
        }
    }
    Ok(())
}

/// Ends the recording of a test that ended with `failure` (`None`: it passed). A failed test's
/// recording is kept, and its path returned; a passed test's is removed.
pub(super) fn finish(
    rec: Recorder,
    world: &AnyWorld,
    failure: Option<&EvalAltResult>,
) -> Option<String> {
    match failure {
        Some(e) => rec
            .finish(world, end_meta(world, "error", e.to_string()))
            .ok()
            .map(|w| w.path.display().to_string()),
        None => {
            let path = rec.path().to_path_buf();
            drop(rec.finish(world, end_meta(world, "completed", String::new())));
            let _ = std::fs::remove_file(path);
            None
        }
    }
}

/// `expect_matches_recording(path)`: the run from here matches the golden recording's state
/// hash at every step; with `--bless`, the run is recorded as the new golden file instead.
fn expect_matches_recording(host: &Host, run: &TestRun, path: &str) -> Res<()> {
    let file = PathBuf::from(path);
    if run.bless {
        return bless(host, run, &file, path);
    }
    let golden = Recording::open(&file).map_or_else(
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
        run.check_deadline()?;
        let stop = step_once(host, run)?.1.map_err(|e| error(flat(&e)))?;
        if stop.is_some() && step + 1 < last {
            return fail(format!(
                "the scene stopped at step {} but {path} goes on to step {last}",
                step + 1
            ));
        }
    }
}

/// `--bless`: runs the scene its default steps, recording it as the golden file `file`.
fn bless(host: &Host, run: &TestRun, file: &Path, path: &str) -> Res<()> {
    let steps = with_scene(host, |s| s.default_steps)?;
    let rec = with_scene(host, |scene| {
        let overrides = RunOverrides {
            steps: Some(steps),
            limits: run.limits.clone(),
            // Only the hashes are compared: full states at the start and the end keep it small.
            record_every: Some(steps.max(1)),
            ..RunOverrides::default()
        };
        let meta = RunMeta::for_scene(scene, &overrides);
        Recorder::create(file, &meta, &scene.sources, &scene.world)
    })?;
    let mut rec = rec.map_or_else(
        |e| fail(format!("cannot write the golden recording {path}: {e}")),
        Ok,
    )?;
    while with_scene(host, |s| s.world.step_count())? < steps {
        run.check_deadline()?;
        let stop = step_once(host, run)?.1.map_err(|e| error(flat(&e)))?;
        with_scene(host, |s| rec.record(&s.world))?.map_or_else(|e| fail(e.to_string()), Ok)?;
        if stop.is_some() {
            break;
        }
    }
    with_scene(host, |s| {
        rec.finish(&s.world, end_meta(&s.world, "completed", String::new()))
    })?
    .map_or_else(|e| fail(e.to_string()), Ok)?;
    Ok(())
}

pub(super) fn register(api: &mut Api, run: &Rc<TestRun>) {
    let test = run.clone();
    api.func("expect_matches_recording", |h| {
        move |path: &str| -> Res<()> { expect_matches_recording(&h, &test, path) }
    });
}
