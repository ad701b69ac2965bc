//! Neighbour queries (`me.nearby(r)`, `me.nearest(kind)`, `world().nearby(pos, r)`, and the
//! free-place test of `w.scatter`): a uniform grid of the critters' centres, built on the first
//! query and kept while nothing the engine cannot see moves the critters.
//!
//! The broad phase's grid is built in the pairs stage, after the move, so `update` hooks would
//! see it stale; this grid is built from the positions of the moment. Every hook write to a
//! critter ([`Neighbours::moved`]) and every spawn is noted; the next query re-files the noted
//! critters whose centre (or radius) changed, so answers are exact for the current positions.
//! The world drops the grid where the engine itself moves critters (each step's start, after
//! the update stage, before each `collide` call, before the lifecycle, on restore).
//!
//! A query filtered by kind uses a grid of that kind alone (built on the first such query), so
//! asking for a few hunters among many prey looks at hunters only. A query looks at the cells its
//! ball overlaps and the critters in them, never at every critter. Results are in id order and `nearest` breaks ties by the lower id, so the answers do
//! not depend on where critters are stored or how the grid was built.

use crate::border::Topology;
use crate::critter::{Critter, CritterId};
use crate::critter_set::CritterSet;
use crate::kind::{KindId, KindSet};
use crate::tolerance::ROUNDING_MARGIN;
use crate::vector::Vector;

/// No item (end of a cell's list, or an id index with no item).
const NONE: u32 = u32::MAX;

/// A critter as the grid filed it.
#[derive(Clone, Copy, Debug)]
struct Item<V> {
    id: CritterId,
    pos: V,
    radius: f64,
    kind: KindId,
    /// The critter was re-filed under a newer item (it moved, or its id index was reused).
    stale: bool,
}

/// The read-only world a query looks at.
#[derive(Clone, Copy)]
pub(crate) struct Scope<'a, V: Vector> {
    pub critters: &'a CritterSet<V>,
    pub kinds: &'a KindSet<V>,
    pub topo: &'a Topology<V>,
}

/// What `nearby` and `nearest` keep: the kind the answers must be (or extend), and the critter
/// they leave out (the asker).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Filter {
    pub kind: Option<KindId>,
    pub exclude: Option<CritterId>,
}

/// Checks a query radius: a number >= 0 (infinity is every critter).
pub(crate) fn check_radius(r: f64) -> Result<(), String> {
    if r >= 0.0 {
        Ok(())
    } else {
        Err(format!("nearby radius {r}: it must be a number >= 0"))
    }
}

/// The cells along one axis a query looks at: `Full` (all of them), or `lo..=hi` (wrapped
/// modulo the count when the border wraps, so `lo` may be negative).
#[derive(Clone, Copy)]
enum Span {
    Full,
    Range(i64, i64),
}

/// The neighbour grids of a world (see the module docs): one of every critter other than a
/// wall, and one for each kind a query has filtered by, so that asking for a rare kind looks
/// only at critters of that kind.
#[derive(Clone, Debug, Default)]
pub(crate) struct Neighbours<V: Vector> {
    all: Grid<V>,
    by_kind: Vec<Grid<V>>,
    /// Critters a hook may have moved since the grids were built: one log, which each valid
    /// grid reads from its own cursor ([`Grid::seen`]).
    touched: Vec<CritterId>,
    /// How many times a grid was built (tests check it is once per grid and stage).
    builds: u64,
}

/// A uniform grid of the centres of the critters other than walls of one kind (and the kinds
/// extending it), or of every kind.
#[derive(Clone, Debug)]
struct Grid<V: Vector> {
    /// The kind filed here (`None`: every kind).
    kind: Option<KindId>,
    valid: bool,
    /// Cells per axis (1 on axes the dimension lacks).
    cells: [i64; 3],
    /// Cell side per axis.
    side: [f64; 3],
    min: [f64; 3],
    wraps: bool,
    /// By cell (x fastest), its first item.
    head: Vec<u32>,
    /// By item, the next item of its cell.
    next: Vec<u32>,
    items: Vec<Item<V>>,
    /// By id index, its critter's current item.
    home: Vec<u32>,
    /// How much of the log of touched critters this grid has settled.
    seen: usize,
    /// Items at the last build, and stale items since.
    built: usize,
    stale: usize,
    /// Largest radius of an item at the last build (items filed since are re-filed critters,
    /// whose radius `max_radius` also covers).
    max_radius: f64,
}

impl<V: Vector> Default for Grid<V> {
    fn default() -> Self {
        Grid {
            kind: None,
            valid: false,
            cells: [1; 3],
            side: [1.0; 3],
            min: [0.0; 3],
            wraps: false,
            head: Vec::new(),
            next: Vec::new(),
            items: Vec::new(),
            home: Vec::new(),
            seen: 0,
            built: 0,
            stale: 0,
            max_radius: 0.0,
        }
    }
}

