//! Kinds of critter and the one hook trait through which a kind customises behaviour.
//!
//! A kind is a name, an optional parent kind (for `is_kind`), default attributes, and an
//! implementation of [`KindHooks`]. The native behaviour is the trait's default methods, so
//! `impl KindHooks for ()` is the plain ball; scripted kinds implement the same trait.

use crate::critter::{Critter, CritterId, CP_CRITTER, CP_WALL};
use crate::error::Error;
pub use crate::ids::KindId;
use crate::step::access::{CollideCtx, HookContact, UpdateCtx};
use crate::vector::Vector;
use std::collections::BTreeMap;
use std::rc::Rc;

/// Pop's `collidesWith` answer, from one critter about another.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CollideRule {
    /// Never collide (Pop's DONTCOLLIDE).
    DontCollide,
    /// Collide, and I call `collide` (COLLIDEASCALLER).
    AsCaller,
    /// Collide, and the other calls (COLLIDEASARG).
    AsArg,
    /// Collide, either may call (COLLIDEEITHERWAY).
    EitherWay,
}

impl CollideRule {
    /// The rule codes by name, as scripts see them.
    pub const NAMES: [(&'static str, CollideRule); 4] = [
        ("DONT_COLLIDE", CollideRule::DontCollide),
        ("COLLIDE_AS_CALLER", CollideRule::AsCaller),
        ("COLLIDE_AS_ARG", CollideRule::AsArg),
        ("COLLIDE_EITHER_WAY", CollideRule::EitherWay),
    ];
}

/// Pop's default `collidesWith`: two fixed critters don't collide; otherwise the higher priority
/// calls and equal priorities may go either way.
pub fn default_collides_with<V: Vector>(me: &Critter<V>, other: &Critter<V>) -> CollideRule {
    if me.is_fixed() && other.is_fixed() {
        CollideRule::DontCollide
    } else if me.priority() > other.priority() {
        CollideRule::AsCaller
    } else if me.priority() < other.priority() {
        CollideRule::AsArg
    } else {
        CollideRule::EitherWay
    }
}

/// What `collides_with` sees: the two critters, read-only, and the world's kinds and box.
pub struct RuleCtx<'a, V: Vector> {
    /// The critter whose kind is asked.
    pub me: &'a Critter<V>,
    /// The other one.
    pub other: &'a Critter<V>,
    /// The world's kinds (for `is_kind`).
    pub kinds: &'a KindSet<V>,
    /// The world box and border.
    pub topo: &'a crate::border::Topology<V>,
}

/// How a kind behaves. Every method has the native default; override what the kind changes.
///
/// Hooks get a context that reads and writes the critters involved and queues deaths and
/// spawns; structural changes take effect after the step.
pub trait KindHooks<V: Vector> {
    /// Pop's `collidesWith`: how `ctx.me` wants to meet `ctx.other`. Asked once per pair of rule
    /// classes (kind, priority, fixed) and cached, unless [`KindHooks::rule_depends_on_state`]
    /// says otherwise.
    fn collides_with(&self, ctx: &RuleCtx<'_, V>) -> Result<CollideRule, Error> {
        Ok(default_collides_with(ctx.me, ctx.other))
    }

    /// True when `collides_with` reads more than kind, priority and `fixed`, so the answer cannot
    /// be cached per kind pair.
    fn rule_depends_on_state(&self) -> bool {
        false
    }

    /// Pop's `collide`: called on the caller of a touching pair, once per step. Returns whether the
    /// pair touched and was handled. The default is the engine's physical response.
    fn collide(&self, ctx: &mut CollideCtx<'_, V>) -> Result<bool, Error> {
        Ok(ctx.collide_default())
    }

    /// Whether [`KindHooks::collide`] is the kind's own. Only pairs whose caller keeps the
    /// default response can have their contacts solved together (`solve:n`); the others have
    /// their hook called. True unless a kind says otherwise, so an override is never skipped.
    fn has_collide(&self) -> bool {
        true
    }

