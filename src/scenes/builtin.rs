//! The built-in scenes of `critterbox run NAME`, and the standard gas the benchmarks measure.

use super::{AnyWorld, Scene};
use crate::border::Border;
use crate::critter::{CritterId, CritterSpec};
use crate::error::Error;
use crate::kind::KindDefaults;
use crate::vector::Vector;
use crate::wall::{WallBox, DEFAULT_WALL_THICKNESS};
use crate::world::{World, WorldConfig};
use crate::BroadPhaseMode;
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// Builds the built-in scene `name` as a [`Scene`].
pub fn builtin(name: &str, params: &SceneParams) -> Result<Scene, Error> {
    let info = find(name)?;
    Ok(Scene::new(name, (info.build)(params)?, info.default_steps))
}

/// What a scene can be asked to vary.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneParams {
    /// Number of critters, where the scene has a natural count.
    pub n: Option<usize>,
    /// Seed of the world's generator.
    pub seed: u64,
    /// Time step, if not the scene's own.
    pub dt: Option<f64>,
}

impl Default for SceneParams {
    fn default() -> Self {
        SceneParams {
            n: None,
            seed: 1,
            dt: None,
        }
    }
}

/// A built-in scene.
pub struct SceneInfo {
    /// Name for `critterbox run NAME`.
    pub name: &'static str,
    /// One line on what it shows.
    pub about: &'static str,
    /// Steps run when none are asked for.
    pub default_steps: u64,
    build: fn(&SceneParams) -> Result<AnyWorld, Error>,
}

/// The scene run when none is named.
pub const DEFAULT_SCENE: &str = "gas";

/// All built-in scenes.
pub const SCENES: &[SceneInfo] = &[
    SceneInfo {
        name: "gas",
        about: "2D gas: 1000 disks (-n to change) of radius 0.5 at packing fraction 0.2 in a walled box, elastic",
        default_steps: 600,
        build: |p| gas_scene::<DVec2>(p, Border::Bounce),
    },
    SceneInfo {
        name: "gas-wrap",
        about: "2D gas in a periodic box (wrap border, no walls)",
        default_steps: 600,
        build: |p| gas_scene::<DVec2>(p, Border::Wrap),
    },
    SceneInfo {
        name: "gas3d",
        about: "3D gas: 1000 spheres of radius 0.5 at packing fraction 0.2 in a walled box, elastic",
        default_steps: 600,
        build: |p| gas_scene::<DVec3>(p, Border::Bounce),
    },
    SceneInfo {
        name: "billiards",
        about: "a 15-ball rack broken by a cue ball on a walled table (restitution 0.95)",
        default_steps: 900,
        build: billiards,
    },
    SceneInfo {
        name: "cradle",
        about: "Newton's cradle: five touching balls struck by a sixth; only the last should leave",
        default_steps: 300,
        build: cradle,
    },
    SceneInfo {
        name: "pegs",
        about: "balls falling under gravity through rows of fixed pegs onto a sloped floor",
        default_steps: 900,
        build: pegs,
    },
];

/// Builds the built-in scene `name`.
pub fn build(name: &str, params: &SceneParams) -> Result<AnyWorld, Error> {
    let info = find(name)?;
    (info.build)(params)
}

/// The built-in scene `name`.
pub fn find(name: &str) -> Result<&'static SceneInfo, Error> {
    SCENES
        .iter()
        .find(|s| s.name == name)
        .ok_or_else(|| Error::UnknownScene {
            name: name.to_string(),
            known: SCENES.iter().map(|s| s.name).collect::<Vec<_>>().join(", "),
        })
}

/// The standard gas: the scene the benchmarks measure (and the rapier comparison uses).
#[derive(Clone, Debug, PartialEq)]
pub struct GasParams {
    /// Number of disks (spheres).
    pub n: usize,
    /// Radius.
    pub radius: f64,
    /// Fraction of the box's area (volume) the critters cover.
    pub packing: f64,
    /// Coefficient of restitution.
    pub restitution: f64,
    /// Time step.
    pub dt: f64,
    /// Seed for the velocities.
    pub seed: u64,
    /// Bounce = walled box (walls just outside the box); Wrap = periodic box, no walls.
    pub border: Border,
    /// Broad-phase algorithm.
    pub broad_phase: BroadPhaseMode,
}

