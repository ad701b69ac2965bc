//! `critterbox diff`: two recordings compared message by message, step by step: hashes, totals,
//! full states (where both have one: keyframe intervals may differ), collisions, lifecycle
//! events, log lines and the error, and the script attachments. Each file is read on its own
//! thread and handed over a step at a time, so neither is held in memory.
//!
//! A step one file lost to damage (or to being cut off) is not compared and not called a
//! difference; the steps next to a damaged stretch are compared on the messages both kept.

use super::compare::first_difference;
use super::error::RecordingError;
use super::reader::{decode, decode_state, read_items, Flow, Item, Recording};
use super::schema::{self, id_of, CollisionsMsg, LifecycleMsg};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::mpsc::{sync_channel, Receiver};

/// Topics in the order their differences are reported within a step.
const TOPICS: [&str; 7] = [
    schema::HASH,
    schema::TOTALS,
    schema::STATE,
    schema::COLLISIONS,
    schema::LIFECYCLE,
    schema::LOG,
    schema::ERROR,
];

/// What two recordings were found to be.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DiffReport {
    /// Script attachments that differ: one line each.
    pub scripts: Vec<String>,
    /// Steps compared (present in both).
    pub steps: u64,
    /// The first step where a message differs, and what differs there (first line first).
    pub first: Option<(u64, Vec<String>)>,
    /// True when that step's hashes differ (then a critter can be named by re-simulating).
    pub hash_differs: bool,
    /// True when the step's full states were both recorded and compared.
    pub states_compared: bool,
    /// Steps one of the files lost (damaged or cut off), so not compared.
    pub unchecked: u64,
}

impl DiffReport {
    /// True when nothing recorded differs.
    pub fn same(&self) -> bool {
        self.scripts.is_empty() && self.first.is_none()
    }
}

/// The messages of one step of one file.
struct StepGroup {
    step: u64,
    messages: Vec<(String, Vec<u8>)>,
    /// Damage just before or just after this step: some of its messages may be lost.
    near_damage: bool,
}

/// What a reading thread sends: a step, or the end (with whether the file was cut off).
enum Feed {
    Step(StepGroup),
    End { cut_off: bool },
    Failed(String),
}

fn feed(path: PathBuf) -> Receiver<Feed> {
    let (tx, rx) = sync_channel::<Feed>(8);
    std::thread::spawn(move || {
        #[derive(serde::Deserialize)]
        struct StepOnly {
            step: u64,
        }
        let mut group: Option<StepGroup> = None;
        let mut damaged = false;
        let read = read_items(&path, |item| {
            match item {
                Item::Damaged(_) => {
                    damaged = true;
                    if let Some(g) = &mut group {
                        g.near_damage = true;
                    }
                }
                Item::Message { topic, data, .. } if topic != schema::SCENE => {
                    let step = decode::<StepOnly>(topic, data)?.step;
                    if group.as_ref().is_some_and(|g| g.step != step) {
                        if let Some(g) = group.take() {
                            if tx.send(Feed::Step(g)).is_err() {
                                return Ok(Flow::Stop);
                            }
                        }
                    }
                    let g = group.get_or_insert_with(|| StepGroup {
                        step,
                        messages: Vec::new(),
                        near_damage: std::mem::take(&mut damaged),
                    });
                    g.messages.push((topic.to_string(), data.to_vec()));
                }
                _ => {}
            }
            Ok(Flow::Continue)
        });
        let end = match read {
            Ok(end) => {
                if let Some(mut g) = group.take() {
                    g.near_damage |= end.truncated.is_some();
                    let _ = tx.send(Feed::Step(g));
                }
                Feed::End {
                    cut_off: end.truncated.is_some() || damaged,
                }
            }
            Err(e) => Feed::Failed(super::error::with_causes(&e)),
        };
        let _ = tx.send(end);
    });
    rx
}

/// The next step of a feed: `Ok(None)` at its end (with whether it was cut off).
fn next(
    rx: &Receiver<Feed>,
    path: &std::path::Path,
    cut_off: &mut bool,
) -> Result<Option<StepGroup>, RecordingError> {
    match rx.recv() {
        Ok(Feed::Step(g)) => Ok(Some(g)),
        Ok(Feed::End { cut_off: c }) => {
            *cut_off = c;
            Ok(None)
        }
        Ok(Feed::Failed(message)) => Err(RecordingError::CannotRead {
            path: path.to_path_buf(),
            message,
        }),
        Err(_) => Ok(None),
    }
}

