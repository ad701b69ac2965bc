//! Bad input gives an `Err` that names the field (and the kind), never a panic, and changes
//! nothing: critters, worlds, walls, kinds, scenes and queued spawns.

use crate::common;

use common::*;
use critterbox::glam::{DMat3, DVec2, DVec3};
use critterbox::scenes::{self, gas, GasParams, SceneParams};
use critterbox::{
    CollideCtx, CritterSpec, Error, KindDefaults, KindHooks, WallBox, World, WorldConfig, CP_PLAYER,
};
use std::rc::Rc;

const BAD_POSITIVE: [f64; 5] = [-1.0, 0.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY];

/// Asserts the spawn fails with an error naming `field` and the kind, and adds nothing.
#[track_caller]
fn assert_spawn_rejected(world: &mut World<DVec2>, spec: CritterSpec<DVec2>, field: &str) {
    let kind = spec.kind.clone();
    let before = world.critters().len();
    let err = world.spawn(spec).expect_err("a bad spec was accepted");
    let msg = err.to_string();
    assert!(
        matches!(err, Error::InvalidCritter { field: f, .. } if f == field),
        "wrong error for {field}: {msg}"
    );
    assert!(
        msg.contains(field),
        "'{msg}' does not name the field {field}"
    );
    assert!(msg.contains(&kind), "'{msg}' does not name the kind {kind}");
    assert_eq!(
        world.critters().len(),
        before,
        "a rejected critter was added"
    );
}

fn world_with_kind() -> World<DVec2> {
    let mut world = world2(10.0);
    register(&mut world, "mole", KindDefaults::default(), Rc::new(()));
    world
}

#[test]
fn bad_radius_mass_or_density_is_an_error_naming_the_field_and_kind() {
    let mut world = world_with_kind();
    let p = DVec2::new(5.0, 5.0);
    for kind in ["ball", "mole"] {
        for bad in BAD_POSITIVE {
            assert_spawn_rejected(&mut world, CritterSpec::new(kind, p).radius(bad), "radius");
            assert_spawn_rejected(&mut world, CritterSpec::new(kind, p).mass(bad), "mass");
            assert_spawn_rejected(
                &mut world,
                CritterSpec::new(kind, p).density(bad),
                "density",
            );
        }
    }
}

#[test]
fn bad_position_or_velocity_is_an_error_naming_the_field() {
    let mut world = world_with_kind();
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert_spawn_rejected(
            &mut world,
            CritterSpec::new("mole", DVec2::new(bad, 5.0)),
            "position",
        );
        assert_spawn_rejected(
            &mut world,
            CritterSpec::new("mole", DVec2::new(5.0, bad)),
            "position",
        );
        let v = DVec2::new(1.0, bad);
        assert_spawn_rejected(
            &mut world,
            CritterSpec::new("mole", DVec2::splat(5.0)).vel(v),
            "velocity",
        );
    }
}

#[test]
fn restitution_outside_zero_to_one_is_an_error_naming_the_field() {
    let mut world = world_with_kind();
    for bad in [-0.1, 1.0 + 1e-12, 2.0, f64::NAN, f64::INFINITY] {
        let spec = CritterSpec::new("mole", DVec2::splat(5.0)).restitution(bad);
        assert_spawn_rejected(&mut world, spec, "restitution");
    }
    // The ends are allowed.
    world
        .spawn(CritterSpec::ball(DVec2::splat(2.0)).restitution(0.0))
        .unwrap();
    world
        .spawn(CritterSpec::ball(DVec2::splat(8.0)).restitution(1.0))
        .unwrap();
}

#[test]
fn non_finite_priority_or_health_is_an_error_naming_the_field() {
    let mut world = world_with_kind();
    for bad in [f64::NAN, f64::INFINITY] {
        assert_spawn_rejected(
            &mut world,
            CritterSpec::new("mole", DVec2::splat(5.0)).priority(bad),
            "priority",
        );
        assert_spawn_rejected(
            &mut world,
            CritterSpec::new("mole", DVec2::splat(5.0)).health(bad),
            "health",
        );
    }
}

#[test]
fn spawning_outside_the_world_box_is_an_error() {
    let mut world = world2(10.0);
    for p in [
        DVec2::new(-0.1, 5.0),
        DVec2::new(5.0, 10.5),
        DVec2::new(1e300, 1e300),
    ] {
        let err = world.spawn(CritterSpec::ball(p)).unwrap_err();
        assert!(
            err.to_string().contains("position") && err.to_string().contains("outside"),
            "{err}"
        );
    }
    assert!(world.critters().is_empty());
}