    /// Whether [`KindHooks::update`] does anything; kinds without one cost nothing per step.
    fn has_update(&self) -> bool {
        false
    }

    /// Called every step for each live critter of the kind, before it moves.
    fn update(&self, _ctx: &mut UpdateCtx<'_, V>, _dt: f64) -> Result<(), Error> {
        Ok(())
    }

    /// Whether [`KindHooks::init`] does anything.
    fn has_init(&self) -> bool {
        false
    }

    /// Called once when a critter of the kind has been spawned.
    fn init(&self, _ctx: &mut UpdateCtx<'_, V>) -> Result<(), Error> {
        Ok(())
    }

    /// Whether the kind needs touching spells tracked: it has touch hooks, or its `collide`
    /// reads the contact (`first` says whether a spell begins). Off, the engine keeps no spells.
    fn tracks_touch(&self) -> bool {
        false
    }

    /// Whether the kind has `touch_begin` or `touch_end` (the touch stage calls no other).
    fn has_touch_hooks(&self) -> bool {
        self.tracks_touch()
    }

    /// Called when a touching spell of `ctx.me` with `ctx.other` begins (see `world::touch`).
    fn touch_begin(
        &self,
        _ctx: &mut CollideCtx<'_, V>,
        _contact: &HookContact<V>,
    ) -> Result<(), Error> {
        Ok(())
    }

    /// Called when a touching spell of `ctx.me` with `ctx.other` ends.
    fn touch_end(&self, _ctx: &mut CollideCtx<'_, V>) -> Result<(), Error> {
        Ok(())
    }

    /// Whether [`KindHooks::on_death`] does anything.
    fn has_on_death(&self) -> bool {
        false
    }

    /// Called once when a critter of the kind dies, before it is removed.
    fn on_death(&self, _ctx: &mut UpdateCtx<'_, V>) -> Result<(), Error> {
        Ok(())
    }

    /// Whether [`KindHooks::on_damage`] does anything; without any, damage queues nothing.
    fn has_on_damage(&self) -> bool {
        false
    }

    /// Called once per damage `ctx.me` took, `amount` of it, from `source`: the critter whose
    /// hook did it, `None` for the scene or a test between steps. Inside a step it runs in the
    /// damage stage (`step::damage`), between steps at once.
    fn on_damage(
        &self,
        _ctx: &mut UpdateCtx<'_, V>,
        _amount: f64,
        _source: Option<CritterId>,
    ) -> Result<(), Error> {
        Ok(())
    }
}

/// The native behaviour: plain balls and walls.
impl<V: Vector> KindHooks<V> for () {
    fn has_collide(&self) -> bool {
        false
    }
}

/// Default attributes of a kind's critters.
#[derive(Clone, Debug, PartialEq)]
pub struct KindDefaults {
    /// Radius.
    pub radius: f64,
    /// Density: mass = density x radius^3 unless a mass is given.
    pub density: f64,
    /// Mass, overriding density when set.
    pub mass: Option<f64>,
    /// Collide priority.
    pub priority: f64,
    /// Coefficient of restitution.
    pub restitution: f64,
    /// Fixed (infinite mass).
    pub fixed: bool,
    /// Starting health.
    pub health: f64,
    /// Display colour (a CSS-style name or `#rrggbb`), for viewers.
    pub color: Option<String>,
    /// User properties every critter of the kind starts with.
    pub props: crate::critter::Props,
}

impl Default for KindDefaults {
    fn default() -> Self {
        KindDefaults {
            radius: 0.5,
            density: 1.0,
            mass: None,
            priority: CP_CRITTER,
            restitution: 1.0,
            fixed: false,
            health: 1.0,
            color: None,
            props: Default::default(),
        }
    }
}

