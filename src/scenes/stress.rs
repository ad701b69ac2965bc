//! The stress scenes of `docs/stability.md`, written once for the tests, `critterbox stability`
//! and the chart's pile ([`super::chart`]). Each scene runs under a [`Method`] and returns a
//! measured error (0 is perfect; what it measures is in [`STRESS`], [`STRESS_3D`] and the doc).
//! The scenes that carry over to spheres are generic over the vector type.

use super::builtin::spawn_cradle;
use crate::border::Border;
use crate::critter::{CritterId, CritterSpec};
use crate::error::Error;
use crate::method::Method;
use crate::vector::Vector;
use crate::wall::WallBox;
use crate::world::{World, WorldConfig};
use glam::{DMat3, DVec2, DVec3};

/// One stress scene.
pub struct Stress {
    /// Name.
    pub name: &'static str,
    /// What the error measures.
    pub error: &'static str,
    /// Runs the scene under a method.
    pub run: fn(Method) -> Result<f64, Error>,
}

/// The methods the stability table and the chart compare.
pub const METHODS: [Method; 6] = [
    Method::Discrete,
    Method::Substep(8),
    Method::Swept,
    Method::Event,
    Method::Solve(8),
    Method::Auto,
];

/// The stress scenes (the bullet is swept over speeds separately: [`bullet`]).
pub const STRESS: &[Stress] = &[
    Stress {
        name: "cradle",
        error: "momentum left outside the last ball, relative",
        run: cradle::<DVec2>,
    },
    Stress {
        name: "resting pile",
        error: "largest relative rise of total energy (kinetic + potential) over 2 s",
        run: resting_pile,
    },
    Stress {
        name: "mass ratios 1e-6..1e6",
        error: "worst relative error in momentum or kinetic energy (inf for NaN)",
        run: mass_ratios::<DVec2>,
    },
    Stress {
        name: "dense pack 0.7",
        error: "deepest overlap at a step's end, in radii",
        run: dense_pack,
    },
    Stress {
        name: "spawned on top",
        error: "deepest overlap after 30 steps, in radii (inf for NaN)",
        run: spawned_on_top::<DVec2>,
    },
    Stress {
        name: "restitution 0.5 column",
        error: "largest relative rise of total energy; deepest overlap in radii (the larger)",
        run: collapse_column,
    },
    Stress {
        name: "glancing hits",
        error: "worst angle error of the outgoing velocities against the exact 90 degrees (rad)",
        run: glancing::<DVec2>,
    },
    Stress {
        name: "deep pile (20 rows)",
        error: "deepest overlap after 2 s, in radii (inf for NaN)",
        run: deep_pile,
    },
    Stress {
        name: "dropped heap (180 balls)",
        error: "balls that end outside the well, of 180 (after 6 s)",
        run: dropped_heap,
    },
];

/// The stress scenes in 3D, with spheres: the 2D ones that carry over unchanged in what they
/// measure (the bullet is swept over speeds separately: [`bullet_3d`]).
pub const STRESS_3D: &[Stress] = &[
    Stress {
        name: "cradle (3D)",
        error: "momentum left outside the last ball, relative",
        run: cradle::<DVec3>,
    },
    Stress {
        name: "mass ratios 1e-6..1e6 (3D)",
        error: "worst relative error in momentum or kinetic energy (inf for NaN)",
        run: mass_ratios::<DVec3>,
    },
    Stress {
        name: "dense pack 0.5 (3D)",
        error: "deepest overlap at a step's end, in radii",
        run: dense_pack_3d,
    },
    Stress {
        name: "spawned on top (3D)",
        error: "deepest overlap after 30 steps, in radii (inf for NaN)",
        run: spawned_on_top::<DVec3>,
    },
    Stress {
        name: "glancing hits (3D)",
        error:
            "worst angle error of the outgoing velocities, or part out of the plane of impact (rad)",
        run: glancing::<DVec3>,
    },
    Stress {
        name: "deep pile (3D, 12 layers)",
        error: "deepest overlap after 2 s, in radii (inf for NaN)",
        run: deep_pile_3d,
    },
];

const DT: f64 = 1.0 / 60.0;

/// The first [`Vector::DIM`] coordinates of `xyz`: a scene's 3D figures, which its 2D twin shares
/// but for z.
fn xyz<V: Vector>(xyz: [f64; 3]) -> V {
    let mut v = V::zero();
    for (axis, x) in xyz.into_iter().take(V::DIM).enumerate() {
        v.set(axis, x);
    }
    v
}

