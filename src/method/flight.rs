//! The event engine shared by `swept` and `event`: critters fly (straight, or on parabolas under
//! uniform acceleration) between events, and events are processed in time order.
//!
//! Events: pair collisions, wall hits, border hits (bounce and clamp borders) and cell crossings
//! (Rapaport, J. Comput. Phys. 34, 1980): the world box is cut into cells at least one diameter
//! wide, a critter predicts collisions only with critters in its own and the neighbouring cells,
//! and crossing into a new cell is an event that predicts against the new neighbours (keeping
//! the critter's best pair event for the old ones). Each critter keeps its own clock (it is
//! advanced only when it takes part in an event) and an event counter; an event stores its
//! critters' counters when predicted, and a partner's changed counter sends the owner to predict
//! again. Each critter has one pending event, in the queue of `crate::method::queue`, which
//! orders by time, then owner; a critter's candidates are ordered by time, then ids, then kind.
//!
//! Straight 3D flights without walls use neighbour shells instead (Smallenburg, Eur. Phys. J. E
//! 45, 22, 2022): a sphere lists the spheres whose shells overlap its own, predicts against
//! that list, and leaving its shell is the event that lists it again; 27 cells of one diameter
//! hold about 21 spheres at packing 0.4, a shell list about 13.
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
//! substeps short enough not to tunnel.
//!
//! Kept flights: an event step whose flights are straight lines (no gravity) and in which
//! everyone predicts keeps its flight for the next step: the pending events stay in the queue
//! (their predictions look ahead to the end of the flight's life, not just the step's), and the
//! next step predicts again only the critters that something outside the flight changed between
//! the steps (a hook, the caller), found by comparing each critter with its body. A step that
//! cannot go on (a critter came, went or changed size or class, a wall moved, the step's length
//! or the method changed) sets up a new flight. A flight lives at most [`FLIGHT_STEPS`] steps:
//! it is set up anew at every step whose number is a multiple of it, so that a run restored
//! from a recorded state at such a step flies exactly as the recorded run did.

use crate::border::{Border, Topology};
use crate::contact::contact_wall_ball;
use crate::critter::{Shape, CLASS_UNSET};
use crate::error::Error;
use crate::method::queue::{Owned, Queue};
use crate::method::toi::{
    smallest_nonneg_root, surely_no_toi_by, toi_ball_ball, toi_ball_ball_by, toi_wall_ball,
};
use crate::pairs::pair_key;
use crate::rules::roles_order;
use crate::rules::PairRule;
use crate::vector::Vector;
use crate::world::state::{at_step, State};
use crate::world::stats::StepStats;
use std::cmp::Ordering;

/// A kept flight is set up anew at every step whose number is a multiple of this (see the
/// module docs); replays restore recorded states at such steps only.
pub const FLIGHT_STEPS: u64 = 30;

/// Relative shrink of contact distances used for prediction.
pub const SKIN: f64 = 1e-10;
/// Collisions closer than this fraction of dt to the critter's previous one are elastic.
pub const TC_FRACTION: f64 = 1e-9;
/// Events per critter per step before the step falls back to the discrete pass.
pub const BUDGET_PER_CRITTER: u64 = 64;
/// Conservative-advancement iterations before a curved prediction is continued by a recheck.
const CA_ITERATIONS: usize = 64;
/// Neighbour shells (straight flights in 3D without walls): the shell's thickness, as a
/// fraction of the largest diameter. Pairs are listed when their shells overlap.
pub const SHELL_FRACTION: f64 = 0.6;

const NONE: u32 = u32::MAX;
/// What an event is. An enum, not a plain byte, so that `Option<Ev>` needs no tag of its own
/// (it fits the 32 bytes `Ev` takes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[repr(u8)]
enum Kind {
    Pair,
    Wall,
    Border,
    Cell,
    Recheck,
    Shell,
}
const PAIR: Kind = Kind::Pair;
const WALL: Kind = Kind::Wall;
const BORDER: Kind = Kind::Border;
const CELL: Kind = Kind::Cell;
const RECHECK: Kind = Kind::Recheck;
const SHELL: Kind = Kind::Shell;
const BORDER_TAG: u32 = u32::MAX - 16;

/// A predicted event (32 bytes, aligned so that one never straddles two cache lines).
#[derive(Clone, Copy, Debug)]
#[repr(align(32))]
struct Ev {
    time: f64,
    a: u32,
    b: u32,
    kind: Kind,
    ca: u32,
    cb: u32,
}

const _: () = assert!(std::mem::size_of::<Option<Ev>>() == 32);

impl Owned for Ev {
    #[inline]
    fn time(&self) -> f64 {
        self.time
    }
    #[inline]
    fn owner(&self) -> u32 {
        self.a
    }
}

impl PartialEq for Ev {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Ev {}
impl PartialOrd for Ev {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Ev {
    fn cmp(&self, o: &Self) -> Ordering {
        // Ties are rare: compare the rest only on one.
        self.time.total_cmp(&o.time).then_with(|| {
            (self.a, self.b, self.kind, self.ca, self.cb).cmp(&(o.a, o.b, o.kind, o.ca, o.cb))
        })
    }
}

/// What predictions read about a critter, kept compact and contiguous (the critters themselves
/// are large and scattered); refreshed whenever the flight or a hook changes the critter. 48
/// bytes in 2D, one cache line in 3D: what a pair test reads and nothing else.
#[derive(Clone, Copy, Debug, Default)]
struct Body<V: Vector> {
    pos: V,
    vel: V,
    /// The body's own clock: `pos` and `vel` hold at this time.
    t: f64,
    /// The radius of a live disk; NaN for a wall or a dead critter (one test sends those to
    /// the general path).
    radius: f64,
    _align: [V::BodyAlign; 0],
}

/// A shell's centre and its critter's radius: 32 bytes in 3D, aligned so that one is never
/// split between two cache lines (a listing reads one per candidate).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
struct Centre<V>(V, f64);

/// The rest of what the flight knows about a critter (16 bytes: one never straddles two
/// cache lines).
#[derive(Clone, Copy, Debug, Default)]
#[repr(align(16))]
struct Meta {
    /// Accelerates with the flight's gravity (free disks).
    free: bool,
    alive: bool,
    wall: bool,
    /// The critter's rule class (pair rules are looked up by class).
    class: u32,
    /// How many times its flight has changed (collisions, bounces): an event predicted with
    /// another count is stale. Kept here, beside what a validity check reads anyway.
    count: u32,
}

/// The critters in each cell, stored flat: cell `k` owns `stride` entries from
/// `base + k * stride`, its count first, then its members. The stride is a power of two and
/// the first stripe starts on a cache line, so a stripe of 16 entries or fewer is one line and
/// a longer one whole lines, where a vector per cell costs a miss for its header and another
/// for its buffer.
#[derive(Default)]
struct Cells {
    stride: usize,
    /// Where the first stripe starts in `data` (its first cache-line boundary).
    base: usize,
    data: Vec<u32>,
}

/// Entries of `u32` in a cache line.
const LINE_U32: usize = 64 / std::mem::size_of::<u32>();

impl Cells {
    /// Empties `total` cells with room for `cap` members each (or more: the stripes are
    /// rounded up to a power of two).
    fn reset(&mut self, total: usize, cap: usize) {
        self.stride = (cap + 1).next_power_of_two();
        self.data.clear();
        self.data.resize(total * self.stride + LINE_U32, 0);
        let misalign = self.data.as_ptr() as usize % 64 / std::mem::size_of::<u32>();
        self.base = (LINE_U32 - misalign) % LINE_U32;
    }

    /// Where cell `k`'s stripe starts in `data`.
    #[inline]
    fn start(&self, k: usize) -> usize {
        self.base + k * self.stride
    }

    /// The first entry of cell `k`'s stripe, for a prefetch.
    #[inline]
    fn head(&self, k: usize) -> Option<&u32> {
        self.data.get(self.start(k))
    }

    #[inline]
    fn members(&self, k: usize) -> &[u32] {
        let at = self.start(k);
        let n = self.data[at] as usize;
        &self.data[at + 1..at + 1 + n]
    }

    fn push(&mut self, k: usize, a: u32) {
        let at = self.start(k);
        let n = self.data[at] as usize;
        if n + 1 == self.stride {
            self.grow();
            return self.push(k, a);
        }
        self.data[at + 1 + n] = a;
        self.data[at] = n as u32 + 1;
    }

    fn clear(&mut self, k: usize) {
        let at = self.start(k);
        self.data[at] = 0;
    }

    fn remove(&mut self, k: usize, a: u32) {
        let at = self.start(k);
        let n = self.data[at] as usize;
        if let Some(i) = self.data[at + 1..at + 1 + n].iter().position(|&x| x == a) {
            self.data[at + 1 + i] = self.data[at + n];
            self.data[at] = n as u32 - 1;
        }
    }

