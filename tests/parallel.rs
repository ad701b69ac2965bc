//! Parallel stages give the same bits for any number of threads.

use critterbox::glam::{DVec2, DVec3};
use critterbox::scenes::{gas, GasParams};
use critterbox::world::PARALLEL_MIN;
use critterbox::Border;

fn run_in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}

fn hashes_2d(border: Border, steps: usize) -> Vec<u64> {
    let params = GasParams {
        n: PARALLEL_MIN + 5_000,
        border,
        packing: 0.35,
        ..GasParams::default()
    };
    let mut world = gas::<DVec2>(&params).expect("gas builds");
    (0..steps)
        .map(|_| {
            world.step().expect("steps");
            world.state_hash()
        })
        .collect()
}

#[test]
fn a_large_2d_gas_is_bit_identical_on_one_two_and_three_threads() {
    for border in [Border::Bounce, Border::Wrap] {
        let one = run_in_pool(1, || hashes_2d(border, 40));
        let two = run_in_pool(2, || hashes_2d(border, 40));
        let three = run_in_pool(3, || hashes_2d(border, 40));
        assert_eq!(one, two, "{border:?}: 1 and 2 threads differ");
        assert_eq!(one, three, "{border:?}: 1 and 3 threads differ");
    }
}

#[test]
fn a_large_3d_gas_is_bit_identical_on_one_and_two_threads() {
    let run = || {
        let params = GasParams {
            n: PARALLEL_MIN + 1_000,
            ..GasParams::default()
        };
        let mut world = gas::<DVec3>(&params).expect("gas builds");
        world.run(20).expect("steps");
        world.state_hash()
    };
    assert_eq!(run_in_pool(1, run), run_in_pool(2, run));
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
