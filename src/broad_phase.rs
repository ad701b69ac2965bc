//! Broad phase: candidate pairs whose bounding boxes overlap, and nothing else.
//!
//! The structure is a hierarchical grid rebuilt every step. Each object goes to the finest level
//! whose cell is at least as wide as the object (level L has cells of `s0 * 2^L`, `s0` the smallest
//! object's width), so widely varying radii cost no more than uniform ones: an object meets the
//! objects of its own level in its own and the neighbouring cells (a half stencil, so each pair is
//! produced once), and those of every coarser level in the 3^D cells around its position there.
//! Within a level the objects are counting-sorted by cell, which keeps memory access local; the
//! sorted copies are single-precision boxes rounded outwards (`CellBox`), so the walk may find
//! a pair that only touches through the rounding, and every pair it finds is tested again against
//! the exact boxes. The output order depends only on the objects, never on a hash or a thread
//! count.
//!
//! For small scenes a direct loop over all pairs is cheaper than building a grid; [`SMALL_N`] is
//! where `benches/step.rs` measured the two to cross. Above it, [`BroadPhaseMode::Auto`] keeps a
//! Verlet list: the grid is built with boxes widened by a skin, its pairs are kept, and each step
//! re-tests only those until something has moved more than half the skin.
//!
//! Walls never pair with walls.

use crate::border::Topology;
use crate::vector::Vector;

/// Below this many objects the direct all-pairs loop is used (see `docs/performance.md`).
pub const SMALL_N: usize = 100;

/// An object for the broad phase: a centre and per-axis half sizes of its bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BroadObject<V> {
    /// Centre of the bounding box.
    pub center: V,
    /// Half sizes of the bounding box, per world axis.
    pub half: V,
    /// The id to report in pairs (the critter's slot index).
    pub slot: u32,
    /// Walls never pair with walls.
    pub is_wall: bool,
}

/// Where the broad phase reads its objects: indices `0..slots()`, each an object or a gap (a
/// slot with no live critter). Pairs are reported by the objects' `slot`s. A slice of objects is
/// one; the world reads its critters' slots in place, so no list of objects is kept per step.
pub(crate) trait Objects<V: Vector>: Sync {
    /// How many indices there are.
    fn slots(&self) -> usize;
    /// The object at index `i < slots()`, or `None` for a gap.
    fn object(&self, i: usize) -> Option<BroadObject<V>>;
    /// A hint that `object(i)` will be asked for soon: a source that reads scattered memory
    /// may start loading it.
    #[inline]
    fn prefetch(&self, _i: usize) {}
    /// Where the object at index `i` moves in a step at its velocity (zero for a gap or an
    /// object that does not know): the Verlet list widens a fast object's bound, and pushes it
    /// ahead, so that it lasts [`LEAD_STEPS`] steps, where the skin alone would make it rebuild
    /// every step or two.
    #[inline]
    fn step(&self, _i: usize) -> V {
        V::zero()
    }
    /// True when the object at index `i` stays where it is this step and needs no test against
    /// another such object (a sleeper or a wall, src/method/sleep.rs): the kept Verlet list
    /// drops their pairs without reading the objects.
    #[inline]
    fn still(&self, _i: usize) -> bool {
        false
    }
    /// False when no object is [`Objects::still`], so that the pair loops need not ask.
    #[inline]
    fn any_still(&self) -> bool {
        false
    }
}

/// Steps a fast object's bound in the Verlet list is made to last at its speed at the build:
/// the object's box is widened (see [`AHEAD`]) by `LEAD_STEPS` strides less half the skin
/// (nothing for the objects the skin already covers that long). With radii spread over a factor
/// of 100 the small disks are up to 20 times faster than the rest and outran any skin, so the
/// list was rebuilt nearly every step; widened, they pair with a few more neighbours instead.
pub(crate) const LEAD_STEPS: f64 = 8.0;

/// The share of a lead ([`LEAD_STEPS`]) that stretches a fast object's box along its step
/// rather than all round: a disk is more likely to go on than to turn back, and a smaller box
/// has fewer pairs. With half, the mixed radii's step (10,000 disks, after 8,000 steps) took
/// 4-5 % less than with none (the list built 15 % more often, its re-test of the kept pairs
/// 40 % quicker); with 0.7 or all of it a disk turned by a collision left its bound too soon,
/// and the list was built half as often again or three times as often.
const AHEAD: f64 = 0.5;

/// In a crowd (a pile: the last step found a contact for every 8 listed pairs or fewer; the
/// world says so, [`BroadPhase::set_crowded`]) only objects whose stride is more than this many times
/// the median stride are led. A pile jostled by the discrete step's separations moves in ways
/// its velocities do not show, so its list is rebuilt every step whatever the leads, and leading
/// everyone only adds pairs: the 9-layer and 90-layer piles under discrete were 38 % and 56 %
/// slower with every object led. Elsewhere every object whose [`LEAD_STEPS`] strides pass half
/// the skin is led: in the hot gas of mixed radii hundreds of middling disks (1.3 to 2 times the
/// median stride) left their bounds every step and the list lived 3 steps; led, it lives 5 and
/// a step costs half.
const FAST: f64 = 2.0;

/// The objects of `O` with each box widened by its lead (see [`LEAD_STEPS`]), for the Verlet
/// list's build: its pairs and bounds.
struct Led<'a, O: ?Sized> {
    objs: &'a O,
    /// Half the skin, which every box gets anyway.
    half_skin: f64,
    /// Only objects with a longer stride than this are led.
    fast: f64,
}

impl<V: Vector, O: Objects<V> + ?Sized> Objects<V> for Led<'_, O> {
    #[inline]
    fn slots(&self) -> usize {
        self.objs.slots()
    }

    #[inline]
    fn object(&self, i: usize) -> Option<BroadObject<V>> {
        let mut o = self.objs.object(i)?;
        let step = self.objs.step(i);
        let stride = step.length();
        let lead = LEAD_STEPS * stride - self.half_skin;
        if stride > self.fast && lead > 0.0 {
            // Widened all round by `1 - AHEAD` of the lead, and by the rest along the step.
            let ahead = step * (0.5 * AHEAD * lead / stride);
            o.center += ahead;
            for axis in 0..V::DIM {
                let half = o.half.get(axis) + ahead.get(axis).abs() + (1.0 - AHEAD) * lead;
                o.half.set(axis, half);
            }
        }
        Some(o)
    }

    #[inline]
    fn prefetch(&self, i: usize) {
        self.objs.prefetch(i);
    }
}

impl<V: Vector> Objects<V> for [BroadObject<V>] {
    #[inline]
    fn slots(&self) -> usize {
        self.len()
    }

    #[inline]
    fn object(&self, i: usize) -> Option<BroadObject<V>> {
        self.get(i).copied()
    }
}

/// Which algorithm to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BroadPhaseMode {
    /// Direct loop for small scenes, otherwise the grid with a Verlet list (pairs kept while
    /// nothing has moved far).
    #[default]
    Auto,
    /// The grid rebuilt every step.
    Grid,
    /// Always the direct all-pairs loop (the naive baseline).
    AllPairs,
}

/// What a level's build may take instead of a pass over its members (see [`Level::build`]):
/// their indices again, every object's cell key in the level's last grid, and each object by
/// its index.
struct Known<'a, I, F> {
    indices: I,
    keys: &'a [u32],
    object: F,
}

/// One level of the grid: its cells and its members, copied in cell order.
struct Level<V: Vector> {
    inv_cell: [f64; 3],
    dims: [usize; 3],
    wrap: [bool; 3],
    /// `start[k]..start[k + 1]` indexes `sorted` (or `members`) for cell `k`.
    start: Vec<u32>,
    /// The members' boxes in cell order, so the pair loops read memory in order (empty once
    /// [`Level::slim`]).
    sorted: Vec<CellBox<V>>,
    /// Cell key of each entry of `sorted`.
    sorted_keys: Vec<u32>,
    /// Once a Verlet list's build is done with them ([`Level::slim`]): the tag of each entry
    /// of `sorted` (its index, with [`WALL`] for a wall), in the same order, while `sorted` and
    /// `sorted_keys` are let go.
    members: Vec<u32>,
}

impl<V: Vector> Default for Level<V> {
    fn default() -> Self {
        Level {
            inv_cell: [0.0; 3],
            dims: [1; 3],
            wrap: [false; 3],
            start: Vec::new(),
            sorted: Vec::new(),
            sorted_keys: Vec::new(),
            members: Vec::new(),
        }
    }
}

/// `i` mod `n` for `i` within one period of `[0, n)`, the general case otherwise.
/// 2 to the power `l`, exactly (infinite from 1024 on), without a call to `exp2`.
#[inline]
fn pow2(l: usize) -> f64 {
    f64::from_bits((1023 + l.min(1024) as u64) << 52)
}

/// `x` rounded down, clamped to +-1e15 (0 for NaN), without a call to `floor` (a call into the
/// maths library without SSE 4.1, 3 % of the mixed-radii scene's step in the footprints).
#[inline]
fn floor_to_i64(x: f64) -> i64 {
    let x = x.clamp(-1e15, 1e15);
    let t = x as i64;
    t - i64::from((t as f64) > x)
}

#[inline]
fn wrap_index(i: i64, n: usize) -> usize {
    let n = n as i64;
    if i < 0 {
        if i >= -n {
            (i + n) as usize
        } else {
            i.rem_euclid(n) as usize
        }
    } else if i >= n {
        if i < 2 * n {
            (i - n) as usize
        } else {
            i.rem_euclid(n) as usize
        }
    } else {
        i as usize
    }
}

impl<V: Vector> Level<V> {
    #[inline]
    fn coords(&self, topo: &Topology<V>, p: V) -> [usize; 3] {
        let mut c = [0usize; 3];
        for (axis, slot) in c.iter_mut().enumerate().take(V::DIM) {
            let n = self.dims[axis];
            if n == 1 {
                continue;
            }
            let f = (p.get(axis) - topo.min.get(axis)) * self.inv_cell[axis];
            // Truncation is floor for f >= 0; the rare negative case is handled below.
            let i = if f >= 0.0 && f < n as f64 {
                f as i64
            } else {
                floor_to_i64(f)
            };
            *slot = if self.wrap[axis] {
                wrap_index(i, n)
            } else {
                i.clamp(0, n as i64 - 1) as usize
            };
        }
        c
    }

