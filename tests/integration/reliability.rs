//! No silently wrong run: a critter that cannot exist (too big for its box or its walls, a
//! radius beyond f64's reach) is an error naming the radius, whatever spawns it; a wall through a
//! critter is an error in either order; the exact methods never end a step with critters moved
//! past their events; the discrete step says once when it may tunnel.

use crate::script_common;

use critterbox::glam::{DVec2, DVec3};
use critterbox::{Border, CritterSpec, Error, WallBox, World, WorldConfig};
use script_common::*;

/// A world from (0, 0) to `size` with `border`.
fn box2(size: DVec2, border: Border) -> World<DVec2> {
    let mut config = WorldConfig::new(DVec2::ZERO, size);
    config.border = border;
    World::new(config).expect("a valid world")
}

/// Asserts `err` is about the radius `radius` (as written) and says `what`.
#[track_caller]
fn assert_radius_error(err: &Error, radius: &str, what: &[&str]) {
    let msg = err.to_string();
    assert!(matches!(err, Error::InvalidRadius { .. }), "{msg}");
    assert!(msg.contains(&format!("radius {radius} ")), "{msg}");
    for w in what {
        assert!(msg.contains(w), "'{msg}' does not say '{w}'");
    }
    assert!(!msg.contains("mass ="), "{msg}");
}

#[test]
fn a_ball_wider_than_a_bounded_box_is_an_error_naming_radius_and_box() {
    for border in [Border::Bounce, Border::Clamp] {
        let mut w = box2(DVec2::splat(10.0), border);
        let err = w
            .spawn(CritterSpec::ball(DVec2::splat(5.0)).radius(100.0))
            .unwrap_err();
        assert_radius_error(&err, "100", &["10 x 10", "diameter 200", "side 10"]);
        // The narrow side decides: a 10 x 4 box takes a diameter of 4, not 4 and a bit.
        let mut w = box2(DVec2::new(10.0, 4.0), border);
        w.spawn(CritterSpec::ball(DVec2::new(5.0, 2.0)).radius(2.0))
            .expect("a diameter equal to the side fits");
        let err = w
            .spawn(CritterSpec::ball(DVec2::new(5.0, 2.0)).radius(2.0f64.next_up()))
            .unwrap_err();
        assert_radius_error(&err, "2.0000000000000004", &["10 x 4", "side 4"]);
        assert_eq!(w.critters().len(), 1, "the rejected ball was added");
    }
    let mut w3 = World::new(WorldConfig::new(DVec3::ZERO, DVec3::splat(10.0))).unwrap();
    let err = w3
        .spawn(CritterSpec::ball(DVec3::splat(5.0)).radius(6.0))
        .unwrap_err();
    assert!(err.to_string().contains("10 x 10 x 10"), "{err}");
}

#[test]
fn extreme_radii_are_named_as_the_radius_not_as_the_mass() {
    let mut w = box2(DVec2::splat(10.0), Border::Bounce);
    let p = DVec2::splat(5.0);
    let err = w.spawn(CritterSpec::ball(p).radius(1e300)).unwrap_err();
    assert_radius_error(&err, "1e300", &["too large"]);
    let err = w.spawn(CritterSpec::ball(p).radius(1e-300)).unwrap_err();
    assert_radius_error(&err, "1e-300", &["too small"]);
    // In a periodic box the bounds are the same.
    let mut wrap = box2(DVec2::splat(10.0), Border::Wrap);
    let err = wrap.spawn(CritterSpec::ball(p).radius(1e300)).unwrap_err();
    assert_radius_error(&err, "1e300", &["too large"]);
    // A density that makes the mass overflow names the density and the radius it came from.
    let err = w
        .spawn(CritterSpec::ball(p).radius(2.0).density(1e308))
        .unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("density") && msg.contains("radius 2"), "{msg}");
    assert!(w.critters().is_empty());
}

