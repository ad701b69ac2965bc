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
//!
//! The parts: `objects` (what the broad phase reads, and the view of fast objects led ahead by
//! their strides), `cell_box` (the single-precision boxes and their overlap tests), `level` (one
//! level of the grid: its cells, its counting sort, its walks), `grid` (the levels built and
//! walked for one search) and `verlet` (the kept pair list: built, checked, mended, re-tested).

mod cell_box;
mod grid;
mod level;
mod objects;
mod verlet;

#[cfg(test)]
mod tests;

pub use objects::BroadObject;
pub(crate) use objects::Objects;
pub(crate) use verlet::Escapes;

use crate::border::Topology;
use crate::vector::Vector;
use level::Level;
use objects::overlaps;
use verlet::VerletList;

/// Below this many objects the direct all-pairs loop is used (see `docs/performance.md`).
pub const SMALL_N: usize = 100;

/// Steps a fast object's bound in the Verlet list is made to last at its speed at the build:
/// the object's box is widened (see [`objects::LEAD_ALONG_STEP`]) by `LEAD_STEPS` strides less
/// half the skin (nothing for the objects the skin already covers that long), so that small
/// disks much faster than the rest pair with a few more neighbours instead of forcing a build
/// every step.
pub(crate) const LEAD_STEPS: f64 = 8.0;

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

/// The broad phase, with its scratch memory kept between steps.
pub struct BroadPhase<V: Vector> {
    /// Algorithm choice.
    pub mode: BroadPhaseMode,
    list: VerletList<V>,
    levels: Vec<Level<V>>,
    /// The levels the last build filled, finest first (the others may hold older builds).
    built_levels: Vec<usize>,
    /// Each object's level in the last build ([`grid::NO_LEVEL`] for a gap).
    level_of: Vec<u8>,
    /// The finest width of the last build (its `s0`), the guess the next one starts from.
    finest_width: f64,
    /// The grid's pairs before their exact test, kept between calls (`BroadPhaseMode::Grid`).
    candidates: Vec<(u32, u32)>,
    /// Number of bounding-box tests made in the last call.
    pub tests: u64,
    /// Number of grid levels used in the last call (0 for the direct loop).
    pub levels_used: usize,
}

impl<V: Vector> Default for BroadPhase<V> {
    fn default() -> Self {
        BroadPhase {
            mode: BroadPhaseMode::Auto,
            list: VerletList::default(),
            levels: Vec::new(),
            built_levels: Vec::new(),
            level_of: Vec::new(),
            finest_width: 0.0,
            candidates: Vec::new(),
            tests: 0,
            levels_used: 0,
        }
    }
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
    /// world gives its rules and narrow phase, which would otherwise take a second trip through
    /// scattered critters.
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
            self.grid_pairs(objs, topo, out, &mut Vec::new());
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
    /// for its next build's leads (see [`objects::CROWD_LEAD_OVER_MEDIAN`]).
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
    /// (diagnostics; see `SHORT_LIVED` in `verlet.rs`).
    pub fn grid_steps(&self) -> u64 {
        self.list.grid_steps
    }

    /// The direct loop over all pairs, for small scenes.
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
}