/// A world from the origin to `max` without gravity, at dt = 1/60.
fn world<V: Vector>(max: V, method: Method) -> Result<World<V>, Error> {
    World::new(WorldConfig::new(V::zero(), max).dt(DT).method(method))
}

/// The bullet: a disk of radius 0.05 at `speed` towards a wall 0.02 thick, dt = 1/60. Returns
/// true when it ends up past the wall (tunnelled) at any step's end.
pub fn bullet(speed: f64, method: Method) -> Result<bool, Error> {
    let mut w = world(DVec2::new(100.0, 10.0), method)?;
    let wall_x = 50.0;
    w.add_wall(WallBox::segment(
        DVec2::new(wall_x, 0.0),
        DVec2::new(wall_x, 10.0),
        0.02,
    )?)?;
    let b = w.spawn(
        CritterSpec::ball(DVec2::new(10.0, 5.0))
            .vel(DVec2::new(speed, 0.0))
            .radius(0.05),
    )?;
    ends_past(w, b, wall_x, speed)
}

/// The bullet in 3D: a sphere of radius 0.05 at `speed` along x towards a plate 0.02 thick
/// across the whole box, dt = 1/60. True when it ends up past the plate at any step's end.
pub fn bullet_3d(speed: f64, method: Method) -> Result<bool, Error> {
    let mut w = world(DVec3::new(100.0, 10.0, 10.0), method)?;
    let wall_x = 50.0;
    w.add_wall(WallBox::cuboid(
        DVec3::new(wall_x, 5.0, 5.0),
        DVec3::new(0.02, 10.0, 10.0),
        DMat3::IDENTITY,
    )?)?;
    let b = w.spawn(
        CritterSpec::ball(DVec3::new(10.0, 5.0, 5.0))
            .vel(DVec3::new(speed, 0.0, 0.0))
            .radius(0.05),
    )?;
    ends_past(w, b, wall_x, speed)
}

/// Steps `w` until bullet `b`, flying at `speed` along x from 40 before `wall_x`, is past
/// `wall_x` (true) or has had time to cross it twice (false).
fn ends_past<V: Vector>(
    mut w: World<V>,
    b: CritterId,
    wall_x: f64,
    speed: f64,
) -> Result<bool, Error> {
    let steps = ((40.0 / (speed * DT)).ceil() as u64 + 2).min(100_000);
    for _ in 0..steps {
        w.step()?;
        let x = w.get(b).map_or(f64::NAN, |c| c.pos.get(0));
        if x >= wall_x || x.is_nan() {
            return Ok(true);
        }
    }
    Ok(false)
}

/// Speeds of the bullet sweep: 1 to 1e6, four per decade.
pub fn bullet_speeds() -> Vec<f64> {
    (0..=24).map(|i| 10f64.powf(i as f64 / 4.0)).collect()
}

/// The slowest bullet speed (of [`bullet_speeds`]) that tunnels under `method`, if any.
pub fn first_tunnelling_speed(method: Method) -> Result<Option<f64>, Error> {
    first_tunnelling(bullet, method)
}

/// The slowest bullet speed (of [`bullet_speeds`]) that tunnels through the 3D plate under
/// `method`, if any.
pub fn first_tunnelling_speed_3d(method: Method) -> Result<Option<f64>, Error> {
    first_tunnelling(bullet_3d, method)
}

/// The slowest speed of [`bullet_speeds`] at which `bullet` tunnels under `method`, if any.
fn first_tunnelling(
    bullet: fn(f64, Method) -> Result<bool, Error>,
    method: Method,
) -> Result<Option<f64>, Error> {
    for v in bullet_speeds() {
        if bullet(v, method)? {
            return Ok(Some(v));
        }
    }
    Ok(None)
}

/// Newton's cradle (the built-in scene's five balls and striker, along x) run for 3 s: the
/// momentum left outside the last ball, relative.
fn cradle<V: Vector>(method: Method) -> Result<f64, Error> {
    let mut w = world(xyz::<V>([40.0, 4.0, 4.0]), method)?;
    let ids = spawn_cradle(&mut w, 5)?;
    let v0 = 1.0; // the striker's speed
    w.run(180)?; // 3 s: the striker arrives at 2 s
    let (last, rest) = ids.split_last().expect("a cradle has balls");
    let last = w.get(*last).map_or(f64::NAN, |c| c.vel.get(0));
    let others: f64 = rest
        .iter()
        .map(|&id| w.get(id).map_or(f64::NAN, |c| c.vel.length()))
        .sum();
    Ok(((last - v0).abs() + others) / v0)
}

