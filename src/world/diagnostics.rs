//! How the engine's caches and layouts behaved: figures for `--stats`, benchmarks and tests,
//! never inputs to a step.

use crate::rules::RuleCache;

/// What [`crate::World::diagnostics`] reports.
#[derive(Clone, Copy, Debug)]
pub struct Diagnostics<'a> {
    /// The broad phase's candidate pairs of the last step, as slot indices.
    pub candidate_pairs: &'a [(u32, u32)],
    /// The touching pairs of the last step as (caller, arg) slot indices, in response order.
    pub contact_pairs: &'a [(u32, u32)],
    /// How many times the critters were laid out in memory along the grid (see
    /// [`crate::world::Locality`]).
    pub layouts: u64,
    /// How many times the broad phase rebuilt its Verlet list.
    pub list_rebuilds: u64,
    /// How many times the broad phase mended its Verlet list where a few critters had left it,
    /// instead of rebuilding it.
    pub list_repairs: u64,
    /// How many steps the broad phase found its pairs with the plain grid because its Verlet
    /// lists lived a single step each (a pile jostled every step).
    pub grid_steps: u64,
    /// The class-pair rule table (how often roles were computed from hooks).
    pub rule_cache: &'a RuleCache,
}
