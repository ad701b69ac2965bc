//! Tests of the world as a whole: critters alike share their traits, and a change to one
//! critter's traits is its own.

use super::*;
/// The built-in gas of `n` disks.
pub(crate) fn gas(n: usize) -> World<DVec2> {
    let params = crate::scenes::SceneParams {
        n: Some(n),
        ..Default::default()
    };
    match crate::scenes::builtin("gas", &params)
        .expect("builds")
        .world
    {
        crate::scenes::AnyWorld::D2(w) => w,
        crate::scenes::AnyWorld::D3(_) => panic!("gas is 2D"),
    }
}

use crate::critter::{CritterSpec, PropValue, Traits, CP_WALL};
use glam::DVec2;
use std::sync::Arc;

fn disks(w: &World<DVec2>) -> Vec<&Critter<DVec2>> {
    w.critters().iter().filter(|c| !c.is_wall()).collect()
}

/// A gas spawned from one kind keeps one copy of its traits; a change to one critter's
/// traits is that critter's alone, and what the others read is unchanged.
#[test]
fn critters_alike_share_their_traits_and_a_change_is_the_changed_critter_s_own() {
    let mut w = gas(200);
    let all = disks(&w);
    assert_eq!(all.len(), 200);
    assert!(all.iter().all(|c| Arc::ptr_eq(&c.traits, &all[0].traits)));
    let (first, second) = (all[0].id, all[1].id);
    let before: Vec<(u64, u64, u64, u64)> = all
        .iter()
        .map(|c| {
            let t = &c.traits;
            let b = |x: f64| x.to_bits();
            (b(t.mass), b(t.priority), b(t.restitution), b(t.health))
        })
        .collect();
    let c = w.get_mut(first).expect("there");
    c.set_health(c.health() - 1.0);
    c.set_restitution(0.25).expect("a restitution");
    c.props_mut().insert("tag".into(), PropValue::Int(3));
    let all = disks(&w);
    assert_eq!(
        all[0].health().to_bits(),
        (f64::from_bits(before[0].3) - 1.0).to_bits()
    );
    assert_eq!(all[0].restitution(), 0.25);
    assert_eq!(all[0].props().len(), 1);
    for (c, b) in all.iter().zip(&before).skip(1) {
        let t = &c.traits;
        assert_eq!(
            (
                t.mass.to_bits(),
                t.priority.to_bits(),
                t.restitution.to_bits()
            ),
            (b.0, b.1, b.2)
        );
        assert_eq!(t.health.to_bits(), b.3);
        assert!(t.props.is_empty());
        assert!(Arc::ptr_eq(&c.traits, &all[1].traits), "{:?}", c.id);
    }
    assert!(!Arc::ptr_eq(&all[0].traits, &all[1].traits));
    assert_eq!(w.get(second).map(|c| c.restitution()), Some(1.0));
}

/// Only critters whose traits are the same bit for bit share them: a spawn that differs in
/// any one trait (health -0 against 0 too) gets its own, and one alike shares again.
#[test]
fn critters_that_differ_in_any_trait_do_not_share() {
    let mut w = gas(100);
    let last = disks(&w)[99].traits.clone();
    let at = |x: f64| DVec2::new(x, 5.0);
    let specs = [
        CritterSpec::ball(at(1.5)).restitution(0.5),
        CritterSpec::ball(at(2.5)).health(-0.0),
        CritterSpec::ball(at(3.5)).health(0.0),
        CritterSpec::ball(at(4.5)).mass(2.0),
        CritterSpec::ball(at(5.5)).priority(CP_WALL),
        CritterSpec::ball(at(6.5)).prop("tag", PropValue::Int(1)),
        CritterSpec::ball(at(7.5)).prop("tag", PropValue::Int(1)),
    ];
    let mut ids = Vec::new();
    for spec in specs {
        ids.push(w.spawn(spec).expect("spawns"));
    }
    let traits: Vec<Arc<Traits<DVec2>>> = ids
        .iter()
        .map(|&id| w.get(id).expect("there").traits.clone())
        .collect();
    for (i, t) in traits.iter().enumerate() {
        assert!(!Arc::ptr_eq(t, &last), "spawn {i}");
        for (j, u) in traits.iter().enumerate().take(i) {
            assert!(!Arc::ptr_eq(t, u), "spawns {j} and {i}");
        }
    }
    assert_eq!(
        w.get(ids[1]).map(|c| c.health().to_bits()),
        Some((-0.0f64).to_bits())
    );
    // Alike again: shares with the one before.
    let a = w.spawn(CritterSpec::ball(at(8.5))).expect("spawns");
    let b = w.spawn(CritterSpec::ball(at(9.5))).expect("spawns");
    let (ta, tb) = (&w.get(a).expect("a").traits, &w.get(b).expect("b").traits);
    assert!(Arc::ptr_eq(ta, tb));
}

