//! Same world, same bits: every built-in scene run twice gives identical state hashes and
//! identical position and velocity bits; a different seed gives a different run. And the
//! periodic (wrap) border: critters cross it unchanged and collide across it.

use crate::common;

use common::*;
use critterbox::glam::DVec2;
use critterbox::scenes::{self, AnyWorld, SceneParams};
use critterbox::{Border, CritterSpec, World, WorldConfig};

fn bits(world: &AnyWorld) -> StateBits {
    match world {
        AnyWorld::D2(w) => state_bits(w),
        AnyWorld::D3(w) => state_bits(w),
    }
}

/// Builds and runs a scene for `steps`, returning the hash after every step and the final bits.
fn run_scene(name: &str, params: &SceneParams, steps: usize) -> (Vec<u64>, StateBits) {
    let mut world = scenes::build(name, params).unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut hashes = vec![world.state_hash()];
    for _ in 0..steps {
        world.step().unwrap();
        hashes.push(world.state_hash());
    }
    assert!(
        world.totals().contacts > 0,
        "{name}: test setup: something collided"
    );
    (hashes, bits(&world))
}

fn params(n: Option<usize>, seed: u64) -> SceneParams {
    SceneParams {
        n,
        seed,
        ..SceneParams::default()
    }
}

#[test]
fn every_built_in_scene_repeats_bit_for_bit() {
    let scenes = [
        ("gas", Some(500)),
        ("gas3d", Some(500)),
        ("gas-wrap", Some(500)),
        ("pegs", None),
        ("billiards", None),
        ("cradle", None),
    ];
    for (name, n) in scenes {
        // Pegs runs at dt = 1/240: the balls need ~250 steps to fall onto the pegs.
        let steps = match name {
            "cradle" => 150,
            "pegs" => 400,
            _ => 100,
        };
        let (h1, b1) = run_scene(name, &params(n, 1), steps);
        let (h2, b2) = run_scene(name, &params(n, 1), steps);
        assert_eq!(h1, h2, "{name}: state hashes differ between two runs");
        assert_eq!(
            b1, b2,
            "{name}: position/velocity bits differ between two runs"
        );
        // The hash follows the state: it changed as the scene moved.
        assert_ne!(
            h1[0], h1[steps],
            "{name}: the hash did not change over the run"
        );
    }
}

#[test]
fn a_different_seed_gives_a_different_run() {
    for name in ["gas", "gas3d", "gas-wrap"] {
        let (h1, b1) = run_scene(name, &params(Some(200), 1), 100);
        let (h2, b2) = run_scene(name, &params(Some(200), 2), 100);
        assert_ne!(h1[0], h2[0], "{name}: seeds 1 and 2 built the same world");
        assert_ne!(
            h1[100], h2[100],
            "{name}: seeds 1 and 2 end with the same hash"
        );
        assert_ne!(b1, b2, "{name}: seeds 1 and 2 end with the same state");
    }
}

#[test]
fn state_hash_sees_a_one_ulp_change_in_one_velocity() {
    let build = || match scenes::build("gas", &params(Some(100), 1)).unwrap() {
        AnyWorld::D2(w) => w,
        AnyWorld::D3(_) => unreachable!("gas is 2D"),
    };
    let (a, mut b) = (build(), build());
    assert_eq!(a.state_hash(), b.state_hash());
    let id = b.critters().iter().find(|c| !c.is_wall()).unwrap().id();
    let v = &mut b.get_mut(id).unwrap().vel;
    v.x = f64::from_bits(v.x.to_bits() + 1);
    assert_ne!(a.state_hash(), b.state_hash());
}

// ----- the periodic border ----------------------------------------------------------------------

fn wrap_world() -> World<DVec2> {
    World::new(WorldConfig::new(DVec2::ZERO, DVec2::splat(10.0)).border(Border::Wrap)).unwrap()
}

