//! The event engine shared by `swept` and `event`: critters fly (straight, or on parabolas under
//! uniform acceleration) between events, and events are processed in time order.
//!
//! Events ([`events`]): pair collisions, wall hits, border hits (bounce and clamp borders,
//! [`border`]) and cell crossings (Rapaport, J. Comput. Phys. 34, 1980; [`cells`]): the world
//! box is cut into cells at least one diameter wide, a critter predicts collisions only with
//! critters in its own and the neighbouring cells, and crossing into a new cell is an event that
//! predicts against the new neighbours (keeping the critter's earliest contact for the old
//! ones). Each critter keeps its own clock (it is advanced only when it takes part in an event)
//! and a count of its flight's changes; an event stores its critters' counts when predicted,
//! and a partner's changed count sends the owner to predict again. Each critter has one pending
//! event, in the queue of `crate::method::queue`, which orders by time, then owner; a critter's
//! candidates are ordered by time, then ids, then kind ([`predict`](mod@predict)).
//!
//! Straight 3D flights without walls use neighbour shells instead (Smallenburg, Eur. Phys. J. E
//! 45, 22, 2022; [`shells`]): a sphere lists the spheres whose shells overlap its own, predicts
//! against that list, and leaving its shell is the event that lists it again; a shell's list
//! holds far fewer candidates than the 27 cells around a sphere.
//!
//! Finite precision (Bannerman et al., arXiv:1211.6718): collisions are predicted for a contact
//! distance a hair (`SKIN`, relative) inside the true one, so at the predicted time the pair
//! really touches and the response sees it; a pair found overlapping is collided at once (when
//! it approaches, that is the Bannerman rule; when it separates, the response only separates).
//!
//! Inelastic collapse: a collision within `TC_FRACTION x dt` of either critter's previous one is
//! elastic (the TC model of Luding and McNamara), which stops the infinite sequence of ever
//! shorter intervals. An event budget per step bounds the cost of what remains (resting
//! contacts under gravity); when it runs out (counted in `StepStats::budget_exceeded`) the
//! critters are stopped where they are, and `swept` and `event` finish the step in discrete
//! substeps short enough not to tunnel, when a few of them do. Otherwise (a step far longer
//! than the time between collisions) no critter may move without its events: the step carries
//! on with them ([`carry_on`], with a warning once per run), up to [`CARRY_ON_FACTOR`] times the
//! budget, and past that it is an error naming the step and the event.
//!
//! Kept flights ([`kept`]): an event step whose flights are straight lines (no gravity) and in
//! which everyone predicts keeps its flight for the next step: the pending events stay in the
//! queue (their predictions look ahead to the end of the flight's life, not just the step's),
//! and the next step predicts again only the critters that something outside the flight changed
//! between the steps (a hook, the caller), found by comparing each critter with its body. A step
//! that cannot go on (a critter came, went or changed size or class, a wall moved, the step's
//! length or the method changed) sets up a new flight. A flight lives at most [`FLIGHT_STEPS`]
//! steps: it is set up anew at every step whose number is a multiple of it, so that a run
//! restored from a recorded state at such a step flies exactly as the recorded run did.
//!
//! The files: this one holds the flight's state ([`Scratch`]), [`run`] and the loop that
//! processes events; [`setup`](mod@setup) sets a new flight up ([`bodies`] are what it knows
//! of each critter); [`predict`](mod@predict) finds a critter's next event.

mod bodies;
mod border;
mod cells;
mod events;
mod kept;
mod predict;
mod setup;
mod shells;
#[cfg(test)]
mod tests;

use crate::error::Error;
use crate::method::queue::Queue;
use crate::pair_order::pair_key;
use crate::rules::roles_order;
use crate::step::span::Span;
use crate::step::state::{at_step, State};
use crate::step::stats::StepStats;
use crate::vector::Vector;
use bodies::{advance, refresh_body, Body, Status};
use border::bounce_border;
use cells::{cross_cell, relocate, StripedLists};
use events::{prefetch_event, validity, Event, EventKind, Validity};
use kept::{end_flight, fly_kept, steps_to_live, take_up_kept, EndSurvey, KeptFlight};
use predict::{predict, predict_after_crossing};
use setup::{mark_who_may_meet, setup};
use shells::{relist, ShellCentre};

