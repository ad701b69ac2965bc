//! The broad phase: candidate pairs are produced once each and include every pair that touches,
//! checked against brute-force distance tests; the grid agrees with the all-pairs loop for radii
//! varying a hundredfold, in 2D and 3D, walled and periodic; and the choice of algorithm does not
//! change the physics.

use critterbox::broad_phase::{BroadObject, BroadPhase, BroadPhaseMode};
use critterbox::glam::{DVec2, DVec3};
use critterbox::scenes::{gas, GasParams};
use critterbox::Topology;
use critterbox::{Border, Rng, Vector, World};
use std::collections::BTreeSet;

type Pairs = BTreeSet<(u32, u32)>;

/// Pairs as (low, high), checking that none was produced twice.
fn unique_pairs(raw: &[(u32, u32)], label: &str) -> Pairs {
    let set: Pairs = raw.iter().map(|&(a, b)| (a.min(b), a.max(b))).collect();
    assert_eq!(
        set.len(),
        raw.len(),
        "{label}: {} pairs produced more than once",
        raw.len() - set.len()
    );
    assert!(
        raw.iter().all(|&(a, b)| a != b),
        "{label}: an object paired with itself"
    );
    set
}

fn find<V: Vector>(
    mode: BroadPhaseMode,
    objs: &[BroadObject<V>],
    topo: &Topology<V>,
) -> Vec<(u32, u32)> {
    let mut bp = BroadPhase::new(mode);
    let mut out = Vec::new();
    bp.find_pairs(objs, topo, &mut out);
    out
}

/// `b - a` through the nearest periodic image when the topology wraps (computed here).
fn offset<V: Vector>(topo: &Topology<V>, a: V, b: V) -> V {
    let mut d = b - a;
    if topo.border == Border::Wrap {
        for axis in 0..V::DIM {
            let l = topo.max.get(axis) - topo.min.get(axis);
            d.set(axis, d.get(axis) - l * (d.get(axis) / l).round());
        }
    }
    d
}

/// Brute force: every pair of disks (objects with cubic boxes, `half` = radius) whose distance is
/// at most the sum of their radii, and every disk-wall pair whose boxes overlap.
fn touching<V: Vector>(objs: &[BroadObject<V>], topo: &Topology<V>) -> Pairs {
    let mut out = Pairs::new();
    for (i, a) in objs.iter().enumerate() {
        for b in &objs[i + 1..] {
            if a.is_wall && b.is_wall {
                continue;
            }
            let d = offset(topo, a.center, b.center);
            let hit = if a.is_wall || b.is_wall {
                (0..V::DIM).all(|axis| d.get(axis).abs() <= a.half.get(axis) + b.half.get(axis))
            } else {
                d.length() <= a.half.get(0) + b.half.get(0)
            };
            if hit {
                out.insert((a.slot.min(b.slot), a.slot.max(b.slot)));
            }
        }
    }
    out
}

/// Disks with log-uniform radii in [rmin, rmax], centres spread a little beyond the box unless it
/// wraps, plus a few long thin walls.
fn random_objects<V: Vector>(
    rng: &mut Rng,
    n: usize,
    topo: &Topology<V>,
    rmin: f64,
    rmax: f64,
) -> Vec<BroadObject<V>> {
    let spill = if topo.border == Border::Wrap {
        0.0
    } else {
        2.0
    };
    let mut objs = Vec::with_capacity(n + 8);
    let place = |rng: &mut Rng| {
        let mut c = V::zero();
        for axis in 0..V::DIM {
            c.set(
                axis,
                rng.uniform(topo.min.get(axis) - spill, topo.max.get(axis) + spill),
            );
        }
        c
    };
    for i in 0..n {
        let center = place(rng);
        let r = rmin * (rmax / rmin).powf(rng.uniform(0.0, 1.0));
        objs.push(BroadObject {
            center,
            half: V::splat(r),
            slot: i as u32,
            is_wall: false,
        });
    }
    for k in 0..8 {
        let center = place(rng);
        let mut half = V::splat(0.15);
        half.set(k % V::DIM, 0.3 * (topo.max.get(0) - topo.min.get(0)));
        objs.push(BroadObject {
            center,
            half,
            slot: (n + k) as u32,
            is_wall: true,
        });
    }
    objs
}

fn check_grid_against_all_pairs<V: Vector>(
    objs: &[BroadObject<V>],
    topo: &Topology<V>,
    label: &str,
) {
    let grid = unique_pairs(
        &find(BroadPhaseMode::Grid, objs, topo),
        &format!("{label}, grid"),
    );
    let all = unique_pairs(
        &find(BroadPhaseMode::AllPairs, objs, topo),
        &format!("{label}, all pairs"),
    );
    let truth = touching(objs, topo);
    assert!(
        truth.len() > 100,
        "{label}: test setup: many touching pairs"
    );
    let missed: Vec<_> = truth.difference(&grid).take(10).collect();
    assert!(
        missed.is_empty(),
        "{label}: touching pairs the grid missed: {missed:?}"
    );
    let walls: Vec<_> = grid
        .iter()
        .filter(|&&(a, b)| objs[a as usize].is_wall && objs[b as usize].is_wall)
        .collect();
    assert!(walls.is_empty(), "{label}: wall-wall pairs: {walls:?}");
    assert_eq!(grid, all, "{label}: grid and all-pairs disagree");
}