#[test]
fn ball_crossing_the_periodic_edge_reappears_opposite_with_the_same_velocity() {
    // (start, velocity, where it should be after one step: moved, then shifted by one box size)
    let cases = [
        (
            DVec2::new(9.99, 5.0),
            DVec2::new(1.0, 0.5),
            DVec2::new(-10.0, 0.0),
        ),
        (
            DVec2::new(5.0, 0.005),
            DVec2::new(-0.3, -1.0),
            DVec2::new(0.0, 10.0),
        ),
        (
            DVec2::new(0.01, 9.995),
            DVec2::new(-1.2, 0.9),
            DVec2::new(10.0, -10.0),
        ),
    ];
    for (p, v, shift) in cases {
        let mut world = wrap_world();
        let id = world.spawn(CritterSpec::ball(p).vel(v)).unwrap();
        world.step().unwrap();
        let c = world.get(id).unwrap();
        assert_eq!(
            c.vel.x.to_bits(),
            v.x.to_bits(),
            "from {p}: velocity changed"
        );
        assert_eq!(
            c.vel.y.to_bits(),
            v.y.to_bits(),
            "from {p}: velocity changed"
        );
        assert_close_vec(
            c.pos,
            after_move(p, v, world.dt()) + shift,
            ROUND_OFF,
            &format!("from {p}: position"),
        );
        assert!((0.0..10.0).contains(&c.pos.x) && (0.0..10.0).contains(&c.pos.y));
    }
}

#[test]
fn balls_touching_across_the_periodic_edge_collide_elastically() {
    let mut world = wrap_world();
    let (pa, va, ma) = (DVec2::new(0.3, 5.0), DVec2::new(-1.0, 0.1), 1.0);
    let (pb, vb, mb) = (DVec2::new(9.75, 5.2), DVec2::new(1.0, -0.2), 2.5);
    let a = world.spawn(CritterSpec::ball(pa).vel(va).mass(ma)).unwrap();
    let b = world.spawn(CritterSpec::ball(pb).vel(vb).mass(mb)).unwrap();
    let (qa, qb) = (
        after_move(pa, va, world.dt()),
        after_move(pb, vb, world.dt()),
    );
    let d = qb - qa - DVec2::new(10.0, 0.0); // b's nearest image is one box to the left
    assert!(
        d.length() < 1.0 && (vb - va).dot(d) < 0.0,
        "test setup: overlapping, approaching"
    );
    let n = unit(d);
    let (p0, e0) = (world.momentum(), world.kinetic_energy());
    world.step().unwrap();
    assert_eq!(
        world.events().collisions.len(),
        1,
        "no collision across the edge"
    );
    let (ca, cb) = (world.get(a).unwrap(), world.get(b).unwrap());
    let (want_a, want_b) = pop_elastic(va.dot(n), vb.dot(n), mb / ma);
    assert_close(ca.vel.dot(n), want_a, ROUND_OFF, "caller normal velocity");
    assert_close(cb.vel.dot(n), want_b, ROUND_OFF, "arg normal velocity");
    assert_close_vec(
        tangential(ca.vel, n),
        tangential(va, n),
        ROUND_OFF,
        "caller tangential",
    );
    assert_close_vec(
        tangential(cb.vel, n),
        tangential(vb, n),
        ROUND_OFF,
        "arg tangential",
    );
    assert_close_vec(
        world.momentum(),
        p0,
        MOMENTUM_ROUND_OFF * (ma * va.length() + mb * vb.length()),
        "momentum",
    );
    assert_close(world.kinetic_energy(), e0, ROUND_OFF * e0, "kinetic energy");
    // Separated to touching through the edge, without leaving the box.
    let mut gap = cb.pos - ca.pos;
    gap.x -= 10.0 * (gap.x / 10.0).round();
    gap.y -= 10.0 * (gap.y / 10.0).round();
    assert_close(gap.length(), 1.0, ROUND_OFF, "distance through the edge");
    for c in [ca, cb] {
        assert!((0.0..10.0).contains(&c.pos.x) && (0.0..10.0).contains(&c.pos.y));
    }
}

/// Positions in a periodic world live in [min, max): `spawn` refuses anything else and the move
/// wraps every critter back in. The separation after a collision is applied after the move, so a
/// push across the edge should be wrapped too.
#[test]
fn separation_across_the_periodic_edge_keeps_positions_in_the_box() {
    let mut world = wrap_world();
    let a = world
        .spawn(CritterSpec::ball(DVec2::new(9.98, 5.0)))
        .unwrap();
    let b = world
        .spawn(CritterSpec::ball(DVec2::new(9.1, 5.0)).vel(DVec2::new(0.6, 0.0)))
        .unwrap();
    world.step().unwrap();
    assert_eq!(
        world.events().collisions.len(),
        1,
        "test setup: they collide"
    );
    for id in [a, b] {
        let p = world.get(id).unwrap().pos;
        assert!(
            (0.0..10.0).contains(&p.x) && (0.0..10.0).contains(&p.y),
            "{id} ends at {p}, outside the box"
        );
    }
}
