//! What a script may do to the world it runs in: the [`Env`] trait, and its implementations for
//! the whole [`World`] (scene setup, `on_step`) and for a hook's [`Access`] (inside a step). The
//! read-only view `collides_with` gets is in [`super::kind_file`].

use crate::border::Topology;
use crate::critter::{Critter, CritterId, CritterSpec, Props};
use crate::error::Error;
use crate::kind::{KindId, KindSet};
use crate::rng::Rng;
use crate::step::access::Access;
use crate::step::pending::OnOverlap;
use crate::step::pending::SpawnOrigin;
use crate::step::spawn::Placed;
use crate::vector::Vector;
use crate::world::World;

/// What a script may do to the world it runs in.
pub(crate) trait Env<V: Vector> {
    fn critter(&self, id: CritterId) -> Option<&Critter<V>>;
    fn critter_mut(&mut self, id: CritterId) -> Option<&mut Critter<V>>;
    fn kinds(&self) -> &KindSet<V>;
    fn topology(&self) -> &Topology<V>;
    fn step_count(&self) -> u64;
    fn time(&self) -> f64;
    fn dt(&self) -> f64;
    fn rng(&mut self) -> &mut Rng;
    fn die(&mut self, id: CritterId);
    fn damage(&mut self, id: CritterId, amount: f64);
    /// Spawns now (`Some(id)`) between steps, or queues for the end of the step (`None`).
    fn spawn(&mut self, spec: CritterSpec<V>) -> Result<Option<CritterId>, Error>;
    /// Spawns placed under `on_overlap`: now between steps (`Some`), or queued for the end of
    /// the step with where a script asked for it (`None`).
    fn spawn_placed(
        &mut self,
        spec: CritterSpec<V>,
        _on_overlap: OnOverlap,
        _origin: Option<Box<SpawnOrigin>>,
    ) -> Result<Option<Placed>, Error> {
        // Only the world and a hook's access place spawns; elsewhere `spawn` says why not.
        Ok(self.spawn(spec)?.map(Placed::Added))
    }
    fn log(&mut self, line: String);
    fn critters_of(&self, kind: KindId) -> Vec<CritterId>;
    fn touches(&self, a: CritterId, b: CritterId) -> bool {
        match (self.critter(a), self.critter(b)) {
            (Some(x), Some(y)) => crate::default_response::touches(self.topology(), x, y),
            _ => false,
        }
    }
    fn contains(&self, outer: CritterId, inner: CritterId) -> bool {
        match (self.critter(outer), self.critter(inner)) {
            (Some(o), Some(i)) => crate::default_response::contains(self.topology(), o, i),
            _ => false,
        }
    }
    fn distance(&self, a: CritterId, b: CritterId) -> Option<f64> {
        let (x, y) = (self.critter(a)?, self.critter(b)?);
        Some(self.topology().delta(x.pos, y.pos).length())
    }
    /// The default response: the impulse it gave when they touched; `Err` outside a step.
    fn collide_default(&mut self, caller: CritterId, arg: CritterId)
        -> Result<Option<f64>, String>;
    /// Seconds since critter `id` was spawned; `None` where it cannot be told.
    fn age(&self, id: CritterId) -> Option<f64>;
    /// The world itself, between steps (scene setup and `on_step`).
    fn world(&mut self) -> Option<&mut World<V>>;
    /// The shared state `world().vars`; `None` where it is out of reach (`collides_with`).
    fn vars(&mut self) -> Option<&mut Props> {
        None
    }
    /// Neighbour queries (see `world::neighbours`); `Err` where the world is read-only.
    fn nearby(
        &mut self,
        _centre: V,
        _r: f64,
        _kind: Option<KindId>,
        _exclude: Option<CritterId>,
    ) -> Result<Vec<CritterId>, String> {
        Err(NO_QUERIES.into())
    }
    fn nearest(
        &mut self,
        _centre: V,
        _kind: Option<KindId>,
        _exclude: Option<CritterId>,
    ) -> Result<Option<CritterId>, String> {
        Err(NO_QUERIES.into())
    }
}

/// Why `collides_with` cannot ask for neighbours.
const NO_QUERIES: &str =
    "nearby and nearest work in update, init and collide hooks and in scenes, not in collides_with";