#[test]
fn grid_matches_all_pairs_and_finds_every_touching_pair_with_radii_varying_100_fold() {
    let mut rng = Rng::new(2024);
    for border in [Border::Bounce, Border::Wrap] {
        let topo = Topology {
            min: DVec2::new(-10.0, 0.0),
            max: DVec2::new(90.0, 60.0),
            border,
        };
        let objs = random_objects(&mut rng, 3000, &topo, 0.05, 5.0);
        check_grid_against_all_pairs(&objs, &topo, &format!("2D {border:?}"));
        let topo = Topology {
            min: DVec3::ZERO,
            max: DVec3::new(30.0, 25.0, 20.0),
            border,
        };
        let objs = random_objects(&mut rng, 2500, &topo, 0.03, 3.0);
        check_grid_against_all_pairs(&objs, &topo, &format!("3D {border:?}"));
    }
}

#[test]
fn grid_handles_uniform_radii_and_a_single_huge_object() {
    let mut rng = Rng::new(5);
    let topo = Topology {
        min: DVec2::ZERO,
        max: DVec2::splat(50.0),
        border: Border::Bounce,
    };
    let mut objs = random_objects(&mut rng, 2000, &topo, 0.5, 0.5);
    let n = objs.len() as u32;
    // One disk covering a third of the box: a level of its own, paired with everything under it.
    objs.push(BroadObject {
        center: DVec2::splat(25.0),
        half: DVec2::splat(8.0),
        slot: n,
        is_wall: false,
    });
    check_grid_against_all_pairs(&objs, &topo, "uniform plus one huge");
}

fn world_objects<V: Vector>(world: &World<V>) -> Vec<BroadObject<V>> {
    world
        .critters()
        .iter()
        .map(|c| BroadObject {
            center: c.pos,
            half: c.wall().map_or(V::splat(c.radius()), |w| w.aabb_half()),
            slot: c.id().index,
            is_wall: c.is_wall(),
        })
        .collect()
}

/// The standard 2D gas at N = 10,000: each step's candidate pairs are unique and include the
/// touching pairs; on the positions after the last steps (once the gas has started to collide:
/// the grid start leaves gaps of about one diameter) the grid finds every touching pair.
#[test]
fn gas_of_10000_candidate_pairs_are_unique_and_include_every_touching_pair() {
    let mut world = gas::<DVec2>(&GasParams {
        n: 10_000,
        ..GasParams::default()
    })
    .unwrap();
    let topo = *world.topology();
    for step in 0..45 {
        world.step().unwrap();
        let label = format!("step {step}");
        let candidates = unique_pairs(world.diagnostics().candidate_pairs, &label);
        assert_eq!(candidates.len(), world.stats().candidates);
        let contacts: Pairs = world
            .diagnostics()
            .contact_pairs
            .iter()
            .map(|&(a, b)| (a.min(b), a.max(b)))
            .collect();
        assert_eq!(
            contacts.len(),
            world.diagnostics().contact_pairs.len(),
            "{label}: a contact listed twice"
        );
        assert!(
            contacts.is_subset(&candidates),
            "{label}: a contact that was no candidate"
        );
        if step < 42 {
            continue;
        }
        // On the current positions, with the world's own objects (disks and walls).
        let objs = world_objects(&world);
        let grid = unique_pairs(&find(BroadPhaseMode::Grid, &objs, &topo), &label);
        let truth = touching(&objs, &topo);
        assert!(!truth.is_empty(), "{label}: test setup: some pairs touch");
        let missed: Vec<_> = truth.difference(&grid).take(10).collect();
        assert!(
            missed.is_empty(),
            "{label}: touching pairs the grid missed: {missed:?}"
        );
        if step == 44 {
            let all = unique_pairs(&find(BroadPhaseMode::AllPairs, &objs, &topo), &label);
            assert_eq!(grid, all, "{label}: grid and all-pairs disagree on the gas");
        }
    }
    assert!(
        world.totals().contacts > 100,
        "test setup: the gas collides"
    );
}

/// The response order is sorted by id, so the broad phase algorithm changes nothing.
fn same_physics<V: Vector>(border: critterbox::Border, n: usize, steps: usize) {
    let build = |mode| {
        gas::<V>(&GasParams {
            n,
            border,
            broad_phase: mode,
            ..GasParams::default()
        })
        .unwrap()
    };
    let (mut grid, mut all) = (build(BroadPhaseMode::Grid), build(BroadPhaseMode::AllPairs));
    let mut contacts = 0;
    for step in 0..steps {
        grid.step().unwrap();
        all.step().unwrap();
        assert_eq!(
            grid.diagnostics().contact_pairs,
            all.diagnostics().contact_pairs,
            "{}D {border:?} step {step}: contacts differ",
            V::DIM
        );
        assert_eq!(
            grid.state_hash(),
            all.state_hash(),
            "{}D {border:?} step {step}: states differ",
            V::DIM
        );
        contacts += grid.stats().contacts;
    }
    assert!(contacts > 0, "test setup: something collided");
}

#[test]
fn gas_with_grid_and_with_all_pairs_broad_phase_gives_identical_physics() {
    same_physics::<DVec2>(Border::Bounce, 1000, 60);
    same_physics::<DVec2>(Border::Wrap, 1000, 60);
    same_physics::<DVec3>(Border::Bounce, 500, 60);
    same_physics::<DVec3>(Border::Wrap, 500, 60);
}
