//! When each critter was spawned, for `age`: one step count per slot index, kept outside the
//! critter record so the passes over every critter do not stream it.

use crate::critter::CritterId;

/// The step each critter was spawned at, by slot index (with the slot's generation, so a reused
/// slot is not mistaken for its previous critter).
#[derive(Clone, Debug, Default)]
pub(crate) struct Births {
    by_index: Vec<(u32, u64)>,
}

impl Births {
    /// Notes that `id` was spawned when `step` steps had been taken.
    pub(crate) fn note(&mut self, id: CritterId, step: u64) {
        let i = id.index as usize;
        if self.by_index.len() <= i {
            self.by_index.resize(i + 1, (u32::MAX, 0));
        }
        self.by_index[i] = (id.generation, step);
    }

    /// The step `id` was spawned at; 0 when unknown (a critter restored from a recording,
    /// which does not keep spawn steps).
    pub(crate) fn step_of(&self, id: CritterId) -> u64 {
        match self.by_index.get(id.index as usize) {
            Some(&(generation, step)) if generation == id.generation => step,
            _ => 0,
        }
    }

    /// Seconds since `id` was spawned, at `step` steps of `dt`.
    pub(crate) fn age(&self, id: CritterId, step: u64, dt: f64) -> f64 {
        step.saturating_sub(self.step_of(id)) as f64 * dt
    }
}