    /// Doubles every cell's room (a cell filled up: rare, cells are sized for their load).
    fn grow(&mut self) {
        let (old, stride, base) = (std::mem::take(&mut self.data), self.stride, self.base);
        let total = (old.len() - LINE_U32) / stride;
        self.reset(total, 2 * stride - 1);
        for k in 0..total {
            let from = base + k * stride;
            let n = old[from] as usize;
            let dst = self.start(k);
            self.data[dst..dst + 1 + n].copy_from_slice(&old[from..from + 1 + n]);
        }
    }
}

/// Per-world scratch kept between steps so a step allocates nothing once warmed up.
#[derive(Default)]
pub(crate) struct Scratch<V: Vector> {
    body: Vec<Body<V>>,
    meta: Vec<Meta>,
    cell: Vec<u32>,
    /// The coordinates of each critter's cell (`cell` unpacked, saving divisions).
    coord: Vec<[i64; 3]>,
    last: Vec<u32>,
    last_t: Vec<f64>,
    cells: Cells,
    cell_walls: Vec<Vec<u32>>,
    /// Some wall is alive (otherwise `cell_walls` is not read).
    has_walls: bool,
    /// Neighbour shells instead of cell crossings (Smallenburg's scheme): the cells hold each
    /// critter by its shell's centre, `near` lists the critters whose shells overlap, and
    /// leaving the shell is the event that lists again.
    shells: bool,
    /// The shell's thickness: a critter stays within `shell / 2` of its shell's centre.
    shell: f64,
    /// The largest radius the cells and shells are sized for.
    rmax: f64,
    /// At least this `rmax` (set when a hook grew a critter beyond the last flight's).
    least_rmax: f64,
    /// Slower critters predict at the flight's start only if they may meet something (`run`).
    fast: Option<f64>,
    /// With `fast`, at the flight's start: how far each critter can move in it (`reach`), and
    /// whether it may meet something (`may_meet`, found by `mark_who_may_meet`).
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
    /// Each critter's shell centre (its position when it was last listed) and its radius (the
    /// body's, kept equal by `refresh`; NaN for walls and the dead), side by side so that
    /// listing reads one place per candidate.
    center: Vec<Centre<V>>,
    /// When the critter being predicted leaves its shell (`shell_exit`), found before its
    /// pairs and offered after them.
    exit: Option<f64>,
    /// A copy of the neighbour list `predict_all` walks (kept to save allocations).
    partners: Vec<u32>,
    /// The candidates `list_again` gathers from the cells around (kept to save allocations).
    gathered: Vec<u32>,
    /// Each critter's neighbours (`near.members(a)`), symmetric.
    near: Cells,
    /// Each critter's next event.
    heap: Queue<Ev>,
    /// The earliest event found so far by the running `predict_all`.
    cand: Option<Ev>,
    /// Pairs whose hook left them overlapping this step: not handed back at once again.
    stuck: std::collections::HashSet<u64>,
    dims: [usize; 3],
    side: [f64; 3],
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
    best: Vec<Option<Ev>>,
    acc: V,
    /// No acceleration: every flight is a straight line.
    straight: bool,
    t_end: f64,
    tc: f64,
    budget: u64,
    predictions: u64,
    pair_tests: u64,
    /// Sum over default collisions of contact distance x impulse (the collision virial).
    pub virial: f64,
    /// The flight kept for the next step, if it may go on.
    kept: Option<Kept>,
    /// The flight time the last flight ended at.
    clock: f64,
    /// A hook grew a critter beyond the cells in this step (the flight was set up again).
    grew: bool,
    /// The critters changed between two steps of a kept flight (kept to save allocations).
    changed: Vec<u32>,
    /// The step at which the last event step that could have kept its flight could not, or had
    /// to predict more than [`CHURN`] of its critters again: something outside the flight
    /// changes critters every step (hooks steering them, spawns), and the kept flight does not
    /// pay (`auto` reads it). `None` when the last such step kept its flight.
    churned_at: Option<u64>,
}

/// The fraction of the critters a kept flight may have to predict again at a step's start and
/// still count as kept ([`Scratch::churned`]).
pub const CHURN: f64 = 0.125;

impl<V: Vector> Scratch<V> {
    /// Whether an event step since the last step set up on schedule (the last multiple of
    /// [`FLIGHT_STEPS`] at or before `step`) found its flight churned (see the field). Nothing
    /// before that step counts, so that a run restored there chooses the same.
    pub(crate) fn churned(&self, step: u64) -> bool {
        self.churned_at
            .is_some_and(|at| at >= step - step % FLIGHT_STEPS)
    }
}

/// What lets a kept flight go on at the next step.
#[derive(Clone, Copy, Debug)]
struct Kept {
    /// The number of the step that may take it up.
    step: u64,
    /// The step's length it was flown with.
    dt: f64,
}

/// Flies the world's critters for `t_end` under acceleration `acc` (free critters only),
/// processing every event in order. Returns `None` when every event was processed, or the time
/// the event budget ran out, where the critters were stopped (the caller finishes the step).
///
/// `fast`: when set, a critter that moves less than it in the flight predicts at the start only
/// if it may meet something along its line (`may_meet`); otherwise it joins in when a collision
/// changes its flight. The events are the same as when everyone predicts.
pub(crate) fn run<V: Vector>(
    world: &mut State<V>,
    sc: &mut Scratch<V>,
    acc: V,
    t_end: f64,
    fast: Option<f64>,
    keep: bool,
    stats: &mut StepStats,
) -> Result<Option<f64>, Error> {
    sc.fast = fast;
    sc.grew = false;
    let step = world.step_count;
    // Kept only for straight flights in which everyone predicts (a curved prediction would have
    // to look steps ahead; a slow critter that predicts nothing would miss later steps' events).
    let keep = keep && fast.is_none() && acc.length_squared() == 0.0;
    #[cfg(test)]
    let keep = keep && !sc.no_keep;
    let kept = sc
        .kept
        .take()
        .filter(|k| keep && k.step == step && k.dt == t_end && !step.is_multiple_of(FLIGHT_STEPS));
    let out = match kept {
        Some(_) => match resume(world, sc, t_end, step) {
            Ok(true) => fly_on(world, sc, acc, t_end, stats),
            Ok(false) => {
                sc.churned_at = Some(step);
                run_with(world, sc, acc, t_end, life(keep, step), stats)
            }
            Err(e) => Err(e),
        },
        None => run_with(world, sc, acc, t_end, life(keep, step), stats),
    };
    if keep && !sc.grew && matches!(out, Ok(None)) && !(step + 1).is_multiple_of(FLIGHT_STEPS) {
        sc.kept = Some(Kept {
            step: step + 1,
            dt: t_end,
        });
    } else {
        sc.kept = None;
        sc.heap.reset(0, 0.0, 0.0);
    }
    out
}

/// The steps a flight set up at step `step` may live (to the next multiple of [`FLIGHT_STEPS`]),
/// or 1 when it is not kept.
fn life(keep: bool, step: u64) -> u64 {
    if keep {
        FLIGHT_STEPS - step % FLIGHT_STEPS
    } else {
        1
    }
}

/// A kept flight flown on for one more step of `span`, from where the last one ended.
fn fly_on<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    acc: V,
    span: f64,
    stats: &mut StepStats,
) -> Result<Option<f64>, Error> {
    let start = sc.clock;
    match fly(w, sc, acc, Some(start), span, 1, stats)? {
        Flight::Done(stopped) => Ok(stopped),
        Flight::Grown(t) => {
            // The rest of the step in new flights, sized for the grown critter.
            let virial = sc.virial;
            let rest = run_with(w, sc, acc, span - t, 1, stats);
            sc.virial += virial;
            sc.grew = true;
            Ok(rest?.map(|r| t + r))
        }
    }
}

/// Flies the critters to `t_end`, in one flight unless a hook grows a critter beyond the largest
/// radius the flight's cells (or shells) were sized for: the flight then stops there, everyone
/// is brought to that time, and a new flight, sized for the grown critter, flies the rest.
fn run_with<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    acc: V,
    t_end: f64,
    life: u64,
    stats: &mut StepStats,
) -> Result<Option<f64>, Error> {
    sc.least_rmax = 0.0;
    let (mut flown, mut virial) = (0.0, 0.0);
    loop {
        // A flight set up again after a critter grew lives to the step's end only.
        let life = if flown == 0.0 { life } else { 1 };
        let outcome = fly(w, sc, acc, None, t_end - flown, life, stats);
        virial += sc.virial;
        sc.virial = virial;
        match outcome? {
            Flight::Done(stopped) => return Ok(stopped.map(|t| flown + t)),
            Flight::Grown(t) => {
                sc.grew = true;
                flown += t
            }
        }
    }
}

/// How a flight ended.
enum Flight {
    /// At its end, or where the event budget ran out (the time everyone is at).
    Done(Option<f64>),
    /// At this time, because a hook grew a critter beyond what the cells were sized for.
    Grown(f64),
}

/// Flies for `span` from flight time `from` (a kept flight that `resume` took up), or sets up a
/// new flight whose predictions look `life` steps of `span` ahead and flies it from 0.
fn fly<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    acc: V,
    from: Option<f64>,
    span: f64,
    life: u64,
    stats: &mut StepStats,
) -> Result<Flight, Error> {
    let n = w.critters.slot_count() as u32;
    let start = match from {
        Some(t) => t,
        None => {
            // A little past the life's last step's end, whatever the rounding of the steps'
            // sums of dt.
            let horizon = if life > 1 {
                span * life as f64 * (1.0 + 1e-9)
            } else {
                span
            };
            setup(w, sc, acc, span, horizon);
            match sc.fast {
                Some(limit) => {
                    mark_who_may_meet(w, sc);
                    for a in 0..n {
                        if sc.reach[a as usize] > limit || sc.meets[a as usize] {
                            predict_all(w, sc, a, 0.0)?;
                        }
                    }
                }
                None => {
                    for a in 0..n {
                        predict_all(w, sc, a, 0.0)?;
                    }
                }
            }
            0.0
        }
    };
    let t_end = start + span; // (exactly `span` for a new flight, which starts at 0)
    let mut processed = 0u64;
    let mut stopped = None;
    let mut grown = None;
    // Every branch below predicts the event's owner again (which replaces the event in the
    // queue) or removes the event.
    while let Some(ev) = sc.heap.peek_until(t_end) {
        if ev.time > t_end {
            break;
        }
        match validity(sc, &ev) {
            Validity::Stale => {
                sc.heap.remove(ev.a);
                continue;
            }
            Validity::PartnerChanged => {
                predict_all(w, sc, ev.a, ev.time)?;
                continue;
            }
            Validity::Valid => {}
        }
        processed += 1;
        if processed > sc.budget {
            stopped = Some(ev.time);
            break;
        }
        let t = ev.time;
        if sc.shells {
            // What the predictions after this event read: the bodies of both critters'
            // neighbours, asked for before the collision's own work; and what the next event
            // most likely reads. (A large gas's loads are scattered: this measured 1.2x in
            // the 32,000-sphere gas. Cells are left as they were: it cost 2D gases time.)
            for x in [ev.a, ev.b] {
                if ev.kind == PAIR || x == ev.a {
                    for &p in sc.near.members(x as usize) {
                        crate::prefetch::prefetch(sc.body.get(p as usize));
                    }
                }
            }
            if let Some(next) = sc.heap.runner_up() {
                prefetch_event(w, sc, &next);
            }
        }
        match ev.kind {
            PAIR | WALL => {
                advance(w, sc, ev.a, t);
                advance(w, sc, ev.b, t);
                stats.contacts += 1;
                let deaths = w.pending.deaths.len();
                if collide(w, sc, ev.a, ev.b, t)? {
                    stats.collisions += 1;
                }
                // A hook may kill third critters: their bodies must know.
                for i in deaths..w.pending.deaths.len() {
                    let x = w.pending.deaths[i].index;
                    refresh(w, sc, x);
                }
                if let (Some(x), Some(y)) = (w.critters.slot(ev.a), w.critters.slot(ev.b)) {
                    if x.alive && y.alive {
                        if let Some(c) = crate::response::contact_between(&w.topo, x, y) {
                            if c.depth > SKIN * x.radius.min(y.radius) * 4.0 {
                                sc.stuck.insert(pair_key(ev.a, ev.b));
                            }
                        }
                    }
                }
                sc.last[ev.a as usize] = ev.b;
                sc.last_t[ev.a as usize] = t;
                if ev.kind == PAIR {
                    sc.last[ev.b as usize] = ev.a;
                    sc.last_t[ev.b as usize] = t;
                }
                for x in [ev.a, ev.b] {
                    if w.critters.slot(x).is_some_and(|c| !c.is_wall()) {
                        let m = &mut sc.meta[x as usize];
                        m.count = m.count.wrapping_add(1);
                        relocate(w, sc, x);
                        refresh(w, sc, x);
                    }
                }
                // A radius (NaN for walls and the dead) beyond what the cells were sized for:
                // neighbours it now reaches may lie outside the cells it scans. Cells sized for
                // twice the new radius make many restarts in one flight unlikely.
                let radius = |x: u32| sc.body[x as usize].radius;
                let largest = radius(ev.a).max(radius(ev.b));
                if largest > sc.rmax {
                    sc.least_rmax = 2.0 * largest;
                    grown = Some(t);
                    break;
                }
                for x in [ev.a, ev.b] {
                    predict_all(w, sc, x, t)?;
                }
            }
            BORDER => {
                advance(w, sc, ev.a, t);
                bounce_border(w, ev.a, ev.b);
                refresh(w, sc, ev.a);
                sc.last[ev.a as usize] = BORDER_TAG + ev.b;
                let m = &mut sc.meta[ev.a as usize];
                m.count = m.count.wrapping_add(1);
                predict_all(w, sc, ev.a, t)?;
            }
            CELL => {
                cross_cell(w, sc, ev.a, ev.b, t);
                refresh(w, sc, ev.a);
                predict_after_crossing(w, sc, ev.a, ev.b, t)?;
            }
            SHELL => {
                advance(w, sc, ev.a, t);
                list_again(w, sc, ev.a);
                predict_all(w, sc, ev.a, t)?;
            }
            _ => {
                // RECHECK: continue a curved prediction that did not settle.
                predict_all(w, sc, ev.a, t)?;
            }
        }
    }
    stats.events += processed.min(sc.budget);
    stats.pair_tests += sc.pair_tests;
    stats.candidates += sc.predictions as usize;
    // Everyone to the end of the flight.
    let end = grown.or(stopped).unwrap_or(t_end);
    sc.clock = end;
    let topo = w.topo;
    for a in 0..n {
        advance(w, sc, a, end);
        if let Some(c) = w.critters.slot_mut_moving(a) {
            if c.alive && !c.is_wall() {
                c.pos = if topo.wraps() {
                    topo.wrap_position(c.pos)
                } else {
                    topo.apply(c.pos, c.vel, c.radius, c.restitution()).0
                };
            }
        }
    }
    Ok(match grown {
        Some(t) => Flight::Grown(t - start),
        None => Flight::Done(stopped.map(|t| t - start)),
    })
}

