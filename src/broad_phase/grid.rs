//! The grid built and walked for one search: each object's level, each level's counting sort,
//! the pairs within each level and across levels.

use super::cell_box::{push_overlapping, CellBox, WALL_BIT};
use super::level::{KnownKeys, Level};
use super::objects::{box_width, overlap_flag};
use super::{BroadPhase, Objects};
use crate::border::Topology;
use crate::vector::Vector;

/// The level of a gap (no level has it: levels go up to 63).
pub(super) const NO_LEVEL: u8 = u8::MAX;

/// Objects per task of the pass that finds each object's level on rayon's threads.
const LEVEL_CHUNK: usize = 8192;

/// Objects per run of cells walked by one task when a level's pairs are found in parallel.
pub(super) const RUN_OBJECTS: usize = 8192;

/// Runs of [`RUN_OBJECTS`] walked in parallel before their pairs are joined onto the list.
pub(super) const RUNS_AT_ONCE: usize = 16;

/// How many indices ahead a level's passes over its members ask for objects to be prefetched,
/// so that the loads of scattered objects overlap.
const MEMBERS_AHEAD: usize = 8;

/// 2 to the power `l`, exactly (infinite from 1024 on), without a call to `exp2`.
#[inline]
pub(super) fn pow2(l: usize) -> f64 {
    f64::from_bits((1023 + l.min(1024) as u64) << 52)
}

impl<V: Vector> BroadPhase<V> {
    /// The grid rebuilt for this call: its cells' single-precision boxes may find a few more
    /// pairs than overlap, so each is tested again against the exact boxes. The first level
    /// without a buffer of its own for its boxes takes `spare`'s.
    pub(super) fn grid_pairs<O: Objects<V> + ?Sized>(
        &mut self,
        objs: &O,
        topo: &Topology<V>,
        out: &mut Vec<(u32, u32)>,
        spare: &mut Vec<CellBox<V>>,
    ) {
        let mut candidates = std::mem::take(&mut self.candidates);
        candidates.clear();
        self.grid_candidates(objs, topo, &mut candidates, 0.0, spare);
        self.tests += candidates.len() as u64;
        // Every pair written, the end moved on only for those that overlap (no branch on a
        // coin toss, as in the re-test).
        let mut end = out.len();
        out.resize(end + candidates.len(), (0, 0));
        for &(i, j) in &candidates {
            let (Some(a), Some(b)) = (objs.object(i as usize), objs.object(j as usize)) else {
                continue;
            };
            out[end] = (a.slot, b.slot);
            end += usize::from(overlap_flag(topo, &a, &b));
        }
        out.truncate(end);
        self.candidates = candidates;
    }

