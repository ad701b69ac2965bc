//! `swept`: continuous collision detection within the step.
//!
//! Gravity is applied as in the discrete step (velocity first, then straight-line motion over dt),
//! but the motion is swept: the times of impact of disk pairs (closed-form quadratic,
//! [`crate::method::toi::toi_ball_ball`]) and of disks against walls (the wall box expanded by
//! the radius: faces, edges, corners, [`crate::method::toi::toi_wall_ball`]) are processed in time
//! order by the shared event engine (`method::flight`): advance the pair to its time of
//! impact, hand it to the caller's `collide` hook, re-predict for the pair's critters. Then one
//! discrete pass resolves what still touches (resting contacts, spawned overlaps). Where resting
//! contacts under gravity exhaust the flight's event budget, the rest of the step is taken in
//! discrete substeps short enough not to tunnel ([`MOST_TAIL_SUBSTEPS`] at most).
//!
//! A step in which no critter moves more than [`SWEEP_FRACTION`] of the smallest radius (or of
//! the thinnest wall) is exactly the discrete step: sweeping is paid for only when needed.

use super::discrete::{self, Respond};
use super::flight;
use crate::error::Error;
use crate::step::pairs::Pairs;
use crate::step::span::Span;
use crate::step::state::State;
use crate::step::stats::StepStats;
use crate::vector::Vector;

/// A step is swept when some critter moves more than this fraction of the smallest disk radius
/// or wall thickness.
pub const SWEEP_FRACTION: f64 = 0.25;

/// How far disk `c` moves in the coming step of `dt` (the free ones after gravity's kick).
pub(crate) fn displacement<V: Vector>(
    state: &State<V>,
    c: &crate::critter::Critter<V>,
    dt: f64,
) -> f64 {
    let g = state.gravity;
    let v = if c.fixed { c.vel } else { c.vel + g * dt };
    v.length() * dt
}

/// The scales a step's motion is measured against, from one pass over the critters.
#[derive(Clone, Copy, Debug)]
pub struct MotionScale {
    /// The largest displacement of a disk in the coming step.
    pub fastest: f64,
    /// The thinnest wall (its smallest extent), or infinity with no walls.
    pub thinnest_wall: f64,
    /// The smallest disk radius, or infinity with no disks.
    pub smallest_radius: f64,
}

impl MotionScale {
    /// The smallest length a displacement is compared with: the smallest radius or the thinnest
    /// wall.
    pub fn smallest(&self) -> f64 {
        self.thinnest_wall.min(self.smallest_radius)
    }
}

/// The largest displacement of a critter in the coming step of `dt`, and the lengths it must be
/// compared with (smallest disk radius, thinnest wall).
pub(crate) fn motion_scale<V: Vector>(state: &State<V>, dt: f64) -> MotionScale {
    let mut scale = MotionScale {
        fastest: 0.0,
        thinnest_wall: f64::INFINITY,
        smallest_radius: f64::INFINITY,
    };
    // The largest squared speed, and one square root at the end: the square root and the
    // product with dt are correctly rounded and monotone, so this is bit for bit the largest
    // `displacement`, without a square root per critter.
    let g = state.gravity;
    let mut fastest_squared: f64 = 0.0;
    for c in state.critters.iter().filter(|c| c.in_play()) {
        match c.wall() {
            Some(w) => {
                for axis in 0..V::DIM {
                    scale.thinnest_wall = scale.thinnest_wall.min(2.0 * w.half.get(axis));
                }
            }
            None => {
                scale.smallest_radius = scale.smallest_radius.min(c.radius);
                let v = if c.fixed { c.vel } else { c.vel + g * dt };
                fastest_squared = fastest_squared.max(v.length_squared());
            }
        }
    }
    scale.fastest = fastest_squared.sqrt() * dt;
    scale
}

/// How many live disks move more than `limit` in the coming step of `dt`, and how many there
/// are.
pub(crate) fn count_fast<V: Vector>(state: &State<V>, limit: f64, dt: f64) -> (usize, usize) {
    let disks = state
        .critters
        .iter()
        .filter(|c| c.in_play() && !c.is_wall());
    let (mut fast, mut all) = (0, 0);
    for c in disks {
        fast += usize::from(displacement(state, c, dt) > limit);
        all += 1;
    }
    (fast, all)
}

/// One swept step (after the update hooks, before the lifecycle). With `fast_only`, the step
/// as `auto` takes it: the same events, but a slow critter (moving less than [`SWEEP_FRACTION`]
/// of the smallest radius or wall thickness) that can meet nothing along its line this step (no
/// disk, wall or border within reach of both) makes no prediction; it joins in when a collision
/// changes its flight. A few bullets among many spread-out slow critters then cost the bullets'
/// predictions, not everyone's.
pub(crate) fn step<V: Vector>(
    state: &mut State<V>,
    pairs: &mut Pairs<V>,
    flight: &mut flight::Scratch<V>,
    fast_only: bool,
    span: Span,
    stats: &mut StepStats,
) -> Result<(), Error> {
    let dt = span.dt;
    let scale = motion_scale(state, dt);
    let limit = SWEEP_FRACTION * scale.smallest();
    if scale.fastest <= limit {
        return discrete::substeps(state, pairs, &mut Respond::Pop, span, stats);
    }
    let clock = std::time::Instant::now();
    let dv = state.gravity * dt;
    for c in state.critters.iter_mut_moving() {
        if c.in_play() && !c.fixed && !c.is_wall() {
            c.vel += dv;
        }
    }
    let fast = fast_only.then_some(limit);
    let stopped = flight::run(state, flight, V::zero(), span, fast, false, stats)?;
    stats.response += clock.elapsed();
    match stopped {
        None => discrete::collide(state, pairs, &mut Respond::Pop, span, None, stats),
        Some(at) => {
            let overrun = Overrun {
                method: "swept",
                acc: V::zero(),
                at,
                limit,
                kicked: true,
                slow_below: fast,
            };
            finish_after_budget(state, pairs, flight, span, overrun, stats)
        }
    }
}

