//! The partition against brute force: every pair within reach in one island, and each island
//! joined by a chain of such pairs.

use super::*;
use crate::critter::CritterSpec;
use crate::world::{World, WorldConfig};
use glam::DVec2;

/// The reaches `partition` settles on, found by testing every pair: own speed first, then (when
/// the islands may be stepped apart: one held by nothing with two disks approaching, or some
/// held and some not) each island's energy, until no island joins.
fn brute_force(state: &State<DVec2>) -> Vec<Vec<u32>> {
    let (g, dt) = (state.gravity.length(), state.dt);
    let disks: Vec<(u32, &Critter<DVec2>)> = state
        .critters
        .slot_slice()
        .iter()
        .enumerate()
        .filter_map(|(i, c)| c.as_ref().map(|c| (i as u32, c)))
        .filter(|(_, c)| c.alive && !c.is_wall() && !c.fixed)
        .collect();
    let n = disks.len();
    let mut reaches: Vec<f64> = disks
        .iter()
        .map(|(_, c)| reach(c.vel.length(), g, dt))
        .collect();
    let mut label: Vec<usize> = (0..n).collect();
    let supports: Vec<Support<'_, DVec2>> = state
        .critters
        .iter()
        .filter(|c| c.alive && (c.is_wall() || c.fixed))
        .map(|critter| Support { critter })
        .collect();
    let mut first_pass = true;
    loop {
        // Components of the graph of pairs within reach, by repeated relabelling.
        let mut deepest = vec![0.0f64; n];
        loop {
            let mut changed = false;
            for a in 0..n {
                for b in 0..n {
                    let (ca, cb) = (disks[a].1, disks[b].1);
                    let gap = state.topo.delta(ca.pos, cb.pos).length() - ca.radius - cb.radius;
                    if a != b && gap <= reaches[a] + reaches[b] {
                        if gap < 0.0 {
                            deepest[a] = deepest[a].max(-gap);
                        }
                        let l = label[a].min(label[b]);
                        if label[a] != l || label[b] != l {
                            label[a] = l;
                            label[b] = l;
                            changed = true;
                        }
                    }
                }
            }
            if !changed {
                break;
            }
        }
        if first_pass {
            first_pass = false;
            // Held (by an edge or a support) and approaching, at own reaches, by island.
            let mut held = vec![false; n];
            let mut meets = vec![false; n];
            for a in 0..n {
                let c = disks[a].1;
                let d = Disk {
                    slot: disks[a].0,
                    pos: c.pos,
                    vel: c.vel,
                    radius: c.radius,
                    inv_mass: c.inv_mass(),
                    reach: reaches[a],
                    asleep: false,
                    elastic: true,
                };
                held[label[a]] |= supported(&state.topo, &supports, &d, RESTING_STEPS * g * dt);
                for b in 0..n {
                    let cb = disks[b].1;
                    let offset = state.topo.delta(c.pos, cb.pos);
                    let gap = offset.length() - c.radius - cb.radius;
                    if a != b
                        && gap <= reaches[a] + reaches[b]
                        && (cb.vel - c.vel).dot(offset) < 0.0
                    {
                        meets[label[a]] = true;
                    }
                }
            }
            let roots: Vec<usize> = (0..n).filter(|&r| label[r] == r).collect();
            let impact = roots.iter().any(|&r| !held[r] && meets[r]);
            let mixed = roots.iter().any(|&r| held[r]) && roots.iter().any(|&r| !held[r]);
            if !(impact || mixed) {
                break;
            }
        }
        let mut grew = false;
        for a in 0..n {
            let members: Vec<usize> = (0..n).filter(|&b| label[b] == label[a]).collect();
            let energy: f64 = members
                .iter()
                .map(|&b| 0.5 * disks[b].1.mass() * disks[b].1.vel.length_squared())
                .sum();
            let depth = members.iter().map(|&b| deepest[b]).fold(0.0, f64::max);
            let c = disks[a].1;
            let u = (2.0 * energy * c.inv_mass()).sqrt().max(c.vel.length());
            let r = reach(u, g, dt) + 2.0 * depth;
            if r > reaches[a] {
                reaches[a] = r;
                grew = true;
            }
        }
        if !grew {
            break;
        }
    }
    let mut islands: Vec<Vec<u32>> = Vec::new();
    for first in 0..n {
        if label[first] == first {
            islands.push(
                (0..n)
                    .filter(|&b| label[b] == first)
                    .map(|b| disks[b].0)
                    .collect(),
            );
        }
    }
    islands
}

