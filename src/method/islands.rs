//! Islands for `auto`: the live disks cut into groups that cannot meet within the coming step,
//! each with the regime that decides its method (`partition`).
//!
//! **Own reach first.** A free disk moves in a step at most `(v + 2|g| dt) dt` at its own speed
//! `v` (gravity adds `|g| dt` to a speed over the step, twice for a bounce off a support). Disks
//! whose gap is within their two reaches are joined (a hashed grid, about two buckets per
//! disk; the few fastest or largest disks walk the cells their reach spans). At these reaches each
//! island gets its regime ([`Regime`]), under gravity:
//! - *resting*: a disk of it is within reach of a wall, a fixed critter, a bouncing edge or a
//!   sleeper of `solve:n` and approaches it slower than [`RESTING_STEPS`] steps of gravity: it
//!   is held up, and its contacts carry weight, which is what `solve:N` is for;
//! - *impacts*: held up by nothing, and two of its disks within reach approach each other. It
//!   falls as a whole, gravity does not change its disks' relative motion, and its contacts are
//!   impacts (a cradle struck in mid-air, a clump thrown): only the exact event flight keeps
//!   them;
//! - *clump*: as impacts, but a disk of it is not perfectly elastic: a chain of inelastic
//!   impacts need not end within the step (inelastic collapse), so it is solved;
//! - *free*: held up by nothing, and no two of its disks approach each other.
//!
//! **Then each island's energy, when the step may be cut.** When every island rests, or none
//! rests and none holds impacts, the whole scene takes one method and these islands are final.
//! Otherwise the islands must not meet: collisions inside an island (restitution at most 1,
//! walls and fixed critters not moving) cannot give a disk more than all of its island's
//! kinetic energy, `u = sqrt(2 E / m)`, so its reach grows to that speed's, plus twice the
//! island's deepest overlap (which a separation may push a disk by). Islands whose boxes meet
//! are tested disk by disk with these reaches and joined, and this repeats until no two join
//! (joining only adds energy). Two islands then cannot touch during the step, so stepping each
//! alone gives the same result as stepping them together. Joining keeps an island of impacts
//! held by nothing and makes an island rest when a part rested, so the regimes read at own
//! reach carry over. Walls, fixed critters, the world's bouncing edges and sleepers (which do
//! not move) join no island: every island sees them all.
//!
//! Determinism: the union keeps the lower slot as each root, and islands are listed by their
//! lowest slot, so the result depends on neither thread count nor the order of the passes.

use crate::border::Border;
use crate::contact::contact_wall_ball;
use crate::critter::Critter;
use crate::step::state::State;
use crate::tolerance::ROUNDING_MARGIN;
use crate::vector::Vector;

/// A disk approaching a support slower than this many steps of gravity (`|g| dt`) rests on it.
pub const RESTING_STEPS: f64 = 2.0;

/// How an island's contacts behave in the coming step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Regime {
    /// Held up by nothing, and no two of its disks approach each other: none meet in the step.
    Free,
    /// Held up by a wall, a fixed critter or an edge: its contacts carry weight.
    Resting,
    /// Held up by nothing: its contacts are impacts between perfectly elastic disks in flight.
    Impact,
    /// Held up by nothing, two of its disks approach each other, and one is not perfectly
    /// elastic: a chain of inelastic impacts need not end within the step (inelastic collapse),
    /// so it is solved as a resting island is.
    Clump,
}

impl Regime {
    /// A few words for the island summary.
    pub fn describe(self) -> &'static str {
        match self {
            Regime::Free => "in flight, no two meet",
            Regime::Resting => "resting contacts under gravity",
            Regime::Impact => "impacts in flight",
            Regime::Clump => "inelastic impacts in flight",
        }
    }
}

/// The islands of one step.
#[derive(Clone, Debug, Default)]
pub struct Islands {
    /// Each live disk's island, by slot (`u32::MAX` for empty slots, walls and fixed critters).
    pub of_slot: Vec<u32>,
    /// Per island, in the order of their lowest slot: that slot, its size and its regime.
    pub list: Vec<Island>,
}

/// One island.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Island {
    /// Its lowest slot (its name).
    pub first: u32,
    /// How many disks it holds.
    pub size: usize,
    /// How its contacts behave.
    pub regime: Regime,
}

/// Disks whose radius and reach pass the cells' are tested against all; the grid's cells are
/// sized so that at most this many do.
const MOST_WIDE: usize = 16;

