//! Reading recordings record by record ([`super::scan`]), which also reads files that were cut
//! short or damaged: everything up to the last complete chunk comes back, a damaged chunk is
//! skipped and reported, and the reason reading stopped early is kept. (The summary-based
//! reader needs the footer, which a killed run never wrote.)

use super::error::{with_causes, RecordingError};
use super::meta::{EndMeta, RunMeta};
pub use super::scan::Damage;
use super::scan::{Event, Scanner};
use super::schema::{self, ErrorMsg, LifecycleMsg, LogMsg, StateMsg, TotalsMsg};
use std::collections::BTreeMap;
use std::fs::File;
use std::path::{Path, PathBuf};

/// One record of a recording, as the reader meets them.
pub enum Item<'a> {
    /// A schema and its channel are known: channel id, topic, schema name.
    Channel {
        /// Channel id.
        id: u16,
        /// Topic.
        topic: &'a str,
        /// Schema name.
        schema: &'a str,
        /// Schema encoding.
        schema_encoding: &'a str,
        /// Schema text.
        schema_data: &'a [u8],
        /// Message encoding.
        message_encoding: &'a str,
    },
    /// A metadata record.
    Metadata {
        /// Its name.
        name: &'a str,
        /// Its keys and values.
        map: &'a BTreeMap<String, String>,
    },
    /// An attachment.
    Attachment {
        /// Its name (for scripts: the path they were loaded from).
        name: &'a str,
        /// Its media type.
        media_type: &'a str,
        /// Its bytes.
        data: &'a [u8],
        /// Its log time.
        log_time: u64,
        /// Its create time.
        create_time: u64,
    },
    /// A message.
    Message {
        /// Its channel's topic.
        topic: &'a str,
        /// Its channel id.
        channel: u16,
        /// Sequence number.
        sequence: u32,
        /// Log time (simulated time in ns).
        log_time: u64,
        /// Publish time.
        publish_time: u64,
        /// Payload (JSON for critterbox channels).
        data: &'a [u8],
    },
    /// A damaged stretch of the file was skipped; reading goes on after it.
    Damaged(&'a Damage),
}

/// Whether to go on reading.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    /// Read on.
    Continue,
    /// Stop here.
    Stop,
}

/// How reading ended.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadEnd {
    /// `Some(reason)` when the file ended early or was damaged after its readable part.
    pub truncated: Option<String>,
    /// True when the visitor asked to stop.
    pub stopped: bool,
    /// Damaged stretches skipped (each also visited as [`Item::Damaged`]).
    pub damaged: Vec<Damage>,
}

