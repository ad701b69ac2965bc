//! The channels of a recording, their messages and their JSON schemas.
//!
//! Every channel is JSON (`message_encoding = "json"`) with a JSON Schema (`encoding =
//! "jsonschema"`), so any MCAP tool decodes it without critterbox code. Floats are written in
//! their shortest round-trip form and read back bit for bit; the non-finite ones, which JSON
//! lacks, are the strings `"inf"`, `"-inf"` and `"nan"` (a mass of `"inf"` is a wall's).
//! Critter ids are one integer: `generation * 2^32 + slot index`, which is the slot index until
//! a slot is reused.

use crate::critter::{CritterId, Props};
use serde::de::{self, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::fmt;

/// Full critter states (every step for small scenes, keyframes otherwise).
pub const STATE: &str = "/critterbox/state";
/// The state hash after every step.
pub const HASH: &str = "/critterbox/hash";
/// Totals after every step: energy, momentum, counts.
pub const TOTALS: &str = "/critterbox/totals";
/// The collisions of a step (steps without any have no message).
pub const COLLISIONS: &str = "/critterbox/collisions";
/// Spawns, deaths and damage of a step (steps without any have no message).
pub const LIFECYCLE: &str = "/critterbox/lifecycle";
/// Lines that scripts logged in a step.
pub const LOG: &str = "/critterbox/log";
/// The error that ended a run.
pub const ERROR: &str = "/critterbox/error";
/// The critters as Foxglove spheres and walls as cubes, on the steps with a full state.
pub const SCENE: &str = "/foxglove/scene";
/// Topic: a kind replaced from its edited file between two steps (`run --watch`).
pub const RELOAD: &str = "/critterbox/reload";

/// Name of the metadata record written first: how the run was made.
pub const META: &str = "critterbox";
/// Name of the metadata record written last: how the run ended.
pub const END: &str = "critterbox.end";
/// Name of the metadata record `critterbox recover` adds.
pub const RECOVERED: &str = "critterbox.recovered";
/// Value of the `format` metadata key. Format 2 added the causes of spawns, deaths and damage
/// to the lifecycle channel (who, in which hook, and the kinds of the dead and the damaged).
pub const FORMAT: &str = "critterbox-recording/2";
/// The formats this critterbox reads: its own and format 1 (whose lifecycle messages name no
/// causes).
pub const FORMATS_READ: [&str; 2] = ["critterbox-recording/1", FORMAT];
/// Value of the `state_hash` metadata key: which state hash the file's hashes were computed
/// with. Files without the key used version 1; version 2 put each critter's sixteen words
/// through one set of sixteen lanes; version 3 puts the first eight words through four
/// interleaved sets, and sums the totals the same way.
pub const STATE_HASH: &str = "3";
/// Media type of the script attachments.
pub const SCRIPT_MEDIA_TYPE: &str = "text/x-rhai";
/// Media type of the new text of a reloaded kind file (named as its [`ReloadMsg`] says).
pub const RELOAD_MEDIA_TYPE: &str = "text/x-rhai-reload";

/// A critter id as recorded: `generation * 2^32 + index`.
pub fn id_key(id: CritterId) -> u64 {
    ((id.generation as u64) << 32) | id.index as u64
}

/// The critter id of a recorded id.
pub fn id_of(key: u64) -> CritterId {
    CritterId {
        index: key as u32,
        generation: (key >> 32) as u32,
    }
}

/// A column of floats, written bit-exact (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Floats(pub Vec<f64>);

/// Writes a float: a JSON number when finite, else `"inf"`, `"-inf"`, `"nan"` (or
/// `"nan:HEX"` for a NaN with another payload).
fn put_float<S: Serializer>(x: f64, s: S) -> Result<S::Ok, S::Error> {
    if x.is_finite() {
        s.serialize_f64(x)
    } else if x.is_nan() {
        if x.to_bits() == f64::NAN.to_bits() {
            s.serialize_str("nan")
        } else {
            s.serialize_str(&format!("nan:{:016x}", x.to_bits()))
        }
    } else if x > 0.0 {
        s.serialize_str("inf")
    } else {
        s.serialize_str("-inf")
    }
}

/// Reads a float written by [`put_float`] (or any JSON number).
fn float_from_str<E: de::Error>(v: &str) -> Result<f64, E> {
    match v {
        "inf" => Ok(f64::INFINITY),
        "-inf" => Ok(f64::NEG_INFINITY),
        "nan" => Ok(f64::NAN),
        _ => v
            .strip_prefix("nan:")
            .and_then(|h| u64::from_str_radix(h, 16).ok())
            .map(f64::from_bits)
            .ok_or_else(|| E::custom(format!("'{v}' is not a number"))),
    }
}

struct FloatVisitor;

impl Visitor<'_> for FloatVisitor {
    type Value = f64;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number or \"inf\", \"-inf\", \"nan\"")
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<f64, E> {
        Ok(v)
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<f64, E> {
        Ok(v as f64)
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<f64, E> {
        Ok(v as f64)
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<f64, E> {
        float_from_str(v)
    }
}

/// One float, written as [`Floats`] writes each of its values.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Float(pub f64);

impl Serialize for Float {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        put_float(self.0, s)
    }
}

impl<'de> Deserialize<'de> for Float {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(FloatVisitor).map(Float)
    }
}