/// Takes up the flight kept from the last step, for a step of `span` from where it ended:
/// every critter that something outside the flight changed since (its position or velocity is
/// not its body's) is counted as changed (its partners' events with it go stale), put in its
/// cell and predicted again, as after a collision (and the flight counted churned at `step`
/// when they are more than [`CHURN`] of the disks). Returns false, having changed nothing, when
/// the flight cannot go on (the caller counts that as churned): a critter came or went, changed
/// size, class or mobility, or a wall moved; the step then sets up a new flight.
fn resume<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    span: f64,
    step: u64,
) -> Result<bool, Error> {
    let n = w.critters.slot_count();
    if n != sc.body.len() {
        return Ok(false);
    }
    let start = sc.clock;
    let mut changed = std::mem::take(&mut sc.changed);
    changed.clear();
    let mut disks = 0usize;
    for (a, slot) in w.critters.slot_slice().iter().enumerate() {
        let (body, meta) = (&sc.body[a], &sc.meta[a]);
        let Some(c) = slot else {
            if meta.alive {
                sc.changed = changed;
                return Ok(false);
            }
            continue;
        };
        let same = c.alive == meta.alive
            && c.is_wall() == meta.wall
            && (!c.alive
                || if c.is_wall() {
                    c.pos == body.pos
                } else {
                    c.radius == body.radius && c.class == meta.class && c.fixed != meta.free
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
    sc.heap.rebase(start, start + 2.0 * span);
    for &a in &changed {
        sc.body[a as usize].t = start;
        let m = &mut sc.meta[a as usize];
        m.count = m.count.wrapping_add(1);
        relocate(w, sc, a);
        refresh(w, sc, a);
    }
    let out = changed
        .iter()
        .try_for_each(|&a| predict_all(w, sc, a, start));
    sc.changed = changed;
    out.map(|()| true)
}

/// Sets up a new flight for a step of `span`, its predictions looking to `horizon`.
#[allow(clippy::needless_range_loop)] // per-axis arrays indexed together
fn setup<V: Vector>(w: &mut State<V>, sc: &mut Scratch<V>, acc: V, span: f64, horizon: f64) {
    let n = w.critters.slot_count();
    // A kept flight's calendar covers two steps (see `resume`).
    sc.heap
        .reset(n, 0.0, if horizon > span { 2.0 * span } else { span });
    sc.stuck.clear();
    for v in [&mut sc.cell, &mut sc.last] {
        v.clear();
        v.resize(n, NONE);
    }
    let mut rmax: f64 = 0.0;
    let mut disks = 0usize;
    sc.has_walls = false;
    for c in w.critters.iter_mut_moving() {
        if c.class == CLASS_UNSET {
            c.class = w.rules.class_of(&w.kinds, c);
        }
        if c.alive && !c.is_wall() {
            rmax = rmax.max(c.radius);
            disks += 1;
        }
        sc.has_walls |= c.alive && c.is_wall();
    }
    rmax = rmax.max(sc.least_rmax);
    sc.rmax = rmax;
    sc.coord.clear();
    sc.coord.resize(n, [0; 3]);
    sc.body.clear();
    sc.body.resize(n, Body::default());
    sc.meta.clear();
    sc.meta.resize(n, Meta::default());
    for a in 0..n as u32 {
        refresh(w, sc, a);
    }
    sc.last_t.clear();
    sc.last_t.resize(n, f64::NEG_INFINITY);
    sc.straight = acc.length_squared() == 0.0;
    sc.acc = if sc.straight { V::zero() } else { acc };
    sc.t_end = horizon;
    sc.tc = TC_FRACTION * w.dt;
    sc.virial = 0.0;
    sc.predictions = 0;
    sc.pair_tests = 0;
    sc.budget = BUDGET_PER_CRITTER * disks as u64 + 10_000;
    // Shells pay where a cell's neighbourhood is large (27 cells) and flights are lines.
    sc.shells = sc.straight && !sc.has_walls && V::DIM == 3 && disks > 0 && sc.fast.is_none();
    #[cfg(test)]
    {
        sc.shells &= !sc.no_shells;
    }
    sc.shell = if sc.shells {
        SHELL_FRACTION * 2.0 * rmax
    } else {
        0.0
    };
    // Cells at least one diameter (and a shell) wide, at most about 2 per disk. Critters that do
    // not predict never cross cells: a slow one may end up `fast` out of its cell, and two slow
    // ones that meet were up to a diameter and twice `fast` apart (`may_meet` looks one cell
    // around).
    let size = w.topo.size();
    let dim = V::DIM;
    let slack = sc.shell + 2.0 * sc.fast.unwrap_or(0.0);
    let want = (2.0 * rmax * (1.0 + 1e-9) + slack * (1.0 + 1e-9)).max(f64::MIN_POSITIVE);
    let mut dims = [1usize; 3];
    for axis in 0..dim {
        dims[axis] = ((size.get(axis) / want).floor() as usize).clamp(1, 1 << 20);
    }
    // Over the cap, every axis is scaled down by one factor to just under it (halving every
    // axis, as before, could leave a quarter of the cap in 2D and an eighth in 3D: cells twice
    // as wide as needed, four or eight times the candidates per prediction).
    let cap = (2 * disks).max(27);
    let total = dims[..dim].iter().product::<usize>();
    if total > cap {
        let scale = (cap as f64 / total as f64).powf(1.0 / dim as f64);
        for d in dims[..dim].iter_mut() {
            *d = ((*d as f64 * scale).floor() as usize).max(1);
        }
        // Round-off in the scale: take one cell off the widest axis until under the cap.
        while dims[..dim].iter().product::<usize>() > cap {
            let widest = (0..dim).max_by_key(|&ax| dims[ax]).unwrap_or(0);
            dims[widest] = (dims[widest] - 1).max(1);
        }
    }
    for axis in 0..3 {
        sc.side[axis] = if axis < dim {
            size.get(axis) / dims[axis] as f64
        } else {
            1.0
        };
    }
    sc.dims = dims;
    sc.offsets.clear();
    sc.forward.clear();
    sc.front.iter_mut().for_each(Vec::clear);
    sc.best.clear();
    sc.best.resize(n, None);
    if dims[..dim].iter().all(|&n| n >= 3) {
        let reach = |axis: usize| if axis < dim { -1..=1isize } else { 0..=0 };
        let (nx, nxy) = (dims[0] as isize, (dims[0] * dims[1]) as isize);
        for dz in reach(2) {
            for dy in reach(1) {
                for dx in reach(0) {
                    let o = dx + nx * dy + nxy * dz;
                    sc.offsets.push(o);
                    if o > 0 {
                        sc.forward.push(o);
                    }
                    for (axis, d) in [dx, dy, dz].into_iter().enumerate() {
                        if d != 0 {
                            sc.front[axis * 2 + usize::from(d > 0)].push(o);
                        }
                    }
                }
            }
        }
    }
    let total: usize = dims[..dim].iter().product();
    // Room for the fullest cell now, and some.
    let mut load = std::mem::take(&mut sc.cells.data);
    load.clear();
    load.resize(total, 0);
    for c in w.critters.iter() {
        if c.alive && !c.is_wall() {
            let (k, cc) = cell_of(w, sc, c.pos);
            debug_assert_eq!(coords(&dims, k), cc, "cell {k}'s coordinates");
            sc.cell[c.id.index as usize] = k as u32;
            sc.coord[c.id.index as usize] = cc;
            load[k] += 1;
        }
    }
    let fullest = load.iter().copied().max().unwrap_or(0) as usize;
    sc.cells.data = load;
    sc.cells.reset(total, (fullest + 2).max(7));
    sc.cell_walls.iter_mut().for_each(Vec::clear);
    sc.cell_walls
        .resize_with(if sc.has_walls { total } else { 0 }, Vec::new);
    for c in w.critters.iter() {
        if !c.alive {
            continue;
        }
        match c.shape() {
            Shape::Disk => {
                let k = sc.cell[c.id.index as usize] as usize;
                sc.cells.push(k, c.id.index);
            }
            Shape::Wall(wall) => {
                // Every cell a disk centre could be in while touching the wall.
                let half = wall.aabb_half() + V::splat(rmax + 1e-9 * rmax);
                let mut lo = [0i64; 3];
                let mut hi = [0i64; 3];
                for axis in 0..dim {
                    let m = w.topo.min.get(axis);
                    let s = sc.side[axis];
                    lo[axis] = ((c.pos.get(axis) - half.get(axis) - m) / s).floor() as i64;
                    hi[axis] = ((c.pos.get(axis) + half.get(axis) - m) / s).floor() as i64;
                    let n = dims[axis] as i64;
                    if w.topo.wraps() {
                        if hi[axis] - lo[axis] + 1 >= n {
                            lo[axis] = 0;
                            hi[axis] = n - 1;
                        }
                    } else {
                        lo[axis] = lo[axis].clamp(0, n - 1);
                        hi[axis] = hi[axis].clamp(0, n - 1);
                    }
                }
                for z in lo[2]..=hi[2] {
                    for y in lo[1]..=hi[1] {
                        for x in lo[0]..=hi[0] {
                            let k = key(&dims, [x, y, z]);
                            sc.cell_walls[k].push(c.id.index);
                        }
                    }
                }
            }
        }
    }
    if sc.shells {
        list_all(w, sc);
    }
}

/// How far critter `a` can move in the flight, at most.
#[inline]
fn reach<V: Vector>(sc: &Scratch<V>, a: u32) -> f64 {
    let t = sc.t_end;
    sc.body[a as usize].vel.length() * t + 0.5 * sc.acc.length() * t * t
}

/// Whether slow critter `a` may meet anything in the flight if nobody's flight changes: a disk,
/// a wall or a bounding border within reach of both. (A critter that meets nothing needs no
/// prediction until a collision changes a flight, and then the changed critter predicts.)
/// The flight asks [`mark_who_may_meet`], which gives the same answers pair by pair; this is
/// its definition, which the tests compare it with.
#[cfg(test)]
fn may_meet<V: Vector>(w: &State<V>, sc: &Scratch<V>, a: u32) -> bool {
    let body = sc.body[a as usize];
    if body.radius.is_nan() {
        return false;
    }
    let mine = reach(sc, a);
    if near_border(w, body, mine) || (sc.has_walls && near_a_wall(w, sc, a, mine)) {
        return true;
    }
    let mut around = [0usize; 27];
    let count = cells_around(w, sc, a, &mut around);
    for &k in &around[..count] {
        for &b in sc.cells.members(k) {
            let other = sc.body[b as usize];
            if b == a || other.radius.is_nan() {
                continue;
            }
            let near = body.radius + other.radius + mine + reach(sc, b);
            if w.topo.delta(body.pos, other.pos).length_squared() <= near * near {
                return true;
            }
        }
    }
    false
}

/// Whether a disk `body` that moves up to `mine` may reach a bounding border.
#[inline]
fn near_border<V: Vector>(w: &State<V>, body: Body<V>, mine: f64) -> bool {
    if w.topo.border == Border::Wrap {
        return false;
    }
    (0..V::DIM).any(|axis| {
        let x = body.pos.get(axis);
        let room = (x - w.topo.min.get(axis)).min(w.topo.max.get(axis) - x);
        room <= body.radius + mine
    })
}

/// Whether disk `a`, moving up to `mine`, may reach a wall listed in the cells around its own.
fn near_a_wall<V: Vector>(w: &State<V>, sc: &Scratch<V>, a: u32, mine: f64) -> bool {
    let body = sc.body[a as usize];
    let mut around = [0usize; 27];
    let count = cells_around(w, sc, a, &mut around);
    for &k in &around[..count] {
        for &x in &sc.cell_walls[k] {
            let Some(c) = w.critters.slot(x) else {
                continue;
            };
            let Shape::Wall(wall) = c.shape() else {
                continue;
            };
            let d = w.topo.delta(c.pos, body.pos);
            if c.alive && contact_wall_ball(wall, d, body.radius + mine).is_some() {
                return true;
            }
        }
    }
    false
}

/// Fills `sc.reach` and `sc.meets` at the flight's start: `meets[a]` is exactly `may_meet(a)`,
/// found pair by pair over the cells instead of critter by critter (each pair of neighbouring
/// cells read once, in cell order, each pair of disks tested once for both of its disks, each
/// side with `may_meet`'s own arithmetic), and the walls asked only by disks whose cell has a
/// wall around it.
fn mark_who_may_meet<V: Vector>(w: &State<V>, sc: &mut Scratch<V>) {
    let n = sc.body.len();
    let mut reaches = std::mem::take(&mut sc.reach);
    reaches.clear();
    reaches.extend((0..n as u32).map(|a| reach(sc, a)));
    let mut meets = std::mem::take(&mut sc.meets);
    meets.clear();
    meets.resize(n, false);
    let dims = sc.dims;
    let total: usize = dims[..V::DIM].iter().product();
    let mut near_wall = std::mem::take(&mut sc.near_wall);
    near_wall.clear();
    near_wall.resize(total, false);
    let mut around = [0usize; 27];
    if sc.has_walls {
        for k in 0..total {
            if !sc.cell_walls[k].is_empty() {
                let count = cells_around_cell(w, sc, coords(&dims, k), &mut around);
                for &j in &around[..count] {
                    near_wall[j] = true;
                }
            }
        }
    }
    for a in 0..n {
        let body = sc.body[a];
        if body.radius.is_nan() {
            continue;
        }
        let mine = reaches[a];
        meets[a] = near_border(w, body, mine)
            || (near_wall[sc.cell[a] as usize] && near_a_wall(w, sc, a as u32, mine));
    }
    // Disks in neighbouring cells. Cells off the grid's edges pair with the cells after them
    // (`forward`, each pair of cells once); the others with every cell around them.
    let mut pair = |a: u32, b: u32| {
        let (ba, bb) = (sc.body[a as usize], sc.body[b as usize]);
        if ba.radius.is_nan() || bb.radius.is_nan() {
            return;
        }
        let (ra, rb) = (reaches[a as usize], reaches[b as usize]);
        // `delta` is odd in its arguments bit for bit, so one squared distance serves both.
        let d2 = w.topo.delta(ba.pos, bb.pos).length_squared();
        let near_a = ba.radius + bb.radius + ra + rb;
        let near_b = bb.radius + ba.radius + rb + ra;
        if d2 <= near_a * near_a {
            meets[a as usize] = true;
        }
        if d2 <= near_b * near_b {
            meets[b as usize] = true;
        }
    };
    // The cells in key order, their coordinates counted along (no divisions).
    let cells = (0..dims[2]).flat_map(|z| {
        (0..dims[1]).flat_map(move |y| (0..dims[0]).map(move |x| [x as i64, y as i64, z as i64]))
    });
    for (k, hc) in cells.enumerate() {
        let mine = sc.cells.members(k);
        if mine.is_empty() {
            continue;
        }
        if interior_at::<V>(sc, hc) {
            for (i, &a) in mine.iter().enumerate() {
                for &b in &mine[i + 1..] {
                    pair(a, b);
                }
            }
            for &o in &sc.forward {
                let theirs = sc.cells.members((k as isize + o) as usize);
                for &a in mine {
                    for &b in theirs {
                        pair(a, b);
                    }
                }
            }
        } else {
            let count = cells_around_cell(w, sc, hc, &mut around);
            for &j in &around[..count] {
                for &a in mine {
                    for &b in sc.cells.members(j) {
                        if a != b {
                            pair(a, b);
                        }
                    }
                }
            }
        }
    }
    sc.reach = reaches;
    sc.meets = meets;
    sc.near_wall = near_wall;
}

/// Lists every pair whose shells overlap (at the start of a flight, every shell is centred on
/// its critter).
fn list_all<V: Vector>(w: &State<V>, sc: &mut Scratch<V>) {
    let n = sc.body.len();
    sc.center.clear();
    sc.center
        .extend(sc.body.iter().map(|b| Centre(b.pos, b.radius)));
    // Room for the neighbours a random fluid at close packing would give, and some.
    sc.near.reset(n, 24);
    let mut around = [0usize; 27];
    for a in 0..n as u32 {
        if sc.body[a as usize].radius.is_nan() {
            continue;
        }
        let count = cells_around(w, sc, a, &mut around);
        for &k in &around[..count] {
            for &b in sc.cells.members(k) {
                if b > a && shells_overlap(&w.topo, &sc.center, sc.shell, a, b) {
                    sc.near.push(a as usize, b);
                    sc.near.push(b as usize, a);
                }
            }
        }
    }
}

/// Whether the shells of `a` and `b` (a live disk) overlap: only such pairs can touch before
/// one of them leaves its shell. Takes the flight's fields rather than the flight, so that the
/// listing can push to `near` while it walks `cells`.
#[inline]
fn shells_overlap<V: Vector>(
    topo: &Topology<V>,
    center: &[Centre<V>],
    shell: f64,
    a: u32,
    b: u32,
) -> bool {
    let (Centre(ca, ra), Centre(cb, rb)) = (center[a as usize], center[b as usize]);
    // (A NaN radius, a wall's or the dead's, makes `reach` NaN and the test false.)
    let reach = (ra + rb + shell) * (1.0 + 1e-9);
    topo.delta(ca, cb).length_squared() < reach * reach
}

/// The keys of the cells around `a`'s cell (its own included), each once (at the grid's edges
/// they are wrapped or cut at the border, and with fewer than three cells along an axis they
/// repeat); their number.
fn cells_around<V: Vector>(w: &State<V>, sc: &Scratch<V>, a: u32, out: &mut [usize; 27]) -> usize {
    let home = sc.cell[a as usize] as usize;
    if interior::<V>(sc, a) {
        for (o, k) in sc.offsets.iter().zip(out.iter_mut()) {
            *k = (home as isize + o) as usize;
        }
        return sc.offsets.len();
    }
    cells_around_cell(w, sc, sc.coord[a as usize], out)
}

/// [`cells_around`] the cell at coordinates `hc`, by the general path (wrapped or cut at the
/// grid's edges, each once).
fn cells_around_cell<V: Vector>(
    w: &State<V>,
    sc: &Scratch<V>,
    hc: [i64; 3],
    out: &mut [usize; 27],
) -> usize {
    let dims = sc.dims;
    let mut count = 0;
    let span = |axis: usize| if axis < V::DIM { -1..=1 } else { 0..=0 };
    for dz in span(2) {
        for dy in span(1) {
            for dx in span(0) {
                let cc = [hc[0] + dx, hc[1] + dy, hc[2] + dz];
                if !w.topo.wraps() && (0..V::DIM).any(|ax| cc[ax] < 0 || cc[ax] >= dims[ax] as i64)
                {
                    continue;
                }
                let k = key(&dims, cc);
                if !out[..count].contains(&k) {
                    out[count] = k;
                    count += 1;
                }
            }
        }
    }
    count
}

/// Lists `a` again, centring its shell on where it is now (its body holds now): it empties its
/// list, moves to the cell of its new centre, and lists the critters whose shells overlap the
/// new one (and joins their lists). Its flight is unchanged, so no event is made stale.
fn list_again<V: Vector>(w: &mut State<V>, sc: &mut Scratch<V>, a: u32) {
    let ai = a as usize;
    // The old neighbours keep `a` in their lists until they list again themselves: a pair
    // test too many costs less than finding `a` in every old list.
    sc.near.clear(ai);
    let old = sc.cell[ai] as usize;
    if sc.body[ai].radius.is_nan() {
        sc.cells.remove(old, a);
        return;
    }
    let mut p = sc.body[ai].pos;
    if w.topo.wraps() {
        let q = w.topo.wrap_position(p);
        if q != p {
            p = q;
            sc.body[ai].pos = p;
            if let Some(c) = w.critters.slot_mut_moving(a) {
                c.pos = p;
            }
        }
    }
    sc.center[ai] = Centre(p, sc.body[ai].radius);
    let (new, cc) = cell_of(w, sc, p);
    move_cell(sc, a, old, new, cc);
    let mut around = [0usize; 27];
    let count = cells_around(w, sc, a, &mut around);
    // The loads are scattered, so each stage asks for what the next one reads before it
    // reads any: the cells' stripes, then the candidates' shell centres (with their radii),
    // then the new neighbours' lists.
    use crate::prefetch::prefetch;
    for &k in &around[..count] {
        prefetch(sc.cells.head(k));
    }
    let mut gathered = std::mem::take(&mut sc.gathered);
    gathered.clear();
    for &k in &around[..count] {
        gathered.extend_from_slice(sc.cells.members(k));
    }
    for &b in &gathered {
        prefetch(sc.center.get(b as usize));
    }
    // The candidates kept in place, without a branch on each (about one in seven is kept, in
    // no order a processor can predict).
    let mut kept = 0;
    for i in 0..gathered.len() {
        let b = gathered[i];
        let hit = (b != a) & shells_overlap(&w.topo, &sc.center, sc.shell, a, b);
        gathered[kept] = b;
        kept += usize::from(hit);
    }
    gathered.truncate(kept);
    for &b in &gathered {
        prefetch(sc.near.head(b as usize));
    }
    for &b in &gathered {
        sc.near.push(ai, b);
    }
    // `a`'s new neighbours, each joined by `a` unless it kept `a` from before.
    // (By index: a push may grow the stripes and move `a`'s.)
    for j in 0..sc.near.members(ai).len() {
        let b = sc.near.members(ai)[j] as usize;
        if !sc.near.members(b).contains(&a) {
            sc.near.push(b, a);
        }
    }
    sc.gathered = gathered;
}

/// Offers `a` leaving its shell, as `predict_all` found it (`Scratch::exit`).
#[inline]
fn predict_shell<V: Vector>(sc: &mut Scratch<V>, a: u32) {
    if let Some(at) = sc.exit.take() {
        push(sc, at, a, 0, SHELL);
    }
}

/// The time straight-flying `a` (`mine`: its position and velocity at `t`) leaves its shell,
/// if that is within the flight.
#[inline]
fn shell_exit<V: Vector>(
    w: &State<V>,
    sc: &Scratch<V>,
    a: u32,
    t: f64,
    mine: (V, V, V),
) -> Option<f64> {
    let (p, v, _) = mine;
    let d = w.topo.delta(sc.center[a as usize].0, p);
    let h = 0.5 * sc.shell;
    let c = d.length_squared() - h * h;
    let s = if c >= 0.0 {
        0.0
    } else {
        let (qa, qb) = (v.length_squared(), d.dot(v));
        if qa == 0.0 {
            return None;
        }
        // The positive root; c < 0, so -c / (b + sqrt(disc)) when b > 0 avoids cancellation.
        let root = (qb * qb - qa * c).sqrt();
        if qb > 0.0 {
            -c / (qb + root)
        } else {
            (root - qb) / qa
        }
    };
    (t + s <= sc.t_end).then_some(t + s)
}

#[inline]
fn key(dims: &[usize; 3], c: [i64; 3]) -> usize {
    let m = |i: i64, n: usize| {
        let n = n as i64;
        (if i < 0 {
            i + n
        } else if i >= n {
            i - n
        } else {
            i
        }) as usize
    };
    m(c[0], dims[0]) + dims[0] * (m(c[1], dims[1]) + dims[1] * m(c[2], dims[2]))
}

fn coords(dims: &[usize; 3], k: usize) -> [i64; 3] {
    [
        (k % dims[0]) as i64,
        ((k / dims[0]) % dims[1]) as i64,
        (k / (dims[0] * dims[1])) as i64,
    ]
}

/// The cell of position `p`: its key and its coordinates (kept beside the key, which would
/// take three divisions to unpack).
fn cell_of<V: Vector>(w: &State<V>, sc: &Scratch<V>, p: V) -> (usize, [i64; 3]) {
    let mut c = [0i64; 3];
    for (axis, ca) in c.iter_mut().enumerate().take(V::DIM) {
        let x = ((p.get(axis) - w.topo.min.get(axis)) / sc.side[axis]).floor() as i64;
        *ca = x.clamp(0, sc.dims[axis] as i64 - 1);
    }
    (key(&sc.dims, c), c)
}

/// Copies critter `a` into its body (after the flight or a hook changed it).
#[inline]
fn refresh<V: Vector>(w: &State<V>, sc: &mut Scratch<V>, a: u32) {
    // Field by field into place: a body built whole on the stack and copied was read back
    // across two of its stores (a stall on every collision).
    let (body, meta) = (&mut sc.body[a as usize], &mut sc.meta[a as usize]);
    match w.critters.slot(a) {
        Some(c) => {
            body.pos = c.pos;
            body.vel = c.vel;
            body.radius = if c.alive && !c.is_wall() {
                c.radius
            } else {
                f64::NAN
            };
            meta.free = !c.fixed && !c.is_wall();
            meta.alive = c.alive;
            meta.wall = c.is_wall();
            meta.class = c.class;
        }
        None => {
            *body = Body {
                radius: f64::NAN,
                ..Body::default()
            };
            *meta = Meta {
                count: meta.count,
                ..Meta::default()
            };
        }
    }
    let radius = body.radius;
    if let Some(c) = sc.center.get_mut(a as usize) {
        c.1 = radius; // (unread without shells)
    }
}

/// Position, velocity and acceleration of body `a` at time `t` (its own clock is `body.t`).
#[inline(always)]
fn state_at<V: Vector>(sc: &Scratch<V>, a: u32, t: f64) -> (V, V, V) {
    let b = &sc.body[a as usize];
    if sc.straight {
        // A line: no zero acceleration to multiply and add (a pair test's most common call).
        return (b.pos + b.vel * (t - b.t), b.vel, V::zero());
    }
    let acc = if !sc.meta[a as usize].free {
        V::zero()
    } else {
        sc.acc
    };
    let h = t - b.t;
    if h == 0.0 {
        return (b.pos, b.vel, acc);
    }
    (
        b.pos + b.vel * h + acc * (0.5 * h * h),
        b.vel + acc * h,
        acc,
    )
}

fn advance<V: Vector>(w: &mut State<V>, sc: &mut Scratch<V>, a: u32, t: f64) {
    let m = sc.meta[a as usize];
    if !m.alive || m.wall {
        return;
    }
    let (p, v, _) = state_at(sc, a, t);
    let body = &mut sc.body[a as usize];
    body.pos = p;
    body.vel = v;
    body.t = t;
    if let Some(c) = w.critters.slot_mut_moving(a) {
        c.pos = p;
        c.vel = v;
    }
}

/// Asks for what processing `ev` will read first (its critters, bodies and neighbour lists:
/// with shells), so that the loads overlap the work on the event before it. Only a hint:
/// nothing is read.
#[inline]
fn prefetch_event<V: Vector>(w: &State<V>, sc: &Scratch<V>, ev: &Ev) {
    use crate::prefetch::prefetch;
    let slots = w.critters.slot_slice();
    for x in [ev.a, ev.b] {
        let x = x as usize;
        prefetch(sc.body.get(x));
        prefetch(sc.center.get(x));
        crate::prefetch::prefetch_whole(slots.get(x));
        prefetch(sc.meta.get(x));
        prefetch(sc.near.head(x));
    }
}

enum Validity {
    Valid,
    /// The owner has changed since: it has a newer event already.
    Stale,
    /// The partner has changed: the owner must predict again.
    PartnerChanged,
}

fn validity<V: Vector>(sc: &Scratch<V>, ev: &Ev) -> Validity {
    let alive = |x: u32| sc.meta[x as usize].alive;
    if !alive(ev.a) || sc.meta[ev.a as usize].count != ev.ca {
        return Validity::Stale;
    }
    let ok = match ev.kind {
        PAIR => alive(ev.b) && sc.meta[ev.b as usize].count == ev.cb,
        WALL => alive(ev.b),
        _ => true,
    };
    if ok {
        Validity::Valid
    } else {
        Validity::PartnerChanged
    }
}

/// Offers an event to the running prediction: each critter keeps only its earliest event in
/// the heap (a stale partner makes it predict again when that event comes up).
#[inline]
fn push(sc: &mut Scratch<impl Vector>, time: f64, a: u32, b: u32, kind: Kind) {
    if sc.cand.is_some_and(|c| time > c.time) {
        return;
    }
    let cb = if kind == PAIR {
        sc.meta.get(b as usize).map_or(0, |m| m.count)
    } else {
        0
    };
    let ev = Ev {
        time,
        a,
        b,
        kind,
        ca: sc.meta[a as usize].count,
        cb,
    };
    if sc.cand.is_none_or(|c| ev < c) {
        sc.cand = Some(ev);
    }
}

/// Predicts every next event of disk `a` from time `t`. `initial`: pairs only with higher slots.
fn predict_all<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    t: f64,
) -> Result<(), Error> {
    let me = sc.meta[a as usize];
    if !me.alive || me.wall {
        sc.heap.remove(a);
        return Ok(());
    }
    sc.cand = None;
    sc.predictions += 1;
    let mine = state_at(sc, a, t);
    // With shells there are no walls, and the cell is not read (a load spared: a miss, as
    // often as not, in a large gas).
    let home = if sc.shells {
        0
    } else {
        sc.cell[a as usize] as usize
    };
    if sc.shells {
        // The list copied out, so the loop does not find it again in `near` for every partner
        // (predicting needs the flight mutably), and the partners' bodies asked for at once.
        let mut partners = std::mem::take(&mut sc.partners);
        partners.clear();
        partners.extend_from_slice(sc.near.members(a as usize));
        for &b in &partners {
            crate::prefetch::prefetch(sc.body.get(b as usize));
        }
        // When `a` leaves its shell: offered last (`finish_prediction`), but a bound for the
        // pairs from the start.
        sc.exit = shell_exit(w, sc, a, t, mine);
        let out = if sc.straight {
            predict_straight_partners(w, sc, a, &partners, t, mine)
        } else {
            partners
                .iter()
                .try_for_each(|&b| predict_disk(w, sc, a, b, t, mine))
        };
        sc.partners = partners;
        out?;
    } else if interior::<V>(sc, a) {
        // The common case: the neighbours are fixed offsets away, no wrapping, no repeats.
        for i in 0..sc.offsets.len() {
            let k = (home as isize + sc.offsets[i]) as usize;
            scan_cell(w, sc, a, k, t, mine)?;
        }
    } else {
        scan_edge_neighbours(w, sc, a, t, mine)?;
    }
    finish_prediction(w, sc, a, home, t, mine)
}

/// Ends a prediction of `a` (in cell `home`) whose disk candidates are in: walls, then the
/// pair and wall event kept as `best`, then borders and cells, and the earliest goes to the queue.
fn finish_prediction<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    home: usize,
    t: f64,
    mine: (V, V, V),
) -> Result<(), Error> {
    if sc.has_walls {
        for i in 0..sc.cell_walls[home].len() {
            let b = sc.cell_walls[home][i];
            predict_pair_or_wall(w, sc, a, b, t, mine)?;
        }
    }
    if !sc.shells {
        sc.best[a as usize] = sc.cand; // (read by cell crossings only)
    }
    predict_border(w, sc, a, t, mine);
    if sc.shells {
        predict_shell(sc, a);
    } else if sc.straight {
        predict_cell_straight(w, sc, a, t, mine);
    } else {
        predict_cell(w, sc, a, t);
    }
    match sc.cand.take() {
        Some(ev) => sc.heap.set(ev),
        None => sc.heap.remove(a),
    }
    Ok(())
}

/// Predicts `a` after it crossed into a new cell (`tag`: the axis and direction). Rapaport's
/// scheme: the pairs still in reach were predicted before (by `a`, or by the partner when its
/// flight changed since), so only the cells the crossing brings into reach are new, and `a`'s
/// kept `best` event stands for the rest while its partner has not changed. Otherwise (a
/// changed partner, a curved flight, an edge cell) the full prediction.
fn predict_after_crossing<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    tag: u32,
    t: f64,
) -> Result<(), Error> {
    let home = sc.cell[a as usize] as usize;
    let kept = sc.best[a as usize];
    let kept_valid = kept.is_none_or(|ev| matches!(validity(sc, &ev), Validity::Valid));
    if !(sc.straight && kept_valid && interior::<V>(sc, a) && sc.meta[a as usize].alive) {
        return predict_all(w, sc, a, t);
    }
    sc.predictions += 1;
    sc.cand = kept;
    let mine = state_at(sc, a, t);
    let front = std::mem::take(&mut sc.front[tag as usize]);
    let mut out = Ok(());
    for &o in &front {
        let k = (home as isize + o) as usize;
        out = scan_cell(w, sc, a, k, t, mine);
        if out.is_err() {
            break;
        }
    }
    sc.front[tag as usize] = front;
    out?;
    finish_prediction(w, sc, a, home, t, mine)
}