/// Not in any island.
pub const NO_ISLAND: u32 = u32::MAX;
/// A sleeper in no island: no awake disk can reach it in the step.
pub const ASLEEP: u32 = u32::MAX - 1;

/// What the partition reads of a disk.
struct Disk<V> {
    slot: u32,
    pos: V,
    vel: V,
    radius: f64,
    inv_mass: f64,
    /// How far it may move in the step.
    reach: f64,
    /// A sleeper of `solve:n` (it does not move).
    asleep: bool,
    /// Restitution 1.
    elastic: bool,
}

/// The supports: walls and fixed critters (which join no island).
struct Support<'a, V: Vector> {
    critter: &'a Critter<V>,
}

/// Partitions the live disks of `state` into islands (see the module docs).
///
/// `asleep` marks, by slot, the sleepers of `solve:n` (empty when none sleeps): they do not
/// move in the step, so they are only tested against awake disks, and an island that holds one
/// rests on it. Sleepers that no awake disk can reach belong to no island ([`ASLEEP`]). `dt`:
/// the coming step.
pub(crate) fn partition<V: Vector>(state: &State<V>, asleep: &[bool], dt: f64) -> Islands {
    let g = state.gravity.length();
    let slots = state.critters.slot_slice();
    let mut disks = Vec::new();
    let mut supports = Vec::new();
    for (i, c) in slots.iter().enumerate() {
        let Some(c) = c.as_ref().filter(|c| c.in_play()) else {
            continue;
        };
        if c.is_wall() || c.fixed {
            supports.push(Support { critter: c });
        } else {
            disks.push(Disk {
                slot: i as u32,
                pos: c.pos,
                vel: c.vel,
                radius: c.radius,
                inv_mass: c.inv_mass(),
                reach: 0.0,
                asleep: asleep.get(i).copied().unwrap_or(false),
                elastic: c.restitution() >= 1.0,
            });
        }
    }
    let n = disks.len();
    if disks.iter().all(|d| d.asleep) {
        // A pile asleep whole: nothing to cut (and nothing to pay for it).
        let mut of_slot = vec![NO_ISLAND; slots.len()];
        for d in &disks {
            of_slot[d.slot as usize] = ASLEEP;
        }
        return Islands {
            of_slot,
            list: Vec::new(),
        };
    }
    let mut parent: Vec<u32> = (0..n as u32).collect();
    // First pass: each disk's own speed; later passes: its island's energy.
    for d in disks.iter_mut() {
        d.reach = reach(d.vel.length(), g, dt);
    }
    let mut deepest = vec![0.0f64; n];
    let mut closing = vec![false; n];
    link_pairs(
        state,
        &disks,
        &mut parent,
        Some((&mut deepest, &mut closing)),
    );
    // Held and approaching are read at the disks' own reaches; wider reaches only join islands.
    let held: Vec<bool> = disks
        .iter()
        .map(|d| d.asleep || supported(&state.topo, &supports, d, RESTING_STEPS * g * dt))
        .collect();
    if !may_mix(&held, &closing, &mut parent) {
        return classify(&disks, &held, &closing, &mut parent, slots.len());
    }
    loop {
        // The islands' energies and deepest overlaps, gathered at their roots.
        let mut energy = vec![0.0f64; n];
        let mut depth = vec![0.0f64; n];
        for (k, d) in disks.iter().enumerate() {
            let root = find(&mut parent, k) as usize;
            if d.inv_mass > 0.0 {
                energy[root] += 0.5 * d.vel.length_squared() / d.inv_mass;
            }
            depth[root] = depth[root].max(deepest[k]);
        }
        let mut grew = false;
        for (k, d) in disks.iter_mut().enumerate() {
            let root = find(&mut parent, k) as usize;
            let u = (2.0 * energy[root] * d.inv_mass).sqrt().max(d.vel.length());
            let r = reach(u, g, dt) + 2.0 * depth[root];
            if r > d.reach {
                d.reach = r;
                grew = true;
            }
        }
        if !grew {
            break;
        }
        // Wider reaches may join islands: link again, and stop when none joined.
        let joined = if state.topo.wraps() {
            let before = count_roots(&mut parent);
            link_pairs(state, &disks, &mut parent, None);
            count_roots(&mut parent) != before
        } else {
            link_islands(&disks, &mut parent)
        };
        if !joined {
            break;
        }
    }
    classify(&disks, &held, &closing, &mut parent, slots.len())
}