/// Reads `path` from the start, calling `visit` for each record, in file order. Records of a
/// chunk come only once the whole chunk has been read and its CRC checked, so a cut-off or
/// damaged chunk yields nothing; a damaged one is visited as [`Item::Damaged`] and reading goes
/// on with the next good record. A file that does not start as MCAP is an error; one that ends
/// early has [`ReadEnd::truncated`] set.
pub fn read_items(
    path: &Path,
    mut visit: impl FnMut(Item<'_>) -> Result<Flow, RecordingError>,
) -> Result<ReadEnd, RecordingError> {
    let io = |e: std::io::Error| RecordingError::CannotRead {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let mut file = File::open(path).map_err(io)?;
    let mut magic = [0u8; 8];
    let got = super::scan::read_some(&mut file, &mut magic).map_err(io)?;
    if got < magic.len() || magic != *mcap::MAGIC {
        return Err(RecordingError::NotMcap {
            path: path.to_path_buf(),
        });
    }
    let mut scanner = Scanner::new(file).map_err(io)?;
    // Channels by id: (topic, schema name).
    let mut schemas: BTreeMap<u16, (String, String, Vec<u8>)> = BTreeMap::new();
    let mut channels: BTreeMap<u16, String> = BTreeMap::new();
    let mut end = ReadEnd::default();
    // The summary's copies stand in for channel records lost with a damaged chunk.
    let mut spare: BTreeMap<u16, mcap::records::Channel> = BTreeMap::new();
    for r in scanner.summary_channels() {
        match r {
            mcap::records::Record::Schema { header, data } => {
                let entry = (header.name.clone(), header.encoding.clone(), data.to_vec());
                schemas.entry(header.id).or_insert(entry);
            }
            mcap::records::Record::Channel(c) => {
                spare.insert(c.id, c.clone());
            }
            _ => {}
        }
    }
    while let Some(event) = scanner.next_event().map_err(io)? {
        match event {
            Event::Damaged(damage) => {
                let flow = visit(Item::Damaged(&damage))?;
                end.damaged.push(damage);
                if flow == Flow::Stop {
                    end.stopped = true;
                    break;
                }
            }
            Event::Record(record) => {
                let flow = match record {
                    mcap::records::Record::Schema { header, data } => {
                        schemas
                            .insert(header.id, (header.name, header.encoding, data.into_owned()));
                        Flow::Continue
                    }
                    mcap::records::Record::Channel(c) => {
                        let flow = visit(channel_item(&schemas, &c))?;
                        channels.insert(c.id, c.topic);
                        flow
                    }
                    mcap::records::Record::Metadata(m) => visit(Item::Metadata {
                        name: &m.name,
                        map: &m.metadata,
                    })?,
                    mcap::records::Record::Attachment { header, data, .. } => {
                        visit(Item::Attachment {
                            name: &header.name,
                            media_type: &header.media_type,
                            data: &data,
                            log_time: header.log_time,
                            create_time: header.create_time,
                        })?
                    }
                    mcap::records::Record::Message { header, data } => {
                        let lost = spare
                            .remove(&header.channel_id)
                            .filter(|c| !channels.contains_key(&c.id));
                        if let Some(c) = lost {
                            visit(channel_item(&schemas, &c))?;
                            channels.insert(c.id, c.topic);
                        }
                        let topic = channels.get(&header.channel_id).map_or("", String::as_str);
                        visit(Item::Message {
                            topic,
                            channel: header.channel_id,
                            sequence: header.sequence,
                            log_time: header.log_time,
                            publish_time: header.publish_time,
                            data: &data,
                        })?
                    }
                    _ => Flow::Continue,
                };
                if flow == Flow::Stop {
                    end.stopped = true;
                    break;
                }
            }
        }
    }
    if !end.stopped {
        end.truncated = scanner.truncated().map(str::to_string);
    }
    Ok(end)
}

/// Decodes a JSON message of `topic`, naming the topic on failure.
pub fn decode<T: serde::de::DeserializeOwned>(
    topic: &str,
    data: &[u8],
) -> Result<T, RecordingError> {
    serde_json::from_slice(data).map_err(|error| RecordingError::BadMessage {
        topic: topic.to_string(),
        error,
    })
}

/// Decodes a full state message and checks that its columns fit together.
pub fn decode_state(data: &[u8]) -> Result<StateMsg, RecordingError> {
    let state: StateMsg = decode(schema::STATE, data)?;
    state.check().map_err(|reason| RecordingError::BadState {
        step: state.step,
        reason,
    })?;
    Ok(state)
}

/// True for the errors that say the file as a whole cannot be read as a recording (as opposed
/// to one damaged message in it).
fn is_about_the_file(e: &RecordingError) -> bool {
    matches!(
        e,
        RecordingError::CannotRead { .. }
            | RecordingError::NotMcap { .. }
            | RecordingError::NotCritterbox { .. }
    )
}

/// What `replay`, `inspect`, `diff` and `export` need from a recording, read in one pass (full
/// states are left in the file: see [`for_each_state`]).
#[derive(Clone, Debug, Default)]
pub struct Recording {
    /// The file.
    pub path: PathBuf,
    /// How the run was made.
    pub meta: Option<RunMeta>,
    /// The raw metadata map (for diff).
    pub meta_map: BTreeMap<String, String>,
    /// How the run ended (absent in a cut-off file).
    pub end: Option<EndMeta>,
    /// Script files: (name = path loaded from, text).
    pub scripts: Vec<(String, String)>,
    /// Kind files reloaded while the run went on, in order (`run --watch`).
    pub reloads: Vec<schema::ReloadMsg>,
    /// The reloaded texts, by attachment name.
    pub reload_texts: BTreeMap<String, String>,
    /// Hash after each step, by step.
    pub hashes: BTreeMap<u64, u64>,
    /// Totals after each step.
    pub totals: Vec<TotalsMsg>,
    /// Steps with a full state.
    pub keyframes: Vec<u64>,
    /// Critters by kind in each full state, by step.
    pub kind_counts: BTreeMap<u64, BTreeMap<String, u64>>,
    /// Collisions per step (steps with any).
    pub collisions: BTreeMap<u64, usize>,
    /// Lifecycle events.
    pub lifecycle: Vec<LifecycleMsg>,
    /// Log lines.
    pub log: Vec<LogMsg>,
    /// The error that stopped the run, if any.
    pub error: Option<ErrorMsg>,
    /// Messages by topic.
    pub messages: BTreeMap<String, u64>,
    /// Why reading stopped early, for a cut-off or damaged file.
    pub truncated: Option<String>,
    /// Damaged stretches skipped, with the steps around them.
    pub gaps: Vec<Gap>,
    /// For a copy `critterbox recover` made: the file it was made from.
    pub recovered: Option<String>,
}

/// A damaged stretch of a recording and the steps it took with it.
#[derive(Clone, Debug, PartialEq)]
pub struct Gap {
    /// What was damaged.
    pub damage: Damage,
    /// The last step whose hash was read before the damage (`None`: none was).
    pub after: Option<u64>,
    /// The first step whose hash was read after it (`None`: none was).
    pub resumed: Option<u64>,
}

impl Gap {
    /// The steps none of whose hash was read, first and last; `last` is `None` when no step was
    /// read after the damage. `None` when the damage fell between two consecutive steps (it
    /// may still have held some of the earlier step's events).
    pub fn missing(&self) -> Option<(u64, Option<u64>)> {
        let first = self.after.map_or(0, |a| a + 1);
        match self.resumed {
            Some(r) if r <= first => None,
            Some(r) => Some((first, Some(r - 1))),
            None => Some((first, None)),
        }
    }
}

impl std::fmt::Display for Gap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.missing() {
            Some((a, Some(b))) if a == b => write!(f, "step {a} missing: {}", self.damage),
            Some((a, Some(b))) => write!(f, "steps {a}..{b} missing: {}", self.damage),
            Some((a, None)) => write!(f, "steps from {a} on missing: {}", self.damage),
            None => match self.after {
                Some(a) => write!(
                    f,
                    "no whole step missing (step {a} may lack events): {}",
                    self.damage
                ),
                None => write!(f, "no step missing: {}", self.damage),
            },
        }
    }
}

