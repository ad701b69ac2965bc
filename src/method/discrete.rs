//! Pop's step, the part of every method that is not an event flight: move, find the touching
//! pairs, respond pair by pair, or solve the contacts together (`solve:n`).

use super::sleep::Sleep;
use super::solve::{self, Sweeps};
use crate::error::Error;
use crate::vector::Vector;
use crate::world::stages::{motion, pairs::MoveReport, pairs::Pairs, response};
use crate::world::state::State;
use crate::world::stats::{timed, StepStats};

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

/// Pop's step over `span` (dt, or what is left of it) without the update hooks and lifecycle:
/// `n` times move by h = span/n, find the pairs, respond.
pub(crate) fn substeps<V: Vector>(
    state: &mut State<V>,
    pairs: &mut Pairs<V>,
    respond: &mut Respond<'_, V>,
    span: f64,
    n: u32,
    stats: &mut StepStats,
) -> Result<(), Error> {
    let h = span / f64::from(n);
    for _ in 0..n {
        let check = pairs.move_check();
        let moved = timed(&mut stats.moving, || {
            motion::run(state, h, respond.still(), &check)
        });
        collide(state, pairs, respond, h, Some(moved), stats)?;
    }
    Ok(())
}

/// Finds the touching pairs where the critters are now and responds, after a move of `h`
/// (`moved` is its report, when the move ran just before).
pub(crate) fn collide<V: Vector>(
    state: &mut State<V>,
    pairs: &mut Pairs<V>,
    respond: &mut Respond<'_, V>,
    h: f64,
    moved: Option<MoveReport>,
    stats: &mut StepStats,
) -> Result<(), Error> {
    let ruled = timed(&mut stats.pairs, || {
        pairs.find(state, moved, respond.still())
    })?;
    let collisions = timed(&mut stats.response, || match respond {
        Respond::Pop => response::run(state, pairs),
        Respond::Solve {
            scratch,
            sleep,
            sweeps,
        } => solve::respond(state, pairs, scratch, sleep, *sweeps, h),
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
