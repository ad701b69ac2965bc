//! Neighbour queries: `me.nearby(r)`, `me.nearby(r, "kind")`, `me.nearest("kind")`, and
//! `world().nearby(pos, r)`, `world().nearby(pos, r, "kind")`, `world().nearest(pos, "kind")`.
//! They answer from the world's neighbour grid (`world::neighbours`): exact for the positions
//! of the moment, in id order, looking only at the cells near the asker.

use super::critter::{gone, CritterRef};
use super::values::from_svec;
use super::world::WorldRef;
use super::{fail, Res};
use crate::critter::CritterId;
use crate::kind::KindId;
use crate::script::env::Env;
use crate::script::host::{with_env, Host};
use crate::vector::Vector;
use crate::world::neighbours::check_radius;
use glam::DVec3;
use rhai::{Array, Dynamic, Engine};
use std::rc::Rc;

/// Where a query is centred: a critter (left out of the answer) or a point.
#[derive(Clone, Copy)]
enum From {
    Me(CritterId),
    At(DVec3),
}

/// What is asked: everyone within a radius, or the nearest.
#[derive(Clone, Copy)]
enum Ask {
    Nearby(f64),
    Nearest,
}

fn kind_id<V: Vector>(env: &dyn Env<V>, kind: Option<&str>, call: &str) -> Res<Option<KindId>> {
    let Some(name) = kind else {
        return Ok(None);
    };
    match env.kinds().id(name) {
        Ok(k) => Ok(Some(k)),
        Err(e) => fail(format!("{call}: {e}")),
    }
}

fn query<V: Vector>(
    env: &mut dyn Env<V>,
    from: From,
    kind: Option<&str>,
    ask: Ask,
) -> Res<Dynamic> {
    let call = match ask {
        Ask::Nearby(_) => "nearby",
        Ask::Nearest => "nearest",
    };
    let (centre, exclude) = match from {
        From::Me(id) => match env.critter(id) {
            Some(c) => (c.pos, Some(id)),
            None => return Err(gone(id)),
        },
        From::At(p) if p.is_finite() => (from_svec::<V>(p), None),
        From::At(p) => return fail(format!("{call}: position {p} must be finite")),
    };
    let kind = kind_id(env, kind, call)?;
    let handle = |id: CritterId| Dynamic::from(CritterRef(id));
    match ask {
        Ask::Nearby(r) => {
            check_radius(r).or_else(fail)?;
            let ids = env.nearby(centre, r, kind, exclude).or_else(fail)?;
            Ok(Dynamic::from_array(
                ids.into_iter().map(handle).collect::<Array>(),
            ))
        }
        Ask::Nearest => {
            let id = env.nearest(centre, kind, exclude).or_else(fail)?;
            Ok(id.map_or(Dynamic::UNIT, handle))
        }
    }
}

fn ask(host: &Host, from: From, kind: Option<&str>, ask: Ask) -> Res<Dynamic> {
    with_env!(host, env => query(env, from, kind, ask))
}

fn radius(r: &Dynamic) -> Res<f64> {
    super::num_or(r, "nearby radius")
}

pub(super) fn register(engine: &mut Engine, host: &Rc<Host>) {
    let h = host.clone();
    engine.register_fn(
        "nearby",
        move |me: &mut CritterRef, r: Dynamic| -> Res<Dynamic> {
            ask(&h, From::Me(me.0), None, Ask::Nearby(radius(&r)?))
        },
    );
    let h = host.clone();
    engine.register_fn(
        "nearby",
        move |me: &mut CritterRef, r: Dynamic, kind: &str| -> Res<Dynamic> {
            ask(&h, From::Me(me.0), Some(kind), Ask::Nearby(radius(&r)?))
        },
    );
    let h = host.clone();
    engine.register_fn(
        "nearest",
        move |me: &mut CritterRef, kind: &str| -> Res<Dynamic> {
            ask(&h, From::Me(me.0), Some(kind), Ask::Nearest)
        },
    );
    let h = host.clone();
    engine.register_fn(
        "nearby",
        move |_: &mut WorldRef, pos: DVec3, r: Dynamic| -> Res<Dynamic> {
            ask(&h, From::At(pos), None, Ask::Nearby(radius(&r)?))
        },
    );
    let h = host.clone();
    engine.register_fn(
        "nearby",
        move |_: &mut WorldRef, pos: DVec3, r: Dynamic, kind: &str| -> Res<Dynamic> {
            ask(&h, From::At(pos), Some(kind), Ask::Nearby(radius(&r)?))
        },
    );
    let h = host.clone();
    engine.register_fn(
        "nearest",
        move |_: &mut WorldRef, pos: DVec3, kind: &str| -> Res<Dynamic> {
            ask(&h, From::At(pos), Some(kind), Ask::Nearest)
        },
    );
}
