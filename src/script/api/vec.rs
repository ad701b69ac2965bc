//! `Vec`: a 3-vector with operators and the usual functions; 2D worlds ignore z, and print
//! vectors with two components.

use super::registry::Api;
use super::values::{guess_dim, num_or, show_vec};
use super::Res;
use crate::script::env::Env;
use crate::script::host::with_env;
use crate::vector::Vector;
use glam::DVec3;
use rhai::{Dynamic, EvalAltResult, INT};

pub(super) fn register(api: &mut Api) {
    api.engine.register_type_with_name::<DVec3>("Vec");
    api.engine
        .register_fn("vec", |x: Dynamic, y: Dynamic| -> Res<DVec3> {
            Ok(DVec3::new(num_or(&x, "x")?, num_or(&y, "y")?, 0.0))
        });
    api.engine
        .register_fn("vec", |x: Dynamic, y: Dynamic, z: Dynamic| -> Res<DVec3> {
            Ok(DVec3::new(
                num_or(&x, "x")?,
                num_or(&y, "y")?,
                num_or(&z, "z")?,
            ))
        });
    api.engine
        .register_get_set("x", |v: &mut DVec3| v.x, |v: &mut DVec3, x: f64| v.x = x);
    api.engine
        .register_get_set("y", |v: &mut DVec3| v.y, |v: &mut DVec3, y: f64| v.y = y);
    api.engine
        .register_get_set("z", |v: &mut DVec3| v.z, |v: &mut DVec3, z: f64| v.z = z);
    api.engine.register_fn("+", |a: DVec3, b: DVec3| a + b);
    api.engine.register_fn("-", |a: DVec3, b: DVec3| a - b);
    api.engine.register_fn("-", |a: DVec3| -a);
    api.engine.register_fn("*", |a: DVec3, k: f64| a * k);
    api.engine.register_fn("*", |k: f64, a: DVec3| a * k);
    api.engine.register_fn("*", |a: DVec3, k: INT| a * k as f64);
    api.engine.register_fn("*", |k: INT, a: DVec3| a * k as f64);
    api.engine.register_fn("/", |a: DVec3, k: f64| a / k);
    api.engine.register_fn("/", |a: DVec3, k: INT| a / k as f64);
    api.engine.register_fn("==", |a: DVec3, b: DVec3| a == b);
    api.engine.register_fn("!=", |a: DVec3, b: DVec3| a != b);
    api.engine
        .register_fn("+=", |a: &mut DVec3, b: DVec3| *a += b);
    api.engine
        .register_fn("-=", |a: &mut DVec3, b: DVec3| *a -= b);
    api.engine.register_fn("length", |a: &mut DVec3| a.length());
    api.engine
        .register_fn("length_squared", |a: &mut DVec3| a.length_squared());
    api.engine
        .register_fn("normalize", |a: &mut DVec3| a.normalize_or_zero());
    api.engine
        .register_fn("dot", |a: &mut DVec3, b: DVec3| a.dot(b));
    api.engine
        .register_fn("cross", |a: &mut DVec3, b: DVec3| a.cross(b));
    api.engine
        .register_fn("distance", |a: &mut DVec3, b: DVec3| a.distance(b));
    api.engine
        .register_fn("perp", |a: &mut DVec3| DVec3::new(-a.y, a.x, 0.0));
    api.engine
        .register_fn("rotate", |a: &mut DVec3, angle: f64| {
            let (s, c) = angle.sin_cos();
            DVec3::new(c * a.x - s * a.y, s * a.x + c * a.y, a.z)
        });
    // Printed as users write vectors, in the world's dimension: `(5, NaN)` in 2D.
    let h = api.host();
    let show = move |a: &mut DVec3| -> String {
        let dim = with_env!(h, env => Ok::<_, Box<EvalAltResult>>(dim_of(env)));
        show_vec(*a, dim.unwrap_or_else(|_| guess_dim(*a)))
    };
    api.engine.register_fn("to_string", show.clone());
    api.engine.register_fn("to_debug", show);
}

/// The dimension of the world behind `env`.
fn dim_of<V: Vector>(_: &mut Env<'_, V>) -> usize {
    V::DIM
}
