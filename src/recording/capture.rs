//! What the recorder takes from a world after each step: the hash and totals in one pass over the
//! critters, the step's events, and (on keyframes) the full state as columns.

use super::foxglove::{kind_color, Rgba};
use super::schema::{
    id_key, CollisionsMsg, Float, Floats, LifecycleMsg, LogMsg, StateMsg, TotalsMsg, WallMsg,
    CAUSE_DAMAGE, CAUSE_DIE, CAUSE_REMOVED,
};
use crate::scenes::AnyWorld;
use crate::step::events::{DeathCause, HookAt};
use crate::vector::Vector;
use crate::world::World;
use std::collections::BTreeMap;

/// The kinds of a world: names (index = kind id) and colours.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KindTable {
    /// Names, by kind id.
    pub names: Vec<String>,
    /// Colours, by kind id.
    pub colors: Vec<Rgba>,
}

/// Everything recorded about one step.
#[derive(Clone, Debug)]
pub struct StepRecord {
    /// Steps taken.
    pub step: u64,
    /// Simulated time.
    pub time: f64,
    /// `World::state_hash()`.
    pub hash: u64,
    /// Totals.
    pub totals: TotalsMsg,
    /// The step's collisions, if any.
    pub collisions: Option<CollisionsMsg>,
    /// The step's spawns, deaths and damage, if any.
    pub lifecycle: Option<LifecycleMsg>,
    /// The step's log lines, if any.
    pub log: Option<LogMsg>,
    /// The full state, on keyframes.
    pub state: Option<StateMsg>,
    /// The kind table, when it changed (always on the first record).
    pub kinds: Option<KindTable>,
}

/// The kind table of a world.
pub fn kind_table<V: Vector>(world: &World<V>) -> KindTable {
    let mut t = KindTable::default();
    for (id, kind) in world.kinds().iter() {
        let i = id.0 as usize;
        if t.names.len() <= i {
            t.names.resize(i + 1, String::new());
            t.colors.resize(i + 1, [0.5, 0.5, 0.5, 1.0]);
        }
        t.names[i] = kind.name.clone();
        t.colors[i] = kind_color(&kind.name, kind.defaults.color.as_deref(), i);
    }
    t
}

/// Hash and totals in one pass over the critters.
pub fn hash_and_totals<V: Vector>(world: &World<V>) -> (u64, TotalsMsg) {
    let (hash, energy, momentum) = world.state_hash_and_totals();
    let stats = world.stats();
    let totals = TotalsMsg {
        step: world.step_count(),
        time: Float(world.time()),
        kinetic_energy: Float(energy),
        momentum: Floats((0..V::DIM).map(|a| momentum.get(a)).collect()),
        critters: world.critters().len() as u64,
        collisions: stats.collisions as u64,
        impacts: stats.impacts as u64,
        contacts: stats.contacts as u64,
    };
    (hash, totals)
}

/// The full state of a world as columns.
pub fn state<V: Vector>(world: &World<V>) -> StateMsg {
    let n = world.critters().len();
    let col = || Floats(Vec::with_capacity(n));
    let mut s = StateMsg {
        step: world.step_count(),
        time: Float(world.time()),
        kinds: kind_table(world).names,
        id: Vec::with_capacity(n),
        kind: Vec::with_capacity(n),
        x: col(),
        y: col(),
        z: (V::DIM == 3).then(col),
        vx: col(),
        vy: col(),
        vz: (V::DIM == 3).then(col),
        radius: col(),
        mass: col(),
        health: col(),
        restitution: col(),
        priority: col(),
        fixed: Vec::with_capacity(n),
        alive: Vec::with_capacity(n),
        props: BTreeMap::new(),
        walls: Vec::new(),
        rng: Some(world.rng_state().to_vec()),
        free: Some(world.critters().free_ids().map(id_key).collect()),
        contact_impulses: world
            .contact_impulses()
            .map(|(a, b, j)| (id_key(a), id_key(b), Float(j)))
            .collect(),
        quiet_steps: world
            .quiet_steps()
            .map(|(id, q, island)| (id_key(id), q, island.map(id_key)))
            .collect(),
        vars: world.vars().clone(),
        colors: BTreeMap::new(),
    };
    for c in world.critters().iter() {
        let id = id_key(c.id());
        s.id.push(id);
        s.kind.push(c.kind().0);
        s.x.0.push(c.pos.get(0));
        s.y.0.push(c.pos.get(1));
        s.vx.0.push(c.vel.get(0));
        s.vy.0.push(c.vel.get(1));
        if let (Some(z), Some(vz)) = (&mut s.z, &mut s.vz) {
            z.0.push(c.pos.get(2));
            vz.0.push(c.vel.get(2));
        }
        s.radius.0.push(c.radius());
        s.mass.0.push(c.mass());
        s.health.0.push(c.health());
        s.restitution.0.push(c.restitution());
        s.priority.0.push(c.priority());
        s.fixed.push(c.is_fixed());
        s.alive.push(c.is_alive());
        if !c.props().is_empty() {
            s.props.insert(id.to_string(), c.props().clone());
        }
        if let Some(color) = c.color() {
            s.colors.insert(id.to_string(), color.to_string());
        }
        if let Some(w) = c.wall() {
            let v = |x: V| Floats((0..V::DIM).map(|a| x.get(a)).collect());
            s.walls.push(WallMsg {
                id,
                center: v(w.center),
                half: v(w.half),
                axes: (0..V::DIM).map(|a| v(V::frame_axis(&w.frame, a))).collect(),
            });
        }
    }
    s
}

