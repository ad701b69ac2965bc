//! Building a scene's world from a script: `world(#{ ... })`, `load_kind`, walls
//! (`wall`, `wall_box`, `walls_around`), spawning patterns (`row`, `ring`, `grid`, `scatter`),
//! `spawn(kind, #{ ... })` and `stop(reason)`.

use super::critter::CritterRef;
use super::registry::Api;
use super::spawn::{spawn_in, spec_from_map};
use super::values::{from_svec, num, num_or, to_svec};
use super::world::WorldRef;
use super::{error, fail, fail_hint, lib_err, Res};
use crate::border::Border;
use crate::scenes::{AnyWorld, Scene};
use crate::script::env::Env;
use crate::script::host::{with_env, Host};
use crate::script::kind_file::load_into;
use crate::vector::{fmt_vec, Vector};
use crate::wall::{WallBox, DEFAULT_WALL_THICKNESS};
use crate::world::{World, WorldConfig};
use glam::{DMat3, DVec2, DVec3};
use rhai::{Array, Dynamic, Map, INT};
use std::rc::Rc;

/// The keys `world(#{ ... })` accepts.
const WORLD_KEYS: &[&str] = &[
    "dim", "size", "min", "border", "gravity", "dt", "seed", "method", "sleep", "steps",
];

/// Loads kind `name` into whatever world scripts act on, unless it is there already; the
/// kind's name (a path such as `"kinds/spark.rhai"` names the kind its file defines).
fn ensure_kind(host: &Rc<Host>, name: &str) -> Res<String> {
    let known = with_env!(host, env => Ok(env.kinds().id(name).is_ok()))?;
    if known {
        return Ok(name.to_string());
    }
    let rt = host.runtime()?;
    with_env!(host, env => match env.world() {
        Some(world) => match load_into(&rt, world, name) {
            Ok(id) => Ok(world.kinds().name(id).to_string()),
            Err(e) => Err(host.carry(e)),
        },
        None => fail(format!(
            "unknown kind '{name}': kinds are loaded between steps; call load_kind(\"{name}\") in the scene script"
        )),
    })
}

/// Loads kind `name` with the constants `constants` names set (the runtime applies them to its
/// text as it is built); a kind loaded already cannot take them any more.
fn load_kind_setting(host: &Rc<Host>, name: &str, constants: &Map) -> Res<()> {
    let rt = host.runtime()?;
    // A kind given by path is named after its file.
    let kind = if name.ends_with(".rhai") || name.contains('/') {
        std::path::Path::new(name)
            .file_stem()
            .map_or_else(|| name.to_string(), |s| s.to_string_lossy().into_owned())
    } else {
        name.to_string()
    };
    let loaded = rt.kinds.borrow().contains_key(&kind)
        || with_env!(host, env => Ok(env.kinds().id(&kind).is_ok()))?;
    if loaded && !constants.is_empty() {
        return fail_hint(
            format!("load_kind(\"{name}\", ...): the kind '{kind}' is loaded already, with its constants as they were"),
            "set its constants before it is first spawned or loaded: call load_kind with them first",
        );
    }
    rt.kind_sets.borrow_mut().entry(kind).or_default().extend(
        constants
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string())),
    );
    ensure_kind(host, name).map(drop)
}

fn config<V: Vector>(map: &Map) -> Res<(WorldConfig<V>, Option<u64>)> {
    let mut size = V::splat(10.0);
    let mut min = V::zero();
    let mut config = WorldConfig::new(V::zero(), V::splat(10.0));
    let mut steps = None;
    for (key, value) in map {
        match key.as_str() {
            "dim" => {}
            "size" => {
                size = match num(value) {
                    Some(s) => V::splat(s),
                    None => from_svec(vec_arg(value, "size")?),
                }
            }
            "min" => min = from_svec(vec_arg(value, "min")?),
            "border" => {
                config.border = value.to_string().parse::<Border>().map_or_else(fail, Ok)?;
            }
            "gravity" => config.gravity = from_svec(vec_arg(value, "gravity")?),
            "dt" => config.dt = num_or(value, "dt")?,
            "seed" => {
                config.seed = value.as_int().ok().filter(|s| *s >= 0).map_or_else(
                    || fail("seed must be a whole number >= 0"),
                    |s| Ok(s as u64),
                )?
            }
            "method" => {
                config.method = value
                    .to_string()
                    .parse::<crate::method::Method>()
                    .map_or_else(fail, Ok)?;
            }
            "sleep" => {
                config.sleep = value
                    .as_bool()
                    .map_or_else(|_| fail("sleep must be true or false"), Ok)?
            }
            "steps" => {
                steps = Some(value.as_int().ok().filter(|s| *s >= 0).map_or_else(
                    || fail("steps must be a whole number >= 0"),
                    |s| Ok(s as u64),
                )?)
            }
            other => {
                return fail(format!(
                    "unknown world setting '{other}'; the settings are {}",
                    WORLD_KEYS.join(", ")
                ))
            }
        }
    }
    config.min = min;
    config.max = min + size;
    Ok((config, steps))
}

