//! Critters a method sets aside for part of a step: the islands of one group while another
//! method steps the rest (`mixed`), and `auto`'s bullets while the step is taken without them
//! (`bullets`). A critter set aside is alive but out of play ([`Critter::in_play`]): the stages
//! skip it as they skip the dead, and the hooks' queries do not see it, until it is brought
//! back in the same step.
//!
//! [`Critter::in_play`]: crate::critter::Critter

use crate::step::state::State;
use crate::vector::Vector;

/// Sets aside the critter of each of `slots` that is in play, noting its slot in `aside`.
pub(crate) fn set_aside<V: Vector>(
    state: &mut State<V>,
    slots: impl IntoIterator<Item = u32>,
    aside: &mut Vec<u32>,
) {
    aside.clear();
    let stored = state.critters.slots_mut_moving();
    for i in slots {
        if let Some(Some(c)) = stored.get_mut(i as usize) {
            if c.in_play() {
                c.aside = true;
                aside.push(i);
            }
        }
    }
}

/// Brings back every critter [`set_aside`] noted in `aside`, and empties it.
pub(crate) fn bring_back<V: Vector>(state: &mut State<V>, aside: &mut Vec<u32>) {
    let stored = state.critters.slots_mut_moving();
    for i in aside.drain(..) {
        if let Some(Some(c)) = stored.get_mut(i as usize) {
            c.aside = false;
        }
    }
}
