//! No silently wrong run: a critter that cannot exist (too big for its box or its walls, a
//! radius beyond f64's reach) is an error naming the radius, whatever spawns it; a wall through a
//! critter is an error in either order; the exact methods never end a step with critters moved
//! past their events; the discrete step says once when it may tunnel.

mod script_common;

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
    assert!(msg.contains("between the walls") && msg.contains("9.6"), "{msg}");
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
    let err = scene.step().expect_err("the impossible spawn fails the step");
    let msg = err.to_string();
    assert!(msg.contains("radius 100 ") && msg.contains("10 x 10"), "{msg}");
    assert!(msg.contains("grower.rhai:3"), "no file and line: {msg}");
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
    assert!(msg.contains(&format!("critter {id}")) && msg.contains("radius 0.5"), "{msg}");
    assert!(msg.contains("wall at (5, 5.2)"), "{msg}");
    // Depth: the ball reaches 0.5 - (0.2 - 0.1) = 0.4 into the wall's lower face.
    assert!(msg.contains("by 0.400"), "{msg}");
    assert_eq!(w.critters().len(), 1, "the wall was added");
    assert_eq!(w.get(id).unwrap().pos, DVec2::new(5.0, 5.0), "the ball moved");
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
