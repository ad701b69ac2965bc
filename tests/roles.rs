//! Pop's collide roles: who calls `collide` on whom (priority, id, fixed, `collides_with`
//! overrides), once per touching pair per step, cached per kind pair; and the classic kinds
//! written natively against `KindHooks`: bullet, basket, sensitive player.

mod common;

use common::*;
use critterbox::glam::DVec2;
use critterbox::{
    BroadPhaseMode, CollideRule, CritterId, CritterSpec, KindDefaults, KindHooks, Rng, WallBox,
    World, WorldConfig, CP_BULLET, CP_CRITTER, CP_PLAYER,
};
use std::collections::{BTreeMap, BTreeSet};
use std::rc::Rc;

fn kind(priority: f64) -> KindDefaults {
    KindDefaults {
        priority,
        ..KindDefaults::default()
    }
}

fn register(
    world: &mut World<DVec2>,
    name: &str,
    defaults: KindDefaults,
    hooks: Rc<dyn KindHooks<DVec2>>,
) {
    world
        .register_kind(name, None, defaults, hooks)
        .expect("kind registers");
}

/// Two critters overlapping (0.9 apart, radius 0.5) and approaching.
fn spawn_pair(world: &mut World<DVec2>, first: &str, second: &str) -> (CritterId, CritterId) {
    let a = world
        .spawn(CritterSpec::new(first, DVec2::new(4.0, 5.0)).vel(DVec2::new(0.5, 0.0)))
        .unwrap();
    let b = world
        .spawn(CritterSpec::new(second, DVec2::new(4.9, 5.0)).vel(DVec2::new(-0.5, 0.0)))
        .unwrap();
    (a, b)
}

#[test]
fn higher_priority_critter_is_the_caller_whatever_the_spawn_order() {
    for high_first in [true, false] {
        let log = call_log();
        let mut world = world2(10.0);
        register(
            &mut world,
            "low",
            kind(CP_CRITTER),
            Rc::new(Recorder::new(&log)),
        );
        register(
            &mut world,
            "high",
            kind(CP_PLAYER),
            Rc::new(Recorder::new(&log)),
        );
        let (a, b) = if high_first {
            spawn_pair(&mut world, "high", "low")
        } else {
            spawn_pair(&mut world, "low", "high")
        };
        let (high, low) = if high_first { (a, b) } else { (b, a) };
        world.step().unwrap();
        assert_eq!(*log.borrow(), vec![(high, low)], "high first: {high_first}");
    }
}

#[test]
fn equal_priority_lets_the_lower_id_call_even_when_it_was_spawned_later() {
    let log = call_log();
    let mut world = world2(10.0);
    register(
        &mut world,
        "rec",
        kind(CP_CRITTER),
        Rc::new(Recorder::new(&log)),
    );
    let old = world
        .spawn(CritterSpec::new("rec", DVec2::new(1.0, 1.0)))
        .unwrap();
    let b = world
        .spawn(CritterSpec::new("rec", DVec2::new(4.9, 5.0)).vel(DVec2::new(-0.5, 0.0)))
        .unwrap();
    world.remove(old).unwrap();
    // The freed slot 0 is reused: the newer critter has the lower id.
    let a = world
        .spawn(CritterSpec::new("rec", DVec2::new(4.0, 5.0)).vel(DVec2::new(0.5, 0.0)))
        .unwrap();
    assert!(
        a < b && a.index < b.index,
        "test setup: the later spawn reuses the lower slot"
    );
    world.step().unwrap();
    assert_eq!(*log.borrow(), vec![(a, b)]);
}

#[test]
fn two_fixed_critters_never_collide() {
    let log = call_log();
    let mut world = world2(10.0);
    register(
        &mut world,
        "rec",
        kind(CP_CRITTER),
        Rc::new(Recorder::new(&log)),
    );
    let a = world
        .spawn(CritterSpec::new("rec", DVec2::new(4.0, 5.0)).fixed(true))
        .unwrap();
    let b = world
        .spawn(CritterSpec::new("rec", DVec2::new(4.6, 5.0)).fixed(true))
        .unwrap();
    world.step().unwrap();
    assert!(
        log.borrow().is_empty(),
        "collide was called on two fixed critters"
    );
    assert_eq!(world.stats().ruled, 0);
    assert_eq!(
        world.get(a).unwrap().pos,
        DVec2::new(4.0, 5.0),
        "fixed critters were separated"
    );
    assert_eq!(world.get(b).unwrap().pos, DVec2::new(4.6, 5.0));
    // Control: free one of them and the pair collides.
    world.get_mut(b).unwrap().set_fixed(false);
    world.step().unwrap();
    assert_eq!(log.borrow().len(), 1);
}

