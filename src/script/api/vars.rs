//! `world().vars`: the state a scene, its kinds' hooks and its tests share (a score, a counter),
//! as named values in the world. `w.vars` is a handle, like a critter's: `w.vars.score += 1` and
//! `w.vars["score"]` read and write the world's map, so the write reaches the world (a plain map
//! returned by a getter would be a copy). The values are the critter properties' (numbers,
//! bools, strings, `Vec`s, critters, arrays and maps of those); the map is part of the state hash
//! and of the recording.
//!
//! A compound assignment to a var nobody set (`w.vars["s"] -= 1`) must fail as a read does.
//! rhai runs `x[i] op= v` on a type with an indexer as a read through the getter, then a write
//! through the setter, and when the getter fails it drops that error and writes `v` as it is
//! (so `-= 1` made +1). So the getter marks the handle it was called on with the name it missed
//! and where it was called; the setter, called right after on the same handle at the same place,
//! finds the mark and fails. A plain `w.vars["s"] = v` calls no getter, and a failed read
//! elsewhere left its mark at another place, so only the compound assignment is refused.

use super::registry::Api;
use super::values::{from_prop, to_prop};
use super::world::WorldRef;
use super::{fail, fail_hint, Res};
use crate::script::host::{with_env, Host};
use rhai::{Array, Dynamic, Map, NativeCallContext, Position, INT};

/// A handle to the world's vars, as scripts see it.
#[derive(Clone, Debug, Default)]
pub(crate) struct VarsRef {
    /// The last name the getter did not find through this handle, and where (see the module
    /// docs).
    missed: Option<Missed>,
}

/// A read of a var that does not exist: the name, and the call's file and position.
#[derive(Clone, Debug, PartialEq)]
struct Missed {
    name: String,
    source: Option<String>,
    pos: Position,
}

impl Missed {
    fn at(ctx: &NativeCallContext, name: &str) -> Missed {
        Missed {
            name: name.to_string(),
            source: ctx.call_source().map(str::to_string),
            pos: ctx.call_position(),
        }
    }
}

/// The error where the vars are out of reach.
fn out_of_reach<T>() -> Res<T> {
    fail(
        "world().vars is out of reach in collides_with (its answer may be cached, so it must not \
         depend on changing state); read it in update or collide",
    )
}

/// The error of a var never set, for a read and for a compound assignment alike.
fn no_var<T>(name: &str) -> Res<T> {
    fail_hint(
        format!("world().vars has no '{name}'"),
        format!("give it a value first, e.g. in the scene: w.vars.{name} = 0; or test with w.vars.has(\"{name}\")"),
    )
}

/// The var `name`, or `None` when it was never set.
fn lookup(host: &Host, name: &str) -> Res<Option<Dynamic>> {
    with_env!(host, env => match env.vars() {
        Some(vars) => Ok(vars.get(name).map(from_prop)),
        None => out_of_reach(),
    })
}

fn get(host: &Host, name: &str) -> Res<Dynamic> {
    lookup(host, name)?.map_or_else(|| no_var(name), Ok)
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
    api.engine
        .register_get("vars", |_: &mut WorldRef| VarsRef::default());

    // w.vars["name"], and w.vars.name through rhai's fallback from properties to the indexer.
    // The getter marks a miss and the setter refuses the write it belongs to (module docs).
    api.index_get(|h| {
        move |ctx: NativeCallContext, v: &mut VarsRef, name: &str| -> Res<Dynamic> {
            match lookup(&h, name)? {
                Some(value) => {
                    v.missed = None;
                    Ok(value)
                }
                None => {
                    v.missed = Some(Missed::at(&ctx, name));
                    no_var(name)
                }
            }
        }
    });
    api.index_set(|h| {
        move |ctx: NativeCallContext, v: &mut VarsRef, name: &str, value: Dynamic| -> Res<()> {
            if v.missed.take().is_some_and(|m| m == Missed::at(&ctx, name)) {
                return no_var(name);
            }
            set(&h, name, &value)
        }
    });
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