#[test]
fn a_ball_wider_than_the_space_between_walls_around_is_an_error() {
    let sandbox = Sandbox::new("walls_around_fit");
    // Walls 0.2 thick leave 9.6 x 9.6: a radius of 4.9 fits the box but not the walls.
    let err = sandbox
        .try_load(
            "let w = world(#{ dim: 2, size: vec(10, 10) });\n\
             w.walls_around();\n\
             spawn(\"ball\", #{ pos: vec(5, 5), radius: 4.9 });\n",
        )
        .err()
        .expect("the ball does not fit between the walls");
    let msg = err.to_string();
    assert!(msg.contains("radius 4.9 "), "{msg}");
    assert!(
        msg.contains("between the walls") && msg.contains("9.6"),
        "{msg}"
    );
    sandbox.load(
        "let w = world(#{ dim: 2, size: vec(10, 10) });\n\
         w.walls_around();\n\
         spawn(\"ball\", #{ pos: vec(5, 5), radius: 4.7 });\n",
    );
}

#[test]
fn a_scene_spawn_of_an_impossible_radius_is_an_error_naming_the_radius() {
    let sandbox = Sandbox::new("scene_radius");
    for (radius, says) in [("100.0", "does not fit"), ("1e300", "too large")] {
        let err = sandbox
            .try_load(&format!(
                "world(#{{ dim: 2, size: vec(10, 10) }});\n\
                 spawn(\"ball\", #{{ pos: vec(5, 5), radius: {radius} }});\n"
            ))
            .err()
            .expect("the spawn fails");
        let msg = err.to_string();
        assert!(msg.contains("radius") && msg.contains(says), "{msg}");
        assert!(msg.contains("x.rhai:2"), "no file and line: {msg}");
    }
}

#[test]
fn a_hook_spawn_of_an_impossible_radius_is_an_error_though_overlaps_are_pushed() {
    let sandbox = Sandbox::new("hook_radius");
    // The default policy inside hooks pushes a spawn out of what it overlaps; that cannot make
    // a ball of radius 100 fit a 10 x 10 box, so the step fails instead of skipping it.
    sandbox.kind(
        "grower",
        "fn update(me, dt) {\n    if world().step_count == 1 {\n        spawn(\"ball\", #{ pos: vec(5, 5), radius: 100.0 });\n    }\n}\n",
    );
    let mut scene = sandbox.load(
        "world(#{ dim: 2, size: vec(10, 10) });\n\
         spawn(\"grower\", #{ pos: vec(2, 2) });\n",
    );
    step(&mut scene);
    let err = scene
        .step()
        .expect_err("the impossible spawn fails the step");
    let msg = err.to_string();
    assert!(
        msg.contains("radius 100 ") && msg.contains("10 x 10"),
        "{msg}"
    );
    assert!(msg.contains("grower.rhai:3"), "no file and line: {msg}");
}

#[test]
fn a_live_critter_grown_past_the_box_is_an_error_naming_radius_and_box() {
    let sandbox = Sandbox::new("live_radius");
    // Growing in a hook, or between steps in the scene, is held to what a spawn is.
    sandbox.kind(
        "swelling",
        "fn update(me, dt) {\n    if world().step_count == 1 {\n        me.radius = 100.0;\n    }\n}\n",
    );
    let mut scene = sandbox.load(
        "world(#{ dim: 2, size: vec(10, 10) });\n\
         spawn(\"swelling\", #{ pos: vec(5, 5) });\n",
    );
    step(&mut scene);
    let err = scene.step().expect_err("the radius does not fit");
    let msg = err.to_string();
    assert!(
        msg.contains("radius 100 ") && msg.contains("10 x 10"),
        "{msg}"
    );
    assert!(msg.contains("swelling.rhai:3"), "no file and line: {msg}");
    let err = sandbox
        .try_load(
            "world(#{ dim: 2, size: vec(10, 10) });\n\
             let b = spawn(\"ball\", #{ pos: vec(5, 5) });\n\
             b.radius = 1e300;\n",
        )
        .err()
        .expect("the setter fails");
    let msg = err.to_string();
    assert!(msg.contains("radius") && msg.contains("too large"), "{msg}");
    // A radius that fits is set.
    let mut ok = sandbox.load(
        "world(#{ dim: 2, size: vec(10, 10) });\n\
         let b = spawn(\"ball\", #{ pos: vec(5, 5) });\n\
         b.radius = 4.0;\n",
    );
    step(&mut ok);
}