/// DontCollide from either side: no call, the pair passes through, velocities unchanged.
#[test]
fn dont_collide_from_one_side_means_no_collision() {
    for ghost_first in [true, false] {
        let log = call_log();
        let mut world = world2(10.0);
        register(
            &mut world,
            "rec",
            kind(CP_CRITTER),
            Rc::new(Recorder::new(&log)),
        );
        let ghost = Recorder::saying(&log, CollideRule::DontCollide);
        register(&mut world, "ghost", kind(CP_PLAYER), Rc::new(ghost));
        let (a, b) = if ghost_first {
            spawn_pair(&mut world, "ghost", "rec")
        } else {
            spawn_pair(&mut world, "rec", "ghost")
        };
        world.step().unwrap();
        assert!(log.borrow().is_empty());
        assert!(world.events().collisions.is_empty());
        assert_eq!(world.get(a).unwrap().vel, DVec2::new(0.5, 0.0));
        assert_eq!(world.get(b).unwrap().vel, DVec2::new(-0.5, 0.0));
    }
}

#[test]
fn as_caller_and_as_arg_overrides_flip_the_roles() {
    // Equal priority, so the lower id would call: an override from either side decides instead.
    let log = call_log();
    let mut world = world2(10.0);
    register(
        &mut world,
        "rec",
        kind(CP_CRITTER),
        Rc::new(Recorder::new(&log)),
    );
    register(
        &mut world,
        "pushy",
        kind(CP_CRITTER),
        Rc::new(Recorder::saying(&log, CollideRule::AsCaller)),
    );
    let (rec, pushy) = spawn_pair(&mut world, "rec", "pushy");
    world.step().unwrap();
    assert_eq!(
        *log.borrow(),
        vec![(pushy, rec)],
        "AsCaller from the higher id"
    );

    let log = call_log();
    let mut world = world2(10.0);
    register(
        &mut world,
        "rec",
        kind(CP_CRITTER),
        Rc::new(Recorder::new(&log)),
    );
    register(
        &mut world,
        "meek",
        kind(CP_CRITTER),
        Rc::new(Recorder::saying(&log, CollideRule::AsArg)),
    );
    let (meek, rec) = spawn_pair(&mut world, "meek", "rec");
    world.step().unwrap();
    assert_eq!(*log.borrow(), vec![(rec, meek)], "AsArg from the lower id");

    // Against priority: the low one asks to call and the high one agrees to be the argument.
    let log = call_log();
    let mut world = world2(10.0);
    register(
        &mut world,
        "bold",
        kind(CP_CRITTER),
        Rc::new(Recorder::saying(&log, CollideRule::AsCaller)),
    );
    register(
        &mut world,
        "humble",
        kind(CP_BULLET),
        Rc::new(Recorder::saying(&log, CollideRule::AsArg)),
    );
    let (humble, bold) = spawn_pair(&mut world, "humble", "bold");
    world.step().unwrap();
    assert_eq!(
        *log.borrow(),
        vec![(bold, humble)],
        "the lower priority calls when both agree"
    );
}

