//! `critterbox export --csv DIR`: a recording as CSV files, one row per critter per recorded
//! state and one per event, with floats in shortest round-trip form (they read back exactly).

use super::capture;
use super::error::RecordingError;
use super::reader::{decode, decode_state, read_items, Flow, Item, Recording};
use super::replay::Replay;
use super::schema::{
    self, id_of, CollisionsMsg, HashMsg, LifecycleMsg, LogMsg, StateMsg, TotalsMsg,
};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// What an export wrote.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Exported {
    /// Files written, with their data rows.
    pub files: Vec<(PathBuf, u64)>,
    /// Steps whose full state was written.
    pub states: u64,
    /// Why the recording's readable part ends early, for a cut-off file.
    pub truncated: Option<String>,
}

/// A CSV file written row by row into a reused buffer.
struct Csv {
    path: PathBuf,
    out: BufWriter<File>,
    line: Vec<u8>,
    rows: u64,
}

impl Csv {
    fn create(dir: &Path, name: &str, header: &[&str]) -> Result<Csv, RecordingError> {
        let path = dir.join(name);
        let file = File::create(&path).map_err(|error| RecordingError::CannotCreate {
            path: path.clone(),
            error,
        })?;
        let mut out = BufWriter::with_capacity(1 << 20, file);
        writeln!(out, "{}", header.join(","))?;
        Ok(Csv {
            path,
            out,
            line: Vec::with_capacity(256),
            rows: 0,
        })
    }
    fn f(&mut self, x: f64) -> &mut Self {
        let mut b = ryu::Buffer::new();
        self.line.extend_from_slice(b.format(x).as_bytes());
        self.line.push(b',');
        self
    }
    fn u(&mut self, x: u64) -> &mut Self {
        let mut b = itoa::Buffer::new();
        self.line.extend_from_slice(b.format(x).as_bytes());
        self.line.push(b',');
        self
    }
    fn s(&mut self, x: &str) -> &mut Self {
        if x.contains([',', '"', '\n', '\r']) {
            self.line.push(b'"');
            self.line
                .extend_from_slice(x.replace('"', "\"\"").as_bytes());
            self.line.push(b'"');
        } else {
            self.line.extend_from_slice(x.as_bytes());
        }
        self.line.push(b',');
        self
    }
    fn id(&mut self, key: u64) -> &mut Self {
        self.s(&id_of(key).to_string())
    }
    fn end(&mut self) -> std::io::Result<()> {
        if let Some(last) = self.line.last_mut() {
            *last = b'\n';
        }
        self.out.write_all(&self.line)?;
        self.line.clear();
        self.rows += 1;
        Ok(())
    }
    fn finish(mut self) -> std::io::Result<(PathBuf, u64)> {
        self.out.flush()?;
        Ok((self.path, self.rows))
    }
}

fn state_header(dim: usize) -> Vec<&'static str> {
    let mut h = vec!["step", "time", "id", "kind", "x", "y"];
    if dim == 3 {
        h.push("z");
    }
    h.extend(["vx", "vy"]);
    if dim == 3 {
        h.push("vz");
    }
    h.extend([
        "radius",
        "mass",
        "health",
        "restitution",
        "priority",
        "fixed",
        "alive",
    ]);
    h
}

fn state_rows(csv: &mut Csv, s: &StateMsg) -> std::io::Result<()> {
    for i in 0..s.len() {
        csv.u(s.step).f(s.time.0).id(s.id[i]).s(s.kind_name(i));
        csv.f(s.x.0[i]).f(s.y.0[i]);
        if let Some(z) = &s.z {
            csv.f(z.0[i]);
        }
        csv.f(s.vx.0[i]).f(s.vy.0[i]);
        if let Some(vz) = &s.vz {
            csv.f(vz.0[i]);
        }
        csv.f(s.radius.0[i])
            .f(s.mass.0[i])
            .f(s.health.0[i])
            .f(s.restitution.0[i])
            .f(s.priority.0[i])
            .u(s.fixed[i] as u64)
            .u(s.alive[i] as u64);
        csv.end()?;
    }
    Ok(())
}