/// Whether `a`'s cell is off the grid's edges, so its neighbours are `offsets` away (no
/// wrapping, no repeats).
#[inline]
fn interior<V: Vector>(sc: &Scratch<V>, a: u32) -> bool {
    interior_at::<V>(sc, sc.coord[a as usize])
}

/// Whether the cell at coordinates `hc` is off the grid's edges.
#[inline]
fn interior_at<V: Vector>(sc: &Scratch<V>, hc: [i64; 3]) -> bool {
    !sc.offsets.is_empty() && (0..V::DIM).all(|ax| hc[ax] >= 1 && hc[ax] + 2 <= sc.dims[ax] as i64)
}

/// Predicts `a` against the disks of cell `k`.
#[inline(always)]
fn scan_cell<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    k: usize,
    t: f64,
    mine: (V, V, V),
) -> Result<(), Error> {
    let n = sc.cells.members(k).len();
    for i in 0..n {
        let b = sc.cells.members(k)[i];
        if b != a {
            predict_disk(w, sc, a, b, t, mine)?;
        }
    }
    Ok(())
}

/// Predicts `a` against disk `b` (a member of a cell). The common case, both flying straight,
/// is inline; everything else goes to `predict_pair_or_wall`. Same result either way.
#[inline(always)]
fn predict_disk<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    b: u32,
    t: f64,
    mine: (V, V, V),
) -> Result<(), Error> {
    if !sc.straight || sc.body[b as usize].radius.is_nan() {
        return predict_pair_or_wall(w, sc, a, b, t, mine);
    }
    sc.pair_tests += 1;
    let horizon = sc.t_end - t;
    let (pb, vb, _) = state_at(sc, b, t);
    let (pa, va, _) = mine;
    let d = w.topo.delta(pa, pb);
    let r = (sc.body[a as usize].radius + sc.body[b as usize].radius) * (1.0 - SKIN);
    // As in `predict_straight_partners`: `toi_ball_ball_by`'s dropping tests first, without
    // branches, and with the best event so far as the bound (what meets later is dropped
    // below anyway).
    let rel = vb - va;
    let early = look_ahead(horizon, t, sc.cand.map_or(f64::INFINITY, |c| c.time));
    if surely_no_toi_by(d, rel, r, early) {
        return Ok(());
    }
    let s = if d.length_squared() < r * r {
        0.0 // overlapping: collide now (approaching or not)
    } else {
        // Contacts past the horizon are dropped below; most are found so without a root.
        match toi_ball_ball_by(d, rel, r, horizon) {
            Some(s) => s,
            None => return Ok(()),
        }
    };
    if horizon < 0.0 || s > horizon || sc.cand.is_some_and(|c| t + s > c.time) {
        return Ok(());
    }
    offer_pair(w, sc, a, b, t, s, PAIR)
}

