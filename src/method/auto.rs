//! `auto`: the cheapest method that keeps the scene's tolerances, decided each step.
//!
//! The discrete step is exact enough while no critter moves more than a fraction of the smallest
//! radius or wall thickness per step (`docs/stability.md` measures where it starts to tunnel);
//! beyond that the step is swept. Within a swept step only the pairs that meet pay for times of
//! impact, so slow critters cost what they cost in the discrete step.

use crate::method::swept::{motion_scale, SWEEP_FRACTION};
use crate::method::Method;
use crate::vector::Vector;
use crate::world::World;

/// The method for the coming step and why.
pub fn choose<V: Vector>(world: &World<V>) -> (Method, String) {
    let (fastest, smallest) = motion_scale(world);
    if fastest <= SWEEP_FRACTION * smallest {
        (
            Method::Discrete,
            format!(
                "discrete: the fastest critter moves {fastest:.3e} per step, within {SWEEP_FRACTION} of the smallest radius or wall thickness ({smallest:.3e})"
            ),
        )
    } else {
        (
            Method::Swept,
            format!(
                "swept: the fastest critter moves {fastest:.3e} per step, more than {SWEEP_FRACTION} of the smallest radius or wall thickness ({smallest:.3e}); discrete could tunnel"
            ),
        )
    }
}
