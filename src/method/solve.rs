//! `solve:n`: the discrete step with its contacts solved together, so that piles and stacks come
//! to rest.
//!
//! Pop's response takes one touching pair at a time and removes its whole overlap at once. In a
//! pile each such push moves a ball into its next neighbour, and under gravity the pile never
//! settles (`docs/stability.md`, the deep pile). Here the step moves and finds its contacts as
//! the discrete step does, then treats every touching pair whose caller keeps the default
//! response as one constraint of a system solved by sequential impulses (projected Gauss-Seidel):
//!
//! 1. each contact's wanted relative normal velocity is `-e v0` for the approach speed `v0` it
//!    has when the solve starts, or 0 when `v0` is below [`RESTING_STEPS`] steps of gravity (a
//!    resting contact does not bounce on its own weight);
//! 2. each contact starts from the impulse the same pair ended the last step with (the warm
//!    start: a deep pile's weight is carried over from step to step instead of being found
//!    again by the sweeps every step);
//! 3. `n` sweeps over the contacts, alternately forwards and backwards, each correct one
//!    contact's normal velocity towards its wanted value with an impulse, keeping the contact's
//!    accumulated impulse non-negative (contacts push, never pull); under `auto`, as many as the
//!    pile's depth in weight-bearing contacts asks ([`Sweeps::ByDepth`], `contact_depth`),
//!    since the sweeps carry its weight down one contact at a time;
//! 4. the critters are moved on by the solve's change of velocity times dt: the move advanced
//!    them by their velocities before it, and semi-implicit Euler advances them by the solved
//!    ones (a ball resting on the floor does not sink by g dt^2 every step);
//! 5. up to [`POSITION_SWEEPS`] sweeps move the pairs apart by [`POSITION_SHARE`] of their
//!    overlap beyond a slop of [`SLOP`] radii, split by inverse mass, without changing any
//!    velocity.
//!
//! An isolated pair gets exactly Pop's impulse `-(1 + e) v0 / (1/m1 + 1/m2)` in the first sweep,
//! and every impulse and position move is equal and opposite (by mass), so momentum is kept to
//! rounding and the centre of mass moves on undisturbed. Pairs whose caller has its own
//! `collide` hook are handed to it first, in the discrete step's order; the solve then takes the
//! remaining contacts where the hooks left the critters.
//!
//! The impulses carried to the next step are the only state the solve keeps
//! ([`crate::World::contact_impulses`]); recordings write them with every full state, so a run replays
//! exactly from any recorded state. Under gravity, critters at rest fall asleep and leave the
//! step until something wakes them ([`crate::method::sleep`]); their contacts' impulses are kept
//! for then.

use crate::error::Error;
use crate::method::sleep::Sleep;
use crate::pair_order::{pair_key, unpair_key};
use crate::step::events::CollisionEvent;
use crate::step::pairs::Pairs;
use crate::step::state::State;
use crate::vector::Vector;

/// Sweeps of `solve` when the method is named without a count.
pub const DEFAULT_SWEEPS: u32 = 8;

/// Restitution applies to contacts approaching faster than this many steps of gravity (`|g| dt`);
/// slower ones are resting and end at zero normal speed. 0 without gravity.
pub const RESTING_STEPS: f64 = 2.0;

/// Overlap left alone, in radii of the smaller critter of a pair (walls: the disk's).
pub const SLOP: f64 = 0.01;

/// Share of the overlap beyond the slop removed by each position sweep.
pub const POSITION_SHARE: f64 = 0.2;

/// Largest move of one pair in one position sweep, in radii of the smaller critter.
pub const LARGEST_CORRECTION: f64 = 0.2;

/// How many velocity sweeps a solve takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sweeps {
    /// Exactly this many (`solve:n`).
    Fixed(u32),
    /// As many as the pile's depth asks ([`sweeps_for_depth`]), from `least` to `most`
    /// (`auto`).
    ByDepth {
        /// Sweeps at least.
        least: u32,
        /// Sweeps at most.
        most: u32,
    },
}

