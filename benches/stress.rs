//! Per-critter step cost of scenes that are hard on the broad phase, against the standard gas,
//! in one run, all with 10,000 disks in a walled square box:
//!
//! * `uniform`: the standard gas (radius 0.5, packing fraction 0.2);
//! * `radii_x100`: radii spread log-uniformly over a factor of 100 (0.05 to 5), packing 0.2,
//!   placed at random, largest first (and `radii_x100_grid`, the same with the grid rebuilt
//!   every step instead of the Verlet list);
//! * `pile_9_layers`, `pile_90_layers`: disks of radius 0.5 dropped under gravity (restitution
//!   0.5) in a box 1000 or 100 wide and settled for 900 steps into a pile about 9 or 90 layers
//!   deep, so nearly every disk touches its neighbours (and `pile_9_layers_solve_8`, the
//!   9-layer pile dropped, settled and stepped under `solve:8`, its contacts solved together:
//!   settled, it sleeps, as it would in Box2D or Rapier; `pile_9_layers_solve_8_awake` is the
//!   same with sleep off, every contact solved every step; `pile_90_layers_solve_8` the deep
//!   pile under `solve:8`, which never comes to rest; `pile_90_layers_solve_32` the deep pile
//!   under `solve:32`, settled for 1,800 steps: 32 sweeps carry 90 layers' weight, and it sleeps;
//!   `pile_90_layers_auto` the deep pile under `auto`, settled for 1,800 steps: it counts the
//!   pile's depth and gives its solve the sweeps that carry it, and the pile sleeps).
//!
//! `cargo bench --bench stress`; `docs/performance.md` has the figures. The target is each
//! scene within 3x of the uniform gas per critter.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use critterbox::glam::DVec2;
use critterbox::scenes::{gas, GasParams};
use critterbox::DEFAULT_WALL_THICKNESS;
use critterbox::{BroadPhaseMode, CritterSpec, Method, Rng, WallBox, World, WorldConfig};
use std::f64::consts::PI;
use std::time::Duration;

const N: usize = 10_000;

/// An empty world walled around the box [0, w] x [0, h].
fn walled(w: f64, h: f64, gravity: DVec2, mode: BroadPhaseMode) -> World<DVec2> {
    let t = DEFAULT_WALL_THICKNESS;
    let config = WorldConfig::new(DVec2::splat(-t - 0.5), DVec2::new(w + t + 0.5, h + t + 0.5))
        .gravity(gravity)
        .broad_phase(mode)
        .seed(1);
    let mut world = World::new(config).expect("a world");
    for (lo, hi) in [
        (DVec2::new(-t, -t), DVec2::new(0.0, h + t)),
        (DVec2::new(w, -t), DVec2::new(w + t, h + t)),
        (DVec2::new(-t, -t), DVec2::new(w + t, 0.0)),
        (DVec2::new(-t, h), DVec2::new(w + t, h + t)),
    ] {
        world
            .add_wall(WallBox::aligned(lo, hi).expect("a wall box"))
            .expect("a wall");
    }
    world
}

fn uniform() -> World<DVec2> {
    gas::<DVec2>(&GasParams {
        n: N,
        ..GasParams::default()
    })
    .expect("the standard gas builds")
}

/// Radii log-uniform in [0.05, 5], packing fraction 0.2, random free positions (largest first,
/// found with a coarse grid of already placed disks), velocities uniform in [-1, 1].
fn radii_x100() -> World<DVec2> {
    radii_x100_with(BroadPhaseMode::Auto)
}

