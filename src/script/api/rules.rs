//! Who collides with whom: the priority and collide-rule constants (`CP_BULLET`,
//! `COLLIDE_AS_CALLER`, ...) and `default_collides_with(a, b)`.

use super::critter::{gone, CritterRef};
use super::registry::Api;
use super::Res;
use crate::critter::PRIORITY_NAMES;
use crate::kind::CollideRule;
use crate::script::host::with_env;
use rhai::{Module, INT};

/// The integer scripts use for a rule.
pub(crate) fn rule_code(rule: CollideRule) -> INT {
    match rule {
        CollideRule::DontCollide => 0,
        CollideRule::AsCaller => 1,
        CollideRule::AsArg => 2,
        CollideRule::EitherWay => 3,
    }
}

/// The rule an integer from a script stands for.
pub(crate) fn rule_of_code(code: INT) -> Option<CollideRule> {
    CollideRule::NAMES
        .iter()
        .map(|&(_, r)| r)
        .find(|&r| rule_code(r) == code)
}

pub(super) fn register(api: &mut Api) {
    let mut module = Module::new();
    for (name, value) in PRIORITY_NAMES {
        module.set_var(name, value);
    }
    for (name, rule) in CollideRule::NAMES {
        module.set_var(name, rule_code(rule));
    }
    api.engine.register_global_module(module.into());

    api.func("default_collides_with", |h| {
        move |a: CritterRef, b: CritterRef| -> Res<INT> {
            with_env!(h, env => match (env.critter(a.0), env.critter(b.0)) {
                (Some(x), Some(y)) => Ok(rule_code(crate::kind::default_collides_with(x, y))),
                _ => Err(gone(if env.critter(a.0).is_none() { a.0 } else { b.0 })),
            })
        }
    });
}
