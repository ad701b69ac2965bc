//! `swept`: continuous collision detection within the step.
//!
//! Gravity is applied as in the discrete step (velocity first, then straight-line motion over dt),
//! but the motion is swept: the times of impact of disk pairs (closed-form quadratic,
//! [`crate::method::toi::toi_ball_ball`]) and of disks against walls (the wall box expanded by
//! the radius: faces, edges, corners, [`crate::method::toi::toi_wall_ball`]) are processed in time
//! order by the shared event engine ([`crate::method::flight`]): advance the pair to its time of
//! impact, hand it to the caller's `collide` hook, re-predict for the pair's critters. Then one
//! discrete pass resolves what still touches (resting contacts, spawned overlaps).
//!
//! A step in which no critter moves more than [`SWEEP_FRACTION`] of the smallest radius (or of
//! the thinnest wall) is exactly the discrete step: sweeping is paid for only when needed.

use crate::error::Error;
use crate::vector::Vector;
use crate::world::{StepStats, World};

/// A step is swept when some critter moves more than this fraction of the smallest disk radius
/// or wall thickness.
pub const SWEEP_FRACTION: f64 = 0.25;

/// The largest displacement of a critter in the coming step, and the smallest length it must be
/// compared with (smallest disk radius, thinnest wall).
pub fn motion_scale<V: Vector>(world: &World<V>) -> (f64, f64) {
    let (g, dt) = (world.gravity, world.dt);
    let mut fastest: f64 = 0.0;
    let mut smallest = f64::INFINITY;
    for c in world.critters.iter().filter(|c| c.alive) {
        match c.wall() {
            Some(w) => {
                for axis in 0..V::DIM {
                    smallest = smallest.min(2.0 * w.half.get(axis));
                }
            }
            None => {
                smallest = smallest.min(c.radius);
                let v = if c.fixed { c.vel } else { c.vel + g * dt };
                fastest = fastest.max(v.length() * dt);
            }
        }
    }
    (fastest, smallest)
}

/// One swept step (after the update hooks, before the lifecycle).
pub fn step<V: Vector>(world: &mut World<V>, stats: &mut StepStats) -> Result<(), Error> {
    let (fastest, smallest) = motion_scale(world);
    if fastest <= SWEEP_FRACTION * smallest {
        return world.discrete_substeps(1, stats);
    }
    let clock = std::time::Instant::now();
    let dv = world.gravity * world.dt;
    for c in world.critters.iter_mut_moving() {
        if c.alive && !c.fixed && !c.is_wall() {
            c.vel += dv;
        }
    }
    let complete = crate::method::flight::run(world, V::zero(), world.dt, stats)?;
    if !complete {
        stats.budget_exceeded += 1;
    }
    stats.response += clock.elapsed();
    world.discrete_collide(stats)
}
