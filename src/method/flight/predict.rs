//! Predicting a critter's next event: its contacts with the disks around it (in the cells
//! around its own, or in its neighbour list) and with the walls of its cell, its border hits,
//! and its next cell crossing or shell exit; the earliest goes to the queue.
//!
//! Straight flights (no acceleration) are the common case and have a pair test of their own,
//! [`straight_contact`], inline and mostly free of branches; everything else (curved flights,
//! walls, dead partners) goes to [`predict_general`]. Both give the same times bit for bit
//! where both apply.

use super::bodies::{motion_at, Body, Motion};
use super::border::predict_border;
use super::cells::{cells_around, interior, predict_crossing, predict_crossing_straight};
use super::events::{offer, validity, EventKind, Validity};
use super::shells::shell_exit;
use super::{Scratch, SKIN};
use crate::border::Topology;
use crate::contact::contact_wall_ball;
use crate::critter::Shape;
use crate::error::Error;
use crate::method::toi::{surely_no_toi_by, toi_ball_ball, toi_ball_ball_by, toi_wall_ball};
use crate::pair_order::pair_key;
use crate::rules::PairRule;
use crate::step::state::{at_step, State};
use crate::vector::Vector;

/// Conservative-advancement iterations before a curved prediction is continued by a recheck
/// event (so that one grazing pair cannot hold up the flight).
const CA_ITERATIONS: usize = 64;

/// Predicts every next event of disk `a` from time `t`.
pub(super) fn predict<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    t: f64,
) -> Result<(), Error> {
    let me = sc.status[a as usize];
    if !me.in_play || me.wall {
        sc.queue.remove(a);
        return Ok(());
    }
    sc.earliest = None;
    sc.predictions += 1;
    let motion = motion_at(sc, a, t);
    // With shells there are no walls, and the cell is not read (a load spared: a miss, as
    // often as not, in a large gas).
    let home = if sc.shells {
        0
    } else {
        sc.cell[a as usize] as usize
    };
    let mut exit = None;
    if sc.shells {
        debug_assert!(sc.straight, "shells are set up for straight flights only");
        // The list copied out, so the loop does not find it again in `neighbours` for every
        // partner (predicting needs the flight mutably), and the partners' bodies asked for at
        // once.
        let mut partners = std::mem::take(&mut sc.partners);
        partners.clear();
        partners.extend_from_slice(sc.neighbours.members(a as usize));
        for &b in &partners {
            crate::prefetch::prefetch(sc.body.get(b as usize));
        }
        // When `a` leaves its shell: offered last (`finish_prediction`), but a bound for the
        // pairs from the start.
        exit = shell_exit(state, sc, a, t, motion);
        let out = predict_straight_partners(state, sc, a, &partners, t, motion, exit);
        sc.partners = partners;
        out?;
    } else if interior::<V>(sc, a) {
        // The common case: the neighbours are fixed offsets away, no wrapping, no repeats.
        for i in 0..sc.offsets.len() {
            let k = (home as isize + sc.offsets[i]) as usize;
            scan_cell(state, sc, a, k, t, motion)?;
        }
    } else {
        scan_edge_neighbours(state, sc, a, t, motion)?;
    }
    finish_prediction(state, sc, a, home, t, motion, exit)
}

/// Ends a prediction of `a` (in cell `home`) whose disk candidates are in: walls, then the
/// pair and wall event kept as `earliest_contact`, then borders and the cell crossing or the
/// shell's `exit`, and the earliest goes to the queue.
fn finish_prediction<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    home: usize,
    t: f64,
    motion: Motion<V>,
    exit: Option<f64>,
) -> Result<(), Error> {
    if sc.has_walls {
        for i in 0..sc.cell_walls[home].len() {
            let b = sc.cell_walls[home][i];
            predict_general(state, sc, a, b, t, motion)?;
        }
    }
    if !sc.shells {
        sc.earliest_contact[a as usize] = sc.earliest; // (read by cell crossings only)
    }
    predict_border(state, sc, a, t, motion);
    if sc.shells {
        if let Some(at) = exit {
            offer(sc, at, a, 0, EventKind::ShellExit);
        }
    } else if sc.straight {
        predict_crossing_straight(state, sc, a, t, motion);
    } else {
        predict_crossing(state, sc, a, t);
    }
    match sc.earliest.take() {
        Some(ev) => sc.queue.set(ev),
        None => sc.queue.remove(a),
    }
    Ok(())
}