/// Compares two opened recordings (see the module doc).
pub fn diff(a: &Recording, b: &Recording) -> Result<DiffReport, RecordingError> {
    let mut report = DiffReport {
        scripts: script_differences(&a.scripts, &b.scripts),
        ..DiffReport::default()
    };
    let (ra, rb) = (feed(a.path.clone()), feed(b.path.clone()));
    let (mut cut_a, mut cut_b) = (false, false);
    let mut kinds: BTreeMap<u64, String> = BTreeMap::new();
    let (mut ga, mut gb) = (
        next(&ra, &a.path, &mut cut_a)?,
        next(&rb, &b.path, &mut cut_b)?,
    );
    loop {
        match (&ga, &gb) {
            (None, None) => break,
            (Some(x), Some(y)) if x.step == y.step => {
                report.steps += 1;
                let lenient = x.near_damage || y.near_damage;
                let found = compare_step(x, y, lenient, &mut kinds, &mut report);
                if found {
                    break;
                }
                ga = next(&ra, &a.path, &mut cut_a)?;
                gb = next(&rb, &b.path, &mut cut_b)?;
            }
            // A step only one file has: lost from the other (skipped), or a difference.
            (Some(x), other) if other.as_ref().is_none_or(|y| x.step < y.step) => {
                let lost = match other {
                    Some(y) => y.near_damage,
                    None => cut_b,
                } || lacks(b, x.step);
                if lost {
                    report.unchecked += 1;
                    ga = next(&ra, &a.path, &mut cut_a)?;
                } else {
                    report.first = Some((x.step, vec![only_in(x, "A", b, other.is_none())]));
                    break;
                }
            }
            (other, Some(y)) => {
                let lost = match other {
                    Some(x) => x.near_damage,
                    None => cut_a,
                } || lacks(a, y.step);
                if lost {
                    report.unchecked += 1;
                    gb = next(&rb, &b.path, &mut cut_b)?;
                } else {
                    report.first = Some((y.step, vec![only_in(y, "B", a, other.is_none())]));
                    break;
                }
            }
            // Taken by the arm before last; the compiler cannot see through its guard.
            (Some(_), None) => break,
        }
    }
    Ok(report)
}

/// True when `rec` has no hash for `step` but has later ones: a hole a damaged chunk left (in
/// a copy `recover` made).
fn lacks(rec: &Recording, step: u64) -> bool {
    rec.missing_ranges()
        .iter()
        .any(|&(a, b)| a <= step && step <= b)
}

fn only_in(g: &StepGroup, name: &str, other: &Recording, ended: bool) -> String {
    if ended {
        format!(
            "{name} goes on to step {}, the other recording ends at step {}",
            g.step,
            other.last_step()
        )
    } else {
        format!("step {} is in {name} only", g.step)
    }
}

/// Compares one step's messages; true (with `report.first` set) when they differ.
fn compare_step(
    x: &StepGroup,
    y: &StepGroup,
    lenient: bool,
    kinds: &mut BTreeMap<u64, String>,
    report: &mut DiffReport,
) -> bool {
    let mut found = Vec::new();
    for topic in TOPICS {
        let (ma, mb) = (pick(x, topic), pick(y, topic));
        if topic == schema::STATE {
            learn_kinds(kinds, &ma);
        }
        if topic == schema::LIFECYCLE {
            learn_spawns(kinds, &ma);
        }
        if ma == mb {
            continue;
        }
        // Keyframe intervals may differ; a step near damage may have lost some messages.
        let one_side = ma.is_empty() || mb.is_empty();
        if one_side && (topic == schema::STATE || lenient) {
            continue;
        }
        if ma.len() != mb.len() {
            found.push(format!(
                "{} {} message(s) in A, {} in B",
                ma.len(),
                short(topic),
                mb.len()
            ));
            continue;
        }
        for (da, db) in ma.iter().zip(&mb) {
            if da == db {
                continue;
            }
            if topic == schema::HASH {
                report.hash_differs = true;
            }
            if topic == schema::STATE {
                report.states_compared = true;
            }
            found.push(describe(topic, da, db, kinds));
            break;
        }
    }
    if found.is_empty() {
        return false;
    }
    report.first = Some((x.step, found));
    true
}

fn pick<'a>(g: &'a StepGroup, topic: &str) -> Vec<&'a [u8]> {
    g.messages
        .iter()
        .filter(|(t, _)| t == topic)
        .map(|(_, d)| d.as_slice())
        .collect()
}

fn short(topic: &str) -> &str {
    topic.rsplit('/').next().unwrap_or(topic)
}

fn learn_kinds(kinds: &mut BTreeMap<u64, String>, states: &[&[u8]]) {
    for data in states {
        if let Ok(s) = decode_state(data) {
            for i in 0..s.len() {
                kinds.insert(s.id[i], s.kind_name(i).to_string());
            }
        }
    }
}

fn learn_spawns(kinds: &mut BTreeMap<u64, String>, events: &[&[u8]]) {
    for data in events {
        if let Ok(l) = decode::<LifecycleMsg>(schema::LIFECYCLE, data) {
            for (id, kind) in l.spawn.iter().zip(&l.spawn_kind) {
                kinds.insert(*id, kind.clone());
            }
        }
    }
}

