//! What the layout of the critters in memory is worth ([`critterbox::Locality`]): the standard
//! 2D gas, and the same critters spawned in a shuffled order (as a script that places its
//! critters in any order would), each run with the default layout and with none, in alternating
//! rounds of one process. Every pair of runs gives the same state hash (checked here).
//!
//! `cargo bench --bench layout`; `LAYOUT_N` (default 1,000,000), `LAYOUT_STEPS` (600) and
//! `LAYOUT_ROUNDS` (2) change the run. Prints ms per step; `docs/performance.md` has the figures.

use critterbox::glam::DVec2;
use critterbox::scenes::{gas, GasParams};
use critterbox::{CritterSpec, Locality, Rng, World, WorldConfig};
use std::time::Instant;

fn setting(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The standard gas of `n` disks, its disks spawned in the grid's order or shuffled.
fn build(n: usize, shuffled: bool) -> World<DVec2> {
    let grid: World<DVec2> = gas(&GasParams {
        n,
        ..GasParams::default()
    })
    .expect("the gas");
    if !shuffled {
        return grid;
    }
    let topo = grid.topology();
    let config = WorldConfig::new(topo.min, topo.max)
        .border(topo.border)
        .dt(grid.dt())
        .seed(grid.seed());
    let mut world = World::new(config).expect("a world");
    let mut disks = Vec::new();
    for c in grid.critters().iter() {
        match c.wall() {
            Some(wall) => {
                world.add_wall(wall.clone()).expect("a wall");
            }
            None => disks.push(
                CritterSpec::ball(c.pos)
                    .vel(c.vel)
                    .radius(c.radius())
                    .restitution(c.restitution()),
            ),
        }
    }
    // Fisher-Yates with a seeded generator.
    let mut rng = Rng::new(7);
    for i in (1..disks.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        disks.swap(i, j);
    }
    world.reserve(disks.len()).expect("memory for the disks");
    for spec in disks {
        world.spawn(spec).expect("a disk");
    }
    world
}

/// ms per step over `steps`, and the state hash after.
fn run(n: usize, shuffled: bool, layout: bool, steps: usize) -> (f64, u64) {
    let mut world = build(n, shuffled);
    if !layout {
        world.set_locality(Locality {
            every: 0,
            ..critterbox::world::LOCALITY
        });
    }
    let clock = Instant::now();
    for _ in 0..steps {
        world.step().expect("a step");
    }
    let ms = clock.elapsed().as_secs_f64() * 1e3 / steps as f64;
    (ms, world.state_hash())
}

fn main() {
    // `cargo bench` passes `--bench`; `cargo test --benches` runs this as a quick check.
    let quick = !std::env::args().any(|a| a == "--bench");
    let n = setting("LAYOUT_N", if quick { 60_000 } else { 1_000_000 });
    let steps = setting("LAYOUT_STEPS", if quick { 201 } else { 600 });
    let rounds = setting("LAYOUT_ROUNDS", if quick { 1 } else { 2 });
    println!(
        "layout bench: {n} disks, {steps} steps, {rounds} rounds, {} threads",
        rayon::current_num_threads()
    );
    for round in 0..rounds {
        for shuffled in [false, true] {
            let (on, hash_on) = run(n, shuffled, true, steps);
            let (off, hash_off) = run(n, shuffled, false, steps);
            assert_eq!(hash_on, hash_off, "the layout changed the run");
            println!(
                "round {round}: {:<9} laid out {on:8.3} ms/step, not laid out {off:8.3} ms/step ({:.2}x)",
                if shuffled { "shuffled" } else { "grid" },
                off / on
            );
        }
    }
}