/// Predicts `a` after it crossed into a new cell (`tag`: the axis and direction). Rapaport's
/// scheme: the pairs still in reach were predicted before (by `a`, or by the partner when its
/// flight changed since), so only the cells the crossing brings into reach are new, and `a`'s
/// kept `earliest_contact` stands for the rest while its partner has not changed. Otherwise (a
/// changed partner, a curved flight, an edge cell) the full prediction.
pub(super) fn predict_after_crossing<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    tag: u32,
    t: f64,
) -> Result<(), Error> {
    let home = sc.cell[a as usize] as usize;
    let kept = sc.earliest_contact[a as usize];
    let kept_valid = kept.is_none_or(|ev| matches!(validity(sc, &ev), Validity::Valid));
    if !(sc.straight && kept_valid && interior::<V>(sc, a) && sc.status[a as usize].in_play) {
        return predict(state, sc, a, t);
    }
    sc.predictions += 1;
    sc.earliest = kept;
    let motion = motion_at(sc, a, t);
    let front = std::mem::take(&mut sc.front[tag as usize]);
    let mut out = Ok(());
    for &o in &front {
        let k = (home as isize + o) as usize;
        out = scan_cell(state, sc, a, k, t, motion);
        if out.is_err() {
            break;
        }
    }
    sc.front[tag as usize] = front;
    out?;
    finish_prediction(state, sc, a, home, t, motion, None)
}

/// Predicts `a` against the disks of cell `k`.
#[inline(always)]
fn scan_cell<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    k: usize,
    t: f64,
    motion: Motion<V>,
) -> Result<(), Error> {
    let n = sc.cells.members(k).len();
    for i in 0..n {
        let b = sc.cells.members(k)[i];
        if b != a {
            predict_partner(state, sc, a, b, t, motion)?;
        }
    }
    Ok(())
}

/// Predicts `a`, in a cell at the edge of the grid, against the disks of the cells around
/// it: wrapped or cut at the border, each cell once.
fn scan_edge_neighbours<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    t: f64,
    motion: Motion<V>,
) -> Result<(), Error> {
    let mut around = [0usize; 27];
    let count = cells_around(state, sc, a, &mut around);
    for &k in &around[..count] {
        scan_cell(state, sc, a, k, t, motion)?;
    }
    Ok(())
}

/// Critter `a` flying straight from `t`: what the straight pair test reads of it, read once.
#[derive(Clone, Copy)]
struct Straight<V> {
    t: f64,
    pos: V,
    vel: V,
    radius: f64,
    /// How far from `t` predictions look (to the flight's horizon; negative past it).
    ahead: f64,
}

impl<V: Vector> Straight<V> {
    #[inline(always)]
    fn new(sc: &Scratch<V>, a: u32, t: f64, motion: Motion<V>) -> Self {
        Straight {
            t,
            pos: motion.pos,
            vel: motion.vel,
            radius: sc.body[a as usize].radius,
            ahead: sc.horizon - t,
        }
    }

    /// The cutoff of a pair test when a contact can be the critter's next event only up to
    /// `latest`.
    #[inline(always)]
    fn cutoff(&self, latest: f64) -> Cutoff {
        Cutoff {
            latest,
            look: look_ahead(self.ahead, self.t, latest),
        }
    }
}

/// How late a contact may be and still be the predicting critter's next event (`latest`: the
/// earliest event found so far, and with shells the critter leaving its shell), and how far
/// from `t` the pair test looks (`look`, see [`look_ahead`]).
#[derive(Clone, Copy)]
struct Cutoff {
    latest: f64,
    look: f64,
}

/// How far from `t` a pair test must look when a contact can be the next event only up to
/// `latest`: to the horizon (`ahead` of `t`), or a little past `latest` (1e-12 of the times,
/// far above their rounding), so that a pair dropped beyond it surely meets later, and ties
/// are kept. An infinite `latest` (no event yet) gives the horizon.
#[inline]
fn look_ahead(ahead: f64, t: f64, latest: f64) -> f64 {
    ahead.min((latest - t) + 1e-12 * (latest.abs() + t.abs()))
}

