//! The neighbour grid against brute-force scans: random worlds in 2D and 3D, with and without a
//! wrapping border, kind filters with a child kind, and hooks that move critters between the
//! queries of one update stage.

use super::*;
use crate::border::Border;
use crate::critter::CritterSpec;
use crate::error::Error;
use crate::kind::{KindDefaults, KindHooks};
use crate::rng::Rng;
use crate::step::access::UpdateCtx;
use crate::world::{World, WorldConfig};
use glam::{DVec2, DVec3};
use std::cell::Cell;
use std::rc::Rc;

/// A world of `n` critters of kinds `a`, `b` (extends `a`) and `c`, some on a lattice and some
/// on one spot so distances tie, inside walls.
fn random_world<V: Vector>(seed: u64, n: usize, border: Border) -> World<V> {
    let mut config = WorldConfig::new(V::zero(), V::splat(20.0));
    config.border = border;
    config.seed = seed;
    let mut w = World::new(config).expect("a valid world");
    let d = KindDefaults {
        radius: 0.1,
        ..KindDefaults::default()
    };
    w.register_kind("a", None, d.clone(), Rc::new(())).unwrap();
    w.register_kind("b", Some("a"), d.clone(), Rc::new(()))
        .unwrap();
    w.register_kind("c", None, d, Rc::new(())).unwrap();
    let mut rng = Rng::new(seed);
    for i in 0..n {
        let mut p = V::zero();
        for axis in 0..V::DIM {
            let x = match i % 5 {
                0 => 2.0 + ((i / (axis + 1)) % 16) as f64,
                1 => 7.0,
                _ => rng.uniform(0.5, 19.5),
            };
            p.set(axis, x);
        }
        let kind = ["a", "b", "c"][i % 3];
        w.spawn(CritterSpec::new(kind, p)).expect("spawns");
    }
    w
}

fn brute_nearby<V: Vector>(w: &World<V>, centre: V, r: f64, f: Filter) -> Vec<CritterId> {
    let kinds = w.kinds();
    w.critters()
        .iter()
        .filter(|c| c.alive && !c.is_wall() && f.exclude != Some(c.id))
        .filter(|c| f.kind.is_none_or(|k| kinds.is_kind(c.kind(), k)))
        .filter(|c| w.topology().delta(centre, c.pos).length() <= r)
        .map(|c| c.id)
        .collect()
}

fn brute_nearest<V: Vector>(w: &World<V>, centre: V, f: Filter) -> Option<CritterId> {
    let all = brute_nearby(w, centre, f64::INFINITY, f);
    let dist = |id: &CritterId| w.topology().delta(centre, w.get(*id).unwrap().pos).length();
    // `all` is in id order; `min_by` keeps the first of equal elements.
    all.into_iter()
        .min_by(|a, b| dist(a).partial_cmp(&dist(b)).unwrap())
}

fn check_world<V: Vector>(w: &mut World<V>, rng: &mut Rng) {
    let kinds = [
        None,
        Some(w.kinds().id("a").unwrap()),
        Some(w.kinds().id("b").unwrap()),
    ];
    let ids: Vec<CritterId> = w.critters().iter().map(|c| c.id).collect();
    for (i, &id) in ids.iter().enumerate() {
        let Some(c) = w.get(id) else { continue };
        let centre = if i % 2 == 0 {
            c.pos
        } else {
            let mut p = V::zero();
            for axis in 0..V::DIM {
                p.set(axis, rng.uniform(-3.0, 23.0));
            }
            p
        };
        let exclude = (i % 2 == 0).then_some(id);
        for kind in kinds {
            let f = Filter { kind, exclude };
            for r in [0.0, 1.0, 2.0, 3.5, 9.0, 15.0] {
                assert_eq!(
                    w.nearby(centre, r, kind, exclude),
                    brute_nearby(w, centre, r, f),
                    "nearby({centre:?}, {r}, {kind:?})"
                );
            }
            assert_eq!(
                w.nearest(centre, kind, exclude),
                brute_nearest(w, centre, f),
                "nearest({centre:?}, {kind:?})"
            );
        }
    }
}

