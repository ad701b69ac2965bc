//! The lifecycle stage: the critters that died in the step are removed (and what rested on
//! them wakes), then the spawns the hooks queued are added.

use crate::error::Error;
use crate::method::state::MethodState;
use crate::vector::Vector;
use crate::world::build::Placed;
use crate::world::state::State;

/// Removes the step's dead and adds its queued spawns.
pub(crate) fn run<V: Vector>(
    state: &mut State<V>,
    methods: &mut MethodState<V>,
) -> Result<(), Error> {
    let mut gone = Vec::new();
    for id in std::mem::take(&mut state.pending.deaths) {
        state.events.deaths.push(id);
        let slot = state.critters.slot_of(id);
        if let (Some(slot), Some(c)) = (slot, state.critters.remove(id)) {
            if c.is_wall() {
                state.walls.retain(|&w| w != id);
            }
            if methods.watches_removals() {
                gone.push((slot as usize, c.pos, c.radius));
            }
        }
    }
    if !gone.is_empty() {
        methods.removed(&state.topo, &gone, state.critters.slot_slice());
    }
    for p in std::mem::take(&mut state.pending.spawns) {
        match state.spawn_placed(p.spec, p.on_overlap) {
            Ok(Placed::Added(id)) => state.events.spawns.push(id),
            Ok(Placed::Skipped(why)) => state.events.log.push(match &p.origin {
                Some(o) => format!("warning: {}: spawn skipped: {why}", o.place()),
                None => format!("warning: spawn skipped: {why}"),
            }),
            Err(e) => {
                return Err(match p.origin {
                    Some(o) => o.locate(e),
                    None => e,
                })
            }
        }
    }
    Ok(())
}
