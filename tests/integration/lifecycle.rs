//! Deaths, spawns and ids: a critter killed in a step takes no further part in it and is removed
//! after it; ids are generational; spawns queued by hooks appear after the step; damage kills at
//! or below zero health.

use crate::common;

use common::*;
use critterbox::glam::DVec2;
use critterbox::{
    CollideCtx, CritterId, CritterSpec, Error, KindDefaults, KindHooks, UpdateCtx, World, CP_PLAYER,
};
use std::cell::Cell;
use std::rc::Rc;

fn count(world: &World<DVec2>, kind: &str) -> usize {
    world.count_by_kind().get(kind).copied().unwrap_or(0)
}

#[test]
fn bullet_touching_two_targets_at_once_damages_only_one() {
    let mut world = classic_world();
    let b = world
        .spawn(CritterSpec::new("bullet", DVec2::new(5.0, 5.0)))
        .unwrap();
    let t1 = world
        .spawn(CritterSpec::new("target", DVec2::new(4.45, 5.0)))
        .unwrap();
    let t2 = world
        .spawn(CritterSpec::new("target", DVec2::new(5.55, 5.0)))
        .unwrap();
    assert_eq!(count(&world, "bullet"), 1);
    world.step().unwrap();
    assert_eq!(
        world.stats().contacts,
        2,
        "test setup: the bullet touches both"
    );
    // Response order is by id: the bullet meets t1 first, dies, and never meets t2.
    assert_eq!(world.get(t1).unwrap().health(), 2.0);
    assert_eq!(
        world.get(t2).unwrap().health(),
        3.0,
        "a dead bullet damaged a second target"
    );
    assert_eq!(world.events().damages, vec![(t1, 1.0)]);
    assert_eq!(world.events().deaths, vec![b]);
    assert!(world.get(b).is_none(), "removed after the step");
    assert_eq!(count(&world, "bullet"), 0);
    assert_eq!(count(&world, "target"), 2);
}

/// The basket (lowest id) kills ball 1, which also touches ball 2: the (1, 2) pair is skipped.
#[test]
fn critter_killed_in_a_step_takes_no_further_collisions_in_it() {
    let (p1, p2, v2) = (
        DVec2::new(6.2, 5.0),
        DVec2::new(7.0, 5.0),
        DVec2::new(-1.0, 0.0),
    );
    // Control: without the basket the two balls collide in this step.
    let mut control = classic_world();
    control.spawn(CritterSpec::ball(p1).radius(0.5)).unwrap();
    let c2 = control
        .spawn(CritterSpec::ball(p2).vel(v2).radius(0.5))
        .unwrap();
    control.step().unwrap();
    assert_ne!(
        control.get(c2).unwrap().vel,
        v2,
        "test setup: the balls collide"
    );

    let mut world = classic_world();
    world
        .spawn(CritterSpec::new("basket", DVec2::new(5.0, 5.0)))
        .unwrap();
    let b1 = world.spawn(CritterSpec::ball(p1).radius(0.5)).unwrap();
    let b2 = world
        .spawn(CritterSpec::ball(p2).vel(v2).radius(0.5))
        .unwrap();
    assert_eq!(count(&world, "ball"), 2);
    world.step().unwrap();
    assert_eq!(
        world.stats().contacts,
        3,
        "basket-1, basket-2 and 1-2 all touch"
    );
    assert_eq!(world.events().deaths, vec![b1]);
    let ball2 = world.get(b2).unwrap();
    assert_eq!(
        ball2.vel, v2,
        "the pair with the dead ball was still handled"
    );
    assert_eq!(
        ball2.pos,
        p2 + v2 * world.dt(),
        "ball 2 was pushed by a dead ball"
    );
    // Only the catch is reported (basket and ball 1, no impulse): the pair of ball 1 and ball 2
    // was skipped because ball 1 had died.
    let events = &world.events().collisions;
    assert_eq!(events.len(), 1, "{events:?}");
    assert_eq!(events[0].arg, b1);
    assert_eq!(events[0].impulse, 0.0);
    assert!(world.get(b1).is_none());
    assert_eq!(count(&world, "ball"), 1);
}

