//! Spawns requested by scripts: the spawn map (`#{ pos: ..., vel: ..., ... }`) and the per-step
//! limit on spawns.

use super::values::{from_svec, num_or, to_prop, vec_of};
use super::{fail, lib_err, CritterRef, Res};
use crate::critter::CritterSpec;
use crate::script::env::Env;
use crate::script::host::Host;
use crate::vector::Vector;
use rhai::{Dynamic, Map};

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
