//! Setting a new flight up: the bodies, the cell grid sized for the largest disk, the walls
//! each cell must test, the neighbour shells, and, when only some critters predict, who may
//! meet something.

use super::bodies::{refresh_body, Body, Status};
use super::cells::{cell_coords, cell_key, cell_of, cells_around, cells_around_cell, interior_at};
use super::shells::list_all_neighbours;
use super::{
    Scratch, BUDGET_PER_CRITTER, CARRY_ON_FACTOR, ROUNDING_MARGIN, SHELL_FRACTION, TC_FRACTION,
    UNSET,
};
use crate::border::Border;
use crate::contact::contact_wall_ball;
use crate::critter::{Shape, CLASS_UNSET};
use crate::step::state::State;
use crate::vector::Vector;

/// Sets up a new flight of `life` steps whose predictions look to `horizon`.
#[allow(clippy::needless_range_loop)] // per-axis arrays indexed together
pub(super) fn setup<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    acc: V,
    horizon: f64,
    life: u64,
) {
    let n = state.critters.slot_count();
    if life > 1 {
        // A kept flight's calendar covers its whole life (its later steps go on in it), with a
        // bucket per event of the last step, at most one per two critters a step: more
        // buckets would mostly be opened empty, fewer would fill the heap.
        let most = (n / 2).max(64);
        let per_step = match sc.processed {
            0 => most,
            events => (events as usize).min(most),
        };
        sc.queue
            .reset_buckets(n, 0.0, horizon, per_step.saturating_mul(life as usize));
    } else {
        sc.queue.reset(n, 0.0, horizon);
    }
    sc.stuck.clear();
    for v in [&mut sc.cell, &mut sc.last_partner] {
        v.clear();
        v.resize(n, UNSET);
    }
    let mut rmax: f64 = 0.0;
    let mut disks = 0usize;
    sc.has_walls = false;
    for c in state.critters.iter_mut_moving() {
        if c.class == CLASS_UNSET {
            c.class = state.rules.class_of(&state.kinds, c);
        }
        if c.in_play() && !c.is_wall() {
            rmax = rmax.max(c.radius);
            disks += 1;
        }
        sc.has_walls |= c.in_play() && c.is_wall();
    }
    rmax = rmax.max(sc.grown_radius);
    sc.largest_radius = rmax;
    sc.coord.clear();
    sc.coord.resize(n, [0; 3]);
    sc.body.clear();
    sc.body.resize(n, Body::default());
    sc.status.clear();
    sc.status.resize(n, Status::default());
    for a in 0..n as u32 {
        refresh_body(state, sc, a);
    }
    sc.last_collision.clear();
    sc.last_collision.resize(n, f64::NEG_INFINITY);
    sc.straight = acc.length_squared() == 0.0;
    sc.acc = if sc.straight { V::zero() } else { acc };
    sc.horizon = horizon;
    sc.tc_window = TC_FRACTION * sc.dt;
    sc.virial = 0.0;
    sc.predictions = 0;
    sc.pair_tests = 0;
    sc.budget = BUDGET_PER_CRITTER * disks as u64 + 10_000;
    if sc.carrying_on {
        sc.budget *= CARRY_ON_FACTOR;
    }
    sc.stopped_on = None;
    // Shells pay where a cell's neighbourhood is large (27 cells) and flights are lines.
    sc.shells = sc.straight && !sc.has_walls && V::DIM == 3 && disks > 0 && sc.slow_below.is_none();
    #[cfg(test)]
    {
        sc.shells &= !sc.no_shells;
    }
    sc.shell_width = if sc.shells {
        SHELL_FRACTION * 2.0 * rmax
    } else {
        0.0
    };
    // Cells at least one diameter (and a shell) wide, at most about 2 per disk. Critters that do
    // not predict never cross cells: a slow one may end up `slow_below` out of its cell, and two
    // slow ones that meet were up to a diameter and twice `slow_below` apart (`may_meet` looks
    // one cell around).
    let size = state.topo.size();
    let dim = V::DIM;
    let slack = sc.shell_width + 2.0 * sc.slow_below.unwrap_or(0.0);
    let want = (2.0 * rmax * (1.0 + ROUNDING_MARGIN) + slack * (1.0 + ROUNDING_MARGIN))
        .max(f64::MIN_POSITIVE);
    let mut dims = [1usize; 3];
    for axis in 0..dim {
        dims[axis] = ((size.get(axis) / want).floor() as usize).clamp(1, 1 << 20);
    }
    // Over the cap, every axis is scaled down by one factor to just under it (halving every
    // axis could leave a quarter of the cap in 2D and an eighth in 3D: cells twice as wide as
    // needed, four or eight times the candidates per prediction).
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
        sc.cell_side[axis] = if axis < dim {
            size.get(axis) / dims[axis] as f64
        } else {
            1.0
        };
    }
    sc.dims = dims;
    sc.offsets.clear();
    sc.forward.clear();
    sc.front.iter_mut().for_each(Vec::clear);
    sc.earliest_contact.clear();
    sc.earliest_contact.resize(n, None);
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
    for c in state.critters.iter() {
        if c.in_play() && !c.is_wall() {
            let (k, cc) = cell_of(state, sc, c.pos);
            debug_assert_eq!(cell_coords(&dims, k), cc, "cell {k}'s coordinates");
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
    for c in state.critters.iter() {
        if !c.in_play() {
            continue;
        }
        match c.shape() {
            Shape::Disk => {
                let k = sc.cell[c.id.index as usize] as usize;
                sc.cells.push(k, c.id.index);
            }
            Shape::Wall(wall) => {
                // Every cell a disk centre could be in while touching the wall.
                let half = wall.aabb_half() + V::splat(rmax + ROUNDING_MARGIN * rmax);
                let mut lo = [0i64; 3];
                let mut hi = [0i64; 3];
                for axis in 0..dim {
                    let m = state.topo.min.get(axis);
                    let s = sc.cell_side[axis];
                    lo[axis] = ((c.pos.get(axis) - half.get(axis) - m) / s).floor() as i64;
                    hi[axis] = ((c.pos.get(axis) + half.get(axis) - m) / s).floor() as i64;
                    let n = dims[axis] as i64;
                    if state.topo.wraps() {
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
                            let k = cell_key(&dims, [x, y, z]);
                            sc.cell_walls[k].push(c.id.index);
                        }
                    }
                }
            }
        }
    }
    if sc.shells {
        list_all_neighbours(state, sc);
    }
}

