//! One level of the grid: its cells, the counting sort of its members into them, and the walks
//! over its cells.

use super::cell_box::{cells_overlap_flag, CellBox};
use super::BroadObject;
use crate::border::Topology;
use crate::tolerance::ROUNDING_MARGIN;
use crate::vector::Vector;

/// At most this many parts of a large level's counting sort run at once (each reads every
/// member's key: [`Level::sort_in_parts`]).
const FILL_PARTS: usize = 8;

/// What a level's build may take instead of a pass over its members (see [`Level::build`]):
/// their indices again, every object's cell key in the level's last grid, and each object by
/// its index.
pub(super) struct KnownKeys<'a, I, F> {
    pub(super) indices: I,
    pub(super) keys: &'a [u32],
    pub(super) object: F,
}

/// One level of the grid: its cells and its members, copied in cell order.
pub(super) struct Level<V: Vector> {
    /// Cells per unit of length along each axis.
    inv_cell: [f64; 3],
    /// Cells along each axis (1 on an axis the world does not have).
    dims: [usize; 3],
    /// The axes on which the cells wrap round a periodic border.
    wrap: [bool; 3],
    /// `start[k]..start[k + 1]` indexes `boxes` (or `tags`) for cell `k`.
    pub(super) start: Vec<u32>,
    /// The members' boxes in cell order, so the pair loops read memory in order (empty once
    /// [`Level::keep_tags_only`]).
    pub(super) boxes: Vec<CellBox<V>>,
    /// Cell key of each entry of `boxes`.
    pub(super) keys: Vec<u32>,
    /// Once a Verlet list's build is done with them ([`Level::keep_tags_only`]): the tag of each
    /// entry of `boxes` (its index, with the wall bit for a wall), in the same order, while
    /// `boxes` and `keys` are let go.
    pub(super) tags: Vec<u32>,
}

impl<V: Vector> Default for Level<V> {
    fn default() -> Self {
        Level {
            inv_cell: [0.0; 3],
            dims: [1; 3],
            wrap: [false; 3],
            start: Vec::new(),
            boxes: Vec::new(),
            keys: Vec::new(),
            tags: Vec::new(),
        }
    }
}

/// `x` rounded down, clamped to +-1e15 (0 for NaN), without a call to `floor` (a call into the
/// maths library without SSE 4.1).
#[inline]
pub(super) fn floor_to_i64(x: f64) -> i64 {
    let x = x.clamp(-1e15, 1e15);
    let t = x as i64;
    t - i64::from((t as f64) > x)
}

