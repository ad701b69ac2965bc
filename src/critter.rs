//! Critters: the disks (2D) and spheres (3D) that move and collide, and the walls they bounce off.

use crate::ids::KindId;
pub use crate::ids::{CritterId, ParseCritterIdError};
use crate::vector::Vector;
use crate::wall::WallBox;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Collide priority of the lowest critters (Pop's CP_MINIMUM).
pub const CP_MINIMUM: f64 = 0.0;
/// Collide priority of ordinary critters (Pop's CP_CRITTER).
pub const CP_CRITTER: f64 = 100.0;
/// Collide priority of players (Pop's CP_PLAYER).
pub const CP_PLAYER: f64 = 200.0;
/// Collide priority of silver bullets (Pop's CP_SILVERBULLET).
pub const CP_SILVERBULLET: f64 = 300.0;
/// Collide priority of bullets (Pop's CP_BULLET).
pub const CP_BULLET: f64 = 400.0;
/// Collide priority of walls (Pop's CP_WALL).
pub const CP_WALL: f64 = 500.0;
/// The highest collide priority (Pop's CP_MAXIMUM).
pub const CP_MAXIMUM: f64 = 1e6;

/// Pop's priority constants by name, for scripts and command lines.
pub const PRIORITY_NAMES: [(&str, f64); 7] = [
    ("CP_MINIMUM", CP_MINIMUM),
    ("CP_CRITTER", CP_CRITTER),
    ("CP_PLAYER", CP_PLAYER),
    ("CP_SILVERBULLET", CP_SILVERBULLET),
    ("CP_BULLET", CP_BULLET),
    ("CP_WALL", CP_WALL),
    ("CP_MAXIMUM", CP_MAXIMUM),
];

/// A user property value, for the map every critter carries.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum PropValue {
    /// A flag.
    Bool(bool),
    /// An integer.
    Int(i64),
    /// A number.
    Float(f64),
    /// Some text.
    Text(String),
    /// Another critter.
    Critter(CritterId),
    /// A list of values.
    List(Vec<PropValue>),
    /// A vector (z = 0 in 2D).
    Vector([f64; 3]),
    /// Named values, ordered by name (for `world().vars`, whose values may be maps).
    Map(BTreeMap<String, PropValue>),
}

/// A critter's user properties, ordered by name so iteration is deterministic.
pub type Props = BTreeMap<String, PropValue>;

/// The shape of a critter: a disk (sphere in 3D) of its radius, or a wall box.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape<V: Vector> {
    /// A disk in 2D, a sphere in 3D.
    Disk,
    /// An immovable oriented box (Pop's cCritterWall). Boxed: walls are few, disks are many.
    Wall(Box<WallBox<V>>),
}

/// Sentinel for "rule class not yet known" (see [`crate::rules`]).
pub(crate) const CLASS_UNSET: u32 = u32::MAX;

/// One critter.
///
/// Position and velocity are free to change; restitution, health and properties through their
/// setters. Radius, mass, priority and `fixed` go through setters too, because the engine caches
/// what follows from them (the rule class of the pair cache).
///
/// The record holds what the passes over every critter read (the move, the broad phase's
/// re-test, the narrow phase): position, velocity, radius, id, rule class, fixed, alive and the
/// wall flag, laid out by hand (`repr(C)`). In 2D it is 64 bytes aligned to 64, one cache line;
/// 80 bytes in 3D. The rest, the traits (kind, mass, priority, restitution, health, shape,
/// properties), sits behind a shared pointer: critters alike (a gas spawned from one kind) share
/// one copy, and a setter makes the changed critter's copy its own first. A pass over a million
/// 2D critters then streams 64 MB, not 128.
#[derive(Clone, Debug)]
#[repr(C)]
pub struct Critter<V: Vector> {
    /// Centre.
    pub pos: V,
    /// Velocity.
    pub vel: V,
    pub(crate) radius: f64,
    pub(crate) id: CritterId,
    pub(crate) class: u32,
    pub(crate) fixed: bool,
    pub(crate) alive: bool,
    /// True for a wall: what the shape says, kept in the record so that the passes over every
    /// critter need not read the traits. Not hashed (the kind says it too).
    pub(crate) wall: bool,
    /// Set aside by the collision method for part of a step (a group of islands another
    /// method steps, or a bullet flown on its own; see `method::aside`): alive, but out of play
    /// until brought back. Never set between steps, so not hashed.
    pub(crate) aside: bool,
    pub(crate) traits: Arc<Traits<V>>,
    pub(crate) _align: [V::CritterAlign; 0],
}