impl Serialize for Floats {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        let mut seq = s.serialize_seq(Some(self.0.len()))?;
        for &x in &self.0 {
            seq.serialize_element(&Float(x))?;
        }
        seq.end()
    }
}

impl<'de> Deserialize<'de> for Floats {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct SeqVisitor;
        impl<'de> Visitor<'de> for SeqVisitor {
            type Value = Floats;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an array of numbers")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Floats, A::Error> {
                let mut v = Vec::with_capacity(seq.size_hint().unwrap_or(0));
                while let Some(Float(x)) = seq.next_element()? {
                    v.push(x);
                }
                Ok(Floats(v))
            }
        }
        d.deserialize_seq(SeqVisitor)
    }
}

impl Floats {
    /// True when both hold the same bits (NaN equal to NaN, 0.0 unequal to -0.0).
    pub fn same_bits(&self, other: &Floats) -> bool {
        self.0.len() == other.0.len()
            && self
                .0
                .iter()
                .zip(&other.0)
                .all(|(a, b)| a.to_bits() == b.to_bits())
    }
}

/// A wall's box, recorded with each full state (walls are few).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WallMsg {
    /// Its critter id.
    pub id: u64,
    /// Centre.
    pub center: Floats,
    /// Half extents along its own axes.
    pub half: Floats,
    /// Its axes in world coordinates, one unit vector per dimension.
    pub axes: Vec<Floats>,
}

