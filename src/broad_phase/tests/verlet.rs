//! The Verlet list's unit tests: kept, led, mended and given up for the plain grid, it finds
//! every step what all pairs find.

use super::super::objects::LeadBoxes;
use super::super::verlet::{merge_tail, typical_width, GRID_SPELL, SHORT_LIVED};
use super::*;

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
/// nobody is more than twice the median): outside a crowd every object whose `LEAD_STEPS`
/// strides pass half the skin is led and the list lasts about `LEAD_STEPS` steps; in a crowd (a
/// pile, where strides do not show the moves) only objects over `CROWD_LEAD_OVER_MEDIAN` times
/// the median are, none here, and it is rebuilt every few steps. Both find every pair.
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
        assert_eq!(bp.built_levels.len(), 2);
        // Each level keeps its members' tags, and neither their boxes nor their keys.
        let mut members = 0;
        for &l in &bp.built_levels {
            let level = &bp.levels[l];
            assert_eq!(level.boxes.capacity(), 0, "level {l}'s boxes");
            assert_eq!(level.keys.capacity(), 0, "level {l}'s keys");
            members += level.tags.len();
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
        let led = LeadBoxes {
            objs: &Striding {
                objs: &objs,
                steps: &told,
            },
            half_skin,
            led_above: 0.0,
        };
        let bound = CellBox::bound(led.object(0).as_ref(), half_skin);
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