/// The pair test of straight flights: when `me` and the disk of body `other` (flying straight,
/// both radii live) touch, as a time from `me.t`, if that is within the horizon and not after
/// `cutoff.latest` (a pair that overlaps now touches at once).
///
/// Most pairs are dropped, in no order a processor can predict: first by the tests that drop
/// them, without a branch on each (`surely_no_toi_by`), and before their square root
/// (`toi_ball_ball_by`), both looking only as far as `cutoff.look`. What those drop would meet
/// past the horizon or after `cutoff.latest`, so the last test would drop it anyway: the
/// answer is the same as with no early tests at all.
#[inline(always)]
fn straight_contact<V: Vector>(
    topo: &Topology<V>,
    me: &Straight<V>,
    other: &Body<V>,
    cutoff: Cutoff,
) -> Option<f64> {
    let pb = other.pos + other.vel * (me.t - other.t);
    let d = topo.delta(me.pos, pb);
    let r = (me.radius + other.radius) * (1.0 - SKIN);
    let rel = other.vel - me.vel;
    if surely_no_toi_by(d, rel, r, cutoff.look) {
        return None;
    }
    let s = if d.length_squared() < r * r {
        0.0 // overlapping: collide now (approaching or not)
    } else {
        toi_ball_ball_by(d, rel, r, cutoff.look)?
    };
    if me.ahead < 0.0 || s > me.ahead || me.t + s > cutoff.latest {
        return None;
    }
    Some(s)
}

/// Predicts `a` against disk `b` (a member of a cell): both flying straight, by
/// [`straight_contact`] inline; everything else by [`predict_general`].
#[inline(always)]
fn predict_partner<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    b: u32,
    t: f64,
    motion: Motion<V>,
) -> Result<(), Error> {
    if !sc.straight || sc.body[b as usize].radius.is_nan() {
        return predict_general(state, sc, a, b, t, motion);
    }
    sc.pair_tests += 1;
    let me = Straight::new(sc, a, t, motion);
    let cutoff = me.cutoff(sc.earliest.map_or(f64::INFINITY, |e| e.time));
    match straight_contact(&state.topo, &me, &sc.body[b as usize], cutoff) {
        Some(s) => offer_contact(state, sc, a, b, t, s, EventKind::Pair),
        None => Ok(()),
    }
}

/// [`predict_partner`] for each of `partners` when every flight is straight (the neighbour
/// list of shells), with what is `a`'s and the cutoff read once, not for every partner (the
/// loop writes the flight only when a partner beats the earliest event so far). A contact
/// after `a` leaves its shell (`exit`) is dropped too: the shell's exit, offered after the
/// pairs, would win over it, so the chosen event is the same.
fn predict_straight_partners<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    partners: &[u32],
    t: f64,
    motion: Motion<V>,
    exit: Option<f64>,
) -> Result<(), Error> {
    let me = Straight::new(sc, a, t, motion);
    // A copy: the loop's calls borrow the world mutably.
    let topo = state.topo;
    let exit = exit.unwrap_or(f64::INFINITY);
    let cutoff =
        |sc: &Scratch<V>| me.cutoff(sc.earliest.map_or(f64::INFINITY, |e| e.time).min(exit));
    let mut cut = cutoff(sc);
    let mut tests = 0;
    for &b in partners {
        let body = sc.body[b as usize];
        if body.radius.is_nan() {
            predict_general(state, sc, a, b, t, motion)?;
            cut = cutoff(sc);
            continue;
        }
        tests += 1;
        if let Some(s) = straight_contact(&topo, &me, &body, cut) {
            offer_contact(state, sc, a, b, t, s, EventKind::Pair)?;
            cut = cutoff(sc);
        }
    }
    sc.pair_tests += tests;
    Ok(())
}

