//! The world and its step.
//!
//! [`World::step`] is a recipe of named stages, each timed:
//!
//! 1. **update**: each critter whose kind has an `update` hook runs it;
//! 2. **move**: gravity, straight-line motion, then the border (bounce, wrap or clamp);
//! 3. **broad phase**: candidate pairs whose bounding boxes overlap ([`crate::broad_phase`]);
//! 4. **rules**: Pop's roles per pair from the cached class-pair table ([`crate::rules`]);
//! 5. **narrow phase**: the pairs that really touch, put in a fixed order (disk pairs by id, then
//!    pairs with walls, so no separation pushes a critter back into a wall);
//! 6. **response**: the caller's `collide` hook for each touching pair whose two critters are both
//!    still alive;
//! 7. **lifecycle**: the dead are removed, queued spawns are added.
//!
//! Nothing in a step iterates a hash map or reads a clock to decide anything, and all randomness
//! comes from the world's seeded generator, so the same world gives the same bits every run.

use crate::border::{Border, Topology};
use crate::broad_phase::{BroadObject, BroadPhase, BroadPhaseMode, Escapes, Objects};
use crate::contact::contact_wall_ball;
use crate::context::{Access, CollideCtx, Pending, StepEvents, UpdateCtx};
use crate::critter::{
    check_positive, check_restitution, Critter, CritterId, CritterSpec, Shape, Traits, CLASS_UNSET,
    CP_WALL,
};
use crate::critter_set::CritterSet;
use crate::error::Error;
use crate::hash::{StateHasher, LANES};
use crate::kind::{KindDefaults, KindHooks, KindId, KindSet, WALL};
use crate::method::solve::Sweeps;
use crate::method::Method;
use crate::rng::Rng;
use crate::rules::{PairRule, RuleCache};
use crate::vector::Vector;
use crate::wall::WallBox;
use std::collections::BTreeMap;
use std::rc::Rc;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Worlds with at least this many critters run the stages that allow it on all cores (the
/// results do not depend on the number of threads).
pub const PARALLEL_MIN: usize = 20_000;

/// When the world lays its critters out in memory (see [`Locality`]), by default: every 200
/// steps the layout is checked, from 50,000 critters on, and made anew when a quarter of them
/// are out of order.
pub const LOCALITY: Locality = Locality {
    every: 200,
    min_critters: 50_000,
    disorder: 0.25,
};

/// When the world lays its critters out in memory along its grid's rows, so that critters near
/// each other in space are near each other in memory, as the broad phase walks them (critters
/// spawned in any order, or mixed by a long run, are otherwise scattered over 128 MB at a
/// million). It changes where the critters are stored, never what happens: ids, the order of
/// every hook call and of the response, the state hash and every recorded byte stay the same.
/// Only under `discrete` and `substep:n`; the other methods keep state by slot and find the
/// critters back in id order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Locality {
    /// Steps between two layouts (0: never).
    pub every: u64,
    /// Fewest live critters for a layout (below, the critters fit in the caches anyway).
    pub min_critters: usize,
    /// Least share of critters out of order (more than a row away from the critter stored
    /// before it) for a layout: critters spawned row by row, as the built-in scenes do, are
    /// left where they are until they have mixed.
    pub disorder: f64,
}

/// Steps with at least this many candidate pairs ask the rules and test the pairs in parallel
/// chunks of [`INPUT_CHUNK`] pairs when there is more than one thread (joined in order: the same
/// lists for any thread count; on one thread the chunks would only cost their copies).
const PARALLEL_PAIRS: usize = 2 * INPUT_CHUNK;

/// The settings a world is made with.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldConfig<V: Vector> {
    /// Lower corner of the world box.
    pub min: V,
    /// Upper corner of the world box.
    pub max: V,
    /// What the box's edge does.
    pub border: Border,
    /// Uniform acceleration on every free critter.
    pub gravity: V,
    /// Time step.
    pub dt: f64,
    /// Seed of the world's generator.
    pub seed: u64,
    /// Broad-phase algorithm.
    pub broad_phase: BroadPhaseMode,
    /// Collision method (see [`crate::method`]).
    pub method: Method,
    /// Whether critters at rest may sleep under `solve:n` ([`crate::method::sleep`]).
    pub sleep: bool,
}

impl<V: Vector> WorldConfig<V> {
    /// A box from `min` to `max`, bouncing border, no gravity, dt = 1/60, seed 0.
    pub fn new(min: V, max: V) -> Self {
        WorldConfig {
            min,
            max,
            border: Border::Bounce,
            gravity: V::zero(),
            dt: 1.0 / 60.0,
            seed: 0,
            broad_phase: BroadPhaseMode::Auto,
            method: Method::Discrete,
            sleep: true,
        }
    }
    /// With collision method `m`.
    pub fn method(mut self, m: Method) -> Self {
        self.method = m;
        self
    }
    /// With border `b`.
    pub fn border(mut self, b: Border) -> Self {
        self.border = b;
        self
    }
    /// With gravity `g`.
    pub fn gravity(mut self, g: V) -> Self {
        self.gravity = g;
        self
    }
    /// With time step `dt`.
    pub fn dt(mut self, dt: f64) -> Self {
        self.dt = dt;
        self
    }
    /// With seed `seed`.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }
    /// With broad-phase algorithm `mode`.
    pub fn broad_phase(mut self, mode: BroadPhaseMode) -> Self {
        self.broad_phase = mode;
        self
    }
    /// With sleep under `solve:n` allowed (the default) or not.
    pub fn sleep(mut self, on: bool) -> Self {
        self.sleep = on;
        self
    }

    fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, value: String, reason: &str| {
            Err(Error::InvalidWorld {
                field,
                value,
                reason: reason.to_string(),
            })
        };
        if !self.min.all_finite() || !self.max.all_finite() {
            return bad(
                "box",
                format!("{:?} to {:?}", self.min, self.max),
                "corners must be finite",
            );
        }
        for axis in 0..V::DIM {
            let positive = self.max.get(axis) > self.min.get(axis); // false for NaN too
            if !positive {
                return bad(
                    "size",
                    format!("{:?}", self.max - self.min),
                    "the world box must have a positive size along every axis",
                );
            }
        }
        if !self.gravity.all_finite() {
            return bad("gravity", format!("{:?}", self.gravity), "must be finite");
        }
        if !(self.dt.is_finite() && self.dt > 0.0) {
            return bad(
                "dt",
                self.dt.to_string(),
                "must be finite and greater than zero",
            );
        }
        Ok(())
    }
}