/// What differs between two messages of `topic`, with both values.
fn describe(topic: &str, da: &[u8], db: &[u8], kinds: &BTreeMap<u64, String>) -> String {
    let who = |key: u64| {
        format!(
            "critter {} ({})",
            id_of(key),
            kinds.get(&key).map_or("?", String::as_str)
        )
    };
    if topic == schema::STATE {
        if let (Ok(sa), Ok(sb)) = (decode_state(da), decode_state(db)) {
            if let Some(d) = first_difference(&sa, &sb, "A", "B") {
                return format!("full state: {d}");
            }
        }
    }
    let (Ok(va), Ok(vb)) = (
        serde_json::from_slice::<Value>(da),
        serde_json::from_slice::<Value>(db),
    ) else {
        return format!("the {} messages differ (one does not parse)", short(topic));
    };
    let Some((path, index, x, y)) = first_json_difference(&va, &vb) else {
        return format!(
            "the {} messages differ in their encoding only",
            short(topic)
        );
    };
    match topic {
        schema::HASH => format!(
            "state hash {} | {}",
            x.trim_matches('"'),
            y.trim_matches('"')
        ),
        schema::COLLISIONS => {
            let c: Option<CollisionsMsg> = serde_json::from_value(va).ok();
            let pair = index.zip(c).and_then(|(i, c)| {
                Some(format!(
                    " (collision {i}: {} with {})",
                    who(*c.caller.get(i)?),
                    who(*c.arg.get(i)?)
                ))
            });
            format!(
                "collisions {path}{}: A {x} | B {y}",
                pair.unwrap_or_default()
            )
        }
        _ => format!("{} {path}: A {x} | B {y}", short(topic)),
    }
}

/// The first place two JSON values differ: its path, the index of the first array element on
/// it, and both values as JSON text (equal text means equal bits for floats).
fn first_json_difference(a: &Value, b: &Value) -> Option<(String, Option<usize>, String, String)> {
    fn walk(
        a: &Value,
        b: &Value,
        path: &mut String,
        index: &mut Option<usize>,
    ) -> Option<(String, String)> {
        match (a, b) {
            (Value::Object(x), Value::Object(y)) => {
                let keys: std::collections::BTreeSet<&String> = x.keys().chain(y.keys()).collect();
                for k in keys {
                    let len = path.len();
                    if !path.is_empty() {
                        path.push('.');
                    }
                    path.push_str(k);
                    let null = Value::Null;
                    let (u, v) = (x.get(k).unwrap_or(&null), y.get(k).unwrap_or(&null));
                    if let Some(d) = walk(u, v, path, index) {
                        return Some(d);
                    }
                    path.truncate(len);
                }
                None
            }
            (Value::Array(x), Value::Array(y)) => {
                for i in 0..x.len().max(y.len()) {
                    let len = path.len();
                    path.push_str(&format!("[{i}]"));
                    let null = Value::Null;
                    let (u, v) = (x.get(i).unwrap_or(&null), y.get(i).unwrap_or(&null));
                    let before = *index;
                    index.get_or_insert(i);
                    if let Some(d) = walk(u, v, path, index) {
                        return Some(d);
                    }
                    *index = before;
                    path.truncate(len);
                }
                None
            }
            _ => {
                let (x, y) = (a.to_string(), b.to_string());
                (x != y).then_some((x, y))
            }
        }
    }
    let mut path = String::new();
    let mut index = None;
    let (x, y) = walk(a, b, &mut path, &mut index)?;
    Some((path, index, x, y))
}

/// One line per script attachment that differs: its name, and the first line that differs
/// with both texts.
pub fn script_differences(a: &[(String, String)], b: &[(String, String)]) -> Vec<String> {
    let mut out = Vec::new();
    for i in 0..a.len().max(b.len()) {
        match (a.get(i), b.get(i)) {
            (Some((na, ta)), Some((nb, tb))) => {
                if na != nb {
                    out.push(format!("script {}: named {na} in A, {nb} in B", i + 1));
                } else if ta != tb {
                    let (la, lb): (Vec<&str>, Vec<&str>) =
                        (ta.lines().collect(), tb.lines().collect());
                    let line = (0..la.len().max(lb.len()))
                        .find(|&l| la.get(l) != lb.get(l))
                        .unwrap_or(0);
                    let show =
                        |v: Option<&&str>| v.map_or("(no line)".to_string(), |s| format!("`{s}`"));
                    out.push(format!(
                        "script {na} line {}: A {} | B {}",
                        line + 1,
                        show(la.get(line)),
                        show(lb.get(line))
                    ));
                }
            }
            (Some((n, _)), None) => out.push(format!("script {n} is in A only")),
            (None, Some((n, _))) => out.push(format!("script {n} is in B only")),
            (None, None) => {}
        }
    }
    out
}
