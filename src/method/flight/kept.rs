//! Kept flights: a straight flight goes on from one event step to the next, predicting again
//! only the critters that something outside it changed between the steps (see the module docs
//! of `flight`).

use super::bodies::refresh_body;
use super::cells::relocate;
use super::predict::predict;
use super::{fly, fly_new, FlightEnd, Scratch};
use crate::error::Error;
use crate::vector::Vector;
use crate::world::state::State;
use crate::world::stats::StepStats;

/// A kept flight is set up anew at every step whose number is a multiple of this, so that a
/// replay restored at such a step flies as the recorded run did.
pub const FLIGHT_STEPS: u64 = 30;

/// The fraction of the critters a kept flight may have to predict again at a step's start and
/// still count as kept ([`Scratch::churned`]): more is taken for something steering critters
/// every step, not an occasional push, and a kept flight does not pay there.
pub const CHURN: f64 = 0.125;

/// What lets a kept flight go on at the next step.
#[derive(Clone, Copy, Debug)]
pub(super) struct KeptFlight {
    /// The number of the step that may take it up.
    pub(super) step: u64,
    /// The step's length it was flown with.
    pub(super) dt: f64,
}

impl<V: Vector> Scratch<V> {
    /// Whether an event step since the last step set up on schedule (the last multiple of
    /// [`FLIGHT_STEPS`] at or before `step`) found its flight churned (see `churned_at`).
    /// Nothing before that step counts, so that a run restored there chooses the same.
    pub(crate) fn churned(&self, step: u64) -> bool {
        self.churned_at
            .is_some_and(|at| at >= step - step % FLIGHT_STEPS)
    }
}

/// The steps a flight set up at step `step` may live (to the next multiple of [`FLIGHT_STEPS`]),
/// or 1 when it is not kept.
pub(super) fn steps_to_live(keep: bool, step: u64) -> u64 {
    if keep {
        FLIGHT_STEPS - step % FLIGHT_STEPS
    } else {
        1
    }
}

/// A kept flight flown on for one more step of `span`, from where the last one ended.
pub(super) fn fly_kept<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    acc: V,
    span: f64,
    stats: &mut StepStats,
) -> Result<Option<f64>, Error> {
    let start = sc.ended_at;
    match fly(w, sc, acc, Some(start), span, 1, stats)? {
        FlightEnd::Done(stopped) => Ok(stopped),
        FlightEnd::Grown(t) => {
            // The rest of the step in new flights, sized for the grown critter.
            let virial = sc.virial;
            let rest = fly_new(w, sc, acc, span - t, 1, stats);
            sc.virial += virial;
            sc.outgrown = true;
            Ok(rest?.map(|r| t + r))
        }
    }
}

/// Takes up the flight kept from the last step, for a step of `span` from where it ended:
/// every critter that something outside the flight changed since (its position or velocity is
/// not its body's) is counted as changed (its partners' events with it go stale), put in its
/// cell and predicted again, as after a collision (and the flight counted churned at `step`
/// when they are more than [`CHURN`] of the disks). Returns false, having changed nothing, when
/// the flight cannot go on (the caller counts that as churned): a critter came or went, changed
/// size, class or mobility, or a wall moved; the step then sets up a new flight.
pub(super) fn take_up_kept<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    span: f64,
    step: u64,
) -> Result<bool, Error> {
    let n = w.critters.slot_count();
    if n != sc.body.len() {
        return Ok(false);
    }
    let start = sc.ended_at;
    let mut changed = std::mem::take(&mut sc.changed);
    changed.clear();
    let mut disks = 0usize;
    for (a, slot) in w.critters.slot_slice().iter().enumerate() {
        let (body, status) = (&sc.body[a], &sc.status[a]);
        let Some(c) = slot else {
            if status.alive {
                sc.changed = changed;
                return Ok(false);
            }
            continue;
        };
        let same = c.alive == status.alive
            && c.is_wall() == status.wall
            && (!c.alive
                || if c.is_wall() {
                    c.pos == body.pos
                } else {
                    c.radius == body.radius && c.class == status.class && c.fixed != status.free
                });
        if !same {
            sc.changed = changed;
            return Ok(false);
        }
        if c.alive && !c.is_wall() {
            disks += 1;
            if c.pos != body.pos || c.vel != body.vel || body.t != start {
                changed.push(a as u32);
            }
        }
    }
    let churned = changed.len() as f64 > CHURN * disks as f64;
    sc.churned_at = churned.then_some(step);
    sc.stuck.clear();
    sc.virial = 0.0;
    sc.predictions = 0;
    sc.pair_tests = 0;
    // The calendar over two steps: the events of this one never wait in its last bucket
    // (`Queue::peek_until` leaves that, with everything after the next step, unopened).
    sc.queue.rebase(start, start + 2.0 * span);
    for &a in &changed {
        sc.body[a as usize].t = start;
        let s = &mut sc.status[a as usize];
        s.changes = s.changes.wrapping_add(1);
        relocate(w, sc, a);
        refresh_body(w, sc, a);
    }
    let out = changed.iter().try_for_each(|&a| predict(w, sc, a, start));
    sc.changed = changed;
    out.map(|()| true)
}
