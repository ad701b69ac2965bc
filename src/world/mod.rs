//! The world: critters in a box, the kinds that give their rules, and the step.
//!
//! [`World::step`] (in `step.rs`) is a recipe of named stages, each in a file of its own under
//! `src/step/` and each timed ([`StepStats`]):
//!
//! 1. **update**: each critter whose kind has an `update` hook runs it;
//! 2. the collision method's part (see [`crate::method`]): under Pop's step, `n` times
//!    **motion** (gravity, straight-line motion, the border), **pairs** (the broad phase's
//!    candidates, Pop's roles from the cached class-pair table, the pairs that really touch,
//!    put in a fixed order) and **response** (the caller's `collide` for each touching pair
//!    whose two critters are both still alive, or the contacts solved together); under the
//!    event methods, a flight from event to event;
//! 3. **touch**: the touching spells' begins and ends, when some kind has touch hooks;
//! 4. **damage**: each damage of the step runs the damaged critter's `on_damage`, in id order;
//! 5. **lifecycle**: the dead end their spells, run `on_death` and are removed, queued spawns
//!    are added.
//!
//! Nothing in a step iterates a hash map or reads a clock to decide anything, and all randomness
//! comes from the world's seeded generator, so the same world gives the same bits every run.

mod build;
mod config;
mod diagnostics;
mod layout;
mod queries;
mod restore;
mod state_hash;
mod step;
#[cfg(test)]
pub(crate) mod tests;

pub use crate::step::span::check_dt;
pub use crate::step::stats::StepStats;
pub use config::WorldConfig;
pub use diagnostics::Diagnostics;
pub use layout::{Locality, LOCALITY};

use crate::border::Topology;
use crate::critter::{Critter, CritterId, Props};
use crate::critter_set::CritterSet;
use crate::error::Error;
use crate::kind::KindSet;
use crate::method::auto::Why;
use crate::method::method_state::MethodState;
use crate::method::Method;
use crate::rng::Rng;
use crate::rules::RuleCache;
use crate::step::events::StepEvents;
use crate::step::pairs::Pairs;
use crate::step::state::State;
use crate::vector::Vector;
use layout::Layout;
use std::collections::BTreeMap;

/// A world of critters in 2D (`World<DVec2>`) or 3D (`World<DVec3>`).
pub struct World<V: Vector> {
    /// What every stage and method reads and writes.
    pub(crate) state: State<V>,
    /// The pairs stage's broad phase and lists.
    pub(crate) pairs: Pairs<V>,
    /// The collision method and what it keeps between steps.
    pub(crate) methods: MethodState<V>,
    /// When the critters are laid out in memory.
    layout: Layout,
    /// The seed the world was made with.
    seed: u64,
    /// Stage times and counts of the last step.
    stats: StepStats,
    /// Stage times and counts over all steps.
    totals: StepStats,
}

impl<V: Vector> World<V> {
    /// An empty world. Errors name the bad setting.
    pub fn new(config: WorldConfig<V>) -> Result<Self, Error> {
        config.validate()?;
        Ok(World {
            state: State {
                topo: Topology {
                    min: config.min,
                    max: config.max,
                    border: config.border,
                },
                gravity: config.gravity,
                dt: config.dt,
                critters: CritterSet::default(),
                kinds: KindSet::new(),
                rules: RuleCache::default(),
                walls: Vec::new(),
                rng: Rng::new(config.seed),
                step_count: 0,
                pending: Default::default(),
                events: StepEvents::default(),
                vars: Props::new(),
                neighbours: Default::default(),
                births: Default::default(),
                touch: Default::default(),
                hook: None,
            },
            pairs: Pairs::new(config.broad_phase),
            methods: MethodState::new(config.method, config.sleep),
            layout: Layout::new(LOCALITY),
            seed: config.seed,
            stats: StepStats::default(),
            totals: StepStats::default(),
        })
    }

    // ----- settings ---------------------------------------------------------------------------

    /// The world box and border.
    pub fn topology(&self) -> &Topology<V> {
        &self.state.topo
    }
    /// Time step.
    pub fn dt(&self) -> f64 {
        self.state.dt
    }
    /// Changes the time step.
    pub fn set_dt(&mut self, dt: f64) -> Result<(), Error> {
        check_dt(dt)?;
        self.state.dt = dt;
        Ok(())
    }
    /// The collision method.
    pub fn method(&self) -> Method {
        self.methods.method()
    }
    /// Changes the collision method (takes effect at the next step).
    pub fn set_method(&mut self, m: Method) -> Result<(), Error> {
        let bad_count = |what: &str, most: u32| Error::InvalidWorld {
            field: "method",
            value: m.to_string(),
            reason: format!("the {what} count must be from 1 to {most}"),
        };
        match m {
            Method::Solve(n) if !(1..=crate::method::MAX_SWEEPS).contains(&n) => {
                return Err(bad_count("sweep", crate::method::MAX_SWEEPS));
            }
            Method::Substep(n) if !(1..=crate::method::MAX_SUBSTEPS).contains(&n) => {
                return Err(bad_count("substep", crate::method::MAX_SUBSTEPS));
            }
            _ => {}
        }
        self.methods.set_method(m);
        Ok(())
    }
    /// For `auto`: the method chosen for the last step and the reason, written out by its
    /// `Display` (None for other methods).
    pub fn auto_choice(&self) -> Option<(Method, Why)> {
        self.methods.auto_choice()
    }
    /// For `auto` under gravity: the last step's islands, their sizes and the method each
    /// regime got (`Display` writes the summary line). Under a mixed step, [`World::auto_choice`]
    /// is the choice for the islands that do not take `event`.
    pub fn auto_islands(&self) -> Option<&crate::method::mixed::IslandSummary> {
        self.methods.auto_islands()
    }
    /// Gravity.
    pub fn gravity(&self) -> V {
        self.state.gravity
    }
    /// The seed the world was made with.
    pub fn seed(&self) -> u64 {
        self.seed
    }
    /// The world's seeded generator (for scene setup).
    pub fn rng(&mut self) -> &mut Rng {
        &mut self.state.rng
    }
    /// The random generator's state (what [`World::state_hash`] covers of it).
    pub fn rng_state(&self) -> [u64; 4] {
        self.state.rng.state()
    }
    /// Lets critters sleep under `solve:n` (the default) or keeps every one awake
    /// ([`crate::method::sleep`]). Turning it off wakes every sleeper.
    pub fn set_sleep(&mut self, on: bool) {
        self.methods.set_sleep(on);
    }
    /// True when critters may sleep under `solve:n`.
    pub fn sleep_allowed(&self) -> bool {
        self.methods.sleep_allowed()
    }
    /// Sets when the critters are laid out in memory along the grid (see [`Locality`]).
    /// Changes speed only: every run gives the same bits whatever is set here.
    pub fn set_locality(&mut self, locality: Locality) {
        self.layout.locality = locality;
    }
    /// When the critters are laid out in memory (see [`Locality`]).
    pub fn locality(&self) -> Locality {
        self.layout.locality
    }