    #[inline]
    fn key(&self, c: [usize; 3]) -> usize {
        c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])
    }

    /// The cell at offset `o` from `c`, if it exists.
    #[inline]
    fn neighbour(&self, c: [usize; 3], o: [i32; 3]) -> Option<usize> {
        let mut n = [0usize; 3];
        for axis in 0..3 {
            let d = self.dims[axis] as i64;
            let x = c[axis] as i64 + o[axis] as i64;
            n[axis] = if self.wrap[axis] {
                wrap_index(x, self.dims[axis])
            } else if x < 0 || x >= d {
                return None;
            } else {
                x as usize
            };
        }
        Some(self.key(n))
    }

    /// True when every neighbour of `c` exists without wrapping, so keys can be offset directly.
    #[inline]
    fn interior(&self, c: [usize; 3]) -> bool {
        (0..3).all(|axis| self.dims[axis] == 1 || (c[axis] >= 1 && c[axis] + 1 < self.dims[axis]))
    }

    /// The key offset of cell offset `o` (valid for interior cells).
    fn key_delta(&self, o: [i32; 3]) -> isize {
        o[0] as isize
            + self.dims[0] as isize * (o[1] as isize + self.dims[1] as isize * o[2] as isize)
    }

    /// Per axis, the first cell and the number of cells of this level whose members may overlap
    /// the box of `b` (members are at most one cell wide). Never more cells than the axis has.
    #[inline]
    fn footprint(&self, topo: &Topology<V>, b: &CellBox<V>) -> [(i64, usize); 3] {
        let (center, half) = (b.center(), b.half());
        let mut out = [(0i64, 1usize); 3];
        for (axis, slot) in out.iter_mut().enumerate().take(V::DIM) {
            let n = self.dims[axis];
            if n == 1 {
                continue;
            }
            let origin = topo.min.get(axis);
            // A member's box reaches at most half a cell from its centre's cell. The sums below
            // round, and a member on the footprint's edge may touch `b` exactly: a billionth
            // more keeps it in.
            let reach = half.get(axis) + 0.5 / self.inv_cell[axis];
            let margin = reach + 1e-9 * ((center.get(axis) - origin).abs() + reach);
            let cell_of = |x: f64| floor_to_i64((x - origin) * self.inv_cell[axis]);
            let (first, last) = (
                cell_of(center.get(axis) - margin),
                cell_of(center.get(axis) + margin),
            );
            *slot = if self.wrap[axis] {
                if last - first + 1 >= n as i64 {
                    (0, n)
                } else {
                    (first, (last - first + 1) as usize)
                }
            } else {
                let first = first.clamp(0, n as i64 - 1);
                let last = last.clamp(0, n as i64 - 1);
                (first, (last - first + 1) as usize)
            };
        }
        out
    }

    /// How many cells [`Self::footprint`] gives for `b`.
    fn footprint_cells(&self, topo: &Topology<V>, b: &CellBox<V>) -> f64 {
        self.footprint(topo, b).iter().map(|r| r.1 as f64).product()
    }

    /// Calls `f` with the tag of each member of the cells of `b`'s footprint (every member whose
    /// box may overlap `b`'s), for a slim level ([`Self::slim`]).
    #[inline]
    fn for_each_member_near(&self, topo: &Topology<V>, b: &CellBox<V>, mut f: impl FnMut(u32)) {
        self.for_each_run_near(topo, b, |run| {
            self.members[run].iter().copied().for_each(&mut f);
        });
    }

    /// Calls `f` with the members of the cells of `b`'s footprint, in the order of their cells'
    /// keys, as ranges of indices into the cell-sorted members: the cells of one row of the
    /// footprint (along the first axis) follow each other in the sort, so their members are one
    /// range (two where the row wraps round a periodic border). A large box over a fine level
    /// reads two bounds a row rather than two a cell.
    #[inline]
    fn for_each_run_near(
        &self,
        topo: &Topology<V>,
        b: &CellBox<V>,
        mut f: impl FnMut(std::ops::Range<usize>),
    ) {
        let ranges = self.footprint(topo, b);
        let (first, count) = ranges[0];
        let first = self.axis_cell(0, first);
        // The row's cells before and after the wrap (none after it on a fenced axis).
        let before = count.min(self.dims[0] - first);
        let after = count - before;
        for k in 0..ranges[2].1 {
            for j in 0..ranges[1].1 {
                let row = self.key([
                    0,
                    self.axis_cell(1, ranges[1].0 + j as i64),
                    self.axis_cell(2, ranges[2].0 + k as i64),
                ]);
                let run = |from: usize, cells: usize| {
                    self.start[row + from] as usize..self.start[row + from + cells] as usize
                };
                f(run(first, before));
                if after > 0 {
                    f(run(0, after));
                }
            }
        }
    }

    /// Keeps of the members only their tags in cell order (`members`, written over the cell
    /// keys) and gives up their boxes: what a Verlet list's repairs need of a build's level,
    /// since the list's bounds hold the boxes. Returns the boxes' buffer, for the bounds to be
    /// written into (and handed back at the next build), so that the bounds and the boxes are
    /// never kept at once: at a million disks in 2D, 20 bytes per disk.
    fn slim(&mut self) -> Vec<CellBox<V>> {
        for (key, b) in self.sorted_keys.iter_mut().zip(&self.sorted) {
            *key = b.tag;
        }
        self.members = std::mem::take(&mut self.sorted_keys);
        std::mem::take(&mut self.sorted)
    }

    /// Cell index `i` along `axis`, wrapped on periodic axes (in range otherwise).
    #[inline]
    fn axis_cell(&self, axis: usize, i: i64) -> usize {
        if self.wrap[axis] {
            wrap_index(i, self.dims[axis])
        } else {
            i as usize
        }
    }

    /// The cell coordinates of a key.
    #[inline]
    fn decode(&self, key: usize) -> [usize; 3] {
        let plane = self.dims[0] * self.dims[1];
        let z = key / plane;
        let rest = key - z * plane;
        let y = rest / self.dims[0];
        [rest - y * self.dims[0], y, z]
    }

    #[inline]
    fn cell(&self, key: usize) -> &[CellBox<V>] {
        &self.sorted[self.start[key] as usize..self.start[key + 1] as usize]
    }

    /// The sorted objects cut into runs of whole cells of about `size` objects, in order.
    fn cell_runs(&self, size: usize) -> Vec<std::ops::Range<usize>> {
        let m = self.sorted.len();
        let mut runs = Vec::with_capacity(m / size + 1);
        let mut begin = 0;
        while begin < m {
            let mut end = (begin + size).min(m);
            while end < m && self.sorted_keys[end] == self.sorted_keys[end - 1] {
                end += 1;
            }
            runs.push(begin..end);
            begin = end;
        }
        runs
    }

    /// Appends the pairs of this level's objects in `run` (whole cells of `sorted`) with each
    /// other and with the cells at the `forward` offsets (`deltas` as key offsets); returns the
    /// number of box tests.
    #[inline]
    fn pairs_within(
        &self,
        topo: &Topology<V>,
        forward: &[[i32; 3]],
        deltas: &[isize],
        run: std::ops::Range<usize>,
        out: &mut Vec<(u32, u32)>,
    ) -> u64 {
        let mut tests = 0;
        let mut begin = run.start;
        while begin < run.end {
            let key = self.sorted_keys[begin] as usize;
            let mut end = begin + 1;
            while end < run.end && self.sorted_keys[end] as usize == key {
                end += 1;
            }
            let here = &self.sorted[begin..end];
            let c = self.decode(key);
            begin = end;
            // Each pair is written past the end of those found, which moves on only past an
            // overlap (as in `retest`: no branch on a coin toss).
            let mut at = out.len();
            out.resize(at + here.len() * (here.len() - 1) / 2, (0, 0));
            for (j, a) in here.iter().enumerate() {
                for b in &here[j + 1..] {
                    tests += 1;
                    out[at] = (a.index(), b.index());
                    at += usize::from(cells_overlap_flag(topo, a, b));
                }
            }
            out.truncate(at);
            let interior = self.interior(c);
            for (&o, &delta) in forward.iter().zip(deltas) {
                let nk = if interior {
                    (key as isize + delta) as usize
                } else {
                    match self.neighbour(c, o) {
                        Some(nk) => nk,
                        None => continue,
                    }
                };
                let there = self.cell(nk);
                let mut at = out.len();
                out.resize(at + here.len() * there.len(), (0, 0));
                for a in here {
                    for b in there {
                        tests += 1;
                        out[at] = (a.index(), b.index());
                        at += usize::from(cells_overlap_flag(topo, a, b));
                    }
                }
                out.truncate(at);
            }
        }
        tests
    }

    /// The neighbour offsets after (0,0,0) in (z, y, x) order: the forward half a cell's pairs
    /// are found with.
    fn forward_offsets(&self) -> Vec<[i32; 3]> {
        let range = |axis: usize| -> Vec<i32> {
            if axis < V::DIM && self.dims[axis] > 1 {
                vec![-1, 0, 1]
            } else {
                vec![0]
            }
        };
        let mut out = Vec::new();
        for &z in &range(2) {
            for &y in &range(1) {
                for &x in &range(0) {
                    if (z, y, x) > (0, 0, 0) {
                        out.push([x, y, z]);
                    }
                }
            }
        }
        out
    }

    /// Sizes the level's grid for cells at least `cell` wide (and at most `limit` cells), sorts
    /// its members (the objects `members` gives, with their indices) by cell, and returns the cell
    /// width used. The sorted copies are widened by `pad` and named by their index. `known`, if
    /// given, is the members' indices again and every object's cell key in this level's last
    /// grid: taken where the new grid is the same, in place of a pass over the members.
    fn build<M, I, It, F>(
        &mut self,
        members: impl Fn() -> M,
        known: Option<Known<'_, I, F>>,
        topo: &Topology<V>,
        mut cell: f64,
        limit: f64,
        pad: f64,
    ) -> f64
    where
        M: Iterator<Item = (u32, BroadObject<V>)>,
        I: Fn() -> It + Sync,
        It: Iterator<Item = usize>,
        F: Fn(usize) -> Option<BroadObject<V>> + Sync,
    {
        let last = (self.dims, self.inv_cell, self.wrap);
        let size = topo.size();
        loop {
            let mut cells = 1.0;
            for axis in 0..3 {
                self.wrap[axis] = false;
                if axis >= V::DIM {
                    self.dims[axis] = 1;
                    self.inv_cell[axis] = 0.0;
                    continue;
                }
                let len = size.get(axis);
                if topo.wraps() {
                    let mut n = (len / cell).floor().max(1.0) as usize;
                    if n < 3 {
                        n = 1;
                    }
                    self.dims[axis] = n;
                    self.wrap[axis] = n > 1;
                    self.inv_cell[axis] = n as f64 / len;
                } else {
                    let n = (len / cell).ceil().clamp(1.0, 1e9) as usize;
                    self.dims[axis] = n;
                    self.inv_cell[axis] = 1.0 / cell;
                }
                cells *= self.dims[axis] as f64;
            }
            if cells <= limit {
                break;
            }
            cell *= (cells / limit).powf(1.0 / V::DIM as f64) * 1.01;
        }

        // Counting sort of the members by cell key, copying the objects into cell order.
        let ncells = self.dims[0] * self.dims[1] * self.dims[2];
        self.start.clear();
        self.start.resize(ncells + 1, 0);
        // The members' keys as the caller found them in the last build's grid, if it is this
        // one: the same keys, without reading the members again.
        let known = known.filter(|_| last == (self.dims, self.inv_cell, self.wrap));
        if let Some(known) = &known {
            let parts = rayon::current_num_threads().min(FILL_PARTS);
            if known.keys.len() >= crate::world::PARALLEL_MIN && parts > 1 {
                self.sort_in_parts(known, parts, pad);
                return cell;
            }
        }
        let mut m = 0;
        match &known {
            Some(Known { indices, keys, .. }) => {
                for i in indices() {
                    self.start[keys[i] as usize] += 1;
                    m += 1;
                }
            }
            None => {
                for (_, o) in members() {
                    let k = self.key(self.coords(topo, o.center));
                    self.start[k] += 1;
                    m += 1;
                }
            }
        }
        self.ready_to_fill(m);
        // `start[k]` is used as the fill cursor of cell k, which leaves it at the cell's end;
        // `ends_to_starts` turns ends back into starts.
        // Each key is taken from `known` or found again from the centre (a few operations on
        // what is read anyway) rather than kept from the count: 4 bytes per member less.
        for (i, o) in members() {
            let k = match &known {
                Some(known) => known.keys[i as usize] as usize,
                None => self.key(self.coords(topo, o.center)),
            };
            let at = self.start[k] as usize;
            self.sorted[at] = CellBox::new(&o, i, pad);
            self.sorted_keys[at] = k as u32;
            self.start[k] += 1;
        }
        self.ends_to_starts();
        cell
    }

    /// Turns the cell counts in `start` into each cell's first place (an exclusive prefix sum,
    /// carried in a register: a loop through memory stalls on each add), and sizes the sorted
    /// copies for `m` members.
    fn ready_to_fill(&mut self, m: usize) {
        let mut acc = 0u32;
        for s in self.start.iter_mut() {
            let count = *s;
            *s = acc;
            acc += count;
        }
        self.sorted.clear();
        self.sorted.resize(m, CellBox::default());
        if self.sorted_keys.capacity() == 0 {
            // A slim level's tags are not read again once it is built anew.
            self.sorted_keys = std::mem::take(&mut self.members);
        }
        self.sorted_keys.clear();
        self.sorted_keys.resize(m, 0);
    }

    /// After a fill that used `start[k]` as cell k's cursor, which left it at the cell's end:
    /// each cell's start again.
    fn ends_to_starts(&mut self) {
        let ncells = self.start.len() - 1;
        for k in (1..=ncells).rev() {
            self.start[k] = self.start[k - 1];
        }
        self.start[0] = 0;
    }

    /// [`Level::build`]'s counting sort with every member's key known, in `parts` ranges of
    /// cells on rayon's threads. Each part reads every member's key and takes the members of
    /// its own cells, in index order: the cells come out as the sequential sort fills them, for
    /// any number of parts. The members are counted in ranges of as many cells, and filled in
    /// ranges of about as many members (at a million critters one pass through the critters,
    /// 36 ms a build on one thread, was the sequential part of a build).
    fn sort_in_parts<I, It, F>(&mut self, known: &Known<'_, I, F>, parts: usize, pad: f64)
    where
        I: Fn() -> It + Sync,
        It: Iterator<Item = usize>,
        F: Fn(usize) -> Option<BroadObject<V>> + Sync,
    {
        use rayon::prelude::*;
        let Known {
            indices,
            keys,
            object,
        } = known;
        let ncells = self.start.len() - 1;
        let per = ncells.div_ceil(parts).max(1);
        let m: usize = self.start[..ncells]
            .par_chunks_mut(per)
            .enumerate()
            .map(|(p, counts)| {
                let cells = p * per..p * per + counts.len();
                let mut m = 0;
                for i in indices() {
                    let k = keys[i] as usize;
                    if cells.contains(&k) {
                        counts[k - cells.start] += 1;
                        m += 1;
                    }
                }
                m
            })
            .sum();
        self.ready_to_fill(m);
        // Cells cut where the members before reach each part's share.
        let mut cuts = vec![0usize];
        for p in 1..parts {
            let share = (m * p / parts) as u32;
            let k = self.start[..ncells].partition_point(|&s| s < share);
            cuts.push(k.max(cuts[p - 1]));
        }
        cuts.push(ncells);
        let mut jobs = Vec::with_capacity(parts);
        let (mut start, mut sorted, mut tags) = (
            &mut self.start[..ncells],
            &mut self.sorted[..],
            &mut self.sorted_keys[..],
        );
        for w in cuts.windows(2) {
            let (lo, hi) = (w[0], w[1]);
            let first = start.first().map_or(m, |&s| s as usize);
            let end = if hi < ncells {
                start[hi - lo] as usize
            } else {
                m
            };
            let (s, rest) = std::mem::take(&mut start).split_at_mut(hi - lo);
            let (b, rest_b) = std::mem::take(&mut sorted).split_at_mut(end - first);
            let (t, rest_t) = std::mem::take(&mut tags).split_at_mut(end - first);
            (start, sorted, tags) = (rest, rest_b, rest_t);
            jobs.push((lo..hi, first, s, b, t));
        }
        jobs.into_par_iter()
            .for_each(|(cells, first, cursor, boxes, tags)| {
                for i in indices() {
                    let k = keys[i] as usize;
                    if !cells.contains(&k) {
                        continue;
                    }
                    let Some(o) = object(i) else {
                        continue;
                    };
                    let c = &mut cursor[k - cells.start];
                    let at = *c as usize - first;
                    boxes[at] = CellBox::new(&o, i as u32, pad);
                    tags[at] = k as u32;
                    *c += 1;
                }
            });
        self.ends_to_starts();
    }
}

/// A chunk of the kept list re-tested: how many pairs were tested, those that overlap, and what
/// the caller's `then` gave for them.
type Retested<T> = (u64, Vec<(u32, u32)>, Option<T>);

/// After this many builds in a row of a Verlet list that served one step each, pairs are found
/// with the plain grid (no skin, no list) for [`GRID_SPELL`] steps before a list is tried again.
/// A pile jostled by the discrete step's separations leaves any skin every step: its list's
/// skin only added pairs and its re-test repeated the build's tests (the 9-layer pile of the
/// stress bench, one thread: 2.44-2.47 ms a step, against 2.02-2.15 with the plain grid and the
/// same bits).
const SHORT_LIVED: u32 = 3;