/// `i` mod `n` for `i` within one period of `[0, n)`, the general case otherwise.
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
    pub(super) fn coords(&self, topo: &Topology<V>, p: V) -> [usize; 3] {
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
    pub(super) fn key(&self, c: [usize; 3]) -> usize {
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
    pub(super) fn key_delta(&self, o: [i32; 3]) -> isize {
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
            let margin = reach + ROUNDING_MARGIN * ((center.get(axis) - origin).abs() + reach);
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
    pub(super) fn footprint_cells(&self, topo: &Topology<V>, b: &CellBox<V>) -> f64 {
        self.footprint(topo, b).iter().map(|r| r.1 as f64).product()
    }

    /// Calls `f` with the tag of each member of the cells of `b`'s footprint (every member whose
    /// box may overlap `b`'s), for a level that kept only its tags ([`Self::keep_tags_only`]).
    #[inline]
    pub(super) fn for_each_member_near(
        &self,
        topo: &Topology<V>,
        b: &CellBox<V>,
        mut f: impl FnMut(u32),
    ) {
        self.for_each_run_near(topo, b, |run| {
            self.tags[run].iter().copied().for_each(&mut f);
        });
    }

    /// Calls `f` with the members of the cells of `b`'s footprint, in the order of their cells'
    /// keys, as ranges of indices into the cell-sorted members: the cells of one row of the
    /// footprint (along the first axis) follow each other in the sort, so their members are one
    /// range (two where the row wraps round a periodic border). A large box over a fine level
    /// reads two bounds a row rather than two a cell.
    #[inline]
    pub(super) fn for_each_run_near(
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

    /// Keeps of the members only their tags in cell order (`tags`, written over the cell keys)
    /// and gives up their boxes: what a Verlet list's repairs need of a build's level, since the
    /// list's bounds hold the boxes. Returns the boxes' buffer, for the bounds to be written into
    /// (and handed back at the next build), so that the bounds and the boxes are never kept at
    /// once.
    pub(super) fn keep_tags_only(&mut self) -> Vec<CellBox<V>> {
        for (key, b) in self.keys.iter_mut().zip(&self.boxes) {
            *key = b.tag;
        }
        self.tags = std::mem::take(&mut self.keys);
        std::mem::take(&mut self.boxes)
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
        &self.boxes[self.start[key] as usize..self.start[key + 1] as usize]
    }

    /// The sorted objects cut into runs of whole cells of about `size` objects, in order.
    pub(super) fn cell_runs(&self, size: usize) -> Vec<std::ops::Range<usize>> {
        let m = self.boxes.len();
        let mut runs = Vec::with_capacity(m / size + 1);
        let mut begin = 0;
        while begin < m {
            let mut end = (begin + size).min(m);
            while end < m && self.keys[end] == self.keys[end - 1] {
                end += 1;
            }
            runs.push(begin..end);
            begin = end;
        }
        runs
    }

    /// Appends the pairs of this level's objects in `run` (whole cells of `boxes`) with each
    /// other and with the cells at the `forward` offsets (`deltas` as key offsets); returns the
    /// number of box tests.
    #[inline]
    pub(super) fn pairs_within(
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
            let key = self.keys[begin] as usize;
            let mut end = begin + 1;
            while end < run.end && self.keys[end] as usize == key {
                end += 1;
            }
            let here = &self.boxes[begin..end];
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
    pub(super) fn forward_offsets(&self) -> Vec<[i32; 3]> {
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
    pub(super) fn build<M, I, It, F>(
        &mut self,
        members: impl Fn() -> M,
        known: Option<KnownKeys<'_, I, F>>,
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
            if known.keys.len() >= crate::parallel::PARALLEL_MIN && parts > 1 {
                self.sort_in_parts(known, parts, pad);
                return cell;
            }
        }
        let mut m = 0;
        match &known {
            Some(KnownKeys { indices, keys, .. }) => {
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
            self.boxes[at] = CellBox::new(&o, i, pad);
            self.keys[at] = k as u32;
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
        self.boxes.clear();
        self.boxes.resize(m, CellBox::default());
        if self.keys.capacity() == 0 {
            // Tags kept by `keep_tags_only` are not read again once the level is built anew.
            self.keys = std::mem::take(&mut self.tags);
        }
        self.keys.clear();
        self.keys.resize(m, 0);
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
    /// ranges of about as many members, so that no pass through every member is sequential.
    fn sort_in_parts<I, It, F>(&mut self, known: &KnownKeys<'_, I, F>, parts: usize, pad: f64)
    where
        I: Fn() -> It + Sync,
        It: Iterator<Item = usize>,
        F: Fn(usize) -> Option<BroadObject<V>> + Sync,
    {
        use rayon::prelude::*;
        let KnownKeys {
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
        let (mut start, mut boxes, mut keys_left) = (
            &mut self.start[..ncells],
            &mut self.boxes[..],
            &mut self.keys[..],
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
            let (b, rest_b) = std::mem::take(&mut boxes).split_at_mut(end - first);
            let (t, rest_t) = std::mem::take(&mut keys_left).split_at_mut(end - first);
            (start, boxes, keys_left) = (rest, rest_b, rest_t);
            jobs.push((lo..hi, first, s, b, t));
        }
        jobs.into_par_iter()
            .for_each(|(cells, first, cursor, boxes, cell_keys)| {
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
                    cell_keys[at] = k as u32;
                    *c += 1;
                }
            });
        self.ends_to_starts();
    }
}
