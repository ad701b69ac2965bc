//! Disk-disk and sphere-sphere collisions against the laws they must obey: Pop's 1-D elastic
//! formulas on the normal components, tangential components kept, momentum exact, kinetic energy
//! kept at e = 1 and lost by the closed-form amount at e < 1, separation by inverse mass.

use crate::common;

use common::*;
use critterbox::glam::{DVec2, DVec3};
use critterbox::scenes::{self, AnyWorld, SceneParams};
use critterbox::{CritterId, CritterSpec, Vector, World};

const MASS_RATIOS: [f64; 5] = [1e-6, 1e-3, 1.0, 1e3, 1e6];

/// One body of a two-body test.
#[derive(Clone, Copy, Debug)]
struct Body<V> {
    pos: V,
    vel: V,
    radius: f64,
    mass: f64,
    restitution: f64,
}

fn body<V: Vector>(pos: V, vel: V, radius: f64, mass: f64) -> Body<V> {
    Body {
        pos,
        vel,
        radius,
        mass,
        restitution: 1.0,
    }
}

/// What one step did to a pair: velocities and positions before (after the move) and after.
struct Outcome<V> {
    a: Body<V>,
    b: Body<V>,
    /// Positions after the move, before the response.
    q1: V,
    q2: V,
    /// Unit normal from `a` (the caller: lower id, equal priority) to `b`, after the move.
    n: V,
    v1: V,
    v2: V,
    p1: V,
    p2: V,
    momentum_before: V,
    momentum_after: V,
    /// The impulse the collision event reports.
    impulse: f64,
    energy_before: f64,
    energy_after: f64,
}

fn spawn_body<V: Vector>(world: &mut World<V>, b: &Body<V>) -> CritterId {
    world
        .spawn(
            CritterSpec::ball(b.pos)
                .vel(b.vel)
                .radius(b.radius)
                .mass(b.mass)
                .restitution(b.restitution),
        )
        .expect("valid body")
}

/// Spawns `a` then `b` in a 10-wide world, checks that after the move they overlap and approach,
/// and takes one step.
fn collide_pair<V: Vector>(a: Body<V>, b: Body<V>) -> Outcome<V> {
    let mut world = world::<V>(10.0);
    let ia = spawn_body(&mut world, &a);
    let ib = spawn_body(&mut world, &b);
    assert!(ia < ib, "a has the lower id, so it is the caller");
    let q1 = after_move(a.pos, a.vel, world.dt());
    let q2 = after_move(b.pos, b.vel, world.dt());
    let d = q2 - q1;
    assert!(
        d.length() < a.radius + b.radius,
        "test setup: the pair must overlap after the move"
    );
    let n = unit(d);
    assert!(
        (b.vel - a.vel).dot(n) < 0.0,
        "test setup: the pair must approach"
    );
    let momentum_before = world.momentum();
    let energy_before = world.kinetic_energy();
    world.step().expect("step");
    assert_eq!(world.events().collisions.len(), 1, "exactly one collision");
    let ev = world.events().collisions[0];
    assert_eq!(
        (ev.caller, ev.arg),
        (ia, ib),
        "the lower id calls at equal priority"
    );
    let ca = world.get(ia).expect("a alive");
    let cb = world.get(ib).expect("b alive");
    Outcome {
        a,
        b,
        q1,
        q2,
        n,
        v1: ca.vel,
        v2: cb.vel,
        p1: ca.pos,
        p2: cb.pos,
        momentum_before,
        momentum_after: world.momentum(),
        impulse: ev.impulse,
        energy_before,
        energy_after: world.kinetic_energy(),
    }
}

