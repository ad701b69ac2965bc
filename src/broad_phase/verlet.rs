//! The Verlet list: the grid's pairs for boxes widened by a skin, kept while every object stays
//! inside its bound; each step re-tests only those. Where a few objects left, the list is mended
//! for them; where lists live a single step (a jostled pile), the plain grid takes over for a
//! while.

use super::cell_box::{cells_overlap, CellBox, WALL_BIT};
use super::objects::{box_width, overlap_flag, LeadBoxes, CROWD_LEAD_OVER_MEDIAN};
use super::{BroadObject, BroadPhase, Objects};
use crate::border::Topology;
use crate::vector::Vector;

/// After this many builds in a row of a Verlet list that served one step each, pairs are found
/// with the plain grid (no skin, no list) for [`GRID_SPELL`] steps before a list is tried again:
/// a pile jostled by the discrete step's separations leaves any skin every step, so the skin only
/// adds pairs and the re-test repeats the build's tests.
pub(super) const SHORT_LIVED: u32 = 3;

/// Steps the plain grid is used for once lists are found to live a single step (see
/// [`SHORT_LIVED`]).
pub(super) const GRID_SPELL: u32 = 32;

/// A repair of the Verlet list is refused, and the list built anew, once the objects mended
/// since the build would pass this share of all objects: each is tested against the others'
/// new boxes one by one.
const REPAIR_SHARE: f64 = 1.0 / 32.0;

/// A repair is refused when its cells to visit and its tests among the new boxes would pass
/// this many per object: a build visits a few cells per object on each level.
const REPAIR_WORK: f64 = 4.0;

/// Pairs [`retest`] writes ahead of those it has found at most.
const RETEST_BLOCK: usize = 256;

/// How many pairs ahead [`retest`] asks for its objects to be prefetched, so that the loads of
/// scattered objects overlap.
const PAIRS_AHEAD: usize = 64;

/// Kept pairs per chunk re-tested on one of rayon's threads.
const RETEST_CHUNK: usize = 4096;

