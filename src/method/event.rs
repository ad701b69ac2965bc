//! `event`: exact event-driven dynamics.
//!
//! Between events critters fly exactly: straight lines, or parabolas under the world's uniform
//! gravity (fixed critters do not fall). Pair collisions (equal accelerations cancel, so a pair
//! of free disks is a quadratic in time), wall hits (quadratic against a face when no gravity,
//! conservative advancement on the exact box distance along a parabola), border hits, and cell
//! crossings (so each critter only looks at its neighbours) are predicted and processed in time
//! order by the event engine (`method::flight`); each collision is handed to the caller's `collide` hook.
//! A step advances exactly dt of event time. Without gravity the flight is kept from one step
//! to the next (its pending events stay queued; only critters changed between the steps predict
//! again), so a step pays for its events, not for predicting everyone anew. See `flight` for
//! that, for the treatment of round-off, inelastic collapse and resting contacts.

use super::flight;
use crate::error::Error;
use crate::method::swept::{finish_after_budget, motion_scale, Overrun, SWEEP_FRACTION};
use crate::step::pairs::Pairs;
use crate::step::span::Span;
use crate::step::state::State;
use crate::step::stats::StepStats;
use crate::vector::Vector;

/// One event-driven step of exactly dt (after the update hooks, before the lifecycle).
pub(crate) fn step<V: Vector>(
    state: &mut State<V>,
    pairs: &mut Pairs<V>,
    flight: &mut flight::Scratch<V>,
    span: Span,
    stats: &mut StepStats,
) -> Result<(), Error> {
    let clock = std::time::Instant::now();
    let g = state.gravity;
    let stopped = flight::run(state, flight, g, span, None, true, stats)?;
    stats.response += clock.elapsed();
    if let Some(at) = stopped {
        let overrun = Overrun {
            method: "event",
            acc: g,
            at,
            limit: SWEEP_FRACTION * motion_scale(state, span.dt).smallest(),
            kicked: false,
            slow_below: None,
        };
        finish_after_budget(state, pairs, flight, span, overrun, stats)?;
    }
    Ok(())
}
