//! What a kind's hooks see: the critters involved, the rest of the world read and write, and
//! queues for structural changes (deaths, spawns) that take effect after the step.

use super::events::{CollisionEvent, DeathCause};
use super::neighbours::Filter;
use super::pending::{OnOverlap, PendingSpawn, SpawnOrigin};
use super::state::State;
use crate::border::Topology;
use crate::critter::{Critter, CritterId, CritterSpec, Props};
use crate::default_response::{self, Hit};
use crate::kind::{KindId, KindSet};
use crate::rng::Rng;
use crate::vector::Vector;
use std::ops::{Deref, DerefMut};

/// The contact of a pair as a hook sees it (`collide`'s third argument, `touch_begin`'s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HookContact<V> {
    /// Unit normal from `me` towards `other`.
    pub normal: V,
    /// Contact point (world coordinates).
    pub point: V,
    /// Overlap, >= 0.
    pub depth: f64,
    /// Approach speed along the normal: > 0 while they approach.
    pub speed: f64,
    /// True on the first step of this touching spell.
    pub first: bool,
}

impl<V: Vector> HookContact<V> {
    /// The contact of `me` with `other` where they are now; when they do not touch (a hook moved
    /// one), the normal along the line of centres and depth 0.
    pub fn between(topo: &Topology<V>, me: &Critter<V>, other: &Critter<V>, first: bool) -> Self {
        let (normal, point, depth) = match default_response::contact_between(topo, me, other) {
            Some(c) => (c.normal, me.pos + c.point, c.depth),
            None => {
                let d = topo.delta(me.pos, other.pos);
                let len = d.length();
                let n = if len > 0.0 { d / len } else { V::unit_x() };
                (n, me.pos + d * 0.5, 0.0)
            }
        };
        HookContact {
            normal,
            point,
            depth,
            speed: (me.vel - other.vel).dot(normal),
            first,
        }
    }

    /// The same contact seen from the other critter.
    pub fn flipped(&self) -> Self {
        HookContact {
            normal: -self.normal,
            ..*self
        }
    }
}

/// Read-write access to the world from inside a hook: the step's state, through what its
/// methods allow.
pub struct Access<'a, V: Vector> {
    pub(crate) state: &'a mut State<V>,
}

