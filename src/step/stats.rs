//! What a step took: each stage's time and the counts of pairs, contacts and events.

use std::time::{Duration, Instant};

/// Time spent in each stage and counts from the last step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepStats {
    /// Update hooks.
    pub update: Duration,
    /// Moving and the border.
    pub moving: Duration,
    /// The pairs stage: broad phase, Pop's roles per pair, the narrow phase and the sort of the
    /// contacts (fused into one pass where they can be).
    pub pairs: Duration,
    /// Response (the hooks' `collide`, the default response or the solve; under `swept` and
    /// `event`, the flight too).
    pub response: Duration,
    /// Deaths and spawns.
    pub lifecycle: Duration,
    /// Bounding-box tests made by the broad phase.
    pub pair_tests: u64,
    /// Candidate pairs from the broad phase.
    pub candidates: usize,
    /// Candidate pairs that may collide (roles other than don't-collide).
    pub ruled: usize,
    /// Pairs that touched.
    pub contacts: usize,
    /// `collide` calls that returned true (touching pairs handled, resting contacts included).
    pub collisions: usize,
    /// Default collisions that exchanged an impulse (approaching pairs).
    pub impacts: usize,
    /// Events processed by the swept and event methods (collisions, wall and border hits, cell
    /// crossings).
    pub events: u64,
    /// Steps in which the swept or event method ran out of its event budget and finished the
    /// step in discrete substeps; see `docs/stability.md`.
    pub budget_exceeded: u64,
    /// Velocity sweeps taken by the solves of `solve:n` and `auto` (summed over substeps; a
    /// solve with no contacts takes none).
    pub sweeps: u64,
}

impl StepStats {
    /// Sum of all stage times.
    pub fn total(&self) -> Duration {
        self.update + self.moving + self.pairs + self.response + self.lifecycle
    }

    pub(crate) fn add(&mut self, o: &StepStats) {
        self.update += o.update;
        self.moving += o.moving;
        self.pairs += o.pairs;
        self.response += o.response;
        self.lifecycle += o.lifecycle;
        self.pair_tests += o.pair_tests;
        self.candidates += o.candidates;
        self.ruled += o.ruled;
        self.contacts += o.contacts;
        self.collisions += o.collisions;
        self.impacts += o.impacts;
        self.events += o.events;
        self.budget_exceeded += o.budget_exceeded;
        self.sweeps += o.sweeps;
    }
}

/// Runs `stage`, adding its wall time to `slot`.
#[inline]
pub(crate) fn timed<R>(slot: &mut Duration, stage: impl FnOnce() -> R) -> R {
    let clock = Instant::now();
    let out = stage();
    *slot += clock.elapsed();
    out
}
