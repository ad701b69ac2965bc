//! The mixed scenes of `docs/stability.md`: scenes whose parts need different methods (a pile
//! that must come to rest beside a cradle that must hand its momentum on exactly, bullets fired
//! into a resting pile, an elastic gas above a pile), written once for the tests,
//! `critterbox stability` and `critterbox chart`. Each scene runs under a [`Method`] and returns
//! one measured error per part (0 is perfect; what each measures is in its [`Part`]). They are
//! generic over the vector type: in 3D the disks are spheres in a square well.

use crate::critter::{CritterId, CritterSpec};
use crate::error::Error;
use crate::method::Method;
use crate::vector::Vector;
use crate::wall::WallBox;
use crate::world::{World, WorldConfig};
use glam::{DVec2, DVec3};

/// One part of a mixed scene and what its error measures.
pub struct Part {
    /// Name (the table's row is "scene: part").
    pub name: &'static str,
    /// What the error measures.
    pub error: &'static str,
}

/// One mixed scene.
pub struct Mixed {
    /// Name.
    pub name: &'static str,
    /// Its parts, in the order `run` measures them.
    pub parts: &'static [Part],
    /// Steps a run takes (for the cost per step).
    pub steps: u64,
    /// Runs the scene under a method: one error per part.
    pub run: fn(Method) -> Result<Vec<f64>, Error>,
}

const CRADLE_PARTS: &[Part] = &[
    Part {
        name: "cradle",
        error: "momentum left outside the last ball relative to the common fall, relative",
    },
    Part {
        name: "pile",
        error: "deepest overlap of the pile at the end, in radii",
    },
];

const BULLET_PARTS: &[Part] = &[
    Part {
        name: "escaped",
        error: "critters outside the box at some step's end",
    },
    Part {
        name: "pile moved",
        error: "largest displacement of a pile critter, in radii",
    },
    Part {
        name: "pile overlap",
        error: "deepest overlap of the pile at the end, in radii",
    },
];

const GAS_PARTS: &[Part] = &[
    Part {
        name: "gas energy",
        error: "the gas's energy drift over the steps clear of the pile, relative to its kinetic energy",
    },
    Part {
        name: "pile",
        error: "deepest overlap of the pile at the end, in radii",
    },
];

/// The mixed scenes in 2D.
pub const MIXED: &[Mixed] = &[
    Mixed {
        name: "pile beside cradle",
        parts: CRADLE_PARTS,
        steps: CRADLE_STEPS,
        run: pile_beside_cradle::<DVec2>,
    },
    Mixed {
        name: "bullets into pile",
        parts: BULLET_PARTS,
        steps: BULLET_STEPS,
        run: bullets_into_pile::<DVec2>,
    },
    Mixed {
        name: "gas above pile",
        parts: GAS_PARTS,
        steps: GAS_STEPS,
        run: gas_above_pile::<DVec2>,
    },
];

/// The mixed scenes in 3D, with spheres in a square well.
pub const MIXED_3D: &[Mixed] = &[
    Mixed {
        name: "pile beside cradle (3D)",
        parts: CRADLE_PARTS,
        steps: CRADLE_STEPS,
        run: pile_beside_cradle::<DVec3>,
    },
    Mixed {
        name: "bullets into pile (3D)",
        parts: BULLET_PARTS,
        steps: BULLET_STEPS,
        run: bullets_into_pile::<DVec3>,
    },
    Mixed {
        name: "gas above pile (3D)",
        parts: GAS_PARTS,
        steps: GAS_STEPS,
        run: gas_above_pile::<DVec3>,
    },
];

/// A mixed scene's world and the ids of its two groups of critters (which they are, each
/// scene's `*_world` says).
pub type Groups<V> = (World<V>, Vec<CritterId>, Vec<CritterId>);

const DT: f64 = 1.0 / 60.0;
const GRAVITY: f64 = 9.81;
/// Walls' thickness.
const WALL: f64 = 0.2;
const CRADLE_STEPS: u64 = 240;
const BULLET_STEPS: u64 = 60;
const GAS_STEPS: u64 = 120;

