//! `World`: the running world as scripts see it (`world()`, `w.step_count`, `w.time`, `w.dt`,
//! `w.critters_of(kind)`, `w.count(kind)`), and its log: `log(...)`, `print` and `debug`.

use super::critter::CritterRef;
use super::Res;
use crate::script::host::{with_env, Host};
use rhai::{Array, Dynamic, Engine, EvalAltResult, INT};
use std::rc::Rc;

/// The running world, as scripts see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct WorldRef;

pub(super) fn register(engine: &mut Engine, host: &Rc<Host>) {
    // print and debug go to the run's log.
    let h = host.clone();
    engine.on_print(move |text| {
        let _ = with_env!(h, env => {
            env.log(text.to_string());
            Ok::<(), Box<EvalAltResult>>(())
        });
    });
    let h = host.clone();
    engine.on_debug(move |text, source, pos| {
        let line = match (source, pos.line()) {
            (Some(src), Some(l)) => format!("{src}:{l}: {text}"),
            _ => text.to_string(),
        };
        let _ = with_env!(h, env => {
            env.log(line.clone());
            Ok::<(), Box<EvalAltResult>>(())
        });
    });

    engine.register_type_with_name::<WorldRef>("World");
    engine.register_fn("world", || WorldRef);
    let h = host.clone();
    engine.register_get("step_count", move |_: &mut WorldRef| -> Res<INT> {
        with_env!(h, env => Ok(env.step_count() as INT))
    });
    let h = host.clone();
    engine.register_get("time", move |_: &mut WorldRef| -> Res<f64> {
        with_env!(h, env => Ok(env.time()))
    });
    let h = host.clone();
    engine.register_get("dt", move |_: &mut WorldRef| -> Res<f64> {
        with_env!(h, env => Ok(env.dt()))
    });
    let h = host.clone();
    engine.register_fn(
        "critters_of",
        move |_: &mut WorldRef, kind: &str| -> Res<Array> {
            let Some(k) = super::spawn::kind_for_query(&h, kind)? else {
                return Ok(Array::new());
            };
            with_env!(h, env => {
                Ok(env.critters_of(k).into_iter().map(|id| Dynamic::from(CritterRef(id))).collect())
            })
        },
    );
    let h = host.clone();
    engine.register_fn("count", move |_: &mut WorldRef, kind: &str| -> Res<INT> {
        let Some(k) = super::spawn::kind_for_query(&h, kind)? else {
            return Ok(0);
        };
        with_env!(h, env => Ok(env.critters_of(k).len() as INT))
    });
    let h = host.clone();
    engine.register_fn("log", move |_: &mut WorldRef, line: Dynamic| -> Res<()> {
        with_env!(h, env => {
            env.log(line.to_string());
            Ok(())
        })
    });
    let h = host.clone();
    engine.register_fn("log", move |line: Dynamic| -> Res<()> {
        with_env!(h, env => {
            env.log(line.to_string());
            Ok(())
        })
    });
}
