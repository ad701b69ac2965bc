//! Islands for `auto`: the live disks cut into groups that cannot meet within the coming step,
//! each with the regime that decides its method ([`partition`]).
//!
//! **Reach.** A free disk moves in a step at most `(u + 2|g| dt) dt`, where `u` bounds its speed:
//! collisions inside its island (restitution at most 1, walls and fixed critters not moving)
//! cannot give it more than all of its island's kinetic energy, `u = sqrt(2 E / m)`, and
//! gravity adds `|g| dt` to a speed over the step (twice, for a bounce off a support). Two disks
//! are in one island when their gap is within their two reaches (with the island's deepest
//! overlap added, which the separation may push a disk by); since the reach depends on the
//! island, the partition is repeated with the islands' reaches until no two islands join. Two
//! islands then cannot touch during the step, so stepping each alone gives the same result as
//! stepping them together. Walls, fixed critters and the world's bouncing edges join no island:
//! every island sees them all.
//!
//! **Regime** ([`Regime`]), under gravity: an island is *resting* when one of its disks is
//! within reach of a wall, a fixed critter or a bouncing edge and approaches it slower than
//! [`RESTING_STEPS`] steps of gravity (`|g| dt`): it is held up, and its contacts carry weight,
//! which is what `solve:N` is for. An island held up by nothing falls freely as a whole: gravity
//! does not change its disks' relative motion, so when two of its disks within reach approach
//! each other its contacts are *impacts* (a cradle struck in mid-air, a clump thrown), and only
//! the exact event flight keeps them (a solve spreads a cradle's momentum over its balls).
//! Otherwise it is *free*: no two of its disks meet in the step (at most one hits a wall), and
//! it goes with the resting islands' step, which moves it as the plain step does.
//!
//! Determinism: the union keeps the lower slot as each root, and islands are listed by their
//! lowest slot, so the result depends on neither thread count nor the order of the passes.

use crate::border::Border;
use crate::contact::contact_wall_ball;
use crate::critter::Critter;
use crate::tolerance::ROUNDING_MARGIN;
use crate::vector::Vector;
use crate::world::state::State;

/// A disk approaching a support slower than this many steps of gravity (`|g| dt`) rests on it.
pub const RESTING_STEPS: f64 = 2.0;

/// How an island's contacts behave in the coming step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Regime {
    /// Held up by nothing, and no two of its disks approach each other: none meet in the step.
    Free,
    /// Held up by a wall, a fixed critter or an edge: its contacts carry weight.
    Resting,
    /// Held up by nothing: its contacts are impacts between disks in flight.
    Impact,
}

