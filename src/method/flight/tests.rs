//! The flight's own checks: its memory layout, shells against cells, kept flights against new
//! ones, and who may meet something.

use crate::scenes::{gas, GasParams};
use crate::{Border, Method, World};
use glam::DVec3;

fn periodic_gas(no_shells: bool) -> World<DVec3> {
    let mut w = gas::<DVec3>(&GasParams {
        n: 512,
        packing: 0.35,
        dt: 0.5,
        border: Border::Wrap,
        ..GasParams::default()
    })
    .expect("the gas builds");
    w.set_method(Method::Event).expect("event");
    w.methods.flight.no_shells = no_shells;
    w
}

/// A stripe of cells or of a neighbour list starts on a cache line (16 entries or fewer are
/// one line), before and after the stripes grow, and growing keeps every member; a 3D body
/// is one whole line and a shell's centre half of one.
#[test]
fn stripes_and_bodies_lie_on_cache_lines() {
    let line = |cells: &super::cells::StripedLists, k: usize| {
        (cells.data.as_ptr() as usize + 4 * cells.start(k)) % 64
    };
    let mut cells = super::cells::StripedLists::default();
    cells.reset(40, 5);
    assert_eq!(
        cells.stride, 8,
        "room for 5 and the count, rounded up to a power of two"
    );
    assert!((0..40).all(|k| line(&cells, k) % 32 == 0));
    assert_eq!(line(&cells, 0), 0);
    for k in 0..40 {
        for m in 0..(k % 7) as u32 {
            cells.push(k, 1000 * k as u32 + m);
        }
    }
    // Cell 6 filled past its room for 7: every stripe grew.
    cells.push(6, 6006);
    cells.push(6, 6007);
    assert_eq!(cells.stride, 16);
    assert!((0..40).all(|k| line(&cells, k) == 0));
    for k in 0..40 {
        let mut want: Vec<u32> = (0..(k % 7) as u32).map(|m| 1000 * k as u32 + m).collect();
        if k == 6 {
            want.extend([6006, 6007]);
        }
        assert_eq!(cells.members(k), &want[..], "cell {k}");
    }
    cells.remove(6, 6001);
    assert_eq!(cells.members(6).len(), 7);
    assert!(!cells.members(6).contains(&6001));
    assert_eq!(std::mem::size_of::<super::bodies::Body<DVec3>>(), 64);
    assert_eq!(std::mem::align_of::<super::bodies::Body<DVec3>>(), 64);
    assert_eq!(std::mem::size_of::<super::bodies::Body<glam::DVec2>>(), 48);
    assert_eq!(std::mem::size_of::<super::shells::ShellCentre<DVec3>>(), 32);
    assert_eq!(
        std::mem::align_of::<super::shells::ShellCentre<DVec3>>(),
        32
    );
}

/// Shells and cells are two ways of finding the same collisions: over a few collisions per
/// sphere (before round-off differences grow chaotically) they find the same number and
/// leave every sphere in the same place.
#[test]
fn shells_and_cells_find_the_same_collisions() {
    let (mut shells, mut cells) = (periodic_gas(false), periodic_gas(true));
    let (mut with_shells, mut with_cells) = (0, 0);
    for _ in 0..2 {
        shells.step().expect("steps");
        cells.step().expect("steps");
        with_shells += shells.stats().impacts;
        with_cells += cells.stats().impacts;
    }
    assert!(
        shells.methods.flight.shells,
        "the 3D periodic gas lists neighbours in shells"
    );
    assert!(!cells.methods.flight.shells);
    assert!(
        with_cells > 2 * 512,
        "{with_cells} collisions: too few to compare"
    );
    assert_eq!(with_shells, with_cells);
    let topo = shells.state.topo;
    let worst = shells
        .critters()
        .iter()
        .zip(cells.critters().iter())
        .map(|(a, b)| topo.delta(a.pos, b.pos).length())
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "spheres differ by {worst:e}");
}