/// Layers of a pile one velocity sweep carries, for [`Sweeps::ByDepth`].
pub const LAYERS_PER_SWEEP: u32 = 2;

/// The sweeps a pile `depth` contacts deep gets: one per [`LAYERS_PER_SWEEP`] layers, from
/// `least` to `most`.
pub fn sweeps_for_depth(depth: u32, least: u32, most: u32) -> u32 {
    depth
        .div_ceil(LAYERS_PER_SWEEP)
        .clamp(least, most.max(least))
}

/// Position sweeps per step (fewer once every overlap is within three slops).
pub const POSITION_SWEEPS: u32 = 3;

/// The sweeps take the contacts this many apart (see [`respond`]).
const INTERLEAVE: usize = 16;

/// One contact of the velocity sweeps: only what they read, so that the rows of a large pile
/// stay in the core's own cache over the sweeps.
#[derive(Clone, Copy, Debug)]
struct Row<V> {
    /// Caller's and arg's slots.
    a: u32,
    b: u32,
    /// Unit normal from caller to arg.
    n: V,
    /// 1 / (1/m_a + 1/m_b).
    k: f64,
    /// Wanted relative normal velocity.
    target: f64,
    /// Accumulated impulse on the arg along `n`.
    impulse: f64,
}

/// The rest of a contact, beside its [`Row`]: what the position sweeps and the events need.
#[derive(Clone, Copy, Debug)]
struct Rest {
    /// Overlap found by the narrow phase (the position sweeps hold the normal and follow the
    /// overlap to first order in the pair's moves).
    depth: f64,
    /// Smaller radius of the pair.
    scale: f64,
    /// The row's collision event, counted from the solve's first.
    event: u32,
}

/// A critter's velocity and inverse mass, read together by every row.
#[derive(Clone, Copy, Debug)]
struct Body<V> {
    vel: V,
    inv_mass: f64,
}

/// The solve's working arrays, kept between steps only to save allocations.
#[derive(Debug)]
pub(crate) struct Scratch<V> {
    rows: Vec<Row<V>>,
    rests: Vec<Rest>,
    spare: Vec<Row<V>>,
    spare_rests: Vec<Rest>,
    /// Velocity and inverse mass, position shift and position by slot.
    bodies: Vec<Body<V>>,
    shift: Vec<V>,
    pos: Vec<V>,
    plain: Vec<(u32, u32)>,
    /// The rows' pair keys, in the order the rows were built.
    keys: Vec<u64>,
    /// Velocity sweeps the last solve took (0 with no contacts).
    pub(crate) swept: u32,
    /// Whether the last step was [`rest`]'s: every kept impulse is of two still critters.
    rested: bool,
    graph: Graph,
    /// The last step's accumulated impulses by pair key, ascending: the only state the solve
    /// carries from one step to the next (recorded with every full state).
    pub(crate) warm: Vec<(u64, f64)>,
}

impl<V> Default for Scratch<V> {
    fn default() -> Self {
        Scratch {
            rows: Vec::new(),
            rests: Vec::new(),
            spare: Vec::new(),
            spare_rests: Vec::new(),
            bodies: Vec::new(),
            shift: Vec::new(),
            pos: Vec::new(),
            plain: Vec::new(),
            keys: Vec::new(),
            swept: 0,
            rested: false,
            graph: Graph::default(),
            warm: Vec::new(),
        }
    }
}