#[test]
fn spawning_inside_a_wall_is_spawn_inside_wall() {
    let mut world = world2(10.0);
    let w = world
        .add_wall(WallBox::segment(DVec2::new(2.0, 5.0), DVec2::new(8.0, 5.0), 0.2).unwrap())
        .unwrap();
    // Centre inside, and centre outside but overlapping.
    for p in [
        DVec2::new(5.0, 5.0),
        DVec2::new(5.0, 5.4),
        DVec2::new(8.3, 5.3),
    ] {
        let err = world.spawn(CritterSpec::ball(p).radius(0.5)).unwrap_err();
        assert!(
            matches!(err, Error::SpawnInsideWall { wall, .. } if wall == w),
            "{err}"
        );
        assert!(err.to_string().contains("wall"), "{err}");
    }
    assert_eq!(world.critters().len(), 1, "only the wall");
    // Just clear of the face is fine.
    world
        .spawn(CritterSpec::ball(DVec2::new(5.0, 5.61)).radius(0.5))
        .unwrap();
    // 3D too.
    let mut world = world3(10.0);
    world
        .add_wall(WallBox::aligned(DVec3::splat(4.0), DVec3::splat(6.0)).unwrap())
        .unwrap();
    let err = world
        .spawn(CritterSpec::ball(DVec3::new(6.2, 6.2, 6.2)))
        .unwrap_err();
    assert!(matches!(err, Error::SpawnInsideWall { .. }), "{err}");
}

#[test]
fn unknown_kind_is_an_error_listing_the_known_kinds() {
    let mut world = world_with_kind();
    let err = world
        .spawn(CritterSpec::new("dragon", DVec2::splat(5.0)))
        .unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, Error::UnknownKind { .. }));
    for name in ["dragon", "ball", "wall", "mole"] {
        assert!(msg.contains(name), "'{msg}' does not mention {name}");
    }
    assert!(world.critters_of("dragon").is_err());
    // A kind with an unknown parent, the same.
    let err = world
        .register_kind("imp", Some("dragon"), KindDefaults::default(), Rc::new(()))
        .unwrap_err();
    assert!(
        err.to_string().contains("dragon") && err.to_string().contains("ball"),
        "{err}"
    );
}

#[test]
fn spawning_a_wall_as_a_critter_is_an_error() {
    let mut world = world2(10.0);
    let err = world
        .spawn(CritterSpec::new("wall", DVec2::splat(5.0)))
        .unwrap_err();
    assert!(err.to_string().contains("add_wall"), "{err}");
}

#[test]
fn bad_kind_defaults_or_duplicate_name_are_errors_naming_the_kind_and_field() {
    let mut world = world2(10.0);
    let cases: [(&str, KindDefaults); 6] = [
        (
            "radius",
            KindDefaults {
                radius: 0.0,
                ..KindDefaults::default()
            },
        ),
        (
            "density",
            KindDefaults {
                density: f64::NAN,
                ..KindDefaults::default()
            },
        ),
        (
            "mass",
            KindDefaults {
                mass: Some(-2.0),
                ..KindDefaults::default()
            },
        ),
        (
            "priority",
            KindDefaults {
                priority: f64::INFINITY,
                ..KindDefaults::default()
            },
        ),
        (
            "restitution",
            KindDefaults {
                restitution: 1.5,
                ..KindDefaults::default()
            },
        ),
        (
            "health",
            KindDefaults {
                health: f64::NAN,
                ..KindDefaults::default()
            },
        ),
    ];
    for (field, defaults) in cases {
        let err = world
            .register_kind("newt", None, defaults, Rc::new(()))
            .unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("newt") && msg.contains(field),
            "'{msg}' should name newt and {field}"
        );
    }
    assert!(
        world.kinds().id("newt").is_err(),
        "a rejected kind was registered"
    );
    for name in ["ball", "wall", "", "  "] {
        assert!(
            world
                .register_kind(name, None, KindDefaults::default(), Rc::new(()))
                .is_err(),
            "name '{name}'"
        );
    }
}

