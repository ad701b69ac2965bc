//! The script API: one factory ([`build_engine`]) that makes the rhai engine with every type,
//! function and constant scripts see, sandboxed and limited.
//!
//! Types: `Vec` (a vector with operators; 2D worlds ignore z), `Critter` (a handle to a critter:
//! reading or writing its fields goes to the world), `World` (the running world).

use super::host::{with_env, Env, Host};
use super::Limits;
use crate::critter::{CritterId, CritterSpec, PropValue, Props, PRIORITY_NAMES};
use crate::kind::CollideRule;
use crate::vector::Vector;
use glam::DVec3;
use rhai::{Array, Dynamic, Engine, EvalAltResult, ImmutableString, Map, Module, Position, INT};
use std::rc::Rc;

/// A handle to a critter, as scripts see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CritterRef(pub CritterId);

/// The running world, as scripts see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldRef;

pub(crate) type Res<T> = Result<T, Box<EvalAltResult>>;

/// A runtime error with message `msg` (rhai adds the position of the call).
/// Separates a message from its hint inside a runtime error's text (see `errors::eval_error`).
pub(crate) const HINT_MARK: char = '\u{1f}';

/// A runtime error with a message and a hint for the script's author.
pub(crate) fn fail_hint<T>(msg: impl Into<String>, hint: impl Into<String>) -> Res<T> {
    fail(format!("{}{HINT_MARK}{}", msg.into(), hint.into()))
}

pub(crate) fn fail<T>(msg: impl Into<String>) -> Res<T> {
    Err(Box::new(EvalAltResult::ErrorRuntime(
        Dynamic::from(msg.into()),
        Position::NONE,
    )))
}

pub(crate) fn no_world() -> Box<EvalAltResult> {
    Box::new(EvalAltResult::ErrorRuntime(
        Dynamic::from(
            "there is no world yet: a scene script must call world(#{ ... }) first".to_string(),
        ),
        Position::NONE,
    ))
}

/// A number from a script value (INT or FLOAT).
pub(crate) fn num(d: &Dynamic) -> Option<f64> {
    if let Some(x) = d.clone().try_cast::<f64>() {
        Some(x)
    } else {
        d.clone().try_cast::<INT>().map(|i| i as f64)
    }
}

pub(crate) fn num_or(d: &Dynamic, what: &str) -> Res<f64> {
    num(d).map_or_else(
        || {
            fail(format!(
                "{what} must be a number, got {} ({})",
                d,
                d.type_name()
            ))
        },
        Ok,
    )
}

pub(crate) fn to_svec<V: Vector>(v: V) -> DVec3 {
    let a = v.to_array3();
    DVec3::new(a[0], a[1], a[2])
}

pub(crate) fn from_svec<V: Vector>(s: DVec3) -> V {
    let mut v = V::zero();
    for axis in 0..V::DIM {
        v.set(axis, s[axis]);
    }
    v
}

fn vec_of(d: &Dynamic, what: &str) -> Res<DVec3> {
    d.clone().try_cast::<DVec3>().map_or_else(
        || {
            fail(format!(
                "{what} must be a Vec (e.g. vec(1.0, 2.0)), got {}",
                d.type_name()
            ))
        },
        Ok,
    )
}

/// A script value as a critter property.
pub(crate) fn to_prop(d: &Dynamic) -> Res<PropValue> {
    if let Some(b) = d.clone().try_cast::<bool>() {
        return Ok(PropValue::Bool(b));
    }
    if let Some(i) = d.clone().try_cast::<INT>() {
        return Ok(PropValue::Int(i));
    }
    if let Some(x) = d.clone().try_cast::<f64>() {
        return Ok(PropValue::Float(x));
    }
    if let Some(s) = d.clone().try_cast::<ImmutableString>() {
        return Ok(PropValue::Text(s.to_string()));
    }
    if let Some(c) = d.clone().try_cast::<CritterRef>() {
        return Ok(PropValue::Critter(c.0));
    }
    if let Some(v) = d.clone().try_cast::<DVec3>() {
        return Ok(PropValue::Vector(v.to_array()));
    }
    if let Some(a) = d.clone().try_cast::<Array>() {
        return a
            .iter()
            .map(to_prop)
            .collect::<Res<Vec<_>>>()
            .map(PropValue::List);
    }
    fail(format!(
        "a critter property can be a bool, number, string, Vec, critter or array of those, not {}",
        d.type_name()
    ))
}