impl Recording {
    /// An error, saying what to do, if the file's state hashes were computed by another state
    /// hash than this critterbox's (then no recorded hash can match a replayed one).
    pub fn check_state_hash(&self) -> Result<(), RecordingError> {
        let theirs = self.meta_map.get("state_hash").map_or("1", String::as_str);
        if theirs != schema::STATE_HASH {
            return Err(RecordingError::OtherStateHash {
                path: self.path.clone(),
                theirs: theirs.to_string(),
                ours: schema::STATE_HASH,
            });
        }
        Ok(())
    }

    /// The recording format's version: 2 for files this critterbox writes, 1 for older ones
    /// (whose lifecycle events name no causes).
    pub fn format_version(&self) -> u32 {
        self.meta_map
            .get("format")
            .and_then(|f| f.rsplit('/').next())
            .and_then(|v| v.parse().ok())
            .unwrap_or(1)
    }

    /// True when part of the file could not be read (damaged or cut off), or steps are missing
    /// from it (a copy `recover` made of a damaged file).
    pub fn is_damaged(&self) -> bool {
        self.truncated.is_some() || !self.gaps.is_empty() || self.missing_steps() > 0
    }

    /// The runs of steps, up to the last one read, that have no hash in the file: first and
    /// last of each.
    pub fn missing_ranges(&self) -> Vec<(u64, u64)> {
        let mut ranges = Vec::new();
        let mut next = 0;
        for &s in self.hashes.keys() {
            if s > next {
                ranges.push((next, s - 1));
            }
            next = s + 1;
        }
        ranges
    }

    /// One line per damaged stretch, per run of missing steps no damage here explains (a
    /// recovered copy), and for a cut-off end (empty for an intact file).
    pub fn damage_report(&self) -> Vec<String> {
        let mut lines: Vec<String> = self.gaps.iter().map(Gap::to_string).collect();
        let explained = |&(a, b): &(u64, u64)| {
            self.gaps
                .iter()
                .filter_map(Gap::missing)
                .any(|(x, y)| x <= a && y.is_none_or(|y| b <= y))
        };
        for (a, b) in self.missing_ranges() {
            if !explained(&(a, b)) {
                let steps = if a == b {
                    format!("step {a} is")
                } else {
                    format!("steps {a}..{b} are")
                };
                lines.push(format!(
                    "{steps} missing from the file{}",
                    self.recovered_note()
                ));
            }
        }
        if let Some(t) = &self.truncated {
            lines.push(format!("cut off after step {}: {t}", self.last_step()));
        }
        lines
    }

