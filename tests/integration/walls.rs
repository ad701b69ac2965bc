//! Balls against walls: reflection off faces, edges and corners with the normal taken from the
//! exact closest point, rotated walls, balls whose centre got inside, and no randomness.
//!
//! Expected normals and positions are computed here from the wall's geometry, not read from the
//! engine.

use crate::common;

use common::*;
use critterbox::glam::{DMat3, DVec2, DVec3};
use critterbox::{CritterId, CritterSpec, Vector, WallBox, World, CP_WALL};

const R: f64 = 0.5;

/// One step of a single ball of radius `R` near `wall`; returns the world after the step, the
/// ball's id and its position after the move (before the response).
fn hit<V: Vector>(wall: WallBox<V>, p: V, v: V) -> (World<V>, CritterId, V) {
    let mut world = world::<V>(10.0);
    let w = world.add_wall(wall).expect("valid wall");
    // Spawned clear of the wall, then placed: some starts already overlap the wall a little,
    // which `spawn` rightly refuses.
    let ball = world
        .spawn(CritterSpec::ball(V::splat(1.0)).radius(R))
        .expect("ball clear of the wall");
    {
        let c = world.get_mut(ball).unwrap();
        c.pos = p;
        c.vel = v;
    }
    let q = after_move(p, v, world.dt());
    world.step().expect("step");
    let events = &world.events().collisions;
    assert_eq!(events.len(), 1, "exactly one wall collision");
    assert_eq!(
        (events[0].caller, events[0].arg),
        (w, ball),
        "the wall (priority CP_WALL) calls"
    );
    assert_eq!(world.get(w).unwrap().priority(), CP_WALL);
    (world, ball, q)
}

/// Checks a reflection off a surface whose closest point to the moved centre `q` is `surface`:
/// normal from that point to the centre, normal velocity reversed, tangential kept, speed kept,
/// and the ball placed at the surface point plus its radius along the normal.
fn check_reflection<V: Vector>(
    world: &World<V>,
    ball: CritterId,
    q: V,
    surface: V,
    v: V,
    label: &str,
) {
    let n = unit(q - surface);
    assert!(
        (q - surface).length() < R && v.dot(n) < 0.0,
        "{label}: test setup (touching, approaching)"
    );
    let c = world.get(ball).unwrap();
    assert_close_vec(
        world.events().collisions[0].normal,
        n,
        ROUND_OFF,
        &format!("{label}: contact normal"),
    );
    assert_reflected(c.vel, v, n, label);
    assert_close(
        c.vel.length(),
        v.length(),
        ROUND_OFF,
        &format!("{label}: speed kept at e = 1"),
    );
    assert_close_vec(
        c.pos,
        surface + n * R,
        ROUND_OFF,
        &format!("{label}: pushed out to touch"),
    );
}

// ----- 2D -----------------------------------------------------------------------------------

/// The horizontal wall from (2, 5) to (8, 5), thickness 0.2: the box [2, 8] x [4.9, 5.1].
fn flat_wall() -> WallBox<DVec2> {
    WallBox::segment(DVec2::new(2.0, 5.0), DVec2::new(8.0, 5.0), 0.2).unwrap()
}
const FLAT_LO: DVec2 = DVec2::new(2.0, 4.9);
const FLAT_HI: DVec2 = DVec2::new(8.0, 5.1);

#[test]
fn ball_hitting_wall_face_straight_reverses_velocity() {
    // Onto the top face, and from below through the other face.
    for (p, v, face_y, label) in [
        (
            DVec2::new(5.0, 5.62),
            DVec2::new(0.0, -2.0),
            5.1,
            "top face, straight",
        ),
        (
            DVec2::new(3.0, 4.38),
            DVec2::new(0.0, 1.5),
            4.9,
            "bottom face, straight",
        ),
    ] {
        let (world, ball, q) = hit(flat_wall(), p, v);
        check_reflection(&world, ball, q, DVec2::new(q.x, face_y), v, label);
        assert_close_vec(
            world.get(ball).unwrap().vel,
            -v,
            ROUND_OFF,
            &format!("{label}: straight back"),
        );
    }
}