/// Predicts `a` against `b` by the general formulas: any partner (a disk, a wall, the dead)
/// and any flights (curved ones by conservative advancement).
#[inline]
fn predict_general<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    b: u32,
    t: f64,
    motion: Motion<V>,
) -> Result<(), Error> {
    sc.pair_tests += 1;
    let (body_a, body_b) = (sc.body[a as usize], sc.body[b as usize]);
    let status_b = sc.status[b as usize];
    if !status_b.in_play {
        return Ok(());
    }
    let ahead = sc.horizon - t;
    if ahead < 0.0 {
        return Ok(());
    }
    let Motion {
        pos: pa,
        vel: va,
        acc: aa,
    } = motion;
    let (kind, s) = if status_b.wall {
        let Some(cb) = state.critters.slot(b) else {
            return Ok(());
        };
        let Shape::Wall(wall) = cb.shape() else {
            return Ok(());
        };
        let d = state.topo.delta(cb.pos, pa);
        let r = body_a.radius * (1.0 - SKIN);
        let s = if aa.length_squared() == 0.0 {
            toi_wall_ball(wall, d, va, r)
        } else if contact_wall_ball(wall, d, r).is_some() {
            Some(0.0)
        } else {
            let vb = va.length() + aa.length() * ahead;
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
            match advance_to_contact(gap, vb, ahead, body_a.radius) {
                Advance::Hit(s) => Some(s),
                Advance::Miss => None,
                Advance::Continue(s) => {
                    offer(sc, t + s, a, b, EventKind::Recheck);
                    None
                }
            }
        };
        (EventKind::Wall, s)
    } else {
        let Motion {
            pos: pb,
            vel: vb,
            acc: ab,
        } = motion_at(sc, b, t);
        let d = state.topo.delta(pa, pb);
        let wv = vb - va;
        let ar = ab - aa;
        let r = (body_a.radius + body_b.radius) * (1.0 - SKIN);
        let s = if d.length_squared() < r * r {
            Some(0.0) // overlapping: collide now (approaching or not)
        } else if ar.length_squared() == 0.0 {
            toi_ball_ball(d, wv, r)
        } else {
            let speed = wv.length() + ar.length() * ahead;
            let gap = |s: f64| (d + wv * s + ar * (0.5 * s * s)).length() - r;
            match advance_to_contact(gap, speed, ahead, r) {
                Advance::Hit(s) => Some(s),
                Advance::Miss => None,
                Advance::Continue(s) => {
                    offer(sc, t + s, a, b, EventKind::Recheck);
                    None
                }
            }
        };
        (EventKind::Pair, s)
    };
    if let Some(s) = s {
        if s > ahead || sc.earliest.is_some_and(|e| t + s > e.time) {
            return Ok(());
        }
        offer_contact(state, sc, a, b, t, s, kind)?;
    }
    Ok(())
}

/// Offers the contact of `a` with `b` (a disk, or a wall) `s` after `t`, unless their rule says
/// they don't collide, or they touch now and were just handled.
#[inline(never)]
fn offer_contact<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    b: u32,
    t: f64,
    s: f64,
    kind: EventKind,
) -> Result<(), Error> {
    let (status_a, status_b) = (sc.status[a as usize], sc.status[b as usize]);
    let rule = match state.rules.cached(status_a.class, status_b.class) {
        Some(rule) => rule,
        None => {
            let (ca, cb) = (
                state.critters.slot(a).expect("live"),
                state.critters.slot(b).expect("live"),
            );
            state
                .rules
                .rule(&state.kinds, &state.topo, ca, cb)
                .map_err(|e| at_step(e, state.step_count))?
        }
    };
    if rule == Some(PairRule::DontCollide) {
        return Ok(());
    }
    if s == 0.0 {
        let just_met =
            sc.last_partner[a as usize] == b && (status_b.wall || sc.last_partner[b as usize] == a);
        if just_met || sc.stuck.contains(&pair_key(a, b)) {
            return Ok(()); // the pair was handled; its hook chose to leave them so
        }
    }
    offer(sc, t + s, a, b, kind);
    Ok(())
}

/// How conservative advancement ended.
enum Advance {
    /// In contact this long after the start.
    Hit(f64),
    /// No contact within the horizon.
    Miss,
    /// Out of iterations here, still apart: to be continued by a recheck.
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