/// The events of the last step.
pub fn events<V: Vector>(
    world: &World<V>,
) -> (Option<CollisionsMsg>, Option<LifecycleMsg>, Option<LogMsg>) {
    let ev = world.events();
    let (step, time) = (world.step_count(), Float(world.time()));
    let collisions = (!ev.collisions.is_empty()).then(|| {
        // Columns sized once: this runs on the simulation thread every step.
        let n = ev.collisions.len();
        let col = || Floats(Vec::with_capacity(n));
        let mut m = CollisionsMsg {
            step,
            time,
            caller: Vec::with_capacity(n),
            arg: Vec::with_capacity(n),
            px: col(),
            py: col(),
            pz: (V::DIM == 3).then(col),
            nx: col(),
            ny: col(),
            nz: (V::DIM == 3).then(col),
            impulse: col(),
        };
        for e in &ev.collisions {
            m.caller.push(id_key(e.caller));
            m.arg.push(id_key(e.arg));
            m.px.0.push(e.point.get(0));
            m.py.0.push(e.point.get(1));
            m.nx.0.push(e.normal.get(0));
            m.ny.0.push(e.normal.get(1));
            if let (Some(pz), Some(nz)) = (&mut m.pz, &mut m.nz) {
                pz.0.push(e.point.get(2));
                nz.0.push(e.normal.get(2));
            }
            m.impulse.0.push(e.impulse);
        }
        m
    });
    let any_life = !(ev.spawns.is_empty() && ev.deaths.is_empty() && ev.damages.is_empty());
    let lifecycle = any_life.then(|| lifecycle_msg(world, step, time));
    let log = (!ev.log.is_empty()).then(|| LogMsg {
        step,
        time,
        lines: ev.log.clone(),
    });
    (collisions, lifecycle, log)
}

/// The lifecycle message of the last step: spawns, deaths and damage, and who caused each.
fn lifecycle_msg<V: Vector>(world: &World<V>, step: u64, time: Float) -> LifecycleMsg {
    let ev = world.events();
    let kinds = world.kinds();
    let by = |h: &Option<HookAt>| h.map(|h| id_key(h.critter));
    let hook = |h: &Option<HookAt>| h.map(|h| h.hook.to_string());
    let (die_cause, die_at): (Vec<String>, Vec<Option<HookAt>>) = ev
        .death_info
        .iter()
        .map(|d| match d.cause {
            DeathCause::Die(at) => (CAUSE_DIE.to_string(), at),
            DeathCause::Damage(at) => (CAUSE_DAMAGE.to_string(), at),
            DeathCause::Removed => (CAUSE_REMOVED.to_string(), None),
        })
        .unzip();
    let sources: Vec<Option<HookAt>> = ev.damage_info.iter().map(|d| d.source).collect();
    LifecycleMsg {
        step,
        time,
        spawn: ev.spawns.iter().map(|&id| id_key(id)).collect(),
        spawn_kind: ev
            .spawns
            .iter()
            .map(|&id| {
                world
                    .get(id)
                    .map_or("?", |c| kinds.name(c.kind()))
                    .to_string()
            })
            .collect(),
        spawn_by: ev.spawn_by.iter().map(by).collect(),
        spawn_hook: ev.spawn_by.iter().map(hook).collect(),
        die: ev.deaths.iter().map(|&id| id_key(id)).collect(),
        die_kind: ev
            .death_info
            .iter()
            .map(|d| kinds.name(d.kind).to_string())
            .collect(),
        die_cause,
        die_by: die_at.iter().map(by).collect(),
        die_hook: die_at.iter().map(hook).collect(),
        damage_id: ev.damages.iter().map(|&(id, _)| id_key(id)).collect(),
        damage: Floats(ev.damages.iter().map(|&(_, d)| d).collect()),
        damage_kind: ev
            .damage_info
            .iter()
            .map(|d| kinds.name(d.kind).to_string())
            .collect(),
        damage_source: sources.iter().map(by).collect(),
        damage_hook: sources.iter().map(hook).collect(),
    }
}

/// Captures a step of `world`: always hash, totals and events; the full state when `full`; the
/// kind table when its size is not `known_kinds`.
pub fn capture(world: &AnyWorld, full: bool, known_kinds: usize) -> StepRecord {
    match world {
        AnyWorld::D2(w) => capture_world(w, full, known_kinds),
        AnyWorld::D3(w) => capture_world(w, full, known_kinds),
    }
}

fn capture_world<V: Vector>(world: &World<V>, full: bool, known_kinds: usize) -> StepRecord {
    let (hash, totals) = hash_and_totals(world);
    let (collisions, lifecycle, log) = events(world);
    StepRecord {
        step: world.step_count(),
        time: world.time(),
        hash,
        totals,
        collisions,
        lifecycle,
        log,
        state: full.then(|| state(world)),
        kinds: (world.kinds().len() != known_kinds).then(|| kind_table(world)),
    }
}

/// The full state of any world.
pub fn any_state(world: &AnyWorld) -> StateMsg {
    match world {
        AnyWorld::D2(w) => state(w),
        AnyWorld::D3(w) => state(w),
    }
}

/// Hash and totals of any world.
pub fn any_hash_and_totals(world: &AnyWorld) -> (u64, TotalsMsg) {
    match world {
        AnyWorld::D2(w) => hash_and_totals(w),
        AnyWorld::D3(w) => hash_and_totals(w),
    }
}

/// The events of the last step of any world.
pub fn any_events(
    world: &AnyWorld,
) -> (Option<CollisionsMsg>, Option<LifecycleMsg>, Option<LogMsg>) {
    match world {
        AnyWorld::D2(w) => events(w),
        AnyWorld::D3(w) => events(w),
    }
}
