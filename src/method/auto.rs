//! `auto`: the cheapest method that keeps the scene's tolerances, decided each step and per
//! critter.
//!
//! The discrete step is exact enough while no critter moves more than a fraction of the smallest
//! radius or wall thickness per step (`docs/stability.md` measures where it starts to tunnel).
//! Beyond that the step is swept. In a sparse scene (disks cover less than [`SPARSE`] of the
//! box) it is swept per critter ([`crate::method::swept::step_where_needed`]): a slow critter
//! that can meet nothing along its line this step makes no prediction until a collision changes
//! its flight. The events are the swept step's, so the accuracy is too; a few bullets among many
//! spread-out slow critters cost the bullets' predictions, not everyone's. In a dense scene
//! nearly every critter has something within reach, and the check would only add its cost (and
//! wider cells), so the whole step is swept.

use crate::method::swept::{count_fast, motion_scale, SWEEP_FRACTION};
use crate::method::Method;
use crate::vector::Vector;
use crate::world::World;

/// Below this packing fraction (disk area, or sphere volume, over the box's) a swept step is
/// taken per critter.
pub const SPARSE: f64 = 0.05;

/// The fraction of the box the live disks cover.
pub fn packing<V: Vector>(world: &World<V>) -> f64 {
    let size = world.topo.size();
    let volume: f64 = (0..V::DIM).map(|axis| size.get(axis)).product();
    let unit = if V::DIM == 2 {
        std::f64::consts::PI
    } else {
        4.0 / 3.0 * std::f64::consts::PI
    };
    let disks = world.critters.iter().filter(|c| c.alive && !c.is_wall());
    let covered: f64 = disks.map(|c| unit * c.radius.powi(V::DIM as i32)).sum();
    covered / volume
}

/// What `auto` takes for the coming step.
pub struct Choice {
    /// Discrete or swept.
    pub method: Method,
    /// A swept step taken per critter (a sparse scene).
    pub per_critter: bool,
    /// Why, for `critterbox run`.
    pub why: String,
}

/// The method for the coming step and why.
pub fn choose<V: Vector>(world: &World<V>) -> Choice {
    let (fastest, smallest) = motion_scale(world);
    let limit = SWEEP_FRACTION * smallest;
    if fastest <= limit {
        Choice {
            method: Method::Discrete,
            per_critter: false,
            why: format!(
                "discrete: the fastest critter moves {fastest:.3e} per step, within {SWEEP_FRACTION} of the smallest radius or wall thickness ({smallest:.3e})"
            ),
        }
    } else {
        let (fast, all) = count_fast(world, limit);
        let phi = packing(world);
        let per_critter = phi < SPARSE;
        let slow = if per_critter {
            format!("the disks cover {phi:.3} of the box (under {SPARSE}), so the slow ones are swept only where something is within reach")
        } else {
            format!("the disks cover {phi:.3} of the box ({SPARSE} or more), so everyone is swept")
        };
        Choice {
            method: Method::Swept,
            per_critter,
            why: format!(
                "swept: the fastest critter moves {fastest:.3e} per step, more than {SWEEP_FRACTION} of the smallest radius or wall thickness ({smallest:.3e}), so discrete could tunnel; {fast} of {all} critters move that far; {slow}"
            ),
        }
    }
}
