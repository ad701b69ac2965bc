//! A Box2D v3 world built from a scene's bodies, through the `boxdd` bindings.
//!
//! Box2D is single precision: positions, velocities and the step are f32 (boxdd's
//! `double-precision` feature would widen only absolute positions; it is off here). Disks are
//! circles on dynamic bodies with rotation locked (critterbox's disks do not turn), walls are
//! boxes on static bodies, every shape has density 1, friction 0 and the scene's restitution
//! (Box2D mixes restitution by the larger of a pair, friction by the geometric mean).
//!
//! Threads: Box2D's world definition takes a worker count; with more than one worker and no task
//! callbacks of the caller's, the pinned Box2D (3.2.0 development snapshot) starts its own
//! scheduler with `workers - 1` background threads and the calling thread as worker 0. boxdd
//! exposes that count as `WorkerCount`, and no task callbacks.

use crate::bodies::{Bodies, Disk};
use boxdd::{
    BodyBuilder, BodyId, BodyType, Foundation, MotionLocks, Position, ShapeDef, SurfaceMaterial,
    Vec2, WorkerCount, WorldBuilder,
};
use std::error::Error;

/// How a Box2D world is set up beyond its bodies.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// Box2D's worker count (threads, the caller's included).
    pub workers: u32,
    /// Substeps per step (Box2D's soft step; 4 is its recommended default).
    pub substeps: i32,
    /// Speed below which Box2D drops restitution (its default is 1 m/s).
    pub restitution_threshold: f32,
    /// Whether bodies at rest may sleep (Box2D's default is yes).
    pub sleep: bool,
}

/// A Box2D world and the ids of its disks, in the scene's order.
pub struct Box2d {
    world: boxdd::World,
    disks: Vec<(BodyId, f64, f64)>,
    dt: f32,
    substeps: i32,
}

impl Box2d {
    /// Box2D's world for `scene`'s disks and walls.
    pub fn from(scene: &Bodies, s: &Settings) -> Result<Box2d, Box<dyn Error>> {
        let foundation = Foundation::initialize_default()?;
        let def = WorldBuilder::from(foundation.world_def())
            .gravity(Vec2::new(scene.gravity.x as f32, scene.gravity.y as f32))
            .restitution_threshold(s.restitution_threshold)
            .enable_sleep(s.sleep)
            .worker_count(WorkerCount::new(s.workers)?)
            .build()?;
        let mut world = foundation.create_world(def)?;
        let shape = |restitution: f64| -> Result<ShapeDef, boxdd::Error> {
            let material = SurfaceMaterial::new()
                .with_friction(0.0)?
                .with_restitution(restitution as f32)?;
            ShapeDef::builder().density(1.0).material(material).build()
        };
        // The walls bounce as the disks do (restitution is mixed by the larger of a pair).
        let wall_restitution = scene
            .disks
            .iter()
            .map(|d| d.restitution)
            .fold(0.0, f64::max);
        let wall_shape = shape(wall_restitution)?;
        for w in &scene.walls {
            let body = world.create_body(
                BodyBuilder::from(foundation.body_def())
                    .body_type(BodyType::Static)
                    .position(Position::new(w.center.x as f32, w.center.y as f32))
                    .build()?,
            )?;
            world
                .body(body)?
                .create_box(&wall_shape, w.half.x as f32, w.half.y as f32)?;
        }
        let mut disks = Vec::with_capacity(scene.disks.len());
        for d in &scene.disks {
            let body = world.create_body(
                BodyBuilder::from(foundation.body_def())
                    .body_type(BodyType::Dynamic)
                    .position(Position::new(d.pos.x as f32, d.pos.y as f32))
                    .linear_velocity(Vec2::new(d.vel.x as f32, d.vel.y as f32))
                    .motion_locks(MotionLocks::new(false, false, true))
                    .build()?,
            )?;
            world
                .body(body)?
                .create_centered_circle(&shape(d.restitution)?, d.radius as f32)?;
            disks.push((body, d.radius, d.restitution));
        }
        Ok(Box2d {
            world,
            disks,
            dt: scene.dt as f32,
            substeps: s.substeps,
        })
    }

    /// One step of the scene's dt.
    pub fn step(&mut self) {
        self.world
            .step(self.dt, self.substeps)
            .and_then(|done| done.into_result().map(drop))
            .expect("Box2D steps");
    }

    /// The disks as they are now (velocity 0 for a sleeping body, as Box2D reports it).
    pub fn disks(&mut self) -> Result<Vec<Disk>, Box<dyn Error>> {
        let mut out = Vec::with_capacity(self.disks.len());
        for &(id, radius, restitution) in &self.disks {
            let body = self.world.body(id)?;
            let (p, v) = (body.position()?, body.linear_velocity()?);
            out.push(Disk {
                pos: critterbox::glam::DVec2::new(p.x.into(), p.y.into()),
                vel: critterbox::glam::DVec2::new(v.x.into(), v.y.into()),
                radius,
                restitution,
            });
        }
        Ok(out)
    }

    /// Disks asleep (Box2D counts the awake bodies; the walls are static, never counted).
    pub fn asleep(&self) -> Result<usize, Box<dyn Error>> {
        let awake = usize::try_from(self.world.awake_body_count()?)?;
        Ok(self.disks.len().saturating_sub(awake))
    }
}

/// What Box2D was built as: its version, precision and SIMD, for the tables' heading.
pub fn describe() -> String {
    // boxdd reads the version only once its foundation is up.
    let version = Foundation::initialize_default()
        .and_then(|_| boxdd::version())
        .map(|v| format!("{}.{}.{}", v.major, v.minor, v.revision))
        .unwrap_or_else(|_| "?".into());
    let simd = if cfg!(feature = "avx2") {
        "AVX2 (8 lanes)"
    } else {
        "SSE2 (4 lanes)"
    };
    // The C flags the native library was built with: `.cargo/config.toml` sets them (NDEBUG,
    // as a CMake release build of Box2D has), and rustc sees the same environment.
    let asserts = match option_env!("CFLAGS") {
        Some(flags) if flags.contains("-DNDEBUG") => "asserts off (NDEBUG)",
        _ => "asserts on (no NDEBUG)",
    };
    format!("Box2D {version} (boxdd 0.6), f32, {simd}, {asserts}")
}
