//! What every stage and every collision method reads and writes: the critters, their kinds and
//! rules, the world box, the generator, and the step's events and queued changes. Each stage
//! and method is handed this, and the parts of its own it needs, explicitly.

use super::access::{Access, CollideCtx, UpdateCtx};
use super::births::Births;
use super::events::{CollisionEvent, DamageInfo, HookAt, StepEvents};
use super::pending::{Pending, PendingDamage};
use crate::border::Topology;
use crate::critter::{CritterId, Props};
use crate::critter_set::CritterSet;
use crate::error::Error;
use crate::kind::{KindId, KindSet};
use crate::rng::Rng;
use crate::rules::{roles_of, roles_slots, RuleCache};
use crate::step::neighbours::{Neighbours, Scope};
use crate::vector::Vector;

/// The state a step works on (see the module docs).
pub(crate) struct State<V: Vector> {
    /// The world box and what its edge does.
    pub(crate) topo: Topology<V>,
    /// Uniform acceleration on every free critter.
    pub(crate) gravity: V,
    /// The time step.
    pub(crate) dt: f64,
    pub(crate) critters: CritterSet<V>,
    pub(crate) kinds: KindSet<V>,
    /// Pop's roles per pair of rule classes, cached.
    pub(crate) rules: RuleCache,
    /// The walls, in the order they were added (the order their pairs are tested in).
    pub(crate) walls: Vec<CritterId>,
    pub(crate) rng: Rng,
    /// Steps completed.
    pub(crate) step_count: u64,
    /// Deaths and spawns the hooks asked for, taking effect at the step's end.
    pub(crate) pending: Pending<V>,
    /// What happened in the current (or last) step.
    pub(crate) events: StepEvents<V>,
    /// The scripts' shared state (`world().vars`), hashed when not empty.
    pub(crate) vars: Props,
    /// The grid neighbour queries use, built on the first one (see `neighbours`).
    pub(crate) neighbours: Neighbours<V>,
    /// The step each critter was spawned at (for `age`).
    pub(crate) births: Births,
    /// The touching spells, kept when some kind tracks them.
    pub(crate) touch: super::spells::Spells<V>,
    /// The kind's hook running now, if any: what a death, damage or spawn it asks for is
    /// recorded as caused by.
    pub(crate) hook: Option<HookAt>,
}