impl<V: Vector> Access<'_, V> {
    /// The same access, borrowed for a shorter while.
    pub(crate) fn reborrow(&mut self) -> Access<'_, V> {
        Access {
            state: &mut *self.state,
        }
    }
    /// The critter `id`, if alive or dying this step.
    pub fn get(&self, id: CritterId) -> Option<&Critter<V>> {
        self.state.critters.get(id)
    }
    /// The critter `id`, mutably.
    pub fn get_mut(&mut self, id: CritterId) -> Option<&mut Critter<V>> {
        self.state.neighbours.moved(id);
        self.state.critters.get_mut(id)
    }
    /// Live critters other than walls whose centres lie within `r` of `centre` (through the
    /// border when it wraps), of `kind` or a kind extending it when given, leaving out
    /// `exclude`, in id order. Looks only at the grid cells the ball overlaps.
    pub fn nearby(
        &mut self,
        centre: V,
        r: f64,
        kind: Option<KindId>,
        exclude: Option<CritterId>,
    ) -> Vec<CritterId> {
        let (grid, at) = self.state.scope();
        grid.nearby(at, centre, r, Filter { kind, exclude })
    }
    /// The live critter other than walls nearest to `centre`, of `kind` (or a kind extending
    /// it) when given, leaving out `exclude`; ties go to the lower id.
    pub fn nearest(
        &mut self,
        centre: V,
        kind: Option<KindId>,
        exclude: Option<CritterId>,
    ) -> Option<CritterId> {
        let (grid, at) = self.state.scope();
        grid.nearest(at, centre, Filter { kind, exclude })
    }
    /// The kinds of the world.
    pub fn kinds(&self) -> &KindSet<V> {
        &self.state.kinds
    }
    /// The world box and border.
    pub fn topology(&self) -> &Topology<V> {
        &self.state.topo
    }
    /// Steps completed before this one.
    pub fn step(&self) -> u64 {
        self.state.step_count
    }
    /// Simulated time at the start of this step.
    pub fn time(&self) -> f64 {
        self.state.step_count as f64 * self.state.dt
    }
    /// Time step.
    pub fn dt(&self) -> f64 {
        self.state.dt
    }
    /// The acceleration every moving critter falls with.
    pub fn gravity(&self) -> V {
        self.state.gravity
    }
    /// The world's seeded generator.
    pub fn rng(&mut self) -> &mut Rng {
        &mut self.state.rng
    }
    /// The scripts' shared state (`world().vars`).
    pub fn vars(&self) -> &Props {
        &self.state.vars
    }
    /// The scripts' shared state, to change.
    pub fn vars_mut(&mut self) -> &mut Props {
        &mut self.state.vars
    }
    /// Seconds since critter `id` was spawned (see [`crate::world::World::age`]).
    pub fn age(&self, id: CritterId) -> Option<f64> {
        self.state.age(id)
    }
    /// True when critter `id` is of kind `kind` or a kind that extends it.
    pub fn is_kind(&self, id: CritterId, kind: KindId) -> bool {
        self.state
            .critters
            .get(id)
            .is_some_and(|c| self.state.kinds.is_kind(c.kind(), kind))
    }
    /// Live critters of `kind` (or kinds extending it), in id order. O(N).
    pub fn critters_of(&self, kind: KindId) -> Vec<CritterId> {
        self.state
            .critters
            .iter()
            .filter(|c| c.in_play() && self.state.kinds.is_kind(c.kind(), kind))
            .map(|c| c.id)
            .collect()
    }
    /// Kills critter `id`: it takes no further collisions and is removed after the step.
    pub fn die(&mut self, id: CritterId) {
        let cause = DeathCause::Die(self.state.hook);
        self.die_because(id, cause);
    }
    /// Kills critter `id` for `cause` (kept for the step's events).
    fn die_because(&mut self, id: CritterId, cause: DeathCause) {
        if let Some(c) = self.state.critters.get_mut(id) {
            if c.in_play() {
                c.alive = false;
                self.state.pending.deaths.push(id);
                self.state.pending.death_causes.push(cause);
            }
        }
    }
    /// Pop's `damage`: lowers health by `amount`; at or below zero the critter dies. The damage
    /// is an event naming the hook running (its source), and the critter's `on_damage` runs for
    /// it later in the step (`step::damage`).
    pub fn damage(&mut self, id: CritterId, amount: f64) {
        let by = self.state.hook;
        let dead = match self.state.critters.get_mut(id) {
            Some(c) if c.in_play() => {
                c.traits_mut().health -= amount;
                let (kind, dead) = (c.kind(), c.health() <= 0.0);
                self.state.note_damage(id, kind, amount, by);
                dead
            }
            _ => false,
        };
        if dead {
            self.die_because(id, DeathCause::Damage(by));
        }
    }
    /// Queues a spawn for the end of the step (checked then, like any spawn).
    pub fn spawn(&mut self, spec: CritterSpec<V>) {
        self.spawn_placed(spec, OnOverlap::Error, None);
    }
    /// Queues a spawn placed under `on_overlap`, remembering where a script asked for it.
    pub(crate) fn spawn_placed(
        &mut self,
        spec: CritterSpec<V>,
        on_overlap: OnOverlap,
        origin: Option<Box<SpawnOrigin>>,
    ) {
        let by = self.state.hook;
        self.state.pending.spawns.push(PendingSpawn {
            spec,
            on_overlap,
            origin,
            by,
        });
    }
    /// Adds a line to the step's log.
    pub fn log(&mut self, line: impl Into<String>) {
        self.state.events.log.push(line.into());
    }
    /// `b - a`, through the border when it wraps.
    pub fn delta(&self, a: V, b: V) -> V {
        self.state.topo.delta(a, b)
    }
    /// Distance between the centres of `a` and `b` (through the border when it wraps).
    pub fn distance_pair(&self, a: CritterId, b: CritterId) -> Option<f64> {
        let (a, b) = (self.state.critters.get(a)?, self.state.critters.get(b)?);
        Some(self.state.topo.delta(a.pos, b.pos).length())
    }
    /// True when `a` and `b` touch now.
    pub fn touches_pair(&self, a: CritterId, b: CritterId) -> bool {
        match (self.state.critters.get(a), self.state.critters.get(b)) {
            (Some(a), Some(b)) => default_response::touches(&self.state.topo, a, b),
            _ => false,
        }
    }
    /// Pop's `contains`: `inner` lies wholly inside `outer` (disks only).
    pub fn contains_pair(&self, outer: CritterId, inner: CritterId) -> bool {
        match (
            self.state.critters.get(outer),
            self.state.critters.get(inner),
        ) {
            (Some(o), Some(i)) => default_response::contains(&self.state.topo, o, i),
            _ => false,
        }
    }
    /// The engine's physical response between `caller` and `arg` (Pop's `cCritter::collide`),
    /// recorded as a collision event. `None` when they don't touch (or either is gone).
    pub fn collide_default_pair(&mut self, caller: CritterId, arg: CritterId) -> Option<Hit<V>> {
        if caller == arg {
            return None;
        }
        let (a, b) = (
            self.state.critters.slot_of(caller)?,
            self.state.critters.slot_of(arg)?,
        );
        let state = &mut *self.state;
        state.neighbours.moved(caller);
        state.neighbours.moved(arg);
        let (me, other) = state.critters.pair_mut_moving(a, b);
        let hit = default_response::collide_default(&state.topo, me, other)?;
        state.events.collisions.push(CollisionEvent {
            caller,
            arg,
            point: hit.point,
            normal: hit.normal,
            impulse: hit.impulse,
        });
        Some(hit)
    }
}

