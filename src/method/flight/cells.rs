//! Rapaport's cells: the world box cut into cells at least one diameter wide, the disks each
//! holds, the cells around a cell, and the crossings from one cell into the next.

use super::bodies::{advance, motion_at, refresh_body, Motion};
use super::border::on_bound;
use super::events::{offer, EventKind};
use super::shells::relist;
use super::Scratch;
use crate::method::toi::smallest_nonneg_root;
use crate::step::state::State;
use crate::vector::Vector;

/// Lists of critters stored flat, in stripes: list `k` owns `stride` entries from
/// `base + k * stride`, its length first, then its members. The stride is a power of two and
/// the first stripe starts on a cache line, so a stripe of 16 entries or fewer is one line and
/// a longer one whole lines, where a vector per list costs a miss for its header and another
/// for its buffer. The cells' members and the neighbour lists are kept so.
#[derive(Default)]
pub(super) struct StripedLists {
    pub(super) stride: usize,
    /// Where the first stripe starts in `data` (its first cache-line boundary).
    pub(super) base: usize,
    pub(super) data: Vec<u32>,
}

/// Entries of `u32` in a cache line: the room `data` keeps to start a stripe on a line.
const U32_PER_LINE: usize = 64 / std::mem::size_of::<u32>();

impl StripedLists {
    /// Empties `total` lists with room for `cap` members each (or more: the stripes are
    /// rounded up to a power of two).
    pub(super) fn reset(&mut self, total: usize, cap: usize) {
        self.stride = (cap + 1).next_power_of_two();
        self.data.clear();
        self.data.resize(total * self.stride + U32_PER_LINE, 0);
        let misalign = self.data.as_ptr() as usize % 64 / std::mem::size_of::<u32>();
        self.base = (U32_PER_LINE - misalign) % U32_PER_LINE;
    }

    /// Where list `k`'s stripe starts in `data`.
    #[inline]
    pub(super) fn start(&self, k: usize) -> usize {
        self.base + k * self.stride
    }

    /// The first entry of list `k`'s stripe, for a prefetch.
    #[inline]
    pub(super) fn head(&self, k: usize) -> Option<&u32> {
        self.data.get(self.start(k))
    }

    #[inline]
    pub(super) fn members(&self, k: usize) -> &[u32] {
        let at = self.start(k);
        let n = self.data[at] as usize;
        &self.data[at + 1..at + 1 + n]
    }

    pub(super) fn push(&mut self, k: usize, a: u32) {
        let at = self.start(k);
        let n = self.data[at] as usize;
        if n + 1 == self.stride {
            self.grow();
            return self.push(k, a);
        }
        self.data[at + 1 + n] = a;
        self.data[at] = n as u32 + 1;
    }

    pub(super) fn clear(&mut self, k: usize) {
        let at = self.start(k);
        self.data[at] = 0;
    }

    pub(super) fn remove(&mut self, k: usize, a: u32) {
        let at = self.start(k);
        let n = self.data[at] as usize;
        if let Some(i) = self.data[at + 1..at + 1 + n].iter().position(|&x| x == a) {
            self.data[at + 1 + i] = self.data[at + n];
            self.data[at] = n as u32 - 1;
        }
    }

    /// Doubles every list's room (a list filled up: rare, lists are sized for their load).
    fn grow(&mut self) {
        let (old, stride, base) = (std::mem::take(&mut self.data), self.stride, self.base);
        let total = (old.len() - U32_PER_LINE) / stride;
        self.reset(total, 2 * stride - 1);
        for k in 0..total {
            let from = base + k * stride;
            let n = old[from] as usize;
            let dst = self.start(k);
            self.data[dst..dst + 1 + n].copy_from_slice(&old[from..from + 1 + n]);
        }
    }
}