fn vec_arg(d: &Dynamic, what: &str) -> Res<DVec3> {
    d.clone().try_cast::<DVec3>().map_or_else(
        || {
            fail(format!(
                "{what} must be a Vec (e.g. vec(20, 10)) or a number"
            ))
        },
        Ok,
    )
}

/// `world(#{ dim: 2, size: vec(20, 10), ... })`: makes the scene's world and points scripts at it.
fn make_world(host: &Rc<Host>, map: &Map) -> Res<WorldRef> {
    if host.has_scene() {
        return fail("this scene already made its world; call world(#{ ... }) once");
    }
    if host.kind_decl.borrow().is_some() {
        return fail("a kind file cannot make a world; world(#{ ... }) belongs in a scene script");
    }
    let dim = match map.get("dim") {
        None => 2,
        Some(d) => d.as_int().map_err(|_| error("dim must be 2 or 3"))?,
    };
    let seed = host.seed_override.get();
    let (any, steps) = match dim {
        2 => {
            let (mut c, steps) = config::<DVec2>(map)?;
            c.seed = seed.unwrap_or(c.seed);
            (AnyWorld::D2(World::new(c).map_err(lib_err)?), steps)
        }
        3 => {
            let (mut c, steps) = config::<DVec3>(map)?;
            c.seed = seed.unwrap_or(c.seed);
            (AnyWorld::D3(World::new(c).map_err(lib_err)?), steps)
        }
        other => return fail(format!("dim must be 2 or 3, not {other}")),
    };
    host.scene_steps.set(steps);
    host.put_scene(Scene::new("world", any, steps.unwrap_or(600)))?;
    Ok(WorldRef)
}

/// Runs `f` on the world between steps, or fails with `what` inside a step.
macro_rules! on_world {
    ($host:expr, $what:expr, $w:ident => $body:expr) => {
        with_env!($host, env => match env.world() {
            Some($w) => $body,
            None => fail(concat!($what, " works in scene scripts (top level and on_step), not inside a kind's hooks")),
        })
    };
}

fn add_wall_2d_or_3d<V: Vector>(w: &mut World<V>, wall: Res<WallBox<V>>) -> Res<CritterRef> {
    let id = w.add_wall(wall?).map_err(lib_err)?;
    Ok(CritterRef(id))
}

fn segment<V: Vector>(a: DVec3, b: DVec3, t: f64) -> Res<WallBox<V>> {
    if V::DIM != 2 {
        return fail("wall(a, b) is for 2D worlds; in 3D use wall_box(min, max)");
    }
    let wall = WallBox::segment(DVec2::new(a.x, a.y), DVec2::new(b.x, b.y), t).map_err(lib_err)?;
    let any: Box<dyn std::any::Any> = Box::new(wall);
    any.downcast::<WallBox<V>>()
        .map(|w| *w)
        .map_or_else(|_| fail("wall(a, b) is for 2D worlds"), Ok)
}

fn dim_of<V: Vector>(_: &Env<'_, V>) -> usize {
    V::DIM
}

/// Walls of thickness `t` lining the inside of the world box.
fn walls_around<V: Vector>(w: &mut World<V>, t: f64) -> Res<Array> {
    let (min, max) = (w.topology().min, w.topology().max);
    let mut out = Array::new();
    for axis in 0..V::DIM {
        for low in [true, false] {
            let (mut lo, mut hi) = (min, max);
            if low {
                hi.set(axis, min.get(axis) + t);
            } else {
                lo.set(axis, max.get(axis) - t);
            }
            let wall = WallBox::aligned(lo, hi).map_err(lib_err)?;
            out.push(Dynamic::from(CritterRef(
                w.add_wall(wall).map_err(lib_err)?,
            )));
        }
    }
    Ok(out)
}

