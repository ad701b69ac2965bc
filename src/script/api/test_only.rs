//! The test runner's functions, as a scene or kind script meets them: an error that says where
//! they work. A test runtime registers the real ones over these (`crate::testing`).

use super::registry::Api;
use super::world::WorldRef;
use super::{fail, Res};
use rhai::{Dynamic, FnPtr, Map, INT};

/// Where the test functions work, for `what`.
fn only_in_tests<T>(what: &str) -> Res<T> {
    fail(format!(
        "{what} works in test scripts (scripts/tests/); a scene runs with `critterbox run`"
    ))
}

pub(super) fn register(api: &mut Api) {
    api.engine
        .register_fn("step", |_: &mut WorldRef| -> Res<()> {
            only_in_tests("world.step(n)")
        });
    api.engine
        .register_fn("step", |_: &mut WorldRef, _: INT| -> Res<()> {
            only_in_tests("world.step(n)")
        });
    api.engine.register_fn(
        "run_until",
        |_: &mut WorldRef, _: FnPtr, _: INT| -> Res<INT> { only_in_tests("world.run_until") },
    );
    api.engine
        .register_fn("load_scene", |_: &str| -> Res<WorldRef> {
            only_in_tests("load_scene")
        });
    api.engine
        .register_fn("load_scene", |_: &str, _: Map| -> Res<WorldRef> {
            only_in_tests("load_scene")
        });
    api.engine
        .register_fn("kinetic_energy", |_: &mut WorldRef| -> Res<f64> {
            only_in_tests("world.kinetic_energy()")
        });
    api.engine
        .register_fn("momentum", |_: &mut WorldRef| -> Res<Dynamic> {
            only_in_tests("world.momentum()")
        });
    api.engine.register_fn(
        "expect_collision",
        |_: Dynamic, _: Dynamic, _: INT| -> Res<INT> { only_in_tests("expect_collision") },
    );
    api.engine
        .register_fn("expect_matches_recording", |_: &str| -> Res<()> {
            only_in_tests("expect_matches_recording")
        });
}