#[test]
fn ball_hitting_wall_face_at_an_angle_keeps_tangential_velocity() {
    let (p, v) = (DVec2::new(4.0, 5.62), DVec2::new(1.5, -2.0));
    let (world, ball, q) = hit(flat_wall(), p, v);
    check_reflection(&world, ball, q, DVec2::new(q.x, 5.1), v, "top face, angled");
    assert_close_vec(
        world.get(ball).unwrap().vel,
        DVec2::new(1.5, 2.0),
        ROUND_OFF,
        "mirror image",
    );
}

#[test]
fn ball_hitting_wall_end_corner_reflects_about_corner_to_centre_normal() {
    // Upper right corner (8, 5.1), approached diagonally from beyond the end.
    let (p, v) = (DVec2::new(8.3, 5.45), DVec2::new(-1.0, -1.0));
    let (world, ball, q) = hit(flat_wall(), p, v);
    assert!(q.x > 8.0 && q.y > 5.1, "the closest feature is the corner");
    let corner = DVec2::new(8.0, 5.1);
    check_reflection(&world, ball, q, corner, v, "upper right corner");
    // The reflection is about the corner normal, not the face: not simply (v.x, -v.y).
    let n = unit(q - corner);
    assert_close_vec(
        world.get(ball).unwrap().vel,
        reflect(v, n),
        ROUND_OFF,
        "reflected off the corner",
    );

    // Lower left corner (2, 4.9), from below and before the start.
    let (p, v) = (DVec2::new(1.75, 4.55), DVec2::new(1.0, 0.8));
    let (world, ball, q) = hit(flat_wall(), p, v);
    assert!(q.x < 2.0 && q.y < 4.9);
    check_reflection(
        &world,
        ball,
        q,
        DVec2::new(2.0, 4.9),
        v,
        "lower left corner",
    );
}

#[test]
fn ball_hitting_the_end_face_of_a_wall_reflects_along_the_wall_axis() {
    let (p, v) = (DVec2::new(8.48, 5.02), DVec2::new(-1.2, 0.3));
    let (world, ball, q) = hit(flat_wall(), p, v);
    assert!(q.y < 5.1 && q.y > 4.9);
    check_reflection(&world, ball, q, DVec2::new(8.0, q.y), v, "end face");
}

/// A wall at 30 degrees: face and corner, in the wall's own frame.
#[test]
fn ball_hitting_a_wall_rotated_30_degrees_reflects_off_its_face_and_corner() {
    let c = DVec2::new(5.0, 5.0);
    let u = DVec2::from_angle(30f64.to_radians());
    let nrm = u.perp(); // the face normal, (-sin 30, cos 30)
    let wall = || WallBox::segment(c - u * 3.0, c + u * 3.0, 0.2).unwrap();

    // Face: 0.7 along the wall, 0.58 above its middle line, coming in against the normal.
    let p = c + u * 0.7 + nrm * 0.58;
    let v = -nrm * 1.2 + u * 0.4;
    let (world, ball, q) = hit(wall(), p, v);
    let along = (q - c).dot(u);
    let surface = c + u * along + nrm * 0.1;
    check_reflection(&world, ball, q, surface, v, "rotated face");
    assert_close_vec(
        world.get(ball).unwrap().vel,
        reflect(v, nrm),
        ROUND_OFF,
        "mirror about the rotated face",
    );

    // Corner: beyond the upper end, above the face.
    let corner = c + u * 3.0 + nrm * 0.1;
    let p = corner + unit(u + nrm * 1.2) * 0.52;
    let v = -unit(u * 0.8 + nrm) * 1.5;
    let (world, ball, q) = hit(wall(), p, v);
    assert!(
        (q - c).dot(u) > 3.0 && (q - c).dot(nrm) > 0.1,
        "the closest feature is the corner"
    );
    check_reflection(&world, ball, q, corner, v, "rotated corner");
    let local = world.get(ball).unwrap().pos - c;
    let (x, y) = (local.dot(u), local.dot(nrm));
    let dist = DVec2::new((x.abs() - 3.0).max(0.0), (y.abs() - 0.1).max(0.0)).length();
    assert!(
        dist >= R - ROUND_OFF,
        "ball ends outside the rotated wall: distance {dist}"
    );
}

