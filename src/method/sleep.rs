//! Sleep under `solve:n`: a pile at rest stops costing a full step.
//!
//! A resting pile under `solve:n` still moves, tests and solves every one of its contacts every
//! step, only to find them where they were. Like the engines people compare against (Box2D,
//! Rapier), `solve:n` lets such critters sleep:
//!
//! * a critter is *quiet* in a step when it ends the step slower than [`SLEEP_SPEED_STEPS`] steps
//!   of gravity (`|g| dt`) and no `collide` hook took it;
//! * the critters that touch each other (walls, fixed critters and sleepers do not join them)
//!   form an *island*; an island whose critters are all quiet counts one more quiet step, from
//!   the fewest any of them had, and any other island starts again from 0;
//! * after [`SLEEP_STEPS`] quiet steps the island falls asleep at once: its velocities are set to
//!   zero, and from then on its critters are not moved, gravity does not pull them, and pairs of
//!   two sleepers (or a sleeper and a wall) are neither tested nor solved;
//! * to an awake critter a sleeper is as heavy as a wall;
//! * an island that falls asleep touching sleeping islands joins them: the sleepers that touch
//!   form one sleeping island;
//! * a sleeper wakes, and with it its whole island, when an awake critter that is not quiet
//!   touches it, when a `collide` hook takes it, when anything (a script, the host) changes its
//!   position, velocity or radius, when it dies or is removed, and when a critter within reach
//!   of it is removed.
//!
//! Waking the whole island is what Box2D does: a ball that rests on a support that is taken
//! away falls with it instead of hanging in the air. Sleep needs gravity (without it no critter
//! is ever quiet) and ends when the method is no longer `solve:n`. The counts of quiet steps and
//! the sleepers' islands are state: [`World::state_hash`] covers them and recordings write them
//! with every full state ([`World::quiet_steps`]).
//!
//! [`World::state_hash`]: crate::World::state_hash
//! [`World::quiet_steps`]: crate::World::quiet_steps

use crate::border::Topology;
use crate::critter::Critter;
use crate::critter_set::CritterSet;
use crate::vector::Vector;

/// A critter slower than this many steps of gravity (`|g| dt`) at the end of a step is quiet.
/// At 60 steps a second under 9.81 that is 0.16, between Box2D's 0.05 and Rapier's 0.4.
pub const SLEEP_SPEED_STEPS: f64 = 1.0;

/// Quiet steps after which an island falls asleep (half a second at 60 steps a second, Box2D's
/// time to sleep).
pub const SLEEP_STEPS: u16 = 30;

/// A removed critter wakes the sleepers whose gap to it is below this share of their two radii.
const REACH: f64 = 0.1;

/// Removals in one step beyond which every sleeper is woken rather than searched for.
const MANY_REMOVALS: usize = 16;

/// The sleep state and its working arrays, by slot.
#[derive(Debug, Default)]
pub(crate) struct Sleep<V> {
    /// Whether critters may sleep at all (on by default).
    pub(crate) off: bool,
    /// Whether this step sleeps (`solve:n` with gravity, not off).
    pub(crate) active: bool,
    /// Quiet steps of each slot's critter, up to [`SLEEP_STEPS`] (asleep).
    quiet: Vec<u16>,
    /// Each sleeper's island, named by the slot of its first member (a sleeper itself).
    island: Vec<u32>,
    /// Where each sleeper fell asleep, and its radius then.
    rest: Vec<(V, f64)>,
    /// Sleepers and walls: a pair of two of them needs no test.
    still: Vec<bool>,
    /// How many sleepers there are.
    sleepers: usize,
    /// Whether the last [`Sleep::check`] found every critter a live wall or a sleeper.
    all_still: bool,
    /// The critters' mark when that check found them all still (0 otherwise): while they are
    /// untouched since, the next check has nothing to look at.
    still_mark: u64,
    /// Whether critters were removed since [`Sleep::take_removed`] last asked.
    removed: bool,
    /// Slots a `collide` hook took this step.
    stirred: Vec<u32>,
    /// Islands to wake at the next [`Sleep::flush`].
    waking: Vec<u32>,
    /// Union-find parents and per-slot flags of the island pass.
    parent: Vec<u32>,
    quiet_now: Vec<bool>,
    fewest: Vec<u16>,
}