/// The key of the cell at coordinates `c`, wrapped onto the grid's other side when one step off
/// it.
#[inline]
pub(super) fn cell_key(dims: &[usize; 3], c: [i64; 3]) -> usize {
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

/// The coordinates of the cell of key `k`.
pub(super) fn cell_coords(dims: &[usize; 3], k: usize) -> [i64; 3] {
    [
        (k % dims[0]) as i64,
        ((k / dims[0]) % dims[1]) as i64,
        (k / (dims[0] * dims[1])) as i64,
    ]
}

/// The cell of position `p`: its key and its coordinates (kept beside the key, which would
/// take three divisions to unpack).
pub(super) fn cell_of<V: Vector>(state: &State<V>, sc: &Scratch<V>, p: V) -> (usize, [i64; 3]) {
    let mut c = [0i64; 3];
    for (axis, ca) in c.iter_mut().enumerate().take(V::DIM) {
        let x = ((p.get(axis) - state.topo.min.get(axis)) / sc.cell_side[axis]).floor() as i64;
        *ca = x.clamp(0, sc.dims[axis] as i64 - 1);
    }
    (cell_key(&sc.dims, c), c)
}

/// Whether `a`'s cell is off the grid's edges, so its neighbours are `offsets` away (no
/// wrapping, no repeats).
#[inline]
pub(super) fn interior<V: Vector>(sc: &Scratch<V>, a: u32) -> bool {
    interior_at::<V>(sc, sc.coord[a as usize])
}

/// Whether the cell at coordinates `hc` is off the grid's edges.
#[inline]
pub(super) fn interior_at<V: Vector>(sc: &Scratch<V>, hc: [i64; 3]) -> bool {
    !sc.offsets.is_empty() && (0..V::DIM).all(|ax| hc[ax] >= 1 && hc[ax] + 2 <= sc.dims[ax] as i64)
}

/// The keys of the cells around `a`'s cell (its own included), each once (at the grid's edges
/// they are wrapped or cut at the border, and with fewer than three cells along an axis they
/// repeat); their number.
pub(super) fn cells_around<V: Vector>(
    state: &State<V>,
    sc: &Scratch<V>,
    a: u32,
    out: &mut [usize; 27],
) -> usize {
    let home = sc.cell[a as usize] as usize;
    if interior::<V>(sc, a) {
        for (o, k) in sc.offsets.iter().zip(out.iter_mut()) {
            *k = (home as isize + o) as usize;
        }
        return sc.offsets.len();
    }
    cells_around_cell(state, sc, sc.coord[a as usize], out)
}

/// [`cells_around`] the cell at coordinates `hc`, by the general path (wrapped or cut at the
/// grid's edges, each once).
pub(super) fn cells_around_cell<V: Vector>(
    state: &State<V>,
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
                if !state.topo.wraps()
                    && (0..V::DIM).any(|ax| cc[ax] < 0 || cc[ax] >= dims[ax] as i64)
                {
                    continue;
                }
                let k = cell_key(&dims, cc);
                if !out[..count].contains(&k) {
                    out[count] = k;
                    count += 1;
                }
            }
        }
    }
    count
}