/// A world under gravity (along -y) from -1 on every axis to `top`, with a box of walls
/// `WALL` thick around the inside from the origin to `inner`: a floor, side walls `inner`
/// high, and a lid when `lid`.
pub fn walled_box<V: Vector>(
    method: Method,
    inner: V,
    top: V,
    lid: bool,
) -> Result<World<V>, Error> {
    let mut g = V::zero();
    g.set(1, -GRAVITY);
    let mut w = World::new(
        WorldConfig::new(V::splat(-1.0), top)
            .dt(DT)
            .gravity(g)
            .method(method),
    )?;
    for axis in 0..V::DIM {
        for high in [false, true] {
            if axis == 1 && high && !lid {
                continue;
            }
            let (mut lo, mut hi) = (V::splat(-WALL), inner + V::splat(WALL));
            if high {
                lo.set(axis, inner.get(axis));
            } else {
                hi.set(axis, 0.0);
            }
            w.add_wall(WallBox::aligned(lo, hi)?)?;
        }
    }
    Ok(w)
}

/// The point `horizontal` (x, and z in 3D) at height `y`.
fn at<V: Vector>(horizontal: [f64; 2], y: f64) -> V {
    let mut p = V::zero();
    p.set(0, horizontal[0]);
    p.set(1, y);
    if V::DIM == 3 {
        p.set(2, horizontal[1]);
    }
    p
}

/// The sites of a horizontal layer of `per_row` (x, and z in 3D) critters `pitch` apart, the
/// first at `first`.
fn layer_sites<V: Vector>(per_row: usize, first: f64, pitch: f64) -> Vec<[f64; 2]> {
    let rows_z = if V::DIM == 3 { per_row } else { 1 };
    let mut sites = Vec::with_capacity(per_row * rows_z);
    for k in 0..rows_z {
        for i in 0..per_row {
            let z = if V::DIM == 3 {
                first + k as f64 * pitch
            } else {
                0.0
            };
            sites.push([first + i as f64 * pitch, z]);
        }
    }
    sites
}

/// A pile at rest that cannot spread: `layers` layers of balls of radius 0.5 (restitution `e`)
/// on the floor of a box `width` wide (a whole number), the bottom layer touching the walls
/// and each other, every other layer in the hollows of the one below (hexagonal rows in 2D,
/// body-centred layers in 3D), a hair apart in height. The ids.
fn jammed_pile<V: Vector>(
    w: &mut World<V>,
    width: usize,
    layers: usize,
    e: f64,
) -> Result<Vec<CritterId>, Error> {
    let r = 0.5;
    let gap = 1e-6;
    // Centres of touching balls in the hollows: sqrt(3) r higher in rows, sqrt(2) r in layers.
    let rise = if V::DIM == 2 {
        3f64.sqrt()
    } else {
        2f64.sqrt()
    } * r
        + gap;
    let mut ids = Vec::new();
    for layer in 0..layers {
        let (count, first) = if layer % 2 == 0 {
            (width, r)
        } else {
            (width - 1, 2.0 * r)
        };
        let y = r + gap + layer as f64 * rise;
        for site in layer_sites::<V>(count, first, 2.0 * r) {
            let spec = CritterSpec::ball(at::<V>(site, y)).radius(r).restitution(e);
            ids.push(w.spawn(spec)?);
        }
    }
    Ok(ids)
}

/// The deepest overlap between two of `ids`, in radii of the smaller (infinite for a NaN or a
/// critter gone).
pub fn overlap_among<V: Vector>(w: &World<V>, ids: &[CritterId]) -> f64 {
    let mut cs = Vec::with_capacity(ids.len());
    for &id in ids {
        match w.get(id) {
            Some(c) if c.pos.all_finite() => cs.push(c),
            _ => return f64::INFINITY,
        }
    }
    let mut worst: f64 = 0.0;
    for (i, a) in cs.iter().enumerate() {
        for b in &cs[i + 1..] {
            let d = w.topology().delta(a.pos, b.pos).length();
            let depth = (a.radius() + b.radius() - d) / a.radius().min(b.radius());
            worst = worst.max(depth);
        }
    }
    worst
}

/// Number of balls in the jumbled pile.
pub const JUMBLED_PILE: usize = 192;
/// The cradle's striker speed.
const STRIKER: f64 = 5.0;

