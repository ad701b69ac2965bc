//! Helpers shared by the integration tests: worlds, the motion law of one step, Pop's 1-D elastic
//! formulas, and tolerance checks that say what they compared.
//!
//! Each test file uses only some of these, hence the `dead_code` allowance.
#![allow(dead_code)]

use critterbox::glam::{DVec2, DVec3};
use critterbox::{
    default_collides_with, CollideCtx, CollideRule, CritterId, Error, KindHooks, RuleCtx, Vector,
    World, WorldConfig,
};
use std::cell::{Cell, RefCell};
use std::rc::Rc;

/// The default time step of a world.
pub const DT: f64 = 1.0 / 60.0;

/// An empty 2D world, bouncing border, from (0, 0) to (size, size).
pub fn world2(size: f64) -> World<DVec2> {
    World::new(WorldConfig::new(DVec2::ZERO, DVec2::splat(size))).expect("a valid 2D world")
}

/// An empty 3D world, bouncing border, from (0, 0, 0) to (size, size, size).
pub fn world3(size: f64) -> World<DVec3> {
    World::new(WorldConfig::new(DVec3::ZERO, DVec3::splat(size))).expect("a valid 3D world")
}

/// An empty world of either dimension.
pub fn world<V: Vector>(size: f64) -> World<V> {
    World::new(WorldConfig::new(V::zero(), V::splat(size))).expect("a valid world")
}

/// Where a free critter is after one step of straight-line motion (before any contact).
pub fn after_move<V: Vector>(pos: V, vel: V, dt: f64) -> V {
    pos + vel * dt
}

/// Pop's 1-D elastic formulas with `mr = m_arg / m_caller`: the normal velocities after the hit.
pub fn pop_elastic(v1n: f64, v2n: f64, mr: f64) -> (f64, f64) {
    (
        ((1.0 - mr) * v1n + 2.0 * mr * v2n) / (1.0 + mr),
        (2.0 * v1n + (mr - 1.0) * v2n) / (1.0 + mr),
    )
}

/// Asserts `|actual - expected| <= tol`, naming the quantity.
#[track_caller]
pub fn assert_close(actual: f64, expected: f64, tol: f64, what: &str) {
    assert!(
        (actual - expected).abs() <= tol,
        "{what}: got {actual:e}, want {expected:e} (difference {:e} > tolerance {tol:e})",
        (actual - expected).abs()
    );
}

/// Asserts `|actual - expected| <= tol` for vectors (Euclidean norm of the difference).
#[track_caller]
pub fn assert_close_vec<V: Vector>(actual: V, expected: V, tol: f64, what: &str) {
    let diff = (actual - expected).length();
    assert!(
        diff <= tol,
        "{what}: got {actual:?}, want {expected:?} (difference {diff:e} > tolerance {tol:e})"
    );
}

/// The unit vector along `v`.
pub fn unit<V: Vector>(v: V) -> V {
    v * (1.0 / v.length())
}

/// `v` with its component along the unit vector `n` removed.
pub fn tangential<V: Vector>(v: V, n: V) -> V {
    v - n * v.dot(n)
}

/// `v` reflected off a surface with unit normal `n` (the normal component reversed).
pub fn reflect<V: Vector>(v: V, n: V) -> V {
    v - n * (2.0 * v.dot(n))
}

/// Every critter's (id index, id generation, position and velocity bits), in slot order.
pub type StateBits = Vec<(u32, u32, Vec<u64>)>;

/// The [`StateBits`] of a world.
pub fn state_bits<V: Vector>(world: &World<V>) -> StateBits {
    world
        .critters()
        .iter()
        .map(|c| {
            let mut bits = Vec::with_capacity(2 * V::DIM);
            for axis in 0..V::DIM {
                bits.push(c.pos.get(axis).to_bits());
                bits.push(c.vel.get(axis).to_bits());
            }
            (c.id().index, c.id().generation, bits)
        })
        .collect()
}