#[test]
fn a_wall_through_a_critter_is_an_error_in_either_order() {
    let ball = || CritterSpec::ball(DVec2::new(5.0, 5.0)).radius(0.5);
    let wall = || WallBox::segment(DVec2::new(2.0, 5.2), DVec2::new(8.0, 5.2), 0.2).unwrap();
    // Critter first, then the wall.
    let mut w = box2(DVec2::splat(10.0), Border::Bounce);
    let id = w.spawn(ball()).unwrap();
    let err = w.add_wall(wall()).unwrap_err();
    assert!(matches!(err, Error::WallThroughCritter { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.contains(&format!("critter {id}")) && msg.contains("radius 0.5"),
        "{msg}"
    );
    assert!(msg.contains("wall at (5, 5.2)"), "{msg}");
    // Depth: the ball reaches 0.5 - (0.2 - 0.1) = 0.4 into the wall's lower face.
    assert!(msg.contains("by 0.400"), "{msg}");
    assert_eq!(w.critters().len(), 1, "the wall was added");
    assert_eq!(
        w.get(id).unwrap().pos,
        DVec2::new(5.0, 5.0),
        "the ball moved"
    );
    // Wall first, then the critter.
    let mut w = box2(DVec2::splat(10.0), Border::Bounce);
    w.add_wall(wall()).unwrap();
    let err = w.spawn(ball()).unwrap_err();
    assert!(matches!(err, Error::SpawnInsideWall { .. }), "{err}");
    assert!(err.to_string().contains("by 0.400"), "{err}");
    // Clear of each other, both orders are fine.
    let mut w = box2(DVec2::splat(10.0), Border::Bounce);
    w.spawn(CritterSpec::ball(DVec2::new(5.0, 4.5)).radius(0.5))
        .unwrap();
    w.add_wall(wall()).expect("a wall just clear of the ball");
}

#[test]
fn a_scene_wall_through_a_critter_is_an_error_in_either_order() {
    let sandbox = Sandbox::new("scene_wall_order");
    let spawn = "spawn(\"ball\", #{ pos: vec(5, 5), radius: 0.5 });\n";
    let wall = "w.wall(vec(2, 5.2), vec(8, 5.2));\n";
    for body in [format!("{spawn}{wall}"), format!("{wall}{spawn}")] {
        let err = sandbox
            .try_load(&format!(
                "let w = world(#{{ dim: 2, size: vec(10, 10) }});\n{body}"
            ))
            .err()
            .expect("the scene fails");
        let msg = err.to_string();
        assert!(msg.contains("wall") && msg.contains("by 0.400"), "{msg}");
        assert!(msg.contains("x.rhai:3"), "no file and line: {msg}");
    }
}

// ----- exact methods at any dt ------------------------------------------------------------------

use critterbox::scenes::{builtin, AnyWorld, SceneParams};
use critterbox::Method;

/// The 2D world of built-in scene `name` with `dt` and `method`.
fn scene2(name: &str, n: Option<usize>, dt: f64, method: Method) -> World<DVec2> {
    let params = SceneParams {
        n,
        dt: Some(dt),
        ..SceneParams::default()
    };
    let scene = builtin(name, &params).expect("a built-in scene");
    let AnyWorld::D2(mut w) = scene.world else {
        panic!("{name} is 2D")
    };
    w.set_method(method).expect("a valid method");
    w
}

/// How far the deepest disk reaches into a wall, relative to its radius, measured against each
/// wall's box independently of the engine's contact code (the scenes' walls are aligned).
fn deepest_into_walls(w: &World<DVec2>) -> f64 {
    let walls: Vec<_> = w
        .critters()
        .iter()
        .filter_map(|c| c.wall().cloned())
        .collect();
    assert!(!walls.is_empty(), "the check needs walls");
    let mut deepest: f64 = 0.0;
    for c in w.critters().iter().filter(|c| !c.is_wall()) {
        for wall in &walls {
            let (lo, hi) = (wall.center - wall.half, wall.center + wall.half);
            let gap = distance_to_aligned_box(c.pos, lo, hi);
            deepest = deepest.max((c.radius() - gap) / c.radius());
        }
    }
    deepest
}

/// Distance from `p` to the box [lo, hi] (0 inside), independent of the engine's wall code.
fn distance_to_aligned_box(p: DVec2, lo: DVec2, hi: DVec2) -> f64 {
    (p.max(lo).min(hi) - p).length()
}

/// Every critter's id, position and velocity, as bits.
fn state_bits(w: &World<DVec2>) -> Vec<(String, [u64; 4])> {
    w.critters()
        .iter()
        .map(|c| {
            let bits = [c.pos.x, c.pos.y, c.vel.x, c.vel.y].map(f64::to_bits);
            (c.id().to_string(), bits)
        })
        .collect()
}

/// Steps `w` `steps` times; an error must be the endless-events error, naming the step.
fn run_exact(w: &mut World<DVec2>, steps: u64) -> Result<Vec<String>, Error> {
    let mut log = Vec::new();
    for k in 0..steps {
        match w.step() {
            Ok(()) => log.extend(w.events().log.iter().cloned()),
            Err(e) => {
                assert!(
                    matches!(e, Error::EndlessEvents { step, .. } if step == k),
                    "step {k}: {e}"
                );
                assert!(e.to_string().contains(&format!("step {k}:")), "{e}");
                return Err(e);
            }
        }
    }
    Ok(log)
}

#[test]
fn exact_methods_at_a_huge_dt_keep_every_ball_inside_the_walls() {
    // Steps far longer than the time between collisions: the event budget runs out. The
    // billiard balls lose energy at every hit and their events run out; the elastic gas's do
    // within a step of 1e3, not within one of 1e9 (an error then).
    let cases = [
        ("billiards", None, 1e9, true),
        ("gas", Some(60), 1e3, true),
        ("gas", Some(60), 1e9, false),
    ];
    for method in [Method::Event, Method::Swept, Method::Auto] {
        for (name, n, dt, finishes) in cases {
            let mut w = scene2(name, n, dt, method);
            let energy0 = w.kinetic_energy();
            let outcome = run_exact(&mut w, 3);
            assert_eq!(
                outcome.is_ok(),
                finishes,
                "{name} {method} dt {dt}: {outcome:?}"
            );
            match outcome {
                Ok(log) => {
                    assert!(
                        w.totals().budget_exceeded > 0,
                        "{name} {method}: no overrun"
                    );
                    let deepest = deepest_into_walls(&w);
                    assert!(
                        deepest < 1e-6,
                        "{name} {method}: a ball is {deepest} r into a wall"
                    );
                    let inside = w.critters().iter().all(|c| c.pos.is_finite());
                    assert!(inside, "{name} {method}");
                    let warned = log.iter().filter(|l| l.contains("event budget")).count();
                    assert_eq!(warned, 1, "{name} {method}: {log:?}");
                    if name == "gas" {
                        // Elastic: every collision keeps the energy, whatever the step.
                        let change = (w.kinetic_energy() - energy0).abs() / energy0;
                        assert!(change < 1e-9, "{name} {method}: energy changed by {change}");
                    }
                }
                Err(e) => assert!(e.to_string().contains("--dt"), "{e}"),
            }
        }
    }
}

#[test]
fn a_carried_on_step_is_deterministic() {
    let run = || {
        let mut w = scene2("gas", Some(60), 1e3, Method::Event);
        run_exact(&mut w, 2).expect("the gas's events run out");
        assert!(w.totals().budget_exceeded > 0, "the setup must overrun");
        state_bits(&w)
    };
    assert_eq!(run(), run());
}

#[test]
fn endless_events_are_an_error_naming_the_step_and_the_pair() {
    // A ball bouncing on a floor under gravity: its bounces shrink without end (the TC model
    // makes the last ones elastic), so a step of 10 s never runs out of events.
    let mut config = WorldConfig::new(DVec2::ZERO, DVec2::splat(10.0));
    config.gravity = DVec2::new(0.0, -9.81);
    config.dt = 10.0;
    config.method = Method::Event;
    let mut w = World::new(config).unwrap();
    let floor = w
        .add_wall(WallBox::aligned(DVec2::ZERO, DVec2::new(10.0, 0.2)).unwrap())
        .unwrap();
    let ball = w
        .spawn(
            CritterSpec::ball(DVec2::new(5.0, 1.0))
                .radius(0.5)
                .restitution(0.5),
        )
        .unwrap();
    let e = w.step().expect_err("the events do not run out");
    let msg = e.to_string();
    assert!(matches!(e, Error::EndlessEvents { step: 0, .. }), "{msg}");
    assert!(
        msg.contains(&format!("critter {ball} (ball) and wall {floor}")),
        "{msg}"
    );
    assert!(msg.contains("--dt") && msg.contains("--method"), "{msg}");
    let y = w.get(ball).unwrap().pos.y;
    assert!(y >= 0.7 - 1e-6, "the ball fell into the floor: y = {y}");
}

// ----- the discrete step's tunnelling warning ---------------------------------------------------

#[test]
fn discrete_warns_once_when_a_critter_moves_farther_than_its_radius() {
    for (method, per) in [(Method::Discrete, "step"), (Method::Substep(2), "substep")] {
        let mut config = WorldConfig::new(DVec2::ZERO, DVec2::splat(100.0));
        config.dt = 1.0;
        config.method = method;
        let mut w = World::new(config).unwrap();
        let slow = w
            .spawn(CritterSpec::ball(DVec2::new(5.0, 5.0)).vel(DVec2::new(0.1, 0.0)))
            .unwrap();
        let fast = w
            .spawn(CritterSpec::ball(DVec2::new(5.0, 50.0)).vel(DVec2::new(30.0, 0.0)))
            .unwrap();
        w.step().unwrap();
        let log = w.events().log.clone();
        assert_eq!(log.len(), 1, "{log:?}");
        assert!(
            log[0].contains(&format!("critter {fast} (ball)")),
            "{log:?}"
        );
        assert!(log[0].contains(&format!("in one {per}")), "{log:?}");
        assert!(
            log[0].contains("--method swept") && log[0].contains("event"),
            "{log:?}"
        );
        assert!(!log[0].contains(&format!("{slow}")), "{log:?}");
        // The warning changes nothing: the fast ball moved by the motion law alone.
        assert_eq!(w.get(fast).unwrap().pos, DVec2::new(35.0, 50.0));
        for _ in 0..3 {
            w.step().unwrap();
            assert!(
                w.events().log.is_empty(),
                "said again: {:?}",
                w.events().log
            );
        }
    }
}

#[test]
fn a_normal_discrete_run_does_not_warn() {
    for method in [Method::Discrete, Method::Substep(3)] {
        let mut w = scene2("gas", Some(200), 1.0 / 60.0, method);
        for _ in 0..60 {
            w.step().unwrap();
            assert!(w.events().log.is_empty(), "{:?}", w.events().log);
        }
    }
}
