//! The update stage: each live critter whose kind has an `update` hook runs it, in id order
//! wherever the critters are stored.

use super::span::Span;
use crate::error::Error;
use crate::step::access::UpdateCtx;
use crate::step::state::{hook_error, State};
use crate::vector::Vector;

/// Runs the `update` hooks of the step, each told the time since the last: the step `span`.
pub(crate) fn run<V: Vector>(state: &mut State<V>, span: Span) -> Result<(), Error> {
    if !state.kinds.iter().any(|(_, k)| k.has_update) {
        return Ok(());
    }
    let dt = span.dt;
    let step = state.step_count;
    for index in 0..state.critters.index_count() as u32 {
        let Some(slot) = state.critters.slot_of_index(index) else {
            continue;
        };
        let Some(c) = state.critters.slot(slot) else {
            continue;
        };
        if !c.in_play() || !state.kinds.get(c.kind()).has_update {
            continue;
        }
        let (kind, id) = (c.kind(), c.id);
        let hooks = state.kinds.get(kind).hooks.clone();
        let outer = state.enter_hook(id, "update");
        let mut ctx = UpdateCtx {
            access: state.access(),
            me: slot,
        };
        let done = hooks.update(&mut ctx, dt);
        state.hook = outer;
        done.map_err(|e| hook_error(e, &state.kinds, kind, id, step))?;
    }
    Ok(())
}