/// `/critterbox/state`: every critter at the end of a step, one array per field.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StateMsg {
    /// Steps taken (0 is the scene as built).
    pub step: u64,
    /// Simulated time.
    pub time: Float,
    /// Kind names; `kind` holds indices into this list.
    pub kinds: Vec<String>,
    /// Critter ids, in slot order.
    pub id: Vec<u64>,
    /// Kind of each critter (index into `kinds`).
    pub kind: Vec<u32>,
    /// Position x.
    pub x: Floats,
    /// Position y.
    pub y: Floats,
    /// Position z (3D only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z: Option<Floats>,
    /// Velocity x.
    pub vx: Floats,
    /// Velocity y.
    pub vy: Floats,
    /// Velocity z (3D only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vz: Option<Floats>,
    /// Radius (a wall's bounding radius).
    pub radius: Floats,
    /// Mass (`"inf"` for walls).
    pub mass: Floats,
    /// Health.
    pub health: Floats,
    /// Coefficient of restitution.
    pub restitution: Floats,
    /// Collide priority.
    pub priority: Floats,
    /// Fixed (infinite mass).
    pub fixed: Vec<bool>,
    /// False for a critter killed since the last step's end.
    pub alive: Vec<bool>,
    /// User properties of the critters that have any, by id (as a decimal string).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub props: BTreeMap<String, Props>,
    /// Wall boxes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<WallMsg>,
    /// The world's random generator after the step (four 64-bit words), so a replay can start
    /// from this state instead of from step 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rng: Option<Vec<u64>>,
    /// The free slots, in the order the world keeps them (the last is reused first), as the ids
    /// the next critters in them will get.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub free: Option<Vec<u64>>,
    /// Under `solve:n`, the impulses of the step's contacts, which the next step starts from
    /// (its warm start), as (lower id, higher id, impulse), ascending: a replay from this state
    /// needs them to be exact. Empty under the other methods.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub contact_impulses: Vec<(u64, u64, Float)>,
    /// Under `solve:n` with gravity, the critters' counts of quiet steps towards sleep that are
    /// not 0, as (id, count, island) in ascending slots; a count of 30 means asleep, and then
    /// the island is the id of the sleeper that names it (null for the others). A replay from
    /// this state needs them to be exact. Empty under the other methods.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub quiet_steps: Vec<(u64, u16, Option<u64>)>,
    /// The world's shared script state (`world().vars`), when it has any; it is part of the
    /// state hash.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub vars: Props,
    /// The colours scripts gave critters (`me.color`), by id (as a decimal string), for the
    /// critters that have one; the others are drawn in their kind's colour.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub colors: BTreeMap<String, String>,
}

impl StateMsg {
    /// Number of critters.
    pub fn len(&self) -> usize {
        self.id.len()
    }
    /// True when there are no critters.
    pub fn is_empty(&self) -> bool {
        self.id.is_empty()
    }
    /// 2 or 3.
    pub fn dim(&self) -> usize {
        if self.z.is_some() {
            3
        } else {
            2
        }
    }
    /// Checks that every column has one value per critter (a decoded message may not).
    pub fn check(&self) -> Result<(), String> {
        let n = self.id.len();
        let mut lens = vec![
            ("kind", self.kind.len()),
            ("x", self.x.0.len()),
            ("y", self.y.0.len()),
            ("vx", self.vx.0.len()),
            ("vy", self.vy.0.len()),
            ("radius", self.radius.0.len()),
            ("mass", self.mass.0.len()),
            ("health", self.health.0.len()),
            ("restitution", self.restitution.0.len()),
            ("priority", self.priority.0.len()),
            ("fixed", self.fixed.len()),
            ("alive", self.alive.len()),
        ];
        if let (Some(z), Some(vz)) = (&self.z, &self.vz) {
            lens.push(("z", z.0.len()));
            lens.push(("vz", vz.0.len()));
        } else if self.z.is_some() != self.vz.is_some() {
            return Err("z and vz come together (3D) or not at all (2D)".into());
        }
        for (name, len) in lens {
            if len != n {
                return Err(format!("column {name} has {len} values for {n} critters"));
            }
        }
        if let Some(k) = self.kind.iter().find(|&&k| k as usize >= self.kinds.len()) {
            return Err(format!(
                "kind index {k} but only {} kinds",
                self.kinds.len()
            ));
        }
        Ok(())
    }
    /// Position of critter `i` as `[x, y, z]` (z = 0 in 2D).
    pub fn pos(&self, i: usize) -> [f64; 3] {
        [
            self.x.0[i],
            self.y.0[i],
            self.z.as_ref().map_or(0.0, |z| z.0[i]),
        ]
    }
    /// Velocity of critter `i` as `[x, y, z]` (z = 0 in 2D).
    pub fn vel(&self, i: usize) -> [f64; 3] {
        [
            self.vx.0[i],
            self.vy.0[i],
            self.vz.as_ref().map_or(0.0, |z| z.0[i]),
        ]
    }
    /// Kind name of critter `i`.
    pub fn kind_name(&self, i: usize) -> &str {
        self.kinds
            .get(self.kind[i] as usize)
            .map_or("?", String::as_str)
    }
    /// The float fields of critter `i` by name, in column order (for comparing and printing).
    pub fn fields(&self, i: usize) -> Vec<(&'static str, f64)> {
        let mut f = vec![("x", self.x.0[i]), ("y", self.y.0[i])];
        if let Some(z) = &self.z {
            f.push(("z", z.0[i]));
        }
        f.push(("vx", self.vx.0[i]));
        f.push(("vy", self.vy.0[i]));
        if let Some(vz) = &self.vz {
            f.push(("vz", vz.0[i]));
        }
        f.extend([
            ("radius", self.radius.0[i]),
            ("mass", self.mass.0[i]),
            ("health", self.health.0[i]),
            ("restitution", self.restitution.0[i]),
            ("priority", self.priority.0[i]),
        ]);
        f
    }
}

