//! The pairs of islands whose boxes meet, for `link_islands`.
//!
//! A sweep along x finds them simply, but in a falling grid each box's x-window holds its whole
//! column, and the sweep costs O(n^1.5). A uniform grid of cells about as wide as a box keeps
//! it linear: each box goes into every cell it covers, and a pair that meets is reported by one
//! cell only, the one holding the low corner of the two boxes' intersection (a point of both
//! boxes, so both are in that cell). Boxes that would fill the grid too often fall back to the
//! sweep.

use crate::vector::Vector;

/// Below this many boxes the sweep costs less than setting up a grid.
const GRID_FROM: usize = 256;

/// Cells a grid may have, per box.
const CELLS_PER_BOX: usize = 2;

/// Cell entries a grid may fill, per box, before the sweep is used instead (many large boxes).
const ENTRIES_PER_BOX: usize = 16;

/// Every pair of `roots` whose closed boxes `lo`..`hi` (indexed by root) meet, once each, as
/// `(a, b)` with `a` before `b` in the order of (low x, root). The pairs come in no useful
/// order.
pub(super) fn meeting<V: Vector>(roots: &[usize], lo: &[V], hi: &[V]) -> Vec<(usize, usize)> {
    let before = |a: usize, b: usize| lo[a].get(0).total_cmp(&lo[b].get(0)).then(a.cmp(&b));
    let meet = |a: usize, b: usize| {
        (0..V::DIM).all(|ax| lo[a].get(ax) <= hi[b].get(ax) && lo[b].get(ax) <= hi[a].get(ax))
    };
    let mut out = Vec::new();
    if roots.len() >= GRID_FROM {
        if let Some(grid) = Grid::of(roots, lo, hi) {
            grid.pairs(lo, |a, b| {
                if meet(a, b) {
                    out.push(if before(a, b).is_lt() { (a, b) } else { (b, a) });
                }
            });
            return out;
        }
    }
    let mut sorted = roots.to_vec();
    sorted.sort_by(|&a, &b| before(a, b));
    for (i, &a) in sorted.iter().enumerate() {
        for &b in &sorted[i + 1..] {
            if lo[b].get(0) > hi[a].get(0) {
                break;
            }
            if meet(a, b) {
                out.push((a, b));
            }
        }
    }
    out
}

/// Boxes by the cells they cover.
struct Grid {
    origin: [f64; 3],
    side: f64,
    dims: [usize; 3],
    /// Each cell's entries: `entries[start[c]..start[c + 1]]`, roots in the order given.
    start: Vec<usize>,
    entries: Vec<usize>,
}