/// A critter property as a script value.
pub(crate) fn from_prop(p: &PropValue) -> Dynamic {
    match p {
        PropValue::Bool(b) => Dynamic::from(*b),
        PropValue::Int(i) => Dynamic::from(*i),
        PropValue::Float(x) => Dynamic::from(*x),
        PropValue::Text(s) => Dynamic::from(s.clone()),
        PropValue::Critter(id) => Dynamic::from(CritterRef(*id)),
        PropValue::List(items) => Dynamic::from(items.iter().map(from_prop).collect::<Array>()),
        PropValue::Vector(v) => Dynamic::from(DVec3::from_array(*v)),
    }
}

/// The fields a spawn map may set.
pub(crate) const SPAWN_FIELDS: &[&str] = &[
    "pos",
    "vel",
    "radius",
    "mass",
    "density",
    "fixed",
    "priority",
    "restitution",
    "health",
    "props",
];

/// A spawn request from a script: `spawn(kind, #{ pos: ..., vel: ..., ... })`.
pub(crate) fn spec_from_map<V: Vector>(kind: &str, map: &Map) -> Res<CritterSpec<V>> {
    let mut spec = CritterSpec::new(kind, V::zero());
    for (key, value) in map {
        let f = |what: &str| num_or(value, &format!("{what} of the {kind} to spawn"));
        match key.as_str() {
            "pos" => spec.pos = from_svec(vec_of(value, "pos")?),
            "vel" => spec.vel = from_svec(vec_of(value, "vel")?),
            "radius" => spec.radius = Some(f("radius")?),
            "mass" => spec.mass = Some(f("mass")?),
            "density" => spec.density = Some(f("density")?),
            "priority" => spec.priority = Some(f("priority")?),
            "restitution" => spec.restitution = Some(f("restitution")?),
            "health" => spec.health = Some(f("health")?),
            "fixed" => match value.clone().try_cast::<bool>() {
                Some(b) => spec.fixed = Some(b),
                None => return fail("fixed must be true or false"),
            },
            "props" => match value.clone().try_cast::<Map>() {
                Some(props) => {
                    for (name, v) in props {
                        spec.props.insert(name.to_string(), to_prop(&v)?);
                    }
                }
                None => return fail("props must be a map, e.g. props: #{ score: 0 }"),
            },
            other => {
                return fail(format!(
                    "unknown field '{other}' for a spawn; the fields are {}; user properties go in props: #{{ ... }}",
                    SPAWN_FIELDS.join(", ")
                ))
            }
        }
    }
    Ok(spec)
}

/// Props given as a script map.
pub(crate) fn props_from_map(map: &Map) -> Res<Props> {
    let mut props = Props::new();
    for (name, v) in map {
        props.insert(name.to_string(), to_prop(v)?);
    }
    Ok(props)
}

/// A library error as a script error (rhai adds the position of the call).
pub(crate) fn lib_err(e: crate::Error) -> Box<EvalAltResult> {
    Box::new(EvalAltResult::ErrorRuntime(
        Dynamic::from(e.to_string()),
        Position::NONE,
    ))
}

fn gone(id: CritterId) -> Box<EvalAltResult> {
    Box::new(EvalAltResult::ErrorRuntime(
        Dynamic::from(format!(
            "critter {id} is gone (it died); check `c.alive` before using it"
        )),
        Position::NONE,
    ))
}

fn count_spawn(host: &Host, step: u64) -> Res<()> {
    if host.spawns_step.get() != step {
        host.spawns_step.set(step);
        host.spawns.set(0);
    }
    let n = host.spawns.get() + 1;
    host.spawns.set(n);
    if n > host.max_spawns_per_step {
        return fail(format!(
            "more than {} spawns in one step; raise the limit with --max-spawns if this is intended",
            host.max_spawns_per_step
        ));
    }
    Ok(())
}