#[test]
fn bad_world_size_or_time_step_is_an_error_naming_the_field() {
    let cases: [(&str, WorldConfig<DVec2>); 9] = [
        ("size", WorldConfig::new(DVec2::ZERO, DVec2::ZERO)),
        ("size", WorldConfig::new(DVec2::ZERO, DVec2::new(10.0, 0.0))),
        (
            "size",
            WorldConfig::new(DVec2::splat(5.0), DVec2::splat(1.0)),
        ),
        (
            "box",
            WorldConfig::new(DVec2::ZERO, DVec2::new(f64::NAN, 10.0)),
        ),
        (
            "box",
            WorldConfig::new(DVec2::new(f64::NEG_INFINITY, 0.0), DVec2::splat(10.0)),
        ),
        (
            "dt",
            WorldConfig::new(DVec2::ZERO, DVec2::splat(10.0)).dt(0.0),
        ),
        (
            "dt",
            WorldConfig::new(DVec2::ZERO, DVec2::splat(10.0)).dt(-0.01),
        ),
        (
            "dt",
            WorldConfig::new(DVec2::ZERO, DVec2::splat(10.0)).dt(f64::NAN),
        ),
        (
            "gravity",
            WorldConfig::new(DVec2::ZERO, DVec2::splat(10.0)).gravity(DVec2::new(0.0, f64::NAN)),
        ),
    ];
    for (field, config) in cases {
        let err = World::new(config.clone())
            .err()
            .unwrap_or_else(|| panic!("{config:?} was accepted"));
        assert!(
            matches!(err, Error::InvalidWorld { field: f, .. } if f == field),
            "{field}: {err}"
        );
        assert!(
            err.to_string().contains(field),
            "'{err}' does not name {field}"
        );
    }
    let err = World::new(WorldConfig::new(DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0)))
        .err()
        .unwrap();
    assert!(err.to_string().contains("size"), "{err}");
    let mut world = world2(10.0);
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let err = world.set_dt(bad).unwrap_err();
        assert!(err.to_string().contains("dt"), "{err}");
    }
    assert_eq!(world.dt(), DT, "a rejected dt was kept");
}

#[test]
fn bad_wall_geometry_is_an_error_naming_the_field() {
    let a = DVec2::new(1.0, 1.0);
    let err = WallBox::segment(a, a, 0.2).unwrap_err();
    assert!(err.to_string().contains("ends"), "zero length: {err}");
    for t in BAD_POSITIVE {
        let err = WallBox::segment(a, DVec2::new(5.0, 1.0), t).unwrap_err();
        assert!(err.to_string().contains("size"), "thickness {t}: {err}");
    }
    let err = WallBox::segment(a, DVec2::new(f64::NAN, 1.0), 0.2).unwrap_err();
    assert!(err.to_string().contains("ends"), "{err}");
    let err = WallBox::aligned(DVec3::ZERO, DVec3::new(1.0, 0.0, 1.0)).unwrap_err();
    assert!(err.to_string().contains("size"), "{err}");
    let err = WallBox::cuboid(
        DVec3::ZERO,
        DVec3::ONE,
        DMat3::from_diagonal(DVec3::new(1.0, 2.0, 1.0)),
    )
    .unwrap_err();
    assert!(err.to_string().contains("orientation"), "{err}");
    let err = WallBox::cuboid(DVec3::splat(f64::NAN), DVec3::ONE, DMat3::IDENTITY).unwrap_err();
    assert!(err.to_string().contains("center"), "{err}");
    // A wall built by hand, bypassing the constructors, is checked when added.
    let mut world = world2(10.0);
    let bad = WallBox {
        center: DVec2::splat(5.0),
        frame: DVec2::X,
        half: DVec2::new(1.0, 0.0),
    };
    assert!(world
        .add_wall(bad)
        .unwrap_err()
        .to_string()
        .contains("size"));
    assert!(world.critters().is_empty());
}

#[test]
fn bad_setters_on_a_live_critter_are_errors_naming_the_field() {
    let mut world = world2(10.0);
    let id = world.spawn(CritterSpec::ball(DVec2::splat(5.0))).unwrap();
    let c = world.get_mut(id).unwrap();
    for bad in BAD_POSITIVE {
        assert!(c
            .set_radius(bad)
            .unwrap_err()
            .to_string()
            .contains("radius"));
        assert!(c.set_mass(bad).unwrap_err().to_string().contains("mass"));
    }
    assert!(c
        .set_priority(f64::NAN)
        .unwrap_err()
        .to_string()
        .contains("priority"));
    assert_eq!(
        (c.radius(), c.mass()),
        (0.5, 0.125),
        "a rejected value was kept"
    );
}