pub use kept::{CHURN, FLIGHT_STEPS};

/// Relative shrink of contact distances used for prediction: at the predicted time the pair
/// really touches, whatever the rounding.
pub const SKIN: f64 = 1e-10;
/// Collisions closer than this fraction of dt to the critter's previous one are elastic: far
/// below any time scale of the motion, and it stops inelastic collapse.
pub const TC_FRACTION: f64 = 1e-9;
/// Events per critter per step before the step falls back to discrete substeps: bounds the cost
/// of resting contacts under gravity, which never run out of events.
pub const BUDGET_PER_CRITTER: u64 = 64;
/// A step whose rest the discrete substeps cannot take without tunnelling carries on with its
/// events instead ([`carry_on`]), up to this many times the budget: beyond it the events are
/// taken to be endless (Zeno) and the step is an error.
pub const CARRY_ON_FACTOR: u64 = 16;
/// Neighbour shells' thickness, as a fraction of the largest diameter: thinner shells are
/// left more often, thicker ones list more partners (`docs/methods.md` has the trade).
pub const SHELL_FRACTION: f64 = 0.6;

pub(crate) use crate::tolerance::ROUNDING_MARGIN;

/// An unset slot, cell or partner (above every slot).
const UNSET: u32 = u32::MAX;
/// In `last_partner`, the border side `s` a critter last bounced off is `BORDER_PARTNER + s`
/// (above every slot, below `UNSET`).
const BORDER_PARTNER: u32 = u32::MAX - 16;