/// A small pit of `solve:8` disks in a walled box; the same every call.
fn pit() -> World<DVec2> {
    use crate::wall::WallBox;
    let config = WorldConfig::new(DVec2::splat(-2.0), DVec2::new(22.0, 22.0))
        .dt(1.0 / 60.0)
        .gravity(DVec2::new(0.0, -9.81))
        .seed(3)
        .method(crate::method::Method::Solve(8));
    let mut w = World::new(config).expect("the pit's world");
    for (lo, hi) in [
        ((-1.0, -1.0), (21.0, 0.0)),
        ((-1.0, 0.0), (0.0, 20.0)),
        ((20.0, 0.0), (21.0, 20.0)),
    ] {
        let wall = WallBox::aligned(DVec2::from(lo), DVec2::from(hi)).expect("a wall");
        w.add_wall(wall).expect("the wall joins");
    }
    for i in 0..120 {
        let shift = w.rng().uniform(-0.1, 0.1);
        let pos = DVec2::new(
            1.0 + 1.25 * (i % 15) as f64 + shift,
            1.0 + 1.25 * (i / 15) as f64,
        );
        w.spawn(CritterSpec::ball(pos).radius(0.5).restitution(0.5))
            .expect("a disk");
    }
    w
}

/// Steps in which every critter sleeps skip the step's stages: the run is the full step's,
/// bit for bit, through falling asleep, a sleeper pushed awake, and a sleeper removed.
#[test]
fn a_pit_asleep_skips_its_steps_and_stays_the_full_step_s_run() {
    let (mut short, mut full) = (pit(), pit());
    full.methods.no_rest_shortcut();
    let movers = short.critters().iter().filter(|c| !c.is_wall()).count();
    let mut all_asleep = 0;
    let top = |w: &World<DVec2>| {
        let disks = w.critters().iter().filter(|c| !c.is_wall());
        disks
            .max_by(|a, b| a.pos.y.total_cmp(&b.pos.y))
            .expect("disks")
            .id()
    };
    for step in 0..2400 {
        if step == 1200 {
            for w in [&mut short, &mut full] {
                let id = top(w);
                w.get_mut(id).expect("the top disk").vel = DVec2::new(1.0, 2.0);
            }
        }
        if step == 1800 {
            for w in [&mut short, &mut full] {
                let id = top(w);
                w.remove(id).expect("the top disk goes");
            }
        }
        short.step().expect("steps");
        full.step().expect("steps");
        assert_eq!(short.state_hash(), full.state_hash(), "step {step}");
        let counts = |w: &World<DVec2>| {
            let t = w.totals();
            (t.contacts, t.collisions, t.impacts)
        };
        assert_eq!(counts(&short), counts(&full), "step {step}");
        all_asleep += usize::from(short.sleepers() + usize::from(step >= 1800) == movers);
    }
    // The shortcut was taken, before and after each disturbance.
    assert!(all_asleep > 600, "all asleep in {all_asleep} steps");
}