impl<V: Vector> State<V> {
    /// What a hook may read and write.
    pub(crate) fn access(&mut self) -> Access<'_, V> {
        Access { state: self }
    }

    /// Seconds of simulated time since critter `id` was spawned: the steps begun since then
    /// times dt (0 in its `init`).
    pub(crate) fn age(&self, id: CritterId) -> Option<f64> {
        self.critters.get(id)?;
        Some(self.births.age(id, self.step_count, self.dt))
    }

    /// Runs critter `id`'s `init` hook.
    pub(crate) fn run_init(&mut self, id: CritterId) -> Result<(), Error> {
        let step = self.step_count;
        let kind = self
            .critters
            .get(id)
            .map(|c| c.kind())
            .ok_or(Error::NoSuchCritter(id))?;
        let hooks = self.kinds.get(kind).hooks.clone();
        let me = self.critters.slot_of(id).ok_or(Error::NoSuchCritter(id))?;
        let outer = self.enter_hook(id, "init");
        let mut ctx = UpdateCtx {
            access: self.access(),
            me,
        };
        let done = hooks.init(&mut ctx);
        self.hook = outer;
        done.map_err(|e| hook_error(e, &self.kinds, kind, id, step))
    }

    /// Notes that the hook `hook` of critter `critter` runs from now on; returns the one that
    /// ran before, for the caller to put back when the hook returns.
    pub(crate) fn enter_hook(&mut self, critter: CritterId, hook: &'static str) -> Option<HookAt> {
        self.hook.replace(HookAt { critter, hook })
    }

    /// Notes a damage of `amount` to `id` (of kind `kind`) done by the hook `by`: the step's
    /// event, and its `on_damage` to run when some kind has that hook.
    pub(crate) fn note_damage(
        &mut self,
        id: CritterId,
        kind: KindId,
        amount: f64,
        by: Option<HookAt>,
    ) {
        self.events.damages.push((id, amount));
        self.events
            .damage_info
            .push(DamageInfo { kind, source: by });
        if self.kinds.has_on_damage() {
            self.pending.damages.push(PendingDamage {
                id,
                amount,
                source: by.map(|h| h.critter),
            });
        }
    }

    /// Runs the `on_damage` hook of the critter `d` damaged, if it is still there and its kind
    /// has one.
    pub(crate) fn run_on_damage(&mut self, d: PendingDamage) -> Result<(), Error> {
        let step = self.step_count;
        let Some(me) = self.critters.slot_of(d.id) else {
            return Ok(());
        };
        let Some(kind) = self.critters.slot(me).map(|c| c.kind()) else {
            return Ok(());
        };
        if !self.kinds.get(kind).has_on_damage {
            return Ok(());
        }
        let hooks = self.kinds.get(kind).hooks.clone();
        let outer = self.enter_hook(d.id, "on_damage");
        let mut ctx = UpdateCtx {
            access: self.access(),
            me,
        };
        let done = hooks.on_damage(&mut ctx, d.amount, d.source);
        self.hook = outer;
        done.map_err(|e| hook_error(e, &self.kinds, kind, d.id, step))
    }

    /// Runs critter `id`'s `on_death` hook, if its kind has one.
    pub(crate) fn run_on_death(&mut self, id: CritterId) -> Result<(), Error> {
        let step = self.step_count;
        let Some(me) = self.critters.slot_of(id) else {
            return Ok(());
        };
        let Some(kind) = self.critters.slot(me).map(|c| c.kind()) else {
            return Ok(());
        };
        if !self.kinds.get(kind).has_on_death {
            return Ok(());
        }
        let hooks = self.kinds.get(kind).hooks.clone();
        let outer = self.enter_hook(id, "on_death");
        let mut ctx = UpdateCtx {
            access: self.access(),
            me,
        };
        let done = hooks.on_death(&mut ctx);
        self.hook = outer;
        done.map_err(|e| hook_error(e, &self.kinds, kind, id, step))
    }

    /// In a periodic world, maps every live critter back into the box.
    pub(crate) fn wrap_positions(&mut self) {
        if self.topo.wraps() {
            let topo = self.topo;
            for c in self
                .critters
                .iter_mut_moving()
                .filter(|c| c.in_play() && !c.is_wall())
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
        if !a.in_play()
            || !b.in_play()
            || crate::default_response::contact_between(&self.topo, a, b).is_none()
        {
            return Ok(None);
        }
        if !ask {
            return Ok(Some((first, second)));
        }
        let rule =
            roles_of(&self.kinds, &self.topo, a, b).map_err(|e| at_step(e, self.step_count))?;
        Ok(roles_slots(rule, (first, a), (second, b)))
    }

    /// Calls the caller's `collide` on a touching pair, if both are still alive.
    pub(crate) fn collide_pair(&mut self, caller: u32, arg: u32) -> Result<bool, Error> {
        let (Some(c), Some(a)) = (self.critters.slot(caller), self.critters.slot(arg)) else {
            return Ok(false);
        };
        if !c.in_play() || !a.in_play() {
            return Ok(false);
        }
        let (kind, id, step) = (c.kind(), c.id, self.step_count);
        let arg_id = a.id;
        let hooks = self.kinds.get(kind).hooks.clone();
        let events_before = self.events.collisions.len();
        // The engine moves critters between collide calls: each call starts with no grid.
        self.neighbours.invalidate();
        let first = self.kinds.tracks_touch() && self.note_touch(caller, arg);
        let outer = self.enter_hook(id, "collide");
        let mut ctx = CollideCtx {
            access: self.access(),
            me: caller,
            other: arg,
            first,
        };
        let handled = hooks.collide(&mut ctx);
        self.hook = outer;
        let handled = handled.map_err(|e| hook_error(e, &self.kinds, kind, id, step))?;
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
        let (normal, point) = match crate::default_response::contact_between(&self.topo, c, a) {
            Some(contact) => (contact.normal, c.pos + contact.point),
            None => {
                let len = d.length();
                let n = if len > 0.0 { d / len } else { V::unit_x() };
                (n, c.pos + d * 0.5)
            }
        };
        self.events.collisions.push(CollisionEvent {
            caller,
            arg,
            point,
            normal,
            impulse: 0.0,
        });
    }
}

impl<V: Vector> State<V> {
    /// The neighbour grid, and the critters it files.
    pub(crate) fn scope(&mut self) -> (&mut Neighbours<V>, Scope<'_, V>) {
        let at = Scope {
            critters: &self.critters,
            kinds: &self.kinds,
            topo: &self.topo,
        };
        (&mut self.neighbours, at)
    }
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

/// A hook's error, naming the kind, critter and step it came from.
pub(crate) fn hook_error<V: Vector>(
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
