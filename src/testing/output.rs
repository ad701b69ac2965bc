//! What a test prints: its `print`, `debug` and `log` lines, and those of its scene and its
//! kinds' hooks, kept in order with its outcome (`critterbox test` shows a failing test's, and
//! every test's under `--show-output`).
//!
//! The lines go where a run's go, to the world's log, which each step begins afresh; so the
//! test's stepping takes them after every step (and before it, for those logged between
//! steps). A `print` with no world to log to (before the test made one, or in a kind file's top
//! level) is kept at once.

use super::run::TestRun;
use super::MAX_OUTPUT_LINES;
use crate::script::api::Api;
use crate::script::host::with_env;
use rhai::EvalAltResult;
use std::cell::{Cell, RefCell};

/// The lines a test printed so far.
#[derive(Default)]
pub(super) struct Output {
    lines: RefCell<Vec<String>>,
    /// Lines not kept past [`MAX_OUTPUT_LINES`].
    dropped: Cell<usize>,
    /// How many lines of the world's log, as it is now, are already kept.
    taken: Cell<usize>,
}

impl Output {
    fn push(&self, line: String) {
        let mut lines = self.lines.borrow_mut();
        if lines.len() < MAX_OUTPUT_LINES {
            lines.push(line);
        } else {
            self.dropped.set(self.dropped.get() + 1);
        }
    }

    /// Keeps the lines of the world's `log` not kept yet; `step`: they were logged in that step
    /// (prefixed `[step k]`, as `critterbox run` prints them).
    pub fn keep(&self, log: &[String], step: Option<u64>) {
        let from = self.taken.get().min(log.len());
        for line in &log[from..] {
            self.push(match step {
                Some(k) => format!("[step {k}] {line}"),
                None => line.clone(),
            });
        }
        self.taken.set(log.len());
    }

    /// The world is about to step, which clears its log: the lines kept so far are all of it.
    pub fn log_cleared(&self) {
        self.taken.set(0);
    }

    /// Every line kept, and one saying how many were not.
    pub fn take(&self) -> Vec<String> {
        let mut lines = self.lines.take();
        if self.dropped.get() > 0 {
            lines.push(format!(
                "({} more lines not kept: a test keeps its first {MAX_OUTPUT_LINES})",
                self.dropped.get()
            ));
        }
        lines
    }
}

/// `print` and `debug` in the test's engine: to the world's log as everywhere, or kept at once
/// when no world is reachable (they would be lost otherwise).
pub(super) fn register(api: &mut Api, run: &std::rc::Rc<TestRun>) {
    let (h, test) = (api.host(), run.clone());
    api.engine.on_print(move |text| {
        let logged = with_env!(h, env => {
            env.log(text.to_string());
            Ok::<(), Box<EvalAltResult>>(())
        });
        if logged.is_err() {
            test.output.push(text.to_string());
        }
    });
    let (h, test) = (api.host(), run.clone());
    api.engine.on_debug(move |text, source, pos| {
        let line = match (source, pos.line()) {
            (Some(src), Some(l)) => format!("{src}:{l}: {text}"),
            _ => text.to_string(),
        };
        let logged = with_env!(h, env => {
            env.log(line.clone());
            Ok::<(), Box<EvalAltResult>>(())
        });
        if logged.is_err() {
            test.output.push(line);
        }
    });
}