#[test]
fn balls_end_outside_walls_after_face_edge_and_corner_hits_in_2d() {
    let starts = [
        (DVec2::new(5.0, 5.62), DVec2::new(0.0, -2.0)),
        (DVec2::new(8.3, 5.45), DVec2::new(-1.0, -1.0)),
        (DVec2::new(8.48, 5.02), DVec2::new(-1.2, 0.3)),
        (DVec2::new(1.75, 4.55), DVec2::new(1.0, 0.8)),
    ];
    for (p, v) in starts {
        let (world, ball, _) = hit(flat_wall(), p, v);
        let d = distance_to_aligned_box(world.get(ball).unwrap().pos, FLAT_LO, FLAT_HI);
        assert!(d >= R - ROUND_OFF, "ball from {p} ends {d} from the wall");
    }
}

// ----- 3D -----------------------------------------------------------------------------------

const CUBE_LO: DVec3 = DVec3::new(4.0, 4.0, 4.0);
const CUBE_HI: DVec3 = DVec3::new(6.0, 6.0, 6.0);

fn cube() -> WallBox<DVec3> {
    WallBox::aligned(CUBE_LO, CUBE_HI).unwrap()
}

/// The closest point of the cube to `q` (clamp, computed here).
fn cube_closest(q: DVec3) -> DVec3 {
    q.clamp(CUBE_LO, CUBE_HI)
}

#[test]
fn sphere_hitting_box_face_edge_and_corner_reflects_about_the_closest_point_normal() {
    let cases = [
        (
            "face",
            DVec3::new(5.0, 5.0, 6.48),
            DVec3::new(0.3, -0.2, -1.0),
        ),
        (
            "edge",
            DVec3::new(6.3, 6.35, 5.2),
            DVec3::new(-1.0, -1.0, 0.4),
        ),
        (
            "corner",
            DVec3::new(6.25, 6.25, 6.25),
            DVec3::new(-1.0, -1.0, -1.0),
        ),
        (
            "corner, skew",
            DVec3::new(3.7, 6.2, 3.75),
            DVec3::new(0.9, -0.7, 1.1),
        ),
    ];
    for (label, p, v) in cases {
        let (world, ball, q) = hit(cube(), p, v);
        let surface = cube_closest(q);
        let outside_axes = (0..3)
            .filter(|&a| q[a] < CUBE_LO[a] || q[a] > CUBE_HI[a])
            .count();
        let want_axes = match label {
            "face" => 1,
            "edge" => 2,
            _ => 3,
        };
        assert_eq!(
            outside_axes, want_axes,
            "{label}: test setup hits the intended feature"
        );
        check_reflection(&world, ball, q, surface, v, label);
        let d = distance_to_aligned_box(world.get(ball).unwrap().pos, CUBE_LO, CUBE_HI);
        assert!(d >= R - ROUND_OFF, "{label}: ends {d} from the box");
    }
    // The corner straight along the diagonal bounces straight back.
    let (world, ball, _) = hit(cube(), DVec3::splat(6.25), DVec3::splat(-1.0));
    assert_close_vec(
        world.get(ball).unwrap().vel,
        DVec3::splat(1.0),
        ROUND_OFF,
        "diagonal corner hit",
    );
}