/// A flight kept from step to step flies what a new flight every step flies: over a few
/// collisions per disk (before round-off differences grow chaotically) the same number of
/// collisions, every disk in the same place, energy kept, and no two disks overlapping.
/// Between the steps some critters are pushed from outside the flight (as a hook or the
/// caller may), which the kept flight must notice. Walled 2D gas (cells) and periodic 3D gas
/// (shells); dt short, so that most of a step's events were predicted in earlier steps.
#[test]
fn a_kept_flight_flies_what_a_new_flight_every_step_flies() {
    fn check<V: crate::Vector>(border: Border, n: usize, speed: f64, dt: f64, steps: usize) {
        let build = |no_keep: bool| {
            let mut w = gas::<V>(&GasParams {
                n,
                packing: 0.3,
                dt,
                border,
                ..GasParams::default()
            })
            .expect("the gas builds");
            // A few collisions per disk in the run.
            let ids: Vec<_> = w.critters().iter().map(|c| c.id()).collect();
            for id in ids {
                if let Some(c) = w.get_mut(id) {
                    c.vel = c.vel * speed;
                }
            }
            w.set_method(Method::Event).expect("event");
            w.methods.flight.no_keep = no_keep;
            w
        };
        let (mut kept, mut fresh) = (build(false), build(true));
        let e0 = kept.kinetic_energy();
        let (mut with_kept, mut with_fresh, mut resumed) = (0, 0, 0);
        for step in 0..steps {
            for w in [&mut kept, &mut fresh] {
                if step % 7 == 3 {
                    // A push from outside: every 50th disk turned around.
                    let ids: Vec<_> = w.critters().iter().map(|c| c.id()).collect();
                    for id in ids.into_iter().step_by(50) {
                        if let Some(c) = w.get_mut(id) {
                            c.vel = -c.vel;
                        }
                    }
                }
            }
            resumed += usize::from(kept.methods.flight.kept.is_some());
            kept.step().expect("steps");
            fresh.step().expect("steps");
            with_kept += kept.stats().impacts;
            with_fresh += fresh.stats().impacts;
        }
        assert!(
            resumed >= steps / 2,
            "the flight went on in only {resumed} of {steps} steps"
        );
        assert!(fresh.methods.flight.kept.is_none());
        assert!(
            with_fresh > 2 * n,
            "{with_fresh} collisions: too few to compare"
        );
        assert_eq!(with_kept, with_fresh);
        let topo = kept.state.topo;
        let cs: Vec<_> = kept.critters().iter().collect();
        let worst = cs
            .iter()
            .zip(fresh.critters().iter())
            .map(|(a, b)| topo.delta(a.pos, b.pos).length())
            .fold(0.0, f64::max);
        // Round-off differences, grown by each collision (a gas is chaotic); a missed or
        // wrong event would put disks a good part of a radius apart.
        assert!(worst < 1e-6, "disks differ by {worst:e}");
        let drift = (kept.kinetic_energy() - e0).abs() / e0;
        assert!(drift < 1e-12, "energy drift {drift:e}");
        let mut overlap: f64 = 0.0;
        for (i, a) in cs.iter().enumerate().filter(|(_, c)| !c.is_wall()) {
            for b in cs[i + 1..].iter().filter(|c| !c.is_wall()) {
                let d = topo.delta(a.pos, b.pos).length();
                overlap = overlap.max(a.radius + b.radius - d);
            }
        }
        assert!(overlap < 1e-9, "disks overlap by {overlap:e}");
    }
    check::<glam::DVec2>(Border::Bounce, 400, 4.0, 1.0 / 60.0, 120);
    check::<DVec3>(Border::Wrap, 300, 1.0, 1.0 / 30.0, 30);
}

/// The flight's start asks who may meet something pair by pair over the cells
/// (`mark_who_may_meet`); the answers are `may_meet`'s, critter by critter, for every disk:
/// walled and periodic gases in 2D and 3D, stirred so that some disks are close and some
/// fast, a wall across the middle, and a box too thin for three cells across.
#[test]
fn who_may_meet_pair_by_pair_is_may_meet() {
    fn check<V: crate::Vector>(border: Border, n: usize, packing: f64, thin: bool) {
        let mut w = if thin {
            // A periodic box 1.5 across but along the first axis: one cell across.
            let mut hi = V::splat(1.5);
            hi.set(0, 1.3 * n as f64);
            let config = crate::WorldConfig::new(V::zero(), hi)
                .border(border)
                .dt(1.0 / 60.0);
            let mut w = World::new(config).expect("the world builds");
            for i in 0..n {
                let mut p = V::splat(0.75);
                p.set(0, 1.3 * i as f64 + 0.2 * ((i * 7) % 5) as f64);
                let mut v = V::zero();
                v.set(0, if i % 2 == 0 { 1.0 } else { -0.7 });
                w.spawn(crate::CritterSpec::ball(p).vel(v).radius(0.5))
                    .expect("spawns");
            }
            w
        } else {
            gas::<V>(&GasParams {
                n,
                packing,
                dt: 1.0 / 60.0,
                border,
                seed: 11,
                ..GasParams::default()
            })
            .expect("the gas builds")
        };
        if border != Border::Wrap {
            let (lo, hi) = (w.state.topo.min, w.state.topo.max);
            let mid = (lo + hi) * 0.5;
            let mut a = mid;
            a.set(0, lo.get(0) + 2.0);
            let mut b = mid;
            b.set(0, hi.get(0) - 2.0);
            let half = V::splat(0.05);
            let wall = crate::WallBox::aligned(a - half, b + half).expect("a box");
            // A wall may not be put down through critters: clear its place first.
            for id in w.state.critters_under(&wall) {
                w.remove(id).expect("there");
            }
            w.add_wall(wall).expect("the wall goes in");
        }
        // Stir: a few discrete steps at speeds of several radii per second, then some disks
        // much faster.
        let ids: Vec<_> = w
            .critters()
            .iter()
            .filter(|c| !c.is_wall())
            .map(|c| c.id())
            .collect();
        for (i, id) in ids.iter().enumerate() {
            let c = w.get_mut(*id).expect("live");
            c.vel = c.vel * if i % 13 == 0 { 40.0 } else { 6.0 };
        }
        for _ in 0..20 {
            w.step().expect("steps");
        }
        let limit = 0.25 * 0.5;
        let mut sc = std::mem::take(&mut w.methods.flight);
        sc.slow_below = Some(limit);
        let dt = w.dt();
        sc.dt = dt;
        super::setup::setup(&mut w.state, &mut sc, V::zero(), dt, 1);
        super::setup::mark_who_may_meet(&w.state, &mut sc);
        let (mut yes, mut no) = (0, 0);
        for a in 0..sc.body.len() as u32 {
            let want = super::setup::may_meet(&w.state, &sc, a);
            assert_eq!(sc.meets[a as usize], want, "disk {a}");
            if sc.body[a as usize].radius.is_nan() {
                continue;
            }
            if want {
                yes += 1;
            } else {
                no += 1;
            }
        }
        assert!(
            yes * 20 > n && no * 20 > n,
            "{yes} may meet, {no} not: too one-sided"
        );
    }
    check::<glam::DVec2>(Border::Bounce, 3000, 0.15, false);
    check::<glam::DVec2>(Border::Wrap, 3000, 0.15, false);
    check::<glam::DVec2>(Border::Wrap, 200, 0.0, true);
    check::<DVec3>(Border::Bounce, 2000, 0.1, false);
    check::<DVec3>(Border::Wrap, 2000, 0.1, false);
}