/// Per-world scratch kept between steps so a step allocates nothing once warmed up.
#[derive(Default)]
pub(crate) struct Scratch<V: Vector> {
    /// What a pair test reads of each critter (see [`Body`]).
    body: Vec<Body<V>>,
    /// The rest of what the flight knows of each critter (see [`Status`]).
    status: Vec<Status>,
    /// Each critter's cell key.
    cell: Vec<u32>,
    /// The coordinates of each critter's cell (`cell` unpacked, saving divisions).
    coord: Vec<[i64; 3]>,
    /// The partner of each critter's last collision, or the border it last bounced off
    /// (`BORDER_PARTNER + side`), or `UNSET`: a pair touching at once is not handed back.
    last_partner: Vec<u32>,
    /// When each critter last collided (for the TC model).
    last_collision: Vec<f64>,
    /// The disks in each cell.
    cells: StripedLists,
    /// The walls each cell must test (a disk centred in it could touch them).
    cell_walls: Vec<Vec<u32>>,
    /// Some wall is alive (otherwise `cell_walls` is not read).
    has_walls: bool,
    /// Neighbour shells instead of cell crossings (Smallenburg's scheme): the cells hold each
    /// critter by its shell's centre, `neighbours` lists the critters whose shells overlap, and
    /// leaving the shell is the event that lists again.
    shells: bool,
    /// The shell's thickness: a critter stays within `shell_width / 2` of its shell's centre.
    shell_width: f64,
    /// The largest radius the cells and shells are sized for.
    largest_radius: f64,
    /// The next flight sizes its cells for at least this radius (set when a hook grew a
    /// critter beyond the last flight's cells).
    grown_radius: f64,
    /// When set, a critter that moves less than this in the flight predicts at its start only
    /// if it may meet something (see [`run`]).
    slow_below: Option<f64>,
    /// With `slow_below`, at the flight's start: how far each critter can move in it (`reach`),
    /// and whether it may meet something (`meets`, found by `mark_who_may_meet`).
    reach: Vec<f64>,
    meets: Vec<bool>,
    /// Per cell: a wall is listed in the cell or one around it.
    near_wall: Vec<bool>,
    /// Cells only, even where shells would pay (tests compare the two).
    #[cfg(test)]
    no_shells: bool,
    /// A new flight every step, even where it could be kept (tests compare the two).
    #[cfg(test)]
    no_keep: bool,
    /// Each critter's shell centre (its position when it was last listed) beside its radius.
    shell_centres: Vec<ShellCentre<V>>,
    /// A copy of the neighbour list `predict` walks (kept to save allocations).
    partners: Vec<u32>,
    /// The candidates `relist` gathers from the cells around (kept to save allocations).
    gathered: Vec<u32>,
    /// Each critter's neighbours (the critters whose shells overlap its own), symmetric.
    neighbours: StripedLists,
    /// Each critter's next event.
    queue: Queue<Event>,
    /// The earliest event found so far by the running prediction.
    earliest: Option<Event>,
    /// Pairs whose hook left them overlapping this step: not handed back at once again.
    stuck: std::collections::HashSet<u64>,
    /// Cells along each axis (1 beyond the world's dimension).
    dims: [usize; 3],
    /// A cell's width along each axis.
    cell_side: [f64; 3],
    /// Key offsets of the 3^D cells around an interior cell (none when an axis has fewer than
    /// three cells: neighbours then repeat, and the general path dedups them).
    offsets: Vec<isize>,
    /// The positive ones among `offsets`: the cells after an interior cell, with which
    /// `mark_who_may_meet` pairs it (each pair of neighbouring cells once).
    forward: Vec<isize>,
    /// Per axis and direction (`axis * 2 + dir`), the offsets among `offsets` of the cells a
    /// crossing that way brings into reach.
    front: [Vec<isize>; 6],
    /// Each critter's earliest pair or wall event from its last prediction, kept so that a cell
    /// crossing only has to look at the cells it brings into reach (Rapaport's scheme).
    earliest_contact: Vec<Option<Event>>,
    /// The acceleration of free critters.
    acc: V,
    /// No acceleration: every flight is a straight line.
    straight: bool,
    /// How far ahead (in flight time) predictions look: the step's end, or the end of a kept
    /// flight's life.
    horizon: f64,
    /// The step's dt (the flight may be a part of it).
    dt: f64,
    /// A collision this soon after either critter's last is elastic (the TC model).
    tc_window: f64,
    /// Events the flight may process before it stops.
    budget: u64,
    /// The flight carries a step on past its budget ([`carry_on`]): its budget is
    /// [`CARRY_ON_FACTOR`] times the usual.
    carrying_on: bool,
    /// Events the last flight processed, and the event it stopped at when its budget ran out.
    processed: u64,
    stopped_on: Option<Event>,
    /// The run was told once that a step carried on past its budget.
    pub(crate) warned_budget: bool,
    /// Predictions made and pair tests run in this flight (for the step's stats).
    predictions: u64,
    pair_tests: u64,
    /// Sum over default collisions of contact distance x impulse (the collision virial).
    pub virial: f64,
    /// The flight kept for the next step, if it may go on.
    kept: Option<KeptFlight>,
    /// The flight time the last flight ended at.
    ended_at: f64,
    /// A hook grew a critter beyond the cells in this step (the flight was set up again).
    outgrown: bool,
    /// The critters changed between two steps of a kept flight (kept to save allocations).
    changed: Vec<u32>,
    /// What the last flight's end found of the critters against their bodies.
    ended: EndSurvey,
    /// The step at which the last event step that could have kept its flight could not, or had
    /// to predict more than [`CHURN`] of its critters again: something outside the flight
    /// changes critters every step (hooks steering them, spawns), and the kept flight does not
    /// pay (`auto` reads it). `None` when the last such step kept its flight.
    churned_at: Option<u64>,
}

impl<V: Vector> Scratch<V> {
    /// The events the last flight might process before it stopped.
    pub(crate) fn budget(&self) -> u64 {
        self.budget
    }
}