impl<V: Vector> Sleep<V> {
    /// Nobody asleep; sleep allowed when `on`.
    pub(crate) fn new(on: bool) -> Self {
        Sleep {
            off: !on,
            ..Default::default()
        }
    }

    /// Everything but whether sleep is off, for a world put in a recorded state.
    pub(crate) fn forget(&mut self) {
        *self = Sleep::new(!self.off);
    }

    /// How many critters sleep.
    pub(crate) fn count(&self) -> usize {
        self.sleepers
    }

    /// True when the critter in `slot` sleeps.
    pub(crate) fn asleep(&self, slot: usize) -> bool {
        self.quiet.get(slot).is_some_and(|&q| q >= SLEEP_STEPS)
    }

    /// Sleepers and walls by slot (empty when nobody sleeps).
    pub(crate) fn still(&self) -> &[bool] {
        if self.sleepers > 0 {
            &self.still
        } else {
            &[]
        }
    }

    /// Quiet steps and island by slot, for the slots whose count is not 0 (the island is
    /// meaningful for sleepers only).
    pub(crate) fn counts(&self) -> impl Iterator<Item = (usize, u16, u32)> + '_ {
        self.quiet
            .iter()
            .enumerate()
            .filter(|&(_, &q)| q > 0)
            .map(|(i, &q)| (i, q, if q >= SLEEP_STEPS { self.island[i] } else { 0 }))
    }

    /// Everybody awake, every count at 0: the arrays are emptied, and fitted to the slots again
    /// when next needed (so a world under another method pays nothing per step).
    pub(crate) fn clear(&mut self) {
        self.quiet.clear();
        self.island.clear();
        self.rest.clear();
        self.still.clear();
        self.sleepers = 0;
        self.all_still = false;
        self.stirred.clear();
        self.waking.clear();
    }

    /// Wakes the critter in `slot` (its count back to 0), and at the next [`Sleep::flush`] the
    /// rest of its island.
    pub(crate) fn wake(&mut self, slot: usize) {
        if self.asleep(slot) {
            self.waking.push(self.island[slot]);
        } else if let Some(q) = self.quiet.get_mut(slot) {
            *q = 0;
        }
    }

    /// Wakes the islands [`Sleep::wake`] named.
    pub(crate) fn flush(&mut self) {
        if self.waking.is_empty() {
            return;
        }
        self.all_still = false;
        self.waking.sort_unstable();
        self.waking.dedup();
        for i in 0..self.quiet.len() {
            if self.quiet[i] >= SLEEP_STEPS && self.waking.binary_search(&self.island[i]).is_ok() {
                self.quiet[i] = 0;
                self.still[i] = false;
                self.sleepers -= 1;
            }
        }
        self.waking.clear();
    }

    /// A `collide` hook takes the pair: both are awake and not quiet this step (the caller
    /// flushes before the solve).
    pub(crate) fn stir(&mut self, a: u32, b: u32) {
        if !self.active {
            return;
        }
        for slot in [a, b] {
            self.wake(slot as usize);
            self.stirred.push(slot);
        }
    }

    /// Sets the counts from a recorded state: (slot, quiet steps, island's slot), the critters
    /// where they are. Refuses a sleeper whose island's slot is not a sleeper of the same island.
    pub(crate) fn restore(
        &mut self,
        counts: &[(u32, u16, u32)],
        slots: &[Option<Critter<V>>],
    ) -> Result<(), String> {
        self.clear();
        self.fit(slots);
        for &(slot, q, island) in counts {
            let i = slot as usize;
            self.quiet[i] = q.min(SLEEP_STEPS);
            if q >= SLEEP_STEPS {
                if let Some(c) = &slots[i] {
                    self.rest[i] = (c.pos, c.radius);
                }
                self.island[i] = island;
                self.still[i] = true;
                self.sleepers += 1;
            }
        }
        for &(_, q, island) in counts {
            let named = island as usize;
            if q >= SLEEP_STEPS && !(self.asleep(named) && self.island[named] == island) {
                return Err(format!(
                    "the state's sleeping island {island} is not named by one of its sleepers"
                ));
            }
        }
        Ok(())
    }

    /// Sizes the arrays to the slots and marks the walls still.
    fn fit(&mut self, slots: &[Option<Critter<V>>]) {
        let n = slots.len();
        self.quiet.resize(n, 0);
        self.island.resize(n, 0);
        self.rest.resize(n, (V::zero(), 0.0));
        self.still.resize(n, false);
        for (i, c) in slots.iter().enumerate() {
            if !self.asleep(i) {
                self.still[i] = c.as_ref().is_some_and(|c| c.in_play() && c.is_wall());
            }
        }
    }

    /// At the start of a step, after the update hooks: wakes the sleepers something moved (and
    /// their islands), and fits the arrays to the slots. With `reuse`, a check that found
    /// everyone still stands while no one has touched the critters since.
    pub(crate) fn check(&mut self, critters: &mut CritterSet<V>, reuse: bool) {
        self.stirred.clear();
        let untouched = critters.untouched_since(self.still_mark);
        if reuse && self.all_still && untouched && self.waking.is_empty() {
            return;
        }
        self.look(critters.slot_slice());
        self.still_mark = match self.all_still {
            true => critters.mark_untouched(),
            false => 0,
        };
    }

    /// [`Sleep::check`]'s look at every critter.
    fn look(&mut self, slots: &[Option<Critter<V>>]) {
        self.all_still = false;
        if self.quiet.len() != slots.len() {
            self.fit(slots);
        }
        if self.sleepers == 0 {
            return;
        }
        let mut all_still = true;
        for (i, c) in slots.iter().enumerate() {
            if !self.asleep(i) {
                all_still &= c.as_ref().is_none_or(|c| c.in_play() && c.is_wall());
                continue;
            }
            let (pos, radius) = self.rest[i];
            let kept = c.as_ref().is_some_and(|c| {
                c.in_play() && !c.fixed && c.vel == V::zero() && c.pos == pos && c.radius == radius
            });
            if !kept {
                self.wake(i);
            }
        }
        self.all_still = all_still && self.waking.is_empty();
        self.flush();
    }

    /// Whether critters were removed since the last call.
    pub(crate) fn take_removed(&mut self) -> bool {
        std::mem::take(&mut self.removed)
    }

    /// True when the last [`Sleep::check`] found every critter a live wall or a sleeper and
    /// woke none: the step has nothing to move, test or solve.
    pub(crate) fn all_still(&self) -> bool {
        self.all_still
    }

    /// At the end of a `solve:n` step: wakes the islands touched by moving critters, then counts
    /// the islands' quiet steps and puts to sleep the islands that reach [`SLEEP_STEPS`].
    /// `contacts` are the step's touching pairs (walls included).
    pub(crate) fn after_solve(
        &mut self,
        slots: &mut [Option<Critter<V>>],
        contacts: &[(u32, u32)],
        speed: f64,
    ) {
        if self.quiet.len() != slots.len() {
            self.fit(slots);
        }
        let n = slots.len();
        let limit = speed * speed;
        self.quiet_now.clear();
        self.quiet_now.extend(slots.iter().map(|c| {
            c.as_ref()
                .is_some_and(|c| c.in_play() && c.vel.length_squared() < limit)
        }));
        for &slot in &self.stirred {
            self.quiet_now[slot as usize] = false;
        }
        // Critters that may sleep: live, free, not walls.
        let islander = |c: &Option<Critter<V>>| {
            c.as_ref()
                .is_some_and(|c| c.in_play() && !c.is_wall() && !c.fixed)
        };
        // A sleeper that died in a hook wakes its island; so does one touched by a critter that
        // moves (walls never move).
        for (i, c) in slots.iter().enumerate() {
            if self.asleep(i) && !islander(c) {
                self.wake(i);
            }
        }
        for &(a, b) in contacts {
            let (a, b) = (a as usize, b as usize);
            for (me, other) in [(a, b), (b, a)] {
                let moving = !self.asleep(me)
                    && !self.quiet_now[me]
                    && slots[me].as_ref().is_some_and(|c| !c.is_wall());
                if moving && self.asleep(other) {
                    self.wake(other);
                }
            }
        }
        self.flush();

        // Islands of awake critters: the lower slot is each union's root, so the islands do
        // not depend on the contacts' order.
        let awake = |s: &Self, i: usize| islander(&slots[i]) && !s.asleep(i);
        self.parent.clear();
        self.parent.extend(0..n as u32);
        for &(a, b) in contacts {
            let (a, b) = (a as usize, b as usize);
            if awake(self, a) && awake(self, b) {
                union(&mut self.parent, a, b);
            }
        }
        // Each root gathers its island's fewest quiet steps, or LOUD when one is not quiet.
        const LOUD: u16 = u16::MAX;
        let mut fewest = std::mem::take(&mut self.fewest);
        fewest.clear();
        fewest.resize(n, SLEEP_STEPS);
        for i in 0..n {
            if !awake(self, i) {
                continue;
            }
            let root = find(&mut self.parent, i);
            fewest[root] = if self.quiet_now[i] && fewest[root] != LOUD {
                fewest[root].min(self.quiet[i])
            } else {
                LOUD
            };
        }
        let mut falling = false;
        for (i, c) in slots.iter().enumerate() {
            if !islander(c) {
                self.quiet[i] = 0;
                continue;
            }
            if self.asleep(i) {
                continue;
            }
            let root = find(&mut self.parent, i);
            self.quiet[i] = match fewest[root] {
                LOUD => 0,
                f => (f + 1).min(SLEEP_STEPS),
            };
            falling |= self.quiet[i] >= SLEEP_STEPS;
        }
        self.fewest = fewest;
        if !falling {
            return;
        }
        // The islands that fall asleep join the sleeping islands they touch. A critter that has
        // reached SLEEP_STEPS and is not yet still falls asleep now (it is an islander, quiet
        // and awake, or its count would be 0).
        let mut joined = false;
        for &(a, b) in contacts {
            let (a, b) = (a as usize, b as usize);
            for (me, other) in [(a, b), (b, a)] {
                let falls = self.quiet[me] >= SLEEP_STEPS && !self.still[me];
                if falls && self.asleep_before(other) {
                    let named = self.island[other] as usize;
                    union(&mut self.parent, me, named);
                    joined = true;
                }
            }
        }
        for (i, slot) in slots.iter_mut().enumerate() {
            if self.quiet[i] < SLEEP_STEPS {
                continue;
            }
            if self.still[i] {
                // Asleep before this step.
                if joined {
                    self.island[i] = find(&mut self.parent, self.island[i] as usize) as u32;
                }
            } else if let Some(c) = slot.as_mut() {
                c.vel = V::zero();
                self.rest[i] = (c.pos, c.radius);
                self.island[i] = find(&mut self.parent, i) as u32;
                self.still[i] = true;
                self.sleepers += 1;
            }
        }
    }

    /// True for a critter asleep since before this step's island pass (walls are still too, but
    /// never asleep).
    fn asleep_before(&self, slot: usize) -> bool {
        self.asleep(slot) && self.still[slot]
    }

    /// After removals: the removed critters' islands wake, and so do the sleepers within reach
    /// of a removed critter; the removed critters' slots start again from 0.
    pub(crate) fn removed(
        &mut self,
        topo: &Topology<V>,
        gone: &[(usize, V, f64)],
        slots: &[Option<Critter<V>>],
    ) {
        if self.quiet.is_empty() {
            return;
        }
        self.removed |= !gone.is_empty();
        for &(slot, _, _) in gone {
            self.wake(slot);
        }
        if self.sleepers > 0 && gone.len() > MANY_REMOVALS {
            self.clear();
        } else if self.sleepers > 0 {
            for (i, c) in slots.iter().enumerate() {
                let Some(c) = c else { continue };
                if !self.asleep(i) {
                    continue;
                }
                let near = gone.iter().any(|&(_, pos, radius)| {
                    let reach = (1.0 + REACH) * (radius + c.radius);
                    topo.delta(pos, c.pos).length_squared() < reach * reach
                });
                if near {
                    self.wake(i);
                }
            }
        }
        self.flush();
        for &(slot, _, _) in gone {
            if let Some(q) = self.quiet.get_mut(slot) {
                *q = 0;
            }
            if let Some(still) = self.still.get_mut(slot) {
                *still = false; // a wall's slot may be reused by a disk
            }
        }
    }
}

/// Joins the sets of `a` and `b` under the lower of their roots.
fn union(parent: &mut [u32], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        parent[hi] = lo as u32;
    }
}

/// The root of `i`'s set, halving the path on the way.
fn find(parent: &mut [u32], mut i: usize) -> usize {
    while parent[i] as usize != i {
        let up = parent[parent[i] as usize];
        parent[i] = up;
        i = up as usize;
    }
    i
}