/// Steps the plain grid is used for once lists are found to live a single step (see
/// [`SHORT_LIVED`]).
const GRID_SPELL: u32 = 32;

/// A repair of the Verlet list is refused, and the list built anew, once the objects mended
/// since the build would pass this share of all objects: each is tested against the others'
/// new boxes one by one.
const REPAIR_SHARE: f64 = 1.0 / 32.0;

/// A repair is refused when its cells to visit and its tests among the new boxes would pass
/// this many per object: a build visits a few cells per object on each level.
const REPAIR_WORK: f64 = 4.0;

/// Objects per task of the pass that finds each object's level on rayon's threads.
const LEVEL_CHUNK: usize = 8192;

/// At most this many parts of a large level's counting sort run at once (each reads every
/// member's key: [`Level::sort_in_parts`]).
const FILL_PARTS: usize = 8;

/// Objects per run of cells walked by one task when a level's pairs are found in parallel.
const RUN_OBJECTS: usize = 8192;

/// Runs of [`RUN_OBJECTS`] walked in parallel before their pairs are joined onto the list.
const RUNS_AT_ONCE: usize = 16;

/// The skin of the Verlet list, as a fraction of the objects' typical width: 0.6 in 2D, 0.4 in
/// 3D. A larger skin means fewer rebuilds and more kept pairs to re-test; in 2D 0.6 against 0.4
/// made the settled gas 2-10 % faster from 1e4 to 1e6 for about 6 bytes per critter more, in 3D
/// (where the kept pairs grow with the cube of the reach) it saved no time and cost 15 bytes
/// per critter at 2e5 and 50 at 1e6 (docs/performance.md).
fn skin<V: Vector>() -> f64 {
    if V::DIM == 2 {
        0.6
    } else {
        0.4
    }
}

/// Most objects sampled for the typical width.
const WIDTH_SAMPLES: usize = 1024;

/// The median width of the disks among up to [`WIDTH_SAMPLES`] indices spread evenly over `objs`
/// (all of them when there are fewer); the smallest width of all when none of those is a disk;
/// infinite for no objects. The skin follows it rather than the smallest width: with radii
/// spread over a factor of 100, a skin of the smallest width is outrun by the small disks every
/// step, and the list was rebuilt every step (12x the uniform gas's step). A median of a fixed
/// sample costs nothing at any N and depends only on `objs`.
fn typical_width<V: Vector, O: Objects<V> + ?Sized>(
    objs: &O,
    width: impl Fn(&BroadObject<V>) -> f64,
) -> f64 {
    sample_median(objs, |_, o| width(o)).unwrap_or_else(|| {
        (0..objs.slots())
            .filter_map(|i| objs.object(i))
            .map(|o| width(&o))
            .fold(f64::INFINITY, f64::min)
    })
}

/// The median of `value(i, object)` over the objects that are not walls among up to
/// [`WIDTH_SAMPLES`] indices spread evenly over `objs`; `None` when there are none.
fn sample_median<V: Vector, O: Objects<V> + ?Sized>(
    objs: &O,
    value: impl Fn(usize, &BroadObject<V>) -> f64,
) -> Option<f64> {
    let n = objs.slots();
    let step = n.div_ceil(WIDTH_SAMPLES).max(1);
    let mut sample = [0.0f64; WIDTH_SAMPLES];
    let mut taken = 0;
    for i in (0..n).step_by(step) {
        if let Some(o) = objs.object(i).filter(|o| !o.is_wall) {
            sample[taken] = value(i, &o);
            taken += 1;
        }
    }
    if taken == 0 {
        return None;
    }
    let (_, median, _) = sample[..taken].select_nth_unstable_by(taken / 2, f64::total_cmp);
    Some(*median)
}

/// The median stride of the objects that are not walls among the same sample as
/// [`typical_width`]'s (0 for none).
fn typical_stride<V: Vector, O: Objects<V> + ?Sized>(objs: &O) -> f64 {
    sample_median(objs, |i, _| objs.step(i).length()).unwrap_or(0.0)
}

/// Where one index's object may be while the Verlet list stays valid: its box at the build widened
/// by half the skin, in single precision rounded inwards, so that a box inside the bound is inside
/// the widened box its pairs were found with. A [`CellBox`] made by [`CellBox::bound`] (its half
/// sizes are then how far the object's box may reach from the centre), so that the bounds and a
/// level's cell-sorted boxes can take turns with one buffer (see [`Level::slim`]); 20 bytes in
/// 2D, 28 in 3D.
type Bound<V> = CellBox<V>;

/// The tag of a gap's [`Bound`] (its centre is NaN too, so no object is ever inside it).
const GAP: u32 = u32::MAX;

impl<V: Vector> CellBox<V> {
    /// The [`Bound`] of `o` widened by `pad`: the centre to the nearest `f32`, the half sizes
    /// (how far the box may reach from the centre) the widened ones less the centre's rounding,
    /// rounded down; the slot as the tag, with [`WALL`] for a wall. A gap's is NaN, tagged
    /// [`GAP`].
    #[inline]
    fn bound(o: Option<&BroadObject<V>>, pad: f64) -> Self {
        let Some(o) = o else {
            let mut nan = V::Single::default();
            nan.as_mut().fill(f32::NAN);
            return CellBox {
                center: nan,
                half: nan,
                tag: GAP,
            };
        };
        let (center, moved) = rounded(o.center);
        let mut room = V::Single::default();
        for (axis, r) in room.as_mut().iter_mut().enumerate() {
            *r = at_most(o.half.get(axis) + pad - moved.get(axis));
        }
        CellBox {
            center,
            half: room,
            tag: tag_of(o),
        }
    }

    /// For a [`Bound`]: true when `o` is what the bound was made from, a gap for a gap, or for
    /// an object the box of one with the same slot and wall flag that lies inside the bound.
    /// Never for a NaN.
    #[inline]
    fn holds(&self, topo: &Topology<V>, o: Option<&BroadObject<V>>) -> bool {
        let Some(o) = o else {
            return self.tag == GAP;
        };
        if tag_of(o) != self.tag {
            return false;
        }
        let d = topo.delta(V::from_single(self.center), o.center);
        let room = self.half.as_ref();
        (0..V::DIM).all(|axis| d.get(axis).abs() + o.half.get(axis) <= f64::from(room[axis]))
    }
}

/// An object's slot with [`WALL`] set for a wall.
#[inline]
fn tag_of<V: Vector>(o: &BroadObject<V>) -> u32 {
    if o.is_wall {
        o.slot | WALL
    } else {
        o.slot
    }
}

/// `v` to the nearest `f32` on each axis, and how far each component moved (its magnitude).
#[inline]
fn rounded<V: Vector>(v: V) -> (V::Single, V) {
    let mut single = V::Single::default();
    let mut moved = V::zero();
    for (axis, x) in single.as_mut().iter_mut().enumerate() {
        *x = v.get(axis) as f32;
        moved.set(axis, (f64::from(*x) - v.get(axis)).abs());
    }
    (single, moved)
}

/// The smallest `f32` not below `x`, or one just above it (NaN for NaN).
#[inline]
fn at_least(x: f64) -> f32 {
    -at_most(-x)
}

/// The largest `f32` not above `x`, or one just below it (NaN for NaN, so a bound made from it
/// holds nothing).
#[inline]
fn at_most(x: f64) -> f32 {
    let size = x.abs();
    if size >= f64::from(f32::MIN_POSITIVE) && size <= f64::from(f32::MAX) {
        // Stepping down by f32's relative epsilon before rounding to nearest lands at or below
        // `x` (the rounding moves by at most half that), without a branch on whether the
        // rounding went up: a coin toss per value, which a branch would mispredict.
        (x - size * f64::from(f32::EPSILON)) as f32
    } else {
        let y = x as f32;
        if f64::from(y) > x {
            y.next_down()
        } else {
            y
        }
    }
}

/// The kept pairs of the Verlet list and where each object may go before it must be rebuilt.
struct PairList<V: Vector> {
    valid: bool,
    skin: f64,
    /// The stride above which an object is led, as set at the build.
    fast: f64,
    bounds: Vec<Bound<V>>,
    pairs: Vec<(u32, u32)>,
    /// True once `pairs` are in the order of their lower index, then their higher one
    /// (repairs then keep it); a build leaves them in the grid's order.
    sorted: bool,
    /// Set by [`BroadPhase::sort_list`]: sort `pairs` when the list is next kept.
    sort_wanted: bool,
    /// Set by [`BroadPhase::set_crowded`]: the last step's contacts were many for the list's
    /// pairs (a pile), so the next build leads only the objects faster than [`FAST`] times the
    /// median.
    crowded: bool,
    rebuilds: u64,
    /// Steps the list has served since its build (the build's own included).
    served: u32,
    /// Builds in a row that served a single step.
    short_lived: u32,
    /// Steps left to find pairs with the plain grid instead of a list (see [`SHORT_LIVED`]).
    grid_left: u32,
    /// Steps found with the plain grid instead of a list.
    grid_steps: u64,
    /// Indices whose box was made anew by a repair since the build (one bit each): their
    /// entries in the build's levels are stale.
    moved: Vec<u64>,
    /// The new boxes of the `moved` indices that have an object.
    extras: Vec<CellBox<V>>,
    repairs: u64,
}

impl<V: Vector> Default for PairList<V> {
    fn default() -> Self {
        PairList {
            valid: false,
            skin: 0.0,
            fast: 0.0,
            bounds: Vec::new(),
            pairs: Vec::new(),
            sorted: false,
            sort_wanted: false,
            crowded: false,
            rebuilds: 0,
            served: 0,
            short_lived: 0,
            grid_left: 0,
            grid_steps: 0,
            moved: Vec::new(),
            extras: Vec::new(),
            repairs: 0,
        }
    }
}

/// Bit `i` of a bit set.
#[inline]
fn bit(set: &[u64], i: usize) -> bool {
    set[i / 64] >> (i % 64) & 1 != 0
}

/// Sets bit `i` of a bit set.
#[inline]
fn set_bit(set: &mut [u64], i: usize) {
    set[i / 64] |= 1 << (i % 64);
}

/// The broad phase, with its scratch memory kept between steps.
pub struct BroadPhase<V: Vector> {
    /// Algorithm choice.
    pub mode: BroadPhaseMode,
    list: PairList<V>,
    levels: Vec<Level<V>>,
    /// The levels the last build filled, finest first (the others may hold older builds).
    used: Vec<usize>,
    level_of: Vec<u8>,
    /// The finest width of the last build (its `s0`), the guess the next one starts from.
    finest: f64,
    /// The grid's pairs before their exact test, kept between calls (`BroadPhaseMode::Grid`).
    found: Vec<(u32, u32)>,
    /// Number of bounding-box tests made in the last call.
    pub tests: u64,
    /// Number of grid levels used in the last call (0 for the direct loop).
    pub levels_used: usize,
}

impl<V: Vector> Default for BroadPhase<V> {
    fn default() -> Self {
        BroadPhase {
            mode: BroadPhaseMode::Auto,
            list: PairList::default(),
            levels: Vec::new(),
            used: Vec::new(),
            level_of: Vec::new(),
            finest: 0.0,
            found: Vec::new(),
            tests: 0,
            levels_used: 0,
        }
    }
}

#[inline]
fn overlaps<V: Vector>(topo: &Topology<V>, a: &BroadObject<V>, b: &BroadObject<V>) -> bool {
    if a.is_wall && b.is_wall {
        return false;
    }
    let d = topo.delta(a.center, b.center);
    for axis in 0..V::DIM {
        if d.get(axis).abs() > a.half.get(axis) + b.half.get(axis) {
            return false;
        }
    }
    true
}

/// The pair of `objs` at indices `(i, j)` by slot, if both are objects and their boxes overlap.
#[cfg(test)]
fn exact<V: Vector, O: Objects<V> + ?Sized>(
    objs: &O,
    topo: &Topology<V>,
    &(i, j): &(u32, u32),
) -> Option<(u32, u32)> {
    let (a, b) = (objs.object(i as usize)?, objs.object(j as usize)?);
    overlaps(topo, &a, &b).then_some((a.slot, b.slot))
}

/// Pairs [`retest`] writes ahead of those it has found at most.
const RETEST_BLOCK: usize = 256;

/// [`overlaps`] computed whole, without a branch on any axis (`&`, not `&&`): the re-test's
/// outcome is a coin toss the processor cannot predict.
#[inline(always)]
fn overlap_flag<V: Vector>(topo: &Topology<V>, a: &BroadObject<V>, b: &BroadObject<V>) -> bool {
    let d = topo.delta(a.center, b.center);
    let mut hit = !(a.is_wall & b.is_wall);
    for axis in 0..V::DIM {
        hit &= d.get(axis).abs() <= a.half.get(axis) + b.half.get(axis);
    }
    hit
}

/// How many indices ahead a level's passes over its members ask for objects to be prefetched
/// (8: the list's builds at a million critters about 2 % faster than with 4; no change at 1e4).
const MEMBERS_AHEAD: usize = 8;

/// How many pairs ahead [`retest`] asks for its objects to be prefetched (64: with 64-byte 2D
/// records the broad phase at a million critters took 12.2 ms a step on two threads against
/// 12.7-13.2 with 32 and 14.1-14.3 with 16, and 17.8-18.5 on one thread against 18.9-19.7 and
/// 20.7-21.2; no change at 1e3 to 1e5. With 128-byte records, 16 had been 7 % faster than 8).
const PAIRS_AHEAD: usize = 64;