/// Cells are at least a diameter wide and at most about two per disk: over that cap the
/// grid is scaled down to just under it, not halved (which could leave a quarter of the
/// cap in 2D and an eighth in 3D, cells twice as wide as needed).
#[test]
fn cells_come_as_close_to_their_cap_as_a_diameter_allows() {
    fn check<V: crate::Vector>(n: usize, packing: f64) {
        let mut w = gas::<V>(&GasParams {
            n,
            packing,
            ..GasParams::default()
        })
        .expect("the gas builds");
        let mut sc = std::mem::take(&mut w.methods.flight);
        let dt = w.dt();
        sc.dt = dt;
        super::setup::setup(&mut w.state, &mut sc, V::zero(), dt, 1);
        let total: usize = sc.dims[..V::DIM].iter().product();
        let cap = 2 * n;
        let widest = (w.state.topo.size().get(0) / 1.0).floor() as usize;
        let unconstrained = widest.pow(V::DIM as u32);
        assert!(total <= cap, "{total} cells for {n} disks");
        assert!(
            10 * total >= 7 * cap.min(unconstrained),
            "{total} cells for {n} disks (cap {cap}, {unconstrained} a diameter wide)"
        );
        for axis in 0..V::DIM {
            assert!(
                sc.cell_side[axis] >= 1.0,
                "cells {} wide",
                sc.cell_side[axis]
            );
        }
    }
    check::<glam::DVec2>(100, 0.3);
    check::<glam::DVec2>(10_000, 0.02);
    check::<glam::DVec2>(10_000, 0.4);
    check::<DVec3>(1000, 0.2);
    check::<DVec3>(4000, 0.05);
}

/// Shells keep the gas exact: energy and momentum conserved, nobody overlapping.
#[test]
fn shells_conserve_energy_and_momentum_and_leave_no_overlap() {
    let mut w = periodic_gas(false);
    let e0 = w.kinetic_energy();
    let p0: DVec3 = w.critters().iter().map(|c| c.vel * c.mass()).sum();
    let mut impacts = 0;
    for _ in 0..6 {
        w.step().expect("steps");
        impacts += w.stats().impacts;
    }
    assert!(impacts > 5 * 512, "{impacts} collisions");
    let e1 = w.kinetic_energy();
    let p1: DVec3 = w.critters().iter().map(|c| c.vel * c.mass()).sum();
    assert!(((e1 - e0) / e0).abs() < 1e-12, "energy {e0} -> {e1}");
    assert!(
        (p1 - p0).length() < 1e-9 * e0.sqrt(),
        "momentum {p0} -> {p1}"
    );
    let all: Vec<_> = w.critters().iter().collect();
    for (i, a) in all.iter().enumerate() {
        for b in &all[i + 1..] {
            let gap = w.state.topo.delta(a.pos, b.pos).length() - a.radius - b.radius;
            assert!(gap > -1e-9, "overlap {gap:e}");
        }
    }
}