fn radii_x100_with(mode: BroadPhaseMode) -> World<DVec2> {
    let (r_min, ratio) = (0.05, 100.0f64);
    let mut rng = Rng::new(7);
    let mut radii: Vec<f64> = (0..N).map(|_| r_min * ratio.powf(rng.next_f64())).collect();
    radii.sort_by(|a, b| b.total_cmp(a));
    let area: f64 = radii.iter().map(|r| PI * r * r).sum();
    let side = (area / 0.2).sqrt();
    let cell = 2.0 * radii[0];
    let cells = (side / cell).ceil() as usize;
    let mut grid: Vec<Vec<(DVec2, f64)>> = vec![Vec::new(); cells * cells];
    let at = |p: DVec2| {
        let c = |x: f64| ((x / cell) as usize).min(cells - 1);
        (c(p.x), c(p.y))
    };
    let mut world = walled(side, side, DVec2::ZERO, mode);
    for &r in &radii {
        let pos = loop {
            let p = DVec2::new(rng.uniform(r, side - r), rng.uniform(r, side - r));
            let (cx, cy) = at(p);
            let free = (cx.saturating_sub(1)..=(cx + 1).min(cells - 1)).all(|x| {
                (cy.saturating_sub(1)..=(cy + 1).min(cells - 1)).all(|y| {
                    grid[y * cells + x]
                        .iter()
                        .all(|&(q, s)| p.distance(q) > r + s)
                })
            });
            if free {
                break p;
            }
        };
        let (cx, cy) = at(pos);
        grid[cy * cells + cx].push((pos, r));
        let vel = DVec2::new(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0));
        world
            .spawn(CritterSpec::ball(pos).vel(vel).radius(r))
            .expect("a disk");
    }
    world
}

/// Disks of radius 0.5 on a loose grid (spacing 1.5) in a box `w` wide, dropped under gravity
/// with restitution 0.5 and settled for 900 steps.
fn pile(w: f64) -> World<DVec2> {
    pile_under(w, Method::Discrete, false, 900)
}

/// [`pile`], dropped, settled for `settle` steps and stepped under `method`, with sleep on or
/// off.
fn pile_under(w: f64, method: Method, sleep: bool, settle: u64) -> World<DVec2> {
    let spacing = 1.5;
    let per_row = (w / spacing) as usize;
    let rows = N.div_ceil(per_row);
    let h = rows as f64 * spacing + 2.0;
    let mut world = walled(w, h, DVec2::new(0.0, -9.81), BroadPhaseMode::Auto);
    world.set_method(method).expect("a method");
    world.set_sleep(sleep);
    let mut rng = Rng::new(3);
    for i in 0..N {
        let pos = DVec2::new(
            (i % per_row) as f64 * spacing + 0.75,
            (i / per_row) as f64 * spacing + 0.75,
        );
        let vel = DVec2::new(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0));
        world
            .spawn(CritterSpec::ball(pos).vel(vel).radius(0.5).restitution(0.5))
            .expect("a disk");
    }
    world.run(settle).expect("the pile settles");
    world
}

fn stress(c: &mut Criterion) {
    let mut group = c.benchmark_group("stress_step");
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(3));
    for (name, build) in [
        ("uniform", uniform as fn() -> World<DVec2>),
        ("radii_x100", radii_x100),
        ("radii_x100_grid", || radii_x100_with(BroadPhaseMode::Grid)),
        ("pile_9_layers", || pile(1000.0)),
        ("pile_90_layers", || pile(100.0)),
        ("pile_9_layers_solve_8", || {
            pile_under(1000.0, Method::Solve(8), true, 900)
        }),
        ("pile_9_layers_solve_8_awake", || {
            pile_under(1000.0, Method::Solve(8), false, 900)
        }),
        ("pile_90_layers_solve_8", || {
            pile_under(100.0, Method::Solve(8), true, 900)
        }),
        ("pile_90_layers_solve_32", || {
            pile_under(100.0, Method::Solve(32), true, 1800)
        }),
        ("pile_90_layers_auto", || {
            pile_under(100.0, Method::Auto, true, 1800)
        }),
    ] {
        let mut world = build();
        group.bench_with_input(BenchmarkId::new(name, N), &N, |b, _| {
            b.iter(|| world.step().expect("steps"));
        });
        let stats = world.stats();
        eprintln!(
            "{name}: {} critters ({} asleep), {} contacts and {} pair tests in the last step, {} list rebuilds, {} repairs",
            world.critters().len(),
            world.sleepers(),
            stats.contacts,
            stats.pair_tests,
            world.diagnostics().list_rebuilds,
            world.diagnostics().list_repairs
        );
    }
    group.finish();
}

criterion_group!(benches, stress);
criterion_main!(benches);