pub(super) fn register(api: &mut Api) {
    api.func("world", |h| move |map: Map| make_world(&h, &map));
    api.kind_func("load_kind", |h| {
        move |name: &str| -> Res<()> { ensure_kind(&h, name).map(drop) }
    });
    // load_kind("boid", #{ SIGHT: 3 }): the kind with its constants set, as `--set boid.SIGHT=3`.
    api.kind_func("load_kind", |h| {
        move |name: &str, constants: Map| -> Res<()> { load_kind_setting(&h, name, &constants) }
    });

    api.func("wall", |h| {
        move |_: &mut WorldRef, a: DVec3, b: DVec3| -> Res<CritterRef> {
            on_world!(h, "wall", w => add_wall_2d_or_3d(w, segment(a, b, DEFAULT_WALL_THICKNESS)))
        }
    });
    api.func("wall", |h| {
        move |_: &mut WorldRef, a: DVec3, b: DVec3, t: Dynamic| -> Res<CritterRef> {
            let t = num_or(&t, "wall thickness")?;
            on_world!(h, "wall", w => add_wall_2d_or_3d(w, segment(a, b, t)))
        }
    });
    api.func("wall_box", |h| move |_: &mut WorldRef, lo: DVec3, hi: DVec3| -> Res<CritterRef> {
        on_world!(h, "wall_box", w => add_wall_2d_or_3d(w, WallBox::aligned(from_svec(lo), from_svec(hi)).map_err(lib_err)))
    });
    api.func("wall_box", |h| {
        move |_: &mut WorldRef, center: DVec3, size: DVec3, angle: Dynamic| -> Res<CritterRef> {
            let angle = num_or(&angle, "wall_box angle")?;
            on_world!(h, "wall_box", w => {
                let rot = DMat3::from_rotation_z(angle);
                let wall = rotated_box(from_svec(center), size, rot);
                add_wall_2d_or_3d(w, wall)
            })
        }
    });
    api.func("walls_around", |h| {
        move |_: &mut WorldRef| -> Res<Array> {
            on_world!(h, "walls_around", w => walls_around(w, DEFAULT_WALL_THICKNESS))
        }
    });
    api.func("walls_around", |h| {
        move |_: &mut WorldRef, t: Dynamic| -> Res<Array> {
            let t = num_or(&t, "wall thickness")?;
            on_world!(h, "walls_around", w => walls_around(w, t))
        }
    });

    // Spawning patterns (scene scripts; kinds load on first use).
    api.kind_func("row", |h| {
        move |_: &mut WorldRef,
              kind: &str,
              start: DVec3,
              step: DVec3,
              count: INT,
              map: Map|
              -> Res<Array> {
            let positions = (0..count.max(0)).map(|i| start + step * i as f64);
            spawn_at(&h, kind, &map, positions)
        }
    });
    api.kind_func("ring", |h| {
        move |_: &mut WorldRef,
              kind: &str,
              center: DVec3,
              radius: Dynamic,
              count: INT,
              map: Map|
              -> Res<Array> {
            let r = num_or(&radius, "ring radius")?;
            let positions = (0..count.max(0)).map(|i| {
                let a = std::f64::consts::TAU * i as f64 / count as f64;
                center + DVec3::new(r * a.cos(), r * a.sin(), 0.0)
            });
            spawn_at(&h, kind, &map, positions)
        }
    });
    api.kind_func("grid", |h| {
        move |_: &mut WorldRef,
              kind: &str,
              lo: DVec3,
              hi: DVec3,
              spacing: Dynamic,
              map: Map|
              -> Res<Array> {
            let s = num_or(&spacing, "grid spacing")?;
            if !(s > 0.0 && s.is_finite()) {
                return fail(format!("grid spacing {s} must be a finite number > 0"));
            }
            let dim = with_env!(h, env => Ok(dim_of(env)))?;
            let count = |a: f64, b: f64| ((b - a) / s).floor().max(0.0) as i64 + 1;
            let (nx, ny, nz) = (
                count(lo.x, hi.x),
                count(lo.y, hi.y),
                if dim == 3 { count(lo.z, hi.z) } else { 1 },
            );
            if nx * ny * nz > 10_000_000 {
                return fail("that grid would hold more than 10 million critters");
            }
            let positions = (0..nz).flat_map(|k| {
                (0..ny).flat_map(move |j| {
                    (0..nx).map(move |i| lo + DVec3::new(i as f64 * s, j as f64 * s, k as f64 * s))
                })
            });
            spawn_at(&h, kind, &map, positions)
        }
    });
    api.kind_func("scatter", |h| {
        move |_: &mut WorldRef, kind: &str, count: INT, map: Map| -> Res<Array> {
            let kind = ensure_kind(&h, kind)?;
            // `within` picks the region; the rest of the map is each spawn's.
            let mut map = map;
            let within = map.remove("within");
            let asked = count.max(0) as usize;
            let mut out = Array::new();
            for placed in 0..asked {
                let scatter = Scatter {
                    kind: &kind,
                    map: &map,
                    within: within.as_ref(),
                    placed,
                    asked,
                };
                out.push(on_world!(h, "scatter", w => scatter_one(w, &h, &scatter))?);
            }
            Ok(out)
        }
    });
    api.func("stop", |h| {
        move |_: &mut WorldRef, reason: Dynamic| -> Res<()> {
            *h.stop.borrow_mut() = Some(reason.to_string());
            Ok(())
        }
    });
    // spawn(kind, #{ ... }). `spawn` is a reserved word in rhai, so it is custom syntax: now
    // between steps (loading the kind on first use), queued inside a step.
    let registered = api.kind_syntax(&["spawn", "(", "$expr$", ",", "$expr$", ")"], |h| {
        Box::new(move |ctx, inputs| {
            // Errors raised here have no position of their own: give them the spawn's.
            let pos = inputs[0].position();
            spawn_syntax(&h, ctx, inputs).map_err(|mut e| {
                if e.position().is_none() {
                    e.set_position(pos);
                }
                e
            })
        })
    });
    debug_assert!(registered.is_ok());
}