/// A kind that dies in its own update: it never reaches the collide stage.
struct Mayfly;

impl KindHooks<DVec2> for Mayfly {
    fn has_update(&self) -> bool {
        true
    }
    fn update(&self, ctx: &mut UpdateCtx<'_, DVec2>, _dt: f64) -> Result<(), Error> {
        ctx.die_me();
        Ok(())
    }
}

#[test]
fn critter_that_dies_in_update_takes_no_collision_that_step() {
    let mut world = world2(10.0);
    register(
        &mut world,
        "mayfly",
        KindDefaults::default(),
        Rc::new(Mayfly),
    );
    let m = world
        .spawn(CritterSpec::new("mayfly", DVec2::new(5.0, 5.0)))
        .unwrap();
    let (p, v) = (DVec2::new(5.8, 5.0), DVec2::new(-1.0, 0.0));
    let b = world.spawn(CritterSpec::ball(p).vel(v)).unwrap();
    world.step().unwrap();
    assert!(world.events().collisions.is_empty());
    assert_eq!(world.get(b).unwrap().vel, v);
    assert!(world.get(m).is_none());
    assert_eq!(world.events().deaths, vec![m]);
}

#[test]
fn ids_are_generational_so_a_dead_critters_id_never_names_its_successor() {
    let mut world = classic_world();
    let b = world
        .spawn(CritterSpec::new("bullet", DVec2::new(5.0, 5.0)))
        .unwrap();
    world
        .spawn(CritterSpec::new("target", DVec2::new(4.45, 5.0)))
        .unwrap();
    world.step().unwrap();
    assert!(world.get(b).is_none());
    let new = world
        .spawn(CritterSpec::ball(DVec2::new(2.0, 2.0)))
        .unwrap();
    assert_eq!(new.index, b.index, "test setup: the slot is reused");
    assert_ne!(new, b);
    assert!(new.generation > b.generation);
    assert!(world.get(b).is_none(), "the old id names the new critter");
    assert!(world.get_mut(b).is_none());
    assert!(matches!(world.remove(b), Err(Error::NoSuchCritter(id)) if id == b));
    assert_eq!(world.get(new).unwrap().pos, DVec2::new(2.0, 2.0));
    // Removing the new one works and frees the slot again, with yet another generation.
    world.remove(new).unwrap();
    let newer = world
        .spawn(CritterSpec::ball(DVec2::new(3.0, 3.0)))
        .unwrap();
    assert_eq!(newer.index, b.index);
    assert!(newer.generation > new.generation);
    assert!(world.get(new).is_none() && world.get(b).is_none());
}

/// On collide: bounce, then queue a ball at `at`, recording how many critters the hook saw.
struct Spawner {
    at: DVec2,
    seen: Cell<usize>,
}

impl KindHooks<DVec2> for Spawner {
    fn collide(&self, ctx: &mut CollideCtx<'_, DVec2>) -> Result<bool, Error> {
        let hit = ctx.collide_default();
        let ball = ctx.kinds().id("ball")?;
        self.seen.set(ctx.critters_of(ball).len());
        ctx.spawn(CritterSpec::ball(self.at).vel(DVec2::new(0.25, 0.0)));
        Ok(hit)
    }
}