/// Spawns from a script, now between steps or queued inside one.
pub(crate) fn spawn_in<V: Vector>(
    env: &mut dyn Env<V>,
    host: &Host,
    kind: &str,
    map: &Map,
) -> Res<Dynamic> {
    count_spawn(host, env.step_count())?;
    env.kinds().id(kind).map_err(lib_err)?;
    let spec = spec_from_map::<V>(kind, map)?;
    match env.spawn(spec).map_err(|e| host.carry(e))? {
        Some(id) => Ok(Dynamic::from(CritterRef(id))),
        None => Ok(Dynamic::UNIT),
    }
}

/// Makes the engine scripts run in: sandboxed (no files, no clock, no unseeded randomness, no
/// `eval`), limited per call, with the whole critterbox API registered.
pub(crate) fn build_engine(host: &Rc<Host>, limits: &Limits) -> Engine {
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

    register_constants(&mut engine);
    register_vec(&mut engine);
    register_critter(&mut engine, host);
    register_world(&mut engine, host);
    super::scene::register(&mut engine, host);
    super::testing::register(&mut engine, host);
    engine
}

fn register_constants(engine: &mut Engine) {
    let mut module = Module::new();
    for (name, value) in PRIORITY_NAMES {
        module.set_var(name, value);
    }
    for (name, rule) in CollideRule::NAMES {
        module.set_var(name, rule_code(rule));
    }
    engine.register_global_module(module.into());
}

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

fn register_vec(engine: &mut Engine) {
    engine.register_type_with_name::<DVec3>("Vec");
    engine.register_fn("vec", |x: Dynamic, y: Dynamic| -> Res<DVec3> {
        Ok(DVec3::new(num_or(&x, "x")?, num_or(&y, "y")?, 0.0))
    });
    engine.register_fn("vec", |x: Dynamic, y: Dynamic, z: Dynamic| -> Res<DVec3> {
        Ok(DVec3::new(
            num_or(&x, "x")?,
            num_or(&y, "y")?,
            num_or(&z, "z")?,
        ))
    });
    engine.register_get_set("x", |v: &mut DVec3| v.x, |v: &mut DVec3, x: f64| v.x = x);
    engine.register_get_set("y", |v: &mut DVec3| v.y, |v: &mut DVec3, y: f64| v.y = y);
    engine.register_get_set("z", |v: &mut DVec3| v.z, |v: &mut DVec3, z: f64| v.z = z);
    engine.register_fn("+", |a: DVec3, b: DVec3| a + b);
    engine.register_fn("-", |a: DVec3, b: DVec3| a - b);
    engine.register_fn("-", |a: DVec3| -a);
    engine.register_fn("*", |a: DVec3, k: f64| a * k);
    engine.register_fn("*", |k: f64, a: DVec3| a * k);
    engine.register_fn("*", |a: DVec3, k: INT| a * k as f64);
    engine.register_fn("*", |k: INT, a: DVec3| a * k as f64);
    engine.register_fn("/", |a: DVec3, k: f64| a / k);
    engine.register_fn("/", |a: DVec3, k: INT| a / k as f64);
    engine.register_fn("==", |a: DVec3, b: DVec3| a == b);
    engine.register_fn("!=", |a: DVec3, b: DVec3| a != b);
    engine.register_fn("+=", |a: &mut DVec3, b: DVec3| *a += b);
    engine.register_fn("-=", |a: &mut DVec3, b: DVec3| *a -= b);
    engine.register_fn("length", |a: &mut DVec3| a.length());
    engine.register_fn("length_squared", |a: &mut DVec3| a.length_squared());
    engine.register_fn("normalize", |a: &mut DVec3| a.normalize_or_zero());
    engine.register_fn("dot", |a: &mut DVec3, b: DVec3| a.dot(b));
    engine.register_fn("cross", |a: &mut DVec3, b: DVec3| a.cross(b));
    engine.register_fn("distance", |a: &mut DVec3, b: DVec3| a.distance(b));
    engine.register_fn("perp", |a: &mut DVec3| DVec3::new(-a.y, a.x, 0.0));
    engine.register_fn("rotate", |a: &mut DVec3, angle: f64| {
        let (s, c) = angle.sin_cos();
        DVec3::new(c * a.x - s * a.y, s * a.x + c * a.y, a.z)
    });
    let show = |a: &mut DVec3| -> String {
        if a.z == 0.0 {
            format!("vec({}, {})", a.x, a.y)
        } else {
            format!("vec({}, {}, {})", a.x, a.y, a.z)
        }
    };
    engine.register_fn("to_string", show);
    engine.register_fn("to_debug", show);
}