    /// Steps up to the last one read whose hash is not in the file (lost to damage).
    pub fn missing_steps(&self) -> u64 {
        if self.hashes.is_empty() {
            return 0;
        }
        self.last_step() + 1 - self.hashes.len() as u64
    }

    /// The error a command returns, after its output, when part of the file could not be read
    /// (`None` for an intact file); [`Recording::damage_report`] has the details.
    pub fn damage_error(&self) -> Option<RecordingError> {
        if !self.is_damaged() {
            return None;
        }
        let mut what = Vec::new();
        if !self.gaps.is_empty() {
            what.push(format!(
                "{} damaged stretch{} skipped",
                self.gaps.len(),
                if self.gaps.len() == 1 { "" } else { "es" },
            ));
        }
        if self.missing_steps() > 0 {
            what.push(format!("{} steps missing", self.missing_steps()));
        }
        if self.truncated.is_some() {
            what.push(format!("cut off after step {}", self.last_step()));
        }
        Some(RecordingError::Damaged {
            path: self.path.clone(),
            what: format!(
                "{}; what could be read was used (`critterbox recover` writes a readable copy)",
                what.join(", ")
            ),
        })
    }

    /// For a copy `recover` made: where from and why.
    fn recovered_note(&self) -> String {
        self.recovered.as_ref().map_or(String::new(), |from| {
            format!(" (it was recovered from {from})")
        })
    }

    /// Reads a recording; a file that is not one is a clear error.
    pub fn open(path: &Path) -> Result<Recording, RecordingError> {
        let mut rec = Recording {
            path: path.to_path_buf(),
            ..Recording::default()
        };
        let end = read_items(path, |item| {
            match item {
                Item::Metadata { name, map } if name == schema::META => {
                    rec.meta_map = map.clone();
                    rec.meta = Some(RunMeta::from_map(map).map_err(|reason| {
                        RecordingError::NotCritterbox {
                            path: path.to_path_buf(),
                            reason,
                        }
                    })?);
                }
                Item::Metadata { name, map } if name == schema::RECOVERED => {
                    rec.recovered = map.get("from").cloned();
                }
                Item::Metadata { name, map } if name == schema::END => {
                    rec.end = Some(EndMeta::from_map(map));
                }
                Item::Attachment {
                    name,
                    media_type,
                    data,
                    ..
                } if media_type == schema::SCRIPT_MEDIA_TYPE => {
                    let text = String::from_utf8_lossy(data).into_owned();
                    rec.scripts.push((name.to_string(), text));
                }
                Item::Attachment {
                    name,
                    media_type,
                    data,
                    ..
                } if media_type == schema::RELOAD_MEDIA_TYPE => {
                    let text = String::from_utf8_lossy(data).into_owned();
                    rec.reload_texts.insert(name.to_string(), text);
                }
                Item::Damaged(damage) => rec.gaps.push(Gap {
                    damage: damage.clone(),
                    after: rec.hashes.keys().next_back().copied(),
                    resumed: None,
                }),
                Item::Message { topic, data, .. } => {
                    if rec.meta.is_none() {
                        return Err(RecordingError::NotCritterbox {
                            path: path.to_path_buf(),
                            reason: "it has no 'critterbox' metadata record before its messages"
                                .into(),
                        });
                    }
                    *rec.messages.entry(topic.to_string()).or_insert(0) += 1;
                    rec.take(topic, data)?;
                }
                _ => {}
            }
            Ok(Flow::Continue)
        });
        let end = match end {
            Ok(end) => end,
            // A damaged message in an otherwise readable file: keep what came before.
            Err(e) if rec.meta.is_some() && !is_about_the_file(&e) => ReadEnd {
                truncated: Some(with_causes(&e)),
                stopped: true,
                damaged: Vec::new(),
            },
            Err(e) => return Err(e),
        };
        if rec.meta.is_none() {
            let reason = match &end.truncated {
                Some(t) => format!("no 'critterbox' metadata record could be read ({t})"),
                None => "it has no 'critterbox' metadata record".to_string(),
            };
            return Err(RecordingError::NotCritterbox {
                path: path.to_path_buf(),
                reason,
            });
        }
        rec.truncated = end.truncated;
        Ok(rec)
    }