/// Time spent in each stage and counts from the last step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepStats {
    /// Update hooks.
    pub update: Duration,
    /// Moving and the border.
    pub moving: Duration,
    /// Broad phase.
    pub broad_phase: Duration,
    /// Roles, when asked in a stage of their own: only in steps where some candidate's rule is
    /// not in the class table yet or a touching pair's roles depend on state (a script is run);
    /// otherwise the narrow phase's pass asks them and its time is in `narrow_phase`.
    pub rules: Duration,
    /// Narrow phase (with the rules in the same pass, see `rules`), and the sort of the contacts.
    pub narrow_phase: Duration,
    /// Response.
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
        self.update
            + self.moving
            + self.broad_phase
            + self.rules
            + self.narrow_phase
            + self.response
            + self.lifecycle
    }

    fn add(&mut self, o: &StepStats) {
        self.update += o.update;
        self.moving += o.moving;
        self.broad_phase += o.broad_phase;
        self.rules += o.rules;
        self.narrow_phase += o.narrow_phase;
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

/// Whether the rules and narrow phase were done with the broad phase's re-test.
#[derive(Clone, Copy, Debug)]
enum Fused {
    /// Not tried: the pairs came another way, or sleepers are about.
    NotTried,
    /// A pair's rule is not in the class table, or its roles are to be asked of the hooks: the
    /// stages run one after the other.
    Refused,
    /// Done: how many candidates may collide, and the pass's time on every thread together.
    Done(usize, Duration),
}

/// A world of critters in 2D (`World<DVec2>`) or 3D (`World<DVec3>`).
pub struct World<V: Vector> {
    pub(crate) topo: Topology<V>,
    pub(crate) gravity: V,
    pub(crate) dt: f64,
    pub(crate) seed: u64,
    pub(crate) critters: CritterSet<V>,
    pub(crate) kinds: KindSet<V>,
    pub(crate) rules: RuleCache,
    pub(crate) broad: BroadPhase<V>,
    pub(crate) walls: Vec<CritterId>,
    pub(crate) rng: Rng,
    pub(crate) step_count: u64,
    pub(crate) pending: Pending<V>,
    pub(crate) events: StepEvents<V>,
    pub(crate) stats: StepStats,
    pub(crate) totals: StepStats,
    /// What the move stage did for the broad phase's input pass, which follows it at once (see
    /// [`World::stage_move`]); `None` when no move just ran.
    moved: Option<Moved>,
    /// The rules and narrow phase done with the broad phase's re-test (see
    /// [`World::stage_broad_phase`]): how many candidates may collide, and the time the pass took
    /// on every thread together; or that they were refused (a pair's rule is to be asked).
    fused: Fused,
    pub(crate) candidates: Vec<(u32, u32)>,
    /// (caller, arg, roles still to ask the hooks for)
    pub(crate) ruled: Vec<(u32, u32, bool)>,
    pub(crate) contacts: Vec<(u32, u32)>,
    /// Candidate pairs with a wall: (first, second, roles still to ask the hooks for).
    pub(crate) wall_pairs: Vec<(u32, u32, bool)>,
    pub(crate) method: Method,
    /// What `auto` chose for the last step, and why.
    pub(crate) auto_choice: Option<(Method, crate::method::auto::Why)>,
    pub(crate) flight: crate::method::flight::Scratch<V>,
    pub(crate) solve: crate::method::solve::Scratch<V>,
    /// Who sleeps under `solve:n` ([`crate::method::sleep`]).
    pub(crate) sleep: crate::method::sleep::Sleep<V>,
    /// When the critters are laid out in memory.
    locality: Locality,
    /// How many times they were (diagnostics).
    layouts: u64,
}

impl<V: Vector> World<V> {
    /// An empty world. Errors name the bad setting.
    pub fn new(config: WorldConfig<V>) -> Result<Self, Error> {
        config.validate()?;
        Ok(World {
            topo: Topology {
                min: config.min,
                max: config.max,
                border: config.border,
            },
            gravity: config.gravity,
            dt: config.dt,
            seed: config.seed,
            critters: CritterSet::default(),
            kinds: KindSet::new(),
            rules: RuleCache::default(),
            broad: BroadPhase::new(config.broad_phase),
            walls: Vec::new(),
            rng: Rng::new(config.seed),
            step_count: 0,
            pending: Pending::default(),
            events: StepEvents::default(),
            stats: StepStats::default(),
            totals: StepStats::default(),
            moved: None,
            fused: Fused::NotTried,
            candidates: Vec::new(),
            ruled: Vec::new(),
            contacts: Vec::new(),
            wall_pairs: Vec::new(),
            method: config.method,
            auto_choice: None,
            flight: Default::default(),
            solve: Default::default(),
            sleep: crate::method::sleep::Sleep::new(config.sleep),
            locality: LOCALITY,
            layouts: 0,
        })
    }

    // ----- settings and queries -------------------------------------------------------------

    /// The world box and border.
    pub fn topology(&self) -> &Topology<V> {
        &self.topo
    }
    /// Time step.
    pub fn dt(&self) -> f64 {
        self.dt
    }
    /// Changes the time step.
    pub fn set_dt(&mut self, dt: f64) -> Result<(), Error> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::InvalidWorld {
                field: "dt",
                value: dt.to_string(),
                reason: "must be finite and greater than zero".into(),
            });
        }
        self.dt = dt;
        Ok(())
    }
    /// The collision method.
    pub fn method(&self) -> Method {
        self.method
    }
    /// Changes the collision method (takes effect at the next step).
    pub fn set_method(&mut self, m: Method) -> Result<(), Error> {
        if let Method::Solve(n) = m {
            if !(1..=crate::method::MAX_SWEEPS).contains(&n) {
                return Err(Error::InvalidWorld {
                    field: "method",
                    value: m.to_string(),
                    reason: format!(
                        "the sweep count must be from 1 to {}",
                        crate::method::MAX_SWEEPS
                    ),
                });
            }
        }
        if let Method::Substep(n) = m {
            if !(1..=crate::method::MAX_SUBSTEPS).contains(&n) {
                return Err(Error::InvalidWorld {
                    field: "method",
                    value: m.to_string(),
                    reason: format!(
                        "the substep count must be from 1 to {}",
                        crate::method::MAX_SUBSTEPS
                    ),
                });
            }
        }
        self.method = m;
        Ok(())
    }
    /// For `auto`: the method chosen for the last step and the reason, written out by its
    /// `Display` (None for other methods).
    pub fn auto_choice(&self) -> Option<(Method, crate::method::auto::Why)> {
        self.auto_choice
    }
    /// Gravity.
    pub fn gravity(&self) -> V {
        self.gravity
    }
    /// The seed the world was made with.
    pub fn seed(&self) -> u64 {
        self.seed
    }
    /// The world's seeded generator (for scene setup).
    pub fn rng(&mut self) -> &mut Rng {
        &mut self.rng
    }
    /// Steps taken.
    pub fn step_count(&self) -> u64 {
        self.step_count
    }
    /// Simulated time: steps x dt.
    pub fn time(&self) -> f64 {
        self.step_count as f64 * self.dt
    }
    /// The random generator's state (what [`World::state_hash`] covers of it).
    pub fn rng_state(&self) -> [u64; 4] {
        self.rng.state()
    }

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
        let mut all = Vec::with_capacity(critters.len() + self.walls.len());
        let mut walls = Vec::new();
        for c in critters {
            if c.kind() == WALL {
                let Some(wall) = self.critters.get(c.id) else {
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
        let mut kept: Vec<CritterId> = self.walls.clone();
        kept.retain(|w| walls.contains(w));
        let set = CritterSet::from_parts(all, free)
            .ok_or_else(|| "the state's slots contradict each other".to_string())?;
        self.critters = set;
        self.walls = kept;
        self.rng = Rng::from_state(rng);
        self.step_count = step;
        self.broad = BroadPhase::new(self.broad.mode);
        self.pending = Pending::default();
        self.events.clear();
        self.auto_choice = None;
        self.flight = Default::default();
        self.solve = Default::default();
        self.sleep.forget();
        Ok(())
    }

    /// Under `solve:n`, the last step's contact impulses that the next step starts from, as
    /// (lower id, higher id, impulse) in ascending slots; nothing under the other methods.
    pub fn contact_impulses(&self) -> impl Iterator<Item = (CritterId, CritterId, f64)> + '_ {
        self.solve.warm.iter().filter_map(|&(key, j)| {
            let (lo, hi) = crate::method::unpair_key(key);
            let (a, b) = (self.critters.slot(lo)?, self.critters.slot(hi)?);
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
            let known = |id: CritterId| self.critters.get(id).is_some();
            if !(known(a) && known(b)) || a.index >= b.index || !(j.is_finite() && j > 0.0) {
                return Err(format!(
                    "the state's contact impulse ({a}, {b}, {j}) is not between two of its critters in order"
                ));
            }
            let key = crate::method::pair_key(a.index, b.index);
            if warm.last().is_some_and(|&(k, _)| k >= key) {
                return Err("the state's contact impulses are out of order".into());
            }
            warm.push((key, j));
        }
        self.solve.warm = warm;
        Ok(())
    }

    /// Under `solve:n` with gravity, the critters' counts of quiet steps that are not 0, as (id,
    /// count, island) in ascending slots. A count of [`crate::method::sleep::SLEEP_STEPS`] means
    /// asleep, and then the island is named by one of its sleepers (see
    /// [`crate::method::sleep`]); it is `None` for the others.
    pub fn quiet_steps(&self) -> impl Iterator<Item = (CritterId, u16, Option<CritterId>)> + '_ {
        self.sleep.counts().filter_map(|(i, q, island)| {
            let c = self.critters.slot(i as u32)?;
            let named = (q >= crate::method::sleep::SLEEP_STEPS)
                .then(|| self.critters.slot(island))
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
        use crate::method::sleep::SLEEP_STEPS;
        let mut list: Vec<(u32, u16, u32)> = Vec::new();
        for (id, q, island) in counts {
            let known = |id: CritterId| self.critters.get(id).is_some_and(|c| !c.is_wall());
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
        self.sleep.restore(&list, self.critters.slot_slice())
    }

    /// Lets critters sleep under `solve:n` (the default) or keeps every one awake
    /// ([`crate::method::sleep`]). Turning it off wakes every sleeper.
    pub fn set_sleep(&mut self, on: bool) {
        self.sleep.off = !on;
        if !on {
            self.sleep.clear();
        }
    }

    /// Sets when the critters are laid out in memory along the grid (see [`Locality`]).
    /// Changes speed only: every run gives the same bits whatever is set here.
    pub fn set_locality(&mut self, locality: Locality) {
        self.locality = locality;
    }

    /// When the critters are laid out in memory (see [`Locality`]).
    pub fn locality(&self) -> Locality {
        self.locality
    }

    /// True when critters may sleep under `solve:n`.
    pub fn sleep_allowed(&self) -> bool {
        !self.sleep.off
    }

    /// True when critter `id` sleeps.
    pub fn is_asleep(&self, id: CritterId) -> bool {
        self.critters
            .slot_of(id)
            .is_some_and(|slot| self.sleep.asleep(slot as usize))
    }

    /// How many critters sleep.
    pub fn sleepers(&self) -> usize {
        self.sleep.count()
    }

    /// The critters.
    pub fn critters(&self) -> &CritterSet<V> {
        &self.critters
    }
    /// Critter `id`.
    pub fn get(&self, id: CritterId) -> Option<&Critter<V>> {
        self.critters.get(id)
    }
    /// Critter `id`, mutably.
    pub fn get_mut(&mut self, id: CritterId) -> Option<&mut Critter<V>> {
        self.critters.get_mut(id)
    }
    /// The kinds.
    pub fn kinds(&self) -> &KindSet<V> {
        &self.kinds
    }
    /// What happened in the last step.
    pub fn events(&self) -> &StepEvents<V> {
        &self.events
    }
    /// Stage times and counts of the last step.
    pub fn stats(&self) -> &StepStats {
        &self.stats
    }
    /// Stage times and counts summed over all steps.
    pub fn totals(&self) -> &StepStats {
        &self.totals
    }
    /// The broad phase's candidate pairs of the last step, as slot indices (diagnostics).
    pub fn candidate_pairs(&self) -> &[(u32, u32)] {
        &self.candidates
    }
    /// The touching pairs of the last step as (caller, arg) slot indices, in response order.
    pub fn contact_pairs(&self) -> &[(u32, u32)] {
        &self.contacts
    }
    /// How many times the critters were laid out in memory along the grid (diagnostics; see
    /// [`Locality`]).
    pub fn layouts(&self) -> u64 {
        self.layouts
    }
    /// How many times the broad phase rebuilt its Verlet list (diagnostics).
    pub fn broad_phase_rebuilds(&self) -> u64 {
        self.broad.rebuilds()
    }
    /// How many times the broad phase mended its Verlet list where a few critters had left it,
    /// instead of rebuilding it (diagnostics).
    pub fn broad_phase_repairs(&self) -> u64 {
        self.broad.repairs()
    }
    /// How many steps the broad phase found its pairs with the plain grid because its Verlet
    /// lists lived a single step each (a pile jostled every step; diagnostics).
    pub fn broad_phase_grid_steps(&self) -> u64 {
        self.broad.grid_steps()
    }
    /// The class-pair rule table (diagnostics: how often roles were computed from hooks).
    pub fn rule_cache(&self) -> &RuleCache {
        &self.rules
    }

    /// Total kinetic energy of the free critters, in four interleaved sums over the slots added
    /// in order ([`crate::hash::critters::totals`]: the recording's totals have the same bits).
    pub fn kinetic_energy(&self) -> f64 {
        crate::hash::critters::totals(self.critters.in_id_order()).0
    }
    /// Total momentum of the free critters, summed as [`World::kinetic_energy`].
    pub fn momentum(&self) -> V {
        crate::hash::critters::totals(self.critters.in_id_order()).1
    }
    /// Number of live critters of each kind, by name.
    pub fn count_by_kind(&self) -> BTreeMap<String, usize> {
        let mut counts = BTreeMap::new();
        for c in self.critters.iter().filter(|c| c.alive) {
            *counts
                .entry(self.kinds.name(c.kind()).to_string())
                .or_insert(0) += 1;
        }
        counts
    }
    /// Live critters of kind `kind` or kinds that extend it, in id order.
    pub fn critters_of(&self, kind: &str) -> Result<Vec<CritterId>, Error> {
        let k = self.kinds.id(kind)?;
        Ok(self
            .critters
            .iter()
            .filter(|c| c.alive && self.kinds.is_kind(c.kind(), k))
            .map(|c| c.id)
            .collect())
    }

    /// A hash of the whole dynamic state over raw float bits: equal hashes mean (with
    /// overwhelming probability) bit-identical worlds. It covers the step count, dt, the
    /// generator's state and, for every critter, id, kind, fixed, alive, position, velocity,
    /// radius, mass, priority, restitution, health and properties, and under `solve:n` the
    /// critters' counts of quiet steps towards sleep.
    pub fn state_hash(&self) -> u64 {
        self.state_hash_and_totals().0
    }

    /// [`World::state_hash`], [`World::kinetic_energy`] and [`World::momentum`] (the same bits)
    /// from one pass over the critters, so a recorder walks them once.
    pub fn state_hash_and_totals(&self) -> (u64, f64, V) {
        let mut h = StateHasher::default();
        h.word(self.step_count);
        h.float(self.dt);
        for w in self.rng.state() {
            h.word(w);
        }
        // Every critter's fields in lanes (src/hash/critters.rs), the rarely changing ones reused
        // from the last hash when nothing could have written them; properties go to a hasher of
        // their own, after their owner's id.
        const _: () = assert!(crate::hash::critters::LANES.is_multiple_of(LANES));
        let pass = crate::hash::critters::hash_critters(
            self.critters.in_id_order(),
            self.critters.statics(),
        );
        for half in pass.lanes.chunks_exact(LANES) {
            let mut w = [0u64; LANES];
            w.copy_from_slice(half);
            h.words(w);
        }
        h.word(pass.props);
        // The quiet steps, when there are any (a world without them hashes as it did before
        // sleep existed).
        for (slot, q, island) in self.sleep.counts() {
            h.word((slot as u64) << 16 | u64::from(q));
            h.word(u64::from(island));
        }
        (h.finish(), pass.energy, pass.momentum)
    }

    // ----- building ---------------------------------------------------------------------------

    /// Registers a kind (see [`KindSet::register`]).
    pub fn register_kind(
        &mut self,
        name: &str,
        parent: Option<&str>,
        defaults: KindDefaults,
        hooks: Rc<dyn KindHooks<V>>,
    ) -> Result<KindId, Error> {
        self.kinds.register(name, parent, defaults, hooks)
    }

    /// Adds a wall (always fixed, priority CP_WALL, kind `wall`).
    pub fn add_wall(&mut self, wall: WallBox<V>) -> Result<CritterId, Error> {
        wall.validate()?;
        let center = wall.center;
        let radius = wall.bounding_radius();
        let id = self.critters.insert(|id| Critter {
            id,
            class: CLASS_UNSET,
            pos: center,
            vel: V::zero(),
            radius,
            _align: [],
            fixed: true,
            alive: true,
            wall: true,
            traits: Arc::new(Traits {
                kind: WALL,
                mass: f64::INFINITY,
                priority: CP_WALL,
                restitution: 1.0,
                health: 1.0,
                shape: Shape::Wall(Box::new(wall)),
                props: Default::default(),
            }),
        });
        self.walls.push(id);
        Ok(id)
    }

    /// Makes room for `additional` more critters, exactly (for a scene that knows how many it
    /// will spawn: the critters' storage then does not grow by doubling).
    pub fn reserve(&mut self, additional: usize) {
        self.critters.reserve(additional);
    }

    /// Spawns a critter now. Errors name the critter and the bad field; nothing is added then.
    pub fn spawn(&mut self, spec: CritterSpec<V>) -> Result<CritterId, Error> {
        let critter = self.build(spec)?;
        let has_init = self.kinds.get(critter.kind()).has_init;
        let id = self.critters.insert(|id| Critter { id, ..critter });
        if has_init {
            self.run_init(id)?;
        }
        Ok(id)
    }

    fn build(&self, spec: CritterSpec<V>) -> Result<Critter<V>, Error> {
        let kind_id = self.kinds.id(&spec.kind)?;
        if kind_id == WALL {
            return Err(Error::InvalidKind {
                kind: spec.kind,
                reason: "walls are added with add_wall (they need a box, not a radius)".into(),
            });
        }
        let kind = self.kinds.get(kind_id);
        let d = &kind.defaults;
        let who = || format!("the {} spawned at {}", spec.kind, fmt_vec(spec.pos));
        if !spec.pos.all_finite() {
            return Err(Error::InvalidCritter {
                critter: who(),
                field: "position",
                value: format!("{:?}", spec.pos),
                reason: "every coordinate must be a finite number".into(),
            });
        }
        for axis in 0..V::DIM {
            let x = spec.pos.get(axis);
            if x < self.topo.min.get(axis) || x > self.topo.max.get(axis) {
                return Err(Error::InvalidCritter {
                    critter: who(),
                    field: "position",
                    value: fmt_vec(spec.pos),
                    reason: format!(
                        "outside the world box {} to {}",
                        fmt_vec(self.topo.min),
                        fmt_vec(self.topo.max)
                    ),
                });
            }
        }
        if !spec.vel.all_finite() {
            return Err(Error::InvalidCritter {
                critter: who(),
                field: "velocity",
                value: format!("{:?}", spec.vel),
                reason: "every component must be a finite number".into(),
            });
        }
        let radius = spec.radius.unwrap_or(d.radius);
        check_positive(who, "radius", radius)?;
        let density = spec.density.unwrap_or(d.density);
        check_positive(who, "density", density)?;
        let mass = spec
            .mass
            .or(if spec.density.is_some() { None } else { d.mass });
        let mass = mass.unwrap_or(density * radius * radius * radius);
        check_positive(who, "mass", mass)?;
        let restitution = spec.restitution.unwrap_or(d.restitution);
        check_restitution(who, restitution)?;
        let priority = spec.priority.unwrap_or(d.priority);
        if !priority.is_finite() {
            return Err(Error::InvalidCritter {
                critter: who(),
                field: "priority",
                value: priority.to_string(),
                reason: "must be a finite number; use the CP_* constants".into(),
            });
        }
        let health = spec.health.unwrap_or(d.health);
        if !health.is_finite() {
            return Err(Error::InvalidCritter {
                critter: who(),
                field: "health",
                value: health.to_string(),
                reason: "must be a finite number".into(),
            });
        }
        for &wall_id in &self.walls {
            let Some(wall) = self.critters.get(wall_id) else {
                continue;
            };
            let Shape::Wall(geom) = wall.shape() else {
                continue;
            };
            let d = self.topo.delta(wall.pos, spec.pos);
            if let Some(c) = contact_wall_ball(geom, d, radius) {
                if c.depth > 1e-9 * radius.max(1.0) {
                    return Err(Error::SpawnInsideWall {
                        critter: who(),
                        wall: wall_id,
                        depth: c.depth,
                    });
                }
            }
        }
        let fixed = spec.fixed.unwrap_or(d.fixed);
        Ok(Critter {
            id: CritterId {
                index: 0,
                generation: 0,
            },
            class: CLASS_UNSET,
            pos: spec.pos,
            vel: spec.vel,
            radius,
            _align: [],
            fixed,
            alive: true,
            wall: false,
            traits: Arc::new(Traits {
                kind: kind_id,
                mass,
                priority,
                restitution,
                health,
                shape: Shape::Disk,
                props: {
                    let mut props = d.props.clone();
                    props.extend(spec.props);
                    props
                },
            }),
        })
    }

    /// Adds a line to the current step's log (scene scripts between steps).
    pub fn log_line(&mut self, line: String) {
        self.events.log.push(line);
    }

    /// Removes critter `id` at once (outside a step). Returns it, or an error if it is not there.
    pub fn remove(&mut self, id: CritterId) -> Result<Critter<V>, Error> {
        let slot = self.critters.slot_of(id).ok_or(Error::NoSuchCritter(id))?;
        let c = self.critters.remove(id).ok_or(Error::NoSuchCritter(id))?;
        if c.is_wall() {
            self.walls.retain(|&w| w != id);
        }
        // What rested on it wakes.
        let gone = [(slot as usize, c.pos, c.radius)];
        self.sleep
            .removed(&self.topo, &gone, self.critters.slot_slice());
        Ok(c)
    }

    fn access(&mut self) -> Access<'_, V> {
        Access {
            critters: &mut self.critters,
            kinds: &self.kinds,
            topo: &self.topo,
            pending: &mut self.pending,
            events: &mut self.events,
            rng: &mut self.rng,
            step: self.step_count,
            time: self.step_count as f64 * self.dt,
            dt: self.dt,
        }
    }

    fn run_init(&mut self, id: CritterId) -> Result<(), Error> {
        let step = self.step_count;
        let kind = self
            .critters
            .get(id)
            .map(|c| c.kind())
            .ok_or(Error::NoSuchCritter(id))?;
        let hooks = self.kinds.get(kind).hooks.clone();
        let me = self.critters.slot_of(id).ok_or(Error::NoSuchCritter(id))?;
        let mut ctx = UpdateCtx {
            access: self.access(),
            me,
        };
        hooks
            .init(&mut ctx)
            .map_err(|e| hook_error(e, &self.kinds, kind, id, step))
    }

    // ----- the step ---------------------------------------------------------------------------

    /// Advances the world by one time step (see the module docs for the stages).
    ///
    /// An error from a hook or a bad queued spawn stops the step where it happened; the world is
    /// then part-way through that step.
    pub fn step(&mut self) -> Result<(), Error> {
        self.events.clear();
        self.moved = None;
        self.stats = StepStats::default();
        let mut stats = StepStats::default();

        let clock = Instant::now();
        self.stage_update()?;
        stats.update = clock.elapsed();
        let mut per_critter = false;
        let mut substeps = 1;
        let mut auto_sweeps = None;
        let method = match self.method {
            Method::Auto => {
                let choice = crate::method::auto::choose(self);
                per_critter = choice.per_critter;
                substeps = choice.substeps;
                auto_sweeps = Some(choice.sweeps);
                self.auto_choice = Some((choice.method, choice.why));
                choice.method
            }
            m => m,
        };
        // The layout is for the broad phase's sake (which rebuilds its list after one).
        let clock = Instant::now();
        self.lay_out(method);
        stats.broad_phase += clock.elapsed();
        if !matches!(method, Method::Solve(_)) {
            self.solve.warm.clear(); // kept only from one solve step to the next
        }
        self.sleep.active =
            matches!(method, Method::Solve(_)) && !self.sleep.off && self.gravity != V::zero();
        if self.sleep.active {
            self.sleep.check(self.critters.slot_slice());
        } else {
            self.sleep.clear();
        }
        match method {
            Method::Discrete | Method::Auto => self.substeps(self.dt, 1, None, &mut stats)?,
            Method::Substep(n) => self.substeps(self.dt, n.max(1), None, &mut stats)?,
            Method::Swept if per_critter => {
                crate::method::swept::step_where_needed(self, &mut stats)?
            }
            Method::Swept => crate::method::swept::step(self, &mut stats)?,
            Method::Event => crate::method::event::step(self, &mut stats)?,
            Method::Solve(n) => {
                let sweeps = auto_sweeps.unwrap_or(Sweeps::Fixed(n));
                self.substeps(self.dt, substeps, Some(sweeps), &mut stats)?
            }
        }
        let clock = Instant::now();
        self.stage_lifecycle()?;
        stats.lifecycle = clock.elapsed();

        stats.impacts = self
            .events
            .collisions
            .iter()
            .filter(|e| e.impulse > 0.0)
            .count();
        self.stats = stats;
        self.totals.add(&stats);
        self.step_count += 1;
        Ok(())
    }

    /// Lays the critters out along the grid's rows when one is due under `method` (see
    /// [`Locality`]), or back in id order for a method that keeps state by slot.
    fn lay_out(&mut self, method: Method) {
        let keeps_slots = matches!(self.method, Method::Discrete | Method::Substep(_))
            && matches!(method, Method::Discrete | Method::Substep(_));
        if !keeps_slots {
            if self.critters.is_arranged() {
                self.critters.unarrange();
                self.broad.forget_list();
            }
            return;
        }
        let Locality {
            every,
            min_critters,
            ..
        } = self.locality;
        if every == 0
            || self.step_count == 0
            || !self.step_count.is_multiple_of(every)
            || self.critters.len() < min_critters.max(2)
        {
            return;
        }
        let set = &self.critters;
        let (keys, per_row) = layout_keys(&self.topo, set.slot_slice(), set.len());
        // Out of order: neighbours in memory more than a row apart.
        let mut live = keys
            .iter()
            .filter(|&&k| k != u32::MAX)
            .map(|&k| k / per_row);
        let (mut pairs, mut apart) = (0usize, 0usize);
        if let Some(mut last) = live.next() {
            for row in live {
                pairs += 1;
                apart += usize::from(row.abs_diff(last) > 1);
                last = row;
            }
        }
        if (apart as f64) < self.locality.disorder * pairs as f64 {
            return;
        }
        self.critters.arrange(&keys);
        self.broad.forget_list();
        self.layouts += 1;
    }

    /// Pop's step over `span` (dt, or what is left of it) without the update hooks and
    /// lifecycle: `n` times move by h = span/n, broad phase, rules, narrow phase, and Pop's
    /// response pair by pair, or with `Some(sweeps)` the contacts solved together in that many
    /// sweeps.
    pub(crate) fn substeps(
        &mut self,
        span: f64,
        n: u32,
        solve: Option<Sweeps>,
        stats: &mut StepStats,
    ) -> Result<(), Error> {
        let h = span / f64::from(n);
        for _ in 0..n {
            let clock = Instant::now();
            self.stage_move(h);
            stats.moving += clock.elapsed();
            self.collide_stages(solve.map(|sweeps| (sweeps, h)), stats)?;
        }
        Ok(())
    }

    /// Broad phase, rules, narrow phase and response where the critters are now.
    pub(crate) fn discrete_collide(&mut self, stats: &mut StepStats) -> Result<(), Error> {
        self.collide_stages(None, stats)
    }

    /// Broad phase, rules, narrow phase and response where the critters are now: Pop's response
    /// pair by pair, or with `Some((n, h))` the contacts solved together in `n` sweeps after a
    /// move of `h`.
    fn collide_stages(
        &mut self,
        solve: Option<(Sweeps, f64)>,
        stats: &mut StepStats,
    ) -> Result<(), Error> {
        let mut clock = Instant::now();
        let mut lap = |slot: &mut Duration| {
            let now = Instant::now();
            *slot += now - clock;
            clock = now;
        };
        self.stage_broad_phase(true);
        if self.sleep.any() {
            // Two sleepers, or a sleeper and a wall, stay as they were.
            let still = self.sleep.still();
            let is_still = |slot: u32| still.get(slot as usize).copied().unwrap_or(false);
            self.candidates
                .retain(|&(a, b)| !(is_still(a) && is_still(b)));
        }
        let mut broad = Duration::ZERO;
        lap(&mut broad);
        let ruled = match std::mem::replace(&mut self.fused, Fused::NotTried) {
            Fused::Done(ruled, spent) => {
                // Done inside the broad phase's re-test on every thread: its share of the
                // stage's time is estimated as the pass's time over the threads.
                let share = (spent / rayon::current_num_threads().max(1) as u32).min(broad);
                broad -= share;
                stats.narrow_phase += share;
                Some(ruled)
            }
            // The pass over all the candidates would refuse them too.
            Fused::Refused => None,
            Fused::NotTried => self.rules_and_narrow_phase_in_one_pass(),
        };
        let ruled = match ruled {
            Some(ruled) => ruled,
            None => {
                self.stage_rules()?;
                lap(&mut stats.rules);
                self.stage_narrow_phase()?;
                self.ruled.len()
            }
        };
        stats.broad_phase += broad;
        self.sort_contacts();
        lap(&mut stats.narrow_phase);
        let collisions = match solve {
            Some((sweeps, h)) => {
                let handled = self.stage_solve(sweeps, h)?;
                stats.sweeps += u64::from(self.solve.swept);
                handled
            }
            None => self.stage_response()?,
        };
        lap(&mut stats.response);
        stats.pair_tests += self.broad.tests;
        stats.candidates += self.candidates.len();
        stats.ruled += ruled;
        stats.contacts += self.contacts.len();
        stats.collisions += collisions;
        Ok(())
    }

    /// Runs `n` steps.
    pub fn run(&mut self, n: u64) -> Result<(), Error> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }

    fn stage_update(&mut self) -> Result<(), Error> {
        if !self.kinds.iter().any(|(_, k)| k.has_update) {
            return Ok(());
        }
        let dt = self.dt;
        let step = self.step_count;
        // In id order, wherever the critters are stored.
        for index in 0..self.critters.index_count() as u32 {
            let Some(slot) = self.critters.slot_of_index(index) else {
                continue;
            };
            let Some(c) = self.critters.slot(slot) else {
                continue;
            };
            if !c.alive || !self.kinds.get(c.kind()).has_update {
                continue;
            }
            let (kind, id) = (c.kind(), c.id);
            let hooks = self.kinds.get(kind).hooks.clone();
            let mut ctx = UpdateCtx {
                access: self.access(),
                me: slot,
            };
            hooks
                .update(&mut ctx, dt)
                .map_err(|e| hook_error(e, &self.kinds, kind, id, step))?;
        }
        Ok(())
    }

    fn stage_move(&mut self, dt: f64) {
        let (g, topo) = (self.gravity, self.topo);
        let dv = g * dt;
        // Each critter moves on its own, so any split over threads gives the same bits.
        // Sleepers stay where they are, unpulled (src/method/sleep.rs).
        let still = self.sleep.still();
        let step = move |i: usize, c: &mut Critter<V>| {
            if !c.alive || c.is_wall() || still.get(i).copied().unwrap_or(false) {
                return;
            }
            if !c.fixed {
                c.vel += dv;
            }
            let moved = c.pos + c.vel * dt;
            // Restitution (in the critter's traits) is read only at an edge.
            if topo.clear_of_edges(moved, c.radius) {
                c.pos = moved;
            } else {
                (c.pos, c.vel) = topo.apply_at_edges(moved, c.vel, c.radius, c.restitution());
            }
        };
        // Each chunk of slots also does the broad phase's input pass, while its critters are
        // in cache: it surveys them and asks whether each one is still inside its bound of
        // the Verlet list (at a million critters a pass of its own was another trip through
        // 128 MB of critters, and the list of objects it read was 40 bytes per critter).
        // Live walls are counted and left to the broad phase stage, which knows how far to
        // widen their boxes only when the survey is done. The critters a few slots on are
        // prefetched: with the check, the loop no longer kept enough loads in flight
        // (26-28 ms against 18 per step at 1e6 on one thread, docs/performance.md).
        // Below `PARALLEL_MIN` critters the chunks are taken in turn on this thread (the
        // same pass: the survey and the check are then not passes of their own either).
        use rayon::prelude::*;
        let broad = &self.broad;
        let parallel = self.critters.len() >= PARALLEL_MIN;
        let slots = self.critters.slots_mut_moving();
        // The slots that left their bound are noted, up to an eighth of a chunk (a repair mends
        // at most a 32nd of all), so that a repair need not look for them again.
        let pass = |(k, chunk): (usize, &mut [Option<Critter<V>>])| {
            let (mut seen, mut walls) = (Survey::default(), 0);
            let mut escapes = Escapes {
                slots: Vec::new(),
                complete: true,
            };
            let most = chunk.len() / 8 + 1;
            let mut note = |i: usize, o: Option<&BroadObject<V>>| {
                if escapes.complete && !broad.list_holds(&topo, i, o) {
                    escapes.complete = escapes.slots.len() < most;
                    escapes.slots.push(i as u32);
                }
            };
            for j in 0..chunk.len() {
                prefetch(chunk.get(j + MOVE_AHEAD));
                let s = &mut chunk[j];
                let i = k * INPUT_CHUNK + j;
                let Some(c) = s else {
                    note(i, None);
                    continue;
                };
                step(i, c);
                seen = seen.and(Survey::of(c));
                if c.alive && c.is_wall() {
                    walls += 1;
                } else {
                    note(i, broad_object(c, i as u32, 0.0).as_ref());
                }
            }
            (seen, escapes, walls)
        };
        let chunks: Vec<(Survey, Escapes, usize)> = if parallel {
            slots
                .par_chunks_mut(INPUT_CHUNK)
                .enumerate()
                .map(pass)
                .collect()
        } else {
            slots
                .chunks_mut(INPUT_CHUNK)
                .enumerate()
                .map(pass)
                .collect()
        };
        let mut escapes = Escapes {
            slots: Vec::new(),
            complete: chunks.iter().all(|(_, e, _)| e.complete),
        };
        if escapes.complete {
            for (_, e, _) in &chunks {
                escapes.slots.extend_from_slice(&e.slots);
            }
        }
        self.moved = Some(Moved {
            escapes,
            walls: chunks.iter().map(|&(_, _, walls)| walls).sum(),
            chunks: chunks.len(),
            seen: chunks
                .iter()
                .fold(Survey::default(), |s, &(c, _, _)| s.and(c)),
        });
    }

    fn stage_broad_phase(&mut self, fuse: bool) {
        // What the move stage did, if it ran just before over the same slots.
        let moved = self
            .moved
            .take()
            .filter(|m| m.chunks == self.critters.slot_count().div_ceil(INPUT_CHUNK));
        let seen = match &moved {
            Some(m) => m.seen,
            None => self
                .critters
                .iter_stored()
                .fold(Survey::default(), |s, c| s.and(Survey::of(c))),
        };
        // New critters and changed priorities need their rule class (rare; sequential).
        if seen.unset {
            for c in self
                .critters
                .iter_mut_moving()
                .filter(|c| c.alive && c.class == CLASS_UNSET)
            {
                c.class = self.rules.class_of(&self.kinds, c);
            }
        }
        // Wall pairs are tested after the disk pairs have been separated (see the response), and
        // a separation moves a disk by at most about its radius: widen walls' boxes by that much.
        let objs = Slots {
            slots: self.critters.slot_slice(),
            wall_pad: seen.largest_radius,
            dt: self.dt,
            still: self.sleep.still(),
        };
        // The move checked every slot but the live walls' against the Verlet list; the walls
        // are checked here, and must be the ones it counted.
        let escapes = moved.map(|m| {
            let mut escapes = m.escapes;
            let (mut walls, disks) = (0, escapes.slots.len());
            for &id in &self.walls {
                let slot = self.critters.slot_of(id);
                if let Some(slot) = slot.filter(|&s| {
                    self.critters
                        .slot(s)
                        .is_some_and(|c| c.alive && c.is_wall())
                }) {
                    walls += 1;
                    let i = slot as usize;
                    if !self
                        .broad
                        .list_holds(&self.topo, i, objs.object(i).as_ref())
                    {
                        escapes.slots.push(slot);
                    }
                }
            }
            if escapes.slots.len() > disks {
                escapes.slots.sort_unstable();
            }
            escapes.complete &= walls == m.walls;
            escapes
        });
        // With no sleepers (whose pairs are dropped after the broad phase), the rules and the
        // narrow phase run on each chunk of the kept list's re-test while its critters are in
        // cache: the same lists, in the same order, as the pass over all the candidates after.
        let (critters, rules, topo) = (&self.critters, &self.rules, &self.topo);
        let narrow = |chunk: &[(u32, u32)]| {
            let clock = Instant::now();
            let (mut contacts, mut walls) = (Vec::new(), Vec::new());
            let ruled = rules_and_narrow(critters, rules, topo, chunk, &mut contacts, &mut walls);
            ruled.map(|ruled| (ruled, contacts, walls, clock.elapsed()))
        };
        let then = (fuse && !self.sleep.any()).then_some(&narrow);
        let parts = self
            .broad
            .find_pairs_then(&objs, topo, &mut self.candidates, escapes, then);
        self.fused = match parts.map(|p| p.into_iter().collect::<Option<Vec<_>>>()) {
            None => Fused::NotTried,
            Some(None) => Fused::Refused,
            Some(Some(parts)) => {
                self.contacts.clear();
                self.wall_pairs.clear();
                let (mut ruled, mut spent) = (0, Duration::ZERO);
                for (n, contacts, walls, time) in parts {
                    ruled += n;
                    spent += time;
                    self.contacts.extend(contacts);
                    self.wall_pairs.extend(walls);
                }
                Fused::Done(ruled, spent)
            }
        };
    }

    fn stage_rules(&mut self) -> Result<(), Error> {
        self.ruled.clear();
        self.rules_in_order()
    }

    /// The rules stage, one candidate after another.
    fn rules_in_order(&mut self) -> Result<(), Error> {
        for &(a, b) in &self.candidates {
            let (Some(ca), Some(cb)) = (self.critters.slot(a), self.critters.slot(b)) else {
                continue;
            };
            match self
                .rules
                .rule(&self.kinds, &self.topo, ca, cb)
                .map_err(|e| at_step(e, self.step_count))?
            {
                Some(rule) => {
                    if let Some((caller, arg)) = roles_slots(rule, (a, ca), (b, cb)) {
                        self.ruled.push((caller, arg, false));
                    }
                }
                // State-dependent rules are asked only for pairs that really touch.
                None => self.ruled.push((a, b, true)),
            }
        }
        Ok(())
    }

    fn stage_narrow_phase(&mut self) -> Result<(), Error> {
        self.contacts.clear();
        self.wall_pairs.clear();
        self.narrow_phase_in_order()
    }

    /// The contacts and wall pairs in the order of their lower id, then their higher one: the
    /// order the response takes them in, whatever order the broad phase found them in, and
    /// wherever the critters are stored.
    fn sort_contacts(&mut self) {
        let crowded = !self.contacts.is_empty()
            && LISTED_PER_CONTACT * self.contacts.len() >= self.broad.listed();
        self.broad.set_crowded(crowded);
        let arranged = self.critters.is_arranged();
        // Stored elsewhere than their ids say: sorted as id indices, then back to slots.
        let slots = self.critters.slot_slice();
        let index = |s: u32| slots[s as usize].as_ref().map_or(u32::MAX, |c| c.id.index);
        if arranged {
            for p in &mut self.contacts {
                *p = (index(p.0), index(p.1));
            }
        }
        let n = self.critters.index_count().max(self.critters.slot_count());
        if !sort_pairs(&mut self.contacts, n) && self.contacts.len() >= RADIX_MIN && crowded {
            self.broad.sort_list();
        }
        if arranged {
            let set = &self.critters;
            let slot = |i: u32| set.slot_of_index(i).unwrap_or(u32::MAX);
            for p in &mut self.contacts {
                *p = (slot(p.0), slot(p.1));
            }
        }
        let key = |a: u32, b: u32| (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
        if arranged {
            self.wall_pairs
                .sort_unstable_by_key(|&(c, a, _)| key(index(c), index(a)));
        } else {
            self.wall_pairs.sort_unstable_by_key(|&(c, a, _)| key(c, a));
        }
    }

    /// The rules and narrow stages in one pass over the candidates, which reads each pair's
    /// critters once instead of once per stage, when every candidate's rule is already in the
    /// class table and no touching disk pair's roles are still to be asked (the rules would run
    /// a script). Returns how many pairs may collide, or `None`, with the lists to be redone,
    /// otherwise. With [`PARALLEL_PAIRS`] candidates or more and more than one thread the pass
    /// runs in chunks of [`INPUT_CHUNK`] pairs on all cores, joined in order, so the lists are
    /// the same for any thread count, and the same as the two stages one after the other.
    fn rules_and_narrow_phase_in_one_pass(&mut self) -> Option<usize> {
        use rayon::prelude::*;
        let (critters, rules, topo) = (&self.critters, &self.rules, &self.topo);
        let pass = |chunk: &[(u32, u32)],
                    contacts: &mut Vec<(u32, u32)>,
                    walls: &mut Vec<(u32, u32, bool)>| {
            rules_and_narrow(critters, rules, topo, chunk, contacts, walls)
        };
        self.contacts.clear();
        self.wall_pairs.clear();
        if self.candidates.len() < PARALLEL_PAIRS || rayon::current_num_threads() == 1 {
            let ruled = pass(&self.candidates, &mut self.contacts, &mut self.wall_pairs);
            if ruled.is_none() {
                self.contacts.clear();
                self.wall_pairs.clear();
            }
            return ruled;
        }
        type Part = (usize, Vec<(u32, u32)>, Vec<(u32, u32, bool)>);
        let parts: Vec<Part> = self
            .candidates
            .par_chunks(INPUT_CHUNK)
            .map(|chunk| {
                let (mut contacts, mut walls) = (Vec::new(), Vec::new());
                let ruled = pass(chunk, &mut contacts, &mut walls)?;
                Some((ruled, contacts, walls))
            })
            .collect::<Option<_>>()?;
        let mut ruled = 0;
        for (n, contacts, walls) in parts {
            ruled += n;
            self.contacts.extend(contacts);
            self.wall_pairs.extend(walls);
        }
        Some(ruled)
    }

    /// The narrow phase, one pair after another.
    fn narrow_phase_in_order(&mut self) -> Result<(), Error> {
        let topo = &self.topo;
        for &(first, second, ask) in &self.ruled {
            let (Some(a), Some(b)) = (self.critters.slot(first), self.critters.slot(second)) else {
                continue;
            };
            if a.is_wall() || b.is_wall() {
                // Tested in the response, once the disk pairs have moved.
                self.wall_pairs.push((first, second, ask));
                continue;
            }
            if !crate::contact::touching_ball_ball(topo.delta(a.pos, b.pos), a.radius, b.radius) {
                continue;
            }
            if ask {
                let rule = crate::rules::roles_of(&self.kinds, topo, a, b)
                    .map_err(|e| at_step(e, self.step_count))?;
                if let Some(pair) = roles_slots(rule, (first, a), (second, b)) {
                    self.contacts.push(pair);
                }
            } else {
                self.contacts.push((first, second));
            }
        }
        Ok(())
    }

    /// Disk pairs first, in id order; then pairs with a wall, tested where the disks are now, so
    /// no separation pushes a critter back into a wall.
    fn stage_response(&mut self) -> Result<usize, Error> {
        let mut collisions = 0;
        let disk_contacts = std::mem::take(&mut self.contacts);
        for (k, &(caller, arg)) in disk_contacts.iter().enumerate() {
            if let Some(&(i, j)) = disk_contacts.get(k + CANDIDATES_AHEAD) {
                let slots = self.critters.slot_slice();
                prefetch(slots.get(i as usize));
                prefetch(slots.get(j as usize));
            }
            if self.collide_pair(caller, arg)? {
                collisions += 1;
            }
        }
        self.contacts = disk_contacts;
        let wall_pairs = std::mem::take(&mut self.wall_pairs);
        let mut result = Ok(());
        for &(first, second, ask) in &wall_pairs {
            let (caller, arg) = match self.touching_wall_pair(first, second, ask) {
                Ok(Some(pair)) => pair,
                Ok(None) => continue,
                Err(e) => {
                    result = Err(e);
                    break;
                }
            };
            self.contacts.push((caller, arg));
            match self.collide_pair(caller, arg) {
                Ok(true) => collisions += 1,
                Ok(false) => {}
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
        }
        self.wall_pairs = wall_pairs;
        result?;
        // Separation may have pushed a critter across the periodic edge.
        self.wrap_positions();
        Ok(collisions)
    }

    /// In a periodic world, maps every live critter back into the box.
    pub(crate) fn wrap_positions(&mut self) {
        if self.topo.wraps() {
            let topo = self.topo;
            for c in self
                .critters
                .iter_mut_moving()
                .filter(|c| c.alive && !c.is_wall())
            {
                c.pos = topo.wrap_position(c.pos);
            }
        }
    }

    /// A candidate pair with a wall, tested where the critters are now: (caller, arg) when both
    /// are alive, touch, and their rule lets them collide (asked of the hooks when `ask`).
    pub(crate) fn touching_wall_pair(
        &self,
        first: u32,
        second: u32,
        ask: bool,
    ) -> Result<Option<(u32, u32)>, Error> {
        let (Some(a), Some(b)) = (self.critters.slot(first), self.critters.slot(second)) else {
            return Ok(None);
        };
        if !a.alive || !b.alive || crate::response::contact_between(&self.topo, a, b).is_none() {
            return Ok(None);
        }
        if !ask {
            return Ok(Some((first, second)));
        }
        let rule = crate::rules::roles_of(&self.kinds, &self.topo, a, b)
            .map_err(|e| at_step(e, self.step_count))?;
        Ok(roles_slots(rule, (first, a), (second, b)))
    }

    /// Calls the caller's `collide` on a touching pair, if both are still alive.
    pub(crate) fn collide_pair(&mut self, caller: u32, arg: u32) -> Result<bool, Error> {
        let (Some(c), Some(a)) = (self.critters.slot(caller), self.critters.slot(arg)) else {
            return Ok(false);
        };
        if !c.alive || !a.alive {
            return Ok(false);
        }
        let (kind, id, step) = (c.kind(), c.id, self.step_count);
        let arg_id = a.id;
        let hooks = self.kinds.get(kind).hooks.clone();
        let events_before = self.events.collisions.len();
        let mut ctx = CollideCtx {
            access: self.access(),
            me: caller,
            other: arg,
        };
        let handled = hooks
            .collide(&mut ctx)
            .map_err(|e| hook_error(e, &self.kinds, kind, id, step))?;
        if handled && self.events.collisions.len() == events_before {
            // A hook that handled the pair its own way (a bullet's hit, a basket's catch) is a
            // collision too, with no impulse.
            self.record_hook_collision(id, arg_id);
        }
        Ok(handled)
    }

    fn record_hook_collision(&mut self, caller: CritterId, arg: CritterId) {
        let (Some(c), Some(a)) = (self.critters.get(caller), self.critters.get(arg)) else {
            return;
        };
        let d = self.topo.delta(c.pos, a.pos);
        let (normal, point) = match crate::response::contact_between(&self.topo, c, a) {
            Some(contact) => (contact.normal, c.pos + contact.point),
            None => {
                let len = d.length();
                let n = if len > 0.0 { d / len } else { V::unit_x() };
                (n, c.pos + d * 0.5)
            }
        };
        self.events.collisions.push(crate::context::CollisionEvent {
            caller,
            arg,
            point,
            normal,
            impulse: 0.0,
        });
    }

    fn stage_lifecycle(&mut self) -> Result<(), Error> {
        let mut gone = Vec::new();
        for id in std::mem::take(&mut self.pending.deaths) {
            self.events.deaths.push(id);
            let slot = self.critters.slot_of(id);
            if let (Some(slot), Some(c)) = (slot, self.critters.remove(id)) {
                if c.is_wall() {
                    self.walls.retain(|&w| w != id);
                }
                if self.sleep.active {
                    gone.push((slot as usize, c.pos, c.radius));
                }
            }
        }
        if !gone.is_empty() {
            self.sleep
                .removed(&self.topo, &gone, self.critters.slot_slice());
        }
        for spec in std::mem::take(&mut self.pending.spawns) {
            let id = self.spawn(spec)?;
            self.events.spawns.push(id);
        }
        Ok(())
    }
}

/// By slot, the key of each critter's place in the layout (`u32::MAX` for an empty slot only),
/// and the keys per row.
///
/// The layout follows the broad phase's grid, whose cells run along x, then y, then z: the box
/// is cut into rows along x, two mean spacings of the critters high (and deep in 3D), taken one
/// after the other as the grid's cells are, and each row's critters are ordered by x. The pair
/// walk of the grid, and of the list it builds, then goes through the critters nearly in memory
/// order.
fn layout_keys<V: Vector>(
    topo: &Topology<V>,
    slots: &[Option<Critter<V>>],
    live: usize,
) -> (Vec<u32>, u32) {
    use rayon::prelude::*;
    let (min, size) = (topo.min, topo.max - topo.min);
    let volume: f64 = (0..V::DIM).map(|axis| size.get(axis)).product();
    let spacing = (volume / live.max(1) as f64).powf(1.0 / V::DIM as f64);
    // Rows along x over the other axes, at most 2^16 of them in all.
    let mut height = 2.0 * spacing;
    let rows_on = |height: f64, axis: usize| (size.get(axis) / height).ceil().max(1.0);
    let rows = |height: f64| {
        (1..V::DIM)
            .map(|axis| rows_on(height, axis))
            .product::<f64>()
    };
    while rows(height) > 65_536.0 {
        height *= 2.0;
    }
    let row_count = rows(height) as u64;
    // Steps along x within a row: the keys of all rows fit below u32::MAX.
    let steps = (u64::from(u32::MAX - 1) / row_count).max(1) as f64;
    let key = |c: &Critter<V>| {
        let mut row = 0.0;
        for axis in (1..V::DIM).rev() {
            let n = rows_on(height, axis);
            // NaN and positions outside the box clamp to its edges.
            let r = ((c.pos.get(axis) - min.get(axis)) / height)
                .floor()
                .clamp(0.0, n - 1.0);
            row = row * n + if r.is_nan() { 0.0 } else { r };
        }
        let t = (c.pos.get(0) - min.get(0)) / size.get(0);
        let x = (t * steps).floor().clamp(0.0, steps - 1.0);
        let x = if x.is_nan() { 0.0 } else { x };
        ((row * steps + x) as u64).min(u64::from(u32::MAX - 1)) as u32
    };
    let keys = slots
        .par_iter()
        .map(|c| c.as_ref().map_or(u32::MAX, key))
        .collect();
    (keys, steps as u32)
}

/// Sets the step of a hook error raised where the step was not known.
pub(crate) fn at_step(e: Error, step: u64) -> Error {
    match e {
        Error::Hook {
            kind,
            critter,
            message,
            ..
        } => Error::Hook {
            kind,
            critter,
            step,
            message,
        },
        Error::Script(mut s) => {
            s.step = Some(step);
            Error::Script(s)
        }
        other => other,
    }
}

/// The rules and the narrow phase of a run of candidates: the pairs that may collide, in the
/// roles their rule gives, kept in `contacts` if they are two touching disks and in `walls` if
/// one is a wall (tested in the response); returns how many may collide. `None` when a pair's
/// rule is not in the class table, or a touching pair's roles are to be asked of the hooks (the
/// rules would run a script): the caller then runs the stages one after the other.
fn rules_and_narrow<V: Vector>(
    critters: &CritterSet<V>,
    rules: &RuleCache,
    topo: &Topology<V>,
    chunk: &[(u32, u32)],
    contacts: &mut Vec<(u32, u32)>,
    walls: &mut Vec<(u32, u32, bool)>,
) -> Option<usize> {
    let slots = critters.slot_slice();
    let mut ruled = 0;
    // Every disk pair is written and the end moved on only for those that touch: in a gas most
    // candidates do not, in no order a processor could predict.
    let mut end = contacts.len();
    contacts.resize(end + chunk.len(), (0, 0));
    for (k, &(a, b)) in chunk.iter().enumerate() {
        if let Some(&(i, j)) = chunk.get(k + CANDIDATES_AHEAD) {
            prefetch(slots.get(i as usize));
            prefetch(slots.get(j as usize));
        }
        let (Some(ca), Some(cb)) = (critters.slot(a), critters.slot(b)) else {
            continue;
        };
        let (pair, ask) = match rules.cached(ca.class, cb.class)? {
            Some(rule) => match roles_slots(rule, (a, ca), (b, cb)) {
                Some(pair) => (pair, false),
                None => continue,
            },
            None => ((a, b), true),
        };
        ruled += 1;
        let (first, second) = if pair.0 == a { (ca, cb) } else { (cb, ca) };
        if first.is_wall() || second.is_wall() {
            // Tested in the response, once the disk pairs have moved.
            walls.push((pair.0, pair.1, ask));
        } else {
            let touching = crate::contact::touching_ball_ball(
                topo.delta(first.pos, second.pos),
                first.radius,
                second.radius,
            );
            if ask & touching {
                return None;
            }
            contacts[end] = pair;
            end += usize::from(touching);
        }
    }
    contacts.truncate(end);
    Some(ruled)
}

/// [`roles_order`] for critters `ca` in slot `a` and `cb` in slot `b`: the slots of (caller, arg).
#[inline]
pub(crate) fn roles_slots<V: Vector>(
    rule: PairRule,
    (a, ca): (u32, &Critter<V>),
    (b, cb): (u32, &Critter<V>),
) -> Option<(u32, u32)> {
    roles_order(rule, ca, cb).map(|(caller, _)| {
        if std::ptr::eq(caller, ca) {
            (a, b)
        } else {
            (b, a)
        }
    })
}

/// (caller, arg) for a pair under `rule`, or `None` when they don't collide.
pub(crate) fn roles_order<'c, V: Vector>(
    rule: PairRule,
    a: &'c Critter<V>,
    b: &'c Critter<V>,
) -> Option<(&'c Critter<V>, &'c Critter<V>)> {
    match rule {
        PairRule::DontCollide => None,
        PairRule::FirstCalls => Some((a, b)),
        PairRule::SecondCalls => Some((b, a)),
        PairRule::LowerIdCalls if a.id < b.id => Some((a, b)),
        PairRule::LowerIdCalls => Some((b, a)),
    }
}

fn hook_error<V: Vector>(
    e: Error,
    kinds: &KindSet<V>,
    kind: KindId,
    id: CritterId,
    step: u64,
) -> Error {
    match e {
        Error::Hook { .. } => e,
        Error::Script(mut s) => {
            s.kind.get_or_insert_with(|| kinds.name(kind).to_string());
            s.critter.get_or_insert(id);
            s.step.get_or_insert(step);
            Error::Script(s)
        }
        other => Error::Hook {
            kind: kinds.name(kind).to_string(),
            critter: id,
            step,
            message: other.to_string(),
        },
    }
}

/// A live critter's box for the broad phase, a wall's widened by `wall_pad`. Only a wall's box
/// is read from its shape, so a disk's traits stay untouched.
#[inline]
fn broad_object<V: Vector>(c: &Critter<V>, slot: u32, wall_pad: f64) -> Option<BroadObject<V>> {
    if !c.alive {
        return None;
    }
    let mut o = BroadObject {
        center: c.pos,
        half: V::splat(c.radius),
        slot,
        is_wall: c.is_wall(),
    };
    if o.is_wall {
        o.half = wall_half(c) + V::splat(wall_pad);
    }
    Some(o)
}

/// The broad phase's objects read in place from the critters' slots: index `i` is slot `i`, a
/// gap where no live critter is.
struct Slots<'a, V: Vector> {
    slots: &'a [Option<Critter<V>>],
    /// How far to widen the walls' boxes.
    wall_pad: f64,
    /// The step's length, for the critters' strides.
    dt: f64,
    /// Sleepers and walls by slot, or empty (see [`Objects::still`]).
    still: &'a [bool],
}

impl<V: Vector> Objects<V> for Slots<'_, V> {
    #[inline]
    fn slots(&self) -> usize {
        self.slots.len()
    }

    #[inline]
    fn object(&self, i: usize) -> Option<BroadObject<V>> {
        self.slots
            .get(i)?
            .as_ref()
            .and_then(|c| broad_object(c, i as u32, self.wall_pad))
    }

    #[inline]
    fn prefetch(&self, i: usize) {
        prefetch(self.slots.get(i));
    }

    #[inline]
    fn still(&self, i: usize) -> bool {
        self.still.get(i).copied().unwrap_or(false)
    }

    #[inline]
    fn any_still(&self) -> bool {
        !self.still.is_empty()
    }

    #[inline]
    fn step(&self, i: usize) -> V {
        match self.slots.get(i) {
            Some(Some(c)) if c.alive && !c.fixed && !c.is_wall() => c.vel * self.dt,
            _ => V::zero(),
        }
    }
}