/// How far from `t` a pair test must look when the best event so far is at `limit`: to the
/// horizon, or a little past `limit` (1e-12 of the times, far above their rounding), so that a
/// pair dropped beyond it surely meets later, and ties are kept. An infinite `limit` (no event
/// yet) gives the horizon.
#[inline]
fn look_ahead(horizon: f64, t: f64, limit: f64) -> f64 {
    horizon.min((limit - t) + 1e-12 * (limit.abs() + t.abs()))
}

/// [`predict_disk`] for each of `partners` when every flight is straight: the same tests in
/// the same order and arithmetic, with what is `a`'s and the horizon read once, not for every
/// partner (the loop writes the flight only when a partner beats the best event so far), and
/// pairs that would meet after `a` leaves its shell dropped (the shell event, offered after,
/// would replace them: the chosen event is the same).
fn predict_straight_partners<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    partners: &[u32],
    t: f64,
    mine: (V, V, V),
) -> Result<(), Error> {
    let (pa, va, _) = mine;
    let ra = sc.body[a as usize].radius;
    let horizon = sc.t_end - t;
    // A copy: the loop's calls borrow the world mutably.
    let topo = w.topo;
    // A pair event at `t + s` can be `a`'s next event only if it is not later than the best
    // found so far, nor than `a` leaving its shell (that event wins over any later one, and it
    // is offered after the pairs). As Smallenburg's code does, the running limit also drops
    // most pairs before their square root: `toi_ball_ball_by` is given a horizon a little past
    // it (1e-12 of the times, far above their rounding), so that what it drops is surely later.
    let exit = sc.exit.unwrap_or(f64::INFINITY);
    let best = |sc: &Scratch<V>| sc.cand.map_or(f64::INFINITY, |c| c.time).min(exit);
    let reach = |limit: f64| look_ahead(horizon, t, limit);
    let mut limit = best(sc);
    let mut early = reach(limit);
    let mut tests = 0;
    for &b in partners {
        let body = sc.body[b as usize];
        if body.radius.is_nan() {
            predict_pair_or_wall(w, sc, a, b, t, mine)?;
            limit = best(sc);
            early = reach(limit);
            continue;
        }
        tests += 1;
        let pb = body.pos + body.vel * (t - body.t);
        let d = topo.delta(pa, pb);
        let r = (ra + body.radius) * (1.0 - SKIN);
        // Most pairs are dropped, in no order a processor can predict: first by the tests
        // that drop them, without a branch on each (`surely_no_toi_by`).
        let rel = body.vel - va;
        if surely_no_toi_by(d, rel, r, early) {
            continue;
        }
        let s = if d.length_squared() < r * r {
            0.0 // overlapping: collide now (approaching or not)
        } else {
            match toi_ball_ball_by(d, rel, r, early) {
                Some(s) => s,
                None => continue,
            }
        };
        if horizon < 0.0 || s > horizon || t + s > limit {
            continue;
        }
        offer_pair(w, sc, a, b, t, s, PAIR)?;
        limit = best(sc);
        early = reach(limit);
    }
    sc.pair_tests += tests;
    Ok(())
}