/// `/critterbox/hash`: the state hash after a step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HashMsg {
    /// Steps taken.
    pub step: u64,
    /// Simulated time.
    pub time: Float,
    /// `World::state_hash()` as 16 hex digits (a string: JSON readers in JavaScript would round
    /// a 64-bit number).
    pub hash: String,
}

/// `/critterbox/totals`: sums over the critters after a step, and the step's counts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TotalsMsg {
    /// Steps taken.
    pub step: u64,
    /// Simulated time.
    pub time: Float,
    /// Kinetic energy of the free critters.
    pub kinetic_energy: Float,
    /// Momentum of the free critters (2 or 3 components).
    pub momentum: Floats,
    /// Critters in the world (walls included; the dead are removed at the end of each step).
    pub critters: u64,
    /// `collide` calls that returned true in the step (resting contacts included).
    pub collisions: u64,
    /// Default collisions that exchanged an impulse.
    pub impacts: u64,
    /// Touching pairs found.
    pub contacts: u64,
}

/// `/critterbox/collisions`: the step's default collisions, one array per field.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CollisionsMsg {
    /// Steps taken at the end of the step they happened in.
    pub step: u64,
    /// Simulated time at the end of that step.
    pub time: Float,
    /// The critter whose `collide` ran.
    pub caller: Vec<u64>,
    /// The other one.
    pub arg: Vec<u64>,
    /// Contact point x.
    pub px: Floats,
    /// Contact point y.
    pub py: Floats,
    /// Contact point z (3D only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pz: Option<Floats>,
    /// Unit normal from caller to arg, x.
    pub nx: Floats,
    /// Normal y.
    pub ny: Floats,
    /// Normal z (3D only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nz: Option<Floats>,
    /// Impulse given to the arg along the normal (0 when they were already separating).
    pub impulse: Floats,
}

/// `/critterbox/lifecycle`: spawns, deaths and damage in a step, with who caused each.
///
/// The fields naming causes came with format 2; reading a format 1 file leaves them empty.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LifecycleMsg {
    /// Steps taken at the end of the step they happened in.
    pub step: u64,
    /// Simulated time at the end of that step.
    pub time: Float,
    /// Critters spawned.
    pub spawn: Vec<u64>,
    /// Their kinds.
    pub spawn_kind: Vec<String>,
    /// The critter whose hook spawned each (`None`: the scene).
    #[serde(default)]
    pub spawn_by: Vec<Option<u64>>,
    /// That hook (`None`: the scene).
    #[serde(default)]
    pub spawn_hook: Vec<Option<String>>,
    /// Critters that died (removed at the end of the step, or by the scene between steps).
    pub die: Vec<u64>,
    /// Their kinds.
    #[serde(default)]
    pub die_kind: Vec<String>,
    /// Why each died: [`CAUSE_DIE`], [`CAUSE_DAMAGE`] or [`CAUSE_REMOVED`].
    #[serde(default)]
    pub die_cause: Vec<String>,
    /// The critter whose hook called `die()` or did the last damage (`None`: none, the scene).
    #[serde(default)]
    pub die_by: Vec<Option<u64>>,
    /// That hook (`None`: no hook was running).
    #[serde(default)]
    pub die_hook: Vec<Option<String>>,
    /// Critters that took damage...
    pub damage_id: Vec<u64>,
    /// ...and how much.
    pub damage: Floats,
    /// Their kinds.
    #[serde(default)]
    pub damage_kind: Vec<String>,
    /// The critter whose hook did each damage (`None`: the scene or a test, between steps).
    #[serde(default)]
    pub damage_source: Vec<Option<u64>>,
    /// That hook (`None`: the scene).
    #[serde(default)]
    pub damage_hook: Vec<Option<String>>,
}