/// Checks an elastic (e = 1) outcome against Pop's formulas and the conservation laws.
fn check_elastic<V: Vector>(o: &Outcome<V>, label: &str) {
    let (m1, m2) = (o.a.mass, o.b.mass);
    let n = o.n;
    let vscale = o.a.vel.length().max(o.b.vel.length());
    let (v1n, v2n) = (o.a.vel.dot(n), o.b.vel.dot(n));
    let (want1, want2) = pop_elastic(v1n, v2n, m2 / m1);
    assert_close(
        o.v1.dot(n),
        want1,
        ROUND_OFF * vscale,
        &format!("{label}: caller normal velocity"),
    );
    assert_close(
        o.v2.dot(n),
        want2,
        ROUND_OFF * vscale,
        &format!("{label}: arg normal velocity"),
    );
    assert_close_vec(
        tangential(o.v1, n),
        tangential(o.a.vel, n),
        ROUND_OFF * vscale,
        &format!("{label}: caller tangential velocity"),
    );
    assert_close_vec(
        tangential(o.v2, n),
        tangential(o.b.vel, n),
        ROUND_OFF * vscale,
        &format!("{label}: arg tangential velocity"),
    );
    check_momentum(o, label);
    // The reported impulse is the arg's change of momentum along the normal, and minus the
    // caller's: measured on the lighter body, whose velocity change is not lost to round-off.
    let measured = if m1 <= m2 {
        m1 * (v1n - o.v1.dot(n))
    } else {
        m2 * (o.v2.dot(n) - v2n)
    };
    assert_close(
        o.impulse,
        measured,
        ROUND_OFF * m1.min(m2) * vscale,
        &format!("{label}: impulse"),
    );
    let rel = (o.energy_after - o.energy_before).abs() / o.energy_before;
    assert!(
        rel <= ROUND_OFF,
        "{label}: kinetic energy changed by {rel:e} (relative) in an elastic hit"
    );
    check_separation(o, label);
}

fn check_momentum<V: Vector>(o: &Outcome<V>, label: &str) {
    let scale = o.a.mass * o.a.vel.length() + o.b.mass * o.b.vel.length();
    assert_close_vec(
        o.momentum_after,
        o.momentum_before,
        MOMENTUM_ROUND_OFF * scale,
        &format!("{label}: momentum"),
    );
    // The world's sum agrees with the bodies' own.
    assert_close_vec(
        o.momentum_after,
        o.v1 * o.a.mass + o.v2 * o.b.mass,
        FEW_ULPS * scale,
        &format!("{label}: world momentum is the sum of m v"),
    );
}

/// After the response the pair just touches and the centre of mass did not move.
fn check_separation<V: Vector>(o: &Outcome<V>, label: &str) {
    let (m1, m2) = (o.a.mass, o.b.mass);
    let dist = (o.p2 - o.p1).length();
    assert_close(
        dist,
        o.a.radius + o.b.radius,
        ROUND_OFF,
        &format!("{label}: distance after separation"),
    );
    let com_before = (o.q1 * m1 + o.q2 * m2) * (1.0 / (m1 + m2));
    let com_after = (o.p1 * m1 + o.p2 * m2) * (1.0 / (m1 + m2));
    assert_close_vec(
        com_after,
        com_before,
        ROUND_OFF,
        &format!("{label}: centre of mass"),
    );
}

/// Whether a pair meets along its line of motion or off it.
#[derive(Clone, Copy, PartialEq)]
enum Hit {
    HeadOn,
    /// Off-centre: the tangential parts are not small.
    Glancing,
}

/// `a` (mass 1) meets `b` given each of [`MASS_RATIOS`] in turn as its mass: Pop's elastic
/// formulas and the conservation laws hold.
fn check_elastic_for_all_mass_ratios<V: Vector>(a: Body<V>, b: Body<V>, hit: Hit, label: &str) {
    for mr in MASS_RATIOS {
        let label = format!("{label}, mr = {mr:e}");
        let o = collide_pair(a, Body { mass: mr, ..b });
        if hit == Hit::Glancing {
            assert!(
                tangential(a.vel, o.n).length() > 0.3 * a.vel.length(),
                "{label}: test setup: a real glancing hit"
            );
        }
        check_elastic(&o, &label);
    }
}

#[test]
fn head_on_pairs_follow_pop_elastic_formula_for_mass_ratios_1e_minus6_to_1e6() {
    check_elastic_for_all_mass_ratios(
        body(DVec2::new(4.0, 5.0), DVec2::new(1.2, 0.0), 0.5, 1.0),
        body(DVec2::new(4.99, 5.0), DVec2::new(-0.7, 0.0), 0.5, 1.0),
        Hit::HeadOn,
        "2D head-on",
    );
    check_elastic_for_all_mass_ratios(
        body(
            DVec3::new(4.0, 5.0, 5.0),
            DVec3::new(0.0, 0.0, 1.1),
            0.5,
            1.0,
        ),
        body(
            DVec3::new(4.0, 5.0, 5.98),
            DVec3::new(0.0, 0.0, -0.9),
            0.5,
            1.0,
        ),
        Hit::HeadOn,
        "3D head-on",
    );
}

