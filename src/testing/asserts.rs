//! `expect_collision`, the expectation that steps the test's world (the other checks are the
//! script layer's own: `script::api::checks`).

use super::run::TestRun;
use super::world::{step_count, step_scene, with_scene};
use crate::scenes::AnyWorld;
use crate::script::api::checks::describe;
use crate::script::api::Api;
use crate::script::api::{fail, CritterRef, Res};
use rhai::INT;
use std::rc::Rc;

/// True when `a` and `b` collided in the last step, either calling.
fn collided(world: &AnyWorld, a: CritterRef, b: CritterRef) -> bool {
    fn hit<V>(
        events: &[crate::step::events::CollisionEvent<V>],
        a: CritterRef,
        b: CritterRef,
    ) -> bool {
        events
            .iter()
            .any(|e| (e.caller == a.0 && e.arg == b.0) || (e.caller == b.0 && e.arg == a.0))
    }
    match world {
        AnyWorld::D2(w) => hit(&w.events().collisions, a, b),
        AnyWorld::D3(w) => hit(&w.events().collisions, a, b),
    }
}

pub(super) fn register(api: &mut Api, run: &Rc<TestRun>) {
    let test = run.clone();
    api.func("expect_collision", |h| move |a: CritterRef, b: CritterRef, within: INT| -> Res<INT> {
        let start = step_count(&h);
        let (da, db) = (describe(&h, a), describe(&h, b));
        for taken in 1..=within.max(0) {
            step_scene(&h, &test, 1)?;
            if with_scene(&h, |s| collided(&s.world, a, b))? {
                return Ok(taken);
            }
        }
        fail(format!(
            "expected {da} and {db} to collide within {within} steps (steps {start} to {}), but they did not",
            step_count(&h)
        ))
    });
}
