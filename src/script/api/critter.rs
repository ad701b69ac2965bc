//! `Critter`: a handle to a critter. Reading or writing its fields (`c.pos`, `c.vel = ...`) and
//! user properties (`c["score"]`, `c.score`) goes to the world; it also answers questions about
//! pairs (`touches`, `contains`, `distance`) and acts (`damage`, `die`, `collide_default`).

use super::registry::Api;
use super::values::{from_prop, from_svec, num_or, to_prop, to_svec};
use super::{error, fail, fail_hint, lib_err, Res};
use crate::border::Topology;
use crate::critter::{CritterId, PropValue};
use crate::script::host::{with_env, Host};
use crate::step::spawn::check_radius_in_box;
use crate::vector::{fmt_vec, Vector};
use glam::DVec3;
use rhai::{Dynamic, EvalAltResult};

/// A handle to a critter, as scripts see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CritterRef(pub(crate) CritterId);

/// The error of a handle whose critter died.
pub(super) fn gone(id: CritterId) -> Box<EvalAltResult> {
    error(format!(
        "critter {id} is gone (it died); check `c.alive` before using it"
    ))
}

macro_rules! critter_field {
    ($api:expr, $name:literal, |$c:ident| $get:expr) => {{
        $api.get($name, |h| move |r: &mut CritterRef| -> Res<_> {
            let id = r.0;
            with_env!(h, env => match env.critter(id) {
                Some($c) => Ok($get),
                None => Err(gone(id)),
            })
        });
    }};
}

macro_rules! critter_setter {
    ($api:expr, $name:literal, $ty:ty, |$c:ident, $v:ident| $set:expr) => {{
        $api.set($name, |h| move |r: &mut CritterRef, $v: $ty| -> Res<()> {
            let id = r.0;
            with_env!(h, env => match env.critter_mut(id) {
                Some($c) => $set,
                None => if env.critter(id).is_some() {
                    fail(concat!("critters are read-only in collides_with: ", $name, " cannot be set there"))
                } else {
                    Err(gone(id))
                },
            })
        });
    }};
}

fn set_prop(host: &Host, id: CritterId, name: &str, value: &Dynamic, create: bool) -> Res<()> {
    let prop = to_prop(value)?;
    with_env!(host, env => {
        let Some(c) = env.critter_mut(id) else {
            return if env.critter(id).is_some() {
                fail("critters are read-only in collides_with")
            } else {
                Err(gone(id))
            };
        };
        // An update hook sets properties of every critter every step: no allocation when the
        // property exists, and no change (nor a copy of shared traits) when it already holds
        // the same bits.
        if c.props().get(name).is_some_and(|p| same_bits(p, &prop)) {
            return Ok(());
        }
        if let Some(slot) = c.props_mut().get_mut(name) {
            *slot = prop;
            return Ok(());
        }
        if create {
            c.props_mut().insert(name.to_string(), prop);
            return Ok(());
        }
        let kind = c.kind();
        let kind = env.kinds().name(kind);
        let message = format!(
            "critter {id} ({kind}) has no property '{name}' (the fields are pos, vel, radius, mass, \
             health, restitution, priority, fixed)"
        );
        match near_field(name) {
            Some(field) => fail_hint(message, did_you_mean(name, field)),
            None => fail_hint(
                message,
                format!(
                    "declare '{name}' in the kind's defaults props or the spawn map, or add it with \
                     set_prop(\"{name}\", value)"
                ),
            ),
        }
    })
}

/// The fields every critter has (getters; the first eight can be set too).
const FIELDS: &[&str] = &[
    "pos",
    "vel",
    "radius",
    "mass",
    "health",
    "restitution",
    "priority",
    "fixed",
    "color",
    "alive",
    "id",
    "kind",
    "is_wall",
    "age",
];

/// The field `name` is most likely a misspelling of: one a small edit away (`radus`), or one it
/// spells out (`velocity`, `position`). A property of that name would be declared first, so an
/// undeclared one that is this near a field is taken for a typo.
fn near_field(name: &str) -> Option<&'static str> {
    crate::script::kind_refs::closest(name, FIELDS.iter().copied()).or_else(|| {
        FIELDS
            .iter()
            .copied()
            .filter(|f| f.len() >= 3)
            .filter(|f| {
                name.strip_prefix(f).is_some_and(|rest| {
                    !rest.is_empty() && rest.chars().all(|c| c.is_ascii_lowercase())
                })
            })
            .max_by_key(|f| f.len())
    })
}