#[test]
fn sphere_hitting_a_rotated_box_face_reflects_about_the_rotated_normal() {
    let c = DVec3::splat(5.0);
    let rot = DMat3::from_rotation_z(30f64.to_radians());
    let wall = WallBox::cuboid(c, DVec3::new(2.0, 2.0, 2.0), rot).unwrap();
    let u = rot.col(0); // the local +x face's normal
    let p = c + u * 1.47 + rot.col(1) * 0.3 + DVec3::new(0.0, 0.0, 0.2);
    let v = -u * 1.1 + rot.col(1) * 0.5 + DVec3::new(0.0, 0.0, 0.3);
    let (world, ball, q) = hit(wall, p, v);
    let surface = q - u * ((q - c).dot(u) - 1.0);
    check_reflection(&world, ball, q, surface, v, "rotated box face");
}

// ----- both dimensions ---------------------------------------------------------------------

/// A ball whose centre got inside the box [lo, hi] (moved there by hand) leaves through the face
/// whose outward normal is the axis vector `face`, to touching, its normal velocity reversed if it
/// was moving in.
fn check_pushed_out_through<V: Vector>(lo: V, hi: V, inside: V, v: V, face: V, label: &str) {
    let (world, ball, q) = hit(WallBox::aligned(lo, hi).unwrap(), inside, v);
    let c = world.get(ball).unwrap();
    // Out through that face: the coordinate along the face normal is the face plus R.
    let axis = (0..V::DIM)
        .find(|&a| face.get(a) != 0.0)
        .expect("an axis face");
    let want = if face.get(axis) > 0.0 { hi } else { lo };
    let mut expected = q;
    expected.set(axis, want.get(axis) + face.get(axis) * R);
    assert_close_vec(c.pos, expected, ROUND_OFF, &format!("{label}: position"));
    let expected_vel = if v.dot(face) < 0.0 {
        reflect(v, face)
    } else {
        v
    };
    assert_close_vec(
        c.vel,
        expected_vel,
        ROUND_OFF,
        &format!("{label}: velocity"),
    );
    assert!(
        distance_to_aligned_box(c.pos, lo, hi) >= R - ROUND_OFF,
        "{label}: ends outside"
    );
}

#[test]
fn ball_with_centre_inside_wall_is_pushed_out_through_the_nearest_face() {
    let (lo, hi) = (DVec2::new(2.0, 4.0), DVec2::new(8.0, 6.0));
    // (start inside, velocity, nearest face's outward normal)
    let cases = [
        (DVec2::new(3.0, 5.8), DVec2::new(0.3, -1.0), DVec2::Y),
        (DVec2::new(2.1, 5.0), DVec2::new(0.5, 0.2), DVec2::NEG_X),
        (DVec2::new(6.0, 4.3), DVec2::new(0.0, 0.0), DVec2::NEG_Y),
        (DVec2::new(7.75, 4.6), DVec2::new(-0.2, 0.4), DVec2::X),
    ];
    for (inside, v, face) in cases {
        check_pushed_out_through(lo, hi, inside, v, face, &format!("2D inside at {inside}"));
    }
    let (inside, v) = (DVec3::new(5.2, 4.15, 5.5), DVec3::new(0.2, 0.6, -0.1));
    check_pushed_out_through(
        CUBE_LO,
        CUBE_HI,
        inside,
        v,
        DVec3::NEG_Y,
        &format!("3D inside at {inside}"),
    );
}

/// A centre exactly on a face (distance 0, no direction from the point itself) leaves along
/// that face's outward normal, within `normal_tol`, and is pushed out by its radius.
fn check_leaves_along_face<V: Vector>(
    wall: WallBox<V>,
    p: V,
    face: V,
    normal_tol: f64,
    label: &str,
) {
    let (world, ball, _) = hit(wall, p, V::zero());
    assert_close_vec(
        world.events().collisions[0].normal,
        face,
        normal_tol,
        &format!("{label}: on the face at {p:?}, the face normal"),
    );
    assert_close_vec(
        world.get(ball).unwrap().pos,
        p + face * R,
        ROUND_OFF,
        &format!("{label}: pushed out by the radius"),
    );
}