/// Where and how a swept or event step ran out of its event budget.
pub(crate) struct Overrun<V> {
    /// The step's method, for messages.
    pub(crate) method: &'static str,
    /// The flight's acceleration (gravity for `event`; `swept` gave its kick up front).
    pub(crate) acc: V,
    /// The time into the step where the budget ran out.
    pub(crate) at: f64,
    /// The most a discrete substep may move a critter without tunnelling.
    pub(crate) limit: f64,
    /// Swept: gravity's kick was given up front, and a discrete pass closes the step.
    pub(crate) kicked: bool,
    /// The flight's `slow_below` (see [`flight::run`]).
    pub(crate) slow_below: Option<f64>,
}

/// Finishes a step whose flight ran out of its event budget: in discrete substeps when at most
/// [`MOST_TAIL_SUBSTEPS`] of them take the rest moving no critter farther than the smallest
/// radius or wall thickness, so that none tunnels (resting contacts under gravity), else by carrying the flight on with every event ([`flight::carry_on`], which
/// errs when the events do not run out), so that no critter moves past its events. The first
/// step of a run that carries on says so in the step's log.
pub(crate) fn finish_after_budget<V: Vector>(
    state: &mut State<V>,
    pairs: &mut Pairs<V>,
    flight: &mut flight::Scratch<V>,
    span: Span,
    o: Overrun<V>,
    stats: &mut StepStats,
) -> Result<(), Error> {
    stats.budget_exceeded += 1;
    let rest = span.dt - o.at;
    // `limit` is SWEEP_FRACTION of the smallest radius or wall thickness: the substeps cannot
    // tunnel while none moves a critter farther than that smallest length itself.
    let safe = f64::from(MOST_TAIL_SUBSTEPS) / SWEEP_FRACTION;
    if tail_substeps(state, rest, o.limit, o.kicked) <= safe {
        return finish_in_substeps(state, pairs, span, rest, o.limit, o.kicked, stats);
    }
    if !flight.warned_budget {
        flight.warned_budget = true;
        state.events.log.push(format!(
            "warning: the {} step ran out of its event budget ({} events) {:.3e} into the step of {:e}; it carries on to the step's end with every event, which may be slow (a shorter --dt keeps steps within the budget)",
            o.method,
            flight.budget(),
            o.at,
            span.dt
        ));
    }
    flight::carry_on(
        state,
        flight,
        o.acc,
        o.at,
        span.over(rest, 1),
        o.slow_below,
        o.method,
        stats,
    )?;
    if o.kicked {
        discrete::collide(state, pairs, &mut Respond::Pop, span, None, stats)?;
    }
    Ok(())
}

/// The discrete substeps [`finish_in_substeps`] needs so that none moves a critter more than
/// `limit` (before it clamps them to [`MOST_TAIL_SUBSTEPS`]); NaN when a speed is not finite.
fn tail_substeps<V: Vector>(state: &State<V>, rest: f64, limit: f64, kicked: bool) -> f64 {
    let g = state.gravity;
    let mut fastest: f64 = 0.0;
    for c in state.critters.iter() {
        if c.in_play() && !c.is_wall() {
            // The same arithmetic as `finish_in_substeps`, without changing the velocities.
            let v = if kicked && !c.fixed {
                c.vel - g * rest
            } else {
                c.vel
            };
            fastest = fastest.max(v.length() + g.length() * rest);
        }
    }
    (fastest * rest / limit).ceil()
}

/// Finishes a step whose flight ran out of its event budget (resting contacts under gravity)
/// `rest` before its end: the rest is stepped in discrete substeps in which no critter moves
/// more than `limit` (so none tunnels, as in a step that needs no sweeping), at most
/// [`MOST_TAIL_SUBSTEPS`] of them. `kicked`: the step gave gravity's kick for the whole step up
/// front (swept), and the rest's part of it is taken back first, since the substeps give it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn finish_in_substeps<V: Vector>(
    state: &mut State<V>,
    pairs: &mut Pairs<V>,
    span: Span,
    rest: f64,
    limit: f64,
    kicked: bool,
    stats: &mut StepStats,
) -> Result<(), Error> {
    let g = state.gravity;
    let mut fastest: f64 = 0.0;
    for c in state.critters.iter_mut_moving() {
        if c.in_play() && !c.is_wall() {
            if kicked && !c.fixed {
                c.vel -= g * rest;
            }
            fastest = fastest.max(c.vel.length() + g.length() * rest);
        }
    }
    let n = (fastest * rest / limit)
        .ceil()
        .clamp(1.0, f64::from(MOST_TAIL_SUBSTEPS));
    discrete::substeps(
        state,
        pairs,
        &mut Respond::Pop,
        span.over(rest, n as u32),
        stats,
    )
}

/// The most discrete substeps that finish a swept or event step whose event budget ran out.
pub const MOST_TAIL_SUBSTEPS: u32 = 64;
