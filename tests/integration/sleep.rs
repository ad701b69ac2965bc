//! Sleep under `solve:n` (src/method/sleep.rs): a pile at rest falls asleep and then stays
//! exactly where it was, and every documented way of waking it wakes it, with the physics of
//! what follows checked against free fall and against overlap.

use crate::common;

use common::*;
use critterbox::glam::DVec2;
use critterbox::method::sleep::{SLEEP_SPEED_STEPS, SLEEP_STEPS};
use critterbox::scenes::{gas, GasParams};
use critterbox::WallBox;
use critterbox::{CritterId, CritterSpec, Method, World, WorldConfig};

const R: f64 = 0.5;

/// The box from `lo` to `hi` under gravity, stepped by `solve:8`.
fn falling(lo: DVec2, hi: DVec2) -> WorldConfig<DVec2> {
    WorldConfig::new(lo, hi)
        .gravity(DVec2::new(0.0, -G))
        .dt(DT)
        .method(Method::Solve(8))
}

/// A world of `config` with an aligned wall from `lo` to `hi` for each of `walls`.
fn walled(config: WorldConfig<DVec2>, walls: &[(DVec2, DVec2)]) -> World<DVec2> {
    let mut w = World::new(config).unwrap();
    for &(lo, hi) in walls {
        w.add_wall(WallBox::aligned(lo, hi).unwrap()).unwrap();
    }
    w
}

/// A walled box 12 wide with `n` balls of radius 0.5 dropped in rows, under `solve:8`.
fn pile(n: usize, sleep: bool) -> (World<DVec2>, Vec<CritterId>) {
    let (lo, hi) = (DVec2::new(-1.0, -1.0), DVec2::new(13.0, 40.0));
    let mut w = walled(
        falling(lo, hi).sleep(sleep).seed(7),
        &[
            (lo, DVec2::new(0.0, 40.0)),
            (DVec2::new(12.0, -1.0), hi),
            (lo, DVec2::new(13.0, 0.0)),
        ],
    );
    let ids = (0..n)
        .map(|i| {
            let (row, col) = (i / 10, i % 10);
            let x = 0.8 + col as f64 * 1.15 + (row % 2) as f64 * 0.3;
            let vel = DVec2::new(((i * 7) % 5) as f64 * 0.2 - 0.4, 0.0);
            w.spawn(
                CritterSpec::ball(DVec2::new(x, 0.6 + row as f64 * 1.3))
                    .vel(vel)
                    .radius(R)
                    .restitution(0.5),
            )
            .unwrap()
        })
        .collect();
    (w, ids)
}

/// Steps until every ball sleeps; panics past `limit` steps.
fn until_asleep(w: &mut World<DVec2>, ids: &[CritterId], limit: u64) -> u64 {
    for k in 0..limit {
        if ids.iter().all(|&id| w.is_asleep(id)) {
            return k;
        }
        w.step().unwrap();
    }
    panic!(
        "{} of {} asleep after {limit} steps",
        w.sleepers(),
        ids.len()
    );
}

#[test]
fn a_resting_pile_falls_asleep_and_then_stays_exactly_where_it_was() {
    let (mut w, ids) = pile(60, true);
    // Nothing sleeps while the balls fall: they are faster than the threshold.
    w.run(20).unwrap();
    assert_eq!(w.sleepers(), 0, "asleep in free fall");
    let took = until_asleep(&mut w, &ids, 1500);
    assert!(took > SLEEP_STEPS as u64, "asleep after {took} steps");
    let before: Vec<(DVec2, DVec2)> = ids
        .iter()
        .map(|&id| (w.get(id).unwrap().pos, w.get(id).unwrap().vel))
        .collect();
    for &(_, v) in &before {
        assert_eq!(v, DVec2::ZERO, "a sleeper's velocity is zero");
    }
    w.run(100).unwrap();
    for (&id, &(p, _)) in ids.iter().zip(&before) {
        let c = w.get(id).unwrap();
        assert_eq!((c.pos, c.vel), (p, DVec2::ZERO), "{id} moved in its sleep");
    }
    let stats = w.stats();
    assert_eq!(stats.contacts, 0, "no pair of sleepers is tested");
    assert!(deepest_overlap(&w, R) < 0.05, "{}", deepest_overlap(&w, R));
}

