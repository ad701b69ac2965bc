//! Parallel stages give the same bits for any number of threads.

use critterbox::glam::{DVec2, DVec3};
use critterbox::scenes::{gas, GasParams};
use critterbox::PARALLEL_MIN;
use critterbox::{Border, Vector};

fn run_in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}

/// The state hash after each of `steps` steps of a gas of `params`, run on `threads` threads.
fn gas_hashes<V: Vector>(params: &GasParams, steps: usize, threads: usize) -> Vec<u64> {
    run_in_pool(threads, || {
        let mut world = gas::<V>(params).expect("gas builds");
        (0..steps)
            .map(|_| {
                world.step().expect("steps");
                world.state_hash()
            })
            .collect()
    })
}

/// A gas of `params` has the same hash after every step on each of `threads` as on one thread.
fn check_same_bits_on<V: Vector>(params: &GasParams, steps: usize, threads: &[usize], label: &str) {
    let one = gas_hashes::<V>(params, steps, 1);
    for &n in threads {
        assert_eq!(
            one,
            gas_hashes::<V>(params, steps, n),
            "{label}: 1 and {n} threads differ"
        );
    }
}

#[test]
fn a_large_gas_is_bit_identical_on_any_number_of_threads() {
    for border in [Border::Bounce, Border::Wrap] {
        let params = GasParams {
            n: PARALLEL_MIN + 5_000,
            border,
            packing: 0.35,
            ..GasParams::default()
        };
        check_same_bits_on::<DVec2>(&params, 40, &[2, 3], &format!("2D, {border:?}"));
    }
    let params = GasParams {
        n: PARALLEL_MIN + 1_000,
        ..GasParams::default()
    };
    check_same_bits_on::<DVec3>(&params, 20, &[2], "3D");
}

#[test]
fn a_large_2d_gas_under_solve_is_bit_identical_on_one_and_two_threads() {
    let run = || {
        let params = GasParams {
            n: PARALLEL_MIN + 1_000,
            packing: 0.45,
            ..GasParams::default()
        };
        let mut world = gas::<DVec2>(&params).expect("gas builds");
        world
            .set_method(critterbox::Method::Solve(4))
            .expect("a method");
        world.run(20).expect("steps");
        (world.state_hash(), world.totals().contacts)
    };
    let (one, two) = (run_in_pool(1, run), run_in_pool(2, run));
    assert_eq!(one, two);
    assert!(one.1 > 0, "the gas collides");
}

/// A layer of balls on a floor, more than [`PARALLEL_MIN`] of them, falls asleep under `solve:4`
/// (the move runs in parallel chunks that must leave sleepers alone); then a few are kicked up
/// and wake their islands. The same bits on one and two threads.
#[test]
fn a_large_sleeping_layer_is_bit_identical_on_one_and_two_threads() {
    use critterbox::WallBox;
    use critterbox::{CritterSpec, Method, World, WorldConfig};
    let n = PARALLEL_MIN + 500;
    let run = || {
        let width = n as f64 * 1.5;
        let config = WorldConfig::new(DVec2::new(-1.0, -1.0), DVec2::new(width + 1.0, 10.0))
            .gravity(DVec2::new(0.0, -9.81))
            .method(Method::Solve(4));
        let mut w = World::new(config).expect("a world");
        w.add_wall(WallBox::aligned(DVec2::new(-1.0, -1.0), DVec2::new(width + 1.0, 0.0)).unwrap())
            .expect("a floor");
        // Pairs of touching balls along the floor, each pair its own island.
        let ids: Vec<_> = (0..n)
            .map(|i| {
                let x = 0.5 + (i / 2) as f64 * 3.0 + (i % 2) as f64 * 0.999;
                w.spawn(CritterSpec::ball(DVec2::new(x, 0.5)).radius(0.5))
                    .expect("a ball")
            })
            .collect();
        w.run(40).expect("steps");
        let asleep = w.sleepers();
        for &id in ids.iter().step_by(97) {
            w.get_mut(id).expect("a ball").vel = DVec2::new(0.3, 2.0);
        }
        w.run(10).expect("steps");
        (asleep, w.sleepers(), w.state_hash())
    };
    let (one, two) = (run_in_pool(1, run), run_in_pool(2, run));
    assert_eq!(one, two);
    assert_eq!(one.0, n, "the whole layer sleeps");
    let kicked = n.div_ceil(97);
    assert!(
        one.1 <= n - kicked && one.1 >= n - 2 * kicked,
        "the kicked balls and their partners wake: {} asleep of {n}",
        one.1
    );
}