#[test]
fn unknown_scene_or_bad_scene_parameters_are_errors() {
    let err = scenes::build("tornado", &SceneParams::default())
        .err()
        .unwrap();
    let msg = err.to_string();
    assert!(matches!(err, Error::UnknownScene { .. }));
    for name in ["tornado", "gas", "gas3d", "cradle", "billiards", "pegs"] {
        assert!(msg.contains(name), "'{msg}' does not mention {name}");
    }
    let zero = SceneParams {
        n: Some(0),
        ..SceneParams::default()
    };
    let err = scenes::build("gas", &zero).err().unwrap();
    assert!(
        matches!(err, Error::InvalidWorld { field: "n", .. }),
        "{err}"
    );
    assert!(err.to_string().contains("n = 0"), "{err}");
    let bad_dt = SceneParams {
        dt: Some(-1.0),
        ..SceneParams::default()
    };
    assert!(scenes::build("cradle", &bad_dt)
        .err()
        .unwrap()
        .to_string()
        .contains("dt"));
    let dense = GasParams {
        packing: 0.9,
        ..GasParams::default()
    };
    assert!(gas::<DVec2>(&dense)
        .err()
        .unwrap()
        .to_string()
        .contains("packing"));
}

/// Queues a spawn with a negative radius from its collide hook.
struct BadSpawner;

impl KindHooks<DVec2> for BadSpawner {
    fn collide(&self, ctx: &mut CollideCtx<'_, DVec2>) -> Result<bool, Error> {
        ctx.spawn(CritterSpec::ball(DVec2::new(1.0, 1.0)).radius(-1.0));
        Ok(ctx.collide_default())
    }
}

#[test]
fn bad_spawn_queued_by_a_hook_fails_the_step_with_the_field_named() {
    let mut world = world2(10.0);
    register(
        &mut world,
        "bad",
        with_priority(CP_PLAYER),
        Rc::new(BadSpawner),
    );
    world
        .spawn(CritterSpec::new("bad", DVec2::new(5.0, 5.0)))
        .unwrap();
    world
        .spawn(CritterSpec::ball(DVec2::new(5.9, 5.0)))
        .unwrap();
    let err = world.step().unwrap_err();
    assert!(err.to_string().contains("radius"), "{err}");
    assert_eq!(world.critters().len(), 2);
}

/// A hook that fails: the step returns the error, naming the kind and the critter.
struct Failing;

impl KindHooks<DVec2> for Failing {
    fn collide(&self, _ctx: &mut CollideCtx<'_, DVec2>) -> Result<bool, Error> {
        Err(Error::InvalidKind {
            kind: "failing".into(),
            reason: "this hook always fails".into(),
        })
    }
}

#[test]
fn failing_hook_is_an_error_naming_the_kind_and_critter() {
    let mut world = world2(10.0);
    register(
        &mut world,
        "failing",
        with_priority(CP_PLAYER),
        Rc::new(Failing),
    );
    let f = world
        .spawn(CritterSpec::new("failing", DVec2::new(5.0, 5.0)))
        .unwrap();
    world
        .spawn(CritterSpec::ball(DVec2::new(5.9, 5.0)))
        .unwrap();
    let err = world.step().unwrap_err();
    assert!(
        matches!(&err, Error::Hook { critter, .. } if *critter == f),
        "{err}"
    );
    assert!(
        err.to_string().contains("failing") && err.to_string().contains("always fails"),
        "{err}"
    );
}

/// Extreme but valid numbers: the step stays finite and does not panic.
#[test]
fn extreme_valid_sizes_and_speeds_do_not_panic_or_produce_nan() {
    let mut world = World::new(WorldConfig::new(DVec2::ZERO, DVec2::splat(1e6))).unwrap();
    world
        .spawn(CritterSpec::ball(DVec2::splat(10.0)).radius(1e-9))
        .unwrap();
    world
        .spawn(CritterSpec::ball(DVec2::splat(5e5)).radius(1e4))
        .unwrap();
    world
        .spawn(
            CritterSpec::ball(DVec2::splat(7e5))
                .radius(1e-3)
                .vel(DVec2::new(1e12, -1e12)),
        )
        .unwrap();
    // A ball as wide as the box in one direction.
    let mut thin = World::new(WorldConfig::new(DVec2::ZERO, DVec2::new(10.0, 0.5))).unwrap();
    thin.spawn(
        CritterSpec::ball(DVec2::new(5.0, 0.25))
            .radius(0.25)
            .vel(DVec2::new(1.0, 1.0)),
    )
    .unwrap();
    for _ in 0..5 {
        world.step().unwrap();
        thin.step().unwrap();
    }
    for c in world.critters().iter().chain(thin.critters().iter()) {
        assert!(c.pos.is_finite() && c.vel.is_finite(), "{c:?}");
    }
}
