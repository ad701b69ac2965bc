//! Seeded randomness: `rand()`, `rand(lo, hi)`, `rand_int(lo, hi)`, drawn from the world's own
//! generator so a run repeats with its seed.

use super::registry::Api;
use super::values::num_or;
use super::{fail, Res};
use crate::script::host::with_env;
use rhai::{Dynamic, INT};

pub(super) fn register(api: &mut Api) {
    api.func("rand", |h| {
        move || -> Res<f64> { with_env!(h, env => Ok(env.rng().next_f64())) }
    });
    api.func("rand", |h| {
        move |lo: Dynamic, hi: Dynamic| -> Res<f64> {
            let (lo, hi) = (
                num_or(&lo, "rand's low end")?,
                num_or(&hi, "rand's high end")?,
            );
            with_env!(h, env => Ok(env.rng().uniform(lo, hi)))
        }
    });
    api.func("rand_int", |h| {
        move |lo: INT, hi: INT| -> Res<INT> {
            if hi < lo {
                return fail(format!(
                    "rand_int({lo}, {hi}): the high end is below the low end"
                ));
            }
            let span = (hi - lo) as u64 + 1;
            with_env!(h, env => Ok(lo + (env.rng().next_u64() % span) as INT))
        }
    });
}