/// Distance from point `p` to the axis-aligned box [lo, hi] (0 inside), computed independently
/// of the engine's wall code.
pub fn distance_to_aligned_box<V: Vector>(p: V, lo: V, hi: V) -> f64 {
    let mut d2 = 0.0;
    for axis in 0..V::DIM {
        let x = p.get(axis);
        let gap = if x < lo.get(axis) {
            lo.get(axis) - x
        } else if x > hi.get(axis) {
            x - hi.get(axis)
        } else {
            0.0
        };
        d2 += gap * gap;
    }
    d2.sqrt()
}

// ----- native test kinds ----------------------------------------------------------------------

/// (caller, arg) of every `collide` call, in call order.
pub type CallLog = Rc<RefCell<Vec<(CritterId, CritterId)>>>;

/// A new, empty call log.
pub fn call_log() -> CallLog {
    Rc::new(RefCell::new(Vec::new()))
}

/// A kind that records who called whom, optionally overrides Pop's `collidesWith` against
/// non-walls, counts how often it was asked, and otherwise behaves like a plain ball.
pub struct Recorder {
    /// Where `collide` calls are written.
    pub log: CallLog,
    /// The answer to `collides_with` against non-walls; Pop's default when `None`.
    pub rule: Option<CollideRule>,
    /// Number of `collides_with` calls.
    pub asked: Cell<u64>,
    /// Whether the rule may not be cached.
    pub state_dependent: bool,
}

impl Recorder {
    /// A recorder with Pop's default rule.
    pub fn new(log: &CallLog) -> Self {
        Recorder {
            log: log.clone(),
            rule: None,
            asked: Cell::new(0),
            state_dependent: false,
        }
    }
    /// A recorder answering `rule` to every non-wall.
    pub fn saying(log: &CallLog, rule: CollideRule) -> Self {
        Recorder {
            rule: Some(rule),
            ..Recorder::new(log)
        }
    }
}

impl<V: Vector> KindHooks<V> for Recorder {
    fn collides_with(&self, ctx: &RuleCtx<'_, V>) -> Result<CollideRule, Error> {
        self.asked.set(self.asked.get() + 1);
        Ok(match self.rule {
            Some(rule) if !ctx.other.is_wall() => rule,
            _ => default_collides_with(ctx.me, ctx.other),
        })
    }
    fn rule_depends_on_state(&self) -> bool {
        self.state_dependent
    }
    fn collide(&self, ctx: &mut CollideCtx<'_, V>) -> Result<bool, Error> {
        self.log
            .borrow_mut()
            .push((ctx.me().id(), ctx.other().id()));
        Ok(ctx.collide_default())
    }
}

/// Pop's bullet: touching a critter of kind `target` (or a kind extending it) damages it by 1
/// and dies, with no bounce; anything else is collided with normally.
pub struct Bullet;

impl<V: Vector> KindHooks<V> for Bullet {
    fn collide(&self, ctx: &mut CollideCtx<'_, V>) -> Result<bool, Error> {
        let target = ctx.kinds().id("target")?;
        let other = ctx.other().id();
        if ctx.is_kind(other, target) {
            ctx.damage(other, 1.0);
            ctx.die_me();
            Ok(true)
        } else {
            Ok(ctx.collide_default())
        }
    }
}

/// Pop's cCritterBasket: kills what it contains, ignores what it only touches.
pub struct Basket;

impl<V: Vector> KindHooks<V> for Basket {
    fn collide(&self, ctx: &mut CollideCtx<'_, V>) -> Result<bool, Error> {
        if ctx.contains() {
            ctx.die_other();
            Ok(true)
        } else {
            Ok(false)
        }
    }
}

/// Pop's sensitive armed player: a normal collision, then damage(1) to itself unless the other
/// is a wall.
pub struct Player;

impl<V: Vector> KindHooks<V> for Player {
    fn collide(&self, ctx: &mut CollideCtx<'_, V>) -> Result<bool, Error> {
        let hit = ctx.collide_default();
        if hit && !ctx.other().is_wall() {
            let me = ctx.me().id();
            ctx.damage(me, 1.0);
        }
        Ok(hit)
    }
}