/// What a critter is, beside where it is and how it moves: read per touching pair and by the
/// hooks, not by the passes over every critter. Shared between critters alike (see
/// [`Critter`]).
#[derive(Clone, Debug)]
pub(crate) struct Traits<V: Vector> {
    pub(crate) kind: KindId,
    pub(crate) mass: f64,
    pub(crate) priority: f64,
    /// Coefficient of restitution in [0, 1]; a pair uses the smaller of its two.
    pub(crate) restitution: f64,
    /// Health; `damage` lowers it and the critter dies at or below zero.
    pub(crate) health: f64,
    pub(crate) shape: Shape<V>,
    /// User properties.
    pub(crate) props: Props,
    /// The colour a script gave this critter (`me.color`), as written; `None` draws it in its
    /// kind's colour. Not hashed: it changes what a viewer shows, never what happens.
    pub(crate) color: Option<String>,
}

impl<V: Vector> Traits<V> {
    /// True when `self` and `o` are the same bit for bit, as far as it is cheap to tell: disks
    /// with no properties (what a spawned gas is). Two traits that are told apart here may
    /// still be shared; they are then not.
    pub(crate) fn same_plain(&self, o: &Self) -> bool {
        matches!((&self.shape, &o.shape), (Shape::Disk, Shape::Disk))
            && self.props.is_empty()
            && o.props.is_empty()
            && self.color.is_none()
            && o.color.is_none()
            && self.kind == o.kind
            && self.mass.to_bits() == o.mass.to_bits()
            && self.priority.to_bits() == o.priority.to_bits()
            && self.restitution.to_bits() == o.restitution.to_bits()
            && self.health.to_bits() == o.health.to_bits()
    }
}

impl<V: Vector> Critter<V> {
    /// Stable id.
    pub fn id(&self) -> CritterId {
        self.id
    }
    /// Kind.
    pub fn kind(&self) -> KindId {
        self.traits.kind
    }
    /// Radius (for a wall: the radius of its bounding sphere).
    pub fn radius(&self) -> f64 {
        self.radius
    }
    /// Mass. Fixed critters have a finite nominal mass but act as infinitely heavy.
    pub fn mass(&self) -> f64 {
        self.traits.mass
    }
    /// 1 / mass, or 0 when fixed.
    pub fn inv_mass(&self) -> f64 {
        if self.fixed {
            0.0
        } else {
            1.0 / self.traits.mass
        }
    }
    /// Collide priority (see `CP_*`).
    pub fn priority(&self) -> f64 {
        self.traits.priority
    }
    /// Fixed critters have infinite mass: collisions never change their velocity.
    pub fn is_fixed(&self) -> bool {
        self.fixed
    }
    /// False once the critter has died (it is removed at the end of the step).
    pub fn is_alive(&self) -> bool {
        self.alive
    }
    /// Alive and not set aside by the method: what the step's stages move, pair and collide.
    #[inline]
    pub(crate) fn in_play(&self) -> bool {
        self.alive && !self.aside
    }
    /// True for walls.
    pub fn is_wall(&self) -> bool {
        debug_assert_eq!(self.wall, matches!(self.traits.shape, Shape::Wall(_)));
        self.wall
    }
    /// The wall geometry, for walls.
    pub fn wall(&self) -> Option<&WallBox<V>> {
        match &self.traits.shape {
            Shape::Wall(w) => Some(w),
            Shape::Disk => None,
        }
    }
    /// Shape.
    pub fn shape(&self) -> &Shape<V> {
        &self.traits.shape
    }
    /// Kinetic energy (zero for fixed critters, which are not part of the dynamics).
    pub fn kinetic_energy(&self) -> f64 {
        if self.fixed {
            0.0
        } else {
            0.5 * self.traits.mass * self.vel.length_squared()
        }
    }

