//! Spawns requested by scripts: the spawn map (`#{ pos: ..., vel: ..., ... }`), its
//! `on_overlap` policy, where a spawn inside a step was asked for, and the per-step limit on
//! spawns.
//!
//! A spawn from a hook is queued for the end of the step; its `on_overlap` defaults to `"push"`
//! there, so a critter spawned against a wall or another critter never aborts the run. Between
//! steps (a scene, a test) it defaults to `"error"`, as a scene's spawn always checked.

use super::values::{from_svec, num_or, to_prop, vec_of};
use super::{error, fail, CritterRef, Res, HINT_MARK};
use crate::critter::CritterSpec;
use crate::kind::KindId;
use crate::script::env::Env;
use crate::script::host::{with_env, Host};
use crate::script::kind_file::load_into;
use crate::step::pending::OnOverlap;
use crate::step::pending::SpawnOrigin;
use crate::step::spawn::Placed;
use crate::vector::Vector;
use rhai::{Dynamic, Map};
use std::rc::Rc;

/// The fields a spawn map may set.
const SPAWN_FIELDS: &[&str] = &[
    "pos",
    "vel",
    "radius",
    "mass",
    "density",
    "fixed",
    "priority",
    "restitution",
    "health",
    "color",
    "props",
    "on_overlap",
];

/// `on_overlap` of a spawn inside a step when the map does not say.
pub(crate) const HOOK_ON_OVERLAP: OnOverlap = OnOverlap::Push;

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
            // As a kind's `color` default and `me.color`: a colour name or "#rrggbb"; `()` is
            // the kind's colour.
            "color" => match value.clone().try_cast::<rhai::ImmutableString>() {
                Some(c) => match crate::color::checked(&c) {
                    Ok(c) => spec.color = Some(c),
                    Err(why) => return fail(format!("color \"{c}\" of the {kind} to spawn: {why}")),
                },
                None if value.is_unit() => spec.color = None,
                None => {
                    return fail(format!(
                        "color must be a string (a colour name or \"#rrggbb\"), or () for the kind's colour; got {}",
                        super::values::type_of(value)
                    ))
                }
            },
            "fixed" => match value.clone().try_cast::<bool>() {
                Some(b) => spec.fixed = Some(b),
                None => return fail("fixed must be true or false"),
            },
            // Read by `on_overlap_of`.
            "on_overlap" => {}
            "props" => match value.clone().try_cast::<Map>() {
                Some(props) => {
                    for (name, v) in props {
                        spec.props.insert(name.to_string(), to_prop(&v)?);
                    }
                }
                None => return fail("props must be a map, e.g. props: #{ score: 0 }"),
            },
            other => {
                let near = crate::script::kind_refs::closest(other, SPAWN_FIELDS.iter().copied())
                    .map(|f| format!("did you mean '{f}'? "))
                    .unwrap_or_default();
                return fail(format!(
                    "unknown field '{other}' for a spawn; the fields are {}{HINT_MARK}{near}user properties go in props: #{{ ... }}",
                    SPAWN_FIELDS.join(", ")
                ));
            }
        }
    }
    Ok(spec)
}

/// Under `critterbox check` (the host keeps notes): every field of `map` that a spawn would
/// refuse is noted, as the error the spawn at `pos` in `file` would give, and left out, so the
/// set-up goes on past it. Elsewhere `map` comes back whole and a bad field is the spawn's error.
pub(crate) fn note_bad_fields(
    host: &Host,
    kind: &str,
    map: Map,
    file: &str,
    pos: rhai::Position,
) -> Map {
    let mut notes = host.check_notes.borrow_mut();
    let Some(notes) = notes.as_mut() else {
        return map;
    };
    let mut kept = Map::new();
    for (key, value) in map {
        let one: Map = std::iter::once((key.clone(), value.clone())).collect();
        let checked = spec_from_map::<glam::DVec3>(kind, &one)
            .and_then(|_| on_overlap_of(&one, OnOverlap::Error).map(drop));
        match checked {
            Ok(()) => {
                kept.insert(key, value);
            }
            Err(mut e) => {
                e.set_position(pos);
                notes.push(crate::script::errors::eval_error(
                    file,
                    None,
                    None,
                    &e,
                    u64::MAX,
                ));
            }
        }
    }
    kept
}

/// Counts one spawn against the limit of the step `step`.
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

/// The `on_overlap` of a spawn map, or `default`.
fn on_overlap_of(map: &Map, default: OnOverlap) -> Res<OnOverlap> {
    let Some(value) = map.get("on_overlap") else {
        return Ok(default);
    };
    let name = value.clone().into_string().unwrap_or_default();
    OnOverlap::parse(&name).map_or_else(
        || {
            fail(format!(
                "on_overlap is \"error\", \"skip\" or \"push\", not {value}"
            ))
        },
        Ok,
    )
}

/// Spawns from a script, now between steps or queued inside one.
pub(crate) fn spawn_in<V: Vector>(
    env: &mut Env<'_, V>,
    host: &Host,
    kind: &str,
    map: &Map,
) -> Res<Dynamic> {
    spawn_from(env, host, kind, map, None)
}