/// The response stage of `solve:n`: hooks first, then the rest solved together, after a move of
/// `h` (the step, or under `auto` a substep of it). Returns how many pairs were handled.
pub(crate) fn respond<V: Vector>(
    state: &mut State<V>,
    pairs: &mut Pairs<V>,
    s: &mut Scratch<V>,
    sleep: &mut Sleep<V>,
    sweeps: Sweeps,
    h: f64,
) -> Result<usize, Error> {
    let mut handled = 0;
    s.rested = false;
    // 1. The hooks, disk pairs then wall pairs, in the discrete step's order.
    s.plain.clear();
    let plain = &mut s.plain;
    let result = pairs.contacts.iter().try_for_each(|&(caller, arg)| {
        hook_or_keep(state, sleep, caller, arg, plain, &mut handled)
    });
    result?;
    let wall_pairs = std::mem::take(&mut pairs.wall_pairs);
    let result = wall_pairs.iter().try_for_each(|&(first, second, ask)| {
        let Some((caller, arg)) = state.touching_wall_pair(first, second, ask)? else {
            return Ok(());
        };
        pairs.contacts.push((caller, arg));
        hook_or_keep(state, sleep, caller, arg, plain, &mut handled)
    });
    pairs.wall_pairs = wall_pairs;
    result?;
    sleep.flush(); // the islands of the sleepers the hooks took

    // 2. The rows, where the hooks left the critters.
    s.bodies.clear();
    s.pos.clear();
    let still = sleep.still();
    // No contacts to solve (a pile asleep): no bodies either.
    let slots = match s.plain.is_empty() {
        true => &[][..],
        false => state.critters.slot_slice(),
    };
    for (i, slot) in slots.iter().enumerate() {
        match slot {
            Some(c) if c.in_play() => {
                // To an awake critter a sleeper is as heavy as a wall.
                let asleep = still.get(i).copied().unwrap_or(false);
                s.bodies.push(Body {
                    vel: c.vel,
                    inv_mass: if asleep { 0.0 } else { c.inv_mass() },
                });
                s.pos.push(c.pos);
            }
            _ => {
                s.bodies.push(Body {
                    vel: V::zero(),
                    inv_mass: 0.0,
                });
                s.pos.push(V::zero());
            }
        }
    }
    s.shift.clear();
    s.shift.extend(s.bodies.iter().map(|body| body.vel));
    let resting = RESTING_STEPS * state.gravity.length() * h;
    s.rows.clear();
    s.rests.clear();
    s.keys.clear();
    let first_event = state.events.collisions.len();
    let mut warm = Warm::new(&s.warm);
    for &(a, b) in &s.plain {
        let (Some(ca), Some(cb)) = (state.critters.slot(a), state.critters.slot(b)) else {
            continue;
        };
        if !ca.in_play() || !cb.in_play() {
            continue;
        }
        let Some(c) = crate::default_response::contact_between(&state.topo, ca, cb) else {
            continue;
        };
        let (ba, bb) = (s.bodies[a as usize], s.bodies[b as usize]);
        let (ia, ib) = (ba.inv_mass, bb.inv_mass);
        if ia + ib == 0.0 {
            continue; // two fixed critters: nothing can move
        }
        let v0 = (bb.vel - ba.vel).dot(c.normal);
        let e = ca.restitution().min(cb.restitution());
        let scale = match (ca.is_wall(), cb.is_wall()) {
            (true, _) => cb.radius,
            (_, true) => ca.radius,
            _ => ca.radius.min(cb.radius),
        };
        // The last step's impulse of the pair is given again before the sweeps (warm start),
        // once every row's approach speed is known.
        let key = pair_key(a, b);
        let start = warm.impulse(key);
        s.keys.push(key);
        s.rows.push(Row {
            a,
            b,
            n: c.normal,
            k: 1.0 / (ia + ib),
            target: if v0 < -resting { -e * v0 } else { 0.0 },
            impulse: start,
        });
        s.rests.push(Rest {
            depth: c.depth,
            scale,
            event: s.rests.len() as u32,
        });
        state.events.collisions.push(CollisionEvent {
            caller: ca.id,
            arg: cb.id,
            point: ca.pos + c.point,
            normal: c.normal,
            impulse: 0.0,
        });
    }

    for row in &s.rows {
        let (a, b) = (row.a as usize, row.b as usize);
        let ja = row.impulse * s.bodies[a].inv_mass;
        let jb = row.impulse * s.bodies[b].inv_mass;
        s.bodies[a].vel -= row.n * ja;
        s.bodies[b].vel += row.n * jb;
    }

    // Rows next to each other in the contact order mostly share a critter, and each would
    // wait for the one before it to store its velocity: taken INTERLEAVE apart, the sweeps'
    // neighbours are mostly independent and their work overlaps.
    s.spare.clear();
    s.spare_rests.clear();
    for start in 0..INTERLEAVE.min(s.rows.len()) {
        s.spare.extend(s.rows[start..].iter().step_by(INTERLEAVE));
        s.spare_rests
            .extend(s.rests[start..].iter().step_by(INTERLEAVE));
    }
    std::mem::swap(&mut s.rows, &mut s.spare);
    std::mem::swap(&mut s.rests, &mut s.spare_rests);

    // 3. Velocities: sweeps of sequential impulses, alternately forwards and backwards.
    let count = match sweeps {
        Sweeps::Fixed(n) => n,
        Sweeps::ByDepth { least, most } => {
            let g = state.gravity.length();
            let down = if g > 0.0 {
                state.gravity * (1.0 / g)
            } else {
                V::zero()
            };
            let depth = contact_depth(&s.rows, &s.bodies, down, &mut s.graph);
            sweeps_for_depth(depth, least, most)
        }
    };
    s.swept = if s.rows.is_empty() { 0 } else { count };
    for sweep in 0..s.swept {
        if sweep % 2 == 0 {
            for row in s.rows.iter_mut() {
                push_velocities(row, &mut s.bodies);
            }
        } else {
            for row in s.rows.iter_mut().rev() {
                push_velocities(row, &mut s.bodies);
            }
        }
    }

    // The move advanced each critter by its velocity before the solve; it should have gone
    // by the solved one (x + v' h, semi-implicit Euler with the impulses in v'): a ball
    // resting on the floor does not sink by g h^2 every step. `shift` held the velocities
    // before the solve.
    for (shift, body) in s.shift.iter_mut().zip(&s.bodies) {
        *shift = (body.vel - *shift) * h;
    }

    // 4. Positions: part of each overlap removed, velocities untouched.
    for _ in 0..POSITION_SWEEPS {
        let mut deepest = f64::NEG_INFINITY;
        for (row, rest) in s.rows.iter().zip(&s.rests) {
            let (a, b) = (row.a as usize, row.b as usize);
            let n = row.n;
            let depth = rest.depth - (s.shift[b] - s.shift[a]).dot(n);
            let slop = SLOP * rest.scale;
            deepest = deepest.max(depth - 3.0 * slop);
            let fix = (POSITION_SHARE * (depth - slop)).min(LARGEST_CORRECTION * rest.scale);
            if fix > 0.0 {
                let push = fix * row.k;
                s.shift[a] -= n * (push * s.bodies[a].inv_mass);
                s.shift[b] += n * (push * s.bodies[b].inv_mass);
            }
        }
        if deepest <= 0.0 {
            break;
        }
    }

    // 5. Back to the critters; the events get their impulses.
    for (row, rest) in s.rows.iter().zip(&s.rests) {
        if let Some(event) = state
            .events
            .collisions
            .get_mut(first_event + rest.event as usize)
        {
            event.impulse = row.impulse;
        }
    }
    // The impulses kept for the next step's warm start, in key order: the rows were built
    // from two runs in key order (disk pairs, then wall pairs), merged here.
    let impulses: Vec<f64> = state.events.collisions[first_event..]
        .iter()
        .map(|e| e.impulse)
        .collect();
    // Pairs of sleepers (or of a sleeper and a wall) had no row: their impulses are kept
    // as they were, for when the island wakes.
    let still = sleep.still();
    let asleep: Vec<(u64, f64)> = match still.is_empty() {
        true => Vec::new(),
        false => s
            .warm
            .iter()
            .filter(|w| both_still(still, w.0))
            .copied()
            .collect(),
    };
    s.warm.clear();
    let split = s
        .keys
        .windows(2)
        .position(|w| w[1] < w[0])
        .map_or(s.keys.len(), |i| i + 1);
    let (mut i, mut j) = (0, split);
    while i < split || j < s.keys.len() {
        let take_first = j == s.keys.len() || (i < split && s.keys[i] < s.keys[j]);
        let k = if take_first { &mut i } else { &mut j };
        if impulses[*k] > 0.0 {
            s.warm.push((s.keys[*k], impulses[*k]));
        }
        *k += 1;
    }
    if !asleep.is_empty() {
        let solved = std::mem::take(&mut s.warm);
        s.warm = merge_by_key(&solved, &asleep);
    }
    if !s.rows.is_empty() {
        let slots = state.critters.slots_mut_moving().iter_mut().enumerate();
        for (i, c) in slots.filter_map(|(i, c)| Some((i, c.as_mut()?))) {
            if s.bodies[i].inv_mass > 0.0 {
                c.vel = s.bodies[i].vel;
                c.pos = s.pos[i] + s.shift[i];
            }
        }
    }
    // The hooks or the position sweeps may have pushed a critter across the edge.
    state.wrap_positions();
    if sleep.active {
        let speed = crate::method::sleep::SLEEP_SPEED_STEPS * state.gravity.length() * h;
        sleep.after_solve(state.critters.slots_mut_moving(), &pairs.contacts, speed);
    }
    Ok(handled + s.rows.len())
}