/// The pairs of `pairs` (indices) whose exact boxes overlap, by slot, pushed onto `out`. The
/// objects of the pair [`PAIRS_AHEAD`] places on are asked for while this one is tested: the
/// world reads them from its critters, scattered over memory, and the loads overlap. Pairs of
/// two still objects are skipped unread. Returns how many pairs were tested.
#[inline]
fn retest<V: Vector, O: Objects<V> + ?Sized>(
    objs: &O,
    topo: &Topology<V>,
    pairs: &[(u32, u32)],
    out: &mut Vec<(u32, u32)>,
) -> u64 {
    if objs.any_still() {
        retest_skipping::<true, V, O>(objs, topo, pairs, out)
    } else {
        retest_skipping::<false, V, O>(objs, topo, pairs, out)
    }
}

/// [`retest`]'s loop; with `STILL` false nothing is still, and the check is compiled away (the
/// gas pays nothing for sleep).
#[inline]
fn retest_skipping<const STILL: bool, V: Vector, O: Objects<V> + ?Sized>(
    objs: &O,
    topo: &Topology<V>,
    pairs: &[(u32, u32)],
    out: &mut Vec<(u32, u32)>,
) -> u64 {
    let still = |&(i, j): &(u32, u32)| STILL && objs.still(i as usize) && objs.still(j as usize);
    let mut tested = 0;
    // Every pair is written at the end of `out`, which moves on only past those that overlap:
    // whether a pair overlaps is a coin toss the processor cannot predict, and this way it is
    // not a branch.
    // A block at a time, so that `out` never grows past the pairs found and one block.
    for (b, block) in pairs.chunks(RETEST_BLOCK).enumerate() {
        let mut end = out.len();
        out.resize(end + block.len(), (0, 0));
        for (k, pair) in block.iter().enumerate() {
            if let Some(ahead) = pairs.get(b * RETEST_BLOCK + k + PAIRS_AHEAD) {
                if !still(ahead) {
                    objs.prefetch(ahead.0 as usize);
                    objs.prefetch(ahead.1 as usize);
                }
            }
            if !still(pair) {
                tested += 1;
                let hit = match (objs.object(pair.0 as usize), objs.object(pair.1 as usize)) {
                    (Some(a), Some(b)) => {
                        out[end] = (a.slot, b.slot);
                        overlap_flag(topo, &a, &b)
                    }
                    _ => false,
                };
                end += usize::from(hit);
            }
        }
        out.truncate(end);
    }
    tested
}

/// Sorts the pairs from `start` on by their lower index, then their higher one, and merges them
/// into the pairs before, which are in that order already.
fn merge_tail(pairs: &mut Vec<(u32, u32)>, start: usize) {
    let key = |&(a, b): &(u32, u32)| (a.min(b), a.max(b));
    pairs[start..].sort_unstable_by_key(key);
    let tail = pairs.split_off(start);
    let (mut i, mut j) = (start, tail.len());
    pairs.resize(start + tail.len(), (0, 0));
    // From the back: each place is written after the pair it held was read.
    while j > 0 {
        let k = i + j - 1;
        if i > 0 && key(&pairs[i - 1]) > key(&tail[j - 1]) {
            pairs[k] = pairs[i - 1];
            i -= 1;
        } else {
            pairs[k] = tail[j - 1];
            j -= 1;
        }
    }
}

/// What a caller that checked each object against the Verlet list while it had it at hand (the
/// world, in its move) found: the indices [`BroadPhase::list_holds`] said no for. A repair then
/// mends those without another pass over every object (at a million critters, a trip through
/// 128 MB).
#[derive(Clone, Debug)]
pub(crate) struct Escapes {
    /// The indices whose object left its bound, ascending.
    pub(crate) slots: Vec<u32>,
    /// False when not every escaped index is in `slots` (the caller stopped noting them, or did
    /// not check every index): the broad phase then checks every object itself.
    pub(crate) complete: bool,
}

/// The tag bit of a wall's [`CellBox`] and [`Bound`].
const WALL: u32 = 1 << 31;

/// The level of a gap (no level has it: levels go up to 63).
const NO_LEVEL: u8 = u8::MAX;

/// An object's box as a level's cell-sorted copy keeps it: the centre to the nearest `f32` and
/// the half sizes (widened by the pad) rounded up past the centre's rounding, so the box holds the
/// exact one; 20 bytes in 2D and 28 in 3D against 40 and 56 for a [`BroadObject`]. The grid's
/// walk may therefore find a pair whose exact boxes only touch through the rounding, never miss
/// one whose exact boxes overlap; the Verlet list and the grid mode test every pair it finds
/// again against the exact boxes.
#[derive(Clone, Copy, Debug, Default)]
struct CellBox<V: Vector> {
    center: V::Single,
    half: V::Single,
    /// The object's index in `objs`, with [`WALL`] set for a wall.
    tag: u32,
}

impl<V: Vector> CellBox<V> {
    #[inline]
    fn new(o: &BroadObject<V>, index: u32, pad: f64) -> Self {
        let (center, moved) = rounded(o.center);
        let mut half = V::Single::default();
        for (axis, h) in half.as_mut().iter_mut().enumerate() {
            *h = at_least(o.half.get(axis) + pad + moved.get(axis));
        }
        CellBox {
            center,
            half,
            tag: if o.is_wall { index | WALL } else { index },
        }
    }

    #[inline]
    fn center(&self) -> V {
        V::from_single(self.center)
    }

    #[inline]
    fn half(&self) -> V {
        V::from_single(self.half)
    }

    /// The object's index in `objs`.
    #[inline]
    fn index(&self) -> u32 {
        self.tag & !WALL
    }
}

/// [`cells_overlap`] computed whole, without a branch on any axis (`&`, not `&&`).
#[inline(always)]
fn cells_overlap_flag<V: Vector>(topo: &Topology<V>, a: &CellBox<V>, b: &CellBox<V>) -> bool {
    let d = topo.delta(a.center(), b.center());
    let (ha, hb) = (a.half(), b.half());
    let mut hit = a.tag & b.tag & WALL == 0;
    for axis in 0..V::DIM {
        hit &= d.get(axis).abs() <= ha.get(axis) + hb.get(axis);
    }
    hit
}

/// Pushes onto `out` the pair `name(a, b)` of indices for each `b` of `run` whose box overlaps
/// `a`'s. Every pair is written past the end of `out`, which moves on only past those that
/// overlap (as in [`retest_skipping`]): no branch on a coin toss.
#[inline(always)]
fn push_overlapping<V: Vector>(
    topo: &Topology<V>,
    a: &CellBox<V>,
    run: &[CellBox<V>],
    out: &mut Vec<(u32, u32)>,
    name: impl Fn(u32, u32) -> (u32, u32),
) {
    let mut end = out.len();
    out.resize(end + run.len(), (0, 0));
    for b in run {
        out[end] = name(a.index(), b.index());
        end += usize::from(cells_overlap_flag(topo, a, b));
    }
    out.truncate(end);
}

/// [`overlaps`] for cells' boxes.
#[inline(always)]
fn cells_overlap<V: Vector>(topo: &Topology<V>, a: &CellBox<V>, b: &CellBox<V>) -> bool {
    if a.tag & b.tag & WALL != 0 {
        return false;
    }
    let d = topo.delta(a.center(), b.center());
    let (ha, hb) = (a.half(), b.half());
    for axis in 0..V::DIM {
        if d.get(axis).abs() > ha.get(axis) + hb.get(axis) {
            return false;
        }
    }
    true
}

impl<V: Vector> BroadPhase<V> {
    /// A broad phase using `mode`.
    pub fn new(mode: BroadPhaseMode) -> Self {
        BroadPhase {
            mode,
            ..Default::default()
        }
    }

    /// Fills `out` with every pair of objects whose bounding boxes overlap, each pair once, as
    /// `(slot, slot)`. Deterministic: the order depends only on `objs`.
    pub fn find_pairs(
        &mut self,
        objs: &[BroadObject<V>],
        topo: &Topology<V>,
        out: &mut Vec<(u32, u32)>,
    ) {
        self.find_pairs_in(objs, topo, out, None);
    }

    /// [`Self::find_pairs`] for any [`Objects`]. `escapes` is what the caller already knows of
    /// the Verlet list: the indices of `objs` for which [`Self::list_holds`] said no, or `None`
    /// when it was not asked (the check is then made here).
    pub(crate) fn find_pairs_in<O: Objects<V> + ?Sized>(
        &mut self,
        objs: &O,
        topo: &Topology<V>,
        out: &mut Vec<(u32, u32)>,
        escapes: Option<Escapes>,
    ) {
        self.find_pairs_then(objs, topo, out, escapes, None::<&fn(&[(u32, u32)])>);
    }

    /// [`Self::find_pairs_in`], and `then` applied to each run of the pairs found where a kept
    /// Verlet list is re-tested in parallel chunks, while the chunk's objects are still in cache:
    /// its results, in the order of the pairs, or `None` when the pairs came another way. The
    /// world gives its rules and narrow phase (at a million critters a second trip through
    /// scattered critters otherwise).
    pub(crate) fn find_pairs_then<O, T, F>(
        &mut self,
        objs: &O,
        topo: &Topology<V>,
        out: &mut Vec<(u32, u32)>,
        escapes: Option<Escapes>,
        then: Option<&F>,
    ) -> Option<Vec<T>>
    where
        O: Objects<V> + ?Sized,
        T: Send,
        F: Fn(&[(u32, u32)]) -> T + Sync,
    {
        out.clear();
        self.tests = 0;
        let n = objs.slots();
        let direct = match self.mode {
            BroadPhaseMode::AllPairs => true,
            BroadPhaseMode::Grid => false,
            BroadPhaseMode::Auto => n <= SMALL_N,
        };
        if direct || n == 0 {
            self.levels_used = 0;
            self.all_pairs(objs, topo, out);
            None
        } else if self.mode == BroadPhaseMode::Grid {
            self.grid(objs, topo, out, &mut Vec::new());
            None
        } else {
            self.listed_pairs(objs, topo, out, escapes, then)
        }
    }

    /// True when the kept Verlet list still covers index `i` holding `o`: for a caller that
    /// checks each object while it has it at hand (the world, in its move) and passes the
    /// indices it said no for to [`Self::find_pairs_in`] ([`Escapes`]). False when there is no
    /// list.
    #[inline]
    pub(crate) fn list_holds(
        &self,
        topo: &Topology<V>,
        i: usize,
        o: Option<&BroadObject<V>>,
    ) -> bool {
        self.list.valid && self.list.bounds.get(i).is_some_and(|b| b.holds(topo, o))
    }

    /// Auto mode's pairs for large scenes: a Verlet list. The grid is built with every box
    /// widened by half a skin, and the pairs it finds are kept; while no object has moved more
    /// than half the skin from where it was then (and none came, went or changed size), every
    /// overlapping pair is among them, so a step only re-tests the kept pairs. When a few have,
    /// the list is mended for them (`repair_list`) rather than built anew.
    fn listed_pairs<O, T, F>(
        &mut self,
        objs: &O,
        topo: &Topology<V>,
        out: &mut Vec<(u32, u32)>,
        escapes: Option<Escapes>,
        then: Option<&F>,
    ) -> Option<Vec<T>>
    where
        O: Objects<V> + ?Sized,
        T: Send,
        F: Fn(&[(u32, u32)]) -> T + Sync,
    {
        if self.list.grid_left > 0 {
            self.list.grid_left -= 1;
            self.list.grid_steps += 1;
            self.plain_grid(objs, topo, out);
            return None;
        }
        let kept = self.list.valid && self.list.bounds.len() == objs.slots();
        // The escaped indices when the caller noted them all, else found by a pass of our own.
        let (valid, known) = match escapes {
            _ if !kept => (false, None),
            Some(e) if e.complete => (e.slots.is_empty(), Some(e.slots)),
            Some(_) => (false, None),
            None => (self.list_still_valid(objs, topo), None),
        };
        if !(valid || kept && self.repair_list(objs, topo, known)) {
            if self.list.valid && self.list.served <= 1 {
                self.list.short_lived += 1;
            } else {
                self.list.short_lived = 0;
            }
            if self.list.short_lived >= SHORT_LIVED {
                // Built anew every step: the skin only adds pairs, and the re-test repeats
                // the build's tests. The plain grid for a while, then a list is tried again.
                self.list.short_lived = 0;
                self.list.grid_left = GRID_SPELL - 1;
                self.list.grid_steps += 1;
                self.plain_grid(objs, topo, out);
                return None;
            }
            self.rebuild_list(objs, topo);
        } else if self.list.sort_wanted && !self.list.sorted {
            crate::world::sort_pairs(&mut self.list.pairs, objs.slots());
            self.list.sorted = true;
        }
        self.list.served = self.list.served.saturating_add(1);
        if objs.slots() >= crate::world::PARALLEL_MIN {
            // Chunks are tested in parallel and joined in order: the same output for any thread count.
            use rayon::prelude::*;
            let parts: Vec<Retested<T>> = self
                .list
                .pairs
                .par_chunks(4096)
                .map(|chunk| {
                    let mut part = Vec::new();
                    let tested = retest(objs, topo, chunk, &mut part);
                    let after = then.map(|f| f(&part));
                    (tested, part, after)
                })
                .collect();
            let mut results = then.map(|_| Vec::with_capacity(parts.len()));
            for (tested, part, after) in parts {
                self.tests += tested;
                out.extend(part);
                if let (Some(results), Some(after)) = (&mut results, after) {
                    results.push(after);
                }
            }
            results
        } else {
            self.tests += retest(objs, topo, &self.list.pairs, out);
            None
        }
    }

    /// Every index's object inside its bound (the list's length already checked).
    fn list_still_valid<O: Objects<V> + ?Sized>(&self, objs: &O, topo: &Topology<V>) -> bool {
        let bounds = &self.list.bounds;
        let inside = |(i, b): (usize, &Bound<V>)| b.holds(topo, objs.object(i).as_ref());
        if objs.slots() >= crate::world::PARALLEL_MIN {
            use rayon::prelude::*;
            bounds.par_iter().enumerate().all(inside)
        } else {
            bounds.iter().enumerate().all(inside)
        }
    }