#[test]
fn without_gravity_or_with_sleep_off_nothing_sleeps() {
    let (mut w, ids) = pile(30, false);
    w.run(800).unwrap();
    assert_eq!(w.sleepers(), 0);
    // The same pile with sleep on does fall asleep in those steps.
    let (mut on, _) = pile(30, true);
    on.run(800).unwrap();
    assert_eq!(on.sleepers(), ids.len());

    let mut g = gas::<DVec2>(&GasParams {
        n: 400,
        ..GasParams::default()
    })
    .unwrap();
    g.set_method(Method::Solve(4)).unwrap();
    g.run(200).unwrap();
    assert_eq!(g.sleepers(), 0, "a gas without gravity");
}

#[test]
fn a_ball_dropped_on_a_sleeping_pile_wakes_it_and_all_of_it_rests_again() {
    let (mut w, ids) = pile(40, true);
    until_asleep(&mut w, &ids, 1500);
    let top = ids
        .iter()
        .map(|&id| w.get(id).unwrap().pos.y)
        .fold(f64::MIN, f64::max);
    let drop = w
        .spawn(
            CritterSpec::ball(DVec2::new(5.7, top + 6.0))
                .vel(DVec2::new(0.0, -4.0))
                .radius(R)
                .restitution(0.5),
        )
        .unwrap();
    let mut fewest = usize::MAX;
    let mut lowest = f64::MAX;
    for _ in 0..200 {
        w.step().unwrap();
        fewest = fewest.min(w.sleepers());
        lowest = lowest.min(w.get(drop).unwrap().pos.y);
    }
    assert!(
        fewest < ids.len() / 4,
        "the impact woke only {} of {}",
        ids.len() - fewest,
        ids.len()
    );
    // It landed on the pile, not in it: never below the old top by more than a radius.
    assert!(lowest > top - R, "lowest {lowest}, top of the pile {top}");
    let mut all = ids.clone();
    all.push(drop);
    until_asleep(&mut w, &all, 2000);
    assert!(deepest_overlap(&w, R) < 0.05, "{}", deepest_overlap(&w, R));
}

#[test]
fn removing_a_support_wakes_what_rests_on_it_and_it_falls_freely() {
    // A column of three in a chute one ball wide, asleep: the bottom one is removed.
    let (lo, hi) = (DVec2::new(-1.0, -1.0), DVec2::new(3.0, 20.0));
    let mut w = walled(
        falling(lo, hi),
        &[
            (lo, DVec2::new(0.0, 20.0)),
            (DVec2::new(1.02, -1.0), hi),
            (lo, DVec2::new(3.0, 0.0)),
        ],
    );
    let column: Vec<CritterId> = (0..3)
        .map(|k| {
            let pos = DVec2::new(0.51, 0.5 + k as f64 * 1.2);
            w.spawn(CritterSpec::ball(pos).radius(R).restitution(0.0))
                .unwrap()
        })
        .collect();
    until_asleep(&mut w, &column, 1000);
    let centre = |w: &World<DVec2>| {
        (w.get(column[1]).unwrap().pos.y + w.get(column[2]).unwrap().pos.y) / 2.0
    };
    let y = centre(&w);
    w.remove(column[0]).unwrap();
    // The two balls left fall from rest together; what passes between them is equal and
    // opposite, so their centre falls freely: y - g t (t + dt) / 2 after t / dt steps of
    // semi-implicit Euler, until the lower one reaches the floor.
    let steps = 8;
    w.run(steps).unwrap();
    let t = steps as f64 * DT;
    let want = y - G * t * (t + DT) / 2.0;
    let got = centre(&w);
    assert!(
        (got - want).abs() < POSITION_DRIFT,
        "their centre fell to {got}, free fall gives {want}"
    );
    assert!(!w.is_asleep(column[2]), "the top ball woke too");
}

#[test]
fn a_sleeper_pushed_by_the_host_wakes_and_moves() {
    let (mut w, ids) = pile(20, true);
    until_asleep(&mut w, &ids, 1500);
    // The top ball, kicked straight up.
    let top = *ids
        .iter()
        .max_by(|&&a, &&b| w.get(a).unwrap().pos.y.total_cmp(&w.get(b).unwrap().pos.y))
        .unwrap();
    let p0 = w.get(top).unwrap().pos;
    let kick = DVec2::new(0.0, 3.0);
    w.get_mut(top).unwrap().vel = kick;
    w.step().unwrap();
    assert!(!w.is_asleep(top));
    let c = w.get(top).unwrap();
    // One step of semi-implicit Euler under gravity, nothing touched on the way up.
    let want = p0 + (kick + DVec2::new(0.0, -G * DT)) * DT;
    assert!(
        (c.pos - want).length() < ROUND_OFF,
        "{} against {want}",
        c.pos
    );
}

