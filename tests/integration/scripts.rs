//! The rhai scripting layer, driven through scene files: the shipped scenes and kinds against the
//! laws they must keep (momentum, energy, the elastic formula, counts that balance), Pop's lecture
//! kinds in small inline scenes, collide roles decided by scripts, inheritance, hooks, determinism
//! and logging.

use crate::script_common;

use critterbox::glam::DVec2;
use critterbox::script::{load_scene, ScriptOptions};
use critterbox::{CritterId, PropValue, World, CP_BULLET};
use script_common::*;

/// Runs `scene` for up to `n` steps, calling `each` after every step; stops early when the
/// scene's `on_step` asks to, returning its reason.
fn run_with(
    scene: &mut critterbox::scenes::Scene,
    n: u64,
    mut each: impl FnMut(&World<DVec2>),
) -> Option<String> {
    for _ in 0..n {
        let reason = step(scene);
        each(w2(scene));
        if reason.is_some() {
            return reason;
        }
    }
    None
}

/// Live critters that are not walls.
fn movers(w: &World<DVec2>) -> Vec<CritterId> {
    w.critters()
        .iter()
        .filter(|c| !c.is_wall())
        .map(|c| c.id())
        .collect()
}

// ----- the shipped scenes --------------------------------------------------------------------

const SHIPPED_SCENES: [&str; 9] = [
    "basket_game",
    "billiards",
    "bullets_vs_player",
    "children",
    "cradle",
    "gas",
    "hunt",
    "pile",
    "splitters",
];

#[test]
fn the_list_of_shipped_scenes_is_the_scenes_folder() {
    let on_disk: Vec<String> = shipped("scenes")
        .iter()
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        on_disk, SHIPPED_SCENES,
        "every shipped scene should be covered by these tests"
    );
}

#[test]
fn every_shipped_scene_loads_and_runs() {
    for name in SHIPPED_SCENES {
        let mut scene = load(&shipped_scene(name), &[]);
        assert_eq!(scene.name, name, "a script scene is named for its file");
        assert!(scene.default_steps > 0, "{name}: its steps should be > 0");
        let start = scene.world.len();
        assert!(start > 0, "{name}: the scene should make critters");
        let n = scene.default_steps.min(120);
        let mut ran = 0;
        for _ in 0..n {
            ran += 1;
            if step(&mut scene).is_some() {
                break;
            }
        }
        assert_eq!(
            scene.world.step_count(),
            ran,
            "{name}: every step should count"
        );
        assert!(
            scene.world.kinetic_energy().is_finite(),
            "{name}: the state should stay finite"
        );
    }
}

/// The cradle: the striker and the balls of the row, ordered by x at the start.
fn cradle_balls(sets: &[(&str, &str)]) -> (critterbox::scenes::Scene, Vec<CritterId>) {
    let scene = load(&shipped_scene("cradle"), sets);
    let w = w2(&scene);
    let mut ids = movers(w);
    ids.sort_by(|a, b| {
        w.get(*a)
            .unwrap()
            .pos
            .x
            .total_cmp(&w.get(*b).unwrap().pos.x)
    });
    (scene, ids)
}

/// Newton's cradle at e = 1 with equal masses: the striker stops and only the last ball leaves,
/// at the striker's speed, exactly.
fn check_cradle(sets: &[(&str, &str)], speed: f64) {
    let (mut scene, ids) = cradle_balls(sets);
    let w = w2(&scene);
    assert_eq!(ids.len(), 6, "a striker and a row of five");
    assert_eq!(
        w.get(ids[0]).unwrap().vel,
        DVec2::new(speed, 0.0),
        "the striker starts at SPEED"
    );
    let m = w.get(ids[0]).unwrap().mass();
    for &id in &ids {
        assert_eq!(w.get(id).unwrap().mass(), m, "equal masses");
        assert_eq!(w.get(id).unwrap().restitution(), 1.0, "elastic balls");
    }
    let steps = scene.default_steps;
    run_with(&mut scene, steps, |_| {});
    let w = w2(&scene);
    for (i, &id) in ids.iter().enumerate() {
        let v = w.get(id).unwrap().vel;
        let want = if i == ids.len() - 1 {
            DVec2::new(speed, 0.0)
        } else {
            DVec2::ZERO
        };
        assert_eq!(v, want, "ball {i} (0 = striker) after {steps} steps");
    }
}

#[test]
fn cradle_leaves_only_the_last_ball_moving_at_the_strikers_speed() {
    check_cradle(&[], 1.0);
}

#[test]
fn cradle_set_speed_2_makes_the_last_ball_leave_at_2() {
    check_cradle(&[("SPEED", "2")], 2.0);
}

/// The gas is elastic: kinetic energy stays put, the count of critters stays N, and momentum
/// changes by exactly the impulses the walls give (balls among themselves conserve it).
#[test]
fn gas_conserves_energy_and_changes_momentum_only_through_walls() {
    let mut scene = load(&shipped_scene("gas"), &[]);
    const N: usize = 400;
    let count = |w: &World<DVec2>| of_kind(w, "ball").len();
    assert_eq!(count(w2(&scene)), N, "the scene's N balls");
    let ke0 = scene.world.kinetic_energy();
    let mut p_prev = w2(&scene).momentum();
    let mut wall_impulse_total = 0.0;
    for _ in 0..200 {
        step(&mut scene);
        let w = w2(&scene);
        let n = w.step_count();
        assert_eq!(count(w), N, "step {n}: no ball is lost or made");
        assert_close(
            w.kinetic_energy(),
            ke0,
            1e-12 * ke0,
            &format!("kinetic energy after step {n}"),
        );
        // What the walls gave the balls this step.
        let mut from_walls = DVec2::ZERO;
        for e in &w.events().collisions {
            let caller_is_wall = w.get(e.caller).unwrap().is_wall();
            let arg_is_wall = w.get(e.arg).unwrap().is_wall();
            if caller_is_wall {
                from_walls += e.normal * e.impulse;
            } else if arg_is_wall {
                from_walls -= e.normal * e.impulse;
            }
            if caller_is_wall || arg_is_wall {
                wall_impulse_total += e.impulse;
            }
        }
        let scale: f64 = w
            .critters()
            .iter()
            .filter(|c| !c.is_fixed())
            .map(|c| c.mass() * c.vel.length())
            .sum();
        assert_close_vec(
            w.momentum() - p_prev,
            from_walls,
            1e-12 * scale,
            &format!("change of momentum in step {n} against the walls' impulses"),
        );
        p_prev = w.momentum();
    }
    assert!(
        wall_impulse_total > 0.0,
        "some ball should have hit a wall, or the momentum check tested nothing"
    );
}