/// Predicts `a`, in a cell at the edge of the grid, against the disks of the cells around
/// it: wrapped or cut at the border, each cell once.
fn scan_edge_neighbours<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    t: f64,
    mine: (V, V, V),
) -> Result<(), Error> {
    let mut around = [0usize; 27];
    let count = cells_around(w, sc, a, &mut around);
    for &k in &around[..count] {
        scan_cell(w, sc, a, k, t, mine)?;
    }
    Ok(())
}

#[inline]
fn predict_pair_or_wall<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    b: u32,
    t: f64,
    mine: (V, V, V),
) -> Result<(), Error> {
    sc.pair_tests += 1;
    let (body_a, body_b) = (sc.body[a as usize], sc.body[b as usize]);
    let meta_b = sc.meta[b as usize];
    if !meta_b.alive {
        return Ok(());
    }
    let horizon = sc.t_end - t;
    if horizon < 0.0 {
        return Ok(());
    }
    let (pa, va, aa) = mine;
    let is_wall = meta_b.wall;
    let (kind, s) = if is_wall {
        let Some(cb) = w.critters.slot(b) else {
            return Ok(());
        };
        let Shape::Wall(wall) = cb.shape() else {
            return Ok(());
        };
        let d = w.topo.delta(cb.pos, pa);
        let r = body_a.radius * (1.0 - SKIN);
        let s = if aa.length_squared() == 0.0 {
            toi_wall_ball(wall, d, va, r)
        } else if contact_wall_ball(wall, d, r).is_some() {
            Some(0.0)
        } else {
            let vb = va.length() + aa.length() * horizon;
            let gap = |s: f64| {
                let p = d + va * s + aa * (0.5 * s * s);
                let f = wall.closest_feature(p);
                let dist = (p - f.offset).length();
                if f.inside {
                    -dist - r
                } else {
                    dist - r
                }
            };
            match advance_to_contact(gap, vb, horizon, body_a.radius) {
                Advance::Hit(s) => Some(s),
                Advance::Miss => None,
                Advance::Continue(s) => {
                    push(sc, t + s, a, b, RECHECK);
                    None
                }
            }
        };
        (WALL, s)
    } else {
        let (pb, vb, ab) = state_at(sc, b, t);
        let d = w.topo.delta(pa, pb);
        let wv = vb - va;
        let ar = ab - aa;
        let r = (body_a.radius + body_b.radius) * (1.0 - SKIN);
        let s = if d.length_squared() < r * r {
            Some(0.0) // overlapping: collide now (approaching or not)
        } else if ar.length_squared() == 0.0 {
            toi_ball_ball(d, wv, r)
        } else {
            let speed = wv.length() + ar.length() * horizon;
            let gap = |s: f64| (d + wv * s + ar * (0.5 * s * s)).length() - r;
            match advance_to_contact(gap, speed, horizon, r) {
                Advance::Hit(s) => Some(s),
                Advance::Miss => None,
                Advance::Continue(s) => {
                    push(sc, t + s, a, b, RECHECK);
                    None
                }
            }
        };
        (PAIR, s)
    };
    if let Some(s) = s {
        if s > horizon || sc.cand.is_some_and(|c| t + s > c.time) {
            return Ok(());
        }
        offer_pair(w, sc, a, b, t, s, kind)?;
    }
    Ok(())
}

/// Offers the contact of `a` with `b` (a disk, or a wall) `s` after `t`, unless their rule says
/// they don't collide, or they touch now and were just handled.
#[inline(never)]
fn offer_pair<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    b: u32,
    t: f64,
    s: f64,
    kind: Kind,
) -> Result<(), Error> {
    let (meta_a, meta_b) = (sc.meta[a as usize], sc.meta[b as usize]);
    let rule = match w.rules.cached(meta_a.class, meta_b.class) {
        Some(rule) => rule,
        None => {
            let (ca, cb) = (
                w.critters.slot(a).expect("live"),
                w.critters.slot(b).expect("live"),
            );
            w.rules
                .rule(&w.kinds, &w.topo, ca, cb)
                .map_err(|e| at_step(e, w.step_count))?
        }
    };
    if rule == Some(PairRule::DontCollide) {
        return Ok(());
    }
    if s == 0.0 {
        let just_met = sc.last[a as usize] == b && (meta_b.wall || sc.last[b as usize] == a);
        if just_met || sc.stuck.contains(&pair_key(a, b)) {
            return Ok(()); // the pair was handled; its hook chose to leave them so
        }
    }
    push(sc, t + s, a, b, kind);
    Ok(())
}

enum Advance {
    Hit(f64),
    Miss,
    Continue(f64),
}

/// Conservative advancement on a gap function whose rate of change is bounded by `speed`:
/// steps of gap / speed never pass the first contact.
fn advance_to_contact(gap: impl Fn(f64) -> f64, speed: f64, horizon: f64, scale: f64) -> Advance {
    let tol = 1e-11 * scale;
    if speed <= 0.0 {
        return Advance::Miss;
    }
    let mut s = 0.0;
    for _ in 0..CA_ITERATIONS {
        let g = gap(s);
        if g <= tol {
            return Advance::Hit(s);
        }
        s += g / speed;
        if s > horizon {
            return Advance::Miss;
        }
    }
    Advance::Continue(s)
}

/// Border hits of disk `a` (`mine`: its position, velocity and acceleration at `t`).
fn predict_border<V: Vector>(w: &State<V>, sc: &mut Scratch<V>, a: u32, t: f64, mine: (V, V, V)) {
    if w.topo.border == Border::Wrap {
        return;
    }
    let r = sc.body[a as usize].radius;
    let (p, v, acc) = mine;
    let just = sc.last[a as usize];
    for axis in 0..V::DIM {
        let lo = w.topo.min.get(axis) + r;
        let hi = w.topo.max.get(axis) - r;
        if lo > hi {
            continue;
        }
        let (x, vx, ax) = (p.get(axis), v.get(axis), acc.get(axis));
        for (side, bound) in [(0u32, lo), (1u32, hi)] {
            let outward = if side == 1 { 1.0 } else { -1.0 };
            // Distance to the bound, positive inside.
            let gap = (bound - x) * outward;
            let s = if gap <= 0.0 {
                on_bound(vx * outward, ax * outward)
            } else {
                smallest_nonneg_root(0.5 * ax * outward, vx * outward, -gap)
            };
            let tag = axis as u32 * 2 + side;
            if let Some(s) = s {
                if s == 0.0 && just == BORDER_TAG + tag {
                    continue;
                }
                if t + s <= sc.t_end {
                    push(sc, t + s, a, tag, BORDER);
                }
            }
        }
    }
}