/// How far a disk at speed `u` may move in a step (see the module docs), with a margin for
/// rounding.
fn reach(u: f64, g: f64, dt: f64) -> f64 {
    (u + 2.0 * g * dt) * dt * (1.0 + 1e3 * ROUNDING_MARGIN)
}

/// Joins the disks within their reaches, over a uniform grid of cells at least as wide as the
/// widest reach of the disks that fit one (the others are tested against everyone).
fn link_pairs<V: Vector>(
    state: &State<V>,
    disks: &[Disk<V>],
    parent: &mut [u32],
    mut first: Option<(&mut [f64], &mut [bool])>,
) {
    let n = disks.len();
    if n < 2 {
        return;
    }
    let topo = &state.topo;
    let size = topo.size();
    // Cells twice as wide as the largest radius plus reach, save the `MOST_WIDE` largest:
    // those disks are tested against all (a few fast or large disks do not widen every cell).
    // The cells are hashed into about two buckets per disk, so a large box with a small pile
    // keeps small cells.
    let mut spans: Vec<f64> = disks.iter().map(|d| d.radius + d.reach).collect();
    let widest = if n > MOST_WIDE {
        let (_, nth, _) = spans.select_nth_unstable_by(MOST_WIDE, |a, b| b.total_cmp(a));
        *nth
    } else {
        spans.iter().copied().fold(0.0, f64::max)
    };
    let mut side = 2.0 * widest;
    if !(side.is_finite() && side > 0.0) {
        side = 1.0;
    }
    let mut dims = [1usize; 3];
    for (a, dim) in dims.iter_mut().enumerate().take(V::DIM) {
        *dim = ((size.get(a) / side).floor() as usize).clamp(1, 1 << 20);
    }
    let cell_side: Vec<f64> = (0..V::DIM).map(|a| size.get(a) / dims[a] as f64).collect();
    let narrowest = cell_side.iter().copied().fold(f64::INFINITY, f64::min);
    let coord = |p: V| {
        let mut c = [0usize; 3];
        for a in 0..V::DIM {
            let x = ((p.get(a) - topo.min.get(a)) / cell_side[a]).floor();
            c[a] = if x.is_finite() {
                (x.max(0.0) as usize).min(dims[a] - 1)
            } else {
                0
            };
        }
        c
    };
    let bits = (2 * n).next_power_of_two().trailing_zeros().max(1);
    let cells = 1usize << bits;
    // A cell's bucket (Fibonacci hashing of its index); cells that share one are both
    // visited, which only repeats tests.
    let bucket = |index: u64| (index.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (64 - bits)) as usize;
    let key = |c: [usize; 3]| {
        bucket(((c[2] as u64 * dims[1] as u64) + c[1] as u64) * dims[0] as u64 + c[0] as u64)
    };
    let wide: Vec<usize> = (0..n)
        .filter(|&k| disks[k].radius + disks[k].reach > 0.5 * narrowest)
        .collect();
    let is_wide = |k: usize| disks[k].radius + disks[k].reach > 0.5 * narrowest;
    // Counting sort of the narrow disks by cell.
    let mut start = vec![0usize; cells + 1];
    let mut cell_of = vec![usize::MAX; n];
    for k in 0..n {
        if !is_wide(k) {
            let c = key(coord(disks[k].pos));
            cell_of[k] = c;
            start[c + 1] += 1;
        }
    }
    for c in 0..cells {
        start[c + 1] += start[c];
    }
    let mut fill = start.clone();
    let mut order = vec![0usize; start[cells]];
    for k in 0..n {
        if cell_of[k] != usize::MAX {
            order[fill[cell_of[k]]] = k;
            fill[cell_of[k]] += 1;
        }
    }
    // The first pass (own reaches) also notes approaching pairs and overlaps.
    let test =
        |a: usize, b: usize, parent: &mut [u32], first: &mut Option<(&mut [f64], &mut [bool])>| {
            let (da, db) = (&disks[a], &disks[b]);
            if da.asleep && db.asleep {
                return; // neither moves
            }
            let offset = topo.delta(da.pos, db.pos);
            let (dist2, touch) = (offset.length_squared(), da.radius + db.radius);
            let within = touch + da.reach + db.reach;
            if dist2 <= within * within {
                union(parent, a, b);
                if let Some((deepest, closing)) = first {
                    if (db.vel - da.vel).dot(offset) < 0.0 {
                        closing[a] = true;
                        closing[b] = true;
                    }
                    if dist2 < touch * touch {
                        let depth = touch - dist2.sqrt();
                        deepest[a] = deepest[a].max(depth);
                        deepest[b] = deepest[b].max(depth);
                    }
                }
            }
        };
    let wraps = topo.wraps();
    // The cells around cell `c` along axis `ax`, each listed once (a wrapped axis of fewer than
    // three cells repeats them). Distinct cells that share a bucket only repeat tests.
    let around = |c: usize, ax: usize| {
        let (mut out, mut len) = ([0usize; 3], 0);
        let m = dims[ax] as i64;
        for v in [c as i64 - 1, c as i64, c as i64 + 1] {
            let v = if (0..m).contains(&v) {
                v as usize
            } else if wraps {
                v.rem_euclid(m) as usize
            } else {
                continue;
            };
            if !out[..len].contains(&v) {
                out[len] = v;
                len += 1;
            }
        }
        (out, len)
    };
    // Awake disks look around their cells; sleepers are only looked at.
    for (a, disk) in disks.iter().enumerate() {
        if cell_of[a] == usize::MAX || disk.asleep {
            continue;
        }
        let ca = coord(disk.pos);
        let (xs, nx) = around(ca[0], 0);
        let (ys, ny) = around(ca[1], 1);
        let (zs, nz) = around(ca[2], 2);
        for &z in &zs[..nz] {
            for &y in &ys[..ny] {
                let row = (z as u64 * dims[1] as u64 + y as u64) * dims[0] as u64;
                for &x in &xs[..nx] {
                    let k = bucket(row + x as u64);
                    for &b in &order[start[k]..start[k + 1]] {
                        if b > a || disks[b].asleep {
                            test(a, b, parent, &mut first);
                        }
                    }
                }
            }
        }
    }
    // A wide disk meets a narrow one only within its own span and half the narrowest cell: it
    // walks the cells of that box when they are fewer than the disks, else tests them all.
    let mut seen = Vec::new();
    for (i, &a) in wide.iter().enumerate() {
        for &b in &wide[i + 1..] {
            test(a, b, parent, &mut first);
        }
        let da = &disks[a];
        let span = da.radius + da.reach + 0.5 * narrowest;
        let mut lo = [0i64; 3];
        let mut hi = [0i64; 3];
        let mut count = 1.0f64;
        for ax in 0..V::DIM {
            let at = |x: f64| ((x - topo.min.get(ax)) / cell_side[ax]).floor();
            let (l, h) = (at(da.pos.get(ax) - span), at(da.pos.get(ax) + span));
            let m = dims[ax] as f64;
            // Wrapped, a box as wide as the grid covers it all; unwrapped, it is clamped.
            let (l, h) = if wraps {
                if h - l + 1.0 >= m {
                    (0.0, m - 1.0)
                } else {
                    (l, h)
                }
            } else {
                (l.max(0.0), h.min(m - 1.0))
            };
            if l.is_nan() || h.is_nan() || l > h {
                count = f64::INFINITY; // NaN (never: the grid is finite) or empty
                break;
            }
            count *= h - l + 1.0;
            (lo[ax], hi[ax]) = (l as i64, h as i64);
        }
        if count > n as f64 {
            for b in 0..n {
                if !is_wide(b) {
                    test(a, b, parent, &mut first);
                }
            }
            continue;
        }
        seen.clear();
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let mut c = [0usize; 3];
                    for (ax, v) in [x, y, z].into_iter().enumerate().take(V::DIM) {
                        c[ax] = v.rem_euclid(dims[ax] as i64) as usize;
                    }
                    seen.push(key(c));
                }
            }
        }
        seen.sort_unstable();
        seen.dedup();
        for &k in &seen {
            for &b in &order[start[k]..start[k + 1]] {
                test(a, b, parent, &mut first);
            }
        }
    }
}