/// Lists of fewer pairs than this are sorted by comparison; longer ones (a pile's contacts)
/// by radix.
const RADIX_MIN: usize = 256;

/// The broad phase's Verlet list is sorted once many contacts were (see
/// [`BroadPhase::sort_list`]), and leads only its fastest objects ([`BroadPhase::set_crowded`]):
/// when it holds at most this many pairs per contact.
const LISTED_PER_CONTACT: usize = 8;

/// Bits per digit of the radix sort of pairs.
const RADIX_BITS: u32 = 11;

/// Sorts `pairs` of slots below `slots` by their lower slot, then their higher one, keeping
/// each pair's own order; no pair may be in the list twice (as `(a, b)` and `(b, a)` either).
/// Each pair becomes one integer (lower slot, higher slot, then a bit for "the first is the
/// higher"), sorted a digit at a time from the lowest: a pile's 100,000 contacts in a few
/// passes over them instead of a comparison sort's 17.
/// Returns true when they were in that order already (and nothing was done).
pub(crate) fn sort_pairs(pairs: &mut [(u32, u32)], slots: usize) -> bool {
    if pairs.is_sorted_by_key(|&(a, b)| (a.min(b), a.max(b))) {
        return true;
    }
    let bits = usize::BITS - slots.saturating_sub(1).leading_zeros();
    let width = 2 * bits + 1;
    let key = |&(a, b): &(u32, u32)| {
        (u64::from(a.min(b)) << (bits + 1)) | (u64::from(a.max(b)) << 1) | u64::from(a > b)
    };
    if pairs.len() < RADIX_MIN || width > u64::BITS {
        pairs.sort_unstable_by_key(|&(a, b)| (a.min(b), a.max(b)));
        return false;
    }
    let mut keys: Vec<u64> = pairs.iter().map(key).collect();
    let mut spare = vec![0u64; keys.len()];
    let mask = (1u64 << RADIX_BITS) - 1;
    for shift in (0..width).step_by(RADIX_BITS as usize) {
        let mut start = [0usize; 1 << RADIX_BITS];
        for &k in &keys {
            start[((k >> shift) & mask) as usize] += 1;
        }
        let mut sum = 0;
        for s in &mut start {
            (*s, sum) = (sum, sum + *s);
        }
        for &k in &keys {
            let d = ((k >> shift) & mask) as usize;
            spare[start[d]] = k;
            start[d] += 1;
        }
        std::mem::swap(&mut keys, &mut spare);
    }
    let slot_mask = (1u64 << bits) - 1;
    for (pair, k) in pairs.iter_mut().zip(keys) {
        let (lo, hi) = ((k >> (bits + 1)) as u32, ((k >> 1) & slot_mask) as u32);
        *pair = if k & 1 == 1 { (hi, lo) } else { (lo, hi) };
    }
    false
}