/// Zero velocities, so the touching pairs of the step are those of the starting positions.
#[test]
fn each_touching_pair_is_handled_exactly_once_per_step() {
    let log = call_log();
    let mut world = world2(20.0);
    register(
        &mut world,
        "rec",
        kind(CP_CRITTER),
        Rc::new(Recorder::new(&log)),
    );
    let mut rng = Rng::new(11);
    for _ in 0..200 {
        let p = DVec2::new(rng.uniform(3.0, 13.0), rng.uniform(3.0, 13.0));
        world
            .spawn(CritterSpec::new("rec", p).radius(rng.uniform(0.2, 0.5)))
            .unwrap();
    }
    for step in 0..3 {
        // Pairs separated in the step before are left exactly touching, where round-off decides;
        // so: every pair clearly touching is handled, and no pair clearly apart is.
        let critters: Vec<_> = world
            .critters()
            .iter()
            .map(|c| (c.id(), c.pos, c.radius()))
            .collect();
        let (mut touching, mut near) = (BTreeSet::new(), BTreeSet::new());
        for (i, a) in critters.iter().enumerate() {
            for b in &critters[i + 1..] {
                let gap = (b.1 - a.1).length() - (a.2 + b.2);
                if gap < -1e-9 {
                    touching.insert((a.0, b.0));
                }
                if gap <= 1e-9 {
                    near.insert((a.0, b.0));
                }
            }
        }
        assert!(touching.len() > 20, "test setup: a crowd");
        log.borrow_mut().clear();
        world.step().unwrap();
        let mut calls: BTreeMap<(CritterId, CritterId), usize> = BTreeMap::new();
        for &(me, other) in log.borrow().iter() {
            *calls.entry((me.min(other), me.max(other))).or_default() += 1;
        }
        let twice: Vec<_> = calls.iter().filter(|(_, &n)| n != 1).collect();
        assert!(
            twice.is_empty(),
            "step {step}: pairs handled more than once: {twice:?}"
        );
        let handled: BTreeSet<_> = calls.keys().copied().collect();
        let missed: Vec<_> = touching.difference(&handled).collect();
        assert!(
            missed.is_empty(),
            "step {step}: touching pairs not handled: {missed:?}"
        );
        let extra: Vec<_> = handled.difference(&near).collect();
        assert!(
            extra.is_empty(),
            "step {step}: pairs handled that do not touch: {extra:?}"
        );
    }
}

/// 1000 critters of three kinds meeting in thousands of pairs: the roles are asked of the hooks
/// once per class pair, not per critter pair.
#[test]
fn collide_roles_are_cached_per_kind_pair_however_many_critters() {
    let log = call_log();
    let red = Rc::new(Recorder::new(&log));
    let blue = Rc::new(Recorder::new(&log));
    let mut world = world2(40.0);
    world
        .add_wall(WallBox::segment(DVec2::new(5.0, 20.0), DVec2::new(35.0, 20.0), 0.3).unwrap())
        .unwrap();
    register(&mut world, "red", kind(CP_CRITTER), red.clone());
    register(&mut world, "blue", kind(CP_PLAYER), blue.clone());
    let mut rng = Rng::new(3);
    for i in 0..1000 {
        let name = ["ball", "red", "blue"][i % 3];
        let p = DVec2::new(rng.uniform(1.0, 39.0), rng.uniform(1.0, 39.0));
        if (p.y - 20.0).abs() < 1.0 {
            continue;
        }
        let v = DVec2::new(rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0));
        world
            .spawn(CritterSpec::new(name, p).vel(v).radius(0.4))
            .unwrap();
    }
    world.run(30).unwrap();
    let classes = world.diagnostics().rule_cache.classes();
    assert_eq!(classes, 4, "ball, red, blue and wall");
    let class_pairs = (classes * (classes + 1) / 2) as u64;
    let computed = world.diagnostics().rule_cache.computed();
    assert!(
        computed <= class_pairs,
        "{computed} role computations for {class_pairs} class pairs"
    );
    let asked = red.asked.get() + blue.asked.get();
    assert!(
        asked <= 2 * computed,
        "hooks asked {asked} times for {computed} computed class pairs"
    );
    assert!(
        world.totals().ruled > 100 * class_pairs as usize,
        "test setup: many more critter pairs than class pairs"
    );
    world.run(10).unwrap();
    assert_eq!(
        world.diagnostics().rule_cache.computed(),
        computed,
        "nothing new to compute"
    );
}

#[test]
fn kind_whose_rule_depends_on_state_is_asked_for_every_pair_every_step() {
    let log = call_log();
    let moody = Rc::new(Recorder {
        state_dependent: true,
        ..Recorder::new(&log)
    });
    let mut world = world2(10.0);
    register(&mut world, "moody", kind(CP_CRITTER), moody.clone());
    for i in 0..6 {
        world
            .spawn(CritterSpec::new(
                "moody",
                DVec2::new(3.0 + 0.8 * i as f64, 5.0),
            ))
            .unwrap();
    }
    world.run(5).unwrap();
    let candidates = world.totals().candidates as u64;
    assert!(
        candidates >= 25,
        "test setup: neighbours are candidates every step"
    );
    assert_eq!(
        moody.asked.get(),
        2 * candidates,
        "both sides asked for every candidate pair"
    );
    assert_eq!(
        world.diagnostics().rule_cache.computed(),
        0,
        "nothing cached"
    );
}

