//! The lifecycle stage: the critters that died in the step end their touching spells, run their
//! `on_death` hooks, the damage those hooks dealt runs its `on_damage`, and they are removed
//! (and what rested on them wakes), then the spawns the hooks queued are added. A death asked
//! for by those hooks is handled in the same way, in a further round, so every dying critter is
//! seen once.

use super::events::DeathCause;
use super::spawn::Placed;
use super::state::State;
use crate::border::Topology;
use crate::critter::{Critter, CritterId};
use crate::error::Error;
use crate::vector::Vector;

/// The critters a lifecycle removed, as (slot, position, radius), for what watches removals (the
/// sleepers that rested on them wake).
pub(crate) type Gone<V> = [(usize, V, f64)];

/// Removes the step's dead and adds its queued spawns. With `watch`, the removed are told to
/// `removed` (with the box and the slots after the removals), before the spawns are added.
pub(crate) fn run<V: Vector>(
    state: &mut State<V>,
    watch: bool,
    removed: impl FnOnce(&Topology<V>, &Gone<V>, &[Option<Critter<V>>]),
) -> Result<(), Error> {
    let mut gone = Vec::new();
    loop {
        let deaths = std::mem::take(&mut state.pending.deaths);
        let causes = std::mem::take(&mut state.pending.death_causes);
        if deaths.is_empty() {
            break;
        }
        before_removal(state, &deaths)?;
        // What the dying did in their last hooks, while they are still there to be its source.
        super::damage::run(state)?;
        remove(state, watch, deaths, causes, &mut gone);
    }
    if !gone.is_empty() {
        removed(&state.topo, &gone, state.critters.slot_slice());
    }
    for p in std::mem::take(&mut state.pending.spawns) {
        match state.spawn_placed(p.spec, p.on_overlap) {
            Ok(Placed::Added(id)) => state.events.spawned(id, p.by),
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
    // Damage the spawns' `init` dealt: heard of in this step (its deaths wait for the next,
    // as a death in `init` does).
    super::damage::run(state)
}

/// What the dying do before they go, when some kind asks for it: end their touching spells,
/// then run their `on_death`, in the order they died.
pub(crate) fn before_removal<V: Vector>(
    state: &mut State<V>,
    dying: &[CritterId],
) -> Result<(), Error> {
    if state.kinds.tracks_touch() {
        state.end_spells_of(dying)?;
    }
    if state.kinds.has_on_death() {
        for &id in dying {
            state.run_on_death(id)?;
        }
    }
    Ok(())
}

/// Removes the critters `deaths`, each dead for its entry of `causes`; with `watch`, each is
/// noted in `gone`.
fn remove<V: Vector>(
    state: &mut State<V>,
    watch: bool,
    deaths: Vec<CritterId>,
    causes: Vec<DeathCause>,
    gone: &mut Vec<(usize, V, f64)>,
) {
    let mut causes = causes.into_iter();
    for id in deaths {
        let cause = causes.next().unwrap_or(DeathCause::Die(None));
        let Some(kind) = state.critters.get(id).map(|c| c.kind()) else {
            continue; // removed between steps already, and reported then
        };
        state.events.died(id, kind, cause);
        let slot = state.critters.slot_of(id);
        if let (Some(slot), Some(c)) = (slot, state.critters.remove(id)) {
            if c.is_wall() {
                state.walls.retain(|&w| w != id);
            }
            if watch {
                gone.push((slot as usize, c.pos, c.radius));
            }
        }
    }
}