/// The solve's part of a step in which every critter sleeps or is a wall: no row, and of the
/// kept impulses those of two still critters (what [`respond`] keeps when it has no row).
/// `removed` tells whether critters were removed since the last step.
pub(crate) fn rest<V: Vector>(s: &mut Scratch<V>, sleep: &Sleep<V>, removed: bool) {
    s.swept = 0;
    // After a step like this one, only a removal can make a kept pair's critter not still.
    let filtered = std::mem::replace(&mut s.rested, true);
    if filtered && !removed {
        return;
    }
    let still = sleep.still();
    s.warm.retain(|w| both_still(still, w.0));
}

/// True when both critters of the pair `key` are still (`still` by slot: sleepers and walls).
fn both_still(still: &[bool], key: u64) -> bool {
    let (lo, hi) = unpair_key(key);
    let is_still = |slot: u32| still.get(slot as usize).copied().unwrap_or(false);
    is_still(lo) && is_still(hi)
}

/// Calls `caller`'s own `collide` on the pair (counted in `handled` when it touched), or
/// keeps the pair for the solve when the caller's kind has none.
fn hook_or_keep<V: Vector>(
    state: &mut State<V>,
    sleep: &mut Sleep<V>,
    caller: u32,
    arg: u32,
    plain: &mut Vec<(u32, u32)>,
    handled: &mut usize,
) -> Result<(), Error> {
    if !own_collide(state, caller) {
        if state.kinds.tracks_touch() {
            state.note_touch(caller, arg);
        }
        plain.push((caller, arg));
        return Ok(());
    }
    sleep.stir(caller, arg);
    if state.collide_pair(caller, arg)? {
        *handled += 1;
    }
    Ok(())
}