/// Two islands whose disks make more pairs than this are joined when their boxes meet, without
/// testing the pairs (joining more is always safe).
const MOST_PAIRS_TESTED: usize = 1 << 14;

/// Islands of more disks than this have their members sorted along x for the test against
/// another island.
const SORTED_MEMBERS: usize = 32;

/// Joins the islands of `parent` that hold two disks within their reaches; true when some
/// joined. Only islands whose boxes (their disks' centres widened by radius and reach, in a
/// border that does not wrap) meet are tested disk by disk ([`box_pairs::meeting`]); the joins
/// are made after all the tests, and each set's root is its lowest disk whatever their order.
fn link_islands<V: Vector>(disks: &[Disk<V>], parent: &mut [u32]) -> bool {
    let n = disks.len();
    // Per root: its box and its disks (a counting sort by root).
    let mut root_of = vec![0u32; n];
    let mut awake = vec![false; n];
    let mut count = vec![0usize; n + 1];
    let mut lo = vec![V::splat(f64::INFINITY); n];
    let mut hi = vec![V::splat(f64::NEG_INFINITY); n];
    for (k, d) in disks.iter().enumerate() {
        let r = find(parent, k) as usize;
        root_of[k] = r as u32;
        count[r + 1] += 1;
        awake[r] |= !d.asleep;
        let w = d.radius + d.reach;
        for ax in 0..V::DIM {
            let x = d.pos.get(ax);
            let (l, h) = (lo[r].get(ax).min(x - w), hi[r].get(ax).max(x + w));
            lo[r].set(ax, l);
            hi[r].set(ax, h);
        }
    }
    for r in 0..n {
        count[r + 1] += count[r];
    }
    let mut fill = count.clone();
    let mut members = vec![0usize; n];
    for (k, &r) in root_of.iter().enumerate() {
        members[fill[r as usize]] = k;
        fill[r as usize] += 1;
    }
    // A large island's members sorted along x, with their widest radius and reach: a disk of
    // another island can be within reach only of the members in a window of x around it.
    // Islands past `MOST_PAIRS_TESTED` are joined untested and need no order.
    let mut widest = vec![0.0f64; n];
    for r in (0..n)
        .filter(|&r| (SORTED_MEMBERS + 1..=MOST_PAIRS_TESTED).contains(&(count[r + 1] - count[r])))
    {
        let own = &mut members[count[r]..count[r + 1]];
        own.sort_by(|&p, &q| disks[p].pos.get(0).total_cmp(&disks[q].pos.get(0)));
        widest[r] = own
            .iter()
            .map(|&p| disks[p].radius + disks[p].reach)
            .fold(0.0, f64::max);
    }
    let within = |p: usize, q: usize| {
        let (dp, dq) = (&disks[p], &disks[q]);
        if dp.asleep && dq.asleep {
            return false;
        }
        let gap = (dq.pos - dp.pos).length() - dp.radius - dq.radius;
        gap <= dp.reach + dq.reach
    };
    let roots: Vec<usize> = (0..n).filter(|&r| count[r + 1] > count[r]).collect();
    let mut joins = Vec::new();
    for (a, b) in box_pairs::meeting(&roots, &lo, &hi) {
        if !(awake[a] || awake[b]) {
            continue;
        }
        let (da, db) = (
            &members[count[a]..count[a + 1]],
            &members[count[b]..count[b + 1]],
        );
        let (big, small, large) = if da.len() >= db.len() {
            (da, db, a)
        } else {
            (db, da, b)
        };
        // The pair in `a`, `b` order, so each gap rounds as the plain test's does.
        let in_order = |p: usize, q: usize| {
            if large == a {
                within(p, q)
            } else {
                within(q, p)
            }
        };
        let near = da.len() * db.len() > MOST_PAIRS_TESTED
            || if big.len() > SORTED_MEMBERS {
                small.iter().any(|&q| {
                    let x = disks[q].pos.get(0);
                    // A margin over rounding, so that the window holds every pair within.
                    let w = disks[q].radius + disks[q].reach + widest[large];
                    let w = w + 1e-9 * (1.0 + x.abs() + w);
                    let from = big.partition_point(|&p| disks[p].pos.get(0) < x - w);
                    big[from..]
                        .iter()
                        .take_while(|&&p| disks[p].pos.get(0) <= x + w)
                        .any(|&p| in_order(p, q))
                })
            } else {
                da.iter().any(|&p| db.iter().any(|&q| within(p, q)))
            };
        if near {
            joins.push((a, b));
        }
    }
    for &(a, b) in &joins {
        union(parent, a, b);
    }
    !joins.is_empty()
}

