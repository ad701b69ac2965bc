//! The operations budget of a step (`--max-step-ops`): all script calls of one step together
//! may run so many operations. `--max-ops` bounds one call; this bounds a kind whose every call
//! stays inside it, for every critter, so a step's scripts stop after a bounded amount of work,
//! at the same operation on every machine (the count is rhai's, never a clock).

use super::registry::Api;
use super::HINT_MARK;
use crate::script::host::with_env;
use rhai::{Dynamic, EvalAltResult};
use std::cell::Cell;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// The operations counted for the current step.
struct StepOps {
    /// Most operations a step's scripts may run together.
    max: u64,
    /// The step being counted (`None` before a world exists).
    step: Cell<Option<u64>>,
    /// Operations of the step's calls so far, charges for data walks included.
    spent: Cell<u64>,
    /// The engine's total of operations charged for data walks, when last seen.
    charged: Cell<u64>,
}

impl StepOps {
    /// Counts one operation of the running call, whose count is now `ops`, while the engine has
    /// charged `charged` operations for data walks in all; the error's text once the step is
    /// over budget. rhai calls this at every operation of every call, nested ones included, so
    /// the step's total is one per call of this plus the charges; a call's first operation
    /// (`ops` 1) is where a new step is noticed.
    fn count(
        &self,
        ops: u64,
        charged: u64,
        step_now: impl FnOnce() -> Option<u64>,
    ) -> Option<String> {
        if ops == 1 {
            let step = step_now();
            if step.is_some() && step != self.step.get() {
                self.step.set(step);
                self.spent.set(0);
            }
        }
        let new_charges = charged.wrapping_sub(self.charged.replace(charged));
        let spent = self
            .spent
            .get()
            .saturating_add(1)
            .saturating_add(new_charges);
        self.spent.set(spent);
        if spent <= self.max {
            return None;
        }
        let step = self
            .step
            .get()
            .map_or(String::new(), |s| format!(" in step {s}"));
        Some(format!(
            "the scripts ran more than {} operations{step} together (all hook calls of the step)\
             {HINT_MARK}do the hooks do more work than they need, for every critter? If the work \
             is real, raise the budget with --max-step-ops (0 turns it off)",
            self.max
        ))
    }
}

/// Installs the budget of `max` operations per step on `engine` (none when `max` is 0);
/// `charged` is the engine's total of operations charged for data walks
/// (`Engine::set_data_walk_charge`).
pub(super) fn install(api: &mut Api, max: u64, charged: Arc<AtomicU64>) {
    if max == 0 {
        return;
    }
    let ops = StepOps {
        max,
        step: Cell::new(None),
        spent: Cell::new(0),
        charged: Cell::new(0),
    };
    let h = api.host();
    api.engine.on_progress(move |n| {
        let step_now = || with_env!(h, env => Ok::<_, Box<EvalAltResult>>(env.step_count())).ok();
        ops.count(n, charged.load(Ordering::Relaxed), step_now)
            .map(Dynamic::from)
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn budget(max: u64) -> StepOps {
        StepOps {
            max,
            step: Cell::new(None),
            spent: Cell::new(0),
            charged: Cell::new(0),
        }
    }

    /// Runs calls of the given lengths in `step`; the call and operation where it stopped.
    fn run(b: &StepOps, step: u64, calls: &[u64]) -> Option<(usize, u64)> {
        for (i, &len) in calls.iter().enumerate() {
            for n in 1..=len {
                if b.count(n, 0, || Some(step)).is_some() {
                    return Some((i, n));
                }
            }
        }
        None
    }

    #[test]
    fn calls_of_one_step_share_the_budget_and_stop_at_its_first_operation_past_it() {
        let b = budget(1000);
        // Three calls of 400: the third passes 1000 at its 201st operation.
        assert_eq!(run(&b, 0, &[400, 400, 400]), Some((2, 201)));
    }

    #[test]
    fn a_nested_call_counts_once_with_its_caller() {
        let b = budget(1000);
        let step = || Some(0);
        // The caller runs 300, a nested call 200, the caller 100 more: 600 in all.
        for n in 1..=300 {
            assert!(b.count(n, 0, step).is_none());
        }
        for n in 1..=200 {
            assert!(b.count(n, 0, step).is_none());
        }
        for n in 301..=400 {
            assert!(b.count(n, 0, step).is_none());
        }
        assert_eq!(b.spent.get(), 600);
        // So 400 more fit, and the 401st does not.
        assert_eq!(run(&b, 0, &[400, 1]), Some((1, 1)));
    }

    #[test]
    fn a_new_step_starts_a_new_budget() {
        let b = budget(1000);
        assert_eq!(run(&b, 0, &[400, 400]), None);
        assert_eq!(run(&b, 1, &[400, 400]), None);
        assert_eq!(run(&b, 2, &[1000]), None);
    }

    #[test]
    fn the_error_names_the_step_the_budget_and_the_flag() {
        let b = budget(10);
        let text = (1..=11)
            .find_map(|n| b.count(n, 0, || Some(7)))
            .expect("over budget");
        assert!(
            text.contains("step 7") && text.contains("10 operations"),
            "{text}"
        );
        assert!(text.contains("--max-step-ops"), "{text}");
    }

    #[test]
    fn operations_charged_for_data_walks_count_toward_the_step() {
        let b = budget(1000);
        let step = || Some(0);
        // One operation, then one more while the engine charged 500 for walking an array.
        assert!(b.count(1, 0, step).is_none());
        assert!(b.count(502, 500, step).is_none());
        assert_eq!(b.spent.get(), 502);
        // A later call in the same step: 498 operations fit, the 499th does not.
        assert_eq!(run_charged(&b, 500, 499), Some(499));
    }

    /// Runs one call of `len` operations with the engine's charge total at `charged`; the
    /// operation where it stopped.
    fn run_charged(b: &StepOps, charged: u64, len: u64) -> Option<u64> {
        (1..=len).find(|&n| b.count(n, charged, || Some(0)).is_some())
    }
}