/// The basket game: every ball is either still flying or in the basket's `caught` count, and
/// balls are never made.
#[test]
fn basket_game_balls_remaining_plus_caught_is_always_the_initial_40() {
    let mut scene = load(&shipped_scene("basket_game"), &[]);
    const BALLS: i64 = 40;
    let balls = |w: &World<DVec2>| of_kind(w, "ball").len() as i64;
    let basket = of_kind(w2(&scene), "basket");
    assert_eq!(basket.len(), 1, "one basket");
    let basket = basket[0];
    assert_eq!(balls(w2(&scene)), BALLS);
    assert_eq!(prop_int(w2(&scene), basket, "caught"), 0);
    let mut prev_balls = BALLS;
    let mut prev_caught = 0;
    run_with(&mut scene, 400, |w| {
        let n = w.step_count();
        let (now, caught) = (balls(w), prop_int(w, basket, "caught"));
        assert_eq!(now + caught, BALLS, "step {n}: balls + caught");
        assert!(now <= prev_balls, "step {n}: the count of balls went up");
        assert_eq!(
            w.events().deaths.len() as i64,
            caught - prev_caught,
            "step {n}: each death is one catch"
        );
        prev_balls = now;
        prev_caught = caught;
    });
    assert!(
        prev_caught > 0,
        "the basket should catch some balls in 400 steps, or the balance tested nothing"
    );
}

/// Bullets against a player: the scene stops when the player is dead, and the damage it took adds
/// up to its starting health (each hit costs 1; nothing is recorded after death).
#[test]
fn bullets_vs_player_stops_when_the_damage_adds_up_to_the_players_health() {
    let mut scene = load(&shipped_scene("bullets_vs_player"), &[]);
    let w = w2(&scene);
    let players: Vec<CritterId> = of_kind(w, "armed_player")
        .into_iter()
        .filter(|&id| !w.get(id).unwrap().is_fixed())
        .collect();
    assert_eq!(players.len(), 1, "one free player among the turrets");
    let player = players[0];
    let health = w.get(player).unwrap().health();
    assert_eq!(health, 8.0, "the scene gives the player health 8");
    let mut damage = 0.0;
    let mut hits = 0;
    let reason = run_with(&mut scene, 3000, |w| {
        for &(id, amount) in &w.events().damages {
            if id == player {
                damage += amount;
                hits += 1;
            }
        }
    });
    let reason = reason.expect("the scene should stop within its 3000 steps");
    assert!(
        reason.contains("dead"),
        "the reason should say the player is dead: {reason:?}"
    );
    assert!(w2(&scene).get(player).is_none(), "the player is gone");
    assert_eq!(damage, health, "damage on the player ({hits} hits)");
}

/// Billiards has restitution 0.95 <= 1: no step may add kinetic energy.
#[test]
fn billiards_kinetic_energy_never_increases() {
    let mut scene = load(&shipped_scene("billiards"), &[]);
    let ke0 = scene.world.kinetic_energy();
    let mut prev = ke0;
    run_with(&mut scene, 300, |w| {
        let ke = w.kinetic_energy();
        assert!(
            ke <= prev * (1.0 + 1e-12),
            "step {}: kinetic energy rose from {prev:e} to {ke:e}",
            w.step_count()
        );
        prev = ke;
    });
    assert!(
        prev < ke0,
        "the break should have lost some energy to e < 1, or nothing collided"
    );
}

/// Children count a hit each time their collide (as caller) touched another critter; walls call
/// on children (higher priority), so every hit is a child-child collision event.
#[test]
fn children_hits_sum_to_the_child_child_collision_events() {
    let mut scene = load(&shipped_scene("children"), &[]);
    let children = of_kind(w2(&scene), "child");
    assert_eq!(children.len(), 30, "the scene's N children");
    let mut child_child = 0;
    run_with(&mut scene, 300, |w| {
        let is_child = |id| w.kinds().name(w.get(id).unwrap().kind()) == "child";
        child_child += w
            .events()
            .collisions
            .iter()
            .filter(|e| is_child(e.caller) && is_child(e.arg))
            .count() as i64;
    });
    let w = w2(&scene);
    let hits: i64 = children.iter().map(|&c| prop_int(w, c, "hits")).sum();
    assert!(
        child_child > 0,
        "some children should have met in 300 steps"
    );
    assert_eq!(hits, child_child, "sum of hits against child-child events");
}

// ----- Pop's lecture kinds -------------------------------------------------------------------