    fn take(&mut self, topic: &str, data: &[u8]) -> Result<(), RecordingError> {
        match topic {
            schema::HASH => {
                let m: schema::HashMsg = decode(topic, data)?;
                let hash =
                    u64::from_str_radix(&m.hash, 16).map_err(|_| RecordingError::BadHash {
                        topic: topic.to_string(),
                        hash: m.hash.clone(),
                    })?;
                self.hashes.insert(m.step, hash);
                for g in self.gaps.iter_mut().filter(|g| g.resumed.is_none()) {
                    g.resumed = Some(m.step);
                }
            }
            schema::TOTALS => self.totals.push(decode(topic, data)?),
            schema::STATE => {
                #[derive(serde::Deserialize)]
                struct Kinds {
                    step: u64,
                    kinds: Vec<String>,
                    kind: Vec<u32>,
                }
                let s: Kinds = decode(topic, data)?;
                let mut counts = BTreeMap::new();
                for k in s.kind {
                    let name = s.kinds.get(k as usize).map_or("?", String::as_str);
                    *counts.entry(name.to_string()).or_insert(0) += 1;
                }
                self.keyframes.push(s.step);
                self.kind_counts.insert(s.step, counts);
            }
            schema::COLLISIONS => {
                #[derive(serde::Deserialize)]
                struct Callers {
                    step: u64,
                    caller: Vec<u64>,
                }
                let c: Callers = decode(topic, data)?;
                self.collisions.insert(c.step, c.caller.len());
            }
            schema::LIFECYCLE => self.lifecycle.push(decode(topic, data)?),
            schema::RELOAD => self.reloads.push(decode(topic, data)?),
            schema::LOG => self.log.push(decode(topic, data)?),
            schema::ERROR => self.error = Some(decode(topic, data)?),
            _ => {}
        }
        Ok(())
    }

    /// The run's metadata (present in every opened recording).
    pub fn meta(&self) -> &RunMeta {
        self.meta
            .as_ref()
            .expect("Recording::open checks the metadata")
    }

    /// The last step recorded.
    pub fn last_step(&self) -> u64 {
        self.hashes.keys().next_back().copied().unwrap_or(0)
    }

    /// The nearest step at or before `step` with a full state that a replay can fly on from
    /// exactly. Under `event` and `auto` that is one whose number is a multiple of
    /// [`crate::method::FLIGHT_STEPS`] (step 0 is): a kept event flight is set up anew at those
    /// steps only, and at the others the recorded run flew on with events its full state does
    /// not hold. Under the other methods a step depends on the full state alone.
    pub fn keyframe_at_or_before(&self, step: u64) -> Option<u64> {
        use crate::method::{Method, FLIGHT_STEPS};
        let keeps_flights = !matches!(
            self.meta().method.parse::<Method>(),
            Ok(Method::Discrete | Method::Substep(_) | Method::Swept | Method::Solve(_))
        );
        self.keyframes
            .iter()
            .copied()
            .filter(|&k| k <= step && (!keeps_flights || k.is_multiple_of(FLIGHT_STEPS)))
            .max()
    }
}

/// Calls `visit` with each full state in the file, in step order, until it returns
/// [`Flow::Stop`].
pub fn for_each_state(
    path: &Path,
    mut visit: impl FnMut(StateMsg) -> Result<Flow, RecordingError>,
) -> Result<ReadEnd, RecordingError> {
    read_items(path, |item| match item {
        Item::Message { topic, data, .. } if topic == schema::STATE => {
            let state = decode_state(data)?;
            visit(state)
        }
        _ => Ok(Flow::Continue),
    })
}

/// The full state recorded at `step`, if there is one.
pub fn state_at(path: &Path, step: u64) -> Result<Option<StateMsg>, RecordingError> {
    let mut found = None;
    for_each_state(path, |s| {
        if s.step == step {
            found = Some(s);
            return Ok(Flow::Stop);
        }
        Ok(if s.step > step {
            Flow::Stop
        } else {
            Flow::Continue
        })
    })?;
    Ok(found)
}

/// A channel as readers see it, with its schema (empty when the schema was lost).
fn channel_item<'a>(
    schemas: &'a BTreeMap<u16, (String, String, Vec<u8>)>,
    c: &'a mcap::records::Channel,
) -> Item<'a> {
    let (schema, schema_encoding, schema_data) = schemas
        .get(&c.schema_id)
        .map(|(n, e, t)| (n.as_str(), e.as_str(), t.as_slice()))
        .unwrap_or(("", "", &[]));
    Item::Channel {
        id: c.id,
        topic: &c.topic,
        schema,
        schema_encoding,
        schema_data,
        message_encoding: &c.message_encoding,
    }
}