/// The hint of an unknown property that is a near miss of `field`.
fn did_you_mean(name: &str, field: &str) -> String {
    format!(
        "did you mean `{field}`? `{name}` is no field of a critter; the fields are {}",
        FIELDS.join(", ")
    )
}

/// `pos = p` on critter `c` in the box `topo`: wrapped into the box on a periodic border, an
/// error naming the critter and the box outside it on any other (a spawn's centre must be in
/// the box too; clamping it silently moved the critter somewhere the script never said).
fn placed<V: Vector>(topo: &Topology<V>, who: impl Fn() -> String, v: DVec3) -> Res<V> {
    let mut p = V::zero();
    set_vec(&mut p, v, "pos")?;
    if topo.wraps() {
        return Ok(topo.wrap_position(p));
    }
    let outside = (0..V::DIM).any(|a| p.get(a) < topo.min.get(a) || p.get(a) > topo.max.get(a));
    if outside {
        let border = format!("{:?}", topo.border).to_lowercase();
        return fail_hint(
            format!(
                "pos = {}: {} would be outside the world box {} to {} (border \"{border}\")",
                fmt_vec(p),
                who(),
                fmt_vec(topo.min),
                fmt_vec(topo.max),
            ),
            "keep pos inside the box; under border: \"wrap\" a position past one side comes back on the other",
        );
    }
    Ok(p)
}

/// True when `a` and `b` are the same scalar, bit for bit (so `-0.0` differs from `0.0`);
/// false for text, lists and maps, which are simply written.
fn same_bits(a: &PropValue, b: &PropValue) -> bool {
    match (a, b) {
        (PropValue::Bool(a), PropValue::Bool(b)) => a == b,
        (PropValue::Int(a), PropValue::Int(b)) => a == b,
        (PropValue::Float(a), PropValue::Float(b)) => a.to_bits() == b.to_bits(),
        (PropValue::Critter(a), PropValue::Critter(b)) => a == b,
        (PropValue::Vector(a), PropValue::Vector(b)) => {
            a.iter().zip(b).all(|(a, b)| a.to_bits() == b.to_bits())
        }
        _ => false,
    }
}

fn set_vec<V: Vector>(slot: &mut V, v: DVec3, what: &str) -> Res<()> {
    if !v.is_finite() {
        return fail(format!(
            "{what} = {}: every component must be a finite number",
            crate::vector::fmt_vec(from_svec::<V>(v))
        ));
    }
    *slot = from_svec(v);
    Ok(())
}

fn set_num(
    c: &mut f64,
    v: &Dynamic,
    what: &str,
    check: impl Fn(f64) -> bool,
    rule: &str,
) -> Res<()> {
    let x = num_or(v, what)?;
    if !check(x) {
        return fail(format!("{what} = {x}: {rule}"));
    }
    *c = x;
    Ok(())
}