impl LifecycleMsg {
    /// What a format 1 file kept of these events: the spawns hooks made, the deaths at the end
    /// of the step, the damage hooks dealt, with no causes; `None` when that is nothing.
    pub fn format_1_view(&self) -> Option<LifecycleMsg> {
        let spawns: Vec<usize> = (0..self.spawn.len())
            .filter(|&i| self.spawn_by.get(i).is_none_or(Option::is_some))
            .collect();
        let deaths: Vec<usize> = (0..self.die.len())
            .filter(|&i| match self.die_cause.get(i).map(String::as_str) {
                Some(CAUSE_REMOVED) => false,
                Some(CAUSE_DAMAGE) => self.die_by.get(i).is_some_and(Option::is_some),
                _ => true,
            })
            .collect();
        let damages: Vec<usize> = (0..self.damage_id.len())
            .filter(|&i| self.damage_source.get(i).is_none_or(Option::is_some))
            .collect();
        if spawns.is_empty() && deaths.is_empty() && damages.is_empty() {
            return None;
        }
        let pick = |v: &[u64], at: &[usize]| -> Vec<u64> {
            at.iter().filter_map(|&i| v.get(i).copied()).collect()
        };
        Some(LifecycleMsg {
            step: self.step,
            time: self.time,
            spawn: pick(&self.spawn, &spawns),
            spawn_kind: spawns
                .iter()
                .filter_map(|&i| self.spawn_kind.get(i).cloned())
                .collect(),
            die: pick(&self.die, &deaths),
            damage_id: pick(&self.damage_id, &damages),
            damage: Floats(
                damages
                    .iter()
                    .filter_map(|&i| self.damage.0.get(i).copied())
                    .collect(),
            ),
            ..LifecycleMsg::default()
        })
    }
}

/// A `die_cause`: `die()` was called (in `die_hook` of `die_by`, or outside any hook).
pub const CAUSE_DIE: &str = "die";
/// A `die_cause`: health at or below 0 after damage (from `die_by`'s `die_hook`, or the scene).
pub const CAUSE_DAMAGE: &str = "damage";
/// A `die_cause`: removed by the scene or a test between steps.
pub const CAUSE_REMOVED: &str = "removed";

/// `/critterbox/log`: lines scripts logged in a step.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LogMsg {
    /// Steps taken at the end of the step they were logged in.
    pub step: u64,
    /// Simulated time at the end of that step.
    pub time: Float,
    /// The lines, in order.
    pub lines: Vec<String>,
}

/// `/critterbox/reload`: a kind file's new text replaced its kinds after step `step` (before
/// the next one).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReloadMsg {
    /// Steps taken when the kinds were replaced.
    pub step: u64,
    /// Simulated time then.
    pub time: Float,
    /// The kind file, as the run loaded it.
    pub file: String,
    /// The attachment holding the new text.
    pub attachment: String,
    /// The kinds replaced: the file's kind, then the kinds that extend it.
    pub kinds: Vec<String>,
}

/// `/critterbox/error`: the error that stopped the run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorMsg {
    /// The failing step (the steps before it completed and were recorded).
    pub step: u64,
    /// Simulated time then.
    pub time: Float,
    /// The error as critterbox reported it.
    pub message: String,
}

/// A channel's schema: its name and JSON Schema text.
pub struct ChannelSchema {
    /// Topic.
    pub topic: &'static str,
    /// Schema name.
    pub name: &'static str,
    /// JSON Schema (draft 2020-12).
    pub schema: Value,
}