/// Kinetic plus potential energy of the free critters.
fn total_energy<V: Vector>(w: &World<V>) -> f64 {
    let g = w.gravity();
    w.critters()
        .iter()
        .filter(|c| !c.is_fixed())
        .map(|c| c.kinetic_energy() - c.mass() * g.dot(c.pos))
        .sum()
}

/// The deepest overlap between two balls, in radii of the smaller (infinite for a NaN).
pub(super) fn max_overlap<V: Vector>(w: &World<V>) -> f64 {
    let cs: Vec<_> = w
        .critters()
        .iter()
        .filter(|c| c.is_alive() && !c.is_wall())
        .collect();
    let mut worst: f64 = 0.0;
    for (i, a) in cs.iter().enumerate() {
        for b in &cs[i + 1..] {
            let d = w.topology().delta(a.pos, b.pos).length();
            let depth = (a.radius() + b.radius() - d) / a.radius().min(b.radius());
            if depth.is_nan() {
                return f64::INFINITY;
            }
            worst = worst.max(depth);
        }
    }
    worst
}

/// A [`well`] with walls 0.2 thick and at least 25 high, raised where `rows` rows of balls would
/// overtop them.
fn floor_box(method: Method, dt: f64, rows: usize) -> Result<World<DVec2>, Error> {
    let height = (rows as f64 + 5.0).max(25.0);
    well(method, dt, DVec2::new(11.0, height + 5.0), height, 0.2)
}

/// A world from (-1, -1) to `top` under gravity, with a well 10 wide: a floor and two side
/// walls `height` high, all `t` thick, the floor's top at y = 0.
pub fn well(
    method: Method,
    dt: f64,
    top: DVec2,
    height: f64,
    t: f64,
) -> Result<World<DVec2>, Error> {
    let mut w = World::new(
        WorldConfig::new(DVec2::new(-1.0, -1.0), top)
            .dt(dt)
            .gravity(DVec2::new(0.0, -9.81))
            .method(method),
    )?;
    for (lo, hi) in [
        (DVec2::new(-t, -t), DVec2::new(10.0 + t, 0.0)),
        (DVec2::new(-t, 0.0), DVec2::new(0.0, height)),
        (DVec2::new(10.0, 0.0), DVec2::new(10.0 + t, height)),
    ] {
        w.add_wall(WallBox::aligned(lo, hi)?)?;
    }
    Ok(w)
}

/// `rows` rows of touching balls resting on the floor of a well 10 wide (a hair apart,
/// hexagonal, 9 balls a row), radius 0.5, restitution 0.5: the resting and deep piles.
pub fn pile(method: Method, rows: usize, dt: f64) -> Result<World<DVec2>, Error> {
    let mut w = floor_box(method, dt, rows)?;
    let r = 0.5;
    for row in 0..rows {
        for k in 0..9 {
            let x = 0.5 + r + k as f64 * (2.0 * r + 1e-6) + if row % 2 == 1 { r } else { 0.0 };
            if x > 10.0 - r {
                continue;
            }
            let y = r + 1e-6 + row as f64 * (2.0 * r * 0.866_025_4 + 1e-6);
            w.spawn(
                CritterSpec::ball(DVec2::new(x, y))
                    .radius(r)
                    .restitution(0.5),
            )?;
        }
    }
    Ok(w)
}

/// Three rows of the [`pile`] at rest for 2 s: the largest rise of their energy, relative to
/// the pile's weight times 1.
fn resting_pile(method: Method) -> Result<f64, Error> {
    let mut w = pile(method, 3, DT)?;
    let e0 = total_energy(&w);
    let scale = w
        .critters()
        .iter()
        .map(|c| c.mass())
        .filter(|m| m.is_finite())
        .sum::<f64>()
        * 9.81
        * 1.0;
    let mut worst: f64 = 0.0;
    for _ in 0..120 {
        w.step()?;
        let e = total_energy(&w);
        if !e.is_finite() {
            return Ok(f64::INFINITY);
        }
        worst = worst.max((e - e0) / scale);
    }
    Ok(worst)
}

