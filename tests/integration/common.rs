//! Helpers shared by the integration tests: worlds, the motion law of one step, Pop's 1-D elastic
//! formulas, the tolerances the checks allow and checks that say what they compared, and the
//! classic kinds written natively.

use critterbox::glam::{DVec2, DVec3};
use critterbox::{
    default_collides_with, CollideCtx, CollideRule, CritterId, Error, KindDefaults, KindHooks,
    RuleCtx, Vector, World, WorldConfig, CP_BULLET, CP_PLAYER,
};
use std::cell::{Cell, RefCell};
use std::rc::Rc;

/// The default time step of a world.
pub const DT: f64 = 1.0 / 60.0;

/// Standard gravity, for the scenes that fall.
pub const G: f64 = 9.81;

// ----- tolerances -------------------------------------------------------------------------------
// f64::EPSILON is 2.2e-16; each tolerance says how much rounding the compared result went through.

/// The relative error an exact result may carry after the rounding of one step's arithmetic (a
/// few thousand ulps); absolute for positions and velocities of order one.
pub const ROUND_OFF: f64 = 1e-12;

/// A few ulps of a quantity of order one: one rounded operation or a short sum.
pub const FEW_ULPS: f64 = 1e-15;

/// The relative change of total momentum a collision may show: its impulses are equal and
/// opposite, so only the rounding of the sum of m v remains.
pub const MOMENTUM_ROUND_OFF: f64 = 1e-14;

/// The relative drift of a conserved quantity after hundreds of steps of rounded collisions.
pub const LONG_RUN_ROUND_OFF: f64 = 1e-10;

/// The absolute error positions may gather over several steps of separations and solve sweeps:
/// a pair separated to touching is within it of touching, either side.
pub const POSITION_DRIFT: f64 = 1e-9;

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

/// Registers kind `name` (no parent) with `defaults` and `hooks`.
pub fn register<V: Vector>(
    world: &mut World<V>,
    name: &str,
    defaults: KindDefaults,
    hooks: Rc<dyn KindHooks<V>>,
) {
    world
        .register_kind(name, None, defaults, hooks)
        .unwrap_or_else(|e| panic!("kind {name} should register: {e}"));
}

/// The default kind with collide priority `priority`.
pub fn with_priority(priority: f64) -> KindDefaults {
    KindDefaults {
        priority,
        ..KindDefaults::default()
    }
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

/// Asserts the velocity `after` is `before` reflected off a surface with unit normal `n`: its
/// normal component reversed and its tangential one kept, to [`ROUND_OFF`].
#[track_caller]
pub fn assert_reflected<V: Vector>(after: V, before: V, n: V, label: &str) {
    assert_close(
        after.dot(n),
        -before.dot(n),
        ROUND_OFF,
        &format!("{label}: normal velocity reversed"),
    );
    assert_close_vec(
        tangential(after, n),
        tangential(before, n),
        ROUND_OFF,
        &format!("{label}: tangential velocity kept"),
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

/// The deepest overlap of two non-wall critters of `world`, in units of `r` (0 when none overlap).
pub fn deepest_overlap<V: Vector>(world: &World<V>, r: f64) -> f64 {
    let balls: Vec<_> = world.critters().iter().filter(|c| !c.is_wall()).collect();
    let mut deepest: f64 = 0.0;
    for (i, a) in balls.iter().enumerate() {
        for b in &balls[i + 1..] {
            deepest = deepest.max((a.radius() + b.radius() - (a.pos - b.pos).length()) / r);
        }
    }
    deepest
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

/// A 10-wide 2D world with Pop's classic kinds registered: `bullet` ([`Bullet`], priority
/// CP_BULLET, radius 0.1), `target` (health 3) and `basket` ([`Basket`], priority CP_PLAYER,
/// radius 2, fixed).
pub fn classic_world() -> World<DVec2> {
    let mut world = world2(10.0);
    let bullet = KindDefaults {
        priority: CP_BULLET,
        radius: 0.1,
        ..KindDefaults::default()
    };
    register(&mut world, "bullet", bullet, Rc::new(Bullet));
    let target = KindDefaults {
        health: 3.0,
        ..KindDefaults::default()
    };
    register(&mut world, "target", target, Rc::new(()));
    let basket = KindDefaults {
        priority: CP_PLAYER,
        radius: 2.0,
        fixed: true,
        ..KindDefaults::default()
    };
    register(&mut world, "basket", basket, Rc::new(Basket));
    world
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