#[test]
fn ball_centre_exactly_on_a_face_leaves_along_that_face_normal() {
    // In 2D the normal is exactly the face's; the 3D frame leaves it within a few ulps.
    for (p, face) in [
        (DVec2::new(5.0, 5.1), DVec2::Y),
        (DVec2::new(3.0, 4.9), DVec2::NEG_Y),
        (DVec2::new(8.0, 5.0), DVec2::X),
    ] {
        check_leaves_along_face(flat_wall(), p, face, 0.0, "2D");
    }
    for (p, face) in [
        (DVec3::new(5.0, 5.0, 6.0), DVec3::Z),
        (DVec3::new(4.0, 5.5, 4.5), DVec3::NEG_X),
    ] {
        check_leaves_along_face(cube(), p, face, FEW_ULPS, "3D");
    }
}

/// Walls that overlap each other are never even candidate pairs, step after step.
fn check_walls_never_meet<V: Vector>(walls: Vec<WallBox<V>>, label: &str) {
    let mut world = world::<V>(10.0);
    for wall in walls {
        world.add_wall(wall).unwrap();
    }
    for step in 0..3 {
        world.step().unwrap();
        assert!(
            world.events().collisions.is_empty(),
            "{label}, step {step}: walls collided"
        );
        assert_eq!(
            world.stats().candidates,
            0,
            "{label}, step {step}: walls are not even candidate pairs"
        );
        assert_eq!(
            world.stats().contacts,
            0,
            "{label}, step {step}: walls touched"
        );
    }
}

#[test]
fn overlapping_walls_never_collide_with_each_other() {
    check_walls_never_meet(
        vec![
            WallBox::segment(DVec2::new(1.0, 5.0), DVec2::new(9.0, 5.0), 0.5).unwrap(),
            WallBox::segment(DVec2::new(5.0, 1.0), DVec2::new(5.0, 9.0), 0.5).unwrap(),
            WallBox::aligned(DVec2::new(4.0, 4.0), DVec2::new(6.0, 6.0)).unwrap(),
        ],
        "2D",
    );
    check_walls_never_meet(
        vec![
            cube(),
            WallBox::aligned(DVec3::splat(5.0), DVec3::splat(7.0)).unwrap(),
        ],
        "3D",
    );
}

// ----- determinism ---------------------------------------------------------------------

/// Balls bouncing around a walled box with a rotated wall in the middle, hitting faces, ends and
/// corners: Pop jiggled at corners with random numbers; here the world's generator is never
/// touched and the same setup gives the same bits.
fn corner_world() -> World<DVec2> {
    let mut world = world2(10.0);
    let t = 0.2;
    world
        .add_wall(WallBox::aligned(DVec2::new(0.0, 0.0), DVec2::new(10.0, t)).unwrap())
        .unwrap();
    world
        .add_wall(WallBox::aligned(DVec2::new(0.0, 10.0 - t), DVec2::new(10.0, 10.0)).unwrap())
        .unwrap();
    world
        .add_wall(WallBox::aligned(DVec2::new(0.0, t), DVec2::new(t, 10.0 - t)).unwrap())
        .unwrap();
    world
        .add_wall(WallBox::aligned(DVec2::new(10.0 - t, t), DVec2::new(10.0, 10.0 - t)).unwrap())
        .unwrap();
    let u = DVec2::from_angle(0.4);
    world
        .add_wall(
            WallBox::segment(
                DVec2::splat(5.0) - u * 2.0,
                DVec2::splat(5.0) + u * 2.0,
                0.3,
            )
            .unwrap(),
        )
        .unwrap();
    for i in 0..12 {
        let a = i as f64 * 0.9;
        let p = DVec2::new(1.0 + 0.7 * i as f64, if i % 2 == 0 { 1.5 } else { 8.5 });
        world
            .spawn(
                CritterSpec::ball(p)
                    .vel(DVec2::from_angle(a) * 3.0)
                    .radius(0.3),
            )
            .unwrap();
    }
    world
}

