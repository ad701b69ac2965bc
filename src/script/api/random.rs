//! Seeded randomness: `rand()`, `rand(lo, hi)`, `rand_int(lo, hi)`, drawn from the world's own
//! generator so a run repeats with its seed.

use super::values::num_or;
use super::{fail, Res};
use crate::script::host::{with_env, Host};
use rhai::{Dynamic, Engine, INT};
use std::rc::Rc;

pub(super) fn register(engine: &mut Engine, host: &Rc<Host>) {
    let h = host.clone();
    engine.register_fn("rand", move || -> Res<f64> {
        with_env!(h, env => Ok(env.rng().next_f64()))
    });
    let h = host.clone();
    engine.register_fn("rand", move |lo: Dynamic, hi: Dynamic| -> Res<f64> {
        let (lo, hi) = (
            num_or(&lo, "rand's low end")?,
            num_or(&hi, "rand's high end")?,
        );
        with_env!(h, env => Ok(env.rng().uniform(lo, hi)))
    });
    let h = host.clone();
    engine.register_fn("rand_int", move |lo: INT, hi: INT| -> Res<INT> {
        if hi < lo {
            return fail(format!(
                "rand_int({lo}, {hi}): the high end is below the low end"
            ));
        }
        let span = (hi - lo) as u64 + 1;
        with_env!(h, env => Ok(lo + (env.rng().next_u64() % span) as INT))
    });
}