/// How many pairs ahead the rules and narrow stages' pass and the response ask for the critters
/// of the next pairs to be loaded (they are scattered over memory, and the loads overlap).
const CANDIDATES_AHEAD: usize = 8;

/// How many slots ahead the move asks for the next critters to be loaded (32, two kilobytes of
/// 2D records: at a million critters the move took 9.2-9.5 ms a step on one thread against
/// 9.6-9.9 with 16 and 11.0-11.1 with 8, and 4.8-5.1 on two threads against 5.3-5.6 and 6.2).
const MOVE_AHEAD: usize = 32;

/// A hint to start loading `slot`'s first cache line (nothing for `None`).
#[inline]
pub(crate) fn prefetch<T>(slot: Option<&T>) {
    #[cfg(target_arch = "x86_64")]
    if let Some(slot) = slot {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: a prefetch only hints the cache (it never faults, whatever the address),
        // and SSE is in every x86_64 target.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(slot).cast()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = slot;
}

/// A hint to start loading every cache line `slot` spans (nothing for `None`): a critter
/// record that straddles lines is read in more than its first.
#[inline]
pub(crate) fn prefetch_whole<T>(slot: Option<&T>) {
    #[cfg(target_arch = "x86_64")]
    if let Some(slot) = slot {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let start = std::ptr::from_ref(slot).cast::<i8>();
        // The offsets from `start` of each line's first byte, from `start`'s line to the
        // line of the value's last byte.
        let into = start as usize % 64;
        let span = into + std::mem::size_of::<T>().max(1);
        for line in (0..span).step_by(64) {
            // SAFETY: as in `prefetch` (the address is only hinted, never read).
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(line).wrapping_sub(into)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = slot;
}

/// A wall's box half sizes.
#[inline]
fn wall_half<V: Vector>(c: &Critter<V>) -> V {
    match c.shape() {
        Shape::Wall(w) => w.aabb_half(),
        Shape::Disk => V::splat(c.radius),
    }
}

/// What the move stage did for the broad phase's input pass (see [`World::stage_move`]).
#[derive(Clone, Debug)]
struct Moved {
    /// How many chunks of [`INPUT_CHUNK`] slots it went through.
    chunks: usize,
    /// What it saw of the critters.
    seen: Survey,
    /// The slots but the live walls' that were no longer inside their bound of the broad
    /// phase's Verlet list.
    escapes: Escapes,
    /// How many live walls it passed over.
    walls: usize,
}

/// What the broad phase's input pass learns about the critters on the way.
#[derive(Clone, Copy, Debug, Default)]
struct Survey {
    /// Some live critter has no rule class yet.
    unset: bool,
    /// The largest radius of a live disk (0 if none).
    largest_radius: f64,
}

impl Survey {
    /// What one critter adds.
    #[inline]
    fn of<V: Vector>(c: &Critter<V>) -> Survey {
        Survey {
            unset: c.alive && c.class == CLASS_UNSET,
            largest_radius: if c.alive && !c.is_wall() {
                c.radius
            } else {
                0.0
            },
        }
    }

    fn and(self, other: Survey) -> Survey {
        Survey {
            unset: self.unset || other.unset,
            largest_radius: self.largest_radius.max(other.largest_radius),
        }
    }
}

/// Slots per chunk of the parallel passes over the critters that build the broad phase's input.
const INPUT_CHUNK: usize = 4096;

/// "(1, 2.5)" or "(1, 2.5, 0)".
pub fn fmt_vec<V: Vector>(v: V) -> String {
    let parts: Vec<String> = (0..V::DIM).map(|a| format!("{}", v.get(a))).collect();
    format!("({})", parts.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    /// The rules and narrow stages in one pass give the lists of the two stages one after the
    /// other, on one thread and in parallel chunks, and so do they when done with the broad
    /// phase's re-test of the kept list, on a gas with walls that has settled into many
    /// candidate pairs.
    #[test]
    fn rules_and_narrow_phase_in_one_pass_match_them_one_after_the_other() {
        let check = || {
            let mut w = crate::scenes::gas::<DVec2>(&crate::scenes::GasParams {
                n: 40_000,
                packing: 0.45,
                ..Default::default()
            })
            .unwrap();
            let mut checked = 0;
            for _ in 0..30 {
                w.step().unwrap();
                w.stage_broad_phase(false);
                if w.candidates.len() < PARALLEL_PAIRS {
                    continue;
                }
                w.stage_rules().unwrap();
                w.stage_narrow_phase().unwrap();
                w.sort_contacts();
                let in_order = (w.ruled.len(), w.contacts.clone(), w.wall_pairs.clone());
                assert!(!in_order.1.is_empty() && !in_order.2.is_empty());
                let ruled = w.rules_and_narrow_phase_in_one_pass();
                w.sort_contacts();
                let fused = (
                    ruled.expect("no roles to ask"),
                    w.contacts.clone(),
                    w.wall_pairs.clone(),
                );
                assert_eq!(fused, in_order);
                // And with the broad phase's re-test, chunk by chunk.
                w.contacts.clear();
                w.wall_pairs.clear();
                w.stage_broad_phase(true);
                let Fused::Done(ruled, _) = w.fused else {
                    panic!("not done with the re-test");
                };
                w.sort_contacts();
                let with_retest = (ruled, w.contacts.clone(), w.wall_pairs.clone());
                assert_eq!(with_retest, in_order);
                checked += 1;
            }
            checked
        };
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let checked = pool.install(check);
            assert!(checked >= 5, "only {checked} steps had enough candidates");
        }
    }

    /// The radix sort of pairs gives the comparison sort's order, each pair kept the way round
    /// it was, for slot counts from a handful to 2^31 (where the key no longer fits and the
    /// comparison sort takes over).
    #[test]
    fn pairs_sorted_by_radix_are_in_the_comparison_sort_s_order() {
        let mut rng = crate::Rng::new(11);
        for (slots, n) in [
            (3, 2),
            (40, 300),
            (10_004, 20_000),
            (1 << 20, 5_000),
            (1 << 31, 600),
        ] {
            let mut seen = std::collections::BTreeSet::new();
            let mut pairs = Vec::new();
            while pairs.len() < n {
                let a = (rng.next_f64() * slots as f64) as u32;
                let b = (rng.next_f64() * slots as f64) as u32;
                if a != b && seen.insert((a.min(b), a.max(b))) {
                    pairs.push((a, b));
                }
            }
            let mut expected = pairs.clone();
            expected.sort_by_key(|&(a, b)| (a.min(b), a.max(b)));
            sort_pairs(&mut pairs, slots);
            assert_eq!(pairs, expected, "{slots} slots");
            if n > 100 {
                let ways = |first_higher: bool| pairs.iter().any(|&(a, b)| (a > b) == first_higher);
                assert!(
                    ways(true) && ways(false),
                    "test setup: pairs both ways round"
                );
            }
        }
    }

    /// The broad phase's objects as a fresh pass over the critters gives them.
    fn fresh_objects<V: Vector>(w: &World<V>) -> Vec<BroadObject<V>> {
        let pad = w
            .critters
            .iter()
            .filter(|c| c.alive && !c.is_wall())
            .map(|c| c.radius)
            .fold(0.0, f64::max);
        (0..w.critters.slot_count() as u32)
            .filter_map(|i| broad_object(w.critters.slot(i)?, i, pad))
            .collect()
    }

    /// A move and a broad phase, whose pairs must be those a fresh grid finds in fresh objects;
    /// true when the Verlet list was rebuilt or mended.
    fn check_pairs(w: &mut World<DVec2>, what: &str) -> bool {
        let changes = |w: &World<DVec2>| w.broad_phase_rebuilds() + w.broad_phase_repairs();
        let rebuilds = changes(w);
        w.stage_move(w.dt);
        w.stage_broad_phase(false);
        assert_fresh_pairs(w, what);
        changes(w) > rebuilds
    }

    /// The broad phase's last pairs must be those a fresh grid finds in fresh objects.
    fn assert_fresh_pairs(w: &World<DVec2>, what: &str) {
        let mut fresh = Vec::new();
        BroadPhase::new(BroadPhaseMode::Grid).find_pairs(&fresh_objects(w), &w.topo, &mut fresh);
        let sorted = |pairs: &[(u32, u32)]| {
            let mut v: Vec<_> = pairs.iter().map(|&(a, b)| (a.min(b), a.max(b))).collect();
            v.sort_unstable();
            v
        };
        assert_eq!(sorted(&w.candidates), sorted(&fresh), "{what}");
    }

    /// The built-in gas of `n` disks.
    fn gas_2d(n: usize) -> World<DVec2> {
        let params = crate::scenes::SceneParams {
            n: Some(n),
            ..Default::default()
        };
        let crate::scenes::AnyWorld::D2(w) = crate::scenes::builtin("gas", &params)
            .expect("builds")
            .world
        else {
            panic!("gas is 2D")
        };
        w
    }

    /// The slots the move notes as having left their bound of the Verlet list are exactly those
    /// a full check of every slot finds, in order, so a repair may mend them without a pass of
    /// its own; and the pairs stay those of a fresh grid through the repairs.
    #[test]
    fn the_move_notes_every_slot_that_left_its_bound() {
        for n in [3_000, PARALLEL_MIN + 5000] {
            let mut w = gas_2d(n);
            // A few fast disks leave their bounds every few steps, too few to rebuild for.
            let ids: Vec<CritterId> = w.critters().iter().map(|c| c.id()).collect();
            for id in ids.iter().step_by(97) {
                if let Some(c) = w.get_mut(*id).filter(|c| !c.is_wall()) {
                    c.vel *= 20.0;
                }
            }
            let (mut noted, mut repairs) = (0, 0);
            for step in 0..40 {
                let before = w.broad_phase_repairs();
                w.stage_move(w.dt);
                let moved = w.moved.clone().expect("the move ran");
                let slots = w.critters.slot_slice();
                let full: Vec<u32> = (0..slots.len())
                    .filter(|&i| {
                        let o = slots[i]
                            .as_ref()
                            .and_then(|c| broad_object(c, i as u32, 0.0));
                        !w.broad.list_holds(&w.topo, i, o.as_ref())
                            && !slots[i].as_ref().is_some_and(|c| c.alive && c.is_wall())
                    })
                    .map(|i| i as u32)
                    .collect();
                if moved.escapes.complete {
                    assert_eq!(moved.escapes.slots, full, "n {n}, step {step}");
                    noted += full.len();
                }
                w.stage_broad_phase(false);
                assert_fresh_pairs(&w, &format!("n {n}, step {step}"));
                repairs += w.broad_phase_repairs() - before;
            }
            assert!(
                noted > 0 && repairs > 0,
                "n {n}: {noted} noted, {repairs} repairs"
            );
        }
    }

    /// Above PARALLEL_MIN the move checks each critter against the Verlet list and the broad
    /// phase the walls: a critter teleported, removed or spawned onto another, one grown, and a
    /// wall put down across the gas each make the list be rebuilt or mended, and the pairs are
    /// always those of a fresh grid.
    #[test]
    fn the_move_s_check_of_the_verlet_list_misses_no_change() {
        let mut w = gas_2d(PARALLEL_MIN + 5000);
        assert!(!w.walls.is_empty(), "the gas has walls");
        assert!(check_pairs(&mut w, "first step"), "the first step builds");
        assert!(
            !check_pairs(&mut w, "second step"),
            "a quiet step keeps the list"
        );
        let disks: Vec<CritterId> = w
            .critters()
            .iter()
            .filter(|c| !c.is_wall())
            .map(|c| c.id())
            .collect();
        let (a, b, c) = (disks[100], disks[20_000], disks[7000]);

        let there = w.get(b).expect("there").pos;
        w.get_mut(a).expect("there").pos = there;
        assert!(check_pairs(&mut w, "a teleport"));
        assert!(w
            .candidates
            .iter()
            .any(|&(p, q)| [p, q] == [a.index, b.index] || [q, p] == [a.index, b.index]));
        assert!(!check_pairs(&mut w, "a quiet step"));

        w.remove(c).expect("there");
        assert!(check_pairs(&mut w, "a removal"));
        let there = w.get(b).expect("there").pos;
        let spawned = w.spawn(CritterSpec::new("ball", there)).expect("spawns");
        assert_eq!(spawned.index, c.index, "the freed slot is reused");
        assert!(check_pairs(&mut w, "a spawn onto a critter"));
        assert!(!check_pairs(&mut w, "a quiet step"));

        w.get_mut(disks[300]).expect("there").radius *= 4.0;
        assert!(check_pairs(&mut w, "a critter grown"));

        // A wall in a freed slot: only the broad phase's check of the walls sees it.
        w.remove(disks[400]).expect("there");
        assert!(check_pairs(&mut w, "a removal"));
        let middle = 0.5 * (w.topo.min + w.topo.max);
        let wall = WallBox::aligned(
            middle - DVec2::new(20.0, 0.5),
            middle + DVec2::new(20.0, 0.5),
        )
        .expect("a wall");
        let id = w.add_wall(wall).expect("added");
        assert_eq!(id.index, disks[400].index, "the freed slot is reused");
        let slots = w.critters.slot_count();
        assert!(check_pairs(&mut w, "a wall put down"));
        assert_eq!(w.critters.slot_count(), slots);
        assert!(w
            .candidates
            .iter()
            .any(|&(p, q)| p == id.index || q == id.index));
        assert!(!check_pairs(&mut w, "a quiet step"));
    }
}

#[cfg(test)]
mod layout_tests {
    use super::*;
    use glam::DVec2;

    /// The built-in gas of `n` disks.
    pub(super) fn gas(n: usize) -> World<DVec2> {
        let params = crate::scenes::SceneParams {
            n: Some(n),
            ..Default::default()
        };
        match crate::scenes::builtin("gas", &params)
            .expect("builds")
            .world
        {
            crate::scenes::AnyWorld::D2(w) => w,
            crate::scenes::AnyWorld::D3(_) => panic!("gas is 2D"),
        }
    }

    /// Every id finds its own critter, iteration goes in id order, and the hash and totals are
    /// those of the same critters in id order.
    fn check_ids(w: &World<DVec2>, what: &str) {
        let set = &w.critters;
        let ids: Vec<CritterId> = set.iter().map(|c| c.id).collect();
        assert_eq!(ids.len(), set.len(), "{what}: every critter once");
        assert!(ids.is_sorted(), "{what}: iteration in id order");
        for &id in &ids {
            let slot = set.slot_of(id).expect("a slot");
            assert_eq!(set.slot(slot).map(|c| c.id), Some(id), "{what}: {id}");
            assert_eq!(set.get(id).map(|c| c.id), Some(id), "{what}: {id}");
        }
        // The same critters put back in id order: a set of their own, built from its parts.
        let free: Vec<CritterId> = set.free_ids().collect();
        let plain = CritterSet::from_parts(set.iter().cloned().collect(), &free).expect("parts");
        assert!(!plain.is_arranged());
        let (a, b) = (
            crate::hash::critters::hash_critters(set.in_id_order(), set.statics()),
            crate::hash::critters::hash_critters(plain.in_id_order(), plain.statics()),
        );
        assert_eq!((a.lanes, a.props), (b.lanes, b.props), "{what}: hash");
        assert_eq!(
            (a.energy.to_bits(), a.momentum),
            (b.energy.to_bits(), b.momentum),
            "{what}: totals"
        );
    }

    /// `arrange` puts the critters in the order of their keys, with the empty slots dropped and
    /// ids unchanged; spawns, removals and `unarrange` after it keep every id on its critter.
    #[test]
    fn critters_laid_out_keep_their_ids() {
        let mut w = gas(400);
        for i in (10..300).step_by(7) {
            let id = w.critters.slot(i).expect("a critter").id;
            w.remove(id).expect("removed");
        }
        let live = w.critters.len();
        assert!(w.critters.slot_count() > live, "test setup: empty slots");
        check_ids(&w, "before");
        // Keys that reverse the slots' order, the empty slots marked.
        let keys: Vec<u32> = (0..w.critters.slot_count())
            .map(|s| match w.critters.slot(s as u32) {
                Some(_) => 1_000_000 - s as u32,
                None => u32::MAX,
            })
            .collect();
        let before: Vec<CritterId> = w.critters.iter_stored().map(|c| c.id).collect();
        w.critters.arrange(&keys);
        assert!(w.critters.is_arranged());
        assert_eq!(w.critters.slot_count(), live, "empty slots dropped");
        let after: Vec<CritterId> = w.critters.iter_stored().map(|c| c.id).collect();
        assert_eq!(
            after,
            before.into_iter().rev().collect::<Vec<_>>(),
            "keys' order"
        );
        check_ids(&w, "arranged");
        // A spawn takes a free id and a new slot at the end; a removal leaves a gap.
        let spawned = w
            .spawn(CritterSpec::ball(DVec2::new(3.0, 3.0)))
            .expect("spawns");
        assert_eq!(w.critters.slot_of(spawned), Some(live as u32));
        check_ids(&w, "spawned");
        let gone = after[5];
        w.remove(gone).expect("removed");
        assert!(w.critters.get(gone).is_none() && w.critters.slot_of(gone).is_none());
        check_ids(&w, "removed");
        w.critters.unarrange();
        assert!(!w.critters.is_arranged());
        for c in w.critters.iter() {
            assert_eq!(
                w.critters.slot_of(c.id),
                Some(c.id.index),
                "back in id order"
            );
        }
        check_ids(&w, "unarranged");
    }

    /// The world's own layout follows the grid's rows: critters stored in a shuffled order
    /// (far apart in space when next to each other in memory) are laid out at the next check,
    /// after which neighbours in memory are about one spacing apart; critters spawned row by
    /// row are left as they are. Neither changes the run.
    #[test]
    fn the_layout_puts_neighbours_in_space_next_to_each_other_in_memory() {
        let checked = Locality {
            every: 1,
            min_critters: 0,
            disorder: LOCALITY.disorder,
        };
        let gap = |w: &World<DVec2>| {
            let cs: Vec<&Critter<DVec2>> = w.critters.iter_stored().filter(|c| !c.wall).collect();
            let sum: f64 = cs.windows(2).map(|p| (p[0].pos - p[1].pos).length()).sum();
            sum / (cs.len() - 1) as f64
        };
        let (mut shuffled, mut plain) = (gas(5_000), gas(5_000));
        plain.set_locality(Locality {
            every: 0,
            ..checked
        });
        shuffled.set_locality(checked);
        let keys: Vec<u32> = (0..shuffled.critters.slot_count() as u64)
            .map(|s| (s.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 33) as u32)
            .collect();
        shuffled.critters.arrange(&keys);
        shuffled.broad.forget_list();
        let (before, spawned) = (gap(&shuffled), gap(&plain));
        // The box is 140 wide: shuffled neighbours are some 70 apart, spawned ones a spacing (2)
        // and a jump at the end of each row of 71 (2 more on average).
        assert!(before > 30.0 && spawned < 5.0, "{before}, {spawned}");
        for step in 0..3 {
            shuffled.step().expect("steps");
            plain.step().expect("steps");
            assert_eq!(shuffled.state_hash(), plain.state_hash(), "step {step}");
        }
        let after = gap(&shuffled);
        assert!(
            after < 5.0,
            "mean gap in memory {after} laid out, {before} shuffled"
        );
        // Spawned row by row, the gas is in order: checked every step, never laid out.
        let mut spawned = gas(5_000);
        spawned.set_locality(checked);
        spawned.run(5).expect("runs");
        assert!(
            !spawned.critters.is_arranged(),
            "a gas in order is left alone"
        );
    }
}

#[cfg(test)]
mod traits_tests {
    use super::layout_tests::gas;
    use super::*;
    use crate::critter::PropValue;
    use glam::DVec2;
    use std::sync::Arc;

    fn disks(w: &World<DVec2>) -> Vec<&Critter<DVec2>> {
        w.critters().iter().filter(|c| !c.is_wall()).collect()
    }

    /// A gas spawned from one kind keeps one copy of its traits; a change to one critter's
    /// traits is that critter's alone, and what the others read is unchanged.
    #[test]
    fn critters_alike_share_their_traits_and_a_change_is_the_changed_critter_s_own() {
        let mut w = gas(200);
        let all = disks(&w);
        assert_eq!(all.len(), 200);
        assert!(all.iter().all(|c| Arc::ptr_eq(&c.traits, &all[0].traits)));
        let (first, second) = (all[0].id, all[1].id);
        let before: Vec<(u64, u64, u64, u64)> = all
            .iter()
            .map(|c| {
                let t = &c.traits;
                let b = |x: f64| x.to_bits();
                (b(t.mass), b(t.priority), b(t.restitution), b(t.health))
            })
            .collect();
        let c = w.get_mut(first).expect("there");
        c.set_health(c.health() - 1.0);
        c.set_restitution(0.25).expect("a restitution");
        c.props_mut().insert("tag".into(), PropValue::Int(3));
        let all = disks(&w);
        assert_eq!(
            all[0].health().to_bits(),
            (f64::from_bits(before[0].3) - 1.0).to_bits()
        );
        assert_eq!(all[0].restitution(), 0.25);
        assert_eq!(all[0].props().len(), 1);
        for (c, b) in all.iter().zip(&before).skip(1) {
            let t = &c.traits;
            assert_eq!(
                (
                    t.mass.to_bits(),
                    t.priority.to_bits(),
                    t.restitution.to_bits()
                ),
                (b.0, b.1, b.2)
            );
            assert_eq!(t.health.to_bits(), b.3);
            assert!(t.props.is_empty());
            assert!(Arc::ptr_eq(&c.traits, &all[1].traits), "{:?}", c.id);
        }
        assert!(!Arc::ptr_eq(&all[0].traits, &all[1].traits));
        assert_eq!(w.get(second).map(|c| c.restitution()), Some(1.0));
    }

    /// Only critters whose traits are the same bit for bit share them: a spawn that differs in
    /// any one trait (health -0 against 0 too) gets its own, and one alike shares again.
    #[test]
    fn critters_that_differ_in_any_trait_do_not_share() {
        let mut w = gas(100);
        let last = disks(&w)[99].traits.clone();
        let at = |x: f64| DVec2::new(x, 5.0);
        let specs = [
            CritterSpec::ball(at(1.5)).restitution(0.5),
            CritterSpec::ball(at(2.5)).health(-0.0),
            CritterSpec::ball(at(3.5)).health(0.0),
            CritterSpec::ball(at(4.5)).mass(2.0),
            CritterSpec::ball(at(5.5)).priority(CP_WALL),
            CritterSpec::ball(at(6.5)).prop("tag", PropValue::Int(1)),
            CritterSpec::ball(at(7.5)).prop("tag", PropValue::Int(1)),
        ];
        let mut ids = Vec::new();
        for spec in specs {
            ids.push(w.spawn(spec).expect("spawns"));
        }
        let traits: Vec<Arc<Traits<DVec2>>> = ids
            .iter()
            .map(|&id| w.get(id).expect("there").traits.clone())
            .collect();
        for (i, t) in traits.iter().enumerate() {
            assert!(!Arc::ptr_eq(t, &last), "spawn {i}");
            for (j, u) in traits.iter().enumerate().take(i) {
                assert!(!Arc::ptr_eq(t, u), "spawns {j} and {i}");
            }
        }
        assert_eq!(
            w.get(ids[1]).map(|c| c.health().to_bits()),
            Some((-0.0f64).to_bits())
        );
        // Alike again: shares with the one before.
        let a = w.spawn(CritterSpec::ball(at(8.5))).expect("spawns");
        let b = w.spawn(CritterSpec::ball(at(9.5))).expect("spawns");
        let (ta, tb) = (&w.get(a).expect("a").traits, &w.get(b).expect("b").traits);
        assert!(Arc::ptr_eq(ta, tb));
    }
}
