//! A critter's story (`critterbox inspect FILE --critter ID`): one critter's timeline, told from
//! the recording alone. Its spawn (the step, and the critter and hook that made it, or the
//! scene), the reloads of its kind, its touching spells and impacts (partners and impulses),
//! each damage (amount and source), the changes of its properties and colour seen at the full
//! states, and its death with the cause.
//!
//! A *spell* here is what the collisions channel shows: a run of consecutive steps in which the
//! pair has collision events (the engine's own spells, `touch_begin` to `touch_end`, are the
//! same wherever the method reports every touching pair). Props and colours are only known at
//! full states, so a change is placed at the full state that first shows it, with the one
//! before it. Causes of spawns, deaths and damage came with recording format 2; a format 1 file
//! tells the events without them.

use super::error::RecordingError;
use super::reader::{decode, decode_state, read_items, Flow, Item, Recording};
use super::schema::{self, id_key, id_of, CollisionsMsg, CAUSE_DAMAGE, CAUSE_DIE, CAUSE_REMOVED};
use crate::critter::{CritterId, PropValue, Props};
use serde::Serialize;
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// One critter's story (see the module docs). Serialised as `inspect --critter ID --json`
/// prints it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Story {
    /// The critter, as critterbox prints ids (`#20v5`).
    pub critter: String,
    /// Its id as the recording writes it (`generation * 2^32 + index`).
    pub id: u64,
    /// Its kind.
    pub kind: Option<String>,
    /// The recording's format (causes are known from 2 on).
    pub format: u32,
    /// The last step in the file.
    pub last_step: u64,
    /// Its spawn, when the file shows it.
    pub spawn: Option<Entry>,
    /// Its death, when it died within the recording.
    pub death: Option<Entry>,
    /// Everything, spawn and death included, in step order.
    pub timeline: Vec<Entry>,
}

/// One event of a critter's timeline. Critters are named as critterbox prints ids; `None`
/// (JSON `null`) for a critter or hook is the scene.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum Entry {
    /// It was spawned in `step` (0: the scene as built), by `by`'s `hook`.
    Spawn {
        /// The step.
        step: u64,
        /// The critter whose hook spawned it (`None`: the scene).
        by: Option<String>,
        /// That critter's kind.
        by_kind: Option<String>,
        /// That hook.
        hook: Option<String>,
        /// False when the file names no cause (format 1, or a spawn it holds no event of).
        known: bool,
    },
    /// Its kind's file was reloaded after `step`.
    Reload {
        /// The step after which the new text ran.
        step: u64,
        /// The kind file.
        file: String,
        /// The kinds it replaced.
        kinds: Vec<String>,
    },
    /// A touching spell with `partner`: collision events in every step from `step` to `last`.
    Spell {
        /// The first step of the spell.
        step: u64,
        /// Its last step (the touch ends after it).
        last: u64,
        /// The other critter.
        partner: String,
        /// Its kind.
        partner_kind: Option<String>,
        /// The collision events of the spell (more than one a step under sub-steps).
        collisions: u64,
        /// Those that exchanged an impulse, in order.
        impacts: Vec<Impact>,
        /// The sum of their impulses.
        impulse_total: f64,
    },
    /// It took `amount` of damage from `source`'s `hook`.
    Damage {
        /// The step.
        step: u64,
        /// How much.
        amount: f64,
        /// The critter whose hook did it (`None`: the scene or a test).
        source: Option<String>,
        /// That critter's kind.
        source_kind: Option<String>,
        /// That hook.
        hook: Option<String>,
        /// False when the file names no source (format 1).
        known: bool,
    },
    /// Properties seen changed at the full state of `step`.
    Props {
        /// The step of the full state.
        step: u64,
        /// The full state before it that held the critter.
        since: Option<u64>,
        /// What changed.
        changes: Vec<Change>,
    },
    /// Its own colour seen changed at the full state of `step` (`None`: its kind's).
    Color {
        /// The step of the full state.
        step: u64,
        /// The full state before it that held the critter.
        since: Option<u64>,
        /// The colour before.
        before: Option<String>,
        /// The colour after.
        after: Option<String>,
    },
    /// It died in `step`.
    Death {
        /// The step.
        step: u64,
        /// `die` (its `die()` was called in `by`'s `hook`), `damage` (health at or below 0
        /// after damage from `by`'s `hook`), `removed` (by the scene), or `None` when the file
        /// does not say (format 1).
        cause: Option<String>,
        /// The critter whose hook killed it (`None`: no hook, the scene).
        by: Option<String>,
        /// That critter's kind.
        by_kind: Option<String>,
        /// That hook.
        hook: Option<String>,
    },
}

