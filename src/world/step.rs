//! The step, as a recipe of named stages (see the module docs of [`crate::world`]).

use super::World;
use crate::error::Error;
use crate::step::damage;
use crate::step::span::Span;
use crate::step::stats::{timed, StepStats};
use crate::step::touch;
use crate::step::update;
use crate::vector::Vector;

impl<V: Vector> World<V> {
    /// Advances the world by one time step: update hooks, the collision method's move, pairs
    /// and response, the touch events (when some kind tracks touch), the damage hooks (when
    /// some kind has `on_damage`), then deaths and spawns.
    ///
    /// An error from a hook or a bad queued spawn stops the step where it happened; the world is
    /// then part-way through that step.
    pub fn step(&mut self) -> Result<(), Error> {
        self.state.events.clear();
        self.stats = StepStats::default();
        let mut stats = StepStats::default();
        let span = Span::of(self.state.dt);

        // Neighbour grids live within a stage: the engine moves critters between stages.
        self.state.neighbours.invalidate();
        timed(&mut stats.update, || update::run(&mut self.state, span))?;
        self.state.neighbours.invalidate();
        let plan = self.methods.plan(&mut self.state, span);
        // The layout is for the broad phase's sake, which rebuilds its list after one.
        let allowed = self.methods.allows_layout(&plan);
        timed(&mut stats.pairs, || {
            self.layout
                .lay_out(&mut self.state, &mut self.pairs.broad, allowed)
        });
        self.methods
            .step(plan, span, &mut self.state, &mut self.pairs, &mut stats)?;
        self.state.neighbours.invalidate();
        if self.state.kinds.tracks_touch() {
            // Timed with the lifecycle: both send what the step's contacts and deaths started.
            timed(&mut stats.lifecycle, || touch::run(&mut self.state))?;
        }
        // The step's damage has been dealt: each damaged critter's `on_damage`, in id order.
        timed(&mut stats.lifecycle, || damage::run(&mut self.state))?;
        timed(&mut stats.lifecycle, || self.lifecycle())?;

        self.finish_step(stats);
        Ok(())
    }

    /// Runs `n` steps.
    pub fn run(&mut self, n: u64) -> Result<(), Error> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }

    /// The step's figures kept and added to the totals; the step is counted.
    fn finish_step(&mut self, mut stats: StepStats) {
        stats.impacts = self
            .state
            .events
            .collisions
            .iter()
            .filter(|e| e.impulse > 0.0)
            .count();
        self.stats = stats;
        self.totals.add(&stats);
        self.state.step_count += 1;
    }
}