fn random_worlds<V: Vector>() {
    for border in [Border::Bounce, Border::Wrap] {
        for seed in [1, 2, 3] {
            let mut w = random_world::<V>(seed, 150, border);
            let mut rng = Rng::new(seed + 100);
            check_world(&mut w, &mut rng);
            w.run(10).expect("steps");
            check_world(&mut w, &mut rng);
            // Moves and deaths between steps, through the world's own handles.
            let ids: Vec<CritterId> = w.critters().iter().map(|c| c.id).collect();
            for (i, id) in ids.into_iter().enumerate() {
                if i % 4 == 0 {
                    let to = V::splat(rng.uniform(1.0, 19.0));
                    w.get_mut(id).unwrap().pos = to;
                } else if i % 7 == 0 {
                    w.remove(id).unwrap();
                }
            }
            w.spawn(CritterSpec::new("b", V::splat(7.0))).unwrap();
            check_world(&mut w, &mut rng);
        }
    }
}

#[test]
fn nearby_and_nearest_match_brute_force_in_2d() {
    random_worlds::<DVec2>();
}

#[test]
fn nearby_and_nearest_match_brute_force_in_3d() {
    random_worlds::<DVec3>();
}

/// A kind whose `update` moves every third critter and then asks for its neighbours, checking
/// each answer against a scan of every critter where they are at that moment.
struct Mover {
    wrong: Rc<Cell<usize>>,
    asked: Rc<Cell<usize>>,
}

impl KindHooks<DVec2> for Mover {
    fn has_update(&self) -> bool {
        true
    }
    fn update(&self, ctx: &mut UpdateCtx<'_, DVec2>, _dt: f64) -> Result<(), Error> {
        let me = ctx.me().id;
        if me.index.is_multiple_of(3) {
            let p = ctx.me().pos;
            ctx.me_mut().pos = DVec2::new(20.0 - p.y, p.x);
        }
        let centre = ctx.me().pos;
        // Every critter, then the mover kind's own grid.
        for (r, kind) in [(1.0, None), (4.0, None), (4.0, Some(ctx.me().kind()))] {
            let got = ctx.nearby(centre, r, kind, Some(me));
            let want: Vec<CritterId> = ctx
                .state
                .critters
                .iter()
                .filter(|c| c.alive && !c.is_wall() && c.id != me)
                .filter(|c| kind.is_none_or(|k| c.kind() == k))
                .filter(|c| ctx.state.topo.delta(centre, c.pos).length() <= r)
                .map(|c| c.id)
                .collect();
            self.asked.set(self.asked.get() + 1);
            if got != want {
                self.wrong.set(self.wrong.get() + 1);
            }
        }
        Ok(())
    }
}

#[test]
fn queries_inside_an_update_stage_see_the_moves_hooks_made() {
    let (wrong, asked) = (Rc::new(Cell::new(0)), Rc::new(Cell::new(0)));
    let mut w = random_world::<DVec2>(5, 0, Border::Wrap);
    let hooks = Mover {
        wrong: wrong.clone(),
        asked: asked.clone(),
    };
    w.register_kind("mover", None, KindDefaults::default(), Rc::new(hooks))
        .unwrap();
    let mut rng = Rng::new(5);
    for _ in 0..300 {
        let p = DVec2::new(rng.uniform(0.5, 19.5), rng.uniform(0.5, 19.5));
        let mut spec = CritterSpec::new("mover", p);
        spec.radius = Some(0.05);
        w.spawn(spec).unwrap();
    }
    for _ in 0..3 {
        let before = w.state.neighbours.builds();
        w.step().unwrap();
        assert_eq!(
            w.state.neighbours.builds() - before,
            2,
            "one grid of all and one of the kind serve the whole update stage"
        );
    }
    assert_eq!(asked.get(), 3 * 300 * 3);
    assert_eq!(wrong.get(), 0, "every answer matched the scan");
}

#[test]
fn a_world_with_no_queries_builds_no_grid() {
    let mut w = random_world::<DVec2>(1, 100, Border::Bounce);
    w.run(5).unwrap();
    assert_eq!(w.state.neighbours.builds(), 0);
}