impl Grid {
    /// The grid of the boxes, or `None` when it would take too many entries.
    fn of<V: Vector>(roots: &[usize], lo: &[V], hi: &[V]) -> Option<Grid> {
        let dim = V::DIM;
        let mut origin = [0.0; 3];
        let mut extent = [0.0f64; 3];
        let mut widths = Vec::with_capacity(roots.len());
        for ax in 0..dim {
            let l = roots
                .iter()
                .map(|&r| lo[r].get(ax))
                .fold(f64::INFINITY, f64::min);
            let h = roots
                .iter()
                .map(|&r| hi[r].get(ax))
                .fold(f64::NEG_INFINITY, f64::max);
            origin[ax] = l;
            extent[ax] = h - l;
        }
        for &r in roots {
            let w = (0..dim).map(|ax| hi[r].get(ax) - lo[r].get(ax));
            widths.push(w.fold(0.0, f64::max));
        }
        // Cells as wide as the median box, but no more of them than CELLS_PER_BOX per box.
        let mid = widths.len() / 2;
        let (_, &mut median, _) = widths.select_nth_unstable_by(mid, f64::total_cmp);
        let volume: f64 = extent
            .iter()
            .take(dim)
            .map(|e| e.max(f64::MIN_POSITIVE))
            .product();
        let fewest = (volume / (CELLS_PER_BOX * roots.len()) as f64).powf(1.0 / dim as f64);
        let side = median.max(fewest);
        if !(side.is_finite() && side > 0.0) {
            return None;
        }
        let mut dims = [1usize; 3];
        for ax in 0..dim {
            dims[ax] = ((extent[ax] / side) as usize + 1).min(1 << 20);
        }
        let mut grid = Grid {
            origin,
            side,
            dims,
            start: Vec::new(),
            entries: Vec::new(),
        };
        let cells: usize = dims.iter().product();
        if cells > 2 * CELLS_PER_BOX * roots.len() + 8 {
            return None; // a rounding of the sizes gave far more cells than planned
        }
        // Entries counted per cell, then filled in the roots' order (a counting sort).
        let mut count = vec![0usize; cells + 1];
        let mut total = 0usize;
        for &r in roots {
            let (a, b) = (grid.cell_of(lo[r]), grid.cell_of(hi[r]));
            total += (0..dim).map(|ax| b[ax] - a[ax] + 1).product::<usize>();
            if total > ENTRIES_PER_BOX * roots.len() {
                return None;
            }
            grid.each_cell(a, b, |c| count[c + 1] += 1);
        }
        for c in 0..cells {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        let mut entries = vec![0usize; total];
        for &r in roots {
            let (a, b) = (grid.cell_of(lo[r]), grid.cell_of(hi[r]));
            grid.each_cell(a, b, |c| {
                entries[fill[c]] = r;
                fill[c] += 1;
            });
        }
        grid.start = count;
        grid.entries = entries;
        Some(grid)
    }

    /// The cell coordinates of a point, clamped to the grid.
    fn cell_of<V: Vector>(&self, p: V) -> [usize; 3] {
        let mut c = [0usize; 3];
        for (ax, c) in c.iter_mut().enumerate().take(V::DIM) {
            // The grid starts at the lowest corner, so this is not negative, and the cast
            // (which saturates) floors it without a call to `floor`.
            let k = (p.get(ax) - self.origin[ax]) / self.side;
            *c = (k as usize).min(self.dims[ax] - 1);
        }
        c
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    /// Calls `f` with every cell from `a` to `b` (inclusive, per axis).
    fn each_cell(&self, a: [usize; 3], b: [usize; 3], mut f: impl FnMut(usize)) {
        for z in a[2]..=b[2] {
            for y in a[1]..=b[1] {
                for x in a[0]..=b[0] {
                    f(self.index([x, y, z]));
                }
            }
        }
    }

    /// Calls `f` once with every pair of roots that share a cell and whose boxes' common low
    /// corner lies in it.
    fn pairs<V: Vector>(&self, lo: &[V], mut f: impl FnMut(usize, usize)) {
        for c in 0..self.start.len() - 1 {
            let here = &self.entries[self.start[c]..self.start[c + 1]];
            for (i, &a) in here.iter().enumerate() {
                for &b in &here[i + 1..] {
                    let mut corner = V::zero();
                    for ax in 0..V::DIM {
                        corner.set(ax, lo[a].get(ax).max(lo[b].get(ax)));
                    }
                    if self.index(self.cell_of(corner)) == c {
                        f(a, b);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec2, DVec3};

    /// A small generator, so the boxes are the same on every run.
    fn numbers(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Every meeting pair, by testing them all.
    fn all_pairs<V: Vector>(roots: &[usize], lo: &[V], hi: &[V]) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for (i, &a) in roots.iter().enumerate() {
            for &b in &roots[i + 1..] {
                let meet = (0..V::DIM)
                    .all(|ax| lo[a].get(ax) <= hi[b].get(ax) && lo[b].get(ax) <= hi[a].get(ax));
                let a_first = lo[a]
                    .get(0)
                    .total_cmp(&lo[b].get(0))
                    .then(a.cmp(&b))
                    .is_lt();
                if meet {
                    out.push(if a_first { (a, b) } else { (b, a) });
                }
            }
        }
        out.sort_unstable();
        out
    }

    /// Boxes of many small widths and a few large, some sharing an edge exactly; every other
    /// index is not a root.
    fn boxes<V: Vector>(n: usize, seed: u64) -> (Vec<usize>, Vec<V>, Vec<V>) {
        let mut next = numbers(seed);
        let (mut lo, mut hi) = (vec![V::zero(); 2 * n], vec![V::zero(); 2 * n]);
        let roots: Vec<usize> = (0..n).map(|k| 2 * k).collect();
        for &r in &roots {
            let wide = next() < 0.02;
            for ax in 0..V::DIM {
                let x = (100.0 * next()).round() / 2.0;
                let w = if wide {
                    40.0 * next()
                } else {
                    (4.0 * next()).round() / 2.0
                };
                lo[r].set(ax, x);
                hi[r].set(ax, x + w);
            }
        }
        (roots, lo, hi)
    }

    #[test]
    fn the_grid_finds_every_meeting_pair_once_in_the_sweep_s_orientation() {
        for seed in 1..=4 {
            for n in [10, GRID_FROM, 2000] {
                let (roots, lo, hi) = boxes::<DVec2>(n, seed);
                let mut found = meeting(&roots, &lo, &hi);
                found.sort_unstable();
                assert_eq!(found, all_pairs(&roots, &lo, &hi), "2D, {n} boxes");
                let (roots, lo, hi) = boxes::<DVec3>(n, seed);
                let mut found = meeting(&roots, &lo, &hi);
                found.sort_unstable();
                assert_eq!(found, all_pairs(&roots, &lo, &hi), "3D, {n} boxes");
            }
        }
    }

    #[test]
    fn many_large_boxes_fall_back_to_the_sweep() {
        let mut next = numbers(7);
        let n = 4 * GRID_FROM;
        let roots: Vec<usize> = (0..n).collect();
        let lo: Vec<DVec2> = (0..n).map(|_| DVec2::new(next(), next())).collect();
        let mut hi: Vec<DVec2> = lo.iter().map(|&l| l + DVec2::splat(0.01)).collect();
        for h in hi.iter_mut().take(n / 4) {
            *h += DVec2::splat(1.0); // a quarter of the boxes cover nearly everything
        }
        assert!(Grid::of(&roots, &lo, &hi).is_none());
        let mut found = meeting(&roots, &lo, &hi);
        found.sort_unstable();
        assert_eq!(found, all_pairs(&roots, &lo, &hi));
    }
}