impl Default for GasParams {
    fn default() -> Self {
        GasParams {
            n: 1000,
            radius: 0.5,
            packing: 0.2,
            restitution: 1.0,
            dt: 1.0 / 60.0,
            seed: 1,
            border: Border::Bounce,
            broad_phase: BroadPhaseMode::Auto,
        }
    }
}

/// The standard gas: `n` critters on a grid filling a square (cubic) box at the given packing
/// fraction, velocities uniform in [-1, 1] per component from the seeded generator.
pub fn gas<V: Vector>(p: &GasParams) -> Result<World<V>, Error> {
    gas_with(p, "ball", |_| Ok(()))
}

/// The standard gas with critters of kind `kind`, which `prepare` registers in the empty world.
pub fn gas_with<V: Vector>(
    p: &GasParams,
    kind: &str,
    prepare: impl FnOnce(&mut World<V>) -> Result<(), Error>,
) -> Result<World<V>, Error> {
    let dim = V::DIM as i32;
    let ball = if dim == 2 {
        PI * p.radius * p.radius
    } else {
        4.0 / 3.0 * PI * p.radius.powi(3)
    };
    if p.n == 0 {
        return Err(Error::InvalidWorld {
            field: "n",
            value: "0".into(),
            reason: "a gas needs at least one critter".into(),
        });
    }
    if !(p.packing > 0.0 && p.packing < 0.5) {
        return Err(Error::InvalidWorld {
            field: "packing",
            value: p.packing.to_string(),
            reason: "the grid start needs a packing fraction between 0 and 0.5".into(),
        });
    }
    let side = (p.n as f64 * ball / p.packing).powf(1.0 / dim as f64);
    let per_row = (p.n as f64).powf(1.0 / dim as f64).ceil() as usize;
    let spacing = side / per_row as f64;
    let t = DEFAULT_WALL_THICKNESS;
    let walled = p.border != Border::Wrap;
    let margin = if walled { t + 0.5 } else { 0.0 };
    let config = WorldConfig::new(V::splat(-margin), V::splat(side + margin))
        .border(p.border)
        .dt(p.dt)
        .seed(p.seed)
        .broad_phase(p.broad_phase);
    let mut world = World::new(config)?;
    prepare(&mut world)?;
    if walled {
        for axis in 0..V::DIM {
            for side_at in [-t, side] {
                let mut lo = V::splat(-t);
                let mut hi = V::splat(side + t);
                lo.set(axis, side_at);
                hi.set(axis, side_at + t);
                world.add_wall(WallBox::aligned(lo, hi)?)?;
            }
        }
    }
    world.reserve(p.n)?;
    for i in 0..p.n {
        let mut pos = V::zero();
        let mut rest = i;
        for axis in 0..V::DIM {
            pos.set(axis, (rest % per_row) as f64 * spacing + 0.5 * spacing);
            rest /= per_row;
        }
        let mut vel = V::zero();
        for axis in 0..V::DIM {
            vel.set(axis, world.rng().uniform(-1.0, 1.0));
        }
        world.spawn(
            CritterSpec::new(kind, pos)
                .vel(vel)
                .radius(p.radius)
                .restitution(p.restitution),
        )?;
    }
    Ok(world)
}

fn gas_scene<V: Vector>(p: &SceneParams, border: Border) -> Result<AnyWorld, Error>
where
    World<V>: Into<AnyWorld>,
{
    let params = GasParams {
        n: p.n.unwrap_or(1000),
        seed: p.seed,
        dt: p.dt.unwrap_or(1.0 / 60.0),
        border,
        ..GasParams::default()
    };
    Ok(gas::<V>(&params)?.into())
}

fn walled_box(world: &mut World<DVec2>, w: f64, h: f64) -> Result<(), Error> {
    let t = DEFAULT_WALL_THICKNESS;
    world.add_wall(WallBox::aligned(
        DVec2::new(-t, -t),
        DVec2::new(w + t, 0.0),
    )?)?;
    world.add_wall(WallBox::aligned(
        DVec2::new(-t, h),
        DVec2::new(w + t, h + t),
    )?)?;
    world.add_wall(WallBox::aligned(DVec2::new(-t, 0.0), DVec2::new(0.0, h))?)?;
    world.add_wall(WallBox::aligned(DVec2::new(w, 0.0), DVec2::new(w + t, h))?)?;
    Ok(())
}