#[test]
fn a_sleeper_teleported_by_the_host_wakes() {
    let (mut w, ids) = pile(20, true);
    until_asleep(&mut w, &ids, 1500);
    let id = ids[5];
    let to = DVec2::new(6.0, 15.0);
    w.get_mut(id).unwrap().pos = to;
    w.step().unwrap();
    assert!(!w.is_asleep(id));
    let y = w.get(id).unwrap().pos.y;
    assert!(
        (y - (to.y - G * DT * DT)).abs() < ROUND_OFF,
        "it fell from where it was put: {y}"
    );
}

#[test]
fn the_threshold_is_a_share_of_a_step_of_gravity() {
    // A ball rolling along the floor slower than the threshold sleeps; one faster does not.
    let threshold = SLEEP_SPEED_STEPS * G * DT;
    for (speed, sleeps) in [(0.5 * threshold, true), (2.0 * threshold, false)] {
        let lo = DVec2::new(-1.0, -1.0);
        let mut w = walled(
            falling(lo, DVec2::new(1000.0, 5.0)),
            &[(lo, DVec2::new(1000.0, 0.0))],
        );
        let id = w
            .spawn(
                CritterSpec::ball(DVec2::new(1.0, R))
                    .vel(DVec2::new(speed, 0.0))
                    .radius(R),
            )
            .unwrap();
        w.run(3 * SLEEP_STEPS as u64).unwrap();
        assert_eq!(w.is_asleep(id), sleeps, "speed {speed}");
    }
}

#[test]
fn a_scene_turns_sleep_off_with_its_world_setting() {
    use critterbox::script::{load_scene, ScriptOptions};
    let dir = std::env::temp_dir().join(format!("critterbox-sleep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = |setting: &str| {
        let path = dir.join(format!("s{}.rhai", setting.len()));
        std::fs::write(
            &path,
            format!(
                "let w = world(#{{ dim: 2, size: vec(10, 10), gravity: vec(0, -9.81), method: \"solve:8\"{setting} }});\n"
            ),
        )
        .unwrap();
        load_scene(&path, &[], &ScriptOptions::default())
    };
    assert!(scene("").unwrap().world.sleep_allowed(), "on by default");
    assert!(!scene(", sleep: false").unwrap().world.sleep_allowed());
    let err = scene(", sleep: 1")
        .err()
        .expect("a number is refused")
        .to_string();
    assert!(err.contains("sleep must be true or false"), "{err}");
}

/// A kind whose own `collide` only counts its calls.
struct Counting(std::rc::Rc<std::cell::Cell<u32>>);

impl critterbox::KindHooks<DVec2> for Counting {
    fn collide(
        &self,
        _ctx: &mut critterbox::CollideCtx<'_, DVec2>,
    ) -> Result<bool, critterbox::Error> {
        self.0.set(self.0.get() + 1);
        Ok(true)
    }
}

#[test]
fn a_collide_hook_that_takes_a_sleeper_wakes_its_island() {
    use critterbox::KindDefaults;
    let (mut w, ids) = pile(20, true);
    let calls = std::rc::Rc::new(std::cell::Cell::new(0));
    let defaults = KindDefaults {
        fixed: true,
        priority: 1e6,
        ..KindDefaults::default()
    };
    register(
        &mut w,
        "counting",
        defaults,
        std::rc::Rc::new(Counting(calls.clone())),
    );
    until_asleep(&mut w, &ids, 1500);
    // A fixed critter at rest, overlapping the top ball a little: it never moves, so only its
    // hook can wake the pile.
    let top = ids
        .iter()
        .map(|&id| w.get(id).unwrap().pos)
        .max_by(|a, b| a.y.total_cmp(&b.y))
        .unwrap();
    w.spawn(CritterSpec::new("counting", top + DVec2::new(0.0, 0.99)).radius(R))
        .unwrap();
    w.step().unwrap();
    assert!(calls.get() > 0, "the hook ran");
    assert_eq!(
        w.sleepers(),
        0,
        "the whole pile woke with the ball the hook took"
    );
}
