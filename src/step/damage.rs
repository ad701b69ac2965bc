//! The damage stage: every damage dealt in the step runs the damaged critter's `on_damage`
//! hook, once per damage, in the order of the damaged critters' ids (a critter's own damages in
//! the order they were dealt), after the touch events and before the deaths.
//!
//! Running the hooks here, and not inside the `damage` call, lets the critter hit as the `arg`
//! of a pair (whose `collide` does not run) react in a fixed order whatever the method, with
//! the step's collisions done: what it does then (a spawn, a `die`, more damage) takes effect
//! as from any other hook. Damage dealt by an `on_damage` runs its own hook in a further round;
//! damage dealt by the dying (in `touch_end` or `on_death`) runs in the lifecycle, before they
//! are removed.

use super::state::State;
use crate::error::Error;
use crate::vector::Vector;

/// Runs the `on_damage` hooks of the damage dealt so far, until no more is dealt.
pub(crate) fn run<V: Vector>(state: &mut State<V>) -> Result<(), Error> {
    while !state.pending.damages.is_empty() {
        let mut round = std::mem::take(&mut state.pending.damages);
        // Stable: a critter's own damages keep the order they were dealt in.
        round.sort_by_key(|d| d.id);
        for d in round {
            state.run_on_damage(d)?;
        }
    }
    Ok(())
}