/// When a critter on (or a hair past) a bound leaves through it, given its outward velocity
/// `v` and acceleration `a`: now if moving (or, at rest, accelerating) outward; after the
/// parabola returns, `-2 v / a`, if moving inward but accelerated outward; never otherwise.
fn on_bound(v: f64, a: f64) -> Option<f64> {
    if v > 0.0 || (v == 0.0 && a > 0.0) {
        Some(0.0)
    } else if v < 0.0 && a > 0.0 {
        Some(-2.0 * v / a)
    } else {
        None
    }
}

fn bounce_border<V: Vector>(w: &mut State<V>, a: u32, tag: u32) {
    let (axis, side) = ((tag / 2) as usize, tag % 2);
    let border = w.topo.border;
    let (lo, hi) = (w.topo.min.get(axis), w.topo.max.get(axis));
    let c = w.critters.slot_mut_moving(a).expect("live slot");
    let bound = if side == 1 {
        hi - c.radius
    } else {
        lo + c.radius
    };
    c.pos.set(axis, bound);
    let v = c.vel.get(axis);
    let outward = if side == 1 { v > 0.0 } else { v < 0.0 };
    if outward {
        match border {
            Border::Bounce => c.vel.set(axis, -c.restitution() * v),
            _ => c.vel.set(axis, 0.0),
        }
    }
}

#[allow(clippy::needless_range_loop)]
fn predict_cell<V: Vector>(w: &State<V>, sc: &mut Scratch<V>, a: u32, t: f64) {
    let (p, v, acc) = state_at(sc, a, t);
    let cc = sc.coord[a as usize];
    let mut best = (f64::INFINITY, 0u32);
    for axis in 0..V::DIM {
        let n = sc.dims[axis] as i64;
        if n == 1 {
            continue;
        }
        let lo = w.topo.min.get(axis) + cc[axis] as f64 * sc.side[axis];
        let hi = lo + sc.side[axis];
        let (x, vx, ax) = (p.get(axis), v.get(axis), acc.get(axis));
        for dir in [0u32, 1] {
            let at_edge = if dir == 1 {
                cc[axis] == n - 1
            } else {
                cc[axis] == 0
            };
            if at_edge && !w.topo.wraps() {
                continue;
            }
            let outward = if dir == 1 { 1.0 } else { -1.0 };
            let bound = if dir == 1 { hi } else { lo };
            let gap = (bound - x) * outward;
            let s = if gap <= 0.0 {
                on_bound(vx * outward, ax * outward)
            } else {
                smallest_nonneg_root(0.5 * ax * outward, vx * outward, -gap)
            };
            if let Some(s) = s {
                if s < best.0 {
                    best = (s, axis as u32 * 2 + dir);
                }
            }
        }
    }
    if best.0.is_finite() && t + best.0 <= sc.t_end {
        push(sc, t + best.0, a, best.1, CELL);
    }
}

/// `predict_cell` for a straight flight (`mine`: position and velocity at `t`): only the side
/// the critter moves towards can be crossed, at `gap / speed`, the time `predict_cell`'s general
/// formulas give bit for bit.
#[inline]
#[allow(clippy::needless_range_loop)] // per-axis arrays indexed together
fn predict_cell_straight<V: Vector>(
    w: &State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    t: f64,
    mine: (V, V, V),
) {
    let (p, v, _) = mine;
    let cc = sc.coord[a as usize];
    let wraps = w.topo.wraps();
    let mut best = (f64::INFINITY, 0u32);
    for axis in 0..V::DIM {
        let n = sc.dims[axis] as i64;
        let vx = v.get(axis);
        if n == 1 || vx == 0.0 || vx.is_nan() {
            continue; // not moving along the axis (or NaN): no crossing, as in `predict_cell`
        }
        let up = vx > 0.0;
        if !wraps && (if up { cc[axis] == n - 1 } else { cc[axis] == 0 }) {
            continue;
        }
        let lo = w.topo.min.get(axis) + cc[axis] as f64 * sc.side[axis];
        let (bound, outward) = if up {
            (lo + sc.side[axis], 1.0)
        } else {
            (lo, -1.0)
        };
        let gap = (bound - p.get(axis)) * outward;
        let s = if gap <= 0.0 {
            0.0
        } else {
            -(-gap) / (vx * outward)
        };
        if s < best.0 {
            best = (s, axis as u32 * 2 + u32::from(up));
        }
    }
    if best.0.is_finite() && t + best.0 <= sc.t_end {
        push(sc, t + best.0, a, best.1, CELL);
    }
}

#[allow(clippy::needless_range_loop)]
fn cross_cell<V: Vector>(w: &mut State<V>, sc: &mut Scratch<V>, a: u32, tag: u32, t: f64) {
    advance(w, sc, a, t);
    let (axis, dir) = ((tag / 2) as usize, tag % 2);
    let old = sc.cell[a as usize] as usize;
    let mut cc = sc.coord[a as usize];
    cc[axis] += if dir == 1 { 1 } else { -1 };
    let n = sc.dims[axis] as i64;
    if cc[axis] < 0 || cc[axis] >= n {
        if w.topo.wraps() {
            let len = w.topo.size().get(axis);
            let c = w.critters.slot_mut_moving(a).expect("live slot");
            let x = c.pos.get(axis);
            c.pos.set(axis, if dir == 1 { x - len } else { x + len });
        }
        // Onto the grid's other side, as `key` takes it.
        cc[axis] = cc[axis].rem_euclid(n);
    }
    let new = key(&sc.dims, cc);
    move_cell(sc, a, old, new, cc);
}

/// Moves `a` from cell `old` to cell `new`, at coordinates `cc`.
fn move_cell<V: Vector>(sc: &mut Scratch<V>, a: u32, old: usize, new: usize, cc: [i64; 3]) {
    if old == new {
        return;
    }
    sc.cells.remove(old, a);
    sc.cells.push(new, a);
    debug_assert_eq!(coords(&sc.dims, new), cc, "cell {new}'s coordinates");
    sc.cell[a as usize] = new as u32;
    sc.coord[a as usize] = cc;
}

/// After a hook ran: the critter may have died or been moved; put it in the right cell.
fn relocate<V: Vector>(w: &mut State<V>, sc: &mut Scratch<V>, a: u32) {
    if sc.shells {
        // Listed again when it died, grew, or was moved out of its shell.
        let stays = w.critters.slot(a).is_some_and(|c| {
            c.alive
                && c.radius == sc.body[a as usize].radius
                && w.topo.delta(sc.center[a as usize].0, c.pos).length() <= 0.5 * sc.shell
        });
        if !stays {
            refresh(w, sc, a);
            list_again(w, sc, a);
        }
        return;
    }
    let old = sc.cell[a as usize] as usize;
    let Some(c) = w.critters.slot(a) else { return };
    if !c.alive {
        sc.cells.remove(old, a);
        return;
    }
    let mut p = c.pos;
    if w.topo.wraps() {
        p = w.topo.wrap_position(p);
        w.critters.slot_mut_moving(a).expect("live").pos = p;
    }
    let (new, cc) = cell_of(w, sc, p);
    move_cell(sc, a, old, new, cc);
}