/// Offers `a`'s next crossing out of its cell, from time `t` (the general formulas: curved or
/// straight flights).
#[allow(clippy::needless_range_loop)]
pub(super) fn predict_crossing<V: Vector>(state: &State<V>, sc: &mut Scratch<V>, a: u32, t: f64) {
    let Motion { pos, vel, acc } = motion_at(sc, a, t);
    let cc = sc.coord[a as usize];
    let mut best = (f64::INFINITY, 0u32);
    for axis in 0..V::DIM {
        let n = sc.dims[axis] as i64;
        if n == 1 {
            continue;
        }
        let lo = state.topo.min.get(axis) + cc[axis] as f64 * sc.cell_side[axis];
        let hi = lo + sc.cell_side[axis];
        let (x, vx, ax) = (pos.get(axis), vel.get(axis), acc.get(axis));
        for dir in [0u32, 1] {
            let at_edge = if dir == 1 {
                cc[axis] == n - 1
            } else {
                cc[axis] == 0
            };
            if at_edge && !state.topo.wraps() {
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
    if best.0.is_finite() && t + best.0 <= sc.horizon {
        offer(sc, t + best.0, a, best.1, EventKind::CellCrossing);
    }
}

/// [`predict_crossing`] for a straight flight (`motion`: at `t`): only the side the critter
/// moves towards can be crossed, at `gap / speed`, the time `predict_crossing`'s general
/// formulas give bit for bit.
#[inline]
#[allow(clippy::needless_range_loop)] // per-axis arrays indexed together
pub(super) fn predict_crossing_straight<V: Vector>(
    state: &State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    t: f64,
    motion: Motion<V>,
) {
    let Motion { pos, vel, .. } = motion;
    let cc = sc.coord[a as usize];
    let wraps = state.topo.wraps();
    let mut best = (f64::INFINITY, 0u32);
    for axis in 0..V::DIM {
        let n = sc.dims[axis] as i64;
        let vx = vel.get(axis);
        if n == 1 || vx == 0.0 || vx.is_nan() {
            continue; // not moving along the axis (or NaN): no crossing, as in `predict_crossing`
        }
        let up = vx > 0.0;
        if !wraps && (if up { cc[axis] == n - 1 } else { cc[axis] == 0 }) {
            continue;
        }
        let lo = state.topo.min.get(axis) + cc[axis] as f64 * sc.cell_side[axis];
        let (bound, outward) = if up {
            (lo + sc.cell_side[axis], 1.0)
        } else {
            (lo, -1.0)
        };
        let gap = (bound - pos.get(axis)) * outward;
        let s = if gap <= 0.0 {
            0.0
        } else {
            -(-gap) / (vx * outward)
        };
        if s < best.0 {
            best = (s, axis as u32 * 2 + u32::from(up));
        }
    }
    if best.0.is_finite() && t + best.0 <= sc.horizon {
        offer(sc, t + best.0, a, best.1, EventKind::CellCrossing);
    }
}

/// Moves `a` at time `t` into the next cell along `tag` (`axis * 2 + dir`), wrapping it onto
/// the box's other side when it left the box through a periodic border.
#[allow(clippy::needless_range_loop)]
pub(super) fn cross_cell<V: Vector>(
    state: &mut State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    tag: u32,
    t: f64,
) {
    advance(state, sc, a, t);
    let (axis, dir) = ((tag / 2) as usize, tag % 2);
    let old = sc.cell[a as usize] as usize;
    let mut cc = sc.coord[a as usize];
    cc[axis] += if dir == 1 { 1 } else { -1 };
    let n = sc.dims[axis] as i64;
    if cc[axis] < 0 || cc[axis] >= n {
        if state.topo.wraps() {
            let len = state.topo.size().get(axis);
            let c = state.critters.slot_mut_moving(a).expect("live slot");
            let x = c.pos.get(axis);
            c.pos.set(axis, if dir == 1 { x - len } else { x + len });
        }
        // Onto the grid's other side, as `cell_key` takes it.
        cc[axis] = cc[axis].rem_euclid(n);
    }
    let new = cell_key(&sc.dims, cc);
    move_cell(sc, a, old, new, cc);
}

/// Moves `a` from cell `old` to cell `new`, at coordinates `cc`.
pub(super) fn move_cell<V: Vector>(
    sc: &mut Scratch<V>,
    a: u32,
    old: usize,
    new: usize,
    cc: [i64; 3],
) {
    if old == new {
        return;
    }
    sc.cells.remove(old, a);
    sc.cells.push(new, a);
    debug_assert_eq!(cell_coords(&sc.dims, new), cc, "cell {new}'s coordinates");
    sc.cell[a as usize] = new as u32;
    sc.coord[a as usize] = cc;
}

/// After a hook ran: the critter may have died or been moved; put it in the right cell (with
/// shells, list it again if it left its shell).
pub(super) fn relocate<V: Vector>(state: &mut State<V>, sc: &mut Scratch<V>, a: u32) {
    if sc.shells {
        // Listed again when it died, grew, or was moved out of its shell.
        let stays = state.critters.slot(a).is_some_and(|c| {
            c.in_play()
                && c.radius == sc.body[a as usize].radius
                && state
                    .topo
                    .delta(sc.shell_centres[a as usize].pos, c.pos)
                    .length()
                    <= 0.5 * sc.shell_width
        });
        if !stays {
            refresh_body(state, sc, a);
            relist(state, sc, a);
        }
        return;
    }
    let old = sc.cell[a as usize] as usize;
    let Some(c) = state.critters.slot(a) else {
        return;
    };
    if !c.in_play() {
        sc.cells.remove(old, a);
        return;
    }
    let mut p = c.pos;
    if state.topo.wraps() {
        p = state.topo.wrap_position(p);
        state.critters.slot_mut_moving(a).expect("live").pos = p;
    }
    let (new, cc) = cell_of(state, sc, p);
    move_cell(sc, a, old, new, cc);
}