/// The kinds of the critters a reader has seen (in spawns and full states), by id.
#[derive(Default)]
struct KindsSeen(std::collections::BTreeMap<u64, String>);

impl KindsSeen {
    fn saw(&mut self, ids: &[u64], kind: &[u32], names: &[String]) {
        for (&id, &k) in ids.iter().zip(kind) {
            if let Some(name) = names.get(k as usize) {
                self.0.entry(id).or_insert_with(|| name.clone());
            }
        }
    }
    fn spawned(&mut self, l: &LifecycleMsg) {
        for (&id, kind) in l.spawn.iter().zip(&l.spawn_kind) {
            self.0.insert(id, kind.clone());
        }
    }
    /// The kind of `id`: as the event names it, else as seen before.
    fn of<'a>(&'a self, named: Option<&'a String>, id: u64) -> &'a str {
        named.or_else(|| self.0.get(&id)).map_or("", String::as_str)
    }
}

/// The ids and kinds of a full state, all a reader needs of it to know the kinds.
#[derive(serde::Deserialize)]
struct KindColumns {
    id: Vec<u64>,
    kind: Vec<u32>,
    kinds: Vec<String>,
}

/// Writes the `by` cell: the critter, or nothing for the scene.
fn by_cell(csv: &mut Csv, by: Option<&Option<u64>>) {
    match by.copied().flatten() {
        Some(id) => csv.id(id),
        None => csv.s(""),
    };
}

/// A hook's name, or nothing for the scene.
fn hook_cell(v: Option<&Option<String>>) -> &str {
    v.and_then(Option::as_deref).unwrap_or("")
}

/// The rows of a lifecycle message: spawns, deaths, damage, each with its kind and cause.
fn lifecycle_rows(csv: &mut Csv, l: &LifecycleMsg, kinds: &KindsSeen) -> std::io::Result<()> {
    for (i, &id) in l.spawn.iter().enumerate() {
        let kind = kinds.of(l.spawn_kind.get(i), id);
        csv.u(l.step).f(l.time.0).s("spawn").id(id).s(kind).s("");
        by_cell(csv, l.spawn_by.get(i));
        csv.s(hook_cell(l.spawn_hook.get(i))).s("").end()?;
    }
    for (i, &id) in l.die.iter().enumerate() {
        let kind = kinds.of(l.die_kind.get(i), id);
        csv.u(l.step).f(l.time.0).s("die").id(id).s(kind).s("");
        by_cell(csv, l.die_by.get(i));
        let cause = l.die_cause.get(i).map_or("", String::as_str);
        csv.s(hook_cell(l.die_hook.get(i))).s(cause).end()?;
    }
    for (i, &id) in l.damage_id.iter().enumerate() {
        let amount = l.damage.0.get(i).copied().unwrap_or(f64::NAN);
        let kind = kinds.of(l.damage_kind.get(i), id);
        csv.u(l.step)
            .f(l.time.0)
            .s("damage")
            .id(id)
            .s(kind)
            .f(amount);
        by_cell(csv, l.damage_source.get(i));
        csv.s(hook_cell(l.damage_hook.get(i))).s("").end()?;
    }
    Ok(())
}