/// True when `slot`'s kind has its own `collide` hook.
fn own_collide<V: Vector>(state: &State<V>, slot: u32) -> bool {
    state
        .critters
        .slot(slot)
        .is_some_and(|c| state.kinds.get(c.kind()).has_collide)
}

/// Two lists ascending by key, with no key in both, merged.
fn merge_by_key(a: &[(u64, f64)], b: &[(u64, f64)]) -> Vec<(u64, f64)> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        if j == b.len() || (i < a.len() && a[i].0 < b[j].0) {
            out.push(a[i]);
            i += 1;
        } else {
            out.push(b[j]);
            j += 1;
        }
    }
    out
}

/// Looks up the last step's impulses for keys that come in ascending runs.
struct Warm<'a> {
    list: &'a [(u64, f64)],
    at: usize,
    last: u64,
}

impl<'a> Warm<'a> {
    fn new(list: &'a [(u64, f64)]) -> Self {
        Warm {
            list,
            at: 0,
            last: 0,
        }
    }

    /// The impulse kept for `key`, or 0.
    fn impulse(&mut self, key: u64) -> f64 {
        if key < self.last {
            self.at = 0; // a new run
        }
        self.last = key;
        while self.list.get(self.at).is_some_and(|&(k, _)| k < key) {
            self.at += 1;
        }
        match self.list.get(self.at) {
            Some(&(k, j)) if k == key => j,
            _ => 0.0,
        }
    }
}

