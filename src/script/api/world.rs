//! `World`: the running world as scripts see it (`world()`, `w.step_count`, `w.step`, `w.time`, `w.dt`,
//! `w.gravity`, `w.critters_of(kind)`, `w.count(kind)`, `w.critter(id)`), and its log:
//! `log(...)`, `print` and `debug`.

use super::critter::CritterRef;
use super::registry::Api;
use super::values::to_svec;
use super::{error, fail_hint, Res};
use crate::critter::CritterId;
use crate::script::host::{with_env, Host};
use glam::DVec3;
use rhai::{Array, Dynamic, EvalAltResult, INT};

/// The running world, as scripts see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct WorldRef;

pub(super) fn register(api: &mut Api) {
    // print and debug go to the run's log.
    let h = api.host();
    api.engine.on_print(move |text| {
        let _ = with_env!(h, env => {
            env.log(text.to_string());
            Ok::<(), Box<EvalAltResult>>(())
        });
    });
    let h = api.host();
    api.engine.on_debug(move |text, source, pos| {
        let line = match (source, pos.line()) {
            (Some(src), Some(l)) => format!("{src}:{l}: {text}"),
            _ => text.to_string(),
        };
        let _ = with_env!(h, env => {
            env.log(line.clone());
            Ok::<(), Box<EvalAltResult>>(())
        });
    });

    api.engine.register_type_with_name::<WorldRef>("World");
    api.engine.register_fn("world", || WorldRef);
    api.get("step_count", |h| {
        move |_: &mut WorldRef| -> Res<INT> { with_env!(h, env => Ok(env.step_count() as INT)) }
    });
    api.get("step", |h| {
        move |_: &mut WorldRef| -> Res<INT> { with_env!(h, env => Ok(env.step_now() as INT)) }
    });
    api.get("time", |h| {
        move |_: &mut WorldRef| -> Res<f64> { with_env!(h, env => Ok(env.time())) }
    });
    api.get("dt", |h| {
        move |_: &mut WorldRef| -> Res<f64> { with_env!(h, env => Ok(env.dt())) }
    });
    api.get("gravity", |h| {
        move |_: &mut WorldRef| -> Res<DVec3> {
            with_env!(h, env => Ok(to_svec(env.access().map_err(error)?.gravity())))
        }
    });
    api.kind_func("critters_of", |h| {
        move |_: &mut WorldRef, kind: &str| -> Res<Array> {
            let Some(k) = super::spawn::kind_for_query(&h, kind)? else {
                return Ok(Array::new());
            };
            with_env!(h, env => {
                Ok(env.critters_of(k).into_iter().map(|id| Dynamic::from(CritterRef(id))).collect())
            })
        }
    });
    api.kind_func("count", |h| {
        move |_: &mut WorldRef, kind: &str| -> Res<INT> {
            let Some(k) = super::spawn::kind_for_query(&h, kind)? else {
                return Ok(0);
            };
            with_env!(h, env => Ok(env.critters_of(k).len() as INT))
        }
    });
    api.func("critter", |h| {
        move |_: &mut WorldRef, id: &str| -> Res<Dynamic> {
            match id.parse::<CritterId>() {
                Ok(id) => live_critter(&h, id),
                Err(e) => fail_hint(
                    format!("world().critter(\"{id}\"): {e}"),
                    "pass an id as me.id gives it, e.g. world().critter(\"#20v5\")",
                ),
            }
        }
    });
    api.func("critter", |h| {
        move |_: &mut WorldRef, index: INT| -> Res<Dynamic> {
            match u32::try_from(index) {
                Ok(index) => live_critter(
                    &h,
                    CritterId {
                        index,
                        generation: 0,
                    },
                ),
                Err(_) => fail_hint(
                    format!(
                        "world().critter({index}): an id's index is a number from 0 to {}",
                        u32::MAX
                    ),
                    "pass an id as me.id gives it, e.g. world().critter(\"#20v5\")",
                ),
            }
        }
    });
    api.func("log", |h| {
        move |_: &mut WorldRef, line: Dynamic| -> Res<()> {
            with_env!(h, env => {
                env.log(line.to_string());
                Ok(())
            })
        }
    });
    api.func("log", |h| {
        move |line: Dynamic| -> Res<()> {
            with_env!(h, env => {
                env.log(line.to_string());
                Ok(())
            })
        }
    });
}

/// `world().critter(id)`: the handle of the live critter `id`, or `()` when none is (it died,
/// or the id was never given out); the generation must match, so an old id finds nothing.
fn live_critter(h: &Host, id: CritterId) -> Res<Dynamic> {
    with_env!(h, env => {
        let access = env.access().map_err(error)?;
        Ok(match access.get(id) {
            Some(c) if c.is_alive() => Dynamic::from(CritterRef(id)),
            _ => Dynamic::UNIT,
        })
    })
}