    fn rebuild_list<O: Objects<V> + ?Sized>(&mut self, objs: &O, topo: &Topology<V>) {
        let width =
            |o: &BroadObject<V>| (0..V::DIM).map(|a| 2.0 * o.half.get(a)).fold(0.0, f64::max);
        let skin = skin::<V>() * typical_width(objs, width);
        // Boxes widened by half the skin, and fast ones by their lead; pairs named by index so
        // they index `objs`.
        let fast = match self.list.crowded {
            true => FAST * typical_stride(objs),
            false => 0.0,
        };
        let led = Led {
            objs,
            half_skin: 0.5 * skin,
            fast,
        };
        let mut pairs = std::mem::take(&mut self.list.pairs);
        pairs.clear();
        // The old bounds' buffer takes the grid's boxes, and the boxes' buffer, once the pairs
        // are found, the new bounds: the two are never kept at once.
        let mut buffer = std::mem::take(&mut self.list.bounds);
        self.grid_padded(&led, topo, &mut pairs, 0.5 * skin, &mut buffer);
        for level in &mut self.levels {
            let boxes = level.slim();
            if boxes.capacity() > buffer.capacity() {
                buffer = boxes;
            }
        }
        self.list.pairs = pairs;
        self.list.sorted = false;
        self.list.sort_wanted = false;
        let bound = |i: usize| Bound::bound(led.object(i).as_ref(), 0.5 * skin);
        buffer.clear();
        buffer.reserve_exact(objs.slots());
        self.list.bounds = buffer;
        if objs.slots() >= crate::world::PARALLEL_MIN {
            use rayon::prelude::*;
            self.list
                .bounds
                .par_extend((0..objs.slots()).into_par_iter().map(bound));
        } else {
            self.list.bounds.extend((0..objs.slots()).map(bound));
        }
        self.list.skin = skin;
        self.list.fast = fast;
        self.list.moved.clear();
        self.list.moved.resize(objs.slots().div_ceil(64), 0);
        self.list.extras.clear();
        self.list.valid = true;
        self.list.served = 0;
        self.list.rebuilds += 1;
        self.tests = 0;
    }

    /// Mends the Verlet list where a few objects left their bounds (or came, went or changed),
    /// instead of building it anew: their pairs are dropped, each gets a new box and bound as a
    /// build would give it, and its pairs are found against the build's levels (skipping the
    /// stale entries of objects mended since) and the new boxes of the mended ones. With radii
    /// spread over a factor of 100 a small disk struck by a large one leaves its bound at once,
    /// and one or two such disks made the list be rebuilt most steps. Returns false, having
    /// changed nothing, when a build is due: more than [`REPAIR_SHARE`] of the objects mended
    /// since the build, or more work than [`REPAIR_WORK`] allows.
    fn repair_list<O: Objects<V> + ?Sized>(
        &mut self,
        objs: &O,
        topo: &Topology<V>,
        known: Option<Vec<u32>>,
    ) -> bool {
        let n = objs.slots();
        let bounds = &self.list.bounds;
        let out = |i: usize| (!bounds[i].holds(topo, objs.object(i).as_ref())).then_some(i as u32);
        let escaped: Vec<u32> = match known {
            Some(escaped) => escaped,
            None if n >= crate::world::PARALLEL_MIN => {
                use rayon::prelude::*;
                (0..n).into_par_iter().filter_map(out).collect()
            }
            None => (0..n).filter_map(out).collect(),
        };
        let (e, x) = (escaped.len(), self.list.extras.len());
        if e == 0 || (e + x) as f64 > REPAIR_SHARE * n as f64 {
            return false;
        }
        let half_skin = 0.5 * self.list.skin;
        let led = Led {
            objs,
            half_skin,
            fast: self.list.fast,
        };
        let fresh: Vec<(u32, Option<CellBox<V>>)> = escaped
            .iter()
            .map(|&i| {
                (
                    i,
                    led.object(i as usize)
                        .map(|o| CellBox::new(&o, i, half_skin)),
                )
            })
            .collect();
        // The work: the cells of each new box's footprint on every level, and its tests against
        // the other new boxes.
        let mut work = (e * (e + x)) as f64;
        for b in fresh.iter().filter_map(|(_, b)| b.as_ref()) {
            for &l in &self.used {
                work += self.levels[l].footprint_cells(topo, b);
            }
        }
        if work > REPAIR_WORK * n as f64 {
            return false;
        }

        let mut leaving = vec![0u64; n.div_ceil(64)];
        for &i in &escaped {
            set_bit(&mut leaving, i as usize);
            set_bit(&mut self.list.moved, i as usize);
        }
        let list = &mut self.list;
        list.extras.retain(|b| !bit(&leaving, b.index() as usize));
        list.pairs
            .retain(|&(a, b)| !bit(&leaving, a as usize) && !bit(&leaving, b as usize));
        let kept = list.pairs.len();
        for (i, b) in fresh {
            list.bounds[i as usize] = Bound::bound(led.object(i as usize).as_ref(), half_skin);
            let Some(b) = b else {
                continue;
            };
            // The others' bounds stand for their boxes at the build: each holds its object's
            // box for as long as the object is not mended, and lies inside that box.
            for &l in &self.used {
                self.levels[l].for_each_member_near(topo, &b, |tag| {
                    let a = tag & !WALL;
                    if !bit(&list.moved, a as usize)
                        && cells_overlap(topo, &list.bounds[a as usize], &b)
                    {
                        list.pairs.push((a, i));
                    }
                });
            }
            for a in &list.extras {
                if cells_overlap(topo, a, &b) {
                    list.pairs.push((a.index(), i));
                }
            }
            list.extras.push(b);
        }
        if list.sorted {
            merge_tail(&mut list.pairs, kept);
        }
        list.repairs += 1;
        true
    }

    /// Asks for the Verlet list's pairs in the order of their lower index, then their higher
    /// one: they are sorted when the list is next kept (not built anew), and stay so until its
    /// next build. The world asks for it when many of the pairs are contacts (a pile): the pairs
    /// found each step then come in the order the response takes them in, and need no sort of
    /// their own. A gas, with few contacts, keeps the grid's order and sorts its few contacts
    /// each step instead; a list built anew every step is never sorted.
    pub(crate) fn sort_list(&mut self) {
        self.list.sort_wanted = true;
    }

    /// Tells the Verlet list whether the last step's contacts were many for its pairs (a pile),
    /// for its next build's leads (see [`FAST`]).
    pub(crate) fn set_crowded(&mut self, crowded: bool) {
        self.list.crowded = crowded;
    }

    /// Drops the Verlet list: the next search builds a new one (the objects' indices changed).
    pub(crate) fn forget_list(&mut self) {
        self.list.valid = false;
    }

    /// Pairs in the Verlet list (0 without one).
    pub(crate) fn listed(&self) -> usize {
        if self.list.valid {
            self.list.pairs.len()
        } else {
            0
        }
    }

    /// How many times the Verlet list was rebuilt (diagnostics).
    pub fn rebuilds(&self) -> u64 {
        self.list.rebuilds
    }

    /// How many times the Verlet list was mended where a few objects left it (diagnostics).
    pub fn repairs(&self) -> u64 {
        self.list.repairs
    }

    /// How many calls found their pairs with the plain grid because lists lived a single step
    /// (diagnostics; see [`SHORT_LIVED`]).
    pub fn grid_steps(&self) -> u64 {
        self.list.grid_steps
    }

    fn all_pairs<O: Objects<V> + ?Sized>(
        &mut self,
        objs: &O,
        topo: &Topology<V>,
        out: &mut Vec<(u32, u32)>,
    ) {
        let n = objs.slots();
        for (i, a) in (0..n).filter_map(|i| Some((i, objs.object(i)?))) {
            for b in (i + 1..n).filter_map(|j| objs.object(j)) {
                self.tests += 1;
                if overlaps(topo, &a, &b) {
                    out.push((a.slot, b.slot));
                }
            }
        }
    }

    /// The grid rebuilt for this call: its cells' single-precision boxes may find a few more
    /// pairs than overlap, so each is tested again against the exact boxes. The first level
    /// without a buffer of its own for its boxes takes `spare`'s.
    fn grid<O: Objects<V> + ?Sized>(
        &mut self,
        objs: &O,
        topo: &Topology<V>,
        out: &mut Vec<(u32, u32)>,
        spare: &mut Vec<CellBox<V>>,
    ) {
        let mut found = std::mem::take(&mut self.found);
        found.clear();
        self.grid_padded(objs, topo, &mut found, 0.0, spare);
        self.tests += found.len() as u64;
        // Every pair written, the end moved on only for those that overlap (no branch on a
        // coin toss, as in the re-test).
        let mut end = out.len();
        out.resize(end + found.len(), (0, 0));
        for &(i, j) in &found {
            let (Some(a), Some(b)) = (objs.object(i as usize), objs.object(j as usize)) else {
                continue;
            };
            out[end] = (a.slot, b.slot);
            end += usize::from(overlap_flag(topo, &a, &b));
        }
        out.truncate(end);
        self.found = found;
    }

    /// [`Self::grid`] in place of the Verlet list, which is let go (its bounds' buffer handed to
    /// the grid's boxes).
    fn plain_grid<O: Objects<V> + ?Sized>(
        &mut self,
        objs: &O,
        topo: &Topology<V>,
        out: &mut Vec<(u32, u32)>,
    ) {
        self.list.valid = false;
        self.list.pairs.clear();
        let mut spare = std::mem::take(&mut self.list.bounds);
        self.grid(objs, topo, out, &mut spare);
    }