/// A jumbled pile of [`JUMBLED_PILE`] balls (restitution 0.5) dropped into a well (10 wide, in 3D
/// 4 x 4) from a loose grid shaken by the world's generator, settling for 4 s, beside a
/// five-ball Newton's cradle (radius 0.5, elastic) struck at `STRIKER` high in the air, far
/// from the pile, all of it falling freely. The errors: the cradle's (as the stress cradle
/// measures it, in the frame that falls with it) and the pile's deepest overlap.
pub fn pile_beside_cradle<V: Vector>(method: Method) -> Result<Vec<f64>, Error> {
    let (mut w, cradle, pile) = pile_beside_cradle_world::<V>(method)?;
    w.run(CRADLE_STEPS)?;
    Ok(vec![
        cradle_error(&w, &cradle, STRIKER),
        overlap_among(&w, &pile),
    ])
}

/// The world of [`pile_beside_cradle`]: it, the cradle's ids (striker first) and the pile's.
pub fn pile_beside_cradle_world<V: Vector>(method: Method) -> Result<Groups<V>, Error> {
    // 2D: 9 disks of radius 0.5 a row in a well 10 wide; 3D: 4 x 4 spheres of radius 0.45 a
    // layer in a well 4 x 4. Either leaves room to shake them.
    let (width, per_row, r) = if V::DIM == 2 {
        (10.0, 9, 0.5)
    } else {
        (4.0, 4, 0.45)
    };
    let mut inner = V::splat(width);
    inner.set(1, 30.0);
    let mut top = V::splat(width + 1.0);
    top.set(0, 60.0);
    top.set(1, 110.0);
    let mut w = walled_box(method, inner, top, false)?;
    let pitch = width / per_row as f64;
    let shake = 0.9 * (pitch / 2.0 - r);
    let rise = 2.2 * r;
    let mut pile = Vec::with_capacity(JUMBLED_PILE);
    'layers: for layer in 0.. {
        for [x, z] in layer_sites::<V>(per_row, pitch / 2.0, pitch) {
            if pile.len() == JUMBLED_PILE {
                break 'layers;
            }
            let dx = w.rng().uniform(-shake, shake);
            let dy = w.rng().uniform(-0.4, 0.4) * 0.1 * r;
            let dz = w.rng().uniform(-shake, shake);
            let y = r + 0.1 * r + layer as f64 * rise + dy;
            let spec = CritterSpec::ball(at::<V>([x + dx, z + dz], y))
                .radius(r)
                .restitution(0.5);
            pile.push(w.spawn(spec)?);
        }
    }
    // The striker 1 before five touching balls, all at height 100 (they fall 79 in 4 s).
    let z = width / 2.0;
    let striker = CritterSpec::ball(at::<V>([15.0, z], 100.0))
        .vel(V::unit_x() * STRIKER)
        .radius(0.5);
    let mut cradle = vec![w.spawn(striker)?];
    for i in 0..5 {
        let spec = CritterSpec::ball(at::<V>([17.0 + i as f64, z], 100.0)).radius(0.5);
        cradle.push(w.spawn(spec)?);
    }
    Ok((w, cradle, pile))
}

/// The momentum left outside the last of `cradle` (equal balls, the striker first at `v0` along
/// x), relative to the striker's, in the frame falling with the cradle: its centre of mass
/// moves at `v0 / n` along x plus the common fall, and an exact strike leaves every ball but
/// the last at the fall's velocity and the last at `v0` more. Infinite when a ball is gone.
pub fn cradle_error<V: Vector>(w: &World<V>, cradle: &[CritterId], v0: f64) -> f64 {
    let mut vels = Vec::with_capacity(cradle.len());
    for &id in cradle {
        match w.get(id) {
            Some(c) => vels.push(c.vel),
            None => return f64::INFINITY,
        }
    }
    let n = vels.len() as f64;
    let mean = vels.iter().fold(V::zero(), |s, &v| s + v) * (1.0 / n);
    let fall = mean - V::unit_x() * (v0 / n);
    let (last, rest) = vels.split_last().expect("a cradle has balls");
    let err = (*last - fall - V::unit_x() * v0).length()
        + rest.iter().map(|&v| (v - fall).length()).sum::<f64>();
    let err = err / v0;
    if err.is_nan() {
        f64::INFINITY
    } else {
        err
    }
}

/// Layers of the bullets' pile.
const BULLET_PILE_LAYERS: usize = 6;
/// The bullets' speed: 1.67 per step, over three times what carries a bullet past the middle
/// of a wall (0.15) or through a ball (0.55) in one step.
pub const BULLET_SPEED: f64 = 100.0;

