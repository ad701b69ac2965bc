//! What happened in a step: its collisions, deaths, spawns, damage and log lines, for summaries,
//! recordings and the next stages, and who caused them (the hook running, if any).

use crate::critter::CritterId;
use crate::ids::KindId;

/// A collision that happened in a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CollisionEvent<V> {
    /// The critter whose `collide` ran.
    pub caller: CritterId,
    /// The other one.
    pub arg: CritterId,
    /// Contact point.
    pub point: V,
    /// Unit normal from caller to arg.
    pub normal: V,
    /// Impulse given to the arg along the normal (0 when they were already separating).
    pub impulse: f64,
}

/// A kind's hook that the engine was running: for which critter, and which hook.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HookAt {
    /// The critter the hook ran for (its `me`).
    pub critter: CritterId,
    /// The hook's name (`update`, `collide`, `on_death`, ...).
    pub hook: &'static str,
}

/// Why a critter died.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeathCause {
    /// `die()`, in the hook named (`None`: outside any hook).
    Die(Option<HookAt>),
    /// Its health fell to 0 or below after damage from the hook named (`None`: damage from the
    /// scene or a test between steps).
    Damage(Option<HookAt>),
    /// Removed by the scene or a test between steps (`c.die()`, `World::remove`).
    Removed,
}

/// A death: the critter's kind and why it died (one per [`StepEvents::deaths`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeathInfo {
    /// The kind of the critter that died.
    pub kind: KindId,
    /// Why.
    pub cause: DeathCause,
}

/// A damage: the damaged critter's kind and the hook that did it (one per
/// [`StepEvents::damages`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DamageInfo {
    /// The kind of the critter damaged.
    pub kind: KindId,
    /// The hook that did the damage (`None`: the scene or a test, between steps).
    pub source: Option<HookAt>,
}

/// Everything that happened in the last step, for summaries and recordings.
#[derive(Clone, Debug, Default)]
pub struct StepEvents<V> {
    /// Default collisions, in the order they were resolved.
    pub collisions: Vec<CollisionEvent<V>>,
    /// Critters that died (removed at the end of the step, or by the scene between steps).
    pub deaths: Vec<CritterId>,
    /// Each death's kind and cause, one per entry of `deaths`.
    pub death_info: Vec<DeathInfo>,
    /// Critters spawned (by hooks, and by the scene between steps after step 0).
    pub spawns: Vec<CritterId>,
    /// The hook that spawned each of `spawns` (`None`: the scene).
    pub spawn_by: Vec<Option<HookAt>>,
    /// Damage taken: (critter, amount).
    pub damages: Vec<(CritterId, f64)>,
    /// Each damage's kind and source, one per entry of `damages`.
    pub damage_info: Vec<DamageInfo>,
    /// Lines logged by hooks.
    pub log: Vec<String>,
}

impl<V> StepEvents<V> {
    pub(crate) fn clear(&mut self) {
        self.collisions.clear();
        self.deaths.clear();
        self.death_info.clear();
        self.spawns.clear();
        self.spawn_by.clear();
        self.damages.clear();
        self.damage_info.clear();
        self.log.clear();
    }

    /// Notes the death of `id`, of kind `kind`, for `cause`.
    pub(crate) fn died(&mut self, id: CritterId, kind: KindId, cause: DeathCause) {
        self.deaths.push(id);
        self.death_info.push(DeathInfo { kind, cause });
    }

    /// Notes the spawn of `id` by the hook `by` (`None`: the scene).
    pub(crate) fn spawned(&mut self, id: CritterId, by: Option<HookAt>) {
        self.spawns.push(id);
        self.spawn_by.push(by);
    }
}
