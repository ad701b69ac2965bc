//! Pop's collide roles: who calls `collide` on whom (priority, id, fixed, `collides_with`
//! overrides), once per touching pair per step, cached per kind pair; and the classic kinds
//! written natively against `KindHooks`: bullet, basket, sensitive player.

use crate::common;

use common::*;
use critterbox::glam::DVec2;
use critterbox::{
    BroadPhaseMode, CollideRule, CritterId, CritterSpec, KindDefaults, Rng, WallBox, World,
    WorldConfig, CP_BULLET, CP_CRITTER, CP_PLAYER,
};
use std::collections::{BTreeMap, BTreeSet};
use std::rc::Rc;

/// One side of a pair: its kind and how that kind was registered.
#[derive(Clone, Copy)]
struct Side {
    kind: &'static str,
    priority: f64,
    /// What the kind answers to `collides_with` against a non-wall; Pop's default when `None`.
    rule: Option<CollideRule>,
    fixed: bool,
}

/// A free critter of kind `kind`, Pop's default rule.
const fn free(kind: &'static str, priority: f64) -> Side {
    Side {
        kind,
        priority,
        rule: None,
        fixed: false,
    }
}

/// A free critter of kind `kind` whose kind answers `rule`.
const fn saying(kind: &'static str, priority: f64, rule: CollideRule) -> Side {
    Side {
        rule: Some(rule),
        ..free(kind, priority)
    }
}

/// A fixed critter of kind `kind`, Pop's default rule.
const fn fixed(kind: &'static str, priority: f64) -> Side {
    Side {
        fixed: true,
        ..free(kind, priority)
    }
}

#[derive(Clone, Copy, Debug)]
enum Who {
    Left,
    Right,
}

/// What must happen in the step.
#[derive(Clone, Copy)]
enum Meet {
    /// `collide` is called once, by the first on the second.
    Calls(Who, Who),
    /// No `collide` call and no collision: both keep their velocities and pass through.
    PassThrough,
    /// The pair is not even ruled and neither is moved; freed, it collides.
    NeverRuled,
}

/// A pair meeting head on: `left` at (4, 5) and `right` at (4.9, 5), overlapping and, when free,
/// approaching at 0.5 each (a fixed critter is spawned at rest). `left` is spawned first, so it
/// has the lower id, unless `left_reuses_a_lower_slot`: then `right` is spawned first and `left`
/// later, into a slot freed below it.
struct RoleCase {
    why: &'static str,
    left: Side,
    right: Side,
    left_reuses_a_lower_slot: bool,
    meet: Meet,
}

const fn case(why: &'static str, left: Side, right: Side, meet: Meet) -> RoleCase {
    RoleCase {
        why,
        left,
        right,
        left_reuses_a_lower_slot: false,
        meet,
    }
}

/// Pop's roles: the higher priority calls; at equal priority the lower id calls, unless a
/// `collides_with` override from either side decides; two fixed critters never collide.
const ROLE_CASES: [RoleCase; 11] = [
    case(
        "the higher priority calls, spawned first",
        free("high", CP_PLAYER),
        free("low", CP_CRITTER),
        Meet::Calls(Who::Left, Who::Right),
    ),
    case(
        "the higher priority calls, spawned second",
        free("low", CP_CRITTER),
        free("high", CP_PLAYER),
        Meet::Calls(Who::Right, Who::Left),
    ),
    RoleCase {
        left_reuses_a_lower_slot: true,
        ..case(
            "at equal priority the lower id calls, even when it was spawned later",
            free("rec", CP_CRITTER),
            free("rec", CP_CRITTER),
            Meet::Calls(Who::Left, Who::Right),
        )
    },
    case(
        "two fixed critters never collide",
        fixed("rec", CP_CRITTER),
        fixed("rec", CP_CRITTER),
        Meet::NeverRuled,
    ),
    case(
        "a fixed and a free critter collide: at equal priority the lower id calls",
        fixed("rec", CP_CRITTER),
        free("rec", CP_CRITTER),
        Meet::Calls(Who::Left, Who::Right),
    ),
    case(
        "DontCollide from the higher priority, spawned first: no collision",
        saying("ghost", CP_PLAYER, CollideRule::DontCollide),
        free("rec", CP_CRITTER),
        Meet::PassThrough,
    ),
    case(
        "DontCollide from the higher priority, spawned second: no collision",
        free("rec", CP_CRITTER),
        saying("ghost", CP_PLAYER, CollideRule::DontCollide),
        Meet::PassThrough,
    ),
    case(
        "AsCaller from the higher id, at equal priority",
        free("rec", CP_CRITTER),
        saying("pushy", CP_CRITTER, CollideRule::AsCaller),
        Meet::Calls(Who::Right, Who::Left),
    ),
    case(
        "AsArg from the lower id, at equal priority",
        saying("meek", CP_CRITTER, CollideRule::AsArg),
        free("rec", CP_CRITTER),
        Meet::Calls(Who::Right, Who::Left),
    ),
    case(
        "against priority: the lower asks to call and the higher agrees to be the argument",
        saying("humble", CP_BULLET, CollideRule::AsArg),
        saying("bold", CP_CRITTER, CollideRule::AsCaller),
        Meet::Calls(Who::Right, Who::Left),
    ),
    case(
        "against priority, spawned the other way round",
        saying("bold", CP_CRITTER, CollideRule::AsCaller),
        saying("humble", CP_BULLET, CollideRule::AsArg),
        Meet::Calls(Who::Left, Who::Right),
    ),
];