#[test]
fn glancing_pairs_change_only_normal_components_for_all_mass_ratios() {
    check_elastic_for_all_mass_ratios(
        body(DVec2::new(4.0, 5.0), DVec2::new(1.0, 0.4), 0.5, 1.0),
        body(DVec2::new(4.3, 5.8), DVec2::new(-0.3, -0.5), 0.4, 1.0),
        Hit::Glancing,
        "2D glancing",
    );
    check_elastic_for_all_mass_ratios(
        body(
            DVec3::new(4.0, 5.0, 5.0),
            DVec3::new(0.8, 0.3, -0.2),
            0.5,
            1.0,
        ),
        body(
            DVec3::new(4.5, 5.6, 5.55),
            DVec3::new(-0.4, 0.1, 0.6),
            0.5,
            1.0,
        ),
        Hit::Glancing,
        "3D glancing",
    );
}

/// With e < 1 the relative normal speed after is e times before, momentum is exact, and the
/// energy lost is the closed form (1 - e^2)/2 * mu * (relative normal speed)^2.
fn check_restitution<V: Vector>(a: Body<V>, b: Body<V>, e: f64, label: &str) {
    // The pair uses the smaller coefficient: give the caller 1 and the arg e.
    let b = Body {
        restitution: e,
        ..b
    };
    let o = collide_pair(a, b);
    let n = o.n;
    let vscale = a.vel.length().max(b.vel.length());
    let before = (b.vel - a.vel).dot(n);
    let after = (o.v2 - o.v1).dot(n);
    assert_close(
        after,
        -e * before,
        ROUND_OFF * vscale,
        &format!("{label}: relative normal velocity"),
    );
    assert_close_vec(
        tangential(o.v1, n),
        tangential(a.vel, n),
        ROUND_OFF * vscale,
        &format!("{label}: tangential"),
    );
    assert_close_vec(
        tangential(o.v2, n),
        tangential(b.vel, n),
        ROUND_OFF * vscale,
        &format!("{label}: tangential"),
    );
    check_momentum(&o, label);
    let mu = a.mass * b.mass / (a.mass + b.mass);
    let lost = 0.5 * (1.0 - e * e) * mu * before * before;
    assert_close(
        o.energy_before - o.energy_after,
        lost,
        ROUND_OFF * o.energy_before,
        &format!("{label}: kinetic energy lost"),
    );
    check_separation(&o, label);
}

#[test]
fn restitution_below_one_scales_relative_normal_speed_and_keeps_momentum() {
    for e in [0.0, 0.3, 0.5, 0.9] {
        let a = body(DVec2::new(4.0, 5.0), DVec2::new(1.0, 0.4), 0.5, 1.0);
        let b = body(DVec2::new(4.7, 5.5), DVec2::new(-0.3, -0.5), 0.4, 2.5);
        check_restitution(a, b, e, &format!("2D, e = {e}"));
        let a = body(
            DVec3::new(4.0, 5.0, 5.0),
            DVec3::new(0.8, 0.3, -0.2),
            0.5,
            3.0,
        );
        let b = body(
            DVec3::new(4.5, 5.6, 5.55),
            DVec3::new(-0.4, 0.1, 0.6),
            0.5,
            0.7,
        );
        check_restitution(a, b, e, &format!("3D, e = {e}"));
    }
}

/// Equal masses, `b` at rest, struck off-centre by `a`: both move, at right angles, and the
/// kinetic energy is kept.
fn check_right_angles<V: Vector>(a: Body<V>, b: Body<V>, label: &str) {
    let o = collide_pair(a, b);
    let (speed, v2) = (a.vel.length(), a.vel.length_squared());
    assert!(
        o.v1.length() > 0.05 * speed && o.v2.length() > 0.05 * speed,
        "{label}: both move after a glancing hit"
    );
    assert_close(
        o.v1.dot(o.v2),
        0.0,
        ROUND_OFF * v2,
        &format!("{label}: v1' . v2'"),
    );
    assert_close(
        o.v1.length_squared() + o.v2.length_squared(),
        v2,
        ROUND_OFF * v2,
        &format!("{label}: |v1'|^2 + |v2'|^2"),
    );
}

#[test]
fn equal_masses_in_a_glancing_hit_on_a_resting_target_leave_at_right_angles() {
    for (offset, speed) in [
        (DVec2::new(0.8, 0.55), 1.0),
        (DVec2::new(0.5, 0.8), 2.0),
        (DVec2::new(0.95, -0.2), 0.6),
    ] {
        let a = body(DVec2::new(4.0, 5.0), DVec2::new(speed, 0.0), 0.5, 0.3);
        let b = body(DVec2::new(4.0, 5.0) + offset, DVec2::ZERO, 0.5, 0.3);
        check_right_angles(a, b, &format!("2D, offset {offset}"));
    }
    let a = body(
        DVec3::new(4.0, 5.0, 5.0),
        DVec3::new(0.0, 1.5, 0.0),
        0.5,
        2.0,
    );
    let b = body(DVec3::new(4.3, 5.8, 5.4), DVec3::ZERO, 0.5, 2.0);
    check_right_angles(a, b, "3D");
}

