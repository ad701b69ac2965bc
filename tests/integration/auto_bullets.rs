//! `auto`'s bullets (`src/method/bullets.rs`): under gravity, a few critters too fast for the
//! solve's substeps are flown after the solved step against the rest. Checked against laws: no
//! bullet passes through a wall or a ball, and an impact keeps momentum.

use critterbox::scenes::stress::well;
use critterbox::{CritterId, CritterSpec, Method, WallBox, World, WorldConfig};
use glam::DVec2;

/// A relative error that a result exact up to rounding may carry.
const ROUND_OFF: f64 = 1e-12;

/// A closed box 10 wide and 20 high with walls `t` thick, a row of nine balls (radius 0.5,
/// restitution 0.5) resting on its floor from x = 1, and a bullet (radius 0.05) at `at` flying
/// at `vel`.
fn row_and_bullet(t: f64, at: DVec2, vel: DVec2) -> (World<DVec2>, Vec<CritterId>, CritterId) {
    let mut w = well(Method::Auto, 1.0 / 60.0, DVec2::new(30.0, 30.0), 20.0, t).unwrap();
    let lid = WallBox::aligned(DVec2::new(-t, 20.0), DVec2::new(10.0 + t, 20.0 + t));
    w.add_wall(lid.unwrap()).unwrap();
    let row = (0..9)
        .map(|k| {
            let pos = DVec2::new(1.0 + 1.000_001 * k as f64, 0.5 + 1e-6);
            w.spawn(CritterSpec::ball(pos).radius(0.5).restitution(0.5))
                .unwrap()
        })
        .collect();
    let bullet = w
        .spawn(CritterSpec::ball(at).vel(vel).radius(0.05))
        .unwrap();
    (w, row, bullet)
}

/// A bullet fired along a long floor, head-on into the end of a resting row of nine balls, at
/// 100, 1,000 and 10,000 (1.7 to 170 per step): the floor's contacts push only upwards, so the
/// momentum along the floor is kept through the impacts to round-off, and the bullet never
/// passes the first ball's centre. Auto flies it as a bullet while it is fast.
#[test]
fn a_bullet_into_a_row_keeps_momentum_along_the_floor_and_stays_in_front() {
    for speed in [1e2, 1e3, 1e4] {
        // No side walls within reach of the test's steps: only the floor.
        let mut w = World::new(
            WorldConfig::new(DVec2::new(-2000.0, -1.0), DVec2::new(2000.0, 50.0))
                .dt(1.0 / 60.0)
                .gravity(DVec2::new(0.0, -9.81))
                .method(Method::Auto),
        )
        .unwrap();
        let floor = WallBox::aligned(DVec2::new(-2000.0, -0.2), DVec2::new(2000.0, 0.0));
        w.add_wall(floor.unwrap()).unwrap();
        let row: Vec<_> = (0..9)
            .map(|k| {
                let pos = DVec2::new(1.0 + 1.000_001 * k as f64, 0.5 + 1e-6);
                w.spawn(CritterSpec::ball(pos).radius(0.5).restitution(0.5))
                    .unwrap()
            })
            .collect();
        let at = DVec2::new(-2.0, 0.5 + 1e-6);
        let bullet = w
            .spawn(
                CritterSpec::ball(at)
                    .vel(DVec2::new(speed, 0.0))
                    .radius(0.05),
            )
            .unwrap();
        let momentum = |w: &World<DVec2>| -> f64 {
            w.critters()
                .iter()
                .filter(|c| !c.is_wall())
                .map(|c| c.mass() * c.vel.x)
                .sum()
        };
        let p0 = momentum(&w);
        let mut flown = 0;
        for step in 0..6 {
            w.step().unwrap();
            flown += w.auto_islands().map_or(0, |i| i.bullets);
            let b = w.get(bullet).unwrap().pos.x;
            let first = w.get(row[0]).unwrap().pos.x;
            assert!(
                b < first,
                "{speed}, step {step}: bullet at {b}, first ball at {first}"
            );
            let p = momentum(&w);
            assert!(
                (p - p0).abs() <= ROUND_OFF * p0.abs(),
                "{speed}, step {step}: momentum {p} against {p0}"
            );
        }
        assert!(flown > 0, "{speed}: auto never flew the bullet");
    }
}

/// A bullet fired at a wall 0.02 thick beside a resting row, from 100 to 1e6 (1.7 to 17,000
/// per step, up to nearly a million times the wall's thickness): it never ends a step outside
/// the box.
#[test]
fn a_bullet_beside_a_pile_never_passes_a_thin_wall() {
    for speed in [1e2, 1e3, 1e4, 1e5, 1e6] {
        let at = DVec2::new(5.0, 10.0);
        let (mut w, _, bullet) = row_and_bullet(0.02, at, DVec2::new(speed, speed * 0.1));
        for step in 0..30 {
            w.step().unwrap();
            let p = w.get(bullet).unwrap().pos;
            assert!(
                p.x > 0.0 && p.x < 10.0 && p.y > 0.0 && p.y < 20.0,
                "{speed}, step {step}: the bullet at {p}"
            );
        }
    }
}
