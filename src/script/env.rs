//! What a script function reaches, [`Env`]: between steps the world itself (scene setup,
//! `on_step`), inside a step a hook's [`Access`], and under `collides_with` the two critters
//! alone, read only. Each operation is written once, here; its arms say what the place changes.
//!
//! A new capability that reads or writes the step's state goes through [`Env::access`] to a
//! method of [`Access`] (`step/access.rs`), which is the same between steps and inside them; it
//! then takes two files, that method and its registration in `api/`.

use crate::border::Topology;
use crate::critter::{Critter, CritterId, CritterSpec, Props};
use crate::error::Error;
use crate::kind::{KindId, KindSet};
use crate::rng::Rng;
use crate::step::access::Access;
use crate::step::pending::{OnOverlap, SpawnOrigin};
use crate::step::spawn::Placed;
use crate::vector::Vector;
use crate::world::World;

/// What a script function reaches (see the module docs).
pub(crate) enum Env<'a, V: Vector> {
    /// Between steps: the world itself; spawns and deaths take effect at once.
    World(&'a mut World<V>),
    /// Inside a step, from a hook: spawns and deaths wait for the step's end.
    Hook(Access<'a, V>),
    /// `collides_with`: the pair, read only (its answer may be cached).
    Pair(PairView<'a, V>),
}

/// What `collides_with` may see: the two critters, read only.
pub(crate) struct PairView<'a, V: Vector> {
    pub a: &'a Critter<V>,
    pub b: &'a Critter<V>,
    pub kinds: &'a KindSet<V>,
    pub topo: &'a Topology<V>,
    /// A generator of its own: `collides_with` must not draw from the world's.
    pub rng: &'a mut Rng,
}

/// Why `collides_with` cannot ask for neighbours.
const NO_QUERIES: &str =
    "nearby and nearest work in update, init and collide hooks and in scenes, not in collides_with";

/// Why `collides_with` reaches no more than its pair.
const READ_ONLY: &str =
    "collides_with only answers how two critters meet: it reads the two, and changes nothing";

impl<V: Vector> Env<'_, V> {
    /// The same place, borrowed for a shorter while.
    pub(crate) fn reborrow(&mut self) -> Env<'_, V> {
        match self {
            Env::World(w) => Env::World(w),
            Env::Hook(a) => Env::Hook(a.reborrow()),
            Env::Pair(p) => Env::Pair(PairView {
                a: p.a,
                b: p.b,
                kinds: p.kinds,
                topo: p.topo,
                rng: p.rng,
            }),
        }
    }

    /// The step's state, as hooks see it (between steps too); an error in `collides_with`.
    pub(crate) fn access(&mut self) -> Result<Access<'_, V>, String> {
        match self {
            Env::World(w) => Ok(w.access()),
            Env::Hook(a) => Ok(a.reborrow()),
            Env::Pair(_) => Err(READ_ONLY.into()),
        }
    }

    pub(crate) fn critter(&self, id: CritterId) -> Option<&Critter<V>> {
        match self {
            Env::World(w) => w.get(id),
            Env::Hook(a) => a.get(id),
            Env::Pair(p) => [p.a, p.b].into_iter().find(|c| c.id() == id),
        }
    }

    pub(crate) fn critter_mut(&mut self, id: CritterId) -> Option<&mut Critter<V>> {
        match self {
            Env::World(w) => w.get_mut(id),
            Env::Hook(a) => a.get_mut(id),
            Env::Pair(_) => None,
        }
    }

    pub(crate) fn kinds(&self) -> &KindSet<V> {
        match self {
            Env::World(w) => w.kinds(),
            Env::Hook(a) => a.kinds(),
            Env::Pair(p) => p.kinds,
        }
    }

    pub(crate) fn topology(&self) -> &Topology<V> {
        match self {
            Env::World(w) => w.topology(),
            Env::Hook(a) => a.topology(),
            Env::Pair(p) => p.topo,
        }
    }

    /// Steps completed (0 in `collides_with`, whose answer must not depend on the time).
    pub(crate) fn step_count(&self) -> u64 {
        match self {
            Env::World(w) => w.step_count(),
            Env::Hook(a) => a.step(),
            Env::Pair(_) => 0,
        }
    }

    /// The step that what a script does now is filed under, in the log's `[step k]` and the
    /// recording: the one running (k, where `step_count` is k - 1) inside a step; the last one
    /// taken between steps (`on_step` after step k, a test or scene between steps).
    pub(crate) fn step_now(&self) -> u64 {
        match self {
            Env::World(w) => w.step_count(),
            Env::Hook(a) => a.step() + 1,
            Env::Pair(_) => 0,
        }
    }

    pub(crate) fn time(&self) -> f64 {
        match self {
            Env::World(w) => w.time(),
            Env::Hook(a) => a.time(),
            Env::Pair(_) => 0.0,
        }
    }

    pub(crate) fn dt(&self) -> f64 {
        match self {
            Env::World(w) => w.dt(),
            Env::Hook(a) => a.dt(),
            Env::Pair(_) => 0.0,
        }
    }

    pub(crate) fn rng(&mut self) -> &mut Rng {
        match self {
            Env::World(w) => w.rng(),
            Env::Hook(a) => a.rng(),
            Env::Pair(p) => p.rng,
        }
    }

    pub(crate) fn die(&mut self, id: CritterId) {
        match self {
            // Between steps a death takes effect at once.
            Env::World(w) => {
                let _ = w.remove(id);
            }
            Env::Hook(a) => a.die(id),
            Env::Pair(_) => {}
        }
    }

    /// Pop's `damage`. Between steps the damaged critter's `on_damage` runs at once, with no
    /// source, and an error from it comes back here; inside a step it runs in the step's
    /// damage stage.
    pub(crate) fn damage(&mut self, id: CritterId, amount: f64) -> Result<(), Error> {
        match self {
            Env::World(w) => match w.damage(id, amount) {
                // A handle to a critter that is gone damages nothing, as inside a step.
                Err(Error::NoSuchCritter(_)) => Ok(()),
                other => other,
            },
            Env::Hook(a) => {
                a.damage(id, amount);
                Ok(())
            }
            Env::Pair(_) => Ok(()),
        }
    }

    /// Spawns placed under `on_overlap`: now between steps (`Some`), or queued for the end of
    /// the step with where a script asked for it (`None`).
    pub(crate) fn spawn_placed(
        &mut self,
        spec: CritterSpec<V>,
        on_overlap: OnOverlap,
        origin: Option<Box<SpawnOrigin>>,
    ) -> Result<Option<Placed>, Error> {
        match self {
            Env::World(w) => w.spawn_placed(spec, on_overlap).map(Some),
            Env::Hook(a) => {
                a.spawn_placed(spec, on_overlap, origin);
                Ok(None)
            }
            Env::Pair(_) => Err(no_spawn()),
        }
    }

    pub(crate) fn log(&mut self, line: String) {
        match self {
            Env::World(w) => w.log_line(line),
            Env::Hook(a) => a.log(line),
            Env::Pair(_) => {}
        }
    }

    pub(crate) fn critters_of(&self, kind: KindId) -> Vec<CritterId> {
        match self {
            Env::World(w) => w
                .critters()
                .iter()
                .filter(|c| c.is_alive() && w.kinds().is_kind(c.kind(), kind))
                .map(|c| c.id())
                .collect(),
            Env::Hook(a) => a.critters_of(kind),
            Env::Pair(_) => Vec::new(),
        }
    }

    pub(crate) fn touches(&self, a: CritterId, b: CritterId) -> bool {
        match (self.critter(a), self.critter(b)) {
            (Some(x), Some(y)) => crate::default_response::touches(self.topology(), x, y),
            _ => false,
        }
    }

    pub(crate) fn contains(&self, outer: CritterId, inner: CritterId) -> bool {
        match (self.critter(outer), self.critter(inner)) {
            (Some(o), Some(i)) => crate::default_response::contains(self.topology(), o, i),
            _ => false,
        }
    }

    pub(crate) fn distance(&self, a: CritterId, b: CritterId) -> Option<f64> {
        let (x, y) = (self.critter(a)?, self.critter(b)?);
        Some(self.topology().delta(x.pos, y.pos).length())
    }

    /// The default response: the impulse it gave when they touched; `Err` outside a step.
    pub(crate) fn collide_default(
        &mut self,
        caller: CritterId,
        arg: CritterId,
    ) -> Result<Option<f64>, String> {
        match self {
            Env::World(_) => Err("collide_default can only be called inside a collide hook".into()),
            Env::Hook(a) => Ok(a.collide_default_pair(caller, arg).map(|hit| hit.impulse)),
            Env::Pair(_) => Err("collide_default belongs in collide, not collides_with".into()),
        }
    }

    /// Seconds since critter `id` was spawned; `None` where it cannot be told.
    pub(crate) fn age(&self, id: CritterId) -> Option<f64> {
        match self {
            Env::World(w) => w.age(id),
            Env::Hook(a) => a.age(id),
            Env::Pair(_) => None,
        }
    }

    /// The world itself, between steps (scene setup and `on_step`).
    pub(crate) fn world(&mut self) -> Option<&mut World<V>> {
        match self {
            Env::World(w) => Some(w),
            _ => None,
        }
    }

    /// The shared state `world().vars`; `None` where it is out of reach (`collides_with`).
    pub(crate) fn vars(&mut self) -> Option<&mut Props> {
        match self {
            Env::World(w) => Some(w.vars_mut()),
            Env::Hook(a) => Some(a.vars_mut()),
            Env::Pair(_) => None,
        }
    }

    /// Neighbour queries (see `step::neighbours`); `Err` in `collides_with`.
    pub(crate) fn nearby(
        &mut self,
        centre: V,
        r: f64,
        kind: Option<KindId>,
        exclude: Option<CritterId>,
    ) -> Result<Vec<CritterId>, String> {
        match self {
            Env::World(w) => Ok(w.nearby(centre, r, kind, exclude)),
            Env::Hook(a) => Ok(a.nearby(centre, r, kind, exclude)),
            Env::Pair(_) => Err(NO_QUERIES.into()),
        }
    }

    pub(crate) fn nearest(
        &mut self,
        centre: V,
        kind: Option<KindId>,
        exclude: Option<CritterId>,
    ) -> Result<Option<CritterId>, String> {
        match self {
            Env::World(w) => Ok(w.nearest(centre, kind, exclude)),
            Env::Hook(a) => Ok(a.nearest(centre, kind, exclude)),
            Env::Pair(_) => Err(NO_QUERIES.into()),
        }
    }
}

/// The error of a spawn asked for in `collides_with`.
fn no_spawn() -> Error {
    Error::InvalidKind {
        kind: "collides_with".into(),
        reason: "collides_with only answers how two critters meet; spawn in collide or update"
            .into(),
    }
}