    /// The pairs of the grid's cells' boxes (`objs` widened by `pad`, in single precision rounded
    /// outwards: every pair whose widened boxes overlap, and perhaps a few whose boxes only
    /// touch through the rounding), named by their indices in `objs`. The first level built
    /// without a buffer of its own for its boxes takes `spare`'s (a Verlet list's old bounds).
    pub(super) fn grid_candidates<O: Objects<V> + ?Sized>(
        &mut self,
        objs: &O,
        topo: &Topology<V>,
        out: &mut Vec<(u32, u32)>,
        pad: f64,
        spare: &mut Vec<CellBox<V>>,
    ) {
        let n = objs.slots();
        assert!(
            n < WALL_BIT as usize,
            "the broad phase names objects by 31-bit indices"
        );
        // Each object's level is measured from the finest width `s0`, which takes a pass over
        // the objects of its own. The levels are first found from the last build's `s0`, in the
        // same pass that finds the new one: where the two are equal (a scene whose smallest
        // objects stay the same size), that is the only pass. On rayon's threads for a large
        // scene, in fixed chunks: a minimum and an indexed map give the same result for any
        // thread count.
        let parallel = n >= crate::parallel::PARALLEL_MIN;
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
                        let w = box_width(&o, pad);
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
        let guess = self.finest_width;
        let s0 = all_levels(guess);
        if s0 != guess {
            all_levels(s0);
        }
        self.finest_width = s0;
        let (mut top, mut count, mut occupied) = (0usize, 0usize, [false; 64]);
        for &l in self.level_of.iter().filter(|&&l| l != NO_LEVEL) {
            top = top.max(usize::from(l));
            count += 1;
            occupied[usize::from(l)] = true;
        }
        // Levels whose cells the limit below would widen to the same size share one grid: as
        // separate levels their objects would be tested against each other cell by cell, level
        // by level.
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
        let mut built = std::mem::take(&mut self.built_levels);
        built.clear();
        for l in (0..=top).filter(|&l| occupied[l]) {
            built.push(l);
            let cell = (s0 * pow2(l)).max(floor_cell);
            // A level's members are found by a pass over one byte per object rather than kept
            // in a list of their own (4 bytes per object less at the peak).
            let level_of = &self.level_of;
            let indices = || {
                level_of
                    .iter()
                    .enumerate()
                    .filter(move |&(_, &at)| usize::from(at) == l)
                    .map(|(i, _)| i)
            };
            let members = || {
                indices().filter_map(|i| {
                    objs.prefetch(i + MEMBERS_AHEAD);
                    Some((i as u32, objs.object(i)?))
                })
            };
            if self.levels[l].boxes.capacity() == 0 {
                std::mem::swap(&mut self.levels[l].boxes, spare);
            }
            let object = |i: usize| {
                objs.prefetch(i + MEMBERS_AHEAD);
                objs.object(i)
            };
            let known = (keys.len() == n).then(|| KnownKeys {
                indices,
                keys: &keys[..],
                object,
            });
            floor_cell = self.levels[l].build(members, known, topo, cell, limit, pad);
        }
        self.levels_used = built.len();

        // Pairs within each level: own cell, then the forward half of the neighbours, walking
        // the occupied cells in order. On a large level with more than one thread, runs of
        // whole cells are walked in parallel and their pairs joined in order: the same list as
        // the one walk, for any thread count.
        for &l in &built {
            let level = &self.levels[l];
            let forward = level.forward_offsets();
            let deltas: Vec<isize> = forward.iter().map(|&o| level.key_delta(o)).collect();
            let walk = |run: std::ops::Range<usize>, out: &mut Vec<(u32, u32)>| {
                level.pairs_within(topo, &forward, &deltas, run, out)
            };
            let m = level.boxes.len();
            if m >= crate::parallel::PARALLEL_MIN && rayon::current_num_threads() > 1 {
                use rayon::prelude::*;
                let runs = level.cell_runs(RUN_OBJECTS);
                // A few runs at a time, so that the parts waiting to be joined are a slice of
                // the list, not a second copy of it.
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
        for (u, &fine) in built.iter().enumerate() {
            for &coarse in &built[u + 1..] {
                let (lo, hi) = self.levels.split_at(coarse);
                let (fine_level, coarse_level) = (&lo[fine], &hi[0]);
                let by_fine = fine_level.boxes.len() as f64 * 3f64.powi(V::DIM as i32);
                // Counted only until it reaches `by_fine`.
                let mut by_coarse = 0.0;
                for b in &coarse_level.boxes {
                    by_coarse += fine_level.footprint_cells(topo, b);
                    if by_coarse >= by_fine {
                        break;
                    }
                }
                if by_coarse < by_fine {
                    for b in &coarse_level.boxes {
                        fine_level.for_each_run_near(topo, b, |run| {
                            let run = &fine_level.boxes[run];
                            self.tests += run.len() as u64;
                            push_overlapping(topo, b, run, out, |a, b| (b, a));
                        });
                    }
                } else {
                    for a in &fine_level.boxes {
                        coarse_level.for_each_run_near(topo, a, |run| {
                            let run = &coarse_level.boxes[run];
                            self.tests += run.len() as u64;
                            push_overlapping(topo, a, run, out, |a, b| (a, b));
                        });
                    }
                }
            }
        }
        self.built_levels = built;
    }
}