/// An impact within a spell.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Impact {
    /// The step.
    pub step: u64,
    /// The impulse exchanged.
    pub impulse: f64,
    /// `caller` when this critter's `collide` ran, `arg` when the partner's did.
    pub role: &'static str,
}

/// A property that changed: its value before and after (`null`: it had none).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Change {
    /// The property.
    pub name: String,
    /// Its value before.
    pub before: Option<Value>,
    /// Its value after.
    pub after: Option<Value>,
}

impl Entry {
    /// The step it happened in.
    pub fn step(&self) -> u64 {
        match self {
            Entry::Spawn { step, .. }
            | Entry::Reload { step, .. }
            | Entry::Spell { step, .. }
            | Entry::Damage { step, .. }
            | Entry::Props { step, .. }
            | Entry::Color { step, .. }
            | Entry::Death { step, .. } => *step,
        }
    }

    /// Order within a step: the spawn first, the death last.
    fn rank(&self) -> u8 {
        match self {
            Entry::Spawn { .. } => 0,
            Entry::Reload { .. } => 1,
            Entry::Spell { .. } => 2,
            Entry::Damage { .. } => 3,
            Entry::Props { .. } => 4,
            Entry::Color { .. } => 5,
            Entry::Death { .. } => 6,
        }
    }
}

/// A property value as JSON a reader takes at a glance: numbers, strings, a critter as
/// `#20v5`, a vector as its components.
pub fn prop_json(v: &PropValue) -> Value {
    match v {
        PropValue::Bool(b) => json!(b),
        PropValue::Int(i) => json!(i),
        PropValue::Float(x) => json!(x),
        PropValue::Text(s) => json!(s),
        PropValue::Critter(id) => json!(id.to_string()),
        PropValue::List(items) => Value::Array(items.iter().map(prop_json).collect()),
        PropValue::Vector(v) => json!(v),
        PropValue::Map(m) => {
            Value::Object(m.iter().map(|(k, v)| (k.clone(), prop_json(v))).collect())
        }
    }
}

/// A property value as scripts write it: `2`, `1.5`, `true`, `"a"`, `#20v5`, `(1, 2, 0)`,
/// `[..]`, `#{..}`.
pub fn prop_text(v: &PropValue) -> String {
    let num = |x: f64| ryu::Buffer::new().format(x).to_string();
    match v {
        PropValue::Bool(b) => b.to_string(),
        PropValue::Int(i) => i.to_string(),
        PropValue::Float(x) => num(*x),
        PropValue::Text(s) => format!("{s:?}"),
        PropValue::Critter(id) => id.to_string(),
        PropValue::List(items) => {
            let items: Vec<String> = items.iter().map(prop_text).collect();
            format!("[{}]", items.join(", "))
        }
        PropValue::Vector(v) => format!("({}, {}, {})", num(v[0]), num(v[1]), num(v[2])),
        PropValue::Map(m) => {
            let items: Vec<String> = m
                .iter()
                .map(|(k, v)| format!("{k}: {}", prop_text(v)))
                .collect();
            format!("#{{{}}}", items.join(", "))
        }
    }
}

/// A JSON value as [`prop_text`] writes the property it came from.
pub fn json_text(v: &Value) -> String {
    match v {
        Value::String(s) if s.starts_with('#') && s.parse::<CritterId>().is_ok() => s.clone(),
        other => other.to_string(),
    }
}