/// Flies the world's critters over `span` (one piece of `span.h`) under acceleration `acc`
/// (free critters only),
/// processing every event in order. Returns `None` when every event was processed, or the time
/// the event budget ran out, where the critters were stopped (the caller finishes the step, in
/// discrete substeps that cannot tunnel or with [`carry_on`]).
///
/// `slow_below`: when set, a critter that moves less than it in the flight predicts at the
/// start only if it may meet something along its line (`may_meet`); otherwise it joins in when
/// a collision changes its flight. The events are the same as when everyone predicts.
pub(crate) fn run<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    acc: V,
    span: Span,
    slow_below: Option<f64>,
    keep: bool,
    stats: &mut StepStats,
) -> Result<Option<f64>, Error> {
    let t_end = span.h;
    sc.dt = span.dt;
    sc.slow_below = slow_below;
    sc.outgrown = false;
    let step = state.step_count;
    // Kept only for straight flights in which everyone predicts (a curved prediction would have
    // to look steps ahead; a slow critter that predicts nothing would miss later steps' events).
    let keep = keep && slow_below.is_none() && acc.length_squared() == 0.0;
    #[cfg(test)]
    let keep = keep && !sc.no_keep;
    let kept = sc
        .kept
        .take()
        .filter(|k| keep && k.step == step && k.dt == t_end && !step.is_multiple_of(FLIGHT_STEPS));
    let life = steps_to_live(keep, step);
    let out = match kept {
        Some(_) => match take_up_kept(state, sc, step) {
            Ok(true) => fly_kept(state, sc, acc, t_end, stats),
            Ok(false) => {
                sc.churned_at = Some(step);
                fly_new(state, sc, acc, t_end, life, stats)
            }
            Err(e) => Err(e),
        },
        None => fly_new(state, sc, acc, t_end, life, stats),
    };
    if keep && !sc.outgrown && matches!(out, Ok(None)) && !(step + 1).is_multiple_of(FLIGHT_STEPS) {
        sc.kept = Some(KeptFlight {
            step: step + 1,
            dt: t_end,
        });
    } else {
        sc.kept = None;
        sc.queue.reset(0, 0.0, 0.0);
    }
    out
}

/// Carries a step on over `rest` (one piece) from where its budget ran out, in a new flight with
/// [`CARRY_ON_FACTOR`] times the budget, so that no critter moves without its events. When that
/// runs out too, the events are endless in this step: an [`Error::EndlessEvents`] naming the
/// step and the event it gave up on. `at`: the flight time the step had reached; `method`: the
/// step's method, for the error.
#[allow(clippy::too_many_arguments)]
pub(crate) fn carry_on<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    acc: V,
    at: f64,
    rest: Span,
    slow_below: Option<f64>,
    method: &'static str,
    stats: &mut StepStats,
) -> Result<(), Error> {
    let before = sc.processed;
    sc.carrying_on = true;
    let out = run(state, sc, acc, rest, slow_below, false, stats);
    sc.carrying_on = false;
    let Some(stopped) = out? else {
        return Ok(());
    };
    let pair = match sc.stopped_on.take() {
        Some(ev) => describe(state, sc, &ev),
        None => "an event".to_string(),
    };
    Err(Error::EndlessEvents {
        step: state.step_count,
        method,
        events: before + sc.processed,
        at: at + stopped,
        dt: rest.dt,
        pair,
    })
}

/// The critters of event `ev`, in words: its owner and what the owner last collided with
/// (the pair an endless sequence repeats), or its partner when it has not collided yet.
fn describe<V: Vector>(state: &State<V>, sc: &Scratch<V>, ev: &Event) -> String {
    let name = |x: u32| match state.critters.slot(x) {
        Some(c) if c.is_wall() => format!("wall {}", c.id),
        Some(c) => format!("critter {} ({})", c.id, state.kinds.name(c.kind())),
        None => format!("slot {x}"),
    };
    let owner = name(ev.owner);
    match sc.last_partner.get(ev.owner as usize).copied() {
        Some(p) if p < BORDER_PARTNER => format!("{owner} and {}", name(p)),
        Some(p) if p < UNSET => format!("{owner} and the border"),
        _ => match ev.kind {
            EventKind::Pair | EventKind::Wall => format!("{owner} and {}", name(ev.other)),
            EventKind::Border => format!("{owner} and the border"),
            _ => owner,
        },
    }
}

/// Flies the critters to `t_end` in new flights: one, unless a hook grows a critter beyond the
/// largest radius the flight's cells (or shells) were sized for: the flight then stops there,
/// everyone is brought to that time, and a new flight, sized for the grown critter, flies the
/// rest.
fn fly_new<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    acc: V,
    t_end: f64,
    life: u64,
    stats: &mut StepStats,
) -> Result<Option<f64>, Error> {
    sc.grown_radius = 0.0;
    let (mut flown, mut virial) = (0.0, 0.0);
    loop {
        // A flight set up again after a critter grew lives to the step's end only.
        let life = if flown == 0.0 { life } else { 1 };
        let outcome = fly(state, sc, acc, None, t_end - flown, life, stats);
        virial += sc.virial;
        sc.virial = virial;
        match outcome? {
            FlightEnd::Done(stopped) => return Ok(stopped.map(|t| flown + t)),
            FlightEnd::Grown(t) => {
                sc.outgrown = true;
                flown += t
            }
        }
    }
}