/// One contact's impulse of a velocity sweep.
#[inline]
fn push_velocities<V: Vector>(row: &mut Row<V>, bodies: &mut [Body<V>]) {
    let (a, b) = (row.a as usize, row.b as usize);
    let vn = (bodies[b].vel - bodies[a].vel).dot(row.n);
    let total = (row.impulse - (vn - row.target) * row.k).max(0.0);
    let j = total - row.impulse;
    row.impulse = total;
    bodies[a].vel -= row.n * (j * bodies[a].inv_mass);
    bodies[b].vel += row.n * (j * bodies[b].inv_mass);
}

/// The contact graph's working arrays for [`contact_depth`].
#[derive(Debug, Default)]
pub(crate) struct Graph {
    /// Where each body's neighbours start in `next` (one more entry than bodies).
    start: Vec<u32>,
    next: Vec<u32>,
    /// Contacts from the nearest support, `u32::MAX` for not reached yet.
    depth: Vec<u32>,
    queue: Vec<u32>,
}

/// A contact carries weight when its normal is at least this far from horizontal: the cosine
/// between the normal and gravity (about 6 degrees from horizontal).
pub const LOAD_BEARING: f64 = 0.1;

/// How many contacts deep the pile of `rows` is: the most contacts any movable body is from the
/// nearest support (a wall, a fixed critter or a sleeper: a body of zero inverse mass) along
/// touching pairs that carry weight (their normal at least [`LOAD_BEARING`] along `down`, the
/// direction of gravity), by breadth-first search from every support at once. A ball against a
/// side wall is not held up by it (walls have no friction), and bodies that reach no support (a
/// cluster in free fall) carry no weight and do not count. 0 with no contacts.
fn contact_depth<V: Vector>(rows: &[Row<V>], bodies: &[Body<V>], down: V, g: &mut Graph) -> u32 {
    let n = bodies.len();
    let bearing = |row: &&Row<V>| row.n.dot(down).abs() >= LOAD_BEARING;
    g.start.clear();
    g.start.resize(n + 1, 0);
    for row in rows.iter().filter(bearing) {
        g.start[row.a as usize + 1] += 1;
        g.start[row.b as usize + 1] += 1;
    }
    for i in 0..n {
        g.start[i + 1] += g.start[i];
    }
    g.next.clear();
    g.next.resize(g.start[n] as usize, 0);
    // `depth` serves as each body's fill cursor first.
    g.depth.clear();
    g.depth.extend_from_slice(&g.start[..n]);
    for row in rows.iter().filter(bearing) {
        for (from, to) in [(row.a, row.b), (row.b, row.a)] {
            let at = &mut g.depth[from as usize];
            g.next[*at as usize] = to;
            *at += 1;
        }
    }
    g.queue.clear();
    for (i, body) in bodies.iter().enumerate() {
        let touched = g.start[i + 1] > g.start[i];
        if body.inv_mass == 0.0 && touched {
            g.depth[i] = 0;
            g.queue.push(i as u32);
        } else {
            g.depth[i] = u32::MAX;
        }
    }
    let (mut head, mut deepest) = (0, 0);
    while let Some(&at) = g.queue.get(head) {
        head += 1;
        let d = g.depth[at as usize] + 1;
        let (lo, hi) = (g.start[at as usize], g.start[at as usize + 1]);
        for k in lo..hi {
            let to = g.next[k as usize] as usize;
            if g.depth[to] == u32::MAX {
                g.depth[to] = d;
                deepest = d;
                g.queue.push(to as u32);
            }
        }
    }
    deepest
}