#[test]
fn wall_collisions_use_no_randomness_and_repeat_bit_for_bit() {
    let mut a = corner_world();
    let mut b = corner_world();
    let rng_before = a.rng().state();
    a.run(400).unwrap();
    b.run(400).unwrap();
    assert!(
        a.totals().contacts > 50,
        "the balls did hit walls and each other"
    );
    assert_eq!(a.rng().state(), rng_before, "no random numbers were drawn");
    assert_eq!(state_bits(&a), state_bits(&b));
    assert_eq!(a.state_hash(), b.state_hash());
    // Elastic everywhere: walls and balls alike keep the kinetic energy.
    let e0 = corner_world().kinetic_energy();
    assert_close(
        a.kinetic_energy(),
        e0,
        LONG_RUN_ROUND_OFF * e0,
        "kinetic energy after 400 steps of elastic hits",
    );
}

// ----- contact details and wall-last ordering -------------------------------------------------

/// Where two shapes touch is a fact about the pair, not about which of them calls `collide`.
/// For a disk pair the engine reports the middle of the overlap either way; for a wall and a ball
/// it should report the wall's surface point either way.
#[test]
fn contact_point_does_not_depend_on_which_side_calls() {
    use critterbox::{KindDefaults, CP_MAXIMUM};
    use std::rc::Rc;
    let (p, v) = (DVec2::new(5.0, 5.61), DVec2::new(0.3, -2.0));
    let point = |kind: &str| {
        let mut world = world2(10.0);
        let boss = KindDefaults {
            priority: CP_MAXIMUM,
            ..KindDefaults::default()
        };
        world
            .register_kind("boss", None, boss, Rc::new(()))
            .unwrap();
        let w = world.add_wall(flat_wall()).unwrap();
        world.spawn(CritterSpec::new(kind, p).vel(v)).unwrap();
        world.step().unwrap();
        let ev = world.events().collisions[0];
        assert_eq!(ev.caller == w, kind == "ball", "test setup: who calls");
        ev.point
    };
    let q = after_move(p, v, DT);
    let surface = DVec2::new(q.x, 5.1);
    assert_close_vec(
        point("ball"),
        surface,
        ROUND_OFF,
        "wall calls: the surface point",
    );
    assert_close_vec(
        point("boss"),
        surface,
        ROUND_OFF,
        "ball calls: the surface point",
    );
}

/// Heavy ball B lands on light ball A resting just above a wall (not touching it after the
/// move). The disk-disk separation pushes A into the wall; the engine orders wall pairs last so
/// that "walls have the last word", but only for wall pairs that touched before the response.
#[test]
fn ball_pushed_into_a_wall_by_another_ball_ends_outside_the_wall() {
    let mut world = world2(10.0);
    world.add_wall(flat_wall()).unwrap();
    let a = world
        .spawn(CritterSpec::ball(DVec2::new(5.0, 5.601)).mass(1.0))
        .unwrap();
    let b = world
        .spawn(
            CritterSpec::ball(DVec2::new(5.0, 6.55))
                .vel(DVec2::new(0.0, -3.0))
                .mass(1000.0),
        )
        .unwrap();
    world.step().unwrap();
    assert!(
        world
            .events()
            .collisions
            .iter()
            .any(|e| e.caller == a && e.arg == b),
        "test setup: A and B collide"
    );
    let d = distance_to_aligned_box(world.get(a).unwrap().pos, FLAT_LO, FLAT_HI);
    assert!(
        d >= R - ROUND_OFF,
        "ball A ends {d} from the wall, {} inside it",
        R - d
    );
}
