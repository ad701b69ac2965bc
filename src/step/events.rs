//! What happened in a step: its collisions, deaths, spawns, damage and log lines, for summaries,
//! recordings and the next stages.

use crate::critter::CritterId;

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

/// Everything that happened in the last step, for summaries and recordings.
#[derive(Clone, Debug, Default)]
pub struct StepEvents<V> {
    /// Default collisions, in the order they were resolved.
    pub collisions: Vec<CollisionEvent<V>>,
    /// Critters that died (removed at the end of the step).
    pub deaths: Vec<CritterId>,
    /// Critters spawned.
    pub spawns: Vec<CritterId>,
    /// Damage taken: (critter, amount).
    pub damages: Vec<(CritterId, f64)>,
    /// Lines logged by hooks.
    pub log: Vec<String>,
}

impl<V> StepEvents<V> {
    pub(crate) fn clear(&mut self) {
        self.collisions.clear();
        self.deaths.clear();
        self.spawns.clear();
        self.damages.clear();
        self.log.clear();
    }
}