impl<V: Vector> Neighbours<V> {
    /// Drops the grids: the engine moved critters where the grids cannot see.
    #[inline]
    pub(crate) fn invalidate(&mut self) {
        self.all.valid = false;
        for g in &mut self.by_kind {
            g.valid = false;
        }
        self.touched.clear();
    }

    /// Notes that critter `id` may have moved (a write through a hook's or the scene's handle).
    #[inline]
    pub(crate) fn moved(&mut self, id: CritterId) {
        if self.is_tracking() {
            self.touched.push(id);
        }
    }

    /// True while writes are noted (some grid is built).
    #[inline]
    pub(crate) fn is_tracking(&self) -> bool {
        self.all.valid || self.by_kind.iter().any(|g| g.valid)
    }

    /// How many times a grid has been built.
    #[cfg(test)]
    pub(crate) fn builds(&self) -> u64 {
        self.builds
    }

    /// The grid for `kind`, built and up to date with every move noted.
    fn grid(&mut self, at: Scope<'_, V>, kind: Option<KindId>) -> &mut Grid<V> {
        let i = match kind {
            None => None,
            Some(k) => Some(match self.by_kind.iter().position(|g| g.kind == Some(k)) {
                Some(i) => i,
                None => {
                    self.by_kind.push(Grid {
                        kind: Some(k),
                        ..Grid::default()
                    });
                    self.by_kind.len() - 1
                }
            }),
        };
        let grid = match i {
            None => &mut self.all,
            Some(i) => &mut self.by_kind[i],
        };
        if grid.ready(at, &self.touched) {
            self.builds += 1;
        }
        // Every grid has read the whole log: start it afresh.
        let log = self.touched.len();
        if log > 0 && self.all.read(log) && self.by_kind.iter().all(|g| g.read(log)) {
            self.touched.clear();
            self.all.seen = 0;
            for g in &mut self.by_kind {
                g.seen = 0;
            }
        }
        match i {
            None => &mut self.all,
            Some(i) => &mut self.by_kind[i],
        }
    }

    /// The live critters other than walls within `r` of `centre` (through the border when it
    /// wraps) that pass `filter`, in id order.
    pub(crate) fn nearby(
        &mut self,
        at: Scope<'_, V>,
        centre: V,
        r: f64,
        filter: Filter,
    ) -> Vec<CritterId> {
        let grid = self.grid(at, filter.kind);
        let mut out = Vec::new();
        // Above this squared distance no item can be within `r` (the square root is then spared).
        let far = r * r * (1.0 + 4.0 * f64::EPSILON) + f64::MIN_POSITIVE;
        grid.visit(centre, r, |item| {
            // Every item of the grid is of the kind asked for. A live item's position is its
            // critter's (`settle` re-filed every move).
            let d = at.topo.delta(centre, item.pos);
            if d.length_squared() <= far && d.length() <= r && passes(at, item, filter) {
                out.push(item.id);
            }
            false
        });
        out.sort_unstable();
        out
    }

    /// The live critter other than walls nearest to `centre` that passes `filter` (ties go to
    /// the lower id), or `None`. The ball searched doubles until it holds an answer or covers
    /// the grid.
    pub(crate) fn nearest(
        &mut self,
        at: Scope<'_, V>,
        centre: V,
        filter: Filter,
    ) -> Option<CritterId> {
        let grid = self.grid(at, filter.kind);
        let dim = V::DIM;
        let mut reach = grid.side[..dim]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        loop {
            let mut best: Option<(f64, CritterId)> = None;
            grid.visit(centre, reach, |item| {
                let d = at.topo.delta(centre, item.pos).length();
                let better = best.is_none_or(|(bd, bid)| d < bd || (d == bd && item.id < bid));
                if better && passes(at, item, filter) {
                    best = Some((d, item.id));
                }
                false
            });
            // Every critter within `reach` was looked at; a nearer one than `best` would be too.
            match best {
                Some((d, id)) if d <= reach => return Some(id),
                _ if grid.covers_all(centre, reach) => return best.map(|(_, id)| id),
                _ => reach *= 2.0,
            }
        }
    }

    /// True when some critter (live or dying, not a wall) satisfies `hit`, among those whose
    /// centre lies within `reach + r` of `centre`, `r` being the largest radius in the grid:
    /// `w.scatter`'s overlap test, which `hit` makes exactly.
    pub(crate) fn any_overlapping(
        &mut self,
        at: Scope<'_, V>,
        centre: V,
        reach: f64,
        mut hit: impl FnMut(&Critter<V>) -> bool,
    ) -> bool {
        let grid = self.grid(at, None);
        let reach = reach + grid.max_radius;
        let mut found = false;
        grid.visit(centre, reach, |item| {
            found = at.critters.get(item.id).is_some_and(&mut hit);
            found
        });
        found
    }
}

