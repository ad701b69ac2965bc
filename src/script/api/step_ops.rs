//! The operations budget of a step (`--max-step-ops`): all script calls of one step together
//! may run so many operations. `--max-ops` bounds one call; this bounds a kind whose every call
//! stays inside it, for every critter, so a step's scripts stop after a bounded amount of work,
//! at the same operation on every machine (the count is rhai's, never a clock).

use super::HINT_MARK;
use crate::script::host::{with_env, Host};
use rhai::{Dynamic, Engine, EvalAltResult};
use std::cell::Cell;
use std::rc::Rc;

/// The operations counted for the current step.
struct StepOps {
    /// Most operations a step's scripts may run together.
    max: u64,
    /// The step being counted (`None` before a world exists).
    step: Cell<Option<u64>>,
    /// Operations of the step's calls before the running one.
    spent: Cell<u64>,
    /// The running call's count at its latest operation.
    last: Cell<u64>,
}

impl StepOps {
    /// Counts operation `ops` of the running call; the error's text once the step is over budget.
    /// rhai counts each call from 1 and calls this at every operation, so a count of 1 starts a
    /// call, and any other jump resumes a caller after a call nested in it (a spawn's `init`):
    /// the step's total is then `spent + ops` exactly.
    fn count(&self, ops: u64, step_now: impl FnOnce() -> Option<u64>) -> Option<String> {
        let last = self.last.replace(ops);
        if ops == 1 {
            let step = step_now();
            if step.is_some() && step != self.step.get() {
                self.step.set(step);
                self.spent.set(0);
            } else {
                // The previous call's operations, or the caller's so far when this one nests.
                self.spent.set(self.spent.get().saturating_add(last));
            }
        } else if ops != last.wrapping_add(1) {
            // A caller resumes: add the nested call's operations, less the caller's own, which
            // were added when the nested call began and which `ops` counts again.
            let spent = self.spent.get().saturating_add(last);
            self.spent.set(spent.saturating_sub(ops - 1));
        }
        if self.spent.get().saturating_add(ops) <= self.max {
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

/// Installs the budget of `max` operations per step on `engine` (none when `max` is 0).
pub(super) fn install(engine: &mut Engine, host: &Rc<Host>, max: u64) {
    if max == 0 {
        return;
    }
    let ops = StepOps {
        max,
        step: Cell::new(None),
        spent: Cell::new(0),
        last: Cell::new(0),
    };
    let h = host.clone();
    engine.on_progress(move |n| {
        let step_now = || with_env!(h, env => Ok::<_, Box<EvalAltResult>>(env.step_count())).ok();
        ops.count(n, step_now).map(Dynamic::from)
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
            last: Cell::new(0),
        }
    }

    /// Runs calls of the given lengths in `step`; the call and operation where it stopped.
    fn run(b: &StepOps, step: u64, calls: &[u64]) -> Option<(usize, u64)> {
        for (i, &len) in calls.iter().enumerate() {
            for n in 1..=len {
                if b.count(n, || Some(step)).is_some() {
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
            assert!(b.count(n, step).is_none());
        }
        for n in 1..=200 {
            assert!(b.count(n, step).is_none());
        }
        for n in 301..=400 {
            assert!(b.count(n, step).is_none());
        }
        assert_eq!(b.spent.get() + b.last.get(), 600);
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
            .find_map(|n| b.count(n, || Some(7)))
            .expect("over budget");
        assert!(
            text.contains("step 7") && text.contains("10 operations"),
            "{text}"
        );
        assert!(text.contains("--max-step-ops"), "{text}");
    }
}
