//! Reading recordings with MCAP's streaming (linear) reader, which also reads files that were
//! cut short: everything up to the last complete chunk comes back, and the reason reading
//! stopped is kept. (The summary-based reader needs the footer, which a killed run never wrote.)

use super::error::{with_causes, RecordingError};
use super::meta::{EndMeta, RunMeta};
use super::schema::{self, ErrorMsg, LifecycleMsg, LogMsg, StateMsg, TotalsMsg};
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::Read;
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
}

/// Bigger records than this are taken as damage (a recording's chunks are about 1 MiB).
const RECORD_LIMIT: usize = 1 << 30;

/// Reads `path` from the start, calling `visit` for each record, in file order. Records of a
/// chunk come only once the whole chunk has been read and its CRC checked, so a cut-off chunk
/// yields nothing. Errors before any record was read mean the file is not a recording; later
/// ones end reading with [`ReadEnd::truncated`] set.
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
    let got = read_full(&mut file, &mut magic).map_err(io)?;
    if got < magic.len() || magic != *mcap::MAGIC {
        return Err(RecordingError::NotMcap {
            path: path.to_path_buf(),
        });
    }
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_start_magic(true)
            .with_prevalidate_chunk_crcs(true)
            .with_record_length_limit(RECORD_LIMIT),
    );
    // Channels by id: (topic, schema name).
    let mut schemas: BTreeMap<u16, (String, String, Vec<u8>)> = BTreeMap::new();
    let mut channels: BTreeMap<u16, String> = BTreeMap::new();
    let mut end = ReadEnd::default();
    while let Some(event) = reader.next_event() {
        let event = match event {
            Ok(e) => e,
            Err(e) => {
                end.truncated = Some(describe(&e));
                break;
            }
        };
        match event {
            LinearReadEvent::ReadRequest(n) => {
                let buf = reader.insert(n);
                let read = file.read(buf).map_err(io)?;
                reader.notify_read(read);
            }
            LinearReadEvent::Record { data, opcode } => {
                let record = match mcap::parse_record(opcode, data) {
                    Ok(r) => r,
                    Err(e) => {
                        end.truncated = Some(format!("a damaged record: {e}"));
                        break;
                    }
                };
                let flow = match record {
                    mcap::records::Record::Schema { header, data } => {
                        schemas
                            .insert(header.id, (header.name, header.encoding, data.into_owned()));
                        Flow::Continue
                    }
                    mcap::records::Record::Channel(c) => {
                        let (name, enc, text) = schemas
                            .get(&c.schema_id)
                            .map(|(n, e, t)| (n.as_str(), e.as_str(), t.as_slice()))
                            .unwrap_or(("", "", &[]));
                        let flow = visit(Item::Channel {
                            id: c.id,
                            topic: &c.topic,
                            schema: name,
                            schema_encoding: enc,
                            schema_data: text,
                            message_encoding: &c.message_encoding,
                        })?;
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
    Ok(end)
}

fn read_full(file: &mut File, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match file.read(&mut buf[got..])? {
            0 => break,
            n => got += n,
        }
    }
    Ok(got)
}

fn describe(e: &mcap::McapError) -> String {
    match e {
        mcap::McapError::UnexpectedEof => {
            "the file ends in the middle of a record (cut off: a crash or a kill?)".to_string()
        }
        other => format!("damaged data: {other}"),
    }
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