fn spawn_syntax(
    h: &Rc<Host>,
    ctx: &mut rhai::EvalContext,
    inputs: &[rhai::Expression],
) -> Res<Dynamic> {
    let kind = ctx.eval_expression_tree(&inputs[0])?;
    let map = ctx.eval_expression_tree(&inputs[1])?;
    let Some(kind) = kind.clone().try_cast::<rhai::ImmutableString>() else {
        return fail(format!(
            "spawn's first argument is the kind's name, not {}",
            kind.type_name()
        ));
    };
    let Some(map) = map.clone().try_cast::<Map>() else {
        return fail(format!(
            "spawn's second argument is a map like #{{ pos: vec(1, 2) }}, not {}",
            map.type_name()
        ));
    };
    let in_world = with_env!(h, env => Ok(env.world().is_some()))?;
    let kind = if in_world {
        ensure_kind(h, &kind)?
    } else {
        kind.to_string()
    };
    // Under `critterbox check`, a bad field is reported and left out, and the scene goes on.
    let map = if in_world {
        let file = ctx.source().unwrap_or_default().to_string();
        super::spawn::note_bad_fields(h, &kind, map, &file, inputs[0].position())
    } else {
        map
    };
    let origin = if in_world {
        None
    } else {
        super::spawn::origin_here(h, ctx, inputs[0].position())
    };
    with_env!(h, env => super::spawn::spawn_from(env, h, &kind, &map, origin))
}

fn rotated_box<V: Vector>(center: V, size: DVec3, rot: DMat3) -> Res<WallBox<V>> {
    let any: &dyn std::any::Any = &rot;
    let frame = if V::DIM == 3 {
        any.downcast_ref::<V::Frame>().copied()
    } else {
        let dir = DVec2::new(rot.x_axis.x, rot.x_axis.y);
        let d: &dyn std::any::Any = &dir;
        d.downcast_ref::<V::Frame>().copied()
    };
    let frame = frame.map_or_else(|| fail("cannot orient that wall"), Ok)?;
    WallBox::new(center, from_svec::<V>(size) * 0.5, frame).map_err(lib_err)
}

/// One critter of `kind` at each position, with the rest of `map` (the kind loads on first use).
fn spawn_at(
    host: &Rc<Host>,
    kind: &str,
    map: &Map,
    positions: impl Iterator<Item = DVec3>,
) -> Res<Array> {
    let kind = ensure_kind(host, kind)?;
    let mut out = Array::new();
    for p in positions {
        let mut m = map.clone();
        m.insert("pos".into(), Dynamic::from(p));
        out.push(with_env!(host, env => spawn_in(env, host, &kind, &m))?);
    }
    Ok(out)
}

/// How many tries `scatter` makes for each critter before it gives up.
const SCATTER_TRIES: usize = 1000;

/// One critter of a `w.scatter(kind, n, #{ ... })`: the kind, its spawn map, the region
/// (`within`, else the whole box), and how many of the `asked` are placed already.
struct Scatter<'a> {
    kind: &'a str,
    map: &'a Map,
    within: Option<&'a Dynamic>,
    placed: usize,
    asked: usize,
}