/// A pile resting in a closed box (10 wide and 12 high; in 3D 4 x 12 x 4) that cannot spread
/// (`jammed_pile`, 6 layers, restitution 0.5), and four bullets of radius 0.05 fired into it
/// from above at [`BULLET_SPEED`], slanting towards the walls, for 1 s. The errors: critters
/// that were outside the box at some step's end (tunnelled through a wall, the floor or the
/// lid), the largest displacement of a pile ball (radii), and the pile's deepest overlap at the
/// end.
pub fn bullets_into_pile<V: Vector>(method: Method) -> Result<Vec<f64>, Error> {
    let (mut w, bullets, pile) = bullets_into_pile_world::<V>(method)?;
    let start: Vec<V> = pile
        .iter()
        .map(|&id| w.get(id).map_or(V::zero(), |c| c.pos))
        .collect();
    let inner = bullet_box::<V>();
    let mut escaped = std::collections::BTreeSet::new();
    for _ in 0..BULLET_STEPS {
        w.step()?;
        for &id in bullets.iter().chain(&pile) {
            let inside = w.get(id).is_some_and(|c| inside_box(c.pos, inner));
            if !inside {
                escaped.insert(id);
            }
        }
    }
    let mut moved: f64 = 0.0;
    for (&id, &p0) in pile.iter().zip(&start) {
        let d = w
            .get(id)
            .map_or(f64::INFINITY, |c| (c.pos - p0).length() / c.radius());
        moved = moved.max(if d.is_nan() { f64::INFINITY } else { d });
    }
    Ok(vec![escaped.len() as f64, moved, overlap_among(&w, &pile)])
}

/// The inside of the bullets' box.
fn bullet_box<V: Vector>() -> V {
    let width = if V::DIM == 2 { 10.0 } else { 4.0 };
    let mut inner = V::splat(width);
    inner.set(1, 12.0);
    inner
}

/// True when `p` is strictly inside the box from the origin to `inner` (and finite).
fn inside_box<V: Vector>(p: V, inner: V) -> bool {
    (0..V::DIM).all(|a| p.get(a) > 0.0 && p.get(a) < inner.get(a))
}

/// The world of [`bullets_into_pile`]: it, the bullets' ids and the pile's.
pub fn bullets_into_pile_world<V: Vector>(method: Method) -> Result<Groups<V>, Error> {
    let inner = bullet_box::<V>();
    let width = inner.get(0);
    let mut w = walled_box(method, inner, inner + V::splat(1.0), true)?;
    let pile = jammed_pile(&mut w, width as usize, BULLET_PILE_LAYERS, 0.5)?;
    let mut bullets = Vec::new();
    // Four bullets at height 8, about 3 above the pile, spread across the box, each slanting
    // towards the nearer side wall (and, in 3D, the nearer of the walls across z).
    for k in 0..4 {
        let x = width * (k as f64 + 0.5) / 4.0;
        let z = width * if k % 2 == 0 { 0.3 } else { 0.7 };
        let mut v = at::<V>(
            [
                (x - width / 2.0).signum() * 0.3,
                (z - width / 2.0).signum() * 0.3,
            ],
            -1.0,
        );
        v = v * (BULLET_SPEED / v.length());
        let spec = CritterSpec::ball(at::<V>([x, z], 8.0)).vel(v).radius(0.05);
        bullets.push(w.spawn(spec)?);
    }
    Ok((w, bullets, pile))
}

/// Layers of the pile under the gas.
const GAS_PILE_LAYERS: usize = 4;

/// A resting pile (`jammed_pile`, 4 layers, restitution 0.5) at the bottom of a closed box
/// (10 wide and 20 high; in 3D 4 x 20 x 4) and an elastic gas above it: 30 disks of radius 0.25
/// (in 3D 27 spheres) from 9 up, velocities up to 5 per axis from the world's generator, for
/// 2 s. The errors: the gas's energy drift ([`GasDrift::drift`]) and the pile's deepest overlap
/// at the end.
pub fn gas_above_pile<V: Vector>(method: Method) -> Result<Vec<f64>, Error> {
    let (drift, overlap) = gas_above_pile_reading::<V>(method)?;
    Ok(vec![drift.drift, overlap])
}

