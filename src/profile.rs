//! The hook profiler: calls and time per kind and hook (`run --stats`, and the recording's end
//! metadata). Off by default; a hook call then pays one flag test. When on, each call is timed
//! with two clock reads and counted in a small table, keyed by kind and hook name.
//!
//! A hook's time includes the hooks it sets off inside it (a spawned critter's `init`).

use serde::{Deserialize, Serialize};
use std::cell::{Cell, RefCell};
use std::fmt::Write;
use std::time::{Duration, Instant};

/// One line of the profile: a kind's hook (or the scene's `on_step`, kind `scene`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ProfileRow {
    /// The kind's name (`scene` for a scene's own hooks).
    pub kind: String,
    /// The hook's name.
    pub hook: String,
    /// Calls.
    pub calls: u64,
    /// Total time of those calls, in nanoseconds.
    pub total_ns: u64,
}

impl ProfileRow {
    /// Mean time per call, in nanoseconds.
    pub fn per_call_ns(&self) -> f64 {
        self.total_ns as f64 / self.calls.max(1) as f64
    }
}

/// The profiler of one script runtime, shared by its kinds and its scene.
#[derive(Debug, Default)]
pub struct Profiler {
    on: Cell<bool>,
    rows: RefCell<Vec<ProfileRow>>,
}

impl Profiler {
    /// Turns timing on or off (what was counted is kept).
    pub fn set_on(&self, on: bool) {
        self.on.set(on);
    }

    /// True while timing.
    pub fn is_on(&self) -> bool {
        self.on.get()
    }

    /// Runs `f`, timing it as `kind`'s `hook` when the profiler is on.
    #[inline]
    pub(crate) fn time<R>(&self, kind: &str, hook: &str, f: impl FnOnce() -> R) -> R {
        if !self.on.get() {
            return f();
        }
        let start = Instant::now();
        let r = f();
        self.add(kind, hook, start.elapsed());
        r
    }

    fn add(&self, kind: &str, hook: &str, took: Duration) {
        // A hook re-entered through a spawn adds after its inner call, so the table is free.
        let Ok(mut rows) = self.rows.try_borrow_mut() else {
            return;
        };
        let ns = u64::try_from(took.as_nanos()).unwrap_or(u64::MAX);
        match rows.iter_mut().find(|r| r.hook == hook && r.kind == kind) {
            Some(r) => {
                r.calls += 1;
                r.total_ns = r.total_ns.saturating_add(ns);
            }
            None => rows.push(ProfileRow {
                kind: kind.to_string(),
                hook: hook.to_string(),
                calls: 1,
                total_ns: ns,
            }),
        }
    }

    /// The table so far, by kind, then hook.
    pub fn rows(&self) -> Vec<ProfileRow> {
        let mut rows = self.rows.borrow().clone();
        rows.sort_by(|a, b| (&a.kind, &a.hook).cmp(&(&b.kind, &b.hook)));
        rows
    }
}

/// The table as `run --stats` prints it: kind, hook, calls, total ms, us per call; the most
/// costly first.
pub fn table(rows: &[ProfileRow]) -> String {
    let mut rows = rows.to_vec();
    rows.sort_by_key(|r| std::cmp::Reverse(r.total_ns));
    let width = |f: fn(&ProfileRow) -> usize, min: usize| rows.iter().map(f).fold(min, usize::max);
    let (wk, wh) = (width(|r| r.kind.len(), 4), width(|r| r.hook.len(), 4));
    let mut out = String::new();
    let _ = writeln!(
        out,
        "  {:<wk$}  {:<wh$}  {:>10}  {:>12}  {:>10}",
        "kind", "hook", "calls", "total ms", "us/call"
    );
    for r in &rows {
        let _ = writeln!(
            out,
            "  {:<wk$}  {:<wh$}  {:>10}  {:>12.3}  {:>10.3}",
            r.kind,
            r.hook,
            r.calls,
            r.total_ns as f64 / 1e6,
            r.per_call_ns() / 1e3
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_only_while_on_and_keys_by_kind_and_hook() {
        let p = Profiler::default();
        p.time("a", "update", || ());
        assert!(p.rows().is_empty());
        p.set_on(true);
        for _ in 0..3 {
            p.time("a", "update", || ());
        }
        p.time("b", "update", || ());
        p.time("a", "collide", || ());
        let rows = p.rows();
        let calls: Vec<(&str, &str, u64)> = rows
            .iter()
            .map(|r| (r.kind.as_str(), r.hook.as_str(), r.calls))
            .collect();
        assert_eq!(
            calls,
            [("a", "collide", 1), ("a", "update", 3), ("b", "update", 1)]
        );
        let t = table(&rows);
        assert_eq!(t.lines().count(), 4, "{t}");
    }

    #[test]
    fn a_nested_call_counts_both() {
        let p = Profiler::default();
        p.set_on(true);
        p.time("a", "collide", || p.time("b", "init", || ()));
        assert_eq!(p.rows().iter().map(|r| r.calls).sum::<u64>(), 2);
    }
}