#[test]
fn who_calls_collide_on_whom_follows_pop_s_roles() {
    const LEFT: (DVec2, DVec2) = (DVec2::new(4.0, 5.0), DVec2::new(0.5, 0.0));
    const RIGHT: (DVec2, DVec2) = (DVec2::new(4.9, 5.0), DVec2::new(-0.5, 0.0));
    for case in &ROLE_CASES {
        let why = case.why;
        let log = call_log();
        let mut world = world2(10.0);
        for side in [case.left, case.right] {
            if world.kinds().id(side.kind).is_ok() {
                continue; // both sides of one kind
            }
            let recorder = match side.rule {
                Some(rule) => Recorder::saying(&log, rule),
                None => Recorder::new(&log),
            };
            register(
                &mut world,
                side.kind,
                with_priority(side.priority),
                Rc::new(recorder),
            );
        }
        let spec = |side: Side, (pos, vel): (DVec2, DVec2)| {
            let vel = if side.fixed { DVec2::ZERO } else { vel };
            CritterSpec::new(side.kind, pos).vel(vel).fixed(side.fixed)
        };
        let (left, right) = if case.left_reuses_a_lower_slot {
            let placeholder = world
                .spawn(CritterSpec::new(case.left.kind, DVec2::new(1.0, 1.0)))
                .unwrap();
            let right = world.spawn(spec(case.right, RIGHT)).unwrap();
            world.remove(placeholder).unwrap();
            let left = world.spawn(spec(case.left, LEFT)).unwrap();
            assert!(
                left < right && left.index < right.index,
                "{why}: test setup: the later spawn reuses the lower slot"
            );
            (left, right)
        } else {
            let left = world.spawn(spec(case.left, LEFT)).unwrap();
            (left, world.spawn(spec(case.right, RIGHT)).unwrap())
        };
        world.step().unwrap();
        let id = |who: Who| match who {
            Who::Left => left,
            Who::Right => right,
        };
        match case.meet {
            Meet::Calls(caller, arg) => {
                assert_eq!(
                    *log.borrow(),
                    vec![(id(caller), id(arg))],
                    "{why}: {caller:?} should call {arg:?}"
                );
            }
            Meet::PassThrough => {
                assert!(log.borrow().is_empty(), "{why}: collide was called");
                assert!(
                    world.events().collisions.is_empty(),
                    "{why}: a collision was reported"
                );
                assert_eq!(
                    world.get(left).unwrap().vel,
                    LEFT.1,
                    "{why}: left's velocity"
                );
                assert_eq!(
                    world.get(right).unwrap().vel,
                    RIGHT.1,
                    "{why}: right's velocity"
                );
            }
            Meet::NeverRuled => {
                assert!(log.borrow().is_empty(), "{why}: collide was called");
                assert_eq!(world.stats().ruled, 0, "{why}: the pair was ruled");
                assert_eq!(
                    [world.get(left).unwrap().pos, world.get(right).unwrap().pos],
                    [LEFT.0, RIGHT.0],
                    "{why}: the pair was moved or separated"
                );
                // Control: free one of them and the pair collides.
                world.get_mut(right).unwrap().set_fixed(false);
                world.step().unwrap();
                assert_eq!(log.borrow().len(), 1, "{why}: freed, the pair collides");
            }
        }
    }
}

/// Zero velocities, so the touching pairs of the step are those of the starting positions.
#[test]
fn each_touching_pair_is_handled_exactly_once_per_step() {
    let log = call_log();
    let mut world = world2(20.0);
    register(
        &mut world,
        "rec",
        with_priority(CP_CRITTER),
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
                if gap < -POSITION_DRIFT {
                    touching.insert((a.0, b.0));
                }
                if gap <= POSITION_DRIFT {
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
    register(&mut world, "red", with_priority(CP_CRITTER), red.clone());
    register(&mut world, "blue", with_priority(CP_PLAYER), blue.clone());
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
    register(
        &mut world,
        "moody",
        with_priority(CP_CRITTER),
        moody.clone(),
    );
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
        register(
            &mut world,
            "moody",
            with_priority(CP_CRITTER),
            moody.clone(),
        );
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

#[test]
fn bullet_damages_a_target_and_dies_without_bouncing_it() {
    let mut world = classic_world();
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
    let mut world = classic_world();
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
        ROUND_OFF,
        "bullet bounced",
    );
    assert_close_vec(
        world.get(o).unwrap().vel,
        DVec2::new(vo, 0.0),
        ROUND_OFF,
        "ball pushed",
    );
    assert_eq!(world.get(o).unwrap().health(), 1.0, "no damage");
}

#[test]
fn basket_kills_what_it_contains_and_ignores_what_it_only_touches() {
    let mut world = classic_world();
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
    let mut world = classic_world();
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