/// Hands a touching pair to the caller's `collide` hook (Pop's roles), with the TC model.
fn collide<V: Vector>(
    w: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    b: u32,
    t: f64,
) -> Result<bool, Error> {
    let (ca, cb) = (
        w.critters.slot(a).expect("live"),
        w.critters.slot(b).expect("live"),
    );
    let rule = match w
        .rules
        .rule(&w.kinds, &w.topo, ca, cb)
        .map_err(|e| at_step(e, w.step_count))?
    {
        Some(r) => r,
        None => crate::rules::roles_of(&w.kinds, &w.topo, ca, cb)
            .map_err(|e| at_step(e, w.step_count))?,
    };
    let Some((caller, arg)) = roles_order(rule, ca, cb) else {
        return Ok(false);
    };
    let (caller, arg) = (caller.id.index, arg.id.index);
    // TC model: a collision right after another one of either critter is elastic.
    let recent = |x: u32| t - sc.last_t[x as usize] < sc.tc;
    let tc = recent(a) || (!cb.is_wall() && recent(b));
    let saved = if tc {
        let e = [a, b].map(|x| w.critters.slot(x).map_or(1.0, |c| c.restitution()));
        for x in [a, b] {
            if let Some(c) = w.critters.slot_mut(x) {
                c.traits_mut().restitution = 1.0;
            }
        }
        Some(e)
    } else {
        None
    };
    let before = w.events.collisions.len();
    let out = w.collide_pair(caller, arg);
    if let Some(e) = saved {
        for (x, e) in [a, b].into_iter().zip(e) {
            if let Some(c) = w.critters.slot_mut(x) {
                if c.restitution() == 1.0 {
                    c.traits_mut().restitution = e;
                }
            }
        }
    }
    for ev in &w.events.collisions[before..] {
        let (Some(c1), Some(c2)) = (w.critters.get(ev.caller), w.critters.get(ev.arg)) else {
            continue;
        };
        if !c1.is_wall() && !c2.is_wall() {
            sc.virial += (c1.radius + c2.radius) * ev.impulse;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use crate::scenes::{gas, GasParams};
    use crate::{Border, Method, World};
    use glam::DVec3;

    fn periodic_gas(no_shells: bool) -> World<DVec3> {
        let mut w = gas::<DVec3>(&GasParams {
            n: 512,
            packing: 0.35,
            dt: 0.5,
            border: Border::Wrap,
            ..GasParams::default()
        })
        .expect("the gas builds");
        w.set_method(Method::Event).expect("event");
        w.methods.flight.no_shells = no_shells;
        w
    }

    /// A stripe of cells or of a neighbour list starts on a cache line (16 entries or fewer are
    /// one line), before and after the stripes grow, and growing keeps every member; a 3D body
    /// is one whole line and a shell's centre half of one.
    #[test]
    fn stripes_and_bodies_lie_on_cache_lines() {
        let line = |cells: &super::Cells, k: usize| {
            (cells.data.as_ptr() as usize + 4 * cells.start(k)) % 64
        };
        let mut cells = super::Cells::default();
        cells.reset(40, 5);
        assert_eq!(
            cells.stride, 8,
            "room for 5 and the count, rounded up to a power of two"
        );
        assert!((0..40).all(|k| line(&cells, k) % 32 == 0));
        assert_eq!(line(&cells, 0), 0);
        for k in 0..40 {
            for m in 0..(k % 7) as u32 {
                cells.push(k, 1000 * k as u32 + m);
            }
        }
        // Cell 6 filled past its room for 7: every stripe grew.
        cells.push(6, 6006);
        cells.push(6, 6007);
        assert_eq!(cells.stride, 16);
        assert!((0..40).all(|k| line(&cells, k) == 0));
        for k in 0..40 {
            let mut want: Vec<u32> = (0..(k % 7) as u32).map(|m| 1000 * k as u32 + m).collect();
            if k == 6 {
                want.extend([6006, 6007]);
            }
            assert_eq!(cells.members(k), &want[..], "cell {k}");
        }
        cells.remove(6, 6001);
        assert_eq!(cells.members(6).len(), 7);
        assert!(!cells.members(6).contains(&6001));
        assert_eq!(std::mem::size_of::<super::Body<DVec3>>(), 64);
        assert_eq!(std::mem::align_of::<super::Body<DVec3>>(), 64);
        assert_eq!(std::mem::size_of::<super::Body<glam::DVec2>>(), 48);
        assert_eq!(std::mem::size_of::<super::Centre<DVec3>>(), 32);
        assert_eq!(std::mem::align_of::<super::Centre<DVec3>>(), 32);
    }

    /// Shells and cells are two ways of finding the same collisions: over a few collisions per
    /// sphere (before round-off differences grow chaotically) they find the same number and
    /// leave every sphere in the same place.
    #[test]
    fn shells_and_cells_find_the_same_collisions() {
        let (mut shells, mut cells) = (periodic_gas(false), periodic_gas(true));
        let (mut with_shells, mut with_cells) = (0, 0);
        for _ in 0..2 {
            shells.step().expect("steps");
            cells.step().expect("steps");
            with_shells += shells.stats().impacts;
            with_cells += cells.stats().impacts;
        }
        assert!(
            shells.methods.flight.shells,
            "the 3D periodic gas lists neighbours in shells"
        );
        assert!(!cells.methods.flight.shells);
        assert!(
            with_cells > 2 * 512,
            "{with_cells} collisions: too few to compare"
        );
        assert_eq!(with_shells, with_cells);
        let topo = shells.state.topo;
        let worst = shells
            .critters()
            .iter()
            .zip(cells.critters().iter())
            .map(|(a, b)| topo.delta(a.pos, b.pos).length())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "spheres differ by {worst:e}");
    }

    /// A flight kept from step to step flies what a new flight every step flies: over a few
    /// collisions per disk (before round-off differences grow chaotically) the same number of
    /// collisions, every disk in the same place, energy kept, and no two disks overlapping.
    /// Between the steps some critters are pushed from outside the flight (as a hook or the
    /// caller may), which the kept flight must notice. Walled 2D gas (cells) and periodic 3D gas
    /// (shells); dt short, so that most of a step's events were predicted in earlier steps.
    #[test]
    fn a_kept_flight_flies_what_a_new_flight_every_step_flies() {
        fn check<V: crate::Vector>(border: Border, n: usize, speed: f64, dt: f64, steps: usize) {
            let build = |no_keep: bool| {
                let mut w = gas::<V>(&GasParams {
                    n,
                    packing: 0.3,
                    dt,
                    border,
                    ..GasParams::default()
                })
                .expect("the gas builds");
                // A few collisions per disk in the run.
                let ids: Vec<_> = w.critters().iter().map(|c| c.id()).collect();
                for id in ids {
                    if let Some(c) = w.get_mut(id) {
                        c.vel = c.vel * speed;
                    }
                }
                w.set_method(Method::Event).expect("event");
                w.methods.flight.no_keep = no_keep;
                w
            };
            let (mut kept, mut fresh) = (build(false), build(true));
            let e0 = kept.kinetic_energy();
            let (mut with_kept, mut with_fresh, mut resumed) = (0, 0, 0);
            for step in 0..steps {
                for w in [&mut kept, &mut fresh] {
                    if step % 7 == 3 {
                        // A push from outside: every 50th disk turned around.
                        let ids: Vec<_> = w.critters().iter().map(|c| c.id()).collect();
                        for id in ids.into_iter().step_by(50) {
                            if let Some(c) = w.get_mut(id) {
                                c.vel = -c.vel;
                            }
                        }
                    }
                }
                resumed += usize::from(kept.methods.flight.kept.is_some());
                kept.step().expect("steps");
                fresh.step().expect("steps");
                with_kept += kept.stats().impacts;
                with_fresh += fresh.stats().impacts;
            }
            assert!(
                resumed >= steps / 2,
                "the flight went on in only {resumed} of {steps} steps"
            );
            assert!(fresh.methods.flight.kept.is_none());
            assert!(
                with_fresh > 2 * n,
                "{with_fresh} collisions: too few to compare"
            );
            assert_eq!(with_kept, with_fresh);
            let topo = kept.state.topo;
            let cs: Vec<_> = kept.critters().iter().collect();
            let worst = cs
                .iter()
                .zip(fresh.critters().iter())
                .map(|(a, b)| topo.delta(a.pos, b.pos).length())
                .fold(0.0, f64::max);
            // Round-off differences, grown by each collision (a gas is chaotic); a missed or
            // wrong event would put disks a good part of a radius apart.
            assert!(worst < 1e-6, "disks differ by {worst:e}");
            let drift = (kept.kinetic_energy() - e0).abs() / e0;
            assert!(drift < 1e-12, "energy drift {drift:e}");
            let mut overlap: f64 = 0.0;
            for (i, a) in cs.iter().enumerate().filter(|(_, c)| !c.is_wall()) {
                for b in cs[i + 1..].iter().filter(|c| !c.is_wall()) {
                    let d = topo.delta(a.pos, b.pos).length();
                    overlap = overlap.max(a.radius + b.radius - d);
                }
            }
            assert!(overlap < 1e-9, "disks overlap by {overlap:e}");
        }
        check::<glam::DVec2>(Border::Bounce, 400, 4.0, 1.0 / 60.0, 120);
        check::<DVec3>(Border::Wrap, 300, 1.0, 1.0 / 30.0, 30);
    }

    /// The flight's start asks who may meet something pair by pair over the cells
    /// (`mark_who_may_meet`); the answers are `may_meet`'s, critter by critter, for every disk:
    /// walled and periodic gases in 2D and 3D, stirred so that some disks are close and some
    /// fast, a wall across the middle, and a box too thin for three cells across.
    #[test]
    fn who_may_meet_pair_by_pair_is_may_meet() {
        fn check<V: crate::Vector>(border: Border, n: usize, packing: f64, thin: bool) {
            let mut w = if thin {
                // A periodic box 1.5 across but along the first axis: one cell across.
                let mut hi = V::splat(1.5);
                hi.set(0, 1.3 * n as f64);
                let config = crate::WorldConfig::new(V::zero(), hi)
                    .border(border)
                    .dt(1.0 / 60.0);
                let mut w = World::new(config).expect("the world builds");
                for i in 0..n {
                    let mut p = V::splat(0.75);
                    p.set(0, 1.3 * i as f64 + 0.2 * ((i * 7) % 5) as f64);
                    let mut v = V::zero();
                    v.set(0, if i % 2 == 0 { 1.0 } else { -0.7 });
                    w.spawn(crate::CritterSpec::ball(p).vel(v).radius(0.5))
                        .expect("spawns");
                }
                w
            } else {
                gas::<V>(&GasParams {
                    n,
                    packing,
                    dt: 1.0 / 60.0,
                    border,
                    seed: 11,
                    ..GasParams::default()
                })
                .expect("the gas builds")
            };
            if border != Border::Wrap {
                let (lo, hi) = (w.state.topo.min, w.state.topo.max);
                let mid = (lo + hi) * 0.5;
                let mut a = mid;
                a.set(0, lo.get(0) + 2.0);
                let mut b = mid;
                b.set(0, hi.get(0) - 2.0);
                let half = V::splat(0.05);
                w.add_wall(crate::WallBox::aligned(a - half, b + half).expect("a box"))
                    .expect("the wall goes in");
            }
            // Stir: a few discrete steps at speeds of several radii per second, then some disks
            // much faster.
            let ids: Vec<_> = w
                .critters()
                .iter()
                .filter(|c| !c.is_wall())
                .map(|c| c.id())
                .collect();
            for (i, id) in ids.iter().enumerate() {
                let c = w.get_mut(*id).expect("live");
                c.vel = c.vel * if i % 13 == 0 { 40.0 } else { 6.0 };
            }
            for _ in 0..20 {
                w.step().expect("steps");
            }
            let limit = 0.25 * 0.5;
            let mut sc = std::mem::take(&mut w.methods.flight);
            sc.fast = Some(limit);
            let dt = w.dt();
            super::setup(&mut w.state, &mut sc, V::zero(), dt, dt);
            super::mark_who_may_meet(&w.state, &mut sc);
            let (mut yes, mut no) = (0, 0);
            for a in 0..sc.body.len() as u32 {
                let want = super::may_meet(&w.state, &sc, a);
                assert_eq!(sc.meets[a as usize], want, "disk {a}");
                if sc.body[a as usize].radius.is_nan() {
                    continue;
                }
                if want {
                    yes += 1;
                } else {
                    no += 1;
                }
            }
            assert!(
                yes * 20 > n && no * 20 > n,
                "{yes} may meet, {no} not: too one-sided"
            );
        }
        check::<glam::DVec2>(Border::Bounce, 3000, 0.15, false);
        check::<glam::DVec2>(Border::Wrap, 3000, 0.15, false);
        check::<glam::DVec2>(Border::Wrap, 200, 0.0, true);
        check::<DVec3>(Border::Bounce, 2000, 0.1, false);
        check::<DVec3>(Border::Wrap, 2000, 0.1, false);
    }

    /// Cells are at least a diameter wide and at most about two per disk: over that cap the
    /// grid is scaled down to just under it, not halved (which could leave a quarter of the
    /// cap in 2D and an eighth in 3D, cells twice as wide as needed).
    #[test]
    fn cells_come_as_close_to_their_cap_as_a_diameter_allows() {
        fn check<V: crate::Vector>(n: usize, packing: f64) {
            let mut w = gas::<V>(&GasParams {
                n,
                packing,
                ..GasParams::default()
            })
            .expect("the gas builds");
            let mut sc = std::mem::take(&mut w.methods.flight);
            let dt = w.dt();
            super::setup(&mut w.state, &mut sc, V::zero(), dt, dt);
            let total: usize = sc.dims[..V::DIM].iter().product();
            let cap = 2 * n;
            let widest = (w.state.topo.size().get(0) / 1.0).floor() as usize;
            let unconstrained = widest.pow(V::DIM as u32);
            assert!(total <= cap, "{total} cells for {n} disks");
            assert!(
                10 * total >= 7 * cap.min(unconstrained),
                "{total} cells for {n} disks (cap {cap}, {unconstrained} a diameter wide)"
            );
            for axis in 0..V::DIM {
                assert!(sc.side[axis] >= 1.0, "cells {} wide", sc.side[axis]);
            }
        }
        check::<glam::DVec2>(100, 0.3);
        check::<glam::DVec2>(10_000, 0.02);
        check::<glam::DVec2>(10_000, 0.4);
        check::<DVec3>(1000, 0.2);
        check::<DVec3>(4000, 0.05);
    }

    /// Shells keep the gas exact: energy and momentum conserved, nobody overlapping.
    #[test]
    fn shells_conserve_energy_and_momentum_and_leave_no_overlap() {
        let mut w = periodic_gas(false);
        let e0 = w.kinetic_energy();
        let p0: DVec3 = w.critters().iter().map(|c| c.vel * c.mass()).sum();
        let mut impacts = 0;
        for _ in 0..6 {
            w.step().expect("steps");
            impacts += w.stats().impacts;
        }
        assert!(impacts > 5 * 512, "{impacts} collisions");
        let e1 = w.kinetic_energy();
        let p1: DVec3 = w.critters().iter().map(|c| c.vel * c.mass()).sum();
        assert!(((e1 - e0) / e0).abs() < 1e-12, "energy {e0} -> {e1}");
        assert!(
            (p1 - p0).length() < 1e-9 * e0.sqrt(),
            "momentum {p0} -> {p1}"
        );
        let all: Vec<_> = w.critters().iter().collect();
        for (i, a) in all.iter().enumerate() {
            for b in &all[i + 1..] {
                let gap = w.state.topo.delta(a.pos, b.pos).length() - a.radius - b.radius;
                assert!(gap > -1e-9, "overlap {gap:e}");
            }
        }
    }
}