#[test]
fn spawns_queued_from_a_hook_appear_after_the_step() {
    let at = DVec2::new(2.0, 8.0);
    let spawner = Rc::new(Spawner {
        at,
        seen: Cell::new(0),
    });
    let mut world = world2(10.0);
    register(
        &mut world,
        "spawner",
        with_priority(CP_PLAYER),
        spawner.clone(),
    );
    world
        .spawn(CritterSpec::new("spawner", DVec2::new(5.0, 5.0)))
        .unwrap();
    world
        .spawn(CritterSpec::ball(DVec2::new(5.9, 5.0)).vel(DVec2::new(-1.0, 0.0)))
        .unwrap();
    assert_eq!(world.critters().len(), 2);
    world.step().unwrap();
    assert_eq!(
        spawner.seen.get(),
        1,
        "the hook saw the queued ball already"
    );
    assert_eq!(world.critters().len(), 3);
    let spawns = world.events().spawns.clone();
    assert_eq!(spawns.len(), 1);
    let c = world.get(spawns[0]).expect("the spawned critter is there");
    // Added after the move: it has not moved yet, and took part in no collision.
    assert_eq!(c.pos, at);
    assert_eq!(c.vel, DVec2::new(0.25, 0.0));
    assert!(world
        .events()
        .collisions
        .iter()
        .all(|e| e.caller != c.id() && e.arg != c.id()));
    world.step().unwrap();
    assert_eq!(
        world.get(spawns[0]).unwrap().pos,
        at + DVec2::new(0.25, 0.0) * world.dt(),
        "moves from the next step"
    );
}

/// A death and a queued spawn in the same step: deaths go first, so the spawn may take the dead
/// critter's slot, under a new generation.
#[test]
fn spawn_queued_in_the_step_a_critter_dies_reuses_its_slot_under_a_new_id() {
    struct Killer;
    impl KindHooks<DVec2> for Killer {
        fn collide(&self, ctx: &mut CollideCtx<'_, DVec2>) -> Result<bool, Error> {
            ctx.die_other();
            ctx.spawn(CritterSpec::ball(DVec2::new(8.0, 8.0)));
            Ok(true)
        }
    }
    let mut world = world2(10.0);
    register(
        &mut world,
        "killer",
        with_priority(CP_PLAYER),
        Rc::new(Killer),
    );
    world
        .spawn(CritterSpec::new("killer", DVec2::new(5.0, 5.0)))
        .unwrap();
    let victim = world
        .spawn(CritterSpec::ball(DVec2::new(5.9, 5.0)))
        .unwrap();
    world.step().unwrap();
    let new = world.events().spawns[0];
    assert_eq!(world.events().deaths, vec![victim]);
    assert_eq!(new.index, victim.index);
    assert_ne!(new, victim);
    assert!(world.get(victim).is_none());
    assert_eq!(world.get(new).unwrap().pos, DVec2::new(8.0, 8.0));
}

/// Damages the other by `amount` on every touch, no bounce.
struct Hitter {
    amount: f64,
}

impl KindHooks<DVec2> for Hitter {
    fn collide(&self, ctx: &mut CollideCtx<'_, DVec2>) -> Result<bool, Error> {
        let other = ctx.other().id();
        ctx.damage(other, self.amount);
        Ok(true)
    }
}

fn hitter_world(amount: f64) -> World<DVec2> {
    let mut world = world2(10.0);
    let hitter = Rc::new(Hitter { amount });
    register(&mut world, "hitter", with_priority(CP_PLAYER), hitter);
    world
}

#[test]
fn damage_kills_at_zero_health_and_not_before() {
    let mut world = hitter_world(0.5);
    world
        .spawn(CritterSpec::new("hitter", DVec2::new(5.0, 5.0)))
        .unwrap();
    let v = world
        .spawn(CritterSpec::ball(DVec2::new(5.9, 5.0)).health(1.0))
        .unwrap();
    world.step().unwrap();
    assert_eq!(world.get(v).unwrap().health(), 0.5);
    assert!(world.get(v).unwrap().is_alive());
    assert!(world.events().deaths.is_empty());
    world.step().unwrap();
    assert_eq!(world.events().deaths, vec![v], "health exactly 0 kills");
    assert!(world.get(v).is_none());
}