/// As [`spawn_in`]; a spawn queued inside a step keeps `origin` for its errors.
pub(crate) fn spawn_from<V: Vector>(
    env: &mut Env<'_, V>,
    host: &Host,
    kind: &str,
    map: &Map,
    origin: Option<Box<SpawnOrigin>>,
) -> Res<Dynamic> {
    count_spawn(host, env.step_count())?;
    if let Err(e) = env.kinds().id(kind) {
        return Err(unknown_kind_in_step(kind, e));
    }
    let spec = spec_from_map::<V>(kind, map)?;
    let in_step = env.world().is_none();
    let policy = on_overlap_of(
        map,
        if in_step {
            HOOK_ON_OVERLAP
        } else {
            OnOverlap::Error
        },
    )?;
    match env
        .spawn_placed(spec, policy, origin)
        .map_err(|e| host.carry(e))?
    {
        Some(Placed::Added(id)) => Ok(Dynamic::from(CritterRef(id))),
        Some(Placed::Skipped(why)) => {
            env.log(format!("warning: spawn skipped: {why}"));
            Ok(Dynamic::UNIT)
        }
        None => Ok(Dynamic::UNIT),
    }
}

/// The error for kind `kind`, not loaded in a world that is in the middle of a step.
pub(crate) fn unknown_kind_in_step(kind: &str, e: crate::Error) -> Box<rhai::EvalAltResult> {
    let known = match &e {
        crate::Error::UnknownKind { known, .. } => known.clone(),
        _ => String::new(),
    };
    let path = std::path::Path::new(kind);
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or(kind);
    if kind.ends_with(".rhai") || kind.contains('/') {
        return error(format!(
            "unknown kind '{kind}' (known kinds: {known}){HINT_MARK}inside a step, spawn by the kind's name: \
             load_kind(\"{kind}\") in the scene, then spawn(\"{stem}\", ...) here",
        ));
    }
    error(format!(
        "unknown kind '{kind}' (known kinds: {known}){HINT_MARK}a kind named as a string literal in a kind file loads before the run; \
         a name computed at run time must be loaded first with load_kind(\"{kind}\") in the scene or test",
    ))
}

/// The id of kind `name` for a query (`is_kind`, `count`, `critters_of`, `nearby`,
/// `nearest`). Between steps the kind loads on first use. Inside a step, a kind that is not in
/// the world has no critters there (`None`); a name that is no kind at all (often a typo,
/// which `critterbox check` reports when it is a literal) also logs a warning, once per name,
/// as a kind may name kinds a game defines only sometimes (a bullet's `targets`).
pub(crate) fn kind_for_query(host: &Rc<Host>, name: &str) -> Res<Option<KindId>> {
    let found = with_env!(host, env => Ok(env.kinds().id(name)))?;
    let e = match found {
        Ok(id) => return Ok(Some(id)),
        Err(e) => e,
    };
    let rt = host.runtime()?;
    let in_step = with_env!(host, env => Ok(env.world().is_none()))?;
    if in_step {
        if !rt.kind_exists(name) && rt.warn_unknown_kind(name) {
            let known = match &e {
                crate::Error::UnknownKind { known, .. } => known.clone(),
                _ => String::new(),
            };
            let line = format!(
                "warning: no kind '{name}' exists (known kinds: {known}); asking for it finds none"
            );
            with_env!(host, env => { env.log(line); Ok(()) })?;
        }
        return Ok(None);
    }
    with_env!(host, env => match env.world() {
        Some(world) => load_into(&rt, world, name).map(Some).map_err(|e| host.carry(e)),
        None => Err(unknown_kind_in_step(name, e)),
    })
}

/// Where a spawn inside a step is asked for: the call's file and position, the hook around it
/// and the critter it runs for (a hook's first parameter), for the spawn's errors.
pub(crate) fn origin_here(
    host: &Host,
    ctx: &rhai::EvalContext,
    pos: rhai::Position,
) -> Option<Box<SpawnOrigin>> {
    let rt = host.runtime().ok()?;
    let critter = ctx
        .scope()
        .iter()
        .next()
        .and_then(|(_, _, v)| v.try_cast::<CritterRef>())
        .map(|c| c.0);
    let here: Res<Option<(u64, Option<String>)>> = with_env!(host, env => {
        if env.world().is_some() {
            Ok(None)
        } else {
            let kind = critter
                .and_then(|id| env.critter(id))
                .map(|c| env.kinds().name(c.kind()).to_string());
            Ok(Some((env.step_count(), kind)))
        }
    });
    let (step, kind) = here.ok().flatten()?;
    let kind_file = kind
        .as_ref()
        .and_then(|k| rt.kinds.borrow().get(k).map(|d| d.file.clone()));
    let file = ctx
        .source()
        .map(str::to_string)
        .or(kind_file)
        .unwrap_or_default();
    let hook = rt
        .sources
        .borrow()
        .iter()
        .find(|s| s.path == file)
        .and_then(|s| enclosing_fn(&s.text, pos.line()?));
    Some(Box::new(SpawnOrigin {
        file,
        line: pos.line(),
        column: pos.position(),
        kind,
        hook,
        critter,
        step,
    }))
}

/// The name of the last `fn name(` that starts a line at or before line `line` of `text`.
fn enclosing_fn(text: &str, line: usize) -> Option<String> {
    text.lines()
        .take(line)
        .filter_map(|l| l.trim_start().strip_prefix("fn "))
        .filter_map(|rest| rest.split('(').next())
        .map(|name| name.trim().to_string())
        .last()
}