/// Whether the islands of `parent` may end in more than one group: some island is held by
/// nothing and has two disks approaching each other (impacts), or some are held and some are
/// not. Joining islands keeps an island of impacts held by nothing and approaching, and an
/// island held when a part was, so without either these islands already decide the step.
fn may_mix(held: &[bool], closing: &[bool], parent: &mut [u32]) -> bool {
    let n = held.len();
    let (mut root_held, mut root_meets) = (vec![false; n], vec![false; n]);
    for k in 0..n {
        let root = find(parent, k) as usize;
        root_held[root] |= held[k];
        root_meets[root] |= closing[k];
    }
    let (mut any_held, mut any_loose) = (false, false);
    for r in (0..n).filter(|&r| find(parent, r) as usize == r) {
        if !root_held[r] && root_meets[r] {
            return true;
        }
        any_held |= root_held[r];
        any_loose |= !root_held[r];
    }
    any_held && any_loose
}

/// Names the islands by their lowest slot and finds each one's regime (held and approaching
/// as read at the disks' own reaches).
fn classify<V: Vector>(
    disks: &[Disk<V>],
    held_disk: &[bool],
    closing: &[bool],
    parent: &mut [u32],
    slot_count: usize,
) -> Islands {
    let n = disks.len();
    let mut size = vec![0usize; n];
    let mut meets = vec![false; n];
    let mut held = vec![false; n];
    let mut awake = vec![false; n];
    let mut soft = vec![false; n];
    for k in 0..n {
        let root = find(parent, k) as usize;
        size[root] += 1;
        soft[root] |= !disks[k].elastic;
        held[root] |= held_disk[k];
        meets[root] |= closing[k];
        awake[root] |= !disks[k].asleep;
    }
    // Disks are listed in slot order, so each root (the lowest index) is its island's lowest
    // slot, and the islands come out in that order.
    let mut of_slot = vec![NO_ISLAND; slot_count];
    let mut index = vec![NO_ISLAND; n];
    let mut list = Vec::new();
    for k in 0..n {
        let root = find(parent, k) as usize;
        if !awake[root] {
            of_slot[disks[k].slot as usize] = ASLEEP;
            continue;
        }
        if index[root] == NO_ISLAND {
            index[root] = list.len() as u32;
            let regime = if held[root] {
                Regime::Resting
            } else if meets[root] && soft[root] {
                Regime::Clump
            } else if meets[root] {
                Regime::Impact
            } else {
                Regime::Free
            };
            list.push(Island {
                first: disks[root].slot,
                size: size[root],
                regime,
            });
        }
        of_slot[disks[k].slot as usize] = index[root];
    }
    Islands { of_slot, list }
}