#[test]
fn bullet_damages_its_target_dies_gives_no_impulse_and_scores_for_its_shooter() {
    let sandbox = Sandbox::with_shipped_kinds("bullet_hits_target");
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), gravity: vec(0, 0), seed: 1 });
let shooter = spawn("armed_player", #{ pos: vec(2, 2), fixed: true,
    props: #{ tag: "shooter", sensitive: false, score: 0 } });
spawn("armed_player", #{ pos: vec(10, 5), vel: vec(0, 0.5), health: 10,
    props: #{ tag: "target", sensitive: true } });
spawn("bullet", #{ pos: vec(9.35, 5), vel: vec(6, 0),
    props: #{ tag: "bullet", shooter: shooter, targets: ["armed_player"], damage: 3 } });
"#,
    );
    let w = w2(&scene);
    let (shooter, target, bullet) = (
        tagged(w, "shooter"),
        tagged(w, "target"),
        tagged(w, "bullet"),
    );
    let damage = prop_int(w, bullet, "damage") as f64;
    let t0 = w.get(target).unwrap().clone();
    let score0 = prop_int(w, shooter, "score");
    let dt = w.dt();

    step(&mut scene);
    let w = w2(&scene);
    assert_eq!(
        w.events().damages,
        vec![(target, damage)],
        "the bullet damages its target by its damage, once"
    );
    let t1 = w.get(target).expect("the target survives 3 of 10");
    assert_eq!(t1.health(), t0.health() - damage);
    assert_eq!(t1.vel, t0.vel, "no impulse on the target");
    assert_close_vec(
        t1.pos,
        t0.pos + t0.vel * dt,
        1e-12,
        "the target moved freely (no separation push)",
    );
    // The hit may be reported as a collision of the bullet with its target, but with no impulse.
    for e in &w.events().collisions {
        assert_eq!((e.caller, e.arg), (bullet, target), "only the hit: {e:?}");
        assert_eq!(e.impulse, 0.0, "no impulse: {e:?}");
    }
    assert!(w.events().deaths.contains(&bullet), "the bullet died");
    assert!(w.get(bullet).is_none(), "and was removed after the step");
    assert_eq!(prop_int(w, shooter, "score"), score0 + 1, "one point");
}

#[test]
fn bullet_never_hits_its_shooter_or_the_shooters_other_bullets() {
    let sandbox = Sandbox::with_shipped_kinds("bullet_same_side");
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
let shooter = spawn("armed_player", #{ pos: vec(5, 5), health: 5,
    props: #{ tag: "shooter", sensitive: true } });
spawn("bullet", #{ pos: vec(5.3, 5), props: #{ tag: "b1", shooter: shooter, targets: ["armed_player"] } });
spawn("bullet", #{ pos: vec(5.35, 5.05), props: #{ tag: "b2", shooter: shooter, targets: ["armed_player"] } });
"#,
    );
    let w = w2(&scene);
    let ids = [tagged(w, "shooter"), tagged(w, "b1"), tagged(w, "b2")];
    let before: Vec<_> = ids.iter().map(|&id| w.get(id).unwrap().clone()).collect();
    // They overlap: shooter and bullets, and the two bullets.
    for (i, a) in before.iter().enumerate() {
        for b in &before[i + 1..] {
            assert!(
                (a.pos - b.pos).length() < a.radius() + b.radius(),
                "{} and {} should overlap at the start",
                a.id(),
                b.id()
            );
        }
    }
    run_with(&mut scene, 10, |w| {
        let n = w.step_count();
        assert!(
            w.events().collisions.is_empty(),
            "step {n}: collisions {:?}",
            w.events().collisions
        );
        assert!(w.events().damages.is_empty(), "step {n}: damage");
        assert!(w.events().deaths.is_empty(), "step {n}: deaths");
    });
    let w = w2(&scene);
    for (id, c0) in ids.iter().zip(&before) {
        let c = w.get(*id).expect("all alive");
        assert_eq!(c.health(), c0.health(), "{id}: health");
        assert_eq!(c.pos, c0.pos, "{id}: not pushed");
    }
}

/// The two critters of a collision event, before and after the step that made it.
struct Hit2 {
    caller0: critterbox::Critter<DVec2>,
    arg0: critterbox::Critter<DVec2>,
    caller1: critterbox::Critter<DVec2>,
    arg1: critterbox::Critter<DVec2>,
    normal: DVec2,
}

/// Steps until a collision event between `a` and `b` (at most `max` steps); returns both critters
/// before and after that step. Fails if anything else collides or no event comes.
fn step_until_hit(
    scene: &mut critterbox::scenes::Scene,
    a: CritterId,
    b: CritterId,
    max: u64,
) -> Hit2 {
    for _ in 0..max {
        let w = w2(scene);
        let (a0, b0) = (w.get(a).unwrap().clone(), w.get(b).unwrap().clone());
        step(scene);
        let w = w2(scene);
        let events = &w.events().collisions;
        if events.is_empty() {
            continue;
        }
        assert_eq!(events.len(), 1, "one collision: {events:?}");
        let e = events[0];
        let (caller0, arg0) = if e.caller == a && e.arg == b {
            (a0, b0)
        } else if e.caller == b && e.arg == a {
            (b0, a0)
        } else {
            panic!("an unexpected collision {e:?}");
        };
        return Hit2 {
            caller1: w.get(caller0.id()).unwrap().clone(),
            arg1: w.get(arg0.id()).unwrap().clone(),
            caller0,
            arg0,
            normal: e.normal,
        };
    }
    panic!("{a} and {b} should collide within {max} steps");
}

/// A collision with e = 1: momentum kept, normal velocities as Pop's 1-D elastic formula, tangential
/// parts untouched (no gravity, no update hooks in these scenes).
fn assert_elastic(hit: &Hit2) {
    let (m1, m2) = (hit.caller0.mass(), hit.arg0.mass());
    let (u1, u2) = (hit.caller0.vel, hit.arg0.vel);
    let (v1, v2) = (hit.caller1.vel, hit.arg1.vel);
    let n = hit.normal;
    let scale = m1 * u1.length() + m2 * u2.length();
    assert_close_vec(
        m1 * v1 + m2 * v2,
        m1 * u1 + m2 * u2,
        1e-12 * scale,
        "momentum",
    );
    let (w1, w2) = pop_elastic(u1.dot(n), u2.dot(n), m2 / m1);
    let speed = u1.length() + u2.length();
    assert_close(v1.dot(n), w1, 1e-12 * speed, "caller's normal velocity");
    assert_close(v2.dot(n), w2, 1e-12 * speed, "arg's normal velocity");
    assert_close_vec(
        v1 - n * v1.dot(n),
        u1 - n * u1.dot(n),
        1e-12 * speed,
        "caller's tangential velocity",
    );
    assert_close_vec(
        v2 - n * v2.dot(n),
        u2 - n * u2.dot(n),
        1e-12 * speed,
        "arg's tangential velocity",
    );
    assert!(
        (v2 - v1).dot(n) >= 0.0,
        "after the hit they separate along the normal"
    );
}

#[test]
fn bullet_bounces_elastically_off_a_non_target() {
    let sandbox = Sandbox::with_shipped_kinds("bullet_bounces");
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
let shooter = spawn("armed_player", #{ pos: vec(18, 8), fixed: true, props: #{ sensitive: false } });
spawn("ball", #{ pos: vec(10, 5), vel: vec(-0.5, 0.2), mass: 3.0, props: #{ tag: "ball" } });
spawn("bullet", #{ pos: vec(9.2, 4.7), vel: vec(4, 1), mass: 1.0,
    props: #{ tag: "bullet", shooter: shooter, targets: ["armed_player"] } });
"#,
    );
    let w = w2(&scene);
    let (ball, bullet) = (tagged(w, "ball"), tagged(w, "bullet"));
    let hit = step_until_hit(&mut scene, bullet, ball, 60);
    assert_eq!(
        hit.caller0.id(),
        bullet,
        "the bullet (CP_BULLET) calls on the ball"
    );
    assert_elastic(&hit);
    let w = w2(&scene);
    assert!(
        w.events().damages.is_empty(),
        "a non-target takes no damage"
    );
    assert!(w.events().deaths.is_empty(), "the bullet bounced and lives");
}

#[test]
fn silver_bullet_damages_only_its_target_and_bounces_off_another_player() {
    let sandbox = Sandbox::with_shipped_kinds("silver_bullet");
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
let shooter = spawn("armed_player", #{ pos: vec(18, 8), fixed: true, props: #{ sensitive: false } });
let a = spawn("armed_player", #{ pos: vec(5, 3), health: 10, props: #{ tag: "a", sensitive: false } });
spawn("armed_player", #{ pos: vec(12, 7), health: 10, props: #{ tag: "b", sensitive: false } });
// Both know "armed_player" as a target kind: the bullet's own is_target would hit both players.
spawn("silver_bullet", #{ pos: vec(3.8, 3), vel: vec(4, 0),
    props: #{ tag: "to_a", shooter: shooter, target: a, targets: ["armed_player"], damage: 2 } });
spawn("silver_bullet", #{ pos: vec(10.8, 7), vel: vec(4, 0),
    props: #{ tag: "to_b", shooter: shooter, target: a, targets: ["armed_player"], damage: 2 } });
"#,
    );
    let w = w2(&scene);
    let (a, b, to_a, to_b) = (
        tagged(w, "a"),
        tagged(w, "b"),
        tagged(w, "to_a"),
        tagged(w, "to_b"),
    );
    assert_eq!(
        w.get(to_a).unwrap().radius(),
        0.08,
        "silver_bullet.rhai's own radius"
    );
    let damage = prop_int(w, to_a, "damage") as f64;
    let (ha, hb) = (w.get(a).unwrap().health(), w.get(b).unwrap().health());
    let mut bounce = None;
    run_with(&mut scene, 30, |w| {
        for e in &w.events().collisions {
            if (e.caller, e.arg) == (to_a, a) {
                assert_eq!(e.impulse, 0.0, "the hit on the target gives no impulse");
            } else {
                assert_eq!((e.caller, e.arg), (to_b, b), "the only other collision");
                bounce = Some(w.step_count());
            }
        }
    });
    let w = w2(&scene);
    assert!(
        bounce.is_some(),
        "the silver bullet should bounce off the non-target player"
    );
    assert_eq!(
        w.get(a).unwrap().health(),
        ha - damage,
        "its one target is hit"
    );
    assert_eq!(
        w.get(b).unwrap().health(),
        hb,
        "another armed_player is not hurt"
    );
    assert!(w.get(to_a).is_none(), "the bullet that hit its target died");
    let sb = w.get(to_b).expect("the bullet that bounced lives");
    assert!(sb.vel.x < 0.0, "and flies back: {:?}", sb.vel);
}

#[test]
fn silver_bullet_bounce_off_a_non_target_is_elastic() {
    let sandbox = Sandbox::with_shipped_kinds("silver_bullet_elastic");
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
let shooter = spawn("armed_player", #{ pos: vec(18, 8), fixed: true, props: #{ sensitive: false } });
let a = spawn("armed_player", #{ pos: vec(2, 2), fixed: true, props: #{ sensitive: false } });
spawn("armed_player", #{ pos: vec(12, 5.2), vel: vec(-0.3, 0), props: #{ tag: "b", sensitive: false } });
spawn("silver_bullet", #{ pos: vec(10.8, 5), vel: vec(4, 0.1),
    props: #{ tag: "sb", shooter: shooter, target: a, targets: ["armed_player"] } });
"#,
    );
    let w = w2(&scene);
    let (b, sb) = (tagged(w, "b"), tagged(w, "sb"));
    let hit = step_until_hit(&mut scene, sb, b, 60);
    assert_eq!(hit.caller0.id(), sb, "CP_SILVERBULLET calls on CP_PLAYER");
    assert_elastic(&hit);
    assert!(w2(&scene).events().damages.is_empty());
}

/// A sensitive armed player pays 1 health for each collision it has with a non-wall (it is the
/// caller against balls), and nothing for walls (walls call on it).
#[test]
fn sensitive_armed_player_loses_one_health_per_ball_hit_and_none_for_walls() {
    let sandbox = Sandbox::with_shipped_kinds("sensitive_player");
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(10, 10), seed: 2 });
w.walls_around();
spawn("armed_player", #{ pos: vec(5, 5), vel: vec(3.0, 0.4), health: 100,
    props: #{ tag: "player", sensitive: true } });
spawn("ball", #{ pos: vec(2, 5), props: #{ tag: "ball1" } });
spawn("ball", #{ pos: vec(5, 8), vel: vec(0, -1), props: #{ tag: "ball2" } });
"#,
    );
    let player = tagged(w2(&scene), "player");
    let h0 = w2(&scene).get(player).unwrap().health();
    let (mut wall_hits, mut ball_hits, mut taken) = (0, 0, 0.0);
    run_with(&mut scene, 300, |w| {
        let n = w.step_count();
        let mut ball_now = 0;
        for e in &w.events().collisions {
            if e.caller != player && e.arg != player {
                continue;
            }
            let other = if e.caller == player { e.arg } else { e.caller };
            if w.get(other).unwrap().is_wall() {
                wall_hits += 1;
            } else {
                assert_eq!(e.caller, player, "step {n}: the player calls on balls");
                ball_now += 1;
            }
        }
        ball_hits += ball_now;
        let damage: Vec<f64> = w
            .events()
            .damages
            .iter()
            .filter(|d| d.0 == player)
            .map(|d| d.1)
            .collect();
        assert_eq!(
            damage,
            vec![1.0; ball_now],
            "step {n}: 1 per ball hit, none per wall hit"
        );
        taken += damage.iter().sum::<f64>();
        assert_eq!(w.get(player).unwrap().health(), h0 - taken, "step {n}");
    });
    assert!(wall_hits > 0, "the player should have hit a wall");
    assert!(ball_hits > 0, "a ball should have hit the player");
}

#[test]
fn insensitive_armed_player_takes_no_damage_from_a_ball() {
    let sandbox = Sandbox::with_shipped_kinds("insensitive_player");
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(10, 10), seed: 2 });
spawn("armed_player", #{ pos: vec(5, 5), health: 3, props: #{ tag: "player", sensitive: false } });
spawn("ball", #{ pos: vec(3.5, 5), vel: vec(3, 0) });
"#,
    );
    let player = tagged(w2(&scene), "player");
    let mut hits = 0;
    run_with(&mut scene, 30, |w| {
        hits += w.events().collisions.len();
        assert!(w.events().damages.is_empty());
    });
    assert!(hits > 0, "the ball should have hit the player");
    assert_eq!(w2(&scene).get(player).unwrap().health(), 3.0);
}

#[test]
fn sensitive_armed_player_dies_when_its_health_reaches_zero() {
    let sandbox = Sandbox::with_shipped_kinds("player_dies");
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 2 });
spawn("armed_player", #{ pos: vec(10, 5), health: 2, props: #{ tag: "player", sensitive: true } });
spawn("ball", #{ pos: vec(8.5, 5), vel: vec(3, 0) });
spawn("ball", #{ pos: vec(12, 5) });
"#,
    );
    let player = tagged(w2(&scene), "player");
    let mut health = 2.0;
    let mut died_at = None;
    run_with(&mut scene, 120, |w| {
        let n = w.step_count();
        if died_at.is_some() {
            assert!(w.get(player).is_none(), "step {n}: the dead stay dead");
            return;
        }
        for &(id, amount) in &w.events().damages {
            if id == player {
                assert_eq!(amount, 1.0);
                health -= amount;
            }
        }
        if health <= 0.0 {
            assert!(w.events().deaths.contains(&player), "step {n}: dies at 0");
            assert!(w.get(player).is_none(), "step {n}: and is removed");
            died_at = Some(n);
        } else {
            let c = w.get(player).expect("alive while health > 0");
            assert_eq!(c.health(), health, "step {n}");
        }
    });
    assert!(
        died_at.is_some(),
        "two hits should kill a player of health 2"
    );
}

#[test]
fn basket_kills_a_ball_it_wholly_contains_but_not_one_touching_its_edge() {
    let sandbox = Sandbox::with_shipped_kinds("basket");
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
spawn("basket", #{ pos: vec(10, 5), radius: 2.0, props: #{ tag: "basket" } });
spawn("ball", #{ pos: vec(10.5, 5), radius: 0.3, props: #{ tag: "inside" } });
spawn("ball", #{ pos: vec(10, 7.1), vel: vec(1, 0), radius: 0.3, props: #{ tag: "edge" } });
spawn("ball", #{ pos: vec(5, 5.5), vel: vec(3, 0), radius: 0.3, props: #{ tag: "crossing" } });
"#,
    );
    let w = w2(&scene);
    let basket = tagged(w, "basket");
    let (inside, edge, crossing) = (
        tagged(w, "inside"),
        tagged(w, "edge"),
        tagged(w, "crossing"),
    );
    let bk = w.get(basket).unwrap().clone();
    let contained =
        |c: &critterbox::Critter<DVec2>| (c.pos - bk.pos).length() + c.radius() < bk.radius();
    let touching =
        |c: &critterbox::Critter<DVec2>| (c.pos - bk.pos).length() <= c.radius() + bk.radius();
    assert!(contained(w.get(inside).unwrap()));
    let e0 = w.get(edge).unwrap();
    assert!(
        touching(e0) && !contained(e0),
        "the edge ball overlaps the rim"
    );
    let dt = w.dt();

    let mut prev: Vec<critterbox::Critter<DVec2>> = w.critters().iter().cloned().collect();
    let mut edge_touched = 0;
    let mut crossing_touched = 0;
    let mut caught = 0;
    run_with(&mut scene, 90, |w| {
        let n = w.step_count();
        // A catch may be reported as the basket's collision, but nothing gets an impulse.
        for e in &w.events().collisions {
            assert_eq!(e.caller, basket, "step {n}: the basket calls: {e:?}");
            assert_eq!(e.impulse, 0.0, "step {n}: nothing bounces: {e:?}");
        }
        assert_eq!(w.get(basket).unwrap().pos, bk.pos, "the basket never moves");
        caught += w.events().deaths.len() as i64;
        assert_eq!(prop_int(w, basket, "caught"), caught, "step {n}: caught");
        for c0 in &prev {
            if c0.id() == basket {
                continue;
            }
            let moved = c0.pos + c0.vel * dt;
            let dies = {
                let mut c = c0.clone();
                c.pos = moved;
                contained(&c)
            };
            match w.get(c0.id()) {
                Some(c) => {
                    assert!(!dies, "step {n}: {} is wholly inside but alive", c0.id());
                    assert_eq!(c.vel, c0.vel, "step {n}: {} passes over", c0.id());
                    assert_close_vec(c.pos, moved, 1e-12, "moved freely");
                    if touching(c) {
                        if c.id() == edge {
                            edge_touched += 1;
                        }
                        if c.id() == crossing {
                            crossing_touched += 1;
                        }
                    }
                }
                None => assert!(dies, "step {n}: {} died outside", c0.id()),
            }
        }
        prev = w.critters().iter().cloned().collect();
    });
    let w = w2(&scene);
    assert!(w.get(inside).is_none(), "the contained ball was caught");
    assert!(w.get(edge).is_some(), "the rim ball lives");
    assert!(w.get(crossing).is_none(), "the crossing ball was caught");
    assert!(
        edge_touched > 0 && crossing_touched > 0,
        "balls overlapped the rim"
    );
    assert_eq!(prop_int(w, basket, "caught"), 2);
}

#[test]
fn child_collides_by_default_elastically_and_counts_its_hits() {
    let sandbox = Sandbox::with_shipped_kinds("child");
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
spawn("child", #{ pos: vec(8, 5), vel: vec(2, 0), props: #{ tag: "left" } });
spawn("child", #{ pos: vec(9.5, 5.3), vel: vec(-1, 0), mass: 0.2, props: #{ tag: "right" } });
"#,
    );
    let w = w2(&scene);
    let (left, right) = (tagged(w, "left"), tagged(w, "right"));
    let hit = step_until_hit(&mut scene, left, right, 60);
    assert_elastic(&hit);
    let w = w2(&scene);
    assert_eq!(
        prop_int(w, hit.caller0.id(), "hits"),
        1,
        "the caller counts the hit"
    );
    assert_eq!(
        prop_int(w, hit.arg0.id(), "hits"),
        0,
        "only the caller's collide runs"
    );
}

// ----- roles decided by scripts --------------------------------------------------------------

/// A kind that answers COLLIDE_AS_ARG against balls makes the ball call. Both are at CP_CRITTER, so
/// without that answer the pair could go either way and the lower id (the kind's critter, spawned
/// first) would call, as the control kind without a rule shows. (At a higher priority than the
/// ball's, the ball's own default rule would also ask to be the arg: a conflict, which the higher
/// priority wins.)
#[test]
fn collides_with_as_arg_makes_the_ball_the_caller() {
    let sandbox = Sandbox::new("as_arg");
    sandbox.kind(
        "shy",
        r#"
fn collides_with(me, other) {
    if other.is_kind("ball") { COLLIDE_AS_ARG } else { default_collides_with(me, other) }
}
fn collide(me, other) {
    log("shy called");
    me.collide_default(other)
}
"#,
    );
    sandbox.kind("bold", "defaults(#{ priority: CP_CRITTER });\n");
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
spawn("shy", #{ pos: vec(5, 3), props: #{ tag: "shy" } });
spawn("ball", #{ pos: vec(3.8, 3), vel: vec(3, 0), props: #{ tag: "ball_shy" } });
spawn("bold", #{ pos: vec(5, 7), props: #{ tag: "bold" } });
spawn("ball", #{ pos: vec(3.8, 7), vel: vec(3, 0), props: #{ tag: "ball_bold" } });
"#,
    );
    let w = w2(&scene);
    let (shy, bold) = (tagged(w, "shy"), tagged(w, "bold"));
    let (ball_shy, ball_bold) = (tagged(w, "ball_shy"), tagged(w, "ball_bold"));
    for (a, b) in [(shy, ball_shy), (bold, ball_bold)] {
        assert!(a < b, "the kind's critter has the lower id");
        assert_eq!(w.get(a).unwrap().priority(), w.get(b).unwrap().priority());
    }
    let mut seen = Vec::new();
    run_with(&mut scene, 30, |w| {
        assert!(
            !w.events().log.iter().any(|l| l == "shy called"),
            "the shy kind's collide must not run: it is the arg"
        );
        for e in &w.events().collisions {
            seen.push((e.caller, e.arg));
        }
    });
    assert!(seen.contains(&(ball_shy, shy)), "the ball calls: {seen:?}");
    assert!(!seen.contains(&(shy, ball_shy)), "{seen:?}");
    assert!(
        seen.contains(&(bold, ball_bold)),
        "control: without the rule the lower id calls: {seen:?}"
    );
}

#[test]
fn dont_collide_lets_balls_pass_through() {
    let sandbox = Sandbox::new("dont_collide");
    sandbox.kind("ghost", "fn collides_with(me, other) { DONT_COLLIDE }\n");
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
spawn("ghost", #{ pos: vec(10, 5), vel: vec(-1, 0), props: #{ tag: "ghost" } });
spawn("ball", #{ pos: vec(8, 5), vel: vec(1, 0), props: #{ tag: "ball" } });
"#,
    );
    let w = w2(&scene);
    let (ghost, ball) = (tagged(w, "ghost"), tagged(w, "ball"));
    let (vg, vb) = (w.get(ghost).unwrap().vel, w.get(ball).unwrap().vel);
    let mut overlapped = false;
    run_with(&mut scene, 120, |w| {
        assert!(w.events().collisions.is_empty(), "no collision events");
        let (g, b) = (w.get(ghost).unwrap(), w.get(ball).unwrap());
        assert_eq!((g.vel, b.vel), (vg, vb), "no impulse");
        overlapped |= (g.pos - b.pos).length() < g.radius() + b.radius();
    });
    let w = w2(&scene);
    assert!(overlapped, "they should have overlapped on the way");
    assert!(
        w.get(ghost).unwrap().pos.x < w.get(ball).unwrap().pos.x,
        "and passed through each other"
    );
}

#[test]
fn state_dependent_rule_is_asked_again_when_its_property_changes() {
    let sandbox = Sandbox::new("state_rule");
    sandbox.kind(
        "gate",
        r#"
defaults(#{ fixed: true, rule_depends_on_state: true, props: #{ solid: false } });
fn collides_with(me, other) {
    if me.solid { COLLIDE_AS_CALLER } else { DONT_COLLIDE }
}
fn update(me, dt) {
    if world().step_count >= 60 { me.solid = true; }
}
"#,
    );
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
spawn("gate", #{ pos: vec(10, 5), props: #{ tag: "gate" } });
spawn("ball", #{ pos: vec(8.8, 5), vel: vec(3, 0), props: #{ tag: "early" } });
spawn("ball", #{ pos: vec(4, 5), vel: vec(3, 0), props: #{ tag: "late" } });
"#,
    );
    let w = w2(&scene);
    let (gate, early, late) = (tagged(w, "gate"), tagged(w, "early"), tagged(w, "late"));
    let mut early_overlapped = false;
    let mut late_hit_at = None;
    run_with(&mut scene, 120, |w| {
        let n = w.step_count();
        let (g, e) = (w.get(gate).unwrap(), w.get(early).unwrap());
        let solid = prop_bool(w, gate, "solid");
        if !solid {
            early_overlapped |= (g.pos - e.pos).length() < g.radius() + e.radius();
            assert!(w.events().collisions.is_empty(), "step {n}: open gate");
        }
        for ev in &w.events().collisions {
            assert_eq!((ev.caller, ev.arg), (gate, late), "step {n}");
            assert!(solid, "step {n}: only a solid gate collides");
            late_hit_at.get_or_insert(n);
        }
    });
    let w = w2(&scene);
    assert!(
        early_overlapped,
        "the early ball passed through the open gate"
    );
    assert_eq!(w.get(early).unwrap().vel, DVec2::new(3.0, 0.0));
    assert!(late_hit_at.is_some(), "the late ball hit the solid gate");
    assert_eq!(
        w.get(late).unwrap().vel,
        DVec2::new(-3.0, 0.0),
        "reflected by a fixed critter at e = 1"
    );
}

// ----- inheritance ---------------------------------------------------------------------------

#[test]
fn kind_extending_bullet_is_a_bullet_and_inherits_defaults_and_hooks() {
    let sandbox = Sandbox::with_shipped_kinds("extends_bullet");
    sandbox.kind(
        "tracer",
        r#"
extends "bullet";
defaults(#{ color: "red", props: #{ damage: 5 } });
fn init(me) {
    log(`tracer is a bullet: ${me.is_kind("bullet")}; is a ball: ${me.is_kind("ball")}`);
}
"#,
    );
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
let shooter = spawn("armed_player", #{ pos: vec(10, 5), fixed: true,
    props: #{ tag: "shooter", sensitive: true, score: 0 } });
spawn("armed_player", #{ pos: vec(12.5, 5), health: 10, props: #{ tag: "target", sensitive: false } });
// Starts overlapping its shooter: the inherited collides_with keeps them apart.
spawn("tracer", #{ pos: vec(10.5, 5), vel: vec(6, 0),
    props: #{ tag: "tracer", shooter: shooter, targets: ["armed_player"] } });
"#,
    );
    let w = w2(&scene);
    assert!(
        w.events()
            .log
            .iter()
            .any(|l| l == "tracer is a bullet: true; is a ball: false"),
        "init logs is_kind: {:?}",
        w.events().log
    );
    let (shooter, target, tracer) = (
        tagged(w, "shooter"),
        tagged(w, "target"),
        tagged(w, "tracer"),
    );
    let t = w.get(tracer).unwrap();
    let kinds = w.kinds();
    assert!(kinds.is_kind(t.kind(), kinds.id("bullet").unwrap()));
    assert_eq!(t.radius(), 0.1, "bullet.rhai's radius, not overridden");
    assert_eq!(t.priority(), CP_BULLET, "bullet.rhai's priority");
    assert_eq!(
        prop(w, tracer, "targets"),
        PropValue::List(vec![PropValue::Text("armed_player".into())])
    );
    assert_eq!(prop_int(w, tracer, "damage"), 5, "its own default wins");
    let h_shooter = w.get(shooter).unwrap().health();
    let h_target = w.get(target).unwrap().health();

    run_with(&mut scene, 30, |w| {
        for e in &w.events().collisions {
            assert_eq!((e.caller, e.arg), (tracer, target), "only the hit: {e:?}");
            assert_eq!(e.impulse, 0.0, "no bounce: {e:?}");
        }
    });
    let w = w2(&scene);
    assert!(w.get(tracer).is_none(), "the inherited collide kills it");
    assert_eq!(w.get(target).unwrap().health(), h_target - 5.0);
    assert_eq!(
        w.get(shooter).unwrap().health(),
        h_shooter,
        "never its shooter"
    );
    assert_eq!(prop_int(w, shooter, "score"), 1, "inherited scoring");
}

// ----- init and update -----------------------------------------------------------------------

#[test]
fn init_runs_once_per_spawn_and_update_runs_every_step() {
    let sandbox = Sandbox::new("hooks");
    sandbox.kind(
        "counter",
        r#"
const PUSH = 0.5;
defaults(#{ props: #{ ticks: 0, inits: 0, last_dt: 0.0 } });
fn init(me) { me.inits += 1; }
fn update(me, dt) {
    me.ticks += 1;
    me.last_dt = dt;
    me.vel = me.vel + vec(PUSH, 0) * dt;
}
"#,
    );
    sandbox.kind(
        "spawner",
        r#"
defaults(#{ fixed: true });
fn update(me, dt) {
    if world().step_count == 3 {
        spawn("counter", #{ pos: me.pos + vec(0, 3), props: #{ tag: "late" } });
    }
}
"#,
    );
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(40, 10), dt: 0.01, seed: 1 });
spawn("counter", #{ pos: vec(2, 2), vel: vec(1, 0), props: #{ tag: "first" } });
spawn("spawner", #{ pos: vec(20, 2) });
load_kind("counter");
"#,
    );
    let w = w2(&scene);
    let first = tagged(w, "first");
    assert_eq!(prop_int(w, first, "inits"), 1, "init ran at spawn");
    assert_eq!(prop_int(w, first, "ticks"), 0, "no update before a step");
    let dt = w.dt();
    let n = 50;
    let mut late_born = None;
    run_with(&mut scene, n, |w| {
        if !w.events().spawns.is_empty() {
            assert_eq!(w.events().spawns.len(), 1);
            late_born = Some(w.step_count());
            let late = w.events().spawns[0];
            assert_eq!(prop_int(w, late, "inits"), 1, "init ran for a queued spawn");
            assert_eq!(prop_int(w, late, "ticks"), 0);
        }
    });
    let w = w2(&scene);
    assert_eq!(prop_int(w, first, "ticks"), n as i64, "one update per step");
    assert_eq!(prop_int(w, first, "inits"), 1, "init ran once");
    assert_eq!(
        prop(w, first, "last_dt"),
        PropValue::Float(dt),
        "update's dt"
    );
    assert_close(
        w.get(first).unwrap().vel.x,
        1.0 + 0.5 * dt * n as f64,
        1e-12,
        "velocity pushed by update every step",
    );
    // Spawned at the end of the 4th step (step_count 3 during it); updated in every step after.
    assert_eq!(
        late_born,
        Some(4),
        "queued to the end of the step it was asked in"
    );
    let late = tagged(w, "late");
    assert_eq!(prop_int(w, late, "ticks"), n as i64 - 4);
}

// ----- determinism ---------------------------------------------------------------------------

fn hashes(name: &str, options: &ScriptOptions, steps: u64) -> Vec<u64> {
    let mut scene = load_scene(&shipped_scene(name), &[], options)
        .unwrap_or_else(|e| panic!("{name} should load:\n{e}"));
    let mut out = vec![scene.world.state_hash()];
    for _ in 0..steps {
        let stop = step(&mut scene);
        out.push(scene.world.state_hash());
        if stop.is_some() {
            break;
        }
    }
    out
}

#[test]
fn bullets_vs_player_runs_identically_twice() {
    let options = ScriptOptions::default();
    let a = hashes("bullets_vs_player", &options, 300);
    let b = hashes("bullets_vs_player", &options, 300);
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        assert_eq!(x, y, "state hash after step {i}");
    }
}

#[test]
fn basket_game_runs_identically_twice() {
    let options = ScriptOptions::default();
    let a = hashes("basket_game", &options, 300);
    let b = hashes("basket_game", &options, 300);
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        assert_eq!(x, y, "state hash after step {i}");
    }
}

#[test]
fn seed_option_overrides_the_scenes_seed() {
    let positions = |seed: Option<u64>| {
        let options = ScriptOptions {
            seed,
            ..ScriptOptions::default()
        };
        let scene = load_scene(&shipped_scene("basket_game"), &[], &options)
            .unwrap_or_else(|e| panic!("basket_game should load:\n{e}"));
        let w = w2(&scene);
        let ps: Vec<DVec2> = of_kind(w, "ball")
            .iter()
            .map(|&id| w.get(id).unwrap().pos)
            .collect();
        (ps, hashes("basket_game", &options, 20))
    };
    let (p_default, h_default) = positions(None);
    let (p_same, h_same) = positions(Some(3)); // basket_game.rhai says seed: 3
    let (p_other, h_other) = positions(Some(4));
    assert_eq!(h_same, h_default, "overriding with the scene's own seed");
    assert_eq!(p_same, p_default);
    assert_eq!(p_other.len(), p_default.len(), "still 40 balls");
    assert_ne!(
        p_other, p_default,
        "another seed scatters the balls elsewhere"
    );
    for (i, (x, y)) in h_other.iter().zip(&h_default).enumerate() {
        assert_ne!(x, y, "state hash after step {i} should differ");
    }
}

// ----- output --------------------------------------------------------------------------------

#[test]
fn print_and_log_lines_go_to_the_step_log() {
    let sandbox = Sandbox::new("log");
    sandbox.kind(
        "talker",
        r#"
fn update(me, dt) {
    print(`print from ${me.label} at ${world().step_count}`);
    log(`log from ${me.label}`);
}
"#,
    );
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
spawn("talker", #{ pos: vec(5, 5), props: #{ label: "t" } });
print("scene top level");
fn on_step(world) {
    world.log(`on_step ${world.step_count}`);
}
"#,
    );
    assert_eq!(
        w2(&scene).events().log,
        vec!["scene top level".to_string()],
        "the scene's own print"
    );
    step(&mut scene);
    assert_eq!(
        w2(&scene).events().log,
        vec![
            "print from t at 0".to_string(),
            "log from t".to_string(),
            "on_step 1".to_string()
        ],
        "the first step's log, in order"
    );
    step(&mut scene);
    assert_eq!(
        w2(&scene).events().log,
        vec![
            "print from t at 1".to_string(),
            "log from t".to_string(),
            "on_step 2".to_string()
        ],
        "each step's log holds that step's lines"
    );
}

// ----- user properties -----------------------------------------------------------------------

#[test]
fn user_properties_read_and_write_through_the_critter() {
    let sandbox = Sandbox::new("props");
    sandbox.kind(
        "holder",
        r#"
defaults(#{ props: #{ count: 1, name: "a" } });
fn update(me, dt) {
    me.count += me["count"];          // dot and index read the same property
    me["name"] = me.name + "b";
    if !me.has("added") { me.set_prop("added", true); }
}
"#,
    );
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
spawn("holder", #{ pos: vec(5, 5), props: #{ extra: 2.5 } });
"#,
    );
    let id = of_kind(w2(&scene), "holder")[0];
    assert_eq!(
        prop(w2(&scene), id, "extra"),
        PropValue::Float(2.5),
        "spawn map props"
    );
    for _ in 0..3 {
        step(&mut scene);
    }
    let w = w2(&scene);
    assert_eq!(prop_int(w, id, "count"), 8, "doubled three times from 1");
    assert_eq!(prop(w, id, "name"), PropValue::Text("abbb".into()));
    assert!(prop_bool(w, id, "added"), "set_prop adds a property");
}

/// rhai gives every value a built-in `tag` property (`Dynamic::tag`), which wins over the
/// critter's indexer: `me.tag` reads 0 instead of the critter's `tag` property.
#[test]

fn a_user_property_named_tag_is_the_critters_property() {
    let sandbox = Sandbox::new("prop_tag");
    sandbox.kind(
        "tagger",
        r#"
defaults(#{ props: #{ tag: "start", seen: "" } });
fn update(me, dt) {
    me.seen = `${me.tag}`;
    me.tag = "changed";
}
"#,
    );
    let mut scene = sandbox.load(
        r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1 });
spawn("tagger", #{ pos: vec(5, 5) });
"#,
    );
    let id = of_kind(w2(&scene), "tagger")[0];
    let stepped = scene.step();
    assert!(stepped.is_ok(), "{}", stepped.unwrap_err());
    let w = w2(&scene);
    assert_eq!(prop(w, id, "seen"), PropValue::Text("start".into()));
    assert_eq!(prop(w, id, "tag"), PropValue::Text("changed".into()));
}

/// A scene may name a kind by its file's path: `spawn`, `scatter` and `load_kind` load the file
/// and use the kind it defines (named after the file), so a spawn by path makes critters of
/// that kind, and a second spawn by the same path reuses it.
#[test]
fn a_scene_spawns_a_kind_named_by_its_path() {
    let sandbox = Sandbox::new("spawn_by_path");
    let path = sandbox.kind("sparky", "defaults(#{ radius: 0.25 });\n");
    let path = path.display().to_string();
    let scene = sandbox.load(&format!(
        r#"
let w = world(#{{ dim: 2, size: vec(20, 20), dt: 0.01, seed: 1 }});
load_kind("{path}");
spawn("{path}", #{{ pos: vec(2, 2) }});
spawn("{path}", #{{ pos: vec(6, 2) }});
w.scatter("{path}", 3, #{{}});
"#
    ));
    let w = w2(&scene);
    let kinds: Vec<&str> = w
        .critters()
        .iter()
        .map(|c| w.kinds().name(c.kind()))
        .collect();
    assert_eq!(kinds, vec!["sparky"; 5]);
    assert!(w.critters().iter().all(|c| c.radius() == 0.25));
}