/// A crowd large enough for the rules and narrow phase to run with the broad phase's re-test of
/// its Verlet list, with a kind whose rule depends on state among plain balls: whenever two of
/// them touch, that is refused and the stages run one after the other. The same hooks are asked,
/// the same `collide` calls made in the same order, and the same states reached as with the plain
/// grid, which keeps no list.
#[test]
fn a_large_crowd_whose_rule_depends_on_state_meets_as_with_the_plain_grid() {
    let run = |mode: BroadPhaseMode| {
        let log = call_log();
        let moody = Rc::new(Recorder {
            state_dependent: true,
            ..Recorder::new(&log)
        });
        let mut config = WorldConfig::new(DVec2::ZERO, DVec2::splat(300.0));
        config.broad_phase = mode;
        let mut world = World::new(config).unwrap();
        register(&mut world, "moody", kind(CP_CRITTER), moody.clone());
        let mut rng = Rng::new(8);
        for i in 0..22_000 {
            let name = if i % 4 == 0 { "moody" } else { "ball" };
            let p = DVec2::new(rng.uniform(1.0, 299.0), rng.uniform(1.0, 299.0));
            let v = DVec2::new(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0));
            world.spawn(CritterSpec::new(name, p).vel(v)).unwrap();
        }
        let hashes: Vec<u64> = (0..10)
            .map(|_| {
                world.step().unwrap();
                world.state_hash()
            })
            .collect();
        let calls = log.borrow().clone();
        (hashes, moody.asked.get(), calls)
    };
    let listed = run(BroadPhaseMode::Auto);
    assert!(listed.1 > 100, "test setup: moody critters touched");
    assert_eq!(listed, run(BroadPhaseMode::Grid));
}

// ----- the classic kinds ------------------------------------------------------------------------

fn bullet_world() -> World<DVec2> {
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
    world
}

#[test]
fn bullet_damages_a_target_and_dies_without_bouncing_it() {
    let mut world = bullet_world();
    let t = world
        .spawn(CritterSpec::new("target", DVec2::new(5.0, 5.0)).vel(DVec2::new(0.0, 0.3)))
        .unwrap();
    let b = world
        .spawn(CritterSpec::new("bullet", DVec2::new(4.45, 5.0)).vel(DVec2::new(6.0, 0.0)))
        .unwrap();
    world.step().unwrap();
    let target = world.get(t).unwrap();
    assert_eq!(target.health(), 2.0);
    assert_eq!(target.vel, DVec2::new(0.0, 0.3), "no bounce");
    assert_eq!(
        target.pos,
        DVec2::new(5.0, 5.0) + DVec2::new(0.0, 0.3) * world.dt(),
        "no push"
    );
    assert!(world.get(b).is_none(), "the bullet died");
    assert_eq!(world.events().damages, vec![(t, 1.0)]);
    assert_eq!(world.events().deaths, vec![b]);
    // The hit is reported as a collision of the bullet with the target, with no impulse.
    let events = &world.events().collisions;
    assert_eq!(events.len(), 1, "one collision: the hit");
    assert_eq!((events[0].caller, events[0].arg), (b, t));
    assert_eq!(events[0].impulse, 0.0, "no default collision, no impulse");
}

#[test]
fn bullet_collides_normally_with_a_non_target() {
    let mut world = bullet_world();
    let (mb, mo) = (0.001, 0.125); // radius 0.1 at density 1; radius 0.5 at density 1
    let o = world
        .spawn(CritterSpec::ball(DVec2::new(5.0, 5.0)))
        .unwrap();
    let b = world
        .spawn(CritterSpec::new("bullet", DVec2::new(4.45, 5.0)).vel(DVec2::new(6.0, 0.0)))
        .unwrap();
    world.step().unwrap();
    assert_eq!(world.events().collisions.len(), 1);
    assert_eq!(
        world.events().collisions[0].caller,
        b,
        "the bullet's priority makes it the caller"
    );
    let (vb, vo) = pop_elastic(6.0, 0.0, mo / mb);
    assert_close_vec(
        world.get(b).unwrap().vel,
        DVec2::new(vb, 0.0),
        1e-12,
        "bullet bounced",
    );
    assert_close_vec(
        world.get(o).unwrap().vel,
        DVec2::new(vo, 0.0),
        1e-12,
        "ball pushed",
    );
    assert_eq!(world.get(o).unwrap().health(), 1.0, "no damage");
}