/// A pile deep enough that the bottom rows carry 20 rows' weight: how far do the balls sink
/// into each other (the 3-row pile hides this)?
fn deep_pile(method: Method) -> Result<f64, Error> {
    let mut w = pile(method, DEEP_PILE_ROWS, DT)?;
    w.run(120)?;
    Ok(max_overlap(&w))
}

/// Rows of the deep pile (about 190 balls).
pub const DEEP_PILE_ROWS: usize = 20;

/// A heap about to be dropped onto a thin floor: 20 rows of 9 balls of radius 0.5 (restitution
/// 0.5), 1.5 apart in height, at rest 60 to 90 above a floor 0.02 thick between walls as thin,
/// 98 high. They land at 34 to 42 units per second, 0.57 to 0.7 per step: more than the radius
/// and half the floor (0.51) that keep a ball's centre on the right side of the floor's
/// mid-plane.
pub fn dropped_heap_world(method: Method) -> Result<World<DVec2>, Error> {
    let mut w = well(method, DT, DVec2::new(12.0, 100.0), 98.0, 0.02)?;
    for row in 0..20 {
        for k in 0..9 {
            let pos = DVec2::new(1.0 + k as f64, 60.0 + 1.5 * row as f64);
            w.spawn(CritterSpec::ball(pos).radius(0.5).restitution(0.5))?;
        }
    }
    Ok(w)
}

/// Balls of the [`dropped_heap_world`] outside its well (below the floor or beyond a wall).
pub fn balls_out_of_the_well(w: &World<DVec2>) -> usize {
    let balls = w.critters().iter().filter(|c| c.is_alive() && !c.is_wall());
    balls
        .filter(|b| !(b.pos.x > 0.0 && b.pos.x < 10.0 && b.pos.y > 0.0))
        .count()
}

/// The dropped heap after six seconds: how many balls ended outside the well.
fn dropped_heap(method: Method) -> Result<f64, Error> {
    let mut w = dropped_heap_world(method)?;
    w.run(360)?;
    Ok(balls_out_of_the_well(&w) as f64)
}

/// Thirteen pairs, the second ball 1e-6 to 1e6 times the first's mass, meeting off-centre (and,
/// in 3D, out of the plane of x and y): the worst relative error in momentum or energy.
fn mass_ratios<V: Vector>(method: Method) -> Result<f64, Error> {
    let mut worst: f64 = 0.0;
    let (va, vb) = (xyz::<V>([3.0, 0.4, -0.3]), xyz::<V>([-2.0, 0.0, 0.1]));
    for k in -6..=6 {
        let ratio = 10f64.powi(k);
        let mut w = world(xyz::<V>([40.0, 10.0, 10.0]), method)?;
        let a = w.spawn(CritterSpec::ball(xyz([5.0, 5.0, 5.0])).vel(va).mass(1.0))?;
        let b = w.spawn(CritterSpec::ball(xyz([12.0, 5.3, 4.8])).vel(vb).mass(ratio))?;
        worst = worst.max(two_body_error(w, a, b, ratio)?);
    }
    Ok(worst)
}

/// Runs `w` for 1.5 s, in which `a` (mass 1) and `b` (mass `ratio`) meet once, and measures the
/// relative error in momentum or kinetic energy: infinite for a NaN, or if they never met.
fn two_body_error<V: Vector>(
    mut w: World<V>,
    a: CritterId,
    b: CritterId,
    ratio: f64,
) -> Result<f64, Error> {
    let velocity = |w: &World<V>, id| w.get(id).map(|c| c.vel);
    let (va, vb) = (velocity(&w, a), velocity(&w, b));
    let pscale = va.map_or(f64::NAN, V::length) + vb.map_or(f64::NAN, V::length) * ratio;
    let (p0, e0) = (w.momentum(), w.kinetic_energy());
    w.run(90)?;
    let (p, e) = (w.momentum(), w.kinetic_energy());
    let hit = velocity(&w, a) != va || velocity(&w, b) != vb;
    let err = ((p - p0).length() / pscale).max((e - e0).abs() / e0);
    Ok(if err.is_finite() && hit {
        err
    } else {
        f64::INFINITY
    })
}