/// Whether disk `d` has a support (wall, fixed critter, bouncing or clamping edge) within reach
/// that it approaches slower than `slow` (it rests on it).
fn supported<V: Vector>(
    topo: &crate::border::Topology<V>,
    supports: &[Support<'_, V>],
    d: &Disk<V>,
    slow: f64,
) -> bool {
    let mut rests = false;
    let mut note = |normal: V| {
        // The normal points from the support to the disk: approaching is moving against it.
        rests |= -d.vel.dot(normal) < slow;
    };
    let reach = d.radius + d.reach;
    if topo.border != Border::Wrap {
        for a in 0..V::DIM {
            let (lo, hi, x) = (topo.min.get(a), topo.max.get(a), d.pos.get(a));
            let mut n = V::zero();
            if x - lo <= reach {
                n.set(a, 1.0);
                note(n);
            }
            if hi - x <= reach {
                n.set(a, -1.0);
                note(n);
            }
        }
    }
    for s in supports {
        let c = s.critter;
        let offset = topo.delta(c.pos, d.pos);
        match c.wall() {
            Some(wall) => {
                if let Some(contact) = contact_wall_ball(wall, offset, reach) {
                    note(contact.normal);
                }
            }
            None => {
                let dist = offset.length();
                if dist - c.radius <= reach {
                    let normal = if dist > 0.0 {
                        offset / dist
                    } else {
                        V::unit_x()
                    };
                    note(normal);
                }
            }
        }
    }
    rests
}

fn count_roots(parent: &mut [u32]) -> usize {
    (0..parent.len())
        .filter(|&k| find(parent, k) as usize == k)
        .count()
}

/// The root of `k`, halving the path.
fn find(parent: &mut [u32], mut k: usize) -> u32 {
    while parent[k] as usize != k {
        parent[k] = parent[parent[k] as usize];
        k = parent[k] as usize;
    }
    k as u32
}

/// Joins the islands of `a` and `b`; the lower root stays root.
fn union(parent: &mut [u32], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
    if lo != hi {
        parent[hi as usize] = lo;
    }
}

mod box_pairs;
#[cfg(test)]
mod tests;