fn float_schema() -> Value {
    json!({ "anyOf": [ { "type": "number" },
                       { "type": "string", "description": "inf, -inf, nan or nan:HEX" } ] })
}

fn floats_schema(description: &str) -> Value {
    json!({ "type": "array", "items": float_schema(), "description": description })
}

fn ids_schema(description: &str) -> Value {
    json!({ "type": "array", "items": { "type": "integer", "minimum": 0 },
            "description": format!("{description} (critter ids: generation * 2^32 + slot index)") })
}

fn step_props(extra: Value) -> Value {
    let mut props = json!({
        "step": { "type": "integer", "minimum": 0, "description": "steps taken" },
        "time": float_schema(),
    });
    if let (Some(p), Some(e)) = (props.as_object_mut(), extra.as_object()) {
        p.extend(e.clone());
    }
    props
}

fn object(title: &str, description: &str, properties: Value, required: &[&str]) -> Value {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": title,
        "description": description,
        "type": "object",
        "properties": properties,
        "required": required,
    })
}

/// The critterbox channels and their schemas (the Foxglove channel is in
/// [`super::foxglove`]).
pub fn channel_schemas() -> Vec<ChannelSchema> {
    let state = object(
        "critterbox.State",
        "Every critter after a step, one array per field, in slot order; z and vz only in 3D",
        step_props(json!({
            "kinds": { "type": "array", "items": { "type": "string" }, "description": "kind names" },
            "id": ids_schema("critter ids"),
            "kind": { "type": "array", "items": { "type": "integer", "minimum": 0 },
                      "description": "index into kinds" },
            "x": floats_schema("position x"), "y": floats_schema("position y"),
            "z": floats_schema("position z (3D only)"),
            "vx": floats_schema("velocity x"), "vy": floats_schema("velocity y"),
            "vz": floats_schema("velocity z (3D only)"),
            "radius": floats_schema("radius (a wall's bounding radius)"),
            "mass": floats_schema("mass (inf for walls)"),
            "health": floats_schema("health"),
            "restitution": floats_schema("coefficient of restitution"),
            "priority": floats_schema("collide priority"),
            "fixed": { "type": "array", "items": { "type": "boolean" } },
            "alive": { "type": "array", "items": { "type": "boolean" } },
            "props": { "type": "object", "description": "user properties by critter id (decimal string); each value is {\"Float\": 1.5}, {\"Int\": 2}, {\"Bool\": true}, {\"Text\": \"...\"}, {\"Critter\": {\"index\", \"generation\"}}, {\"Vector\": [x, y, z]}, {\"List\": [...]} or {\"Map\": {name: value}}" },
            "vars": { "type": "object", "description": "the world's shared script state (world().vars) by name, when it has any; values as in props; part of the state hash" },
            "colors": { "type": "object", "additionalProperties": { "type": "string" }, "description": "colours scripts gave critters (me.color) by critter id (decimal string): a colour name or #rrggbb; the others have their kind's colour" },
            "walls": { "type": "array", "items": {
                "type": "object",
                "properties": {
                    "id": { "type": "integer" },
                    "center": floats_schema("centre"),
                    "half": floats_schema("half extents along the wall's own axes"),
                    "axes": { "type": "array", "items": floats_schema("unit axis") },
                },
                "required": ["id", "center", "half", "axes"],
            } },
            "rng": { "type": "array", "items": { "type": "integer", "minimum": 0 },
                     "description": "the random generator's four 64-bit words after the step" },
            "free": ids_schema("free slots in the world's order (the last is reused first), as the ids their next critters get"),
            "contact_impulses": { "type": "array", "items": {
                "type": "array",
                "prefixItems": [ { "type": "integer", "minimum": 0 },
                                 { "type": "integer", "minimum": 0 }, float_schema() ],
                "minItems": 3, "maxItems": 3,
            }, "description": "solve:n only: the impulses the step's contacts ended with (and those of sleeping contacts, kept for when they wake), which the next step starts from, as [lower id, higher id, impulse] in ascending slots" },
            "quiet_steps": { "type": "array", "items": {
                "type": "array",
                "prefixItems": [ { "type": "integer", "minimum": 0 },
                                 { "type": "integer", "minimum": 1, "maximum": 30 },
                                 { "type": ["integer", "null"], "minimum": 0 } ],
                "minItems": 3, "maxItems": 3,
            }, "description": "solve:n with gravity only: the critters' counts of quiet steps towards sleep that are not 0, as [id, count, island] in ascending slots; 30 means asleep, and then island is the id of the sleeper that names its island (null for the others)" },
        })),
        &[
            "step",
            "time",
            "kinds",
            "id",
            "kind",
            "x",
            "y",
            "vx",
            "vy",
            "radius",
            "mass",
            "health",
            "restitution",
            "priority",
            "fixed",
            "alive",
        ],
    );
    let hash = object(
        "critterbox.Hash",
        "World::state_hash() after a step",
        step_props(json!({
            "hash": { "type": "string", "pattern": "^[0-9a-f]{16}$", "description": "64-bit hash as 16 hex digits" },
        })),
        &["step", "time", "hash"],
    );
    let totals = object(
        "critterbox.Totals",
        "Sums over the critters after a step, and the step's counts",
        step_props(json!({
            "kinetic_energy": float_schema(),
            "momentum": floats_schema("momentum of the free critters (2 or 3 components)"),
            "critters": { "type": "integer", "minimum": 0, "description": "critters in the world, walls included" },
            "collisions": { "type": "integer", "minimum": 0, "description": "collide calls that returned true" },
            "impacts": { "type": "integer", "minimum": 0, "description": "default collisions with an impulse" },
            "contacts": { "type": "integer", "minimum": 0, "description": "touching pairs" },
        })),
        &[
            "step",
            "time",
            "kinetic_energy",
            "momentum",
            "critters",
            "collisions",
            "impacts",
            "contacts",
        ],
    );
    let collisions = object(
        "critterbox.Collisions",
        "The default collisions of a step, in the order they were resolved; pz and nz only in 3D",
        step_props(json!({
            "caller": ids_schema("the critter whose collide ran"),
            "arg": ids_schema("the other critter"),
            "px": floats_schema("contact point x"), "py": floats_schema("contact point y"),
            "pz": floats_schema("contact point z (3D only)"),
            "nx": floats_schema("unit normal from caller to arg, x"),
            "ny": floats_schema("normal y"), "nz": floats_schema("normal z (3D only)"),
            "impulse": floats_schema("impulse given to the arg along the normal"),
        })),
        &[
            "step", "time", "caller", "arg", "px", "py", "nx", "ny", "impulse",
        ],
    );
    let maybe_ids = |description: &str| {
        json!({ "type": "array", "items": { "type": ["integer", "null"], "minimum": 0 },
                "description": format!("{description} (critter ids; null: the scene)") })
    };
    let maybe_hooks = |description: &str| {
        json!({ "type": "array", "items": { "type": ["string", "null"] },
                "description": format!("{description} (null: no hook, the scene)") })
    };
    let strings = |description: &str| json!({ "type": "array", "items": { "type": "string" }, "description": description });
    let lifecycle = object(
        "critterbox.Lifecycle",
        "Spawns, deaths and damage in a step, with who caused each; the arrays of a group (spawn, die, damage) have one item per event",
        step_props(json!({
            "spawn": ids_schema("critters spawned"),
            "spawn_kind": strings("their kinds"),
            "spawn_by": maybe_ids("the critter whose hook spawned each"),
            "spawn_hook": maybe_hooks("that hook"),
            "die": ids_schema("critters that died"),
            "die_kind": strings("their kinds"),
            "die_cause": { "type": "array", "items": { "enum": [CAUSE_DIE, CAUSE_DAMAGE, CAUSE_REMOVED] },
                           "description": "why: die() was called, health at or below 0 after damage, or removed by the scene between steps" },
            "die_by": maybe_ids("the critter whose hook called die() or did the damage"),
            "die_hook": maybe_hooks("that hook"),
            "damage_id": ids_schema("critters damaged"),
            "damage": floats_schema("damage taken, one per damage_id"),
            "damage_kind": strings("the kinds of the critters damaged"),
            "damage_source": maybe_ids("the critter whose hook did each damage"),
            "damage_hook": maybe_hooks("that hook"),
        })),
        &[
            "step",
            "time",
            "spawn",
            "spawn_kind",
            "spawn_by",
            "spawn_hook",
            "die",
            "die_kind",
            "die_cause",
            "die_by",
            "die_hook",
            "damage_id",
            "damage",
            "damage_kind",
            "damage_source",
            "damage_hook",
        ],
    );
    let log = object(
        "critterbox.Log",
        "Lines scripts logged in a step",
        step_props(json!({ "lines": { "type": "array", "items": { "type": "string" } } })),
        &["step", "time", "lines"],
    );
    let reload = object(
        "critterbox.Reload",
        "A kind file edited while the run went on: its new text replaced its kinds after step `step`",
        step_props(json!({
            "file": { "type": "string", "description": "the kind file, as the run loaded it" },
            "attachment": { "type": "string", "description": "the attachment (media type text/x-rhai-reload) holding the new text" },
            "kinds": { "type": "array", "items": { "type": "string" }, "description": "the kinds replaced: the file's kind, then those that extend it" },
        })),
        &["step", "time", "file", "attachment", "kinds"],
    );
    let error = object(
        "critterbox.Error",
        "The error that stopped the run in step `step` (the steps before it were recorded)",
        step_props(json!({ "message": { "type": "string" } })),
        &["step", "time", "message"],
    );
    vec![
        ChannelSchema {
            topic: STATE,
            name: "critterbox.State",
            schema: state,
        },
        ChannelSchema {
            topic: HASH,
            name: "critterbox.Hash",
            schema: hash,
        },
        ChannelSchema {
            topic: TOTALS,
            name: "critterbox.Totals",
            schema: totals,
        },
        ChannelSchema {
            topic: COLLISIONS,
            name: "critterbox.Collisions",
            schema: collisions,
        },
        ChannelSchema {
            topic: LIFECYCLE,
            name: "critterbox.Lifecycle",
            schema: lifecycle,
        },
        ChannelSchema {
            topic: LOG,
            name: "critterbox.Log",
            schema: log,
        },
        ChannelSchema {
            topic: ERROR,
            name: "critterbox.Error",
            schema: error,
        },
        ChannelSchema {
            topic: RELOAD,
            name: "critterbox.Reload",
            schema: reload,
        },
        ChannelSchema {
            topic: SCENE,
            name: "foxglove.SceneUpdate",
            schema: super::foxglove::scene_update_schema(),
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_round_trip_bit_exact_through_json() {
        let mut xs = vec![
            0.0,
            -0.0,
            1.0,
            0.1,
            1.0 / 3.0,
            f64::MIN_POSITIVE,
            f64::MIN_POSITIVE / 3.0, // subnormal
            f64::MAX,
            -f64::MAX,
            f64::EPSILON,
            5e-324,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::from_bits(0x7ff0_0000_0000_0001), // a signalling NaN payload
        ];
        let mut rng = crate::Rng::new(9);
        for _ in 0..20_000 {
            let bits = rng.next_u64();
            let x = f64::from_bits(bits);
            xs.push(x);
            xs.push(rng.uniform(-100.0, 100.0));
        }
        let text = serde_json::to_string(&Floats(xs.clone())).expect("encode");
        let back: Floats = serde_json::from_str(&text).expect("decode");
        assert!(Floats(xs).same_bits(&back));
    }

    #[test]
    fn ids_pack_index_and_generation() {
        let id = CritterId {
            index: 7,
            generation: 3,
        };
        assert_eq!(id_key(id), (3 << 32) + 7);
        assert_eq!(id_of(id_key(id)), id);
    }
}