/// How a flight ended.
enum FlightEnd {
    /// At its end, or where the event budget ran out (the time everyone is at).
    Done(Option<f64>),
    /// At this time, because a hook grew a critter beyond what the cells were sized for.
    Grown(f64),
}

/// Flies for `length` from flight time `from` (a kept flight that `take_up_kept` took up), or
/// sets up a new flight whose predictions look `life` steps of `length` ahead and flies it
/// from 0.
fn fly<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    acc: V,
    from: Option<f64>,
    length: f64,
    life: u64,
    stats: &mut StepStats,
) -> Result<FlightEnd, Error> {
    let n = state.critters.slot_count() as u32;
    let start = match from {
        Some(t) => t,
        None => {
            // A little past the life's last step's end, whatever the rounding of the steps'
            // sums of dt.
            let horizon = if life > 1 {
                length * life as f64 * (1.0 + ROUNDING_MARGIN)
            } else {
                length
            };
            setup(state, sc, acc, horizon, life);
            match sc.slow_below {
                Some(limit) => {
                    mark_who_may_meet(state, sc);
                    for a in 0..n {
                        if sc.reach[a as usize] > limit || sc.meets[a as usize] {
                            predict(state, sc, a, 0.0)?;
                        }
                    }
                }
                None => {
                    for a in 0..n {
                        predict(state, sc, a, 0.0)?;
                    }
                }
            }
            0.0
        }
    };
    let t_end = start + length; // (exactly `length` for a new flight, which starts at 0)
    let mut processed = 0u64;
    let mut stopped = None;
    let mut grown = None;
    // Every branch below predicts the event's owner again (which replaces the event in the
    // queue) or removes the event.
    while let Some(ev) = sc.queue.peek_until(t_end) {
        if ev.time > t_end {
            break;
        }
        match validity(sc, &ev) {
            Validity::Stale => {
                sc.queue.remove(ev.owner);
                continue;
            }
            Validity::PartnerChanged => {
                predict(state, sc, ev.owner, ev.time)?;
                continue;
            }
            Validity::Valid => {}
        }
        processed += 1;
        if processed > sc.budget {
            stopped = Some(ev.time);
            sc.stopped_on = Some(ev);
            break;
        }
        let t = ev.time;
        if sc.shells {
            // What the predictions after this event read: the bodies of both critters'
            // neighbours, asked for before the collision's own work; and what the next event
            // most likely reads (a large gas's loads are scattered). Not with cells: there it
            // costs 2D gases time.
            for x in [ev.owner, ev.other] {
                if ev.kind == EventKind::Pair || x == ev.owner {
                    for &p in sc.neighbours.members(x as usize) {
                        crate::prefetch::prefetch(sc.body.get(p as usize));
                    }
                }
            }
            if let Some(next) = sc.queue.runner_up() {
                prefetch_event(state, sc, &next);
            }
        }
        let (a, b) = (ev.owner, ev.other);
        match ev.kind {
            EventKind::Pair | EventKind::Wall => {
                advance(state, sc, a, t);
                advance(state, sc, b, t);
                stats.contacts += 1;
                let deaths = state.pending.deaths.len();
                if collide(state, sc, a, b, t)? {
                    stats.collisions += 1;
                }
                // A hook may kill third critters: their bodies must know.
                for i in deaths..state.pending.deaths.len() {
                    let x = state.pending.deaths[i].index;
                    refresh_body(state, sc, x);
                }
                if let (Some(x), Some(y)) = (state.critters.slot(a), state.critters.slot(b)) {
                    if x.in_play() && y.in_play() {
                        if let Some(c) = crate::default_response::contact_between(&state.topo, x, y)
                        {
                            if c.depth > SKIN * x.radius.min(y.radius) * 4.0 {
                                sc.stuck.insert(pair_key(a, b));
                            }
                        }
                    }
                }
                sc.last_partner[a as usize] = b;
                sc.last_collision[a as usize] = t;
                if ev.kind == EventKind::Pair {
                    sc.last_partner[b as usize] = a;
                    sc.last_collision[b as usize] = t;
                }
                for x in [a, b] {
                    if state.critters.slot(x).is_some_and(|c| !c.is_wall()) {
                        let s = &mut sc.status[x as usize];
                        s.changes = s.changes.wrapping_add(1);
                        relocate(state, sc, x);
                        refresh_body(state, sc, x);
                    }
                }
                // A radius (NaN for walls and the dead) beyond what the cells were sized for:
                // neighbours it now reaches may lie outside the cells it scans. Cells sized for
                // twice the new radius make many restarts in one flight unlikely.
                let radius = |x: u32| sc.body[x as usize].radius;
                let largest = radius(a).max(radius(b));
                if largest > sc.largest_radius {
                    sc.grown_radius = 2.0 * largest;
                    grown = Some(t);
                    break;
                }
                for x in [a, b] {
                    predict(state, sc, x, t)?;
                }
            }
            EventKind::Border => {
                advance(state, sc, a, t);
                bounce_border(state, a, b);
                refresh_body(state, sc, a);
                sc.last_partner[a as usize] = BORDER_PARTNER + b;
                let s = &mut sc.status[a as usize];
                s.changes = s.changes.wrapping_add(1);
                predict(state, sc, a, t)?;
            }
            EventKind::CellCrossing => {
                cross_cell(state, sc, a, b, t);
                refresh_body(state, sc, a);
                predict_after_crossing(state, sc, a, b, t)?;
            }
            EventKind::ShellExit => {
                advance(state, sc, a, t);
                relist(state, sc, a);
                predict(state, sc, a, t)?;
            }
            EventKind::Recheck => {
                // Continue a curved prediction that did not settle.
                predict(state, sc, a, t)?;
            }
        }
    }
    sc.processed = processed.min(sc.budget);
    stats.events += sc.processed;
    stats.pair_tests += sc.pair_tests;
    stats.candidates += sc.predictions as usize;
    // Everyone to the end of the flight.
    let end = grown.or(stopped).unwrap_or(t_end);
    sc.ended_at = end;
    end_flight(state, sc, end);
    Ok(match grown {
        Some(t) => FlightEnd::Grown(t - start),
        None => FlightEnd::Done(stopped.map(|t| t - start)),
    })
}

