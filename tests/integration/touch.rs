//! Touching spells and `on_death` through the library's own hook trait, under every method and
//! in 2D and 3D: one begin and one end per bounce on both sides, a death ends the spells, and a
//! world whose kinds have no such hooks keeps no spells.

use crate::common;

use common::*;
use critterbox::glam::{DVec2, DVec3};
use critterbox::{
    CollideCtx, CritterId, CritterSpec, Error, HookContact, KindDefaults, KindHooks, Method,
    UpdateCtx, Vector, World,
};
use std::cell::RefCell;
use std::rc::Rc;

/// What the watcher saw: (me, other, begin?) per event, and the deaths.
#[derive(Default)]
struct Seen {
    events: Vec<(CritterId, CritterId, bool)>,
    deaths: Vec<CritterId>,
    bad_normals: usize,
}

struct Watcher(Rc<RefCell<Seen>>);

impl<V: Vector> KindHooks<V> for Watcher {
    fn tracks_touch(&self) -> bool {
        true
    }
    fn touch_begin(&self, ctx: &mut CollideCtx<'_, V>, c: &HookContact<V>) -> Result<(), Error> {
        let d = ctx.delta(ctx.me().pos, ctx.other().pos);
        let unit = (c.normal.length() - 1.0).abs() < 1e-9;
        if !unit || c.normal.dot(d) <= 0.0 || !c.first {
            self.0.borrow_mut().bad_normals += 1;
        }
        let (me, other) = (ctx.me().id(), ctx.other().id());
        self.0.borrow_mut().events.push((me, other, true));
        Ok(())
    }
    fn touch_end(&self, ctx: &mut CollideCtx<'_, V>) -> Result<(), Error> {
        let (me, other) = (ctx.me().id(), ctx.other().id());
        self.0.borrow_mut().events.push((me, other, false));
        Ok(())
    }
    fn has_on_death(&self) -> bool {
        true
    }
    fn on_death(&self, ctx: &mut UpdateCtx<'_, V>) -> Result<(), Error> {
        self.0.borrow_mut().deaths.push(ctx.me().id());
        Ok(())
    }
}

fn watched<V: Vector>(method: Method) -> (World<V>, Rc<RefCell<Seen>>) {
    let mut w = world::<V>(20.0);
    w.set_method(method).unwrap();
    let seen = Rc::new(RefCell::new(Seen::default()));
    register(
        &mut w,
        "watcher",
        KindDefaults::default(),
        Rc::new(Watcher(seen.clone())),
    );
    (w, seen)
}

const METHODS: [&str; 6] = ["discrete", "substep:4", "solve:8", "event", "swept", "auto"];

fn head_on<V: Vector>(method: &str) {
    let (mut w, seen) = watched::<V>(method.parse().unwrap());
    let at = |x: f64| {
        let mut p = V::splat(10.0);
        p.set(0, x);
        p
    };
    let vx = |x: f64| {
        let mut v = V::zero();
        v.set(0, x);
        v
    };
    let a = w
        .spawn(CritterSpec::new("watcher", at(8.0)).vel(vx(2.0)))
        .unwrap();
    let b = w
        .spawn(CritterSpec::new("watcher", at(12.0)).vel(vx(-2.0)))
        .unwrap();
    w.run(120).unwrap();
    let seen = seen.borrow();
    assert_eq!(
        seen.events,
        vec![(a, b, true), (b, a, true), (a, b, false), (b, a, false)],
        "{method}: both sides begin, then both end, lower id first"
    );
    assert_eq!(seen.bad_normals, 0, "{method}: normals from me to other");
}

#[test]
fn a_head_on_bounce_is_one_spell_on_both_sides_2d() {
    for m in METHODS {
        head_on::<DVec2>(m);
    }
}

#[test]
fn a_head_on_bounce_is_one_spell_on_both_sides_3d() {
    for m in METHODS {
        head_on::<DVec3>(m);
    }
}

#[test]
fn a_removed_critter_ends_its_spells_and_dies_once() {
    let (mut w, seen) = watched::<DVec2>(Method::Discrete);
    let a = w
        .spawn(CritterSpec::new("watcher", DVec2::new(10.0, 10.0)))
        .unwrap();
    let b = w
        .spawn(CritterSpec::new("watcher", DVec2::new(10.9, 10.0)))
        .unwrap();
    w.step().unwrap();
    w.remove(b).unwrap();
    w.run(5).unwrap();
    let seen = seen.borrow();
    assert_eq!(
        seen.events,
        vec![(a, b, true), (b, a, true), (a, b, false), (b, a, false)]
    );
    assert_eq!(seen.deaths, vec![b]);
}

#[test]
fn kinds_without_touch_hooks_keep_no_spells() {
    let w = world2(10.0);
    assert!(!w.kinds().tracks_touch());
    assert!(!w.kinds().has_on_death());
}

/// A watcher that, as the caller, dies in its own `collide`: on the first step of its spell.
struct Shot(Rc<RefCell<Seen>>);

impl<V: Vector> KindHooks<V> for Shot {
    fn tracks_touch(&self) -> bool {
        true
    }
    fn collide(&self, ctx: &mut CollideCtx<'_, V>) -> Result<bool, Error> {
        ctx.die_me();
        Ok(true)
    }
    fn touch_begin(&self, ctx: &mut CollideCtx<'_, V>, c: &HookContact<V>) -> Result<(), Error> {
        Watcher(self.0.clone()).touch_begin(ctx, c)
    }
    fn touch_end(&self, ctx: &mut CollideCtx<'_, V>) -> Result<(), Error> {
        Watcher(self.0.clone()).touch_end(ctx)
    }
}

#[test]
fn a_critter_dying_in_its_first_touch_still_begins_and_ends_the_spell() {
    for m in METHODS {
        let (mut w, seen) = watched::<DVec2>(m.parse().unwrap());
        let shot = KindDefaults {
            priority: critterbox::CP_BULLET,
            radius: 0.2,
            ..KindDefaults::default()
        };
        register(&mut w, "shot", shot, Rc::new(Shot(seen.clone())));
        let target = w
            .spawn(CritterSpec::new("watcher", DVec2::new(10.0, 10.0)))
            .unwrap();
        let s = w
            .spawn(CritterSpec::new("shot", DVec2::new(8.0, 10.0)).vel(DVec2::new(6.0, 0.0)))
            .unwrap();
        w.run(60).unwrap();
        assert!(w.get(s).is_none(), "{m}: the shot died");
        let seen = seen.borrow();
        assert_eq!(
            seen.events,
            vec![
                (target, s, true),
                (s, target, true),
                (target, s, false),
                (s, target, false)
            ],
            "{m}: the spell begins and ends on both sides, lower id first"
        );
        assert_eq!(seen.deaths, Vec::<CritterId>::new(), "{m}: no watcher died");
    }
}