#[test]
fn damage_below_zero_kills_once_even_when_two_critters_hit() {
    let mut world = hitter_world(3.0);
    world
        .spawn(CritterSpec::new("hitter", DVec2::new(4.1, 5.0)))
        .unwrap();
    world
        .spawn(CritterSpec::new("hitter", DVec2::new(5.9, 5.0)))
        .unwrap();
    let v: CritterId = world
        .spawn(CritterSpec::ball(DVec2::new(5.0, 5.0)).health(1.0))
        .unwrap();
    world.step().unwrap();
    assert_eq!(
        world.stats().contacts,
        2,
        "test setup: both hitters touch the victim"
    );
    assert_eq!(
        world.events().damages,
        vec![(v, 3.0)],
        "a dead critter took more damage"
    );
    assert_eq!(world.events().deaths, vec![v]);
    assert!(world.get(v).is_none());
    assert_eq!(world.critters().len(), 2);
}

/// A kind that dies as soon as it is spawned (in `init`, outside any step).
struct Stillborn;

impl KindHooks<DVec2> for Stillborn {
    fn has_init(&self) -> bool {
        true
    }
    fn init(&self, ctx: &mut UpdateCtx<'_, DVec2>) -> Result<(), Error> {
        ctx.die_me();
        Ok(())
    }
}

/// A world with one stillborn critter at (5, 5), dead but not yet removed.
fn stillborn_world() -> (World<DVec2>, CritterId) {
    let mut world = world2(10.0);
    register(
        &mut world,
        "stillborn",
        KindDefaults::default(),
        Rc::new(Stillborn),
    );
    let s = world
        .spawn(CritterSpec::new("stillborn", DVec2::splat(5.0)))
        .unwrap();
    (world, s)
}

/// The death is filed at once and carried out at the end of the next step, like any other; the
/// step that removes the critter should report the death, or a recording never shows it.
#[test]
fn critter_killed_in_its_init_hook_is_removed_and_reported_by_the_next_step() {
    let (mut world, s) = stillborn_world();
    assert!(
        !world.get(s).unwrap().is_alive(),
        "dead but not yet removed"
    );
    world.step().unwrap();
    assert!(world.get(s).is_none(), "removed after the step");
    assert_eq!(
        world.events().deaths,
        vec![s],
        "the death was never reported"
    );
}

#[test]
fn critter_killed_in_its_init_hook_takes_no_part_and_is_removed_after_the_next_step() {
    let (mut world, s) = stillborn_world();
    let (p, v) = (DVec2::new(5.9, 5.0), DVec2::new(-1.0, 0.0));
    let b = world.spawn(CritterSpec::ball(p).vel(v)).unwrap();
    assert_eq!(count(&world, "stillborn"), 0, "the dead are not counted");
    world.step().unwrap();
    assert!(world.get(s).is_none());
    assert!(world.events().collisions.is_empty());
    assert_eq!(world.get(b).unwrap().vel, v);
}

#[test]
fn damage_and_the_death_it_causes_name_the_hook_that_did_it() {
    use critterbox::{DamageInfo, DeathCause, DeathInfo, HookAt};
    let mut world = hitter_world(0.5);
    let hitter = world
        .spawn(CritterSpec::new("hitter", DVec2::new(5.0, 5.0)))
        .unwrap();
    let v = world
        .spawn(CritterSpec::ball(DVec2::new(5.9, 5.0)).health(1.0))
        .unwrap();
    let ball = world.kinds().id("ball").unwrap();
    let by = Some(HookAt {
        critter: hitter,
        hook: "collide",
    });
    world.step().unwrap();
    assert_eq!(world.events().damages, vec![(v, 0.5)]);
    assert_eq!(
        world.events().damage_info,
        vec![DamageInfo {
            kind: ball,
            source: by
        }]
    );
    world.step().unwrap();
    assert_eq!(world.events().deaths, vec![v]);
    assert_eq!(
        world.events().death_info,
        vec![DeathInfo {
            kind: ball,
            cause: DeathCause::Damage(by)
        }],
        "health at 0 after the hitter's collide"
    );
}