impl Regime {
    /// A few words for the island summary.
    pub fn describe(self) -> &'static str {
        match self {
            Regime::Free => "in flight, no two meet",
            Regime::Resting => "resting contacts under gravity",
            Regime::Impact => "impacts in flight",
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

/// The most grid cells per disk of the partition's grid.
const CELLS_PER_DISK: f64 = 16.0;

/// Not in any island.
pub const NO_ISLAND: u32 = u32::MAX;

/// What the partition reads of a disk.
struct Disk<V> {
    slot: u32,
    pos: V,
    vel: V,
    radius: f64,
    inv_mass: f64,
    /// How far it may move in the step.
    reach: f64,
}

/// The supports: walls and fixed critters (which join no island).
struct Support<'a, V: Vector> {
    critter: &'a Critter<V>,
}

/// Partitions the live disks of `state` into islands (see the module docs).
pub(crate) fn partition<V: Vector>(state: &State<V>) -> Islands {
    let (g, dt) = (state.gravity.length(), state.dt);
    let slots = state.critters.slot_slice();
    let mut disks = Vec::new();
    let mut supports = Vec::new();
    for (i, c) in slots.iter().enumerate() {
        let Some(c) = c.as_ref().filter(|c| c.alive) else {
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
            });
        }
    }
    let n = disks.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    // First pass: each disk's own speed; later passes: its island's energy.
    for d in disks.iter_mut() {
        d.reach = reach(d.vel.length(), g, dt);
    }
    let mut deepest = vec![0.0f64; n];
    let mut closing = vec![false; n];
    link_pairs(state, &disks, &mut parent, &mut deepest, &mut closing);
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
        let before = count_roots(&mut parent);
        link_pairs(state, &disks, &mut parent, &mut deepest, &mut closing);
        if count_roots(&mut parent) == before {
            break;
        }
    }
    classify(
        state,
        &disks,
        &supports,
        &closing,
        &mut parent,
        slots.len(),
        g * dt,
    )
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
    deepest: &mut [f64],
    closing: &mut [bool],
) {
    let n = disks.len();
    if n < 2 {
        return;
    }
    let topo = &state.topo;
    let size = topo.size();
    // Cells twice the largest diameter wide, widened only where the box would hold more than
    // `CELLS_PER_DISK` cells per disk (a clustered scene keeps small cells); disks whose
    // radius and reach pass half a cell are tested against all.
    let largest = disks.iter().map(|d| d.radius).fold(0.0, f64::max);
    let mut side = 4.0 * largest;
    if !(side.is_finite() && side > 0.0) {
        side = 1.0;
    }
    let cells_at = |side: f64| -> f64 {
        (0..V::DIM)
            .map(|a| (size.get(a) / side).floor().max(1.0))
            .product()
    };
    while cells_at(side) > CELLS_PER_DISK * n as f64 {
        side *= 2.0;
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
    let key = |c: [usize; 3]| (c[2] * dims[1] + c[1]) * dims[0] + c[0];
    let cells = dims[0] * dims[1] * dims[2];
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
    let test =
        |a: usize, b: usize, parent: &mut [u32], deepest: &mut [f64], closing: &mut [bool]| {
            let (da, db) = (&disks[a], &disks[b]);
            let offset = topo.delta(da.pos, db.pos);
            let gap = offset.length() - da.radius - db.radius;
            if gap <= da.reach + db.reach {
                union(parent, a, b);
                if (db.vel - da.vel).dot(offset) < 0.0 {
                    closing[a] = true;
                    closing[b] = true;
                }
                if gap < 0.0 {
                    deepest[a] = deepest[a].max(-gap);
                    deepest[b] = deepest[b].max(-gap);
                }
            }
        };
    let wraps = topo.wraps();
    for (a, disk) in disks.iter().enumerate() {
        if is_wide(a) {
            continue;
        }
        let ca = coord(disk.pos);
        let mut lo = [0i64; 3];
        let mut hi = [0i64; 3];
        for ax in 0..3 {
            if ax < V::DIM {
                lo[ax] = ca[ax] as i64 - 1;
                hi[ax] = ca[ax] as i64 + 1;
            }
        }
        let mut seen: Vec<usize> = Vec::with_capacity(27);
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let mut c = [0usize; 3];
                    let mut inside = true;
                    for (ax, v) in [x, y, z].into_iter().enumerate() {
                        let m = dims[ax] as i64;
                        if (0..m).contains(&v) {
                            c[ax] = v as usize;
                        } else if wraps && ax < V::DIM {
                            c[ax] = v.rem_euclid(m) as usize;
                        } else {
                            inside = false;
                        }
                    }
                    if !inside {
                        continue;
                    }
                    let k = key(c);
                    if seen.contains(&k) {
                        continue; // few cells along an axis: the neighbours repeat
                    }
                    seen.push(k);
                    for &b in &order[start[k]..start[k + 1]] {
                        if b > a {
                            test(a, b, parent, deepest, closing);
                        }
                    }
                }
            }
        }
    }
    for &a in &wide {
        for b in 0..n {
            if b != a && (!is_wide(b) || b > a) {
                test(a, b, parent, deepest, closing);
            }
        }
    }
}

/// Names the islands by their lowest slot and finds each one's regime.
fn classify<V: Vector>(
    state: &State<V>,
    disks: &[Disk<V>],
    supports: &[Support<'_, V>],
    closing: &[bool],
    parent: &mut [u32],
    slot_count: usize,
    g_dt: f64,
) -> Islands {
    let n = disks.len();
    let topo = &state.topo;
    let mut size = vec![0usize; n];
    let mut meets = vec![false; n];
    let mut held = vec![false; n];
    for k in 0..n {
        let root = find(parent, k) as usize;
        size[root] += 1;
        let d = &disks[k];
        held[root] |= supported(topo, supports, d, RESTING_STEPS * g_dt);
        meets[root] |= closing[k];
    }
    // Disks are listed in slot order, so each root (the lowest index) is its island's lowest
    // slot, and the islands come out in that order.
    let mut of_slot = vec![NO_ISLAND; slot_count];
    let mut index = vec![NO_ISLAND; n];
    let mut list = Vec::new();
    for k in 0..n {
        let root = find(parent, k) as usize;
        if index[root] == NO_ISLAND {
            index[root] = list.len() as u32;
            let regime = if held[root] {
                Regime::Resting
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

#[cfg(test)]
mod tests;