/// What a pass over the file gathers about the critter.
#[derive(Default)]
struct Seen {
    /// Kinds of every critter seen (to name partners and sources).
    kinds: BTreeMap<u64, String>,
    /// The first full state holding the critter.
    first_state: Option<u64>,
    /// The last full state holding it, with its props and colour there.
    last_state: Option<(u64, Props, Option<String>)>,
    /// Its collision events: step, partner, impulse, caller or arg.
    collisions: Vec<(u64, u64, f64, &'static str)>,
    entries: Vec<Entry>,
}

impl Seen {
    fn state(&mut self, s: &schema::StateMsg, me: u64) {
        for (i, &id) in s.id.iter().enumerate() {
            self.kinds
                .entry(id)
                .or_insert_with(|| s.kind_name(i).to_string());
        }
        if !s.id.contains(&me) {
            return;
        }
        let key = me.to_string();
        let props = s.props.get(&key).cloned().unwrap_or_default();
        let color = s.colors.get(&key).cloned();
        self.first_state.get_or_insert(s.step);
        let (since, before, before_color) = match self.last_state.take() {
            Some((k, p, c)) => (Some(k), p, c),
            None => (None, Props::new(), None),
        };
        let mut changes = Vec::new();
        let names: std::collections::BTreeSet<&String> =
            before.keys().chain(props.keys()).collect();
        for name in names {
            let (a, b) = (before.get(name), props.get(name));
            if a != b {
                changes.push(Change {
                    name: name.clone(),
                    before: a.map(prop_json),
                    after: b.map(prop_json),
                });
            }
        }
        if !changes.is_empty() {
            self.entries.push(Entry::Props {
                step: s.step,
                since,
                changes,
            });
        }
        if color != before_color {
            self.entries.push(Entry::Color {
                step: s.step,
                since,
                before: before_color,
                after: color.clone(),
            });
        }
        self.last_state = Some((s.step, props, color));
    }

    fn collisions(&mut self, c: &CollisionsMsg, me: u64) {
        for (i, (&caller, &arg)) in c.caller.iter().zip(&c.arg).enumerate() {
            let impulse = c.impulse.0.get(i).copied().unwrap_or(0.0);
            if caller == me {
                self.collisions.push((c.step, arg, impulse, "caller"));
            } else if arg == me {
                self.collisions.push((c.step, caller, impulse, "arg"));
            }
        }
    }

