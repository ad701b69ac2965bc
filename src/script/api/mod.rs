//! The script API: one factory ([`build_engine`]) that makes the rhai engine with every type,
//! function and constant scripts see, sandboxed and limited. Each capability registers itself
//! from its own file:
//!
//! - [`vec`]: `Vec`, a vector with operators (2D worlds ignore z);
//! - [`critter`]: `Critter`, a handle to a critter: reading or writing its fields goes to the
//!   world;
//! - [`world`]: `World`, the running world: time, counts, the log (`print` and `debug` too);
//! - [`vars`]: `world().vars`, the state a scene, its kinds and its tests share;
//! - [`neighbours`]: `me.nearby(r)`, `me.nearest(kind)`, `world().nearby(pos, r)`;
//! - [`random`]: seeded randomness from the world's generator;
//! - [`rules`]: the priority and collide-rule constants, `default_collides_with`;
//! - [`hooks`]: `Contact`, the `parent_*` calls, `me.age`;
//! - [`kind_decl`]: what a kind file's top level declares (`extends`, `defaults`);
//! - [`scene`]: building a scene's world: `world(#{ ... })`, walls, spawning patterns, `spawn`.
//!
//! [`step_ops`] is the operations budget of a step (`--max-step-ops`).
//!
//! [`values`] converts between script values and the engine's, and [`spawn`] turns spawn maps
//! into spawns; both serve the capabilities above.

pub(crate) mod checks;
mod critter;
mod hooks;
mod kind_decl;
mod neighbours;
mod random;
mod registry;
mod rules;
mod scene;
mod spawn;
mod step_ops;
mod test_only;
mod values;
mod vars;
mod vec;
mod world;

pub(crate) use critter::CritterRef;
pub(crate) use hooks::ScriptContact;
pub(crate) use registry::Api;
pub(crate) use rules::{rule_code, rule_of_code};
pub(crate) use values::{num_or, props_from_map};
pub(crate) use world::WorldRef;

use super::host::Host;
use super::Limits;
use rhai::{Dynamic, Engine, EvalAltResult, Position};
use std::rc::Rc;

/// What a script function returns: a value, or the error rhai reports at the call.
pub(crate) type Res<T> = Result<T, Box<EvalAltResult>>;

/// Separates a message from its hint inside a runtime error's text (see `errors::eval_error`).
pub(crate) const HINT_MARK: char = '\u{1f}';

/// A runtime error with message `msg` (rhai adds the position of the call).
pub(crate) fn fail<T>(msg: impl Into<String>) -> Res<T> {
    Err(error(msg))
}

/// A runtime error with a message and a hint for the script's author.
pub(crate) fn fail_hint<T>(msg: impl Into<String>, hint: impl Into<String>) -> Res<T> {
    fail(format!("{}{HINT_MARK}{}", msg.into(), hint.into()))
}

/// The runtime error [`fail`] returns, for `map_err` and `ok_or_else`.
pub(crate) fn error(msg: impl Into<String>) -> Box<EvalAltResult> {
    Box::new(EvalAltResult::ErrorRuntime(
        Dynamic::from(msg.into()),
        Position::NONE,
    ))
}

/// The error of a script function called where no world is reachable.
pub(crate) fn no_world() -> Box<EvalAltResult> {
    error("there is no world yet: a scene script must call world(#{ ... }) first")
}

/// A library error as a script error (rhai adds the position of the call).
pub(crate) fn lib_err(e: crate::Error) -> Box<EvalAltResult> {
    error(e.to_string())
}

/// Makes the engine scripts run in: sandboxed (no files, no clock, no unseeded randomness, no
/// `eval`), limited per call, with the whole critterbox API registered, and then the functions
/// of the host's [`Extension`](super::Extension), if it has one. Also gives the functions
/// whose string arguments name kinds (see [`Api::kind_func`]).
pub(crate) fn build_engine(host: &Rc<Host>, limits: &Limits) -> (Engine, Vec<&'static str>) {
    let mut engine = Engine::new();
    engine.set_module_resolver(rhai::module_resolvers::DummyModuleResolver::new());
    engine.disable_symbol("eval");
    engine.set_max_operations(limits.max_operations);
    engine.set_max_call_levels(limits.max_call_levels);
    engine.set_max_expr_depths(256, 256);
    engine.set_max_string_size(limits.max_string_size);
    engine.set_max_array_size(limits.max_array_size);
    engine.set_max_map_size(limits.max_map_size);
    engine.set_fail_on_invalid_map_property(true);
    let charged = engine.set_data_walk_charge(super::DATA_WALK_ITEMS_PER_OP);

    let mut api = Api::new(&mut engine, host);
    step_ops::install(&mut api, limits.max_step_operations, charged);
    rules::register(&mut api);
    vec::register(&mut api);
    critter::register(&mut api);
    hooks::register(&mut api);
    world::register(&mut api);
    vars::register(&mut api);
    neighbours::register(&mut api);
    random::register(&mut api);
    kind_decl::register(&mut api);
    scene::register(&mut api);
    checks::register(&mut api);
    match host.extension.clone() {
        Some(extension) => extension.register(&mut api),
        None => test_only::register(&mut api),
    }
    let kind_calls = api.kind_calls();
    (engine, kind_calls)
}
