//! The broad phase's unit tests: the rounding of the single-precision boxes, the grid against
//! all pairs, and the counting sort and the walks in parallel against one thread. The Verlet
//! list's are in `verlet`.

use super::cell_box::{at_most, cells_overlap, CellBox};
use super::grid::{pow2, RUNS_AT_ONCE, RUN_OBJECTS};
use super::level::floor_to_i64;
use super::objects::overlaps;
use super::*;
use crate::border::Border;
use crate::rng::Rng;
use glam::{DVec2, DVec3};

mod verlet;

/// The pair of `objs` at indices `(i, j)` by slot, if both are objects and their boxes overlap.
fn exact_pair<V: Vector, O: Objects<V> + ?Sized>(
    objs: &O,
    topo: &Topology<V>,
    &(i, j): &(u32, u32),
) -> Option<(u32, u32)> {
    let (a, b) = (objs.object(i as usize)?, objs.object(j as usize)?);
    overlaps(topo, &a, &b).then_some((a.slot, b.slot))
}

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
        let bound = CellBox::bound(Some(&at(center, half)), pad);
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
        let gap = CellBox::bound(None, pad);
        assert!(gap.holds(&topo, None), "a gap in a gap's place");
        assert!(
            !gap.holds(&topo, Some(&at(center, half))),
            "an object in a gap's place"
        );
    }
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
        for &l in &bp.built_levels {
            let level = &bp.levels[l];
            for (b, &key) in level.boxes.iter().zip(&level.keys) {
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
        crate::parallel::PARALLEL_MIN + 7_000,
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
                .built_levels
                .iter()
                .map(|&l| {
                    let level = &bp.levels[l];
                    let tags = level.boxes.iter().map(|b| b.tag).collect();
                    (level.start.clone(), level.keys.clone(), tags)
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
    assert_eq!(bp.candidates, whole);
    assert_eq!(bp.tests, tests + whole.len() as u64);
    let exact_pairs: Vec<(u32, u32)> = whole
        .iter()
        .filter_map(|pair| exact_pair(objs.as_slice(), &topo, pair))
        .collect();
    assert_eq!(out, exact_pairs);
    assert_eq!(found(1).1, out);
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