/// What [`gas_above_pile`] measures of its gas.
#[derive(Clone, Copy, Debug)]
pub struct GasDrift {
    /// The largest magnitude of the gas's energy change (kinetic plus potential) summed over the
    /// steps clear of the pile, relative to its kinetic energy at the start: 0 for an exact
    /// method, since only the pile exchanges energy with the elastic gas.
    pub drift: f64,
    /// Steps clear of the pile: no gas critter within reach of a pile critter (their radii and
    /// twice what it can move in a step) at the step's start or end.
    pub clear_steps: u64,
}

/// Runs [`gas_above_pile`]: the gas's drift and the pile's deepest overlap at the end.
pub fn gas_above_pile_reading<V: Vector>(method: Method) -> Result<(GasDrift, f64), Error> {
    let (mut w, gas, pile) = gas_above_pile_world::<V>(method)?;
    let drift = gas_drift(&mut w, &gas, &pile, GAS_STEPS)?;
    Ok((drift, overlap_among(&w, &pile)))
}

/// Steps `w` `steps` times and measures the energy drift of `gas` over the steps clear of
/// `pile` ([`GasDrift`]).
pub fn gas_drift<V: Vector>(
    w: &mut World<V>,
    gas: &[CritterId],
    pile: &[CritterId],
    steps: u64,
) -> Result<GasDrift, Error> {
    let scale = gas
        .iter()
        .filter_map(|&id| w.get(id))
        .map(|c| c.kinetic_energy())
        .sum::<f64>();
    let (mut sum, mut drift, mut clear_steps) = (0.0, 0.0f64, 0);
    let (mut e, mut near) = (gas_energy(w, gas), near_the_pile(w, gas, pile));
    for _ in 0..steps {
        w.step()?;
        let (e1, near1) = (gas_energy(w, gas), near_the_pile(w, gas, pile));
        if !near && !near1 {
            sum += e1 - e;
            clear_steps += 1;
            drift = drift.max(if sum.is_finite() {
                sum.abs() / scale
            } else {
                f64::INFINITY
            });
        }
        (e, near) = (e1, near1);
    }
    Ok(GasDrift { drift, clear_steps })
}

/// Kinetic plus potential energy of `ids` (NaN when one is gone).
fn gas_energy<V: Vector>(w: &World<V>, ids: &[CritterId]) -> f64 {
    let g = w.gravity();
    ids.iter()
        .map(|&id| {
            w.get(id)
                .map_or(f64::NAN, |c| c.kinetic_energy() - c.mass() * g.dot(c.pos))
        })
        .sum()
}

/// True when a critter of `gas` is within reach of one of `pile` (their radii and twice what
/// it moves in a step at its speed and gravity's), or one is gone.
fn near_the_pile<V: Vector>(w: &World<V>, gas: &[CritterId], pile: &[CritterId]) -> bool {
    let dt = w.dt();
    let g = w.gravity().length();
    gas.iter().any(|&a| {
        let Some(a) = w.get(a) else { return true };
        let reach = 2.0 * (a.vel.length() + g * dt) * dt + a.radius();
        pile.iter().any(|&b| {
            w.get(b)
                .is_none_or(|b| w.topology().delta(a.pos, b.pos).length() < reach + b.radius())
        })
    })
}

/// The world of [`gas_above_pile`]: it, the gas's ids and the pile's.
pub fn gas_above_pile_world<V: Vector>(method: Method) -> Result<Groups<V>, Error> {
    let width = if V::DIM == 2 { 10.0 } else { 4.0 };
    let mut inner = V::splat(width);
    inner.set(1, 20.0);
    let mut w = walled_box(method, inner, inner + V::splat(1.0), true)?;
    let pile = jammed_pile(&mut w, width as usize, GAS_PILE_LAYERS, 0.5)?;
    let (per_row, layers) = if V::DIM == 2 { (6, 5) } else { (3, 3) };
    let pitch = width / per_row as f64;
    let mut gas = Vec::new();
    for layer in 0..layers {
        let y = 9.0 + 2.0 * layer as f64;
        for site in layer_sites::<V>(per_row, pitch / 2.0, pitch) {
            let mut v = V::zero();
            for axis in 0..V::DIM {
                v.set(axis, w.rng().uniform(-5.0, 5.0));
            }
            let spec = CritterSpec::ball(at::<V>(site, y)).vel(v).radius(0.25);
            gas.push(w.spawn(spec)?);
        }
    }
    Ok((w, gas, pile))
}