fn billiards(p: &SceneParams) -> Result<AnyWorld, Error> {
    let (w, h, r) = (20.0, 10.0, 0.3);
    let config = WorldConfig::new(DVec2::splat(-1.0), DVec2::new(w + 1.0, h + 1.0))
        .dt(p.dt.unwrap_or(1.0 / 120.0))
        .seed(p.seed);
    let mut world = World::new(config)?;
    walled_box(&mut world, w, h)?;
    let e = 0.95;
    // Rack: rows of 1..5 balls, touching neighbours along the rows' diagonals (tiny gap).
    let gap = 2.0 * r + 1e-3;
    let apex = DVec2::new(14.0, h / 2.0);
    for row in 0..5 {
        for k in 0..=row {
            let pos = apex
                + DVec2::new(
                    row as f64 * gap * (3f64.sqrt() / 2.0),
                    (k as f64 - row as f64 / 2.0) * gap,
                );
            world.spawn(CritterSpec::ball(pos).radius(r).restitution(e))?;
        }
    }
    // The cue ball, a shade off the axis so the break is not symmetric.
    let aim = world.rng().uniform(-0.02, 0.02);
    world.spawn(
        CritterSpec::ball(DVec2::new(4.0, h / 2.0))
            .vel(DVec2::new(15.0, aim))
            .radius(r)
            .restitution(e),
    )?;
    Ok(world.into())
}

fn cradle(p: &SceneParams) -> Result<AnyWorld, Error> {
    let n = p.n.unwrap_or(5);
    let config = WorldConfig::new(
        DVec2::ZERO,
        DVec2::new(10.0 + 2.0 * CRADLE_RADIUS * n as f64 + 10.0, 4.0),
    )
    .dt(p.dt.unwrap_or(1.0 / 60.0))
    .seed(p.seed);
    let mut world = World::new(config)?;
    spawn_cradle(&mut world, n)?;
    Ok(world.into())
}

/// Radius of the cradle's balls.
const CRADLE_RADIUS: f64 = 0.5;

/// Newton's cradle along x, at height 2 (and depth 2 in 3D): a striker at x = 2 moving at 1
/// towards `n` touching balls from x = 5 on, all of radius [`CRADLE_RADIUS`]. The ids, striker
/// first.
pub(super) fn spawn_cradle<V: Vector>(
    world: &mut World<V>,
    n: usize,
) -> Result<Vec<CritterId>, Error> {
    let r = CRADLE_RADIUS;
    let at = |x: f64| {
        let mut p = V::splat(2.0);
        p.set(0, x);
        p
    };
    let striker = CritterSpec::ball(at(2.0)).vel(V::unit_x()).radius(r);
    let mut ids = vec![world.spawn(striker)?];
    for i in 0..n {
        ids.push(world.spawn(CritterSpec::ball(at(5.0 + 2.0 * r * i as f64)).radius(r))?);
    }
    Ok(ids)
}

fn pegs(p: &SceneParams) -> Result<AnyWorld, Error> {
    let (w, h) = (20.0, 30.0);
    let config = WorldConfig::new(DVec2::splat(-1.0), DVec2::new(w + 1.0, h + 1.0))
        .gravity(DVec2::new(0.0, -9.81))
        .dt(p.dt.unwrap_or(1.0 / 240.0))
        .seed(p.seed);
    let mut world = World::new(config)?;
    walled_box(&mut world, w, h)?;
    let peg = KindDefaults {
        radius: 0.25,
        fixed: true,
        ..KindDefaults::default()
    };
    world.register_kind("peg", None, peg, std::rc::Rc::new(()))?;
    for row in 0..8 {
        let y = 8.0 + 2.0 * row as f64;
        let shift = if row % 2 == 0 { 0.0 } else { 1.0 };
        let mut x = 1.0 + shift;
        while x < w - 0.5 {
            world.spawn(CritterSpec::new("peg", DVec2::new(x, y)))?;
            x += 2.0;
        }
    }
    // A sloped floor: a rotated wall, touched at faces, edges and corners.
    world.add_wall(WallBox::segment(
        DVec2::new(2.0, 4.0),
        DVec2::new(18.0, 2.0),
        0.3,
    )?)?;
    let n = p.n.unwrap_or(200);
    for i in 0..n {
        let x = 1.0 + (i % 30) as f64 * 0.6 + world.rng().uniform(-0.05, 0.05);
        let y = 26.0 + (i / 30) as f64 * 0.6;
        if y > h - 0.5 {
            break;
        }
        world.spawn(
            CritterSpec::ball(DVec2::new(x, y))
                .radius(0.2)
                .restitution(0.8),
        )?;
    }
    Ok(world.into())
}