impl<V: Vector> Env<V> for World<V> {
    fn critter(&self, id: CritterId) -> Option<&Critter<V>> {
        self.get(id)
    }
    fn critter_mut(&mut self, id: CritterId) -> Option<&mut Critter<V>> {
        self.get_mut(id)
    }
    fn kinds(&self) -> &KindSet<V> {
        World::kinds(self)
    }
    fn topology(&self) -> &Topology<V> {
        World::topology(self)
    }
    fn step_count(&self) -> u64 {
        World::step_count(self)
    }
    fn time(&self) -> f64 {
        World::time(self)
    }
    fn dt(&self) -> f64 {
        World::dt(self)
    }
    fn rng(&mut self) -> &mut Rng {
        World::rng(self)
    }
    fn die(&mut self, id: CritterId) {
        // Between steps a death takes effect at once.
        let _ = self.remove(id);
    }
    fn damage(&mut self, id: CritterId, amount: f64) {
        let dead = match self.get_mut(id) {
            Some(c) => {
                c.traits_mut().health -= amount;
                c.health() <= 0.0
            }
            None => false,
        };
        if dead {
            let _ = self.remove(id);
        }
    }
    fn spawn(&mut self, spec: CritterSpec<V>) -> Result<Option<CritterId>, Error> {
        World::spawn(self, spec).map(Some)
    }
    fn spawn_placed(
        &mut self,
        spec: CritterSpec<V>,
        on_overlap: OnOverlap,
        _origin: Option<Box<SpawnOrigin>>,
    ) -> Result<Option<Placed>, Error> {
        World::spawn_placed(self, spec, on_overlap).map(Some)
    }
    fn log(&mut self, line: String) {
        self.log_line(line);
    }
    fn critters_of(&self, kind: KindId) -> Vec<CritterId> {
        self.critters()
            .iter()
            .filter(|c| c.is_alive() && World::kinds(self).is_kind(c.kind(), kind))
            .map(|c| c.id())
            .collect()
    }
    fn collide_default(
        &mut self,
        _caller: CritterId,
        _arg: CritterId,
    ) -> Result<Option<f64>, String> {
        Err("collide_default can only be called inside a collide hook".into())
    }
    fn age(&self, id: CritterId) -> Option<f64> {
        World::age(self, id)
    }
    fn world(&mut self) -> Option<&mut World<V>> {
        Some(self)
    }
    fn vars(&mut self) -> Option<&mut Props> {
        Some(self.vars_mut())
    }
    fn nearby(
        &mut self,
        centre: V,
        r: f64,
        kind: Option<KindId>,
        exclude: Option<CritterId>,
    ) -> Result<Vec<CritterId>, String> {
        Ok(World::nearby(self, centre, r, kind, exclude))
    }
    fn nearest(
        &mut self,
        centre: V,
        kind: Option<KindId>,
        exclude: Option<CritterId>,
    ) -> Result<Option<CritterId>, String> {
        Ok(World::nearest(self, centre, kind, exclude))
    }
}

impl<V: Vector> Env<V> for Access<'_, V> {
    fn critter(&self, id: CritterId) -> Option<&Critter<V>> {
        self.get(id)
    }
    fn critter_mut(&mut self, id: CritterId) -> Option<&mut Critter<V>> {
        self.get_mut(id)
    }
    fn kinds(&self) -> &KindSet<V> {
        Access::kinds(self)
    }
    fn topology(&self) -> &Topology<V> {
        Access::topology(self)
    }
    fn step_count(&self) -> u64 {
        self.step()
    }
    fn time(&self) -> f64 {
        Access::time(self)
    }
    fn dt(&self) -> f64 {
        Access::dt(self)
    }
    fn rng(&mut self) -> &mut Rng {
        Access::rng(self)
    }
    fn die(&mut self, id: CritterId) {
        Access::die(self, id)
    }
    fn damage(&mut self, id: CritterId, amount: f64) {
        Access::damage(self, id, amount)
    }
    fn spawn(&mut self, spec: CritterSpec<V>) -> Result<Option<CritterId>, Error> {
        Access::spawn(self, spec);
        Ok(None)
    }
    fn spawn_placed(
        &mut self,
        spec: CritterSpec<V>,
        on_overlap: OnOverlap,
        origin: Option<Box<SpawnOrigin>>,
    ) -> Result<Option<Placed>, Error> {
        Access::spawn_placed(self, spec, on_overlap, origin);
        Ok(None)
    }
    fn log(&mut self, line: String) {
        Access::log(self, line)
    }
    fn critters_of(&self, kind: KindId) -> Vec<CritterId> {
        Access::critters_of(self, kind)
    }
    fn collide_default(
        &mut self,
        caller: CritterId,
        arg: CritterId,
    ) -> Result<Option<f64>, String> {
        Ok(self
            .collide_default_pair(caller, arg)
            .map(|hit| hit.impulse))
    }
    fn age(&self, id: CritterId) -> Option<f64> {
        Access::age(self, id)
    }
    fn world(&mut self) -> Option<&mut World<V>> {
        None
    }
    fn vars(&mut self) -> Option<&mut Props> {
        Some(self.vars_mut())
    }
    fn nearby(
        &mut self,
        centre: V,
        r: f64,
        kind: Option<KindId>,
        exclude: Option<CritterId>,
    ) -> Result<Vec<CritterId>, String> {
        Ok(Access::nearby(self, centre, r, kind, exclude))
    }
    fn nearest(
        &mut self,
        centre: V,
        kind: Option<KindId>,
        exclude: Option<CritterId>,
    ) -> Result<Option<CritterId>, String> {
        Ok(Access::nearest(self, centre, kind, exclude))
    }
}