/// The region `within: [vec(x0, y0), vec(x1, y1)]` names (two opposite corners), checked to lie
/// in the world box `min..max` and to hold a critter of radius `r`.
fn scatter_region<V: Vector>(within: &Dynamic, min: V, max: V, r: f64) -> Res<(V, V)> {
    let shape = "within is a region, two opposite corners: #{ within: [vec(x0, y0), vec(x1, y1)] }";
    let corners = within
        .clone()
        .try_cast::<Array>()
        .filter(|a| a.len() == 2)
        .and_then(|a| {
            let a0 = a[0].clone().try_cast::<DVec3>()?;
            let a1 = a[1].clone().try_cast::<DVec3>()?;
            Some((from_svec::<V>(a0), from_svec::<V>(a1)))
        });
    let Some((a, b)) = corners else {
        return fail(format!("{shape}, not {}", super::values::show(within)));
    };
    let (mut lo, mut hi) = (a, b);
    for axis in 0..V::DIM {
        let (x, y) = (a.get(axis), b.get(axis));
        lo.set(axis, x.min(y));
        hi.set(axis, x.max(y));
    }
    let region = || format!("{} to {}", fmt_vec(lo), fmt_vec(hi));
    if !(lo.all_finite() && hi.all_finite()) {
        return fail(format!(
            "within {}: every coordinate must be a finite number",
            region()
        ));
    }
    for axis in 0..V::DIM {
        if lo.get(axis) < min.get(axis) || hi.get(axis) > max.get(axis) {
            return fail_hint(
                format!(
                    "within {}: the region reaches out of the world box {} to {}",
                    region(),
                    fmt_vec(min),
                    fmt_vec(max)
                ),
                "give corners inside the box",
            );
        }
        if hi.get(axis) - lo.get(axis) < 2.0 * r {
            return fail_hint(
                format!(
                    "within {}: the region is narrower than the critters' diameter {} along {}",
                    region(),
                    2.0 * r,
                    ["x", "y", "z"][axis]
                ),
                "make the region larger or the radius smaller",
            );
        }
    }
    Ok((lo, hi))
}

/// One critter at a random free place (seeded) in the region `within` names or else the world
/// box, clear of walls and critters.
fn scatter_one<V: Vector>(w: &mut World<V>, host: &Host, s: &Scatter) -> Res<Dynamic> {
    let kind = s.kind;
    let spec = spec_from_map::<V>(kind, s.map)?;
    let kid = w.kinds().id(kind).map_err(lib_err)?;
    let r = spec.radius.unwrap_or(w.kinds().get(kid).defaults.radius);
    let (min, max) = match s.within {
        Some(within) => scatter_region(within, w.topology().min, w.topology().max, r)?,
        None => (w.topology().min, w.topology().max),
    };
    for _ in 0..SCATTER_TRIES {
        let mut p = V::zero();
        for axis in 0..V::DIM {
            p.set(axis, w.rng().uniform(min.get(axis) + r, max.get(axis) - r));
        }
        // Walls one by one (they are few), disks through the neighbour grid: the same test on
        // the same critters as a scan over all of them, so the same places are taken.
        let topo = *w.topology();
        let clear_of_walls = w.state.walls.iter().all(|&id| {
            w.get(id)
                .and_then(|c| Some((c.pos, c.wall()?)))
                .is_none_or(|(pos, wall)| {
                    crate::contact::contact_wall_ball(wall, topo.delta(pos, p), r).is_none()
                })
        });
        let free = clear_of_walls && !w.overlaps_critter(p, r);
        if free {
            let mut m = s.map.clone();
            m.insert("pos".into(), Dynamic::from(to_svec(p)));
            let spec = spec_from_map::<V>(kind, &m)?;
            let id = w.spawn(spec).map_err(|e| host.carry(e))?;
            return Ok(Dynamic::from(CritterRef(id)));
        }
    }
    let place = match s.within {
        Some(_) => format!("the region {} to {}", fmt_vec(min), fmt_vec(max)),
        None => "the world".to_string(),
    };
    fail_hint(
        format!(
            "no free place for another {kind} of radius {r} after {SCATTER_TRIES} tries: {} of \
             the {} asked for are placed, and {place} is too full",
            s.placed, s.asked
        ),
        "ask for fewer, give them a smaller radius, or give them more room",
    )
}
