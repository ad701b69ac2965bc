//! A world put back in a recorded state: its critters and generator, and what the methods
//! carry from step to step (the solve's impulses, the counts of quiet steps towards sleep).

use super::World;
use crate::critter::{Critter, CritterId};
use crate::critter_set::CritterSet;
use crate::kind::WALL;
use crate::method::sleep::SLEEP_STEPS;
use crate::pair_order::{pair_key, unpair_key};
use crate::rng::Rng;
use crate::step::pairs::Pairs;
use crate::step::pending::Pending;
use crate::vector::Vector;

impl<V: Vector> World<V> {
    /// Puts the world in a recorded state between steps: `step` steps taken, the generator at
    /// `rng`, and these critters and free slots (see [`CritterSet::from_parts`]). Walls are
    /// taken from this world, by id: a state whose walls this world does not have is refused.
    /// Caches (broad phase, rule classes, method scratch) start afresh; the result is the
    /// recorded world exactly when its [`World::state_hash`] equals the recorded one.
    pub(crate) fn restore(
        &mut self,
        step: u64,
        rng: [u64; 4],
        critters: Vec<Critter<V>>,
        free: &[CritterId],
    ) -> Result<(), String> {
        let state = &mut self.state;
        let mut all = Vec::with_capacity(critters.len() + state.walls.len());
        let mut walls = Vec::new();
        for c in critters {
            if c.kind() == WALL {
                let Some(wall) = state.critters.get(c.id) else {
                    return Err(format!(
                        "the state has wall {} and this world does not",
                        c.id
                    ));
                };
                walls.push(c.id);
                all.push(wall.clone());
            } else {
                all.push(c);
            }
        }
        // The walls keep this world's order (the order their pairs are tested in).
        let mut kept: Vec<CritterId> = state.walls.clone();
        kept.retain(|w| walls.contains(w));
        let set = CritterSet::from_parts(all, free)
            .ok_or_else(|| "the state's slots contradict each other".to_string())?;
        state.critters = set;
        state.neighbours.invalidate();
        state.walls = kept;
        state.rng = Rng::from_state(rng);
        state.step_count = step;
        state.pending = Pending::default();
        state.touch.clear();
        state.events.clear();
        self.pairs = Pairs::new(self.pairs.broad.mode);
        self.methods.forget();
        Ok(())
    }

    /// Under `solve:n`, the last step's contact impulses that the next step starts from, as
    /// (lower id, higher id, impulse) in ascending slots; nothing under the other methods.
    pub fn contact_impulses(&self) -> impl Iterator<Item = (CritterId, CritterId, f64)> + '_ {
        let critters = &self.state.critters;
        self.methods.warm_impulses().iter().filter_map(|&(key, j)| {
            let (lo, hi) = unpair_key(key);
            let (a, b) = (critters.slot(lo)?, critters.slot(hi)?);
            Some((a.id, b.id, j))
        })
    }

    /// Restores the impulses [`World::contact_impulses`] gave, after [`World::restore`]. Refuses
    /// pairs of critters this world does not have, or out of order.
    pub(crate) fn set_contact_impulses(
        &mut self,
        impulses: impl Iterator<Item = (CritterId, CritterId, f64)>,
    ) -> Result<(), String> {
        let mut warm = Vec::new();
        for (a, b, j) in impulses {
            let known = |id: CritterId| self.state.critters.get(id).is_some();
            if !(known(a) && known(b)) || a.index >= b.index || !(j.is_finite() && j > 0.0) {
                return Err(format!(
                    "the state's contact impulse ({a}, {b}, {j}) is not between two of its critters in order"
                ));
            }
            let key = pair_key(a.index, b.index);
            if warm.last().is_some_and(|&(k, _)| k >= key) {
                return Err("the state's contact impulses are out of order".into());
            }
            warm.push((key, j));
        }
        self.methods.set_warm_impulses(warm);
        Ok(())
    }

    /// Under `solve:n` with gravity, the critters' counts of quiet steps that are not 0, as (id,
    /// count, island) in ascending slots. A count of [`crate::method::sleep::SLEEP_STEPS`] means
    /// asleep, and then the island is named by one of its sleepers (see
    /// [`crate::method::sleep`]); it is `None` for the others.
    pub fn quiet_steps(&self) -> impl Iterator<Item = (CritterId, u16, Option<CritterId>)> + '_ {
        let critters = &self.state.critters;
        self.methods.quiet_counts().filter_map(|(i, q, island)| {
            let c = critters.slot(i as u32)?;
            let named = (q >= SLEEP_STEPS)
                .then(|| critters.slot(island))
                .flatten()
                .map(|c| c.id);
            Some((c.id, q, named))
        })
    }

    /// Restores the counts [`World::quiet_steps`] gave, after [`World::restore`]. Refuses ids
    /// this world does not have, counts out of range, slots out of order, and sleepers without
    /// an island named by one of them.
    pub(crate) fn set_quiet_steps(
        &mut self,
        counts: impl Iterator<Item = (CritterId, u16, Option<CritterId>)>,
    ) -> Result<(), String> {
        let mut list: Vec<(u32, u16, u32)> = Vec::new();
        for (id, q, island) in counts {
            let known = |id: CritterId| self.state.critters.get(id).is_some_and(|c| !c.is_wall());
            let named = match island {
                Some(named) if q == SLEEP_STEPS && known(named) => Some(named.index),
                None if q < SLEEP_STEPS => Some(0),
                _ => None,
            };
            let Some(named) = named.filter(|_| known(id) && q > 0 && q <= SLEEP_STEPS) else {
                return Err(format!(
                    "the state's quiet steps ({id}, {q}, {island:?}) are not those of one of its critters"
                ));
            };
            if list.last().is_some_and(|&(s, _, _)| s >= id.index) {
                return Err("the state's quiet steps are out of order".into());
            }
            list.push((id.index, q, named));
        }
        self.methods
            .restore_quiet_counts(&list, self.state.critters.slot_slice())
    }
}