    /// The pairs of the grid's cells' boxes (`objs` widened by `pad`, in single precision rounded
    /// outwards: every pair whose widened boxes overlap, and perhaps a few whose boxes only
    /// touch through the rounding), named by their indices in `objs`. The first level built
    /// without a buffer of its own for its boxes takes `spare`'s (a Verlet list's old bounds).
    fn grid_padded<O: Objects<V> + ?Sized>(
        &mut self,
        objs: &O,
        topo: &Topology<V>,
        out: &mut Vec<(u32, u32)>,
        pad: f64,
        spare: &mut Vec<CellBox<V>>,
    ) {
        let n = objs.slots();
        assert!(
            n < WALL as usize,
            "the broad phase names objects by 31-bit indices"
        );
        // Widths, finest width, and each object's level.
        let width = |o: &BroadObject<V>| {
            let mut w: f64 = 0.0;
            for axis in 0..V::DIM {
                w = w.max(2.0 * (o.half.get(axis) + pad));
            }
            w
        };
        // Each object's level is measured from the finest width `s0`, which takes a pass over
        // the objects of its own (at 1e6 the world's are 2D critters 64 bytes apart). The levels
        // are first found from the last build's `s0`, in the same pass that finds the new one:
        // where the two are equal (a scene whose smallest objects stay the same size), that is
        // the only pass. On rayon's threads for a large scene, in fixed chunks: a minimum and
        // an indexed map give the same result for any thread count.
        let parallel = n >= crate::world::PARALLEL_MIN;
        let level_from = |s0: f64, w: f64| {
            let mut level = 0usize;
            if w > s0 {
                // The smallest level whose width holds `w`, from a first guess read off the
                // ratio's exponent (no call to `log2`).
                level = ((w / s0).to_bits() >> 52).saturating_sub(1023) as usize;
                while level > 0 && w <= s0 * pow2(level - 1) {
                    level -= 1;
                }
                while w > s0 * pow2(level) {
                    level += 1;
                }
                level = level.min(63);
            }
            level as u8
        };
        // The levels of the objects from index `start` on, from `s0`, and each one's cell key
        // in its level's grid as the last build left it; returns their finest width. Where a
        // level's grid comes out the same (most builds of a steady scene), its counting sort
        // takes the keys from here instead of a pass over its objects of its own.
        let last = &self.levels;
        let levels = |s0: f64, start: usize, out: &mut [u8], keys: &mut [u32]| {
            let mut finest = f64::INFINITY;
            for (k, (at, key)) in out.iter_mut().zip(keys.iter_mut()).enumerate() {
                objs.prefetch(start + k + MEMBERS_AHEAD);
                *at = match objs.object(start + k) {
                    Some(o) => {
                        let w = width(&o);
                        finest = finest.min(w);
                        let l = level_from(s0, w);
                        if let Some(grid) = last.get(usize::from(l)) {
                            *key = grid.key(grid.coords(topo, o.center)) as u32;
                        }
                        l
                    }
                    None => NO_LEVEL,
                };
            }
            finest
        };
        let mut keys = Vec::new();
        let mut all_levels = |s0: f64| {
            self.level_of.clear();
            self.level_of.resize(n, NO_LEVEL);
            keys.clear();
            keys.resize(n, 0u32);
            if parallel {
                use rayon::prelude::*;
                self.level_of
                    .par_chunks_mut(LEVEL_CHUNK)
                    .zip(keys.par_chunks_mut(LEVEL_CHUNK))
                    .enumerate()
                    .map(|(k, (out, keys))| levels(s0, k * LEVEL_CHUNK, out, keys))
                    .reduce(|| f64::INFINITY, f64::min)
            } else {
                levels(s0, 0, &mut self.level_of, &mut keys)
            }
            .max(f64::MIN_POSITIVE)
        };
        let guess = self.finest;
        let s0 = all_levels(guess);
        if s0 != guess {
            all_levels(s0);
        }
        self.finest = s0;
        let (mut top, mut count, mut occupied) = (0usize, 0usize, [false; 64]);
        for &l in self.level_of.iter().filter(|&&l| l != NO_LEVEL) {
            top = top.max(usize::from(l));
            count += 1;
            occupied[usize::from(l)] = true;
        }
        // Levels whose cells the limit below would widen to the same size share one grid: as
        // separate levels their objects would be tested against each other cell by cell, level
        // by level (with radii spread over a factor of 100, three levels of 1,000 to 2,000 disks
        // had cells of one size).
        let limit = (4 * count).max(64) as f64;
        let volume: f64 = (0..V::DIM).map(|axis| topo.size().get(axis)).product();
        let widest = (volume / limit).powf(1.0 / V::DIM as f64);
        if widest > s0 {
            let shared = ((widest / s0).log2().floor() as usize).min(63);
            if let Some(into) = (0..=shared.min(top)).rev().find(|&l| occupied[l]) {
                if (0..into).any(|l| occupied[l]) {
                    for l in self.level_of.iter_mut().filter(|l| **l < into as u8) {
                        *l = into as u8;
                    }
                    occupied[..into].fill(false);
                    // Keys found in the merged levels' grids are not the shared grid's.
                    keys = Vec::new();
                }
            }
        }
        if self.levels.len() < top + 1 {
            self.levels.resize_with(top + 1, Level::default);
        }

        // Build each non-empty level's grid, finest first, cells never narrower than the level
        // below. At most ~4 cells per object in the whole scene (not per level: a sparse fine
        // level must not force coarse cells on the crowded levels above it).
        let mut floor_cell = 0.0f64;
        let mut used = std::mem::take(&mut self.used);
        used.clear();
        for l in (0..=top).filter(|&l| occupied[l]) {
            used.push(l);
            let cell = (s0 * pow2(l)).max(floor_cell);
            // A level's members are found by a pass over one byte per object rather than kept
            // in a list of their own (4 bytes per object less at the peak).
            let level_of = &self.level_of;
            let members = || {
                level_of
                    .iter()
                    .enumerate()
                    .filter(move |&(_, &at)| usize::from(at) == l)
                    .filter_map(|(i, _)| {
                        objs.prefetch(i + MEMBERS_AHEAD);
                        Some((i as u32, objs.object(i)?))
                    })
            };
            let indices = || {
                level_of
                    .iter()
                    .enumerate()
                    .filter(move |&(_, &at)| usize::from(at) == l)
                    .map(|(i, _)| i)
            };
            if self.levels[l].sorted.capacity() == 0 {
                std::mem::swap(&mut self.levels[l].sorted, spare);
            }
            let object = |i: usize| {
                objs.prefetch(i + MEMBERS_AHEAD);
                objs.object(i)
            };
            let known = (keys.len() == n).then(|| Known {
                indices,
                keys: &keys[..],
                object,
            });
            floor_cell = self.levels[l].build(members, known, topo, cell, limit, pad);
        }
        self.levels_used = used.len();

        // Pairs within each level: own cell, then the forward half of the neighbours, walking
        // the occupied cells in order. On a large level with more than one thread, runs of
        // whole cells are walked in parallel and their pairs joined in order: the same list as
        // the one walk, for any thread count.
        for &l in &used {
            let level = &self.levels[l];
            let forward = level.forward_offsets();
            let deltas: Vec<isize> = forward.iter().map(|&o| level.key_delta(o)).collect();
            let walk = |run: std::ops::Range<usize>, out: &mut Vec<(u32, u32)>| {
                level.pairs_within(topo, &forward, &deltas, run, out)
            };
            let m = level.sorted.len();
            if m >= crate::world::PARALLEL_MIN && rayon::current_num_threads() > 1 {
                use rayon::prelude::*;
                let runs = level.cell_runs(RUN_OBJECTS);
                // A few runs at a time, so that the parts waiting to be joined are a slice of
                // the list, not a second copy of it (at a million disks, 8 bytes per disk).
                for batch in runs.chunks(RUNS_AT_ONCE) {
                    let parts: Vec<(Vec<(u32, u32)>, u64)> = batch
                        .par_iter()
                        .map(|run| {
                            let mut part = Vec::new();
                            let tests = walk(run.clone(), &mut part);
                            (part, tests)
                        })
                        .collect();
                    for (part, tests) in parts {
                        out.extend(part);
                        self.tests += tests;
                    }
                }
            } else {
                self.tests += walk(0..m, out);
            }
        }

        // Pairs across levels, fine against coarse. Either each fine object looks at the 3^D coarse
        // cells around it, or each coarse object walks the fine cells its box covers (long walls
        // over a gas): whichever visits fewer cells, as counted here before doing either.
        for (u, &fine) in used.iter().enumerate() {
            for &coarse in &used[u + 1..] {
                let (lo, hi) = self.levels.split_at(coarse);
                let (fine_level, coarse_level) = (&lo[fine], &hi[0]);
                let by_fine = fine_level.sorted.len() as f64 * 3f64.powi(V::DIM as i32);
                // Counted only until it reaches `by_fine`.
                let mut by_coarse = 0.0;
                for b in &coarse_level.sorted {
                    by_coarse += fine_level.footprint_cells(topo, b);
                    if by_coarse >= by_fine {
                        break;
                    }
                }
                if by_coarse < by_fine {
                    for b in &coarse_level.sorted {
                        fine_level.for_each_run_near(topo, b, |run| {
                            let run = &fine_level.sorted[run];
                            self.tests += run.len() as u64;
                            push_overlapping(topo, b, run, out, |a, b| (b, a));
                        });
                    }
                } else {
                    for a in &fine_level.sorted {
                        coarse_level.for_each_run_near(topo, a, |run| {
                            let run = &coarse_level.sorted[run];
                            self.tests += run.len() as u64;
                            push_overlapping(topo, a, run, out, |a, b| (a, b));
                        });
                    }
                }
            }
        }
        self.used = used;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::border::Border;
    use crate::rng::Rng;
    use glam::{DVec2, DVec3};

    fn brute<V: Vector>(objs: &[BroadObject<V>], topo: &Topology<V>) -> Vec<(u32, u32)> {
        let mut bp = BroadPhase::new(BroadPhaseMode::AllPairs);
        let mut out = Vec::new();
        bp.find_pairs(objs, topo, &mut out);
        normalise(out)
    }

    fn normalise(mut pairs: Vec<(u32, u32)>) -> Vec<(u32, u32)> {
        for p in &mut pairs {
            if p.0 > p.1 {
                *p = (p.1, p.0);
            }
        }
        pairs.sort_unstable();
        pairs
    }

    fn grid<V: Vector>(objs: &[BroadObject<V>], topo: &Topology<V>) -> Vec<(u32, u32)> {
        let mut bp = BroadPhase::new(BroadPhaseMode::Grid);
        let mut out = Vec::new();
        bp.find_pairs(objs, topo, &mut out);
        let n = out.len();
        let pairs = normalise(out);
        let mut dedup = pairs.clone();
        dedup.dedup();
        assert_eq!(dedup.len(), n, "a pair was produced twice");
        pairs
    }

    #[test]
    fn at_most_never_rounds_up_and_loses_at_most_two_f32_steps() {
        let mut rng = Rng::new(7);
        let mut values = vec![
            0.0,
            -0.0,
            1e-45,
            -1e-45,
            1e-39,
            f64::from(f32::MAX),
            1e300,
            -1e300,
        ];
        for _ in 0..100_000 {
            let magnitude = 10f64.powf(rng.uniform(-40.0, 40.0));
            values.push(if rng.uniform(0.0, 1.0) < 0.5 {
                magnitude
            } else {
                -magnitude
            });
        }
        for x in values {
            let y = at_most(x);
            assert!(f64::from(y) <= x, "{x} rounded up to {y}");
            if x.abs() <= f64::from(f32::MAX) {
                let near = x as f32;
                assert!(
                    y >= near.next_down().next_down(),
                    "{x}: {y} is too far below"
                );
            }
        }
        assert!(at_most(f64::NAN).is_nan());
        assert_eq!(at_most(f64::INFINITY), f32::INFINITY);
    }

    #[test]
    fn a_cell_box_holds_its_widened_box_and_finds_every_pair_the_exact_boxes_find() {
        let mut rng = Rng::new(11);
        let topo = Topology {
            min: DVec3::splat(-3e4),
            max: DVec3::splat(3e4),
            border: Border::Wrap,
        };
        let mut found = 0;
        for i in 0..100_000u32 {
            let scale = 10f64.powf(rng.uniform(-3.0, 1.0));
            let pad = scale * rng.uniform(0.0, 0.3);
            let object = |rng: &mut Rng, center: DVec3| BroadObject {
                center,
                half: DVec3::new(
                    scale * rng.uniform(0.1, 1.0),
                    scale * rng.uniform(0.1, 1.0),
                    scale * rng.uniform(0.1, 1.0),
                ),
                slot: 0,
                is_wall: false,
            };
            let at = DVec3::new(
                rng.uniform(-3e4, 3e4),
                rng.uniform(-3e4, 3e4),
                rng.uniform(-3e4, 3e4),
            );
            let a = object(&mut rng, at);
            let cell = CellBox::<DVec3>::new(&a, i, pad);
            for axis in 0..3 {
                let (c, h) = (cell.center.as_ref()[axis], cell.half.as_ref()[axis]);
                let reach = (f64::from(c) - a.center.get(axis)).abs() + a.half.get(axis) + pad;
                assert!(reach <= f64::from(h), "axis {axis}: {a:?} widened by {pad}");
            }
            assert_eq!(cell.index(), i);
            // A second box placed so the widened boxes just overlap or just miss, across the
            // periodic seam for some: the cells' boxes overlap whenever the widened ones do.
            let mut b = object(&mut rng, DVec3::ZERO);
            let reach = a.half + b.half + DVec3::splat(2.0 * pad);
            let offset = reach
                * DVec3::new(
                    rng.uniform(-1.0, 1.0),
                    rng.uniform(-1.0, 1.0),
                    rng.uniform(-1.0, 1.0),
                )
                .signum()
                * (1.0 - 1e-12 * rng.uniform(-1.0, 1.0));
            b.center = topo.wrap_position(a.center + offset);
            let widen = |o: &BroadObject<DVec3>| BroadObject {
                half: o.half + DVec3::splat(pad),
                ..*o
            };
            if overlaps(&topo, &widen(&a), &widen(&b)) {
                found += 1;
                assert!(
                    cells_overlap(&topo, &cell, &CellBox::new(&b, 0, pad)),
                    "{a:?} and {b:?} widened by {pad}"
                );
            }
        }
        assert!(found > 10_000, "only {found} pairs just overlapped");
    }

    #[test]
    fn a_bound_holds_a_box_inside_its_widened_box_and_nothing_beyond() {
        let topo = Topology {
            min: DVec2::ZERO,
            max: DVec2::splat(4000.0),
            border: Border::Bounce,
        };
        let mut rng = Rng::new(11);
        for _ in 0..20_000 {
            // Centres whose f32 rounding is coarse (ulp 2.4e-4 near 3000).
            let center = DVec2::new(rng.uniform(0.0, 4000.0), rng.uniform(0.0, 4000.0));
            let half = DVec2::splat(rng.uniform(0.1, 2.0));
            let pad = 0.2;
            let at = |c: DVec2, h: DVec2| BroadObject {
                center: c,
                half: h,
                slot: 3,
                is_wall: false,
            };
            let bound = Bound::bound(Some(&at(center, half)), pad);
            assert!(
                bound.holds(&topo, Some(&at(center, half))),
                "the box it was made from"
            );
            // Moved along one axis: held well inside, never once beyond the widened box.
            let axis = DVec2::new(1.0, 0.0);
            assert!(bound.holds(&topo, Some(&at(center + axis * (pad - 1e-3), half))));
            assert!(
                bound.holds(&topo, Some(&at(center, half * 0.5))),
                "shrunk in place"
            );
            assert!(!bound.holds(
                &topo,
                Some(&at(center - axis * (pad * (1.0 + 1e-12)), half))
            ));
            assert!(!bound.holds(&topo, Some(&at(center, half + DVec2::splat(pad * 1.001)))));
            let other = BroadObject {
                slot: 4,
                ..at(center, half)
            };
            assert!(
                !bound.holds(&topo, Some(&other)),
                "another object in the slot's place"
            );
            let wall = BroadObject {
                is_wall: true,
                ..at(center, half)
            };
            assert!(!bound.holds(&topo, Some(&wall)), "a wall in a disk's place");
            assert!(!bound.holds(&topo, None), "a gap in an object's place");
            let gap = Bound::bound(None, pad);
            assert!(gap.holds(&topo, None), "a gap in a gap's place");
            assert!(
                !gap.holds(&topo, Some(&at(center, half))),
                "an object in a gap's place"
            );
        }
    }

    #[test]
    fn the_typical_width_is_the_median_disk_width_of_an_even_sample() {
        let disk = |r: f64, wall: bool| BroadObject {
            center: DVec2::ZERO,
            half: DVec2::splat(r),
            slot: 0,
            is_wall: wall,
        };
        let width = |o: &BroadObject<DVec2>| 2.0 * o.half.x;
        assert_eq!(typical_width::<DVec2, [_]>(&[], width), f64::INFINITY);
        // Walls do not count, however many and however wide.
        let objs: Vec<_> = [disk(100.0, true), disk(100.0, true), disk(100.0, true)]
            .into_iter()
            .chain([1.0, 3.0, 2.0].map(|r| disk(r, false)))
            .collect();
        assert_eq!(typical_width(objs.as_slice(), width), 4.0);
        // Only walls: the smallest of them.
        assert_eq!(
            typical_width(&[disk(7.0, true), disk(5.0, true)][..], width),
            10.0
        );
        // Radii 1..=100_000 in order: an even sample of about 1,000 has its median near the
        // middle, far from the smallest width (2).
        let many: Vec<_> = (1..=100_000).map(|r| disk(r as f64, false)).collect();
        let t = typical_width(many.as_slice(), width);
        assert!((95_000.0..=105_000.0).contains(&t), "{t}");
    }

    fn random_objs<V: Vector>(
        rng: &mut Rng,
        n: usize,
        size: f64,
        rmin: f64,
        rmax: f64,
    ) -> Vec<BroadObject<V>> {
        (0..n)
            .map(|i| {
                let mut c = V::zero();
                for axis in 0..V::DIM {
                    c.set(axis, rng.uniform(-0.5, size + 0.5));
                }
                // log-uniform radii
                let r = rmin * (rmax / rmin).powf(rng.uniform(0.0, 1.0));
                BroadObject {
                    center: c,
                    half: V::splat(r),
                    slot: i as u32,
                    is_wall: false,
                }
            })
            .collect()
    }

    #[test]
    fn grid_matches_all_pairs_with_varied_radii_in_2d_and_3d() {
        let mut rng = Rng::new(7);
        for border in [Border::Bounce, Border::Wrap] {
            let topo2 = Topology {
                min: DVec2::ZERO,
                max: DVec2::splat(40.0),
                border,
            };
            let objs2 = random_objs::<DVec2>(&mut rng, 600, 40.0, 0.2, 6.0);
            assert_eq!(grid(&objs2, &topo2), brute(&objs2, &topo2));
            let topo3 = Topology {
                min: DVec3::ZERO,
                max: DVec3::splat(15.0),
                border,
            };
            let objs3 = random_objs::<DVec3>(&mut rng, 500, 15.0, 0.1, 3.0);
            assert_eq!(grid(&objs3, &topo3), brute(&objs3, &topo3));
        }
    }

    /// A build finds the levels from the last build's finest width and again when the new one
    /// differs, and takes the cell keys found with the last grid only where the grid is the
    /// same: one grid reused while every object shrinks and grows finds what all pairs find.
    #[test]
    fn levels_found_from_the_last_finest_width_are_found_again_when_it_changes() {
        let mut rng = Rng::new(11);
        let topo = Topology {
            min: DVec2::ZERO,
            max: DVec2::splat(40.0),
            border: Border::Bounce,
        };
        // No disk narrower than the widest cells the limit allows, so no levels share a grid
        // (whose keys are never taken) but at a quarter of the size.
        let objs = random_objs::<DVec2>(&mut rng, 600, 40.0, 0.45, 6.0);
        let mut bp = BroadPhase::new(BroadPhaseMode::Grid);
        // The last: cells a hundredth wider, but as many of them (a walled box).
        for scale in [1.0, 1.0, 0.25, 0.25, 3.0, 1.0, 1.01] {
            let scaled: Vec<BroadObject<DVec2>> = objs
                .iter()
                .map(|o| BroadObject {
                    half: o.half * scale,
                    ..*o
                })
                .collect();
            let mut out = Vec::new();
            bp.find_pairs(&scaled, &topo, &mut out);
            assert_eq!(normalise(out), brute(&scaled, &topo), "scale {scale}");
            // Every member sits in its cell of the grid just built.
            for &l in &bp.used {
                let level = &bp.levels[l];
                for (b, &key) in level.sorted.iter().zip(&level.sorted_keys) {
                    let o = &scaled[b.index() as usize];
                    let cell = level.key(level.coords(&topo, o.center));
                    assert_eq!(key as usize, cell, "scale {scale}, level {l}");
                }
            }
        }
    }

    #[test]
    fn a_large_level_sorted_in_parts_is_the_sequential_sort() {
        let mut rng = Rng::new(5);
        let topo = Topology {
            min: DVec2::ZERO,
            max: DVec2::splat(300.0),
            border: Border::Bounce,
        };
        // Three levels, none merged (the widest cells the limit allows are narrower than the
        // finest), so the second build takes every key from the first.
        let objs = random_objs::<DVec2>(
            &mut rng,
            crate::world::PARALLEL_MIN + 7_000,
            300.0,
            0.5,
            2.0,
        );
        // Moved by about a cell, some across a cell's edge.
        let moved: Vec<BroadObject<DVec2>> = objs
            .iter()
            .map(|o| BroadObject {
                center: o.center + DVec2::new(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)),
                ..*o
            })
            .collect();
        type Sort = (Vec<u32>, Vec<u32>, Vec<u32>);
        let sorts = |threads: usize| -> (Vec<Sort>, Vec<(u32, u32)>) {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut bp = BroadPhase::new(BroadPhaseMode::Grid);
                let mut out = Vec::new();
                bp.find_pairs(&objs, &topo, &mut out);
                out.clear();
                bp.find_pairs(&moved, &topo, &mut out);
                let levels = bp
                    .used
                    .iter()
                    .map(|&l| {
                        let level = &bp.levels[l];
                        let tags = level.sorted.iter().map(|b| b.tag).collect();
                        (level.start.clone(), level.sorted_keys.clone(), tags)
                    })
                    .collect();
                (levels, out)
            })
        };
        let one = sorts(1);
        assert_eq!(one.0.len(), 3, "levels");
        assert_eq!(normalise(one.1.clone()), brute(&moved, &topo));
        assert_eq!(sorts(2), one, "two threads");
        assert_eq!(sorts(3), one, "three threads");
    }

    #[test]
    fn long_walls_over_a_crowd_match_all_pairs() {
        // Few large objects over many small ones: the coarse objects walk the fine cells.
        let mut rng = Rng::new(11);
        for border in [Border::Bounce, Border::Wrap] {
            let topo = Topology {
                min: DVec2::ZERO,
                max: DVec2::splat(60.0),
                border,
            };
            let mut objs = random_objs::<DVec2>(&mut rng, 2000, 60.0, 0.3, 0.5);
            for (k, (c, h)) in [
                (DVec2::new(30.0, -0.1), DVec2::new(30.2, 0.1)),
                (DVec2::new(30.0, 60.1), DVec2::new(30.2, 0.1)),
                (DVec2::new(-0.1, 30.0), DVec2::new(0.1, 30.2)),
                (DVec2::new(17.0, 23.0), DVec2::new(9.0, 0.3)),
            ]
            .into_iter()
            .enumerate()
            {
                objs.push(BroadObject {
                    center: c,
                    half: h,
                    slot: 5000 + k as u32,
                    is_wall: true,
                });
            }
            let mut bp = BroadPhase::new(BroadPhaseMode::Grid);
            let mut out = Vec::new();
            bp.find_pairs(&objs, &topo, &mut out);
            assert!(
                bp.tests < 40_000,
                "walls should not test every disk: {} tests",
                bp.tests
            );
            assert_eq!(grid(&objs, &topo), brute(&objs, &topo));
        }
    }

    #[test]
    fn verlet_list_finds_what_a_fresh_grid_finds_as_things_move_come_and_go() {
        let mut rng = Rng::new(3);
        for border in [Border::Bounce, Border::Wrap] {
            let topo = Topology {
                min: DVec2::ZERO,
                max: DVec2::splat(60.0),
                border,
            };
            let mut objs = random_objs::<DVec2>(&mut rng, 1200, 50.0, 0.4, 0.6);
            objs.push(BroadObject {
                center: DVec2::new(30.0, 0.0),
                half: DVec2::new(30.0, 0.3),
                slot: 9999,
                is_wall: true,
            });
            let mut auto = BroadPhase::new(BroadPhaseMode::Auto);
            for step in 0..40 {
                let mut listed = Vec::new();
                auto.find_pairs(&objs, &topo, &mut listed);
                let n = listed.len();
                let listed = normalise(listed);
                let mut dedup = listed.clone();
                dedup.dedup();
                assert_eq!(dedup.len(), n, "step {step}: a pair listed twice");
                assert_eq!(listed, brute(&objs, &topo), "step {step}");
                // Drift, with now and then a jump, a death and a birth.
                for o in objs.iter_mut().filter(|o| !o.is_wall) {
                    o.center += DVec2::new(rng.uniform(-0.04, 0.04), rng.uniform(-0.04, 0.04));
                }
                if step % 17 == 5 {
                    objs[7].center = DVec2::new(rng.uniform(0.0, 60.0), rng.uniform(0.0, 60.0));
                }
                if step % 23 == 11 {
                    let gone = objs.remove(3);
                    objs.push(BroadObject {
                        slot: 20_000 + step,
                        ..gone
                    });
                }
            }
            assert!(
                auto.rebuilds() < 40,
                "the list should last several steps: {} rebuilds",
                auto.rebuilds()
            );
        }
    }

    /// Objects that know their steps.
    struct Striding<'a> {
        objs: &'a [BroadObject<DVec2>],
        steps: &'a [DVec2],
    }

    impl Objects<DVec2> for Striding<'_> {
        fn slots(&self) -> usize {
            self.objs.len()
        }
        fn object(&self, i: usize) -> Option<BroadObject<DVec2>> {
            self.objs.get(i).copied()
        }
        fn step(&self, i: usize) -> DVec2 {
            self.steps[i]
        }
    }

    /// 1,000 disks of radius 0.5 at random in a wrapped box 56 wide, each to move `speed(i)` a
    /// step in a random direction: the box, the disks, each one's step and its length.
    #[allow(clippy::type_complexity)]
    fn drifting(
        seed: u64,
        speed: impl Fn(usize) -> f64,
    ) -> (Topology<DVec2>, Vec<BroadObject<DVec2>>, Vec<DVec2>) {
        let topo = Topology {
            min: DVec2::ZERO,
            max: DVec2::splat(56.0),
            border: Border::Wrap,
        };
        let mut rng = Rng::new(seed);
        let objs = random_objs::<DVec2>(&mut rng, 1000, 55.0, 0.5, 0.5);
        let steps: Vec<DVec2> = (0..objs.len())
            .map(|i| {
                let a = rng.uniform(0.0, std::f64::consts::TAU);
                DVec2::new(a.cos(), a.sin()) * speed(i)
            })
            .collect();
        (topo, objs, steps)
    }

    /// `turns` steps of the [`drifting`] disks: each step every phase finds the pairs, told the
    /// given steps (or none) and whether it is in a crowd, and they must be brute force's.
    fn drift(
        topo: &Topology<DVec2>,
        mut objs: Vec<BroadObject<DVec2>>,
        steps: &[DVec2],
        turns: usize,
        phases: &mut [(&mut BroadPhase<DVec2>, &[DVec2], bool)],
    ) {
        for step in 0..turns {
            let expected = brute(&objs, topo);
            for (phase, told, crowded) in phases.iter_mut() {
                phase.set_crowded(*crowded);
                let mut pairs = Vec::new();
                let objects = Striding {
                    objs: &objs,
                    steps: told,
                };
                phase.find_pairs_in(&objects, topo, &mut pairs, None);
                assert_eq!(normalise(pairs), expected, "step {step}, crowded {crowded}");
            }
            for (o, d) in objs.iter_mut().zip(steps) {
                o.center = topo.wrap_position(o.center + *d);
            }
        }
    }

    /// A few fast objects among slow ones: with their strides known, their leads keep the list
    /// (neither rebuilt nor mended) for several steps instead of one, and it still finds every
    /// pair.
    #[test]
    fn fast_objects_led_by_their_strides_keep_the_list_and_miss_no_pair() {
        // One in 50 moves 0.33 a step (outrunning the half skin, 0.3, in one step), the rest
        // 0.01 a step, in random directions.
        let (topo, objs, steps) = drifting(9, |i| if i % 50 == 0 { 0.33 } else { 0.01 });
        let (mut led, mut unled) = (
            BroadPhase::new(BroadPhaseMode::Auto),
            BroadPhase::new(BroadPhaseMode::Auto),
        );
        let turns = 64;
        let none = [DVec2::ZERO; 1000];
        drift(
            &topo,
            objs,
            &steps,
            turns,
            &mut [(&mut led, &steps, false), (&mut unled, &none, false)],
        );
        let changes = |b: &BroadPhase<DVec2>| b.rebuilds() + b.repairs();
        assert!(
            changes(&unled) >= turns as u64 - 1,
            "test setup: without strides the fast objects force a rebuild or a repair every \
             step ({})",
            changes(&unled)
        );
        // A fast object mended between builds leaves again out of step with the others, so the
        // fast ones leave in a few groups: about twice as many changes as one every LEAD_STEPS.
        let most = 2 * (turns as u64 / LEAD_STEPS as u64 + 1);
        assert!(
            changes(&led) <= most,
            "{} rebuilds and {} repairs in {turns} steps, at most {most} expected",
            led.rebuilds(),
            led.repairs()
        );
    }

    /// A gas where everyone moves fast for the skin (six in ten 0.06 a step, the rest 0.1, so
    /// nobody is more than twice the median): outside a crowd every object whose
    /// `LEAD_STEPS` strides pass half the skin is led and the list lasts about `LEAD_STEPS`
    /// steps; in a crowd (a pile, where strides do not show the moves) only objects over
    /// `FAST` times the median are, none here, and it is rebuilt every few steps. Both find
    /// every pair.
    #[test]
    fn outside_a_crowd_every_object_that_would_outrun_the_skin_is_led() {
        let (topo, objs, steps) = drifting(11, |i| if i % 10 < 6 { 0.06 } else { 0.1 });
        let (mut gas, mut crowd) = (
            BroadPhase::new(BroadPhaseMode::Auto),
            BroadPhase::new(BroadPhaseMode::Auto),
        );
        let turns = 64;
        drift(
            &topo,
            objs,
            &steps,
            turns,
            &mut [(&mut gas, &steps, false), (&mut crowd, &steps, true)],
        );
        let changes = |b: &BroadPhase<DVec2>| b.rebuilds() + b.repairs();
        let most = 2 * (turns as u64 / LEAD_STEPS as u64 + 1);
        assert!(
            changes(&gas) <= most,
            "not crowded: {} rebuilds and {} repairs in {turns} steps, at most {most} expected",
            gas.rebuilds(),
            gas.repairs()
        );
        // Unled, a 0.1 stride passes the half skin (0.3) in the fourth step, and four in ten
        // leaving is too many to mend: a build every 4 steps, twice as many as led.
        assert!(
            crowd.rebuilds() >= turns as u64 / 4 && crowd.rebuilds() >= 2 * gas.rebuilds(),
            "crowded: {} rebuilds in {turns} steps (not crowded: {})",
            crowd.rebuilds(),
            gas.rebuilds()
        );
    }

    /// Objects that outrun the skin every step, their steps untold (as a pile jostled by the
    /// discrete step's separations does): after `SHORT_LIVED` lists of one step each the plain
    /// grid takes over for `GRID_SPELL` steps, then a list is tried again; every step still
    /// finds brute force's pairs. A gas that keeps its list never leaves it.
    #[test]
    fn lists_that_live_one_step_give_way_to_the_plain_grid_for_a_while() {
        let (topo, objs, steps) = drifting(13, |_| 0.4);
        let (slow_topo, slow_objs, slow_steps) = drifting(13, |_| 0.003);
        let none = [DVec2::ZERO; 1000];
        let (mut jostled, mut gas) = (
            BroadPhase::new(BroadPhaseMode::Auto),
            BroadPhase::new(BroadPhaseMode::Auto),
        );
        let turns = 2 * (SHORT_LIVED + GRID_SPELL) as usize;
        drift(
            &topo,
            objs,
            &steps,
            turns,
            &mut [(&mut jostled, &none, false)],
        );
        drift(
            &slow_topo,
            slow_objs,
            &slow_steps,
            turns,
            &mut [(&mut gas, &none, false)],
        );
        // Lists built at steps 0-2, the grid for steps 3-34, lists again at 35-37 (the one at
        // 35 starts a new run of short lives), the grid from 38 on.
        let short = u64::from(SHORT_LIVED);
        assert_eq!(jostled.rebuilds(), 2 * short, "builds");
        assert_eq!(
            jostled.grid_steps(),
            turns as u64 - 2 * short,
            "steps on the grid"
        );
        assert_eq!(gas.grid_steps(), 0);
        assert_eq!(gas.rebuilds(), 1);
    }

    /// Objects with gaps: `None` is a slot with no object.
    struct Gappy<V: Vector>(Vec<Option<BroadObject<V>>>);

    impl<V: Vector> Objects<V> for Gappy<V> {
        fn slots(&self) -> usize {
            self.0.len()
        }
        fn object(&self, i: usize) -> Option<BroadObject<V>> {
            self.0[i]
        }
    }

    /// Radii over a factor of 25, most objects drifting and a few jumping out of their bounds
    /// every step, one now and then teleported, removed (leaving a gap) or born in a gap, and a
    /// wall moved: the list is mended rather than rebuilt, and its pairs are every step exactly
    /// the overlapping ones, each once. In 2D and 3D, walled and periodic.
    fn mended_list_misses_no_pair<V: Vector>(size: f64, n: usize, radii: (f64, f64)) {
        let mut rng = Rng::new(5);
        for border in [Border::Bounce, Border::Wrap] {
            let topo = Topology {
                min: V::zero(),
                max: V::splat(size),
                border,
            };
            let mut objs = random_objs::<V>(&mut rng, n, size, radii.0, radii.1);
            let mut wall = V::splat(0.3);
            wall.set(0, 0.4 * size);
            objs.push(BroadObject {
                center: V::splat(0.5 * size),
                half: wall,
                slot: n as u32,
                is_wall: true,
            });
            let mut objs = Gappy(objs.into_iter().map(Some).collect());
            let mut phase = BroadPhase::new(BroadPhaseMode::Auto);
            let random_point = |rng: &mut Rng| {
                let mut p = V::zero();
                for axis in 0..V::DIM {
                    p.set(axis, rng.uniform(0.0, size));
                }
                p
            };
            let steps = 60;
            let mut kept_in_order = 0;
            for step in 0..steps {
                let mut listed = Vec::new();
                phase.find_pairs_in(&objs, &topo, &mut listed, None);
                if phase.list.sorted {
                    // A sorted list stays sorted through its repairs (by index: the world's
                    // indices are its slots, so its pairs then come out in the response's order).
                    let key = |&(a, b): &(u32, u32)| (a.min(b), a.max(b));
                    assert!(phase.list.pairs.is_sorted_by_key(key), "step {step}");
                    kept_in_order += 1;
                }
                // The second half of the steps asks for the list in order, as a pile's world does.
                if step >= steps / 2 {
                    phase.sort_list();
                }
                let count = listed.len();
                let listed = normalise(listed);
                let mut once = listed.clone();
                once.dedup();
                assert_eq!(once.len(), count, "step {step}: a pair listed twice");
                let live: Vec<_> = objs.0.iter().flatten().copied().collect();
                assert_eq!(listed, brute(&live, &topo), "step {step}");

                for o in objs.0.iter_mut().flatten().filter(|o| !o.is_wall) {
                    let mut d = V::zero();
                    for axis in 0..V::DIM {
                        d.set(axis, rng.uniform(-0.002, 0.002));
                    }
                    o.center = topo.wrap_position(o.center + d);
                }
                for _ in 0..3 {
                    let i = (rng.next_u64() % n as u64) as usize;
                    if let Some(o) = objs.0[i].as_mut() {
                        let mut d = V::zero();
                        for axis in 0..V::DIM {
                            d.set(axis, rng.uniform(-1.5, 1.5));
                        }
                        o.center = topo.wrap_position(o.center + d);
                    }
                }
                match step % 6 {
                    1 => {
                        let i = (rng.next_u64() % n as u64) as usize;
                        if let Some(o) = objs.0[i].as_mut() {
                            o.center = random_point(&mut rng);
                        }
                    }
                    2 => objs.0[(rng.next_u64() % n as u64) as usize] = None,
                    3 => {
                        if let Some(gap) = objs.0.iter().position(Option::is_none) {
                            objs.0[gap] = Some(BroadObject {
                                center: random_point(&mut rng),
                                half: V::splat(radii.1),
                                slot: 10_000 + step,
                                is_wall: false,
                            });
                        }
                    }
                    4 => {
                        if let Some(w) = objs.0[n].as_mut() {
                            w.center = random_point(&mut rng);
                        }
                    }
                    _ => {}
                }
            }
            assert!(
                kept_in_order >= 10,
                "{kept_in_order} steps from a sorted list"
            );
            assert!(
                phase.repairs() >= steps as u64 / 2 && phase.rebuilds() <= 10,
                "{border:?}: {} repairs and {} rebuilds in {steps} steps",
                phase.repairs(),
                phase.rebuilds()
            );
        }
    }

    #[test]
    fn a_sorted_tail_merged_gives_the_whole_list_sorted() {
        let mut rng = Rng::new(5);
        let key = |&(a, b): &(u32, u32)| (a.min(b), a.max(b));
        for (len, tail) in [
            (0, 0),
            (0, 5),
            (7, 0),
            (1, 1),
            (200, 3),
            (200, 150),
            (3, 40),
        ] {
            let mut pairs: Vec<(u32, u32)> = (0..len + tail)
                .map(|_| {
                    let a = (rng.next_u64() % 1000) as u32;
                    let b = a + 1 + (rng.next_u64() % 50) as u32;
                    if rng.next_f64() < 0.5 {
                        (b, a)
                    } else {
                        (a, b)
                    }
                })
                .collect();
            pairs[..len].sort_unstable_by_key(key);
            let mut expected = pairs.clone();
            expected.sort_by_key(key);
            merge_tail(&mut pairs, len);
            assert!(pairs.is_sorted_by_key(key), "{len} + {tail}");
            let (mut got, mut want) = (pairs.clone(), expected);
            got.sort_unstable();
            want.sort_unstable();
            assert_eq!(
                got, want,
                "{len} + {tail}: the same pairs, each the same way round"
            );
        }
    }

    #[test]
    fn a_mended_list_misses_no_pair_in_2d_and_3d() {
        mended_list_misses_no_pair::<DVec2>(60.0, 1500, (0.1, 2.5));
        mended_list_misses_no_pair::<DVec3>(16.0, 800, (0.1, 1.0));
    }

    #[test]
    fn a_large_level_walked_in_runs_in_parallel_gives_one_walk_s_pairs_in_order() {
        let mut rng = Rng::new(5);
        let topo = Topology {
            min: DVec2::ZERO,
            max: DVec2::splat(330.0),
            border: Border::Bounce,
        };
        // Equal radii: one level, of more objects than the parallel threshold, in more runs
        // than are walked at once.
        let objs = random_objs::<DVec2>(&mut rng, 140_000, 330.0, 0.4, 0.4);
        let found = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut bp = BroadPhase::new(BroadPhaseMode::Grid);
            let mut out = Vec::new();
            pool.install(|| bp.find_pairs(&objs, &topo, &mut out));
            (bp, out)
        };
        let (bp, out) = found(2);
        assert_eq!(bp.levels_used, 1);
        let level = &bp.levels[0];
        assert!(
            level.cell_runs(RUN_OBJECTS).len() > RUNS_AT_ONCE,
            "more runs than are walked at once"
        );
        let forward = level.forward_offsets();
        let deltas: Vec<isize> = forward.iter().map(|&o| level.key_delta(o)).collect();
        let mut whole = Vec::new();
        let tests = level.pairs_within(&topo, &forward, &deltas, 0..objs.len(), &mut whole);
        assert!(whole.len() > 1000, "{} pairs", whole.len());
        assert_eq!(bp.found, whole);
        assert_eq!(bp.tests, tests + whole.len() as u64);
        let exact_pairs: Vec<(u32, u32)> = whole
            .iter()
            .filter_map(|pair| exact(objs.as_slice(), &topo, pair))
            .collect();
        assert_eq!(out, exact_pairs);
        assert_eq!(found(1).1, out);
    }

    #[test]
    fn a_built_list_keeps_its_bounds_and_not_the_grid_s_boxes() {
        let mut rng = Rng::new(9);
        let topo = Topology {
            min: DVec2::ZERO,
            max: DVec2::splat(100.0),
            border: Border::Wrap,
        };
        // Two sizes of disk: two levels.
        let mut objs = random_objs::<DVec2>(&mut rng, 4_000, 100.0, 0.3, 0.3);
        objs.extend(random_objs::<DVec2>(&mut rng, 100, 100.0, 3.0, 3.0));
        for (i, o) in objs.iter_mut().enumerate() {
            o.slot = i as u32;
        }
        let mut bp = BroadPhase::new(BroadPhaseMode::Auto);
        let mut out = Vec::new();
        let mut buffers = Vec::new();
        for build in 1..=3u64 {
            bp.find_pairs(&objs, &topo, &mut out);
            assert_eq!(
                normalise(out.clone()),
                normalise(brute(&objs, &topo)),
                "build {build}"
            );
            assert_eq!(bp.rebuilds(), build);
            assert_eq!(bp.used.len(), 2);
            // Each level keeps its members' tags, and neither their boxes nor their keys.
            let mut members = 0;
            for &l in &bp.used {
                let level = &bp.levels[l];
                assert_eq!(level.sorted.capacity(), 0, "level {l}'s boxes");
                assert_eq!(level.sorted_keys.capacity(), 0, "level {l}'s keys");
                members += level.members.len();
            }
            assert_eq!(members, objs.len());
            // The bounds are written where the last build's bounds were (no new buffer).
            buffers.push(bp.list.bounds.as_ptr());
            // Every object moves by a third of the box: too many to mend, a build.
            for o in &mut objs {
                o.center.x = (o.center.x + 33.0).rem_euclid(100.0);
            }
        }
        assert_eq!(buffers[1], buffers[0]);
        assert_eq!(buffers[2], buffers[0]);
    }

    /// A led box, widened by half the skin as the list's are, holds the object all along
    /// `LEAD_STEPS` of its steps ahead, in any direction, but not as many behind.
    #[test]
    fn a_led_box_covers_its_steps_ahead_and_less_behind() {
        let mut rng = Rng::new(5);
        let topo = Topology {
            min: DVec2::ZERO,
            max: DVec2::splat(100.0),
            border: Border::Bounce,
        };
        let half_skin = 0.3;
        for _ in 0..100 {
            let a = rng.uniform(0.0, std::f64::consts::TAU);
            let step = DVec2::new(a.cos(), a.sin()) * rng.uniform(0.05, 1.0);
            // Behind, the lead is checked where it is well over the half skin.
            let far = step.length() > 0.3;
            let o = BroadObject {
                center: DVec2::splat(50.0),
                half: DVec2::splat(rng.uniform(0.05, 2.0)),
                slot: 0,
                is_wall: false,
            };
            let objs = [o];
            let told = [step];
            let led = Led {
                objs: &Striding {
                    objs: &objs,
                    steps: &told,
                },
                half_skin,
                fast: 0.0,
            };
            let bound = Bound::bound(led.object(0).as_ref(), half_skin);
            let moved = |k: f64| BroadObject {
                center: o.center + step * k,
                ..o
            };
            for k in 0..=LEAD_STEPS as usize {
                let k = k as f64 * 0.999;
                assert!(
                    bound.holds(&topo, Some(&moved(k))),
                    "{k} steps ahead of {step}"
                );
            }
            assert!(
                !far || !bound.holds(&topo, Some(&moved(-LEAD_STEPS))),
                "{step}: as far behind as ahead"
            );
        }
    }

    #[test]
    fn pow2_is_exp2() {
        for l in [0usize, 1, 2, 10, 63, 1023, 1024, 5000, usize::MAX] {
            assert_eq!(pow2(l), (l as f64).exp2(), "{l}");
        }
    }

    #[test]
    fn floor_to_i64_is_floor_clamped() {
        for x in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.999999,
            -2.000001,
            1e14 + 0.5,
            -1e14 - 0.5,
            3e15,
            -3e15,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            assert_eq!(floor_to_i64(x), x.floor().clamp(-1e15, 1e15) as i64, "{x}");
        }
        assert_eq!(floor_to_i64(f64::NAN), 0);
    }

    #[test]
    fn walls_never_pair_with_walls() {
        let topo = Topology {
            min: DVec2::ZERO,
            max: DVec2::splat(10.0),
            border: Border::Bounce,
        };
        let wall = |slot, x| BroadObject {
            center: DVec2::new(x, 5.0),
            half: DVec2::new(0.5, 5.0),
            slot,
            is_wall: true,
        };
        let objs = vec![wall(0, 1.0), wall(1, 1.5)];
        assert!(brute(&objs, &topo).is_empty());
        assert!(grid(&objs, &topo).is_empty());
    }
}