/// A registered kind.
pub struct Kind<V: Vector> {
    /// Name, unique in the world.
    pub name: String,
    /// The kind this one extends, if any.
    pub parent: Option<KindId>,
    /// Default attributes.
    pub defaults: KindDefaults,
    /// Behaviour.
    pub hooks: Rc<dyn KindHooks<V>>,
    pub(crate) has_update: bool,
    pub(crate) has_init: bool,
    pub(crate) has_collide: bool,
    pub(crate) has_touch_hooks: bool,
    pub(crate) has_on_death: bool,
    pub(crate) has_on_damage: bool,
    pub(crate) rule_depends_on_state: bool,
}

impl<V: Vector> Kind<V> {
    /// A kind, with what its hooks do read once.
    fn new(
        name: String,
        parent: Option<KindId>,
        defaults: KindDefaults,
        hooks: Rc<dyn KindHooks<V>>,
    ) -> Self {
        Kind {
            name,
            parent,
            has_update: hooks.has_update(),
            has_init: hooks.has_init(),
            has_collide: hooks.has_collide(),
            has_touch_hooks: hooks.has_touch_hooks(),
            has_on_death: hooks.has_on_death(),
            has_on_damage: hooks.has_on_damage(),
            rule_depends_on_state: hooks.rule_depends_on_state(),
            defaults,
            hooks,
        }
    }
}

/// The kinds of a world. Always holds `ball` and `wall`.
pub struct KindSet<V: Vector> {
    kinds: Vec<Kind<V>>,
    by_name: BTreeMap<String, KindId>,
    /// Some kind tracks touching spells (so the step keeps them).
    tracks_touch: bool,
    /// Some kind has an `on_death` hook.
    has_on_death: bool,
    /// Some kind has an `on_damage` hook.
    has_on_damage: bool,
}

/// The kind id of `wall` in every world.
pub const WALL: KindId = KindId(1);

impl<V: Vector> Default for KindSet<V> {
    fn default() -> Self {
        Self::new()
    }
}

impl<V: Vector> KindSet<V> {
    /// The native kinds: `ball` and `wall`.
    pub fn new() -> Self {
        let mut set = KindSet {
            kinds: Vec::new(),
            by_name: BTreeMap::new(),
            tracks_touch: false,
            has_on_death: false,
            has_on_damage: false,
        };
        set.insert("ball", None, KindDefaults::default(), Rc::new(()));
        let wall = KindDefaults {
            priority: CP_WALL,
            fixed: true,
            ..KindDefaults::default()
        };
        set.insert("wall", None, wall, Rc::new(()));
        set
    }

    fn insert(
        &mut self,
        name: &str,
        parent: Option<KindId>,
        defaults: KindDefaults,
        hooks: Rc<dyn KindHooks<V>>,
    ) -> KindId {
        let id = KindId(self.kinds.len() as u32);
        self.by_name.insert(name.to_string(), id);
        self.tracks_touch |= hooks.tracks_touch();
        self.has_on_death |= hooks.has_on_death();
        self.has_on_damage |= hooks.has_on_damage();
        self.kinds
            .push(Kind::new(name.to_string(), parent, defaults, hooks));
        id
    }

    /// Registers a new kind. Errors if the name is taken, empty, or the parent is unknown, or the
    /// defaults are out of range.
    pub fn register(
        &mut self,
        name: &str,
        parent: Option<&str>,
        defaults: KindDefaults,
        hooks: Rc<dyn KindHooks<V>>,
    ) -> Result<KindId, Error> {
        if name.trim().is_empty() {
            return Err(Error::InvalidKind {
                kind: name.to_string(),
                reason: "a kind needs a non-empty name".into(),
            });
        }
        if self.by_name.contains_key(name) {
            return Err(Error::InvalidKind {
                kind: name.to_string(),
                reason: "a kind of that name is already registered".into(),
            });
        }
        let parent = match parent {
            Some(p) => Some(self.id(p)?),
            None => None,
        };
        check_defaults(name, &defaults)?;
        Ok(self.insert(name, parent, defaults, hooks))
    }

