//! Neighbour queries: `me.nearby(r)`, `me.nearby(r, "kind")`, `me.nearest("kind")`, and
//! `world().nearby(pos, r)`, `world().nearby(pos, r, "kind")`, `world().nearest(pos, "kind")`.
//! They answer from the world's neighbour grid (`world::neighbours`): exact for the positions
//! of the moment, in id order, looking only at the cells near the asker.

use super::critter::{gone, CritterRef};
use super::registry::Api;
use super::spawn::kind_for_query;
use super::values::from_svec;
use super::world::WorldRef;
use super::{fail, Res};
use crate::critter::CritterId;
use crate::kind::KindId;
use crate::script::env::Env;
use crate::script::host::{with_env, Host};
use crate::step::neighbours::check_radius;
use crate::vector::Vector;
use glam::DVec3;
use rhai::{Array, Dynamic, INT};
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

fn query<V: Vector>(env: &mut Env<'_, V>, from: From, kind: Kind, ask: Ask) -> Res<Dynamic> {
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
    let kind = match kind {
        Kind::Any => None,
        Kind::Of(k) => Some(k),
        // A kind with no critters in this world: nothing to find, once the input is checked.
        Kind::Absent => {
            return match ask {
                Ask::Nearby(r) => check_radius(r)
                    .or_else(fail)
                    .map(|()| Dynamic::from_array(Array::new())),
                Ask::Nearest => Ok(Dynamic::UNIT),
            };
        }
    };
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

/// The kind a query keeps: any, one in the world, or one that has no critters here.
#[derive(Clone, Copy)]
enum Kind {
    Any,
    Of(KindId),
    Absent,
}

fn ask(host: &Rc<Host>, from: From, kind: Option<&str>, ask: Ask) -> Res<Dynamic> {
    let kind = match kind {
        None => Kind::Any,
        Some(name) => match kind_for_query(host, name)? {
            Some(k) => Kind::Of(k),
            None => Kind::Absent,
        },
    };
    with_env!(host, env => query(env, from, kind, ask))
}

/// A radius as scripts write it: a float or an integer.
trait Radius: Copy + Send + Sync + 'static {
    fn get(self) -> f64;
}

impl Radius for f64 {
    fn get(self) -> f64 {
        self
    }
}

impl Radius for INT {
    fn get(self) -> f64 {
        self as f64
    }
}

/// Registers the four `nearby` forms for radius type `R`: typed parameters let rhai find the
/// function at its first lookup, where a `Dynamic` one makes it try every pattern of wildcards
/// on each call.
fn register_nearby<R: Radius>(api: &mut Api) {
    api.kind_func("nearby", |h| {
        move |me: &mut CritterRef, r: R| -> Res<Dynamic> {
            ask(&h, From::Me(me.0), None, Ask::Nearby(r.get()))
        }
    });
    api.kind_func("nearby", |h| {
        move |me: &mut CritterRef, r: R, kind: &str| -> Res<Dynamic> {
            ask(&h, From::Me(me.0), Some(kind), Ask::Nearby(r.get()))
        }
    });
    api.kind_func("nearby", |h| {
        move |_: &mut WorldRef, pos: DVec3, r: R| -> Res<Dynamic> {
            ask(&h, From::At(pos), None, Ask::Nearby(r.get()))
        }
    });
    api.kind_func("nearby", |h| {
        move |_: &mut WorldRef, pos: DVec3, r: R, kind: &str| -> Res<Dynamic> {
            ask(&h, From::At(pos), Some(kind), Ask::Nearby(r.get()))
        }
    });
}

/// The error of a `nearby` whose radius is not a number or whose kind is not a string. The
/// typed forms are found first; these `Dynamic` ones are reached only when they do not fit.
fn bad_nearby(args: &[&Dynamic]) -> Res<Dynamic> {
    let types: Vec<&str> = args.iter().map(|a| a.type_name()).collect();
    fail(format!(
        "nearby takes a radius (a number >= 0) and may take a kind name (a string), \
         but got nearby({}): give the radius as a number, e.g. nearby(5.0, \"prey\")",
        types.join(", ")
    ))
}

pub(super) fn register(api: &mut Api) {
    register_nearby::<f64>(api);
    register_nearby::<INT>(api);
    api.engine
        .register_fn("nearby", |_: &mut CritterRef, r: Dynamic| bad_nearby(&[&r]));
    api.engine
        .register_fn("nearby", |_: &mut CritterRef, r: Dynamic, k: Dynamic| {
            bad_nearby(&[&r, &k])
        });
    api.engine
        .register_fn("nearby", |_: &mut WorldRef, p: Dynamic, r: Dynamic| {
            bad_nearby(&[&p, &r])
        });
    api.engine.register_fn(
        "nearby",
        |_: &mut WorldRef, p: Dynamic, r: Dynamic, k: Dynamic| bad_nearby(&[&p, &r, &k]),
    );
    api.kind_func("nearest", |h| {
        move |me: &mut CritterRef, kind: &str| -> Res<Dynamic> {
            ask(&h, From::Me(me.0), Some(kind), Ask::Nearest)
        }
    });
    api.kind_func("nearest", |h| {
        move |_: &mut WorldRef, pos: DVec3, kind: &str| -> Res<Dynamic> {
            ask(&h, From::At(pos), Some(kind), Ask::Nearest)
        }
    });
}
