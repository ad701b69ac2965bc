//! Kept flights: a straight flight goes on from one event step to the next, predicting again
//! only the critters that something outside it changed between the steps (see the module docs
//! of `flight`).

use super::bodies::{motion_at, refresh_body, Body, Status};
use super::cells::relocate;
use super::predict::predict;
use super::{fly, fly_new, FlightEnd, Scratch};
use crate::critter::Critter;
use crate::error::Error;
use crate::step::state::State;
use crate::step::stats::StepStats;
use crate::vector::Vector;

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

/// What the end of a flight found of the critters against their bodies, as [`take_up_kept`]
/// would at the next step's start: while the critters are untouched since (`mark`), the next
/// step takes it instead of comparing every critter again. The critters it found moved (the
/// ones the end wrapped into the box) are in [`Scratch::changed`].
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct EndSurvey {
    /// The critters' mark when the survey ended (see `CritterSet::mark_untouched`).
    mark: u64,
    /// Some critter's slot or shape does not match its body: the flight cannot go on.
    lost: bool,
    /// The live disks.
    disks: usize,
}

/// Critter slot `slot` against its body and status, at flight time `start`.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Against {
    /// It came, went, or changed size, class or mobility, or it is a wall that moved.
    Lost,
    /// An empty slot, a dead critter or a wall, as the flight knows it.
    NoDisk,
    /// A live disk where its body is.
    Same,
    /// A live disk that something outside the flight moved or turned.
    Moved,
}

#[inline]
fn against<V: Vector>(
    slot: &Option<Critter<V>>,
    body: &Body<V>,
    status: &Status,
    start: f64,
) -> Against {
    let Some(c) = slot else {
        return if status.in_play {
            Against::Lost
        } else {
            Against::NoDisk
        };
    };
    let same = c.in_play() == status.in_play
        && c.is_wall() == status.wall
        && (!c.in_play()
            || if c.is_wall() {
                c.pos == body.pos
            } else {
                c.radius == body.radius && c.class == status.class && c.fixed != status.free
            });
    if !same {
        Against::Lost
    } else if !c.in_play() || c.is_wall() {
        Against::NoDisk
    } else if c.pos != body.pos || c.vel != body.vel || body.t != start {
        Against::Moved
    } else {
        Against::Same
    }
}

/// Brings every critter (and its body) to flight time `end` along its flight, and wraps or
/// borders the disks into the box; then surveys them for the next step ([`EndSurvey`]), in the
/// same pass: a step of a kept flight reads every critter once.
#[allow(clippy::needless_range_loop)] // bodies, statuses and slots indexed together
pub(super) fn end_flight<V: Vector>(state: &mut State<V>, sc: &mut Scratch<V>, end: f64) {
    let topo = state.topo;
    let n = sc.body.len().min(state.critters.slot_count());
    let mut changed = std::mem::take(&mut sc.changed);
    changed.clear();
    let (mut lost, mut disks) = (false, 0usize);
    let straight = sc.straight;
    let slots = &mut state.critters.slots_mut_moving()[..n];
    for a in 0..n {
        let s = sc.status[a];
        // As `advance` (a line needs no acceleration, the most common case).
        let motion = match (s.in_play && !s.wall, straight) {
            (false, _) => None,
            (true, true) => {
                let b = &sc.body[a];
                Some((b.pos + b.vel * (end - b.t), b.vel))
            }
            (true, false) => {
                let m = motion_at(sc, a as u32, end);
                Some((m.pos, m.vel))
            }
        };
        let body = &mut sc.body[a];
        if let Some((pos, vel)) = motion {
            body.pos = pos;
            body.vel = vel;
            body.t = end;
        }
        let slot = &mut slots[a];
        if let Some(c) = slot {
            if let Some((pos, vel)) = motion {
                c.pos = pos;
                c.vel = vel;
            }
            if c.in_play() && !c.is_wall() {
                c.pos = if topo.wraps() {
                    topo.wrap_position(c.pos)
                } else if topo.clear_of_edges(c.pos, c.radius) {
                    c.pos // (what `apply` gives, without reading the restitution)
                } else {
                    topo.apply_at_edges(c.pos, c.vel, c.radius, c.restitution())
                        .0
                };
            }
        }
        match against(slot, body, &s, end) {
            Against::Lost => lost = true,
            Against::NoDisk => {}
            Against::Same => disks += 1,
            Against::Moved => {
                disks += 1;
                changed.push(a as u32);
            }
        }
    }
    sc.changed = changed;
    let mark = state.critters.mark_untouched();
    sc.ended = EndSurvey { mark, lost, disks };
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

/// A kept flight flown on for one more step of `length`, from where the last one ended.
pub(super) fn fly_kept<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    acc: V,
    length: f64,
    stats: &mut StepStats,
) -> Result<Option<f64>, Error> {
    let start = sc.ended_at;
    match fly(state, sc, acc, Some(start), length, 1, stats)? {
        FlightEnd::Done(stopped) => Ok(stopped),
        FlightEnd::Grown(t) => {
            // The rest of the step in new flights, sized for the grown critter.
            let virial = sc.virial;
            let rest = fly_new(state, sc, acc, length - t, 1, stats);
            sc.virial += virial;
            sc.outgrown = true;
            Ok(rest?.map(|r| t + r))
        }
    }
}

/// Takes up the flight kept from the last step, from where it ended:
/// every critter that something outside the flight changed since (its position or velocity is
/// not its body's) is counted as changed (its partners' events with it go stale), put in its
/// cell and predicted again, as after a collision (and the flight counted churned at `step`
/// when they are more than [`CHURN`] of the disks). Returns false, having changed nothing, when
/// the flight cannot go on (the caller counts that as churned): a critter came or went, changed
/// size, class or mobility, or a wall moved; the step then sets up a new flight.
pub(super) fn take_up_kept<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    step: u64,
) -> Result<bool, Error> {
    let n = state.critters.slot_count();
    if n != sc.body.len() {
        return Ok(false);
    }
    let start = sc.ended_at;
    let mut changed = std::mem::take(&mut sc.changed);
    let ended = sc.ended;
    let disks = if state.critters.untouched_since(ended.mark) {
        // Nothing touched the critters since the last flight's end surveyed them.
        if ended.lost {
            sc.changed = changed;
            return Ok(false);
        }
        ended.disks
    } else {
        changed.clear();
        let mut disks = 0usize;
        for (a, slot) in state.critters.slot_slice().iter().enumerate() {
            match against(slot, &sc.body[a], &sc.status[a], start) {
                Against::Lost => {
                    sc.changed = changed;
                    return Ok(false);
                }
                Against::NoDisk => {}
                Against::Same => disks += 1,
                Against::Moved => {
                    disks += 1;
                    changed.push(a as u32);
                }
            }
        }
        disks
    };
    let churned = changed.len() as f64 > CHURN * disks as f64;
    sc.churned_at = churned.then_some(step);
    sc.stuck.clear();
    sc.virial = 0.0;
    sc.predictions = 0;
    sc.pair_tests = 0;
    for &a in &changed {
        sc.body[a as usize].t = start;
        let s = &mut sc.status[a as usize];
        s.changes = s.changes.wrapping_add(1);
        relocate(state, sc, a);
        refresh_body(state, sc, a);
    }
    let out = changed
        .iter()
        .try_for_each(|&a| predict(state, sc, a, start));
    sc.changed = changed;
    out.map(|()| true)
}