/// 400 disks at packing fraction 0.7 in a periodic box: a hexagonal lattice, shaken.
fn dense_pack(method: Method) -> Result<f64, Error> {
    let (nx, ny) = (20usize, 20usize);
    let r = 0.5;
    let phi: f64 = 0.7;
    let area = (nx * ny) as f64 * std::f64::consts::PI * r * r / phi;
    let aspect = 3f64.sqrt() / 2.0;
    let lx = (area / aspect).sqrt();
    let ly = area / lx;
    let (sx, sy) = (lx / nx as f64, ly / ny as f64);
    let mut sites = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let x = (i as f64 + 0.25 + 0.5 * (j % 2) as f64) * sx;
            let y = (j as f64 + 0.5) * sy;
            sites.push(DVec2::new(x, y));
        }
    }
    shaken_lattice(method, DVec2::new(lx, ly), &sites)
}

/// 256 spheres at packing fraction 0.5 in a periodic box: a face-centred cubic lattice, shaken.
fn dense_pack_3d(method: Method) -> Result<f64, Error> {
    let cells = 4usize;
    let r: f64 = 0.5;
    let phi = 0.5;
    let volume = (4 * cells.pow(3)) as f64 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3) / phi;
    let l = volume.cbrt();
    let a = l / cells as f64;
    let basis = [
        DVec3::ZERO,
        DVec3::new(0.5, 0.5, 0.0),
        DVec3::new(0.5, 0.0, 0.5),
        DVec3::new(0.0, 0.5, 0.5),
    ];
    let mut sites = Vec::with_capacity(basis.len() * cells.pow(3));
    for k in 0..cells {
        for j in 0..cells {
            for i in 0..cells {
                for b in basis {
                    sites.push((DVec3::new(i as f64, j as f64, k as f64) + b + 0.25) * a);
                }
            }
        }
    }
    shaken_lattice(method, DVec3::splat(l), &sites)
}

/// Balls of radius 0.5 on `sites` of a periodic box from the origin to `size`, each with a
/// velocity of up to 3 per axis from the world's generator (seed 3): the deepest overlap at the
/// end of any of 60 steps, in radii.
fn shaken_lattice<V: Vector>(method: Method, size: V, sites: &[V]) -> Result<f64, Error> {
    let mut w = World::new(
        WorldConfig::new(V::zero(), size)
            .border(Border::Wrap)
            .dt(DT)
            .method(method)
            .seed(3),
    )?;
    for &at in sites {
        let mut v = V::zero();
        for axis in 0..V::DIM {
            v.set(axis, w.rng().uniform(-1.0, 1.0));
        }
        w.spawn(CritterSpec::ball(at).vel(v * 3.0).radius(0.5))?;
    }
    let mut worst: f64 = 0.0;
    for _ in 0..60 {
        w.step()?;
        worst = worst.max(max_overlap(&w));
    }
    Ok(worst)
}

/// Eight balls spawned on top of each other, every other one a hair off (along x, and in 3D
/// against z): the deepest overlap after 30 steps, in radii (infinite for a NaN position).
fn spawned_on_top<V: Vector>(method: Method) -> Result<f64, Error> {
    let mut w = world(V::splat(20.0), method)?;
    for i in 0..8 {
        let off = if i % 2 == 0 { 0.0 } else { 1e-9 * i as f64 };
        w.spawn(CritterSpec::ball(xyz([10.0 + off, 10.0, 10.0 - off])).radius(0.5))?;
    }
    w.run(30)?;
    let any_nan = w.critters().iter().any(|c| !c.pos.all_finite());
    Ok(if any_nan {
        f64::INFINITY
    } else {
        max_overlap(&w)
    })
}

/// Six balls of radius 0.25 (restitution 0.5) dropped in a column onto a floor: over 3 s, the
/// larger of the rise of their energy (relative) and their deepest overlap (radii).
fn collapse_column(method: Method) -> Result<f64, Error> {
    let mut w = floor_box(method, DT, 0)?;
    let r = 0.25;
    for k in 0..6 {
        w.spawn(
            CritterSpec::ball(DVec2::new(5.0, 1.0 + k as f64 * 0.6))
                .radius(r)
                .restitution(0.5),
        )?;
    }
    let e0 = total_energy(&w);
    let scale = e0.abs().max(1.0);
    let mut worst: f64 = 0.0;
    for _ in 0..180 {
        w.step()?;
        let e = total_energy(&w);
        if !e.is_finite() {
            return Ok(f64::INFINITY);
        }
        worst = worst.max((e - e0) / scale).max(max_overlap(&w));
    }
    Ok(worst)
}