/// How far critter `a` can move in the flight, at most.
#[inline]
fn reach<V: Vector>(sc: &Scratch<V>, a: u32) -> f64 {
    let t = sc.horizon;
    sc.body[a as usize].vel.length() * t + 0.5 * sc.acc.length() * t * t
}

/// Whether slow critter `a` may meet anything in the flight if nobody's flight changes: a disk,
/// a wall or a bounding border within reach of both. (A critter that meets nothing needs no
/// prediction until a collision changes a flight, and then the changed critter predicts.)
/// The flight asks [`mark_who_may_meet`], which gives the same answers pair by pair; this is
/// its definition, which the tests compare it with.
#[cfg(test)]
pub(super) fn may_meet<V: Vector>(state: &State<V>, sc: &Scratch<V>, a: u32) -> bool {
    let body = sc.body[a as usize];
    if body.radius.is_nan() {
        return false;
    }
    let moves = reach(sc, a);
    if near_border(state, body, moves) || (sc.has_walls && near_a_wall(state, sc, a, moves)) {
        return true;
    }
    let mut around = [0usize; 27];
    let count = cells_around(state, sc, a, &mut around);
    for &k in &around[..count] {
        for &b in sc.cells.members(k) {
            let other = sc.body[b as usize];
            if b == a || other.radius.is_nan() {
                continue;
            }
            let near = body.radius + other.radius + moves + reach(sc, b);
            if state.topo.delta(body.pos, other.pos).length_squared() <= near * near {
                return true;
            }
        }
    }
    false
}

/// Whether a disk `body` that moves up to `moves` may reach a bounding border.
#[inline]
fn near_border<V: Vector>(state: &State<V>, body: Body<V>, moves: f64) -> bool {
    if state.topo.border == Border::Wrap {
        return false;
    }
    (0..V::DIM).any(|axis| {
        let x = body.pos.get(axis);
        let room = (x - state.topo.min.get(axis)).min(state.topo.max.get(axis) - x);
        room <= body.radius + moves
    })
}

/// Whether disk `a`, moving up to `moves`, may reach a wall listed in the cells around its own.
fn near_a_wall<V: Vector>(state: &State<V>, sc: &Scratch<V>, a: u32, moves: f64) -> bool {
    let body = sc.body[a as usize];
    let mut around = [0usize; 27];
    let count = cells_around(state, sc, a, &mut around);
    for &k in &around[..count] {
        for &x in &sc.cell_walls[k] {
            let Some(c) = state.critters.slot(x) else {
                continue;
            };
            let Shape::Wall(wall) = c.shape() else {
                continue;
            };
            let d = state.topo.delta(c.pos, body.pos);
            if c.in_play() && contact_wall_ball(wall, d, body.radius + moves).is_some() {
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
pub(super) fn mark_who_may_meet<V: Vector>(state: &State<V>, sc: &mut Scratch<V>) {
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
                let count = cells_around_cell(state, sc, cell_coords(&dims, k), &mut around);
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
        let moves = reaches[a];
        meets[a] = near_border(state, body, moves)
            || (near_wall[sc.cell[a] as usize] && near_a_wall(state, sc, a as u32, moves));
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
        let d2 = state.topo.delta(ba.pos, bb.pos).length_squared();
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
        let members = sc.cells.members(k);
        if members.is_empty() {
            continue;
        }
        if interior_at::<V>(sc, hc) {
            for (i, &a) in members.iter().enumerate() {
                for &b in &members[i + 1..] {
                    pair(a, b);
                }
            }
            for &o in &sc.forward {
                let theirs = sc.cells.members((k as isize + o) as usize);
                for &a in members {
                    for &b in theirs {
                        pair(a, b);
                    }
                }
            }
        } else {
            let count = cells_around_cell(state, sc, hc, &mut around);
            for &j in &around[..count] {
                for &a in members {
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