    // ----- queries ----------------------------------------------------------------------------

    /// Steps taken.
    pub fn step_count(&self) -> u64 {
        self.state.step_count
    }
    /// Simulated time: steps x dt.
    pub fn time(&self) -> f64 {
        self.state.step_count as f64 * self.state.dt
    }
    /// The critters.
    pub fn critters(&self) -> &CritterSet<V> {
        &self.state.critters
    }
    /// Critter `id`.
    pub fn get(&self, id: CritterId) -> Option<&Critter<V>> {
        self.state.critters.get(id)
    }
    /// Critter `id`, mutably.
    pub fn get_mut(&mut self, id: CritterId) -> Option<&mut Critter<V>> {
        self.state.neighbours.moved(id);
        self.state.critters.get_mut(id)
    }
    /// The kinds.
    pub fn kinds(&self) -> &KindSet<V> {
        &self.state.kinds
    }
    /// The scripts' shared state (`world().vars`): part of the state hash when not empty.
    pub fn vars(&self) -> &Props {
        &self.state.vars
    }
    /// The scripts' shared state, to change.
    pub fn vars_mut(&mut self) -> &mut Props {
        &mut self.state.vars
    }
    /// What happened in the last step.
    pub fn events(&self) -> &StepEvents<V> {
        &self.state.events
    }
    /// Stage times and counts of the last step.
    pub fn stats(&self) -> &StepStats {
        &self.stats
    }
    /// Stage times and counts summed over all steps.
    pub fn totals(&self) -> &StepStats {
        &self.totals
    }
    /// The world between steps as a hook sees it inside one (scene scripts reach it so).
    pub(crate) fn access(&mut self) -> crate::step::access::Access<'_, V> {
        self.state.access()
    }
    /// How the engine's caches and layouts have behaved (for `--stats` and tests).
    pub fn diagnostics(&self) -> Diagnostics<'_> {
        Diagnostics {
            candidate_pairs: &self.pairs.candidates,
            contact_pairs: &self.pairs.contacts,
            layouts: self.layout.count,
            list_rebuilds: self.pairs.broad.rebuilds(),
            list_repairs: self.pairs.broad.repairs(),
            grid_steps: self.pairs.broad.grid_steps(),
            rule_cache: &self.state.rules,
        }
    }
    /// True when critter `id` sleeps.
    pub fn is_asleep(&self, id: CritterId) -> bool {
        self.state
            .critters
            .slot_of(id)
            .is_some_and(|slot| self.methods.is_asleep(slot))
    }
    /// How many critters sleep.
    pub fn sleepers(&self) -> usize {
        self.methods.sleepers()
    }
    /// The collision virial of the last event or swept step: the sum over disk-disk default
    /// collisions of contact distance x impulse (for pressure, `docs/methods.md`).
    pub fn collision_virial(&self) -> f64 {
        self.methods.collision_virial()
    }
    /// Total kinetic energy of the free critters, in four interleaved sums over the slots added
    /// in order, the same sums as the recording's totals (so they have the same bits).
    pub fn kinetic_energy(&self) -> f64 {
        crate::hash::critters::totals(self.state.critters.in_id_order()).0
    }
    /// Total momentum of the free critters, summed as [`World::kinetic_energy`].
    pub fn momentum(&self) -> V {
        crate::hash::critters::totals(self.state.critters.in_id_order()).1
    }
    /// Seconds of simulated time since critter `id` was spawned: the steps begun since then
    /// times dt (0 in its `init`).
    pub fn age(&self, id: CritterId) -> Option<f64> {
        self.state.age(id)
    }
    /// Number of live critters of each kind, by name.
    pub fn count_by_kind(&self) -> BTreeMap<String, usize> {
        let mut counts = BTreeMap::new();
        for c in self.state.critters.iter().filter(|c| c.alive) {
            *counts
                .entry(self.state.kinds.name(c.kind()).to_string())
                .or_insert(0) += 1;
        }
        counts
    }
    /// Live critters of kind `kind` or kinds that extend it, in id order.
    pub fn critters_of(&self, kind: &str) -> Result<Vec<CritterId>, Error> {
        let k = self.state.kinds.id(kind)?;
        Ok(self
            .state
            .critters
            .iter()
            .filter(|c| c.alive && self.state.kinds.is_kind(c.kind(), k))
            .map(|c| c.id)
            .collect())
    }
}