/// A seeded scatter of `n` disks of radii 0.1 to 0.3 and speeds up to `speed` in a 10 x 10 box
/// (whose border wraps when `wrap`).
fn scatter(n: usize, speed: f64, seed: u64, wrap: bool) -> World<DVec2> {
    let mut config = WorldConfig::new(DVec2::ZERO, DVec2::splat(10.0))
        .dt(1.0 / 60.0)
        .gravity(DVec2::new(0.0, -9.81));
    if wrap {
        config = config.border(crate::border::Border::Wrap);
    }
    let mut w = World::new(config).expect("world");
    let mut state = seed;
    let mut rand = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..n {
        let pos = DVec2::new(0.3 + 9.4 * rand(), 0.3 + 9.4 * rand());
        let vel = DVec2::new(rand() - 0.5, rand() - 0.5) * 2.0 * speed;
        let spec = CritterSpec::ball(pos).vel(vel).radius(0.1 + 0.2 * rand());
        w.spawn(spec).expect("disk");
    }
    w
}

#[test]
fn islands_agree_with_brute_force_on_random_scenes() {
    let mut joined = 0;
    for seed in 0..12u64 {
        // Fast disks are wide (tested over the cells of their boxes, or against all), on a
        // border that wraps too.
        let cases = [
            (40, 0.5, false),
            (150, 2.0, false),
            (300, 0.1, false),
            (80, 20.0, false),
            (200, 8.0, true),
            (120, 60.0, true),
        ];
        for (n, speed, wrap) in cases {
            let w = scatter(n, speed, seed + 1, wrap);
            let found = partition(&w.state, &[], w.dt());
            let mut mine: Vec<Vec<u32>> = vec![Vec::new(); found.list.len()];
            for (slot, &i) in found.of_slot.iter().enumerate() {
                if i != NO_ISLAND {
                    mine[i as usize].push(slot as u32);
                }
            }
            let theirs = brute_force(&w.state);
            assert_eq!(
                mine, theirs,
                "seed {seed}, {n} disks at up to {speed}, wrap {wrap}"
            );
            for (island, listed) in mine.iter().zip(&found.list) {
                assert_eq!(listed.first, island[0]);
                assert_eq!(listed.size, island.len());
            }
            joined += mine.iter().filter(|i| i.len() > 1).count();
        }
    }
    assert!(
        joined > 0,
        "no island held two disks: the test would pass vacuously"
    );
}

#[test]
fn a_struck_cradle_in_mid_air_is_impacts_and_a_ball_on_the_floor_rests() {
    let mut w = World::new(
        WorldConfig::new(DVec2::ZERO, DVec2::new(20.0, 20.0))
            .dt(1.0 / 60.0)
            .gravity(DVec2::new(0.0, -9.81)),
    )
    .expect("world");
    // Touching balls at 10 high, the first striking the others: held by nothing.
    for i in 0..3 {
        let vel = DVec2::new(if i == 0 { 1.0 } else { 0.0 }, 0.0);
        w.spawn(
            CritterSpec::ball(DVec2::new(5.0 + i as f64, 10.0))
                .radius(0.5)
                .vel(vel),
        )
        .expect("ball");
    }
    // Touching balls at 15 high, at rest: none meets another.
    for i in 0..2 {
        w.spawn(CritterSpec::ball(DVec2::new(5.0 + i as f64, 15.0)).radius(0.5))
            .expect("ball");
    }
    // A ball on the box's floor, and one far from everything.
    w.spawn(CritterSpec::ball(DVec2::new(15.0, 0.5)).radius(0.5))
        .expect("ball");
    w.spawn(CritterSpec::ball(DVec2::new(15.0, 15.0)).radius(0.5))
        .expect("ball");
    let found = partition(&w.state, &[], w.dt());
    let regimes: Vec<(usize, Regime)> = found.list.iter().map(|i| (i.size, i.regime)).collect();
    assert_eq!(
        regimes,
        [
            (3, Regime::Impact),
            (2, Regime::Free),
            (1, Regime::Resting),
            (1, Regime::Free)
        ]
    );
}