/// The skin of the Verlet list, as a fraction of the objects' typical width: a larger skin means
/// fewer rebuilds and more kept pairs to re-test, and in 3D the kept pairs grow with the cube of
/// the reach, so 3D takes a thinner one.
fn skin_per_width<V: Vector>() -> f64 {
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
/// infinite for no objects. The skin follows it rather than the smallest width, which the small
/// disks of widely spread radii would outrun every step. A median of a fixed sample costs
/// nothing at any N and depends only on `objs`.
pub(super) fn typical_width<V: Vector, O: Objects<V> + ?Sized>(
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

/// The kept pairs of the Verlet list and where each object may go before it must be rebuilt.
pub(super) struct VerletList<V: Vector> {
    /// False until a build, and once the list is dropped or given up for the plain grid.
    pub(super) valid: bool,
    /// The skin of the last build, in units of length.
    skin: f64,
    /// The stride above which an object is led, as set at the build.
    led_above: f64,
    /// Each index's bound ([`CellBox::bound`]): where its object may be while the list stays
    /// valid.
    pub(super) bounds: Vec<CellBox<V>>,
    /// The grid's pairs for the widened boxes, by index.
    pub(super) pairs: Vec<(u32, u32)>,
    /// True once `pairs` are in the order of their lower index, then their higher one
    /// (repairs then keep it); a build leaves them in the grid's order.
    pub(super) sorted: bool,
    /// Set by [`BroadPhase::sort_list`]: sort `pairs` when the list is next kept.
    pub(super) sort_wanted: bool,
    /// Set by [`BroadPhase::set_crowded`]: the last step's contacts were many for the list's
    /// pairs (a pile), so the next build leads only the objects faster than
    /// [`CROWD_LEAD_OVER_MEDIAN`] times the median.
    pub(super) crowded: bool,
    /// Builds so far.
    pub(super) rebuilds: u64,
    /// Steps the list has served since its build (the build's own included).
    served: u32,
    /// Builds in a row that served a single step.
    short_lived: u32,
    /// Steps left to find pairs with the plain grid instead of a list (see [`SHORT_LIVED`]).
    grid_left: u32,
    /// Steps found with the plain grid instead of a list.
    pub(super) grid_steps: u64,
    /// Indices whose box was made anew by a repair since the build (one bit each): their
    /// entries in the build's levels are stale.
    mended: Vec<u64>,
    /// The new boxes of the `mended` indices that have an object.
    mended_boxes: Vec<CellBox<V>>,
    /// Repairs so far.
    pub(super) repairs: u64,
}

impl<V: Vector> Default for VerletList<V> {
    fn default() -> Self {
        VerletList {
            valid: false,
            skin: 0.0,
            led_above: 0.0,
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
            mended: Vec::new(),
            mended_boxes: Vec::new(),
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

/// What a caller that checked each object against the Verlet list while it had it at hand (the
/// world, in its move) found: the indices [`BroadPhase::list_holds`] said no for. A repair then
/// mends those without another pass over every object.
#[derive(Clone, Debug)]
pub(crate) struct Escapes {
    /// The indices whose object left its bound, ascending.
    pub(crate) slots: Vec<u32>,
    /// False when not every escaped index is in `slots` (the caller stopped noting them, or did
    /// not check every index): the broad phase then checks every object itself.
    pub(crate) complete: bool,
}

/// A chunk of the kept list re-tested: how many pairs were tested, those that overlap, and what
/// the caller's `then` gave for them.
type RetestedChunk<T> = (u64, Vec<(u32, u32)>, Option<T>);

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
        retest_unless_still::<true, V, O>(objs, topo, pairs, out)
    } else {
        retest_unless_still::<false, V, O>(objs, topo, pairs, out)
    }
}

/// [`retest`]'s loop; with `STILL` false nothing is still, and the check is compiled away (the
/// gas pays nothing for sleep).
#[inline]
fn retest_unless_still<const STILL: bool, V: Vector, O: Objects<V> + ?Sized>(
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
pub(super) fn merge_tail(pairs: &mut Vec<(u32, u32)>, start: usize) {
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

impl<V: Vector> BroadPhase<V> {
    /// Auto mode's pairs for large scenes: a Verlet list. The grid is built with every box
    /// widened by half a skin, and the pairs it finds are kept; while no object has moved more
    /// than half the skin from where it was then (and none came, went or changed size), every
    /// overlapping pair is among them, so a step only re-tests the kept pairs. When a few have,
    /// the list is mended for them (`repair_list`) rather than built anew.
    pub(super) fn listed_pairs<O, T, F>(
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
            self.grid_instead_of_list(objs, topo, out);
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
                self.grid_instead_of_list(objs, topo, out);
                return None;
            }
            self.rebuild_list(objs, topo);
        } else if self.list.sort_wanted && !self.list.sorted {
            crate::pair_order::sort_pairs(&mut self.list.pairs, objs.slots());
            self.list.sorted = true;
        }
        self.list.served = self.list.served.saturating_add(1);
        if objs.slots() >= crate::parallel::PARALLEL_MIN {
            // Chunks are tested in parallel and joined in order: the same output for any thread
            // count.
            use rayon::prelude::*;
            let parts: Vec<RetestedChunk<T>> = self
                .list
                .pairs
                .par_chunks(RETEST_CHUNK)
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
        let inside = |(i, b): (usize, &CellBox<V>)| b.holds(topo, objs.object(i).as_ref());
        if objs.slots() >= crate::parallel::PARALLEL_MIN {
            use rayon::prelude::*;
            bounds.par_iter().enumerate().all(inside)
        } else {
            bounds.iter().enumerate().all(inside)
        }
    }

    /// Builds the list anew: the skin from the objects' typical width, the grid's pairs for the
    /// boxes widened by half of it (and the fast ones by their leads), and every index's bound.
    fn rebuild_list<O: Objects<V> + ?Sized>(&mut self, objs: &O, topo: &Topology<V>) {
        let skin = skin_per_width::<V>() * typical_width(objs, |o| box_width(o, 0.0));
        // Boxes widened by half the skin, and fast ones by their lead; pairs named by index so
        // they index `objs`.
        let led_above = match self.list.crowded {
            true => CROWD_LEAD_OVER_MEDIAN * typical_stride(objs),
            false => 0.0,
        };
        let led = LeadBoxes {
            objs,
            half_skin: 0.5 * skin,
            led_above,
        };
        let mut pairs = std::mem::take(&mut self.list.pairs);
        pairs.clear();
        // The old bounds' buffer takes the grid's boxes, and the boxes' buffer, once the pairs
        // are found, the new bounds: the two are never kept at once.
        let mut buffer = std::mem::take(&mut self.list.bounds);
        self.grid_candidates(&led, topo, &mut pairs, 0.5 * skin, &mut buffer);
        for level in &mut self.levels {
            let boxes = level.keep_tags_only();
            if boxes.capacity() > buffer.capacity() {
                buffer = boxes;
            }
        }
        self.list.pairs = pairs;
        self.list.sorted = false;
        self.list.sort_wanted = false;
        let bound = |i: usize| CellBox::bound(led.object(i).as_ref(), 0.5 * skin);
        buffer.clear();
        buffer.reserve_exact(objs.slots());
        self.list.bounds = buffer;
        if objs.slots() >= crate::parallel::PARALLEL_MIN {
            use rayon::prelude::*;
            self.list
                .bounds
                .par_extend((0..objs.slots()).into_par_iter().map(bound));
        } else {
            self.list.bounds.extend((0..objs.slots()).map(bound));
        }
        self.list.skin = skin;
        self.list.led_above = led_above;
        self.list.mended.clear();
        self.list.mended.resize(objs.slots().div_ceil(64), 0);
        self.list.mended_boxes.clear();
        self.list.valid = true;
        self.list.served = 0;
        self.list.rebuilds += 1;
        self.tests = 0;
    }

    /// Mends the Verlet list where a few objects left their bounds (or came, went or changed),
    /// instead of building it anew: their pairs are dropped, each gets a new box and bound as a
    /// build would give it, and its pairs are found against the build's levels (skipping the
    /// stale entries of objects mended since) and the new boxes of the mended ones, so that a
    /// small disk struck by a large one, which leaves its bound at once, does not force a build.
    /// Returns false, having changed nothing, when a build is due: more than [`REPAIR_SHARE`] of
    /// the objects mended since the build, or more work than [`REPAIR_WORK`] allows.
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
            None if n >= crate::parallel::PARALLEL_MIN => {
                use rayon::prelude::*;
                (0..n).into_par_iter().filter_map(out).collect()
            }
            None => (0..n).filter_map(out).collect(),
        };
        let (e, x) = (escaped.len(), self.list.mended_boxes.len());
        if e == 0 || (e + x) as f64 > REPAIR_SHARE * n as f64 {
            return false;
        }
        let half_skin = 0.5 * self.list.skin;
        let led = LeadBoxes {
            objs,
            half_skin,
            led_above: self.list.led_above,
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
            for &l in &self.built_levels {
                work += self.levels[l].footprint_cells(topo, b);
            }
        }
        if work > REPAIR_WORK * n as f64 {
            return false;
        }

        let mut leaving = vec![0u64; n.div_ceil(64)];
        for &i in &escaped {
            set_bit(&mut leaving, i as usize);
            set_bit(&mut self.list.mended, i as usize);
        }
        let list = &mut self.list;
        list.mended_boxes
            .retain(|b| !bit(&leaving, b.index() as usize));
        list.pairs
            .retain(|&(a, b)| !bit(&leaving, a as usize) && !bit(&leaving, b as usize));
        let kept = list.pairs.len();
        for (i, b) in fresh {
            list.bounds[i as usize] = CellBox::bound(led.object(i as usize).as_ref(), half_skin);
            let Some(b) = b else {
                continue;
            };
            // The others' bounds stand for their boxes at the build: each holds its object's
            // box for as long as the object is not mended, and lies inside that box.
            for &l in &self.built_levels {
                self.levels[l].for_each_member_near(topo, &b, |tag| {
                    let a = tag & !WALL_BIT;
                    if !bit(&list.mended, a as usize)
                        && cells_overlap(topo, &list.bounds[a as usize], &b)
                    {
                        list.pairs.push((a, i));
                    }
                });
            }
            for a in &list.mended_boxes {
                if cells_overlap(topo, a, &b) {
                    list.pairs.push((a.index(), i));
                }
            }
            list.mended_boxes.push(b);
        }
        if list.sorted {
            merge_tail(&mut list.pairs, kept);
        }
        list.repairs += 1;
        true
    }

    /// [`Self::grid_pairs`] in place of the Verlet list, which is let go (its bounds' buffer
    /// handed to the grid's boxes).
    fn grid_instead_of_list<O: Objects<V> + ?Sized>(
        &mut self,
        objs: &O,
        topo: &Topology<V>,
        out: &mut Vec<(u32, u32)>,
    ) {
        self.list.valid = false;
        self.list.pairs.clear();
        let mut spare = std::mem::take(&mut self.list.bounds);
        self.grid_pairs(objs, topo, out, &mut spare);
    }
}