pub(super) fn register(api: &mut Api) {
    api.engine.register_type_with_name::<CritterRef>("Critter");
    api.engine
        .register_fn("==", |a: CritterRef, b: CritterRef| a == b);
    api.engine
        .register_fn("!=", |a: CritterRef, b: CritterRef| a != b);
    let show = |c: &mut CritterRef| format!("critter {}", c.0);
    api.engine.register_fn("to_string", show);
    api.engine.register_fn("to_debug", show);

    critter_field!(api, "pos", |c| to_svec(c.pos));
    critter_field!(api, "vel", |c| to_svec(c.vel));
    critter_field!(api, "radius", |c| c.radius());
    critter_field!(api, "mass", |c| c.mass());
    critter_field!(api, "health", |c| c.health());
    critter_field!(api, "restitution", |c| c.restitution());
    critter_field!(api, "priority", |c| c.priority());
    critter_field!(api, "fixed", |c| c.is_fixed());
    critter_field!(api, "is_wall", |c| c.is_wall());
    {
        // A dead critter's handle answers `alive` with false rather than an error.
        api.get("alive", |h| {
            move |r: &mut CritterRef| -> Res<bool> {
                let id = r.0;
                with_env!(h, env => Ok(env.critter(id).is_some_and(|c| c.is_alive())))
            }
        });
    }
    // The id as every log, recording and `inspect` prints it (`#20v5`): a text, so it compares
    // with `==`, keys a map and reads in an interpolation; never reused (its generation).
    critter_field!(api, "id", |c| c.id().to_string());
    {
        api.get("kind", |h| {
            move |r: &mut CritterRef| -> Res<String> {
                let id = r.0;
                with_env!(h, env => match env.critter(id) {
                    Some(c) => Ok(env.kinds().name(c.kind()).to_string()),
                    None => Err(gone(id)),
                })
            }
        });
    }
    api.set("pos", |h| {
        move |r: &mut CritterRef, v: DVec3| -> Res<()> {
            let id = r.0;
            with_env!(h, env => {
                let topo = *env.topology();
                let who = match env.critter(id) {
                    Some(c) => format!("{} ({})", c.describe(), env.kinds().name(c.kind())),
                    None => return Err(gone(id)),
                };
                let p = placed(&topo, || who.clone(), v)?;
                match env.critter_mut(id) {
                    Some(c) => {
                        c.pos = p;
                        Ok(())
                    }
                    None => fail("critters are read-only in collides_with: pos cannot be set there"),
                }
            })
        }
    });
    critter_setter!(api, "vel", DVec3, |c, v| set_vec(&mut c.vel, v, "vel"));
    // A new radius must fit in the world box, as a spawn's must.
    api.set("radius", |h| {
        move |r: &mut CritterRef, v: Dynamic| -> Res<()> {
            let (id, radius) = (r.0, num_or(&v, "radius")?);
            with_env!(h, env => {
                if let Some(c) = env.critter(id) {
                    check_radius_in_box(env.topology(), || c.describe(), radius).map_err(lib_err)?;
                }
                match env.critter_mut(id) {
                    Some(c) => c.set_radius(radius).map_err(lib_err),
                    None => if env.critter(id).is_some() {
                        fail("critters are read-only in collides_with: radius cannot be set there")
                    } else {
                        Err(gone(id))
                    },
                }
            })
        }
    });
    critter_setter!(api, "mass", Dynamic, |c, v| c
        .set_mass(num_or(&v, "mass")?)
        .map_err(lib_err));
    critter_setter!(api, "priority", Dynamic, |c, v| c
        .set_priority(num_or(&v, "priority")?)
        .map_err(lib_err));
    critter_setter!(api, "fixed", bool, |c, v| {
        c.set_fixed(v);
        Ok(())
    });
    critter_setter!(api, "health", Dynamic, |c, v| set_num(
        &mut c.traits_mut().health,
        &v,
        "health",
        f64::is_finite,
        "must be a finite number"
    ));
    critter_setter!(api, "restitution", Dynamic, |c, v| set_num(
        &mut c.traits_mut().restitution,
        &v,
        "restitution",
        |e| (0.0..=1.0).contains(&e),
        "must be between 0 and 1"
    ));

    // The colour it is drawn in: its own (`me.color = "red"` or "#rrggbb"), else its kind's.
    {
        api.get("color", |h| move |r: &mut CritterRef| -> Res<String> {
            let id = r.0;
            with_env!(h, env => match env.critter(id) {
                Some(c) => Ok(match c.color() {
                    Some(own) => own.to_string(),
                    None => {
                        let kind = env.kinds().get(c.kind());
                        match kind.defaults.color.as_deref().filter(|k| crate::color::parse(k).is_some()) {
                            Some(named) => named.to_string(),
                            None => crate::color::hex(crate::color::kind_color(
                                &kind.name,
                                None,
                                c.kind().0 as usize,
                            )),
                        }
                    }
                }),
                None => Err(gone(id)),
            })
        });
    }
    critter_setter!(api, "color", Dynamic, |c, v| {
        match v
        .clone()
        .try_cast::<rhai::ImmutableString>()
    {
        Some(name) => c.set_color(Some(name.as_str())).map_err(lib_err),
        None if v.is_unit() => c.set_color(None).map_err(lib_err),
        None => fail(format!(
            "color must be a string (a colour name or \"#rrggbb\"), or () for the kind's colour; got {}",
            super::values::type_of(&v)
        )),
    }
    });

    // User properties: c["name"], and c.name when no field of that name exists.
    api.index_get(|h| move |r: &mut CritterRef, name: &str| -> Res<Dynamic> {
        let id = r.0;
        with_env!(h, env => match env.critter(id) {
            Some(c) => match (c.props().get(name), near_field(name)) {
                (Some(p), _) => Ok(from_prop(p)),
                (None, Some(field)) => fail_hint(
                    format!("critter {id} ({}) has no property '{name}'", env.kinds().name(c.kind())),
                    did_you_mean(name, field),
                ),
                (None, None) => fail(format!(
                    "critter {id} ({}) has no property '{name}'; give it one in its kind's props or spawn map, or test with has(\"{name}\")",
                    env.kinds().name(c.kind())
                )),
            },
            None => Err(gone(id)),
        })
    });
    // Setting an existing property, or one the kind or spawn map declared. A new name is an
    // error, so a typo (`me.velocity = ...`) is caught; `set_prop` adds one on purpose.
    api.index_set(|h| {
        move |r: &mut CritterRef, name: &str, value: Dynamic| -> Res<()> {
            set_prop(&h, r.0, name, &value, false)
        }
    });
    api.func("set_prop", |h| {
        move |r: &mut CritterRef, name: &str, value: Dynamic| -> Res<()> {
            set_prop(&h, r.0, name, &value, true)
        }
    });
    // rhai gives every value a `tag`; for critters, `tag` is a user property like any other.
    api.get("tag", |h| {
        move |r: &mut CritterRef| -> Res<Dynamic> {
            let id = r.0;
            with_env!(h, env => match env.critter(id) {
                Some(c) => c.props().get("tag").map_or_else(
                    || fail(format!("critter {id} has no property 'tag'")),
                    |p| Ok(from_prop(p)),
                ),
                None => Err(gone(id)),
            })
        }
    });
    api.set("tag", |h| {
        move |r: &mut CritterRef, value: Dynamic| -> Res<()> {
            set_prop(&h, r.0, "tag", &value, false)
        }
    });
    api.func("has", |h| {
        move |r: &mut CritterRef, name: &str| -> Res<bool> {
            let id = r.0;
            with_env!(h, env => Ok(env.critter(id).is_some_and(|c| c.props().contains_key(name))))
        }
    });

    api.kind_func("is_kind", |h| {
        move |r: &mut CritterRef, kind: &str| -> Res<bool> {
            let id = r.0;
            let known = with_env!(h, env => {
                let kinds = env.kinds();
                match (env.critter(id), kinds.id(kind)) {
                    (Some(c), Ok(k)) => Ok(Some(kinds.is_kind(c.kind(), k))),
                    (None, _) => Err(gone(id)),
                    (Some(_), Err(_)) => Ok(None),
                }
            })?;
            if let Some(answer) = known {
                return Ok(answer);
            }
            // Not in this world: loaded now, or none of it here, or (no such kind) an error,
            // not `false`, as it is most likely a typo.
            let k = super::spawn::kind_for_query(&h, kind)?;
            with_env!(h, env => {
                let kinds = env.kinds();
                match env.critter(id) {
                    Some(c) => Ok(k.is_some_and(|k| kinds.is_kind(c.kind(), k))),
                    None => Err(gone(id)),
                }
            })
        }
    });
    api.func("touches", |h| {
        move |a: &mut CritterRef, b: CritterRef| -> Res<bool> {
            let a = a.0;
            with_env!(h, env => Ok(env.touches(a, b.0)))
        }
    });
    api.func("contains", |h| {
        move |a: &mut CritterRef, b: CritterRef| -> Res<bool> {
            let a = a.0;
            with_env!(h, env => Ok(env.contains(a, b.0)))
        }
    });
    api.func("distance", |h| move |a: &mut CritterRef, b: CritterRef| -> Res<f64> {
        let a = a.0;
        with_env!(h, env => env.distance(a, b.0).map_or_else(|| Err(gone(if env.critter(a).is_none() { a } else { b.0 })), Ok))
    });
    api.func("damage", |h| {
        move |a: &mut CritterRef, amount: Dynamic| -> Res<()> {
            let a = a.0;
            let amount = num_or(&amount, "damage")?;
            with_env!(h, env => env.damage(a, amount).map_err(|e| h.carry(e)))
        }
    });
    api.func("die", |h| {
        move |a: &mut CritterRef| -> Res<()> {
            let a = a.0;
            with_env!(h, env => {
                env.die(a);
                Ok(())
            })
        }
    });
    api.func("collide_default", |h| {
        move |a: &mut CritterRef, b: CritterRef| -> Res<bool> {
            let a = a.0;
            let hit = with_env!(h, env => env.collide_default(a, b.0).or_else(fail))?;
            // A collide hook's contact reads the impulse of its last default response.
            crate::script::kind_file::note_default(&h, a, b.0, hit);
            Ok(hit.is_some())
        }
    });
}