/// A ball at `pa` moving at `v` strikes an equal ball at rest at `pb`: after one step, a line
/// saying what went wrong unless they exchanged velocities exactly.
fn swap_failure<V: Vector>(pa: V, pb: V, v: V, label: &str) -> Option<String> {
    let mut world = world::<V>(10.0);
    let a = world.spawn(CritterSpec::ball(pa).vel(v)).unwrap();
    let b = world.spawn(CritterSpec::ball(pb)).unwrap();
    world.step().unwrap();
    let (va, vb) = (world.get(a).unwrap().vel, world.get(b).unwrap().vel);
    (va != V::zero() || vb != v).then(|| format!("{label}: a {va:?}, b {vb:?}"))
}

/// Equal masses, target at rest, head on along an axis: the velocities are exchanged bit for bit.
/// Power-of-two masses (the default density and radius 0.5 give 1/8) make every step of the
/// impulse exact, so any difference comes from the contact normal not being exactly the axis.
#[test]
fn head_on_equal_masses_swap_velocities_exactly() {
    let mut failures = Vec::new();
    for k in 0..40 {
        for speed in [1.0, 0.7, 2.5, 1.3] {
            let x0 = 3.0 + 0.0137 * k as f64;
            let gap = 0.97 + 0.0007 * k as f64;
            failures.extend(swap_failure(
                DVec2::new(x0, 5.0),
                DVec2::new(x0 + gap, 5.0),
                DVec2::new(speed, 0.0),
                &format!("2D x0 {x0}, gap {gap}, speed {speed}"),
            ));
        }
    }
    for k in 0..40 {
        let z0 = 3.0 + 0.0113 * k as f64;
        failures.extend(swap_failure(
            DVec3::new(5.0, 5.0, z0),
            DVec3::new(5.0, 5.0, z0 + 0.98),
            DVec3::new(0.0, 0.0, 1.0),
            &format!("3D z0 {z0}"),
        ));
    }
    assert!(
        failures.is_empty(),
        "{} of 200 head-on hits did not swap exactly:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Equal (non power-of-two) masses, both moving, head on: swapped to round-off.
#[test]
fn head_on_equal_masses_both_moving_swap_velocities_to_round_off() {
    for (va, vb) in [(1.3, -0.4), (0.25, -2.0), (3.0, 1.0)] {
        let a = body(DVec2::new(4.0, 5.0), DVec2::new(va, 0.0), 0.5, 0.3);
        let b = body(DVec2::new(4.99, 5.0), DVec2::new(vb, 0.0), 0.5, 0.3);
        let o = collide_pair(a, b);
        let tol = 4.0 * f64::EPSILON * va.abs().max(vb.abs());
        assert_close_vec(o.v1, b.vel, tol, "caller takes the arg's velocity");
        assert_close_vec(o.v2, a.vel, tol, "arg takes the caller's velocity");
    }
}

/// A fixed critter has infinite mass: a ball hitting it has its normal velocity reversed and its
/// tangential velocity kept, and the fixed critter neither moves nor changes velocity, whichever
/// of the two calls. `fixed` is at rest; the ball's radius and the fixed critter's sum to 1.
fn check_fixed_reflects<V: Vector>(fixed: CritterSpec<V>, ball: CritterSpec<V>, label: &str) {
    let (fixed_pos, p, v) = (fixed.pos, ball.pos, ball.vel);
    for fixed_first in [true, false] {
        let label = format!("{label}, fixed spawned first: {fixed_first}");
        let mut world = world::<V>(10.0);
        let (f, b) = if fixed_first {
            let f = world.spawn(fixed.clone()).unwrap();
            (f, world.spawn(ball.clone()).unwrap())
        } else {
            let b = world.spawn(ball.clone()).unwrap();
            (world.spawn(fixed.clone()).unwrap(), b)
        };
        let q = after_move(p, v, world.dt());
        let n = unit(q - fixed_pos); // from the fixed critter to the ball
        assert!(
            v.dot(n) < 0.0 && (q - fixed_pos).length() < 1.0,
            "{label}: test setup"
        );
        world.step().unwrap();
        assert_eq!(world.events().collisions.len(), 1, "{label}: one collision");
        let fc = world.get(f).unwrap();
        assert_eq!(fc.pos, fixed_pos, "{label}: the fixed critter was moved");
        assert_eq!(
            fc.vel,
            V::zero(),
            "{label}: the fixed critter was given a velocity"
        );
        let bc = world.get(b).unwrap();
        assert_close_vec(
            bc.vel,
            reflect(v, n),
            ROUND_OFF,
            &format!("{label}: ball velocity reflected off the fixed critter"),
        );
        assert_reflected(bc.vel, v, n, &label);
        // The whole overlap was taken by the ball: it now touches the fixed critter, moved along n.
        assert_close_vec(
            bc.pos,
            fixed_pos + n * 1.0,
            ROUND_OFF,
            &format!("{label}: ball pushed out along the normal"),
        );
        assert_close(
            (bc.pos - fixed_pos).length(),
            1.0,
            ROUND_OFF,
            &format!("{label}: distance after separation"),
        );
    }
}

#[test]
fn fixed_critter_reflects_a_ball_and_does_not_move() {
    // Even with a nominal mass equal to the ball's.
    check_fixed_reflects(
        CritterSpec::ball(DVec2::new(5.0, 5.0))
            .mass(0.2)
            .fixed(true),
        CritterSpec::ball(DVec2::new(4.4, 5.7))
            .vel(DVec2::new(1.0, -0.5))
            .mass(0.2),
        "2D",
    );
    check_fixed_reflects(
        CritterSpec::ball(DVec3::new(5.0, 5.0, 5.0)).fixed(true),
        CritterSpec::ball(DVec3::new(4.5, 5.4, 5.6)).vel(DVec3::new(0.6, -0.3, -0.9)),
        "3D",
    );
}

/// Pop exchanged velocities even for separating pairs; the fix gives them no impulse, only the
/// separation.
#[test]
fn overlapping_separating_pair_gets_no_impulse_but_is_pushed_apart() {
    let mut world = world2(10.0);
    let (p1, v1) = (DVec2::new(4.0, 5.0), DVec2::new(-1.0, 0.2));
    let (p2, v2) = (DVec2::new(4.8, 5.1), DVec2::new(0.5, 0.3));
    let a = world
        .spawn(CritterSpec::ball(p1).vel(v1).mass(1.0))
        .unwrap();
    let b = world
        .spawn(CritterSpec::ball(p2).vel(v2).mass(3.0))
        .unwrap();
    let (q1, q2) = (
        after_move(p1, v1, world.dt()),
        after_move(p2, v2, world.dt()),
    );
    let n = unit(q2 - q1);
    assert!(
        (q2 - q1).length() < 1.0 && (v2 - v1).dot(n) > 0.0,
        "test setup: overlapping, separating"
    );
    world.step().unwrap();
    let (ca, cb) = (world.get(a).unwrap(), world.get(b).unwrap());
    assert_eq!(ca.vel, v1, "separating caller's velocity changed");
    assert_eq!(cb.vel, v2, "separating arg's velocity changed");
    assert_eq!(world.events().collisions.len(), 1);
    assert_eq!(world.events().collisions[0].impulse, 0.0);
    assert_eq!(world.stats().impacts, 0);
    assert_close(
        (cb.pos - ca.pos).length(),
        1.0,
        ROUND_OFF,
        "pushed apart until they touch",
    );
    // Pushed along the line of centres, heavier one less (split by inverse mass: 3 to 1).
    let (d1, d2) = (ca.pos - q1, cb.pos - q2);
    assert_close(
        d1.dot(n),
        -3.0 * d2.dot(n),
        ROUND_OFF,
        "displacements split 3:1 by inverse mass",
    );
    assert_close(
        tangential(d1, n).length() + tangential(d2, n).length(),
        0.0,
        ROUND_OFF,
        "pushed along the normal only",
    );
}

/// Coincident centres: a deterministic +x normal, finite results, the caller goes -x.
#[test]
fn coincident_centres_separate_along_plus_x_without_nan() {
    let c = DVec2::new(5.0, 5.0);
    let mut world = world2(10.0);
    let a = world
        .spawn(CritterSpec::ball(c).radius(0.5).mass(1.0))
        .unwrap();
    let b = world
        .spawn(CritterSpec::ball(c).radius(0.3).mass(3.0))
        .unwrap();
    world.step().unwrap();
    let (ca, cb) = (world.get(a).unwrap(), world.get(b).unwrap());
    assert!(ca.pos.is_finite() && cb.pos.is_finite() && ca.vel.is_finite() && cb.vel.is_finite());
    assert_eq!(world.events().collisions[0].normal, DVec2::X);
    // Depth 0.8 split by inverse mass: 1 : 1/3 -> caller 0.6 back, arg 0.2 forward.
    assert_close_vec(
        ca.pos,
        DVec2::new(5.0 - 0.6, 5.0),
        ROUND_OFF,
        "caller position",
    );
    assert_close_vec(
        cb.pos,
        DVec2::new(5.0 + 0.2, 5.0),
        ROUND_OFF,
        "arg position",
    );

    let c3 = DVec3::splat(5.0);
    let mut world = world3(10.0);
    let a = world
        .spawn(CritterSpec::ball(c3).vel(DVec3::new(0.0, 1.0, 0.0)))
        .unwrap();
    let b = world
        .spawn(CritterSpec::ball(c3).vel(DVec3::new(0.0, 1.0, 0.0)))
        .unwrap();
    world.step().unwrap();
    let (ca, cb) = (world.get(a).unwrap(), world.get(b).unwrap());
    assert!(ca.pos.is_finite() && cb.pos.is_finite() && ca.vel.is_finite() && cb.vel.is_finite());
    assert_eq!(world.events().collisions[0].normal, DVec3::X);
    assert_close(
        cb.pos.x - ca.pos.x,
        1.0,
        ROUND_OFF,
        "3D: separated along +x to touching",
    );
    assert_eq!(
        ca.vel,
        DVec3::new(0.0, 1.0, 0.0),
        "no relative motion: no impulse"
    );
}

/// Overlapping at rest, different masses and radii, oblique: after the step they just touch and
/// the centre of mass has not moved (Pop split the push by radius, which moved it).
#[test]
fn separation_leaves_pair_touching_with_centre_of_mass_in_place() {
    for (m1, m2, r1, r2) in [
        (1.0, 4.0, 0.5, 0.2),
        (1e-3, 1.0, 0.1, 0.9),
        (7.0, 7.0, 0.3, 0.3),
    ] {
        let p1 = DVec2::new(4.0, 5.0);
        let p2 = p1 + unit(DVec2::new(0.6, -0.8)) * (0.7 * (r1 + r2));
        let mut world = world2(10.0);
        let a = world
            .spawn(CritterSpec::ball(p1).radius(r1).mass(m1))
            .unwrap();
        let b = world
            .spawn(CritterSpec::ball(p2).radius(r2).mass(m2))
            .unwrap();
        world.step().unwrap();
        let (ca, cb) = (world.get(a).unwrap(), world.get(b).unwrap());
        assert_close(
            (cb.pos - ca.pos).length(),
            r1 + r2,
            ROUND_OFF,
            "distance after separation",
        );
        let com = |x1: DVec2, x2: DVec2| (x1 * m1 + x2 * m2) / (m1 + m2);
        assert_close_vec(
            com(ca.pos, cb.pos),
            com(p1, p2),
            ROUND_OFF,
            "centre of mass",
        );
        assert_eq!(
            (ca.vel, cb.vel),
            (DVec2::ZERO, DVec2::ZERO),
            "at rest: no impulse"
        );
    }
}

/// Newton's cradle at e = 1: after the strike only the last ball moves, with the striker's
/// velocity; the striker and the other balls are at rest. Exact values.
#[test]
fn newtons_cradle_moves_only_the_last_ball_exactly() {
    let AnyWorld::D2(mut world) = scenes::build("cradle", &SceneParams::default()).unwrap() else {
        panic!("the cradle is 2D");
    };
    let ids: Vec<CritterId> = world.critters().iter().map(|c| c.id()).collect();
    assert_eq!(ids.len(), 6);
    let striker_vel = world.get(ids[0]).unwrap().vel;
    assert_eq!(striker_vel, DVec2::new(1.0, 0.0));
    world.run(200).unwrap();
    let vels: Vec<DVec2> = ids.iter().map(|&id| world.get(id).unwrap().vel).collect();
    let mut want = vec![DVec2::ZERO; 6];
    want[5] = striker_vel;
    assert_eq!(vels, want, "velocities of striker and balls 1..5");
    assert!(
        world.totals().impacts >= 5,
        "the impulse went through every ball"
    );
    // The last ball has left; the others stay within a hair of where they were.
    assert!(world.get(ids[5]).unwrap().pos.x > 9.5);
}