    /// Sets the radius (finite and > 0). Mass is kept.
    pub fn set_radius(&mut self, radius: f64) -> Result<(), crate::Error> {
        check_positive(|| self.describe(), "radius", radius)?;
        if self.is_wall() {
            return Err(crate::Error::InvalidCritter {
                critter: self.describe(),
                field: "radius",
                value: radius.to_string(),
                reason: "a wall's size is set by its box, not a radius".into(),
            });
        }
        self.radius = radius;
        Ok(())
    }
    /// Sets the mass (finite and > 0).
    pub fn set_mass(&mut self, mass: f64) -> Result<(), crate::Error> {
        check_positive(|| self.describe(), "mass", mass)?;
        self.traits_mut().mass = mass;
        Ok(())
    }
    /// Makes the critter fixed (infinite mass) or free.
    pub fn set_fixed(&mut self, fixed: bool) {
        if self.is_wall() {
            return; // walls are always fixed
        }
        self.fixed = fixed;
        self.class = CLASS_UNSET;
    }
    /// Sets the collide priority (finite).
    pub fn set_priority(&mut self, priority: f64) -> Result<(), crate::Error> {
        if !priority.is_finite() {
            return Err(crate::Error::InvalidCritter {
                critter: self.describe(),
                field: "priority",
                value: priority.to_string(),
                reason: "must be a finite number; use the CP_* constants".into(),
            });
        }
        self.traits_mut().priority = priority;
        self.class = CLASS_UNSET;
        Ok(())
    }

    /// Coefficient of restitution in [0, 1]; a pair uses the smaller of its two.
    pub fn restitution(&self) -> f64 {
        self.traits.restitution
    }
    /// Sets the coefficient of restitution (in [0, 1]).
    pub fn set_restitution(&mut self, restitution: f64) -> Result<(), crate::Error> {
        check_restitution(|| self.describe(), restitution)?;
        self.traits_mut().restitution = restitution;
        Ok(())
    }
    /// Health; `damage` lowers it and the critter dies at or below zero.
    pub fn health(&self) -> f64 {
        self.traits.health
    }
    /// Sets the health (any number; the lifecycle, not this, decides who dies).
    pub fn set_health(&mut self, health: f64) {
        self.traits_mut().health = health;
    }
    /// User properties.
    pub fn props(&self) -> &Props {
        &self.traits.props
    }
    /// User properties, to change.
    pub fn props_mut(&mut self) -> &mut Props {
        &mut self.traits_mut().props
    }
    /// The colour a script gave this critter, if any (else its kind's colour applies).
    pub fn color(&self) -> Option<&str> {
        self.traits.color.as_deref()
    }
    /// Gives the critter its own colour: a colour name or `#rrggbb` (see [`crate::color`]);
    /// `None` goes back to the kind's colour.
    pub fn set_color(&mut self, color: Option<&str>) -> Result<(), crate::Error> {
        let color =
            match color {
                Some(c) => Some(crate::color::checked(c).map_err(|reason| {
                    crate::Error::InvalidCritter {
                        critter: self.describe(),
                        field: "color",
                        value: c.to_string(),
                        reason,
                    }
                })?),
                None => None,
            };
        if self.traits.color != color {
            self.traits_mut().color = color;
        }
        Ok(())
    }
    /// The traits to change: the critter's own copy, made now if it shares them.
    pub(crate) fn traits_mut(&mut self) -> &mut Traits<V> {
        Arc::make_mut(&mut self.traits)
    }

    /// "critter #3" — for error messages.
    pub fn describe(&self) -> String {
        format!("critter {}", self.id)
    }
}

pub(crate) fn check_positive(
    critter: impl FnOnce() -> String,
    field: &'static str,
    v: f64,
) -> Result<(), crate::Error> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(crate::Error::InvalidCritter {
            critter: critter(),
            field,
            value: v.to_string(),
            reason: "must be a finite number greater than zero".into(),
        })
    }
}

