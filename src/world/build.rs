//! Building a world: kinds, walls, spawns and removals, each checked (in [`crate::step::spawn`]),
//! so a bad spawn is an error naming the critter and the field, and nothing is added then.

use super::World;
use crate::critter::{Critter, CritterId, CritterSpec};
use crate::error::Error;
use crate::kind::{KindDefaults, KindHooks, KindId};
use crate::step::damage;
use crate::step::events::DeathCause;
use crate::step::lifecycle;
use crate::step::pending::OnOverlap;
use crate::step::spawn::Placed;
use crate::vector::Vector;
use crate::wall::WallBox;
use std::rc::Rc;

impl<V: Vector> World<V> {
    /// Spawns a critter now, placed under `on_overlap` (a scene's or a test's spawn). After
    /// step 0 the spawn is in the events of the last step, made by the scene; the scene as
    /// built is the state at step 0.
    pub(crate) fn spawn_placed(
        &mut self,
        spec: CritterSpec<V>,
        on_overlap: OnOverlap,
    ) -> Result<Placed, Error> {
        let placed = self.state.spawn_placed(spec, on_overlap)?;
        if let (Placed::Added(id), true) = (&placed, self.state.step_count > 0) {
            self.state.events.spawned(*id, None);
        }
        Ok(placed)
    }

    /// Registers a kind (see [`crate::KindSet::register`]).
    pub fn register_kind(
        &mut self,
        name: &str,
        parent: Option<&str>,
        defaults: KindDefaults,
        hooks: Rc<dyn KindHooks<V>>,
    ) -> Result<KindId, Error> {
        self.state.kinds.register(name, parent, defaults, hooks)
    }

    /// Replaces kind `id`'s parent, defaults and hooks: its file was edited while the run goes
    /// on. Its critters keep their state; critters spawned from now on get the new defaults.
    /// What the world kept that the old hooks decided (the pairs' roles, the broad phase's
    /// list, the method's kept state) is dropped, so the next step asks the new hooks.
    pub fn replace_kind(
        &mut self,
        id: KindId,
        parent: Option<&str>,
        defaults: KindDefaults,
        hooks: Rc<dyn KindHooks<V>>,
    ) -> Result<(), Error> {
        self.state.kinds.replace(id, parent, defaults, hooks)?;
        self.state.rules.forget_roles(&self.state.kinds);
        self.pairs.broad.forget_list();
        self.methods.forget();
        Ok(())
    }

    /// Adds a wall (always fixed, priority CP_WALL, kind `wall`).
    pub fn add_wall(&mut self, wall: WallBox<V>) -> Result<CritterId, Error> {
        self.state.add_wall(wall)
    }

    /// Makes room for `additional` more critters, exactly (for a scene that knows how many it
    /// will spawn: the critters' storage then does not grow by doubling). An error when there
    /// is not memory for them.
    pub fn reserve(&mut self, additional: usize) -> Result<(), Error> {
        let per_critter = std::mem::size_of::<Option<Critter<V>>>() + std::mem::size_of::<u32>();
        self.state
            .critters
            .reserve(additional)
            .map_err(|_| Error::InvalidWorld {
                field: "critters",
                value: additional.to_string(),
                reason: format!(
                    "there is not memory for that many (about {:.3e} bytes for the critters alone); ask for fewer",
                    additional as f64 * per_critter as f64
                ),
            })
    }

    /// Spawns a critter now. Errors name the critter and the bad field; nothing is added then.
    pub fn spawn(&mut self, spec: CritterSpec<V>) -> Result<CritterId, Error> {
        self.state.spawn(spec)
    }

    /// Adds a line to the current step's log (scene scripts between steps).
    pub fn log_line(&mut self, line: String) {
        self.state.events.log.push(line);
    }

    /// Removes critter `id` at once (outside a step). Returns it, or an error if it is not there.
    /// The critter's spells end and its `on_death` runs first, when some kind has those hooks;
    /// what they queue (spawns, further deaths) takes effect before this returns. The death is
    /// in the events of the last step, as removed by the scene.
    pub fn remove(&mut self, id: CritterId) -> Result<Critter<V>, Error> {
        self.remove_because(id, DeathCause::Removed)
    }

    /// [`World::remove`], the death kept in the events for `cause`.
    pub(crate) fn remove_because(
        &mut self,
        id: CritterId,
        cause: DeathCause,
    ) -> Result<Critter<V>, Error> {
        let hooked = self.state.kinds.tracks_touch() || self.state.kinds.has_on_death();
        let mut was_alive = true;
        if hooked {
            was_alive = match self.state.critters.get_mut(id) {
                Some(c) => std::mem::replace(&mut c.alive, false),
                None => return Err(Error::NoSuchCritter(id)),
            };
            if was_alive {
                lifecycle::before_removal(&mut self.state, &[id])?;
                damage::run(&mut self.state)?;
            }
        }
        let mut c = self.remove_now(id)?;
        self.state.events.died(id, c.kind(), cause);
        c.alive = was_alive;
        if hooked {
            self.lifecycle()?;
        }
        Ok(c)
    }

    /// Between steps, Pop's `damage` from the scene or a test: lowers the health of `id` by
    /// `amount`, runs its `on_damage` at once (with no source), and removes it when its health
    /// is then at or below zero. The damage is in the events of the last step. Nothing happens
    /// to a critter that is gone or dead.
    pub fn damage(&mut self, id: CritterId, amount: f64) -> Result<(), Error> {
        let Some(c) = self.state.critters.get_mut(id) else {
            return Err(Error::NoSuchCritter(id));
        };
        if !c.is_alive() {
            return Ok(());
        }
        c.traits_mut().health -= amount;
        let (kind, dead) = (c.kind(), c.health() <= 0.0);
        self.state.note_damage(id, kind, amount, None);
        damage::run(&mut self.state)?;
        if dead && self.state.critters.get(id).is_some_and(|c| c.is_alive()) {
            self.remove_because(id, DeathCause::Damage(None))?;
        }
        Ok(())
    }

    /// The lifecycle stage, its removals told to the method (what rested on them wakes).
    pub(super) fn lifecycle(&mut self) -> Result<(), Error> {
        let methods = &mut self.methods;
        let watch = methods.watches_removals();
        lifecycle::run(&mut self.state, watch, |topo, gone, slots| {
            methods.removed(topo, gone, slots)
        })
    }

    fn remove_now(&mut self, id: CritterId) -> Result<Critter<V>, Error> {
        let state = &mut self.state;
        let slot = state.critters.slot_of(id).ok_or(Error::NoSuchCritter(id))?;
        let c = state.critters.remove(id).ok_or(Error::NoSuchCritter(id))?;
        if c.is_wall() {
            state.walls.retain(|&w| w != id);
        }
        // What rested on it wakes.
        let gone = [(slot as usize, c.pos, c.radius)];
        self.methods
            .removed(&state.topo, &gone, state.critters.slot_slice());
        Ok(c)
    }
}
