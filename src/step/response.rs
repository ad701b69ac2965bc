//! Pop's response: the caller's `collide` for each touching pair whose critters are both still
//! alive, disk pairs first in id order, then pairs with a wall, tested where the disks are now,
//! so no separation pushes a critter back into a wall.

use super::pairs::Pairs;
use crate::error::Error;
use crate::prefetch::prefetch;
use crate::step::state::State;
use crate::vector::Vector;

/// How many pairs ahead the response asks for the critters of the next pairs to be loaded.
const CONTACTS_AHEAD: usize = 8;

/// Hands each touching pair to its caller's `collide`; returns how many were handled. The wall
/// pairs that touched join `pairs.contacts`, after the disk pairs.
pub(crate) fn run<V: Vector>(state: &mut State<V>, pairs: &mut Pairs<V>) -> Result<usize, Error> {
    let mut collisions = 0;
    let disk_contacts = std::mem::take(&mut pairs.contacts);
    for (k, &(caller, arg)) in disk_contacts.iter().enumerate() {
        if let Some(&(i, j)) = disk_contacts.get(k + CONTACTS_AHEAD) {
            let slots = state.critters.slot_slice();
            prefetch(slots.get(i as usize));
            prefetch(slots.get(j as usize));
        }
        if state.collide_pair(caller, arg)? {
            collisions += 1;
        }
    }
    pairs.contacts = disk_contacts;
    let wall_pairs = std::mem::take(&mut pairs.wall_pairs);
    let mut result = Ok(());
    for &(first, second, ask) in &wall_pairs {
        let (caller, arg) = match state.touching_wall_pair(first, second, ask) {
            Ok(Some(pair)) => pair,
            Ok(None) => continue,
            Err(e) => {
                result = Err(e);
                break;
            }
        };
        pairs.contacts.push((caller, arg));
        match state.collide_pair(caller, arg) {
            Ok(true) => collisions += 1,
            Ok(false) => {}
            Err(e) => {
                result = Err(e);
                break;
            }
        }
    }
    pairs.wall_pairs = wall_pairs;
    result?;
    // Separation may have pushed a critter across the periodic edge.
    state.wrap_positions();
    Ok(collisions)
}