    /// The spells, from the collision events: per partner, runs of consecutive steps.
    fn spells(&mut self) {
        let mut by_partner: BTreeMap<u64, Vec<(u64, f64, &'static str)>> = BTreeMap::new();
        for &(step, partner, impulse, role) in &self.collisions {
            by_partner
                .entry(partner)
                .or_default()
                .push((step, impulse, role));
        }
        for (partner, events) in by_partner {
            let mut spell: Option<Entry> = None;
            for (step, impulse, role) in events {
                let goes_on = matches!(&spell, Some(Entry::Spell { last, .. }) if step <= last + 1);
                if !goes_on {
                    self.entries.extend(spell.take());
                    spell = Some(Entry::Spell {
                        step,
                        last: step,
                        partner: id_of(partner).to_string(),
                        partner_kind: self.kinds.get(&partner).cloned(),
                        collisions: 0,
                        impacts: Vec::new(),
                        impulse_total: 0.0,
                    });
                }
                if let Some(Entry::Spell {
                    last,
                    collisions,
                    impacts,
                    impulse_total,
                    ..
                }) = &mut spell
                {
                    *last = step;
                    *collisions += 1;
                    if impulse > 0.0 {
                        impacts.push(Impact {
                            step,
                            impulse,
                            role,
                        });
                        *impulse_total += impulse;
                    }
                }
            }
            self.entries.extend(spell);
        }
    }
}

/// The story of critter `who` in `rec`; an error, saying which ids the file has, when the
/// critter is not in it.
pub fn story(rec: &Recording, who: CritterId) -> Result<Story, RecordingError> {
    let me = id_key(who);
    let mut seen = Seen::default();
    for l in &rec.lifecycle {
        for (&id, kind) in l.spawn.iter().zip(&l.spawn_kind) {
            seen.kinds.insert(id, kind.clone());
        }
        for (&id, kind) in l.die.iter().zip(&l.die_kind) {
            seen.kinds.entry(id).or_insert_with(|| kind.clone());
        }
        for (&id, kind) in l.damage_id.iter().zip(&l.damage_kind) {
            seen.kinds.entry(id).or_insert_with(|| kind.clone());
        }
    }
    read_items(&rec.path, |item| {
        if let Item::Message { topic, data, .. } = item {
            match topic {
                schema::STATE => seen.state(&decode_state(data)?, me),
                schema::COLLISIONS => seen.collisions(&decode(topic, data)?, me),
                _ => {}
            }
        }
        Ok(Flow::Continue)
    })?;
    let in_events = rec
        .lifecycle
        .iter()
        .any(|l| l.spawn.contains(&me) || l.die.contains(&me) || l.damage_id.contains(&me));
    if seen.first_state.is_none() && seen.collisions.is_empty() && !in_events {
        return Err(not_in(rec, who, &seen.kinds));
    }
    let name = |id: Option<u64>| id.map(|id| id_of(id).to_string());
    let kind_of =
        |id: Option<u64>, kinds: &BTreeMap<u64, String>| id.and_then(|id| kinds.get(&id).cloned());
    let mut spawn = None;
    let mut death = None;
    for l in &rec.lifecycle {
        for (i, _) in l.spawn.iter().enumerate().filter(|(_, id)| **id == me) {
            let by = l.spawn_by.get(i).copied().flatten();
            spawn = Some(Entry::Spawn {
                step: l.step,
                by: name(by),
                by_kind: kind_of(by, &seen.kinds),
                hook: l.spawn_hook.get(i).cloned().flatten(),
                known: i < l.spawn_by.len(),
            });
        }
        for (i, _) in l.damage_id.iter().enumerate().filter(|(_, id)| **id == me) {
            let source = l.damage_source.get(i).copied().flatten();
            seen.entries.push(Entry::Damage {
                step: l.step,
                amount: l.damage.0.get(i).copied().unwrap_or(f64::NAN),
                source: name(source),
                source_kind: kind_of(source, &seen.kinds),
                hook: l.damage_hook.get(i).cloned().flatten(),
                known: i < l.damage_source.len(),
            });
        }
        for (i, _) in l.die.iter().enumerate().filter(|(_, id)| **id == me) {
            let by = l.die_by.get(i).copied().flatten();
            death = Some(Entry::Death {
                step: l.step,
                cause: l.die_cause.get(i).cloned(),
                by: name(by),
                by_kind: kind_of(by, &seen.kinds),
                hook: l.die_hook.get(i).cloned().flatten(),
            });
        }
    }
    // No spawn event: in the scene as built (step 0), or spawned by the scene between steps in
    // a format 1 file, which recorded no such spawns.
    let spawn = spawn.or_else(|| {
        seen.first_state.map(|step| Entry::Spawn {
            step,
            by: None,
            by_kind: None,
            hook: None,
            known: step == 0,
        })
    });
    let kind = seen.kinds.get(&me).cloned();
    let born = spawn.as_ref().map_or(0, Entry::step);
    let died = death.as_ref().map_or(u64::MAX, Entry::step);
    if let Some(kind) = &kind {
        for r in rec
            .reloads
            .iter()
            .filter(|r| r.kinds.contains(kind) && r.step >= born && r.step < died)
        {
            seen.entries.push(Entry::Reload {
                step: r.step,
                file: r.file.clone(),
                kinds: r.kinds.clone(),
            });
        }
    }
    seen.spells();
    let mut timeline = std::mem::take(&mut seen.entries);
    timeline.extend(spawn.clone());
    timeline.extend(death.clone());
    timeline.sort_by_key(|e| (e.step(), e.rank()));
    Ok(Story {
        critter: who.to_string(),
        id: me,
        kind,
        format: rec.format_version(),
        last_step: rec.last_step(),
        spawn,
        death,
        timeline,
    })
}

/// The error of a critter the file does not hold, naming the ids it has in that slot.
fn not_in(rec: &Recording, who: CritterId, kinds: &BTreeMap<u64, String>) -> RecordingError {
    let same_slot: Vec<String> = kinds
        .keys()
        .map(|&k| id_of(k))
        .filter(|id| id.index == who.index)
        .map(|id| id.to_string())
        .collect();
    let highest = kinds.keys().map(|&k| id_of(k).index).max();
    let hint = match (same_slot.is_empty(), highest) {
        (false, _) => format!("slot {} held {}", who.index, same_slot.join(", ")),
        (true, Some(h)) => format!("its slots run from #0 to #{h}"),
        (true, None) => "it holds no critter".to_string(),
    };
    RecordingError::NoSuchCritter {
        path: rec.path.clone(),
        critter: who.to_string(),
        hint,
    }
}

/// The cause of a death, in words.
fn death_words(
    cause: Option<&str>,
    by: Option<&str>,
    kind: Option<&str>,
    hook: Option<&str>,
) -> String {
    let who = match (by, kind) {
        (Some(b), Some(k)) => format!("{b} ({k})"),
        (Some(b), None) => b.to_string(),
        _ => "the scene".to_string(),
    };
    let hook = hook.map_or(String::new(), |h| format!("'s {h}"));
    match cause {
        Some(CAUSE_DIE) if by.is_some() => format!("die() in {who}{hook}"),
        Some(CAUSE_DIE) => "die() outside any hook".to_string(),
        Some(CAUSE_DAMAGE) => format!("health at or below 0 after damage from {who}{hook}"),
        Some(CAUSE_REMOVED) => "removed by the scene".to_string(),
        Some(other) => other.to_string(),
        None => "the cause is not recorded (a format 1 recording)".to_string(),
    }
}

/// A critter and its kind, or the scene.
fn who(by: &Option<String>, kind: &Option<String>, hook: &Option<String>) -> String {
    match by {
        Some(b) => {
            let kind = kind.as_ref().map_or(String::new(), |k| format!(" ({k})"));
            let hook = hook.as_ref().map_or(String::new(), |h| format!(" in {h}"));
            format!("{b}{kind}{hook}")
        }
        None => "the scene".to_string(),
    }
}

fn num(x: f64) -> String {
    ryu::Buffer::new().format(x).to_string()
}

impl Entry {
    /// The entry as one line of text (after its step).
    pub fn text(&self) -> String {
        match self {
            Entry::Spawn {
                step,
                by,
                by_kind,
                hook,
                known,
            } => match (known, step) {
                (true, 0) if by.is_none() => "spawned by the scene (as built)".to_string(),
                (true, _) => format!("spawned by {}", who(by, by_kind, hook)),
                (false, _) => "spawned; the file does not say by whom".to_string(),
            },
            Entry::Reload { file, kinds, .. } => {
                format!("kind reloaded from {file} ({})", kinds.join(", "))
            }
            Entry::Spell {
                step,
                last,
                partner,
                partner_kind,
                collisions,
                impacts,
                impulse_total,
            } => {
                let kind = partner_kind
                    .as_ref()
                    .map_or(String::new(), |k| format!(" ({k})"));
                let steps = if last == step {
                    format!("step {step}")
                } else {
                    format!("steps {step}..{last}")
                };
                let mut line = format!(
                    "touching {partner}{kind}, {steps}: {collisions} collision{}, {} impact{}",
                    if *collisions == 1 { "" } else { "s" },
                    impacts.len(),
                    if impacts.len() == 1 { "" } else { "s" },
                );
                if !impacts.is_empty() {
                    let shown: Vec<String> = impacts
                        .iter()
                        .take(5)
                        .map(|i| format!("{} at step {} as {}", num(i.impulse), i.step, i.role))
                        .collect();
                    let more = impacts.len().saturating_sub(5);
                    line.push_str(&format!(
                        ", impulse {} in all ({}{})",
                        num(*impulse_total),
                        shown.join("; "),
                        if more > 0 {
                            format!("; {more} more")
                        } else {
                            String::new()
                        }
                    ));
                }
                line
            }
            Entry::Damage {
                amount,
                source,
                source_kind,
                hook,
                known,
                ..
            } => {
                if *known {
                    format!(
                        "damage {} from {}",
                        num(*amount),
                        who(source, source_kind, hook)
                    )
                } else {
                    format!("damage {} (the source is not recorded)", num(*amount))
                }
            }
            Entry::Props { since, changes, .. } => {
                let list: Vec<String> = changes
                    .iter()
                    .map(|c| match (&c.before, &c.after) {
                        (None, Some(a)) => format!("{} = {}", c.name, json_text(a)),
                        (Some(b), None) => format!("{} gone (was {})", c.name, json_text(b)),
                        (Some(b), Some(a)) => {
                            format!("{} {} -> {}", c.name, json_text(b), json_text(a))
                        }
                        (None, None) => c.name.clone(),
                    })
                    .collect();
                format!("props {}{}", list.join(", "), since_note(*since))
            }
            Entry::Color {
                since,
                before,
                after,
                ..
            } => {
                let c = |c: &Option<String>| c.clone().unwrap_or_else(|| "its kind's".into());
                format!("colour {} -> {}{}", c(before), c(after), since_note(*since))
            }
            Entry::Death {
                cause,
                by,
                by_kind,
                hook,
                ..
            } => format!(
                "died: {}",
                death_words(
                    cause.as_deref(),
                    by.as_deref(),
                    by_kind.as_deref(),
                    hook.as_deref()
                )
            ),
        }
    }
}

/// Where a change seen at a full state may have happened.
fn since_note(since: Option<u64>) -> String {
    since.map_or(String::new(), |k| {
        format!(" (seen at this full state; the one before is step {k})")
    })
}