    /// Replaces kind `id`'s parent, defaults and hooks (its file was edited while the run goes
    /// on). Errors, changing nothing, if the parent is unknown or would make a cycle, or the
    /// defaults are out of range.
    pub fn replace(
        &mut self,
        id: KindId,
        parent: Option<&str>,
        defaults: KindDefaults,
        hooks: Rc<dyn KindHooks<V>>,
    ) -> Result<(), Error> {
        let name = self.get(id).name.clone();
        let parent = match parent {
            Some(p) => Some(self.id(p)?),
            None => None,
        };
        if parent.is_some_and(|p| self.is_kind(p, id)) {
            return Err(Error::InvalidKind {
                kind: name,
                reason: "its new parent extends it; a kind cannot extend itself".into(),
            });
        }
        check_defaults(&name, &defaults)?;
        self.kinds[id.0 as usize] = Kind::new(name, parent, defaults, hooks);
        self.tracks_touch = self.kinds.iter().any(|k| k.hooks.tracks_touch());
        self.has_on_death = self.kinds.iter().any(|k| k.has_on_death);
        self.has_on_damage = self.kinds.iter().any(|k| k.has_on_damage);
        Ok(())
    }

    /// The kind called `name`.
    pub fn id(&self, name: &str) -> Result<KindId, Error> {
        self.by_name
            .get(name)
            .copied()
            .ok_or_else(|| Error::UnknownKind {
                kind: name.to_string(),
                known: self.by_name.keys().cloned().collect::<Vec<_>>().join(", "),
            })
    }

    /// The kind with id `id`.
    ///
    /// # Panics
    /// If `id` did not come from this set.
    pub fn get(&self, id: KindId) -> &Kind<V> {
        &self.kinds[id.0 as usize]
    }

    /// Name of kind `id`.
    pub fn name(&self, id: KindId) -> &str {
        &self.get(id).name
    }

    /// All kinds, in registration order.
    pub fn iter(&self) -> impl Iterator<Item = (KindId, &Kind<V>)> {
        self.kinds
            .iter()
            .enumerate()
            .map(|(i, k)| (KindId(i as u32), k))
    }

    /// True when some kind tracks touching spells (touch hooks or a `collide` that reads the
    /// contact); when false the step keeps no spells.
    pub fn tracks_touch(&self) -> bool {
        self.tracks_touch
    }

    /// True when some kind has an `on_death` hook.
    pub fn has_on_death(&self) -> bool {
        self.has_on_death
    }

    /// True when some kind has an `on_damage` hook.
    pub fn has_on_damage(&self) -> bool {
        self.has_on_damage
    }

    /// Number of kinds.
    pub fn len(&self) -> usize {
        self.kinds.len()
    }

    /// Never true: `ball` and `wall` are always there.
    pub fn is_empty(&self) -> bool {
        self.kinds.is_empty()
    }

    /// True when `kind` is `ancestor` or extends it, directly or not.
    pub fn is_kind(&self, kind: KindId, ancestor: KindId) -> bool {
        let mut k = Some(kind);
        while let Some(id) = k {
            if id == ancestor {
                return true;
            }
            k = self.get(id).parent;
        }
        false
    }
}

fn check_defaults(kind: &str, d: &KindDefaults) -> Result<(), Error> {
    let bad = |reason: String| Error::InvalidKind {
        kind: kind.to_string(),
        reason,
    };
    if !(d.radius.is_finite() && d.radius > 0.0) {
        return Err(bad(format!("radius {} must be finite and > 0", d.radius)));
    }
    if !(d.density.is_finite() && d.density > 0.0) {
        return Err(bad(format!("density {} must be finite and > 0", d.density)));
    }
    if let Some(m) = d.mass {
        if !(m.is_finite() && m > 0.0) {
            return Err(bad(format!("mass {m} must be finite and > 0")));
        }
    }
    if !d.priority.is_finite() {
        return Err(bad(format!("priority {} must be finite", d.priority)));
    }
    if !(0.0..=1.0).contains(&d.restitution) {
        return Err(bad(format!(
            "restitution {} must be between 0 and 1",
            d.restitution
        )));
    }
    if !d.health.is_finite() {
        return Err(bad(format!("health {} must be finite", d.health)));
    }
    Ok(())
}
