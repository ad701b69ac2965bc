//! Running tests: one fresh runtime per test, its engine extended with the test API, on
//! worker threads.

use super::{record, TestCase, TestOptions, TestOutcome};
use crate::error::{Error, ScriptError};
use crate::recording::Recorder;
use crate::script::api::Api;
use crate::script::api::Res;
use crate::script::errors::{eval_error, fn_location};
use crate::script::host::Host;
use crate::script::{read_script, Extension, Limits, Runtime};
use rhai::{Dynamic, Scope};
use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// One test's own state, shared by the functions it registers on its runtime's engine.
pub(super) struct TestRun {
    /// The test's wall-clock deadline.
    pub deadline: Instant,
    /// The limits its scripts run under, for its recordings: a replay rebuilds the scene under
    /// them, not under `run`'s defaults.
    pub limits: Limits,
    /// Where the test's run would be recorded, and the test's name; `None` records nothing.
    pub record_to: Option<(PathBuf, String)>,
    /// `critterbox test --bless`: golden recordings are rewritten, not compared.
    pub bless: bool,
    /// The recording of the test's run (kept only if the test fails).
    pub recorder: RefCell<Option<Recorder>>,
    /// What the test printed.
    pub output: super::output::Output,
}

impl TestRun {
    /// Fails once the test has run out of time.
    pub fn check_deadline(&self) -> Res<()> {
        if Instant::now() > self.deadline {
            crate::script::api::fail("the test ran out of time (--timeout)")
        } else {
            Ok(())
        }
    }
}

impl Extension for TestRun {
    fn register(self: Rc<Self>, api: &mut Api) {
        let run = self.clone();
        api.engine.on_progress(move |ops| {
            if ops % 4096 == 0 && Instant::now() > run.deadline {
                return Some(Dynamic::from(
                    "the test ran out of time (--timeout)".to_string(),
                ));
            }
            None
        });
        super::output::register(api, &self);
        super::world::register(api, &self);
        super::asserts::register(api, &self);
        record::register(api, &self);
    }

    fn scene_made(&self, host: &Host) -> Res<()> {
        record::start(host, self)
    }
}

/// Runs one test in a fresh runtime.
pub fn run_one(case: &TestCase, options: &TestOptions) -> TestOutcome {
    let started = Instant::now();
    let mut output = Vec::new();
    let failure = run_case(case, options, &mut output).err().map(|e| match e {
        Error::Script(s) => *s,
        other => ScriptError::new(case.file.display().to_string(), other.to_string()),
    });
    TestOutcome {
        case: case.clone(),
        failure,
        duration: started.elapsed(),
        output,
    }
}

/// Runs the test; `output` gets what it printed.
fn run_case(case: &TestCase, options: &TestOptions, output: &mut Vec<String>) -> Result<(), Error> {
    let file = case.file.display().to_string();
    let text = read_script(&case.file)?;
    let record_to = options.record_failures.as_ref().map(|dir| {
        let stem = case
            .file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        (dir.join(format!("{stem}-{}.mcap", case.name)), case.id())
    });
    let run = Rc::new(TestRun {
        deadline: Instant::now() + options.timeout,
        limits: options.script.limits.clone(),
        record_to,
        bless: options.bless,
        recorder: RefCell::new(None),
        output: Default::default(),
    });
    let rt = Runtime::extended(&options.script, case.file.parent(), Some(run.clone()));
    let ast = rt.compile(&file, &text)?;
    if case.name.is_empty() {
        return Err(Error::from(ScriptError::new(
            file,
            "the file failed to compile when its tests were listed, and compiles now: was it changed during the run?",
        )));
    }
    let mut scope = Scope::new();
    let result = rt.engine.call_fn_with_options::<Dynamic>(
        rhai::CallFnOptions::new(),
        &mut scope,
        &ast,
        &case.name,
        (),
    );
    let scene = rt.host.take_scene();
    if let Some(scene) = &scene {
        run.output.keep(scene.world.log(), None);
    }
    *output = run.output.take();
    let recorder = run.recorder.borrow_mut().take();
    let kept = match (recorder, &scene) {
        (Some(rec), Some(scene)) => {
            record::finish(rec, &scene.world, result.as_ref().err().map(|e| &**e))
        }
        _ => None,
    };
    result.map(drop).map_err(|e| {
        let mut err = rt.host.locate(&e, || {
            eval_error(
                &file,
                Some(&case.name),
                fn_location(&text, &case.name),
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