/// A ball at 20 along x strikes one at rest, the impact parameter 0.1 to 0.9 diameters (along y,
/// and in 3D along the diagonal of y and z): the worst error of the outgoing directions against
/// the exact ones, in radians.
fn glancing<V: Vector>(method: Method) -> Result<f64, Error> {
    let mut worst: f64 = 0.0;
    let offset = xyz::<V>([0.0, 1.0, 1.0]);
    let offset = offset * (1.0 / offset.length());
    for k in 1..10 {
        let b = k as f64 * 0.1; // impact parameter in diameters
        let mut w = world(V::splat(60.0), method)?;
        let a = w.spawn(
            CritterSpec::ball(xyz([10.0, 30.0, 30.0]))
                .vel(xyz([20.0, 0.0, 0.0]))
                .radius(0.5),
        )?;
        let t =
            w.spawn(CritterSpec::ball(xyz::<V>([20.0, 30.0, 30.0]) + offset * b).radius(0.5))?;
        w.run(40)?;
        let (va, vt) = (w.get(a).map(|c| c.vel), w.get(t).map(|c| c.vel));
        let (Some(va), Some(vt)) = (va, vt) else {
            return Ok(f64::INFINITY);
        };
        // Exact: the target leaves along the line of centres at contact, at angle asin(b) from
        // the x axis in the plane of x and the offset; the striker at right angles to it.
        let right = (va.dot(vt) / (va.length() * vt.length())).acos();
        let err = off_course(vt, b.asin()).max((right - std::f64::consts::FRAC_PI_2).abs());
        if !err.is_finite() {
            return Ok(f64::INFINITY);
        }
        worst = worst.max(err);
    }
    Ok(worst)
}

/// How far the target of [`glancing`] leaves off its exact course, `want` radians from x
/// towards the offset: the angle error, and in 3D the part of the velocity out of the plane of
/// x and the offset (relative).
fn off_course<V: Vector>(vt: V, want: f64) -> f64 {
    let [x, y, z] = vt.to_array3();
    if V::DIM == 2 {
        return (y.atan2(x) - want).abs();
    }
    let got = y.hypot(z).atan2(x);
    (got - want).abs().max(((y - z) / vt.length()).abs())
}

/// Layers of the 3D deep pile (150 spheres).
pub const DEEP_PILE_LAYERS_3D: usize = 12;

/// The deep pile in 3D: [`DEEP_PILE_LAYERS_3D`] layers of spheres of radius 0.5 (restitution 0.5)
/// in a walled 4 x 4 well under gravity, each layer in the hollows of the one below (4 x 4 and
/// 3 x 3 alternately, a hair apart: body-centred stacking, centres 0.707 apart in height), so
/// the bottom spheres carry eleven layers' weight. The deepest overlap after two seconds.
fn deep_pile_3d(method: Method) -> Result<f64, Error> {
    let mut w = World::new(
        WorldConfig::new(DVec3::splat(-1.0), DVec3::new(5.0, 20.0, 5.0))
            .dt(DT)
            .gravity(DVec3::new(0.0, -9.81, 0.0))
            .method(method),
    )?;
    let (t, h) = (0.2, 15.0);
    for (lo, hi) in [
        (DVec3::new(-t, -t, -t), DVec3::new(4.0 + t, 0.0, 4.0 + t)),
        (DVec3::new(-t, 0.0, -t), DVec3::new(0.0, h, 4.0 + t)),
        (DVec3::new(4.0, 0.0, -t), DVec3::new(4.0 + t, h, 4.0 + t)),
        (DVec3::new(0.0, 0.0, -t), DVec3::new(4.0, h, 0.0)),
        (DVec3::new(0.0, 0.0, 4.0), DVec3::new(4.0, h, 4.0 + t)),
    ] {
        w.add_wall(WallBox::aligned(lo, hi)?)?;
    }
    let gap = 1e-6;
    let rise = std::f64::consts::FRAC_1_SQRT_2 + gap;
    for layer in 0..DEEP_PILE_LAYERS_3D {
        let (count, start) = if layer % 2 == 0 { (4, 0.5) } else { (3, 1.0) };
        let y = 0.5 + gap + layer as f64 * rise;
        for i in 0..count {
            for k in 0..count {
                let (x, z) = (start + i as f64, start + k as f64);
                w.spawn(
                    CritterSpec::ball(DVec3::new(x, y, z))
                        .radius(0.5)
                        .restitution(0.5),
                )?;
            }
        }
    }
    w.run(120)?;
    Ok(max_overlap(&w))
}