/// Hands a touching pair to the caller's `collide` hook (Pop's roles), with the TC model.
fn collide<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    b: u32,
    t: f64,
) -> Result<bool, Error> {
    let (ca, cb) = (
        state.critters.slot(a).expect("live"),
        state.critters.slot(b).expect("live"),
    );
    let rule = match state
        .rules
        .rule(&state.kinds, &state.topo, ca, cb)
        .map_err(|e| at_step(e, state.step_count))?
    {
        Some(r) => r,
        None => crate::rules::roles_of(&state.kinds, &state.topo, ca, cb)
            .map_err(|e| at_step(e, state.step_count))?,
    };
    let Some((caller, arg)) = roles_order(rule, ca, cb) else {
        return Ok(false);
    };
    let (caller, arg) = (caller.id.index, arg.id.index);
    // TC model: a collision right after another one of either critter is elastic.
    let recent = |x: u32| t - sc.last_collision[x as usize] < sc.tc_window;
    let tc = recent(a) || (!cb.is_wall() && recent(b));
    let saved = if tc {
        let e = [a, b].map(|x| state.critters.slot(x).map_or(1.0, |c| c.restitution()));
        for x in [a, b] {
            if let Some(c) = state.critters.slot_mut(x) {
                c.traits_mut().restitution = 1.0;
            }
        }
        Some(e)
    } else {
        None
    };
    let before = state.events.collisions.len();
    let out = state.collide_pair(caller, arg);
    if let Some(e) = saved {
        for (x, e) in [a, b].into_iter().zip(e) {
            if let Some(c) = state.critters.slot_mut(x) {
                if c.restitution() == 1.0 {
                    c.traits_mut().restitution = e;
                }
            }
        }
    }
    for ev in &state.events.collisions[before..] {
        let (Some(c1), Some(c2)) = (state.critters.get(ev.caller), state.critters.get(ev.arg))
        else {
            continue;
        };
        if !c1.is_wall() && !c2.is_wall() {
            sc.virial += (c1.radius + c2.radius) * ev.impulse;
        }
    }
    out
}