#[test]
fn die_in_a_hook_and_removal_by_the_scene_are_deaths_with_their_causes() {
    use critterbox::{DeathCause, HookAt};
    let mut world = world2(10.0);
    register(
        &mut world,
        "killer",
        with_priority(CP_PLAYER),
        Rc::new(Slayer),
    );
    let killer = world
        .spawn(CritterSpec::new("killer", DVec2::new(5.0, 5.0)))
        .unwrap();
    let victim = world
        .spawn(CritterSpec::ball(DVec2::new(5.9, 5.0)))
        .unwrap();
    world.step().unwrap();
    assert_eq!(world.events().deaths, vec![victim]);
    let cause = world.events().death_info[0].cause;
    assert_eq!(
        cause,
        DeathCause::Die(Some(HookAt {
            critter: killer,
            hook: "collide"
        }))
    );
    world.step().unwrap();
    world.remove(killer).unwrap();
    assert_eq!(world.events().deaths, vec![killer], "the scene's removal");
    assert_eq!(world.events().death_info[0].cause, DeathCause::Removed);
}

/// Kills what it touches.
struct Slayer;

impl KindHooks<DVec2> for Slayer {
    fn collide(&self, ctx: &mut CollideCtx<'_, DVec2>) -> Result<bool, Error> {
        ctx.die_other();
        Ok(true)
    }
}

/// A damage as `on_damage` hears of it: (me, amount, source).
type Heard = (CritterId, f64, Option<CritterId>);

/// Keeps every damage it takes.
struct Sore(Rc<std::cell::RefCell<Vec<Heard>>>);

impl KindHooks<DVec2> for Sore {
    fn has_on_damage(&self) -> bool {
        true
    }
    fn on_damage(
        &self,
        ctx: &mut UpdateCtx<'_, DVec2>,
        amount: f64,
        source: Option<CritterId>,
    ) -> Result<(), Error> {
        let me = ctx.me().id();
        self.0.borrow_mut().push((me, amount, source));
        Ok(())
    }
}

/// In its update, damages the critters of `targets` in the order given, by 1, 2, 3, ...
struct Blaster(Vec<CritterId>);

impl KindHooks<DVec2> for Blaster {
    fn has_update(&self) -> bool {
        true
    }
    fn update(&self, ctx: &mut UpdateCtx<'_, DVec2>, _dt: f64) -> Result<(), Error> {
        for (i, &t) in self.0.iter().enumerate() {
            ctx.damage(t, (i + 1) as f64);
        }
        Ok(())
    }
}

#[test]
fn on_damage_runs_once_per_damage_in_id_order_with_its_source() {
    let mut world = world2(20.0);
    let seen = Rc::new(std::cell::RefCell::new(Vec::new()));
    register(
        &mut world,
        "sore",
        KindDefaults {
            health: 100.0,
            ..KindDefaults::default()
        },
        Rc::new(Sore(seen.clone())),
    );
    let a = world
        .spawn(CritterSpec::new("sore", DVec2::new(3.0, 3.0)))
        .unwrap();
    let b = world
        .spawn(CritterSpec::new("sore", DVec2::new(6.0, 3.0)))
        .unwrap();
    register(
        &mut world,
        "blaster",
        KindDefaults::default(),
        Rc::new(Blaster(vec![b, a, b])),
    );
    let blaster = world
        .spawn(CritterSpec::new("blaster", DVec2::new(15.0, 15.0)))
        .unwrap();
    world.step().unwrap();
    assert_eq!(
        *seen.borrow(),
        vec![
            (a, 2.0, Some(blaster)),
            (b, 1.0, Some(blaster)),
            (b, 3.0, Some(blaster))
        ],
        "a's damage first (lower id), then b's two in the order dealt"
    );
    // Between steps, from the scene: at once, with no source; the killing damage too.
    seen.borrow_mut().clear();
    world.damage(a, 98.0).unwrap();
    assert_eq!(*seen.borrow(), vec![(a, 98.0, None)]);
    assert!(world.get(a).is_none(), "health at 0: removed");
    assert_eq!(
        world.events().death_info.last().map(|d| d.cause),
        Some(critterbox::DeathCause::Damage(None))
    );
}