/// The context of a `collide` call: `me` is the caller, `other` the arg.
pub struct CollideCtx<'a, V: Vector> {
    pub(crate) access: Access<'a, V>,
    pub(crate) me: u32,
    pub(crate) other: u32,
    /// The call is the first of this pair's touching spell (false while spells are not kept).
    pub(crate) first: bool,
}

impl<'a, V: Vector> Deref for CollideCtx<'a, V> {
    type Target = Access<'a, V>;
    fn deref(&self) -> &Access<'a, V> {
        &self.access
    }
}

impl<V: Vector> DerefMut for CollideCtx<'_, V> {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.access
    }
}

impl<V: Vector> CollideCtx<'_, V> {
    /// The caller.
    pub fn me(&self) -> &Critter<V> {
        self.access
            .state
            .critters
            .slot(self.me)
            .expect("caller is live during its collide")
    }
    /// The arg.
    pub fn other(&self) -> &Critter<V> {
        self.access
            .state
            .critters
            .slot(self.other)
            .expect("arg is live during the collide")
    }
    /// Both, mutably: (me, other).
    pub fn both_mut(&mut self) -> (&mut Critter<V>, &mut Critter<V>) {
        if self.access.state.neighbours.is_tracking() {
            let (me, other) = (self.me().id, self.other().id);
            self.access.state.neighbours.moved(me);
            self.access.state.neighbours.moved(other);
        }
        self.access.state.critters.pair_mut(self.me, self.other)
    }
    /// The caller, mutably.
    pub fn me_mut(&mut self) -> &mut Critter<V> {
        self.both_mut().0
    }
    /// The arg, mutably.
    pub fn other_mut(&mut self) -> &mut Critter<V> {
        self.both_mut().1
    }
    /// Distance between the centres (through the border when it wraps).
    pub fn distance(&self) -> f64 {
        self.topology()
            .delta(self.me().pos, self.other().pos)
            .length()
    }
    /// The contact of me with the other, where they are now.
    pub fn contact(&self) -> HookContact<V> {
        HookContact::between(self.topology(), self.me(), self.other(), self.first)
    }
    /// True when the two touch now.
    pub fn touches(&self) -> bool {
        self.access.touches_pair(self.me().id, self.other().id)
    }
    /// Pop's `contains`: the other lies wholly inside me (disks only).
    pub fn contains(&self) -> bool {
        self.access.contains_pair(self.me().id, self.other().id)
    }
    /// The engine's physical response (Pop's `cCritter::collide`). Returns true if they touched.
    pub fn collide_default(&mut self) -> bool {
        self.collide_default_hit().is_some()
    }
    /// As [`CollideCtx::collide_default`], returning what happened.
    pub fn collide_default_hit(&mut self) -> Option<Hit<V>> {
        let (me, other) = (self.me().id, self.other().id);
        self.access.collide_default_pair(me, other)
    }
    /// Kills the caller.
    pub fn die_me(&mut self) {
        let id = self.me().id;
        self.die(id);
    }
    /// Kills the arg.
    pub fn die_other(&mut self) {
        let id = self.other().id;
        self.die(id);
    }
}

/// The context of an `update` or `init` call.
pub struct UpdateCtx<'a, V: Vector> {
    pub(crate) access: Access<'a, V>,
    pub(crate) me: u32,
}

impl<'a, V: Vector> Deref for UpdateCtx<'a, V> {
    type Target = Access<'a, V>;
    fn deref(&self) -> &Access<'a, V> {
        &self.access
    }
}

impl<V: Vector> DerefMut for UpdateCtx<'_, V> {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.access
    }
}

impl<V: Vector> UpdateCtx<'_, V> {
    /// The critter being updated.
    pub fn me(&self) -> &Critter<V> {
        self.access
            .state
            .critters
            .slot(self.me)
            .expect("updated critter is live")
    }
    /// The critter being updated, mutably.
    pub fn me_mut(&mut self) -> &mut Critter<V> {
        if self.access.state.neighbours.is_tracking() {
            let id = self.me().id;
            self.access.state.neighbours.moved(id);
        }
        self.access
            .state
            .critters
            .slot_mut(self.me)
            .expect("updated critter is live")
    }
    /// Kills the critter being updated.
    pub fn die_me(&mut self) {
        let id = self.me().id;
        self.die(id);
    }
}
