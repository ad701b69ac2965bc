//! `world().vars`: the state a scene, its kinds' hooks and its tests share (a score, a counter),
//! as named values in the world. `w.vars` is a handle, like a critter's: `w.vars.score += 1` and
//! `w.vars["score"]` read and write the world's map, so the write reaches the world (a plain map
//! returned by a getter would be a copy). The values are the critter properties' (numbers,
//! bools, strings, `Vec`s, critters, arrays and maps of those); the map is part of the state hash
//! and of the recording.

use super::registry::Api;
use super::values::{from_prop, to_prop};
use super::world::WorldRef;
use super::{fail, fail_hint, Res};
use crate::script::host::{with_env, Host};
use rhai::{Array, Dynamic, Map, INT};

/// A handle to the world's vars, as scripts see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct VarsRef;

/// The error where the vars are out of reach.
fn out_of_reach<T>() -> Res<T> {
    fail(
        "world().vars is out of reach in collides_with (its answer may be cached, so it must not \
         depend on changing state); read it in update or collide",
    )
}

fn get(host: &Host, name: &str) -> Res<Dynamic> {
    with_env!(host, env => match env.vars() {
        Some(vars) => match vars.get(name) {
            Some(v) => Ok(from_prop(v)),
            None => fail_hint(
                format!("world().vars has no '{name}'"),
                format!("give it a value first, e.g. in the scene: w.vars.{name} = 0; or test with w.vars.has(\"{name}\")"),
            ),
        },
        None => out_of_reach(),
    })
}

fn set(host: &Host, name: &str, value: &Dynamic) -> Res<()> {
    let value = to_prop(value)?;
    with_env!(host, env => match env.vars() {
        Some(vars) => {
            vars.insert(name.to_string(), value);
            Ok(())
        }
        None => out_of_reach(),
    })
}

pub(super) fn register(api: &mut Api) {
    api.engine.register_type_with_name::<VarsRef>("Vars");
    api.engine.register_get("vars", |_: &mut WorldRef| VarsRef);

    // w.vars["name"], and w.vars.name through rhai's fallback from properties to the indexer.
    api.index_get(|h| move |_: &mut VarsRef, name: &str| get(&h, name));
    api.index_set(|h| move |_: &mut VarsRef, name: &str, value: Dynamic| set(&h, name, &value));
    // rhai gives every value a `tag`; here, as for critters, it is a var like any other.
    api.get("tag", |h| move |_: &mut VarsRef| get(&h, "tag"));
    api.set("tag", |h| {
        move |_: &mut VarsRef, value: Dynamic| set(&h, "tag", &value)
    });

    api.func("has", |h| {
        move |_: &mut VarsRef, name: &str| -> Res<bool> {
            with_env!(h, env => match env.vars() {
                Some(vars) => Ok(vars.contains_key(name)),
                None => out_of_reach(),
            })
        }
    });
    api.func("remove", |h| {
        move |_: &mut VarsRef, name: &str| -> Res<Dynamic> {
            with_env!(h, env => match env.vars() {
                Some(vars) => Ok(vars.remove(name).map_or(Dynamic::UNIT, |v| from_prop(&v))),
                None => out_of_reach(),
            })
        }
    });
    api.func("keys", |h| {
        move |_: &mut VarsRef| -> Res<Array> {
            with_env!(h, env => match env.vars() {
                Some(vars) => Ok(vars.keys().map(|k| Dynamic::from(k.clone())).collect()),
                None => out_of_reach(),
            })
        }
    });
    api.func("len", |h| {
        move |_: &mut VarsRef| -> Res<INT> {
            with_env!(h, env => match env.vars() {
                Some(vars) => Ok(vars.len() as INT),
                None => out_of_reach(),
            })
        }
    });
    // A copy of the whole map, to print or compare.
    let h = api.host();
    let to_map = move |_: &mut VarsRef| -> Res<Map> {
        with_env!(h, env => match env.vars() {
            Some(vars) => Ok(vars.iter().map(|(k, v)| (k.as_str().into(), from_prop(v))).collect()),
            None => out_of_reach(),
        })
    };
    api.engine.register_fn("to_map", to_map.clone());
    let show =
        move |v: &mut VarsRef| -> Res<String> { to_map(v).map(|m| super::values::show(&m.into())) };
    api.engine.register_fn("to_string", show.clone());
    api.engine.register_fn("to_debug", show);
}