impl<V: Vector> Grid<V> {
    /// True when the grid is valid and has settled the first `log` entries of the log.
    fn read(&self, log: usize) -> bool {
        !self.valid || self.seen == log
    }

    /// True when a critter of kind `kind` is filed here.
    fn files(&self, kinds: &KindSet<V>, kind: KindId) -> bool {
        self.kind.is_none_or(|k| kinds.is_kind(kind, k))
    }

    /// Builds the grid if it is not valid, and re-files the critters noted in `touched` since
    /// it last looked; true when it was built.
    fn ready(&mut self, at: Scope<'_, V>, touched: &[CritterId]) -> bool {
        if self.valid {
            self.settle(at, &touched[self.seen..]);
        }
        self.seen = touched.len();
        // Too many re-filed items (or a grid grown far past what it was sized for): rebuild.
        let rebuild = !self.valid
            || self.stale * 2 > self.items.len() + 64
            || self.items.len() > 2 * self.built + 64;
        if rebuild {
            self.build(at);
        }
        rebuild
    }

    fn build(&mut self, at: Scope<'_, V>) {
        let (topo, critters, kinds) = (at.topo, at.critters, at.kinds);
        let want = self.kind;
        let filed =
            move |c: &&Critter<V>| !c.is_wall() && want.is_none_or(|k| kinds.is_kind(c.kind(), k));
        let count = critters.iter_stored().filter(filed).count();
        let dim = V::DIM;
        let size = topo.size();
        let volume: f64 = (0..dim).map(|a| size.get(a)).product();
        // About two critters a cell.
        let target = (count / 2).max(1) as f64;
        let side = (volume / target).powf(1.0 / dim as f64);
        self.wraps = topo.wraps();
        self.cells = [1; 3];
        self.side = [1.0; 3];
        self.min = [0.0; 3];
        for a in 0..dim {
            let l = size.get(a);
            let n = if side > 0.0 && side.is_finite() {
                (l / side).floor().clamp(1.0, 4096.0) as i64
            } else {
                1
            };
            self.cells[a] = n;
            self.side[a] = l / n as f64;
            self.min[a] = topo.min.get(a);
        }
        let ncells = (self.cells[0] * self.cells[1] * self.cells[2]) as usize;

        // Counting sort by cell, so each cell's items lie together in memory.
        self.items.clear();
        self.next.clear();
        self.home.clear();
        self.home.resize(critters.index_count(), NONE);
        let mut start = vec![0u32; ncells + 1];
        let mut cell_of = Vec::with_capacity(count);
        let mut max_radius: f64 = 0.0;
        for c in critters.iter_stored().filter(filed) {
            let cell = self.cell(c.pos);
            start[cell + 1] += 1;
            cell_of.push(cell);
            max_radius = max_radius.max(c.radius);
        }
        for i in 0..ncells {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let blank = Item {
            id: CritterId {
                index: NONE,
                generation: 0,
            },
            pos: V::zero(),
            radius: 0.0,
            kind: crate::kind::WALL,
            stale: true,
        };
        self.items.resize(count, blank);
        for (c, &cell) in critters.iter_stored().filter(filed).zip(&cell_of) {
            let i = fill[cell] as usize;
            fill[cell] += 1;
            self.items[i] = Item {
                id: c.id,
                pos: c.pos,
                radius: c.radius,
                kind: c.kind(),
                stale: false,
            };
            self.home[c.id.index as usize] = i as u32;
        }
        self.next.resize(count, NONE);
        self.head.clear();
        self.head.resize(ncells, NONE);
        for cell in 0..ncells {
            let (a, b) = (start[cell] as usize, start[cell + 1] as usize);
            if a < b {
                self.head[cell] = a as u32;
                for i in a..b - 1 {
                    self.next[i] = i as u32 + 1;
                }
            }
        }
        self.built = count;
        self.stale = 0;
        self.max_radius = max_radius;
        self.valid = true;
    }

    /// Re-files the critters in `touched` whose centre or radius changed, and files new ones
    /// of the grid's kind.
    fn settle(&mut self, at: Scope<'_, V>, touched: &[CritterId]) {
        for &id in touched {
            let Some(c) = at.critters.get(id) else {
                continue; // gone: its item is skipped by every query
            };
            if c.is_wall() || !self.files(at.kinds, c.kind()) {
                continue;
            }
            let index = id.index as usize;
            if index >= self.home.len() {
                self.home.resize(index + 1, NONE);
            }
            let h = self.home[index];
            if h != NONE {
                let item = &mut self.items[h as usize];
                if item.id == id && item.pos == c.pos && item.radius == c.radius {
                    continue;
                }
                if !item.stale {
                    item.stale = true;
                    self.stale += 1;
                }
            }
            let cell = self.cell(c.pos);
            let i = self.items.len() as u32;
            self.items.push(Item {
                id,
                pos: c.pos,
                radius: c.radius,
                kind: c.kind(),
                stale: false,
            });
            self.next.push(self.head[cell]);
            self.head[cell] = i;
            self.home[index] = i;
            self.max_radius = self.max_radius.max(c.radius);
        }
    }

    /// The cell coordinate of `x` along `axis` (wrapped, or clamped to the grid).
    #[inline]
    fn coord(&self, axis: usize, x: f64) -> i64 {
        let k = ((x - self.min[axis]) / self.side[axis]).floor();
        let n = self.cells[axis];
        if self.wraps {
            let k = if k.is_finite() && k.abs() < 1e15 {
                k as i64
            } else {
                0
            };
            k.rem_euclid(n)
        } else {
            k.clamp(0.0, (n - 1) as f64) as i64
        }
    }

    #[inline]
    fn cell(&self, p: V) -> usize {
        let mut cell = 0i64;
        for a in (0..V::DIM).rev() {
            cell = cell * self.cells[a] + self.coord(a, p.get(a));
        }
        cell as usize
    }

    /// The cells along `axis` within `reach` of `x`, widened by a rounding margin.
    fn span(&self, axis: usize, x: f64, reach: f64) -> Span {
        let n = self.cells[axis];
        let (min, side) = (self.min[axis], self.side[axis]);
        let margin = ROUNDING_MARGIN * (min.abs() + side * n as f64 + x.abs() + reach);
        let lo = ((x - reach - margin - min) / side).floor();
        let hi = ((x + reach + margin - min) / side).floor();
        if self.wraps {
            // NaN (an infinite reach) also looks at every cell.
            let fits = hi - lo + 1.0 < n as f64;
            if !fits {
                return Span::Full;
            }
            Span::Range(lo as i64, hi as i64)
        } else {
            if !(lo > 0.0 || hi < (n - 1) as f64) {
                return Span::Full;
            }
            let clamp = |k: f64| k.clamp(0.0, (n - 1) as f64) as i64;
            Span::Range(clamp(lo), clamp(hi))
        }
    }

    /// True when a query of `reach` around `centre` looks at every cell.
    fn covers_all(&self, centre: V, reach: f64) -> bool {
        (0..V::DIM).all(|a| matches!(self.span(a, centre.get(a), reach), Span::Full))
    }

    /// Calls `f` on each live item in the cells within `reach` of `centre` until `f` returns
    /// true.
    fn visit(&self, centre: V, reach: f64, mut f: impl FnMut(&Item<V>) -> bool) {
        let mut spans = [Span::Range(0, 0); 3];
        for (a, span) in spans.iter_mut().enumerate().take(V::DIM) {
            *span = self.span(a, centre.get(a), reach);
        }
        let range = |a: usize| match spans[a] {
            Span::Full => (0, self.cells[a] - 1),
            Span::Range(lo, hi) => (lo, hi),
        };
        let wrap = |a: usize, k: i64| {
            if self.wraps {
                k.rem_euclid(self.cells[a])
            } else {
                k
            }
        };
        let (x0, x1) = range(0);
        let (y0, y1) = range(1);
        let (z0, z1) = range(2);
        for z in z0..=z1 {
            let zc = wrap(2, z);
            for y in y0..=y1 {
                let row = (zc * self.cells[1] + wrap(1, y)) * self.cells[0];
                for x in x0..=x1 {
                    let mut i = self.head[(row + wrap(0, x)) as usize];
                    while i != NONE {
                        let item = &self.items[i as usize];
                        i = self.next[i as usize];
                        if !item.stale && f(item) {
                            return;
                        }
                    }
                }
            }
        }
    }
}

/// True when the critter filed as `item` is still there, alive and not left out. (Its kind is
/// the one `filter` asks for: the grid asked holds that kind alone.)
#[inline]
fn passes<V: Vector>(at: Scope<'_, V>, item: &Item<V>, filter: Filter) -> bool {
    debug_assert!(filter.kind.is_none_or(|k| at.kinds.is_kind(item.kind, k)));
    filter.exclude != Some(item.id) && at.critters.get(item.id).is_some_and(|c| c.in_play())
}

#[cfg(test)]
#[path = "neighbours_tests.rs"]
mod tests;