#[test]
fn basket_kills_what_it_contains_and_ignores_what_it_only_touches() {
    let mut world = world2(10.0);
    let basket = KindDefaults {
        priority: CP_PLAYER,
        radius: 2.0,
        fixed: true,
        ..KindDefaults::default()
    };
    register(&mut world, "basket", basket, Rc::new(Basket));
    world
        .spawn(CritterSpec::new("basket", DVec2::new(5.0, 5.0)))
        .unwrap();
    let inside = world
        .spawn(CritterSpec::ball(DVec2::new(5.5, 5.2)).radius(0.3))
        .unwrap();
    let (edge_pos, edge_vel) = (DVec2::new(5.0, 6.8), DVec2::new(0.1, -0.5));
    let edge = world
        .spawn(CritterSpec::ball(edge_pos).vel(edge_vel).radius(0.5))
        .unwrap();
    world.step().unwrap();
    assert!(world.get(inside).is_none(), "the contained ball died");
    let e = world.get(edge).expect("the touching ball lives");
    assert_eq!(e.vel, edge_vel, "not bounced");
    assert_eq!(e.pos, edge_pos + edge_vel * world.dt(), "not pushed");
    assert_eq!(world.stats().contacts, 2);
    assert_eq!(
        world.stats().collisions,
        1,
        "only the contained one counts as handled"
    );
}

#[test]
fn sensitive_player_takes_damage_from_critters_but_not_from_walls() {
    let mut world = world2(10.0);
    let player = KindDefaults {
        priority: CP_PLAYER,
        health: 5.0,
        ..KindDefaults::default()
    };
    register(&mut world, "player", player, Rc::new(Player));
    world
        .add_wall(WallBox::segment(DVec2::new(1.0, 2.0), DVec2::new(9.0, 2.0), 0.2).unwrap())
        .unwrap();
    let p = world
        .spawn(CritterSpec::new("player", DVec2::new(5.0, 2.605)).vel(DVec2::new(0.0, -1.0)))
        .unwrap();
    world.step().unwrap();
    assert_eq!(world.events().collisions.len(), 1, "bounced off the wall");
    assert_eq!(world.get(p).unwrap().health(), 5.0, "walls do no damage");
    assert!(world.get(p).unwrap().vel.y > 0.0);

    let b = world
        .spawn(CritterSpec::ball(DVec2::new(5.0, 3.5)).vel(DVec2::new(0.0, -1.0)))
        .unwrap();
    world.step().unwrap();
    assert_eq!(
        world.events().collisions[0].caller,
        p,
        "the player calls against a critter"
    );
    assert_eq!(
        world.get(p).unwrap().health(),
        4.0,
        "damaged by the critter"
    );
    assert_eq!(world.get(b).unwrap().health(), 1.0, "the critter is not");
}

#[test]
fn kind_registered_with_a_parent_is_kind_of_the_parent() {
    let mut world = bullet_world();
    let silver = KindDefaults {
        priority: CP_BULLET,
        radius: 0.1,
        ..KindDefaults::default()
    };
    let silver_id = world
        .register_kind("silver", Some("bullet"), silver, Rc::new(Bullet))
        .unwrap();
    let armored = KindDefaults {
        health: 2.0,
        ..KindDefaults::default()
    };
    world
        .register_kind("armored", Some("target"), armored, Rc::new(()))
        .unwrap();
    let bullet_id = world.kinds().id("bullet").unwrap();
    assert!(world.kinds().is_kind(silver_id, bullet_id));
    assert!(
        !world.kinds().is_kind(bullet_id, silver_id),
        "a parent is not kind of its child"
    );
    let s = world
        .spawn(CritterSpec::new("silver", DVec2::new(4.45, 5.0)).vel(DVec2::new(6.0, 0.0)))
        .unwrap();
    assert_eq!(world.critters_of("bullet").unwrap(), vec![s]);
    // The bullet hook's ctx.is_kind(target) sees the armored kind as a target.
    let a = world
        .spawn(CritterSpec::new("armored", DVec2::new(5.0, 5.0)))
        .unwrap();
    world.step().unwrap();
    assert_eq!(
        world.get(a).unwrap().health(),
        1.0,
        "the armored target took the bullet's damage"
    );
    assert!(world.get(s).is_none());
}