/// A coefficient of restitution must lie in [0, 1].
pub(crate) fn check_restitution(
    critter: impl FnOnce() -> String,
    e: f64,
) -> Result<(), crate::Error> {
    if (0.0..=1.0).contains(&e) {
        Ok(())
    } else {
        Err(crate::Error::InvalidCritter {
            critter: critter(),
            field: "restitution",
            value: e.to_string(),
            reason: "must be between 0 (sticky) and 1 (elastic)".into(),
        })
    }
}

/// How to spawn a critter: its kind by name plus anything that differs from the kind's defaults.
#[derive(Clone, Debug)]
pub struct CritterSpec<V: Vector> {
    /// Kind name (must be registered in the world).
    pub kind: String,
    /// Centre.
    pub pos: V,
    /// Velocity.
    pub vel: V,
    /// Radius; the kind's default when `None`.
    pub radius: Option<f64>,
    /// Mass; density x radius^3 when `None`.
    pub mass: Option<f64>,
    /// Density; the kind's default when `None`.
    pub density: Option<f64>,
    /// Fixed (infinite mass); the kind's default when `None`.
    pub fixed: Option<bool>,
    /// Collide priority; the kind's default when `None`.
    pub priority: Option<f64>,
    /// Coefficient of restitution; the kind's default when `None`.
    pub restitution: Option<f64>,
    /// Health; the kind's default when `None`.
    pub health: Option<f64>,
    /// User properties, added to the kind's.
    pub props: Props,
    /// Its own colour (a colour name or `#rrggbb`, as `me.color`); the kind's when `None`.
    pub color: Option<String>,
}

impl<V: Vector> CritterSpec<V> {
    /// A critter of `kind` at `pos`, at rest, with the kind's defaults.
    pub fn new(kind: impl Into<String>, pos: V) -> Self {
        CritterSpec {
            kind: kind.into(),
            pos,
            vel: V::zero(),
            radius: None,
            mass: None,
            density: None,
            fixed: None,
            priority: None,
            restitution: None,
            health: None,
            props: Props::new(),
            color: None,
        }
    }
    /// A plain ball.
    pub fn ball(pos: V) -> Self {
        Self::new("ball", pos)
    }
    /// With velocity `vel`.
    pub fn vel(mut self, vel: V) -> Self {
        self.vel = vel;
        self
    }
    /// With radius `r`.
    pub fn radius(mut self, r: f64) -> Self {
        self.radius = Some(r);
        self
    }
    /// With mass `m`.
    pub fn mass(mut self, m: f64) -> Self {
        self.mass = Some(m);
        self
    }
    /// With density `d` (mass = d x radius^3).
    pub fn density(mut self, d: f64) -> Self {
        self.density = Some(d);
        self
    }
    /// Fixed (infinite mass) or not.
    pub fn fixed(mut self, fixed: bool) -> Self {
        self.fixed = Some(fixed);
        self
    }
    /// With collide priority `p`.
    pub fn priority(mut self, p: f64) -> Self {
        self.priority = Some(p);
        self
    }
    /// With restitution `e`.
    pub fn restitution(mut self, e: f64) -> Self {
        self.restitution = Some(e);
        self
    }
    /// With health `h`.
    pub fn health(mut self, h: f64) -> Self {
        self.health = Some(h);
        self
    }
    /// With user property `name` = `value`.
    pub fn prop(mut self, name: impl Into<String>, value: PropValue) -> Self {
        self.props.insert(name.into(), value);
        self
    }
}

#[cfg(test)]
mod layout_tests {
    use super::*;
    use glam::{DVec2, DVec3};
    use std::mem::{align_of, offset_of, size_of};

    #[test]
    fn a_2d_critter_is_one_cache_line_and_a_3d_one_80_bytes() {
        type C = Critter<DVec2>;
        assert_eq!(size_of::<C>(), 64);
        assert_eq!(align_of::<C>(), 64);
        // The slot's tag lives in the critter (no extra word for `Option`).
        assert_eq!(size_of::<Option<C>>(), 64);
        assert_eq!(align_of::<Critter<DVec3>>(), 8);
        assert_eq!(size_of::<Option<Critter<DVec3>>>(), 80);
        assert!(offset_of!(C, traits) + 8 <= 64);
    }
}
