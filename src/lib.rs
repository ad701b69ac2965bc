//! # critterbox
//!
//! A sandbox for critters that collide: disks in 2D, spheres in 3D, and walls, with the collide
//! roles of the Pop game framework (`collides_with` decides who calls, the caller's `collide`
//! handles the pair) and a physically exact default response.
//!
//! ```
//! use critterbox::{World, WorldConfig, CritterSpec};
//! use glam::DVec2;
//!
//! let mut world = World::new(WorldConfig::new(DVec2::ZERO, DVec2::splat(10.0)))?;
//! let a = world.spawn(CritterSpec::ball(DVec2::new(3.0, 5.0)).vel(DVec2::new(1.0, 0.0)))?;
//! let b = world.spawn(CritterSpec::ball(DVec2::new(5.0, 5.0)))?;
//! world.run(120)?;
//! // Equal masses, head on: the velocities were swapped.
//! assert_eq!(world.get(a).unwrap().vel, DVec2::ZERO);
//! assert_eq!(world.get(b).unwrap().vel, DVec2::new(1.0, 0.0));
//! # Ok::<(), critterbox::Error>(())
//! ```
//!
//! See `docs/ARCHITECTURE.md` for a map of the modules.

#![warn(missing_docs)]
#![warn(unnameable_types)]

// The engine's parts, reached through the re-exports below.
mod border;
mod contact;

mod critter;
mod critter_set;
mod default_response;
mod error;
mod hash;
mod ids;
mod kind;
mod pair_order;
mod parallel;
mod prefetch;
mod rng;
mod rules;
mod step;
mod tolerance;
mod vector;
mod wall;

// The broad phase on its own, for its tests and benches.
#[doc(hidden)]
pub mod broad_phase;
pub mod color;

pub mod method;
pub mod profile;
pub mod recording;
pub mod scenes;
pub mod script;
pub mod sweep;
pub mod testing;
#[cfg(feature = "rerun")]
pub mod viewer;
pub mod world;

pub use border::{Border, Topology};
pub use broad_phase::BroadPhaseMode;
pub use critter::{
    Critter, CritterId, CritterSpec, ParseCritterIdError, PropValue, Props, Shape, CP_BULLET,
    CP_CRITTER, CP_MAXIMUM, CP_MINIMUM, CP_PLAYER, CP_SILVERBULLET, CP_WALL,
};
pub use critter_set::CritterSet;
pub use default_response::Hit;
pub use error::{Error, ScriptError};
pub use glam;
pub use kind::{
    default_collides_with, CollideRule, Kind, KindDefaults, KindHooks, KindId, KindSet, RuleCtx,
};
pub use method::Method;
pub use parallel::PARALLEL_MIN;
pub use rng::Rng;
pub use rules::RuleCache;
pub use step::access::{Access, CollideCtx, HookContact, UpdateCtx};
pub use step::events::{CollisionEvent, DamageInfo, DeathCause, DeathInfo, HookAt, StepEvents};
#[doc(hidden)]
pub use vector::Align64;
pub use vector::Vector;
pub use wall::{ClosestFeature, WallBox, DEFAULT_WALL_THICKNESS};
pub use world::{Diagnostics, Locality, StepStats, World, WorldConfig};
