//! ms per step of the standard 2D gas (radius 0.5, packing fraction 0.2, dt 1/60, restitution 1,
//! walled square box, grid start, velocities uniform in [-1, 1]) with the grid broad phase against
//! the naive all-pairs loop, in one run; and the small-N crossover that sets `SMALL_N`.
//!
//! `cargo bench --bench step`; `docs/performance.md` says how to read the results.
//! `CRITTERBOX_BENCH_QUICK=1` skips the naive loop at N = 1e5 (about 10 s per step).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use critterbox::broad_phase::BroadPhaseMode;
use critterbox::glam::{DVec2, DVec3};
use critterbox::scenes::{gas, GasParams};
use std::hint::black_box;
use std::time::Duration;

fn gas2d(n: usize, mode: BroadPhaseMode) -> critterbox::World<DVec2> {
    let params = GasParams {
        n,
        broad_phase: mode,
        ..GasParams::default()
    };
    gas::<DVec2>(&params).expect("the standard gas builds")
}

fn gas_step(c: &mut Criterion) {
    let quick = std::env::var_os("CRITTERBOX_BENCH_QUICK").is_some();
    let mut group = c.benchmark_group("gas2d_step");
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(3));
    for n in [1_000usize, 10_000, 100_000] {
        for (name, mode) in [
            ("grid", BroadPhaseMode::Auto),
            ("naive", BroadPhaseMode::AllPairs),
        ] {
            if quick && n == 100_000 && mode == BroadPhaseMode::AllPairs {
                continue;
            }
            let mut world = gas2d(n, mode);
            group.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
                b.iter(|| world.step().expect("gas steps"));
            });
            black_box(world.state_hash());
        }
    }
    group.finish();
}

fn gas3d_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("gas3d_step");
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(3));
    for n in [1_000usize, 10_000, 100_000] {
        let params = GasParams {
            n,
            ..GasParams::default()
        };
        let mut world = gas::<DVec3>(&params).expect("the standard gas builds");
        group.bench_with_input(BenchmarkId::new("grid", n), &n, |b, _| {
            b.iter(|| world.step().expect("gas steps"));
        });
    }
    group.finish();
}

/// Where the direct loop stops beating the grid (sets `broad_phase::SMALL_N`).
fn small_n(c: &mut Criterion) {
    let mut group = c.benchmark_group("small_n");
    group.sample_size(20);
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_secs(1));
    for n in [8usize, 16, 32, 48, 64, 96, 128, 256] {
        for (name, mode) in [
            ("grid", BroadPhaseMode::Grid),
            ("direct", BroadPhaseMode::AllPairs),
        ] {
            let mut world = gas2d(n, mode);
            group.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
                b.iter(|| world.step().expect("gas steps"));
            });
        }
    }
    group.finish();
}

criterion_group!(benches, gas_step, gas3d_step, small_n);
criterion_main!(benches);