/// Writes `states.csv`, `steps.csv`, `collisions.csv`, `lifecycle.csv` and `log.csv` into `dir`.
/// With `every_step`, states.csv has every step, re-simulated between the keyframes (and
/// checked against every recorded hash); otherwise the recorded full states.
pub fn export_csv(
    rec: &Recording,
    dir: &Path,
    every_step: bool,
) -> Result<Exported, RecordingError> {
    std::fs::create_dir_all(dir).map_err(|error| RecordingError::CannotCreate {
        path: dir.to_path_buf(),
        error,
    })?;
    let dim = rec.meta().dim;
    let z = |h: &mut Vec<&'static str>, at: usize, name: &'static str| {
        if dim == 3 {
            h.insert(at, name);
        }
    };
    let mut states = Csv::create(dir, "states.csv", &state_header(dim))?;
    let mut h = vec!["step", "time", "hash", "kinetic_energy", "px", "py"];
    z(&mut h, 6, "pz");
    h.extend(["critters", "collisions", "impacts", "contacts"]);
    let mut steps = Csv::create(dir, "steps.csv", &h)?;
    let mut h = vec!["step", "time", "caller", "arg", "px", "py"];
    z(&mut h, 6, "pz");
    h.extend(["nx", "ny"]);
    let at = h.len();
    z(&mut h, at, "nz");
    h.push("impulse");
    let mut collisions = Csv::create(dir, "collisions.csv", &h)?;
    let mut lifecycle = Csv::create(
        dir,
        "lifecycle.csv",
        &[
            "step", "time", "event", "id", "kind", "amount", "by", "hook", "cause",
        ],
    )?;
    // A format 1 file names no kinds in its die and damage events: they are taken from the
    // spawns and full states read before them.
    let mut kinds = KindsSeen::default();
    let mut log = Csv::create(dir, "log.csv", &["step", "time", "line"])?;
    let mut out = Exported::default();
    let mut hash: Option<HashMsg> = None;
    let end = read_items(&rec.path, |item| {
        let Item::Message { topic, data, .. } = item else {
            return Ok(Flow::Continue);
        };
        match topic {
            schema::STATE if !every_step => {
                let s = decode_state(data)?;
                kinds.saw(&s.id, &s.kind, &s.kinds);
                state_rows(&mut states, &s)?;
                out.states += 1;
            }
            schema::STATE => {
                let s: KindColumns = decode(topic, data)?;
                kinds.saw(&s.id, &s.kind, &s.kinds);
            }
            schema::HASH => hash = Some(decode(topic, data)?),
            schema::TOTALS => {
                let t: TotalsMsg = decode(topic, data)?;
                let h = hash
                    .take()
                    .filter(|h| h.step == t.step)
                    .map_or(String::new(), |h| h.hash);
                steps.u(t.step).f(t.time.0).s(&h).f(t.kinetic_energy.0);
                for p in &t.momentum.0 {
                    steps.f(*p);
                }
                steps
                    .u(t.critters)
                    .u(t.collisions)
                    .u(t.impacts)
                    .u(t.contacts)
                    .end()?;
            }
            schema::COLLISIONS => {
                let c: CollisionsMsg = decode(topic, data)?;
                for i in 0..c.caller.len() {
                    let at = |v: &schema::Floats| v.0.get(i).copied().unwrap_or(f64::NAN);
                    collisions
                        .u(c.step)
                        .f(c.time.0)
                        .id(c.caller[i])
                        .id(c.arg.get(i).copied().unwrap_or(0))
                        .f(at(&c.px))
                        .f(at(&c.py));
                    if let Some(pz) = &c.pz {
                        collisions.f(at(pz));
                    }
                    collisions.f(at(&c.nx)).f(at(&c.ny));
                    if let Some(nz) = &c.nz {
                        collisions.f(at(nz));
                    }
                    collisions.f(at(&c.impulse)).end()?;
                }
            }
            schema::LIFECYCLE => {
                let l: LifecycleMsg = decode(topic, data)?;
                kinds.spawned(&l);
                lifecycle_rows(&mut lifecycle, &l, &kinds)?;
            }
            schema::LOG => {
                let g: LogMsg = decode(topic, data)?;
                for line in &g.lines {
                    log.u(g.step).f(g.time.0).s(line).end()?;
                }
            }
            _ => {}
        }
        Ok(Flow::Continue)
    })?;
    out.truncated = end.truncated;
    if every_step {
        let mut replay = Replay::new(rec)?;
        let last = rec.last_step();
        let mut write = |world: &crate::scenes::AnyWorld| -> Result<(), RecordingError> {
            let s = world.step_count();
            if rec.hashes.get(&s).is_some_and(|&h| world.state_hash() != h) {
                return Err(RecordingError::ExportDiverged { step: s });
            }
            state_rows(&mut states, &capture::any_state(world))?;
            out.states += 1;
            Ok(())
        };
        write(replay.world())?;
        replay.step_to(last, write)?;
    }
    for csv in [states, steps, collisions, lifecycle, log] {
        out.files.push(csv.finish()?);
    }
    Ok(out)
}
