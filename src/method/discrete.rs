//! Pop's step, the part of every method that is not an event flight: move, find the touching
//! pairs, respond pair by pair, or solve the contacts together (`solve:n`).

use super::sleep::Sleep;
use super::solve::{self, Sweeps};
use crate::error::Error;
use crate::step::span::Span;
use crate::step::state::State;
use crate::step::stats::{timed, StepStats};
use crate::step::{motion, pairs::MoveReport, pairs::Pairs, response};
use crate::vector::Vector;

/// How the touching pairs are answered.
pub(crate) enum Respond<'a, V: Vector> {
    /// Pop's response: each caller's `collide`, pair by pair.
    Pop,
    /// `solve:n`: the kinds' own `collide` hooks, then the other contacts solved together in
    /// `sweeps`; sleepers stay still.
    Solve {
        scratch: &'a mut solve::Scratch<V>,
        sleep: &'a mut Sleep<V>,
        sweeps: Sweeps,
    },
}

impl<V: Vector> Respond<'_, V> {
    /// Sleepers and walls by slot, or empty when nobody sleeps.
    fn still(&self) -> &[bool] {
        match self {
            Respond::Pop => &[],
            Respond::Solve { sleep, .. } => sleep.still(),
        }
    }
}

/// Pop's step over `span` (the step, or what is left of it) without the update hooks and
/// lifecycle: `span.n` times move by `span.h`, find the pairs, respond.
pub(crate) fn substeps<V: Vector>(
    state: &mut State<V>,
    pairs: &mut Pairs<V>,
    respond: &mut Respond<'_, V>,
    span: Span,
    stats: &mut StepStats,
) -> Result<(), Error> {
    for _ in 0..span.n {
        let check = pairs.move_check();
        let moved = timed(&mut stats.moving, || {
            motion::run(state, span.h, respond.still(), &check)
        });
        collide(state, pairs, respond, span, Some(moved), stats)?;
    }
    Ok(())
}

/// [`substeps`] under Pop's response, watching for a critter that moves farther than its
/// radius in a substep (it may tunnel through a wall or a critter): the first one found, by
/// slot, is named in the step's log. The state is what [`substeps`] gives, bit for bit.
/// Returns true when it warned.
pub(crate) fn substeps_watching<V: Vector>(
    state: &mut State<V>,
    pairs: &mut Pairs<V>,
    span: Span,
    stats: &mut StepStats,
) -> Result<bool, Error> {
    let n = span.n;
    let mut far = None;
    for _ in 0..n {
        let check = pairs.move_check();
        let (moved, found) = timed(&mut stats.moving, || {
            motion::run_watching::<V, true>(state, span.h, &[], &check)
        });
        if far.is_none() {
            far = found.and_then(|(slot, d)| state.critters.slot(slot as u32).map(|c| (c.id, d)));
        }
        collide(state, pairs, &mut Respond::Pop, span, Some(moved), stats)?;
    }
    let Some((id, distance)) = far else {
        return Ok(false);
    };
    let Some(c) = state.critters.get(id) else {
        return Ok(false);
    };
    // Substeps that would move this critter at most its radius each.
    let enough = (f64::from(n) * distance / c.radius).ceil();
    let suggest = format!(
        "--method swept or --method event would not tunnel, nor would --method substep:{enough} for this critter's speed"
    );
    let per = if n == 1 { "step" } else { "substep" };
    state.events.log.push(format!(
        "warning: critter {id} ({}) moved {:.3e} in one {per}, farther than its radius {}: it may pass through walls and critters (tunnelling); {suggest} (said once per run)",
        state.kinds.name(c.kind()),
        distance,
        c.radius,
    ));
    Ok(true)
}

/// Finds the touching pairs where the critters are now and responds, after a move of
/// `span.h` (`moved` is its report, when the move ran just before).
pub(crate) fn collide<V: Vector>(
    state: &mut State<V>,
    pairs: &mut Pairs<V>,
    respond: &mut Respond<'_, V>,
    span: Span,
    moved: Option<MoveReport>,
    stats: &mut StepStats,
) -> Result<(), Error> {
    let ruled = timed(&mut stats.pairs, || {
        pairs.find(state, span.dt, moved, respond.still())
    })?;
    let collisions = timed(&mut stats.response, || match respond {
        Respond::Pop => response::run(state, pairs),
        Respond::Solve {
            scratch,
            sleep,
            sweeps,
        } => solve::respond(state, pairs, scratch, sleep, *sweeps, span.h),
    })?;
    if let Respond::Solve { scratch, .. } = respond {
        stats.sweeps += u64::from(scratch.swept);
    }
    stats.pair_tests += pairs.broad.tests;
    stats.candidates += pairs.candidates.len();
    stats.ruled += ruled;
    stats.contacts += pairs.contacts.len();
    stats.collisions += collisions;
    Ok(())
}