macro_rules! critter_field {
    ($engine:expr, $host:expr, $name:literal, |$c:ident| $get:expr) => {{
        let h = $host.clone();
        $engine.register_get($name, move |r: &mut CritterRef| -> Res<_> {
            let id = r.0;
            with_env!(h, env => match env.critter(id) {
                Some($c) => Ok($get),
                None => Err(gone(id)),
            })
        });
    }};
}

macro_rules! critter_setter {
    ($engine:expr, $host:expr, $name:literal, $ty:ty, |$c:ident, $v:ident| $set:expr) => {{
        let h = $host.clone();
        $engine.register_set($name, move |r: &mut CritterRef, $v: $ty| -> Res<()> {
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
        let kind = match env.critter(id) {
            Some(c) => env.kinds().name(c.kind()).to_string(),
            None => return Err(gone(id)),
        };
        match env.critter_mut(id) {
            Some(c) if create || c.props().contains_key(name) => {
                c.props_mut().insert(name.to_string(), prop);
                Ok(())
            }
            Some(_) => fail_hint(
                format!(
                    "critter {id} ({kind}) has no property '{name}' (the fields are pos, vel, radius, mass, \
                     health, restitution, priority, fixed)"
                ),
                format!(
                    "declare '{name}' in the kind's defaults props or the spawn map, or add it with \
                     set_prop(\"{name}\", value)"
                ),
            ),
            None => fail("critters are read-only in collides_with"),
        }
    })
}

fn set_vec<V: Vector>(slot: &mut V, v: DVec3, what: &str) -> Res<()> {
    if !v.is_finite() {
        return fail(format!(
            "{what} = {v}: every component must be a finite number"
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

fn register_critter(engine: &mut Engine, host: &Rc<Host>) {
    engine.register_type_with_name::<CritterRef>("Critter");
    engine.register_fn("==", |a: CritterRef, b: CritterRef| a == b);
    engine.register_fn("!=", |a: CritterRef, b: CritterRef| a != b);
    let show = |c: &mut CritterRef| format!("critter {}", c.0);
    engine.register_fn("to_string", show);
    engine.register_fn("to_debug", show);

    critter_field!(engine, host, "pos", |c| to_svec(c.pos));
    critter_field!(engine, host, "vel", |c| to_svec(c.vel));
    critter_field!(engine, host, "radius", |c| c.radius());
    critter_field!(engine, host, "mass", |c| c.mass());
    critter_field!(engine, host, "health", |c| c.health());
    critter_field!(engine, host, "restitution", |c| c.restitution());
    critter_field!(engine, host, "priority", |c| c.priority());
    critter_field!(engine, host, "fixed", |c| c.is_fixed());
    critter_field!(engine, host, "is_wall", |c| c.is_wall());
    {
        // A dead critter's handle answers `alive` with false rather than an error.
        let h = host.clone();
        engine.register_get("alive", move |r: &mut CritterRef| -> Res<bool> {
            let id = r.0;
            with_env!(h, env => Ok(env.critter(id).is_some_and(|c| c.is_alive())))
        });
    }
    critter_field!(engine, host, "id", |c| c.id().index as INT);
    {
        let h = host.clone();
        engine.register_get("kind", move |r: &mut CritterRef| -> Res<String> {
            let id = r.0;
            with_env!(h, env => match env.critter(id) {
                Some(c) => Ok(env.kinds().name(c.kind()).to_string()),
                None => Err(gone(id)),
            })
        });
    }
    critter_setter!(engine, host, "pos", DVec3, |c, v| set_vec(
        &mut c.pos, v, "pos"
    ));
    critter_setter!(engine, host, "vel", DVec3, |c, v| set_vec(
        &mut c.vel, v, "vel"
    ));
    critter_setter!(engine, host, "radius", Dynamic, |c, v| c
        .set_radius(num_or(&v, "radius")?)
        .map_err(lib_err));
    critter_setter!(engine, host, "mass", Dynamic, |c, v| c
        .set_mass(num_or(&v, "mass")?)
        .map_err(lib_err));
    critter_setter!(engine, host, "priority", Dynamic, |c, v| c
        .set_priority(num_or(&v, "priority")?)
        .map_err(lib_err));
    critter_setter!(engine, host, "fixed", bool, |c, v| {
        c.set_fixed(v);
        Ok(())
    });
    critter_setter!(engine, host, "health", Dynamic, |c, v| set_num(
        &mut c.traits_mut().health,
        &v,
        "health",
        f64::is_finite,
        "must be a finite number"
    ));
    critter_setter!(engine, host, "restitution", Dynamic, |c, v| set_num(
        &mut c.traits_mut().restitution,
        &v,
        "restitution",
        |e| (0.0..=1.0).contains(&e),
        "must be between 0 and 1"
    ));

    // User properties: c["name"], and c.name when no field of that name exists.
    let h = host.clone();
    engine.register_indexer_get(move |r: &mut CritterRef, name: &str| -> Res<Dynamic> {
        let id = r.0;
        with_env!(h, env => match env.critter(id) {
            Some(c) => match c.props().get(name) {
                Some(p) => Ok(from_prop(p)),
                None => fail(format!(
                    "critter {id} ({}) has no property '{name}'; give it one in its kind's props or spawn map, or test with has(\"{name}\")",
                    env.kinds().name(c.kind())
                )),
            },
            None => Err(gone(id)),
        })
    });
    // Setting an existing property, or one the kind or spawn map declared. A new name is an
    // error, so a typo (`me.velocity = ...`) is caught; `set_prop` adds one on purpose.
    let h = host.clone();
    engine.register_indexer_set(
        move |r: &mut CritterRef, name: &str, value: Dynamic| -> Res<()> {
            set_prop(&h, r.0, name, &value, false)
        },
    );
    let h = host.clone();
    engine.register_fn(
        "set_prop",
        move |r: &mut CritterRef, name: &str, value: Dynamic| -> Res<()> {
            set_prop(&h, r.0, name, &value, true)
        },
    );
    // rhai gives every value a `tag`; for critters, `tag` is a user property like any other.
    let h = host.clone();
    engine.register_get("tag", move |r: &mut CritterRef| -> Res<Dynamic> {
        let id = r.0;
        with_env!(h, env => match env.critter(id) {
            Some(c) => c.props().get("tag").map_or_else(
                || fail(format!("critter {id} has no property 'tag'")),
                |p| Ok(from_prop(p)),
            ),
            None => Err(gone(id)),
        })
    });
    let h = host.clone();
    engine.register_set(
        "tag",
        move |r: &mut CritterRef, value: Dynamic| -> Res<()> {
            set_prop(&h, r.0, "tag", &value, false)
        },
    );
    let h = host.clone();
    engine.register_fn("has", move |r: &mut CritterRef, name: &str| -> Res<bool> {
        let id = r.0;
        with_env!(h, env => Ok(env.critter(id).is_some_and(|c| c.props().contains_key(name))))
    });

    let h = host.clone();
    engine.register_fn(
        "is_kind",
        move |r: &mut CritterRef, kind: &str| -> Res<bool> {
            let id = r.0;
            with_env!(h, env => {
                let kinds = env.kinds();
                match (env.critter(id), kinds.id(kind)) {
                    (Some(c), Ok(k)) => Ok(kinds.is_kind(c.kind(), k)),
                    (None, _) => Err(gone(id)),
                    // An unknown kind name: nothing is of that kind (it may simply not be loaded).
                    (Some(_), Err(_)) => Ok(false),
                }
            })
        },
    );
    let h = host.clone();
    engine.register_fn(
        "touches",
        move |a: &mut CritterRef, b: CritterRef| -> Res<bool> {
            let a = a.0;
            with_env!(h, env => Ok(env.touches(a, b.0)))
        },
    );
    let h = host.clone();
    engine.register_fn(
        "contains",
        move |a: &mut CritterRef, b: CritterRef| -> Res<bool> {
            let a = a.0;
            with_env!(h, env => Ok(env.contains(a, b.0)))
        },
    );
    let h = host.clone();
    engine.register_fn("distance", move |a: &mut CritterRef, b: CritterRef| -> Res<f64> {
        let a = a.0;
        with_env!(h, env => env.distance(a, b.0).map_or_else(|| Err(gone(if env.critter(a).is_none() { a } else { b.0 })), Ok))
    });
    let h = host.clone();
    engine.register_fn(
        "damage",
        move |a: &mut CritterRef, amount: Dynamic| -> Res<()> {
            let a = a.0;
            let amount = num_or(&amount, "damage")?;
            with_env!(h, env => {
                env.damage(a, amount);
                Ok(())
            })
        },
    );
    let h = host.clone();
    engine.register_fn("die", move |a: &mut CritterRef| -> Res<()> {
        let a = a.0;
        with_env!(h, env => {
            env.die(a);
            Ok(())
        })
    });
    let h = host.clone();
    engine.register_fn(
        "collide_default",
        move |a: &mut CritterRef, b: CritterRef| -> Res<bool> {
            let a = a.0;
            with_env!(h, env => env.collide_default(a, b.0).or_else(fail))
        },
    );
}

fn register_world(engine: &mut Engine, host: &Rc<Host>) {
    let h = host.clone();
    engine.register_fn(
        "default_collides_with",
        move |a: CritterRef, b: CritterRef| -> Res<INT> {
            with_env!(h, env => match (env.critter(a.0), env.critter(b.0)) {
                (Some(x), Some(y)) => Ok(rule_code(crate::kind::default_collides_with(x, y))),
                _ => Err(gone(if env.critter(a.0).is_none() { a.0 } else { b.0 })),
            })
        },
    );
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
            with_env!(h, env => {
                let k = env.kinds().id(kind).map_err(lib_err)?;
                Ok(env.critters_of(k).into_iter().map(|id| Dynamic::from(CritterRef(id))).collect())
            })
        },
    );
    let h = host.clone();
    engine.register_fn("count", move |_: &mut WorldRef, kind: &str| -> Res<INT> {
        with_env!(h, env => {
            match env.kinds().id(kind) {
                Ok(k) => Ok(env.critters_of(k).len() as INT),
                Err(_) => Ok(0),
            }
        })
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

    // Seeded randomness, from the world's generator.
    let h = host.clone();
    engine.register_fn("rand", move || -> Res<f64> {
        with_env!(h, env => Ok(env.rng().next_f64()))
    });
    let h = host.clone();
    engine.register_fn("rand", move |lo: Dynamic, hi: Dynamic| -> Res<f64> {
        let (lo, hi) = (
            num_or(&lo, "rand's low end")?,
            num_or(&hi, "rand's high end")?,
        );
        with_env!(h, env => Ok(env.rng().uniform(lo, hi)))
    });
    let h = host.clone();
    engine.register_fn("rand_int", move |lo: INT, hi: INT| -> Res<INT> {
        if hi < lo {
            return fail(format!(
                "rand_int({lo}, {hi}): the high end is below the low end"
            ));
        }
        let span = (hi - lo) as u64 + 1;
        with_env!(h, env => Ok(lo + (env.rng().next_u64() % span) as INT))
    });
}
