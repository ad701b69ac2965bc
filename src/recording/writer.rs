//! The recorder: captures each step on the simulation thread and hands it to a writer thread,
//! which encodes JSON, compresses chunks and writes the file.
//!
//! The simulation thread only hashes, sums totals and copies events (and, on keyframes, the
//! critters' columns); encoding and zstd run on the writer thread. A bounded queue between them
//! keeps memory bounded: if the writer falls behind, the simulation waits. The writer ends the
//! current chunk every [`FLUSH_EVERY`] of wall time, so a process killed mid-run leaves a file
//! whose complete chunks `critterbox recover` reads back.

use super::capture::{self, KindTable, StepRecord};
use super::error::RecordingError;
use super::foxglove;
use super::meta::{EndMeta, RunMeta, SETUP_FAILED};
use super::schema::{self, ErrorMsg, Float, HashMsg, ReloadMsg, StateMsg};
use crate::scenes::{AnyWorld, SourceFile};
use mcap::records::{MessageHeader, Metadata};
use mcap::{Attachment, WriteOptions};
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, RecvTimeoutError, SyncSender};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How often the writer ends the current chunk (wall time).
pub const FLUSH_EVERY: Duration = Duration::from_millis(250);

/// Batches of steps the simulation may run ahead of the writer.
const QUEUE: usize = 8;

/// Steps sent to the writer together (one wake-up of its thread per batch, not per step); a
/// full state goes at once.
const BATCH: usize = 16;

/// zstd level of the chunks (see docs/recording-format.md for the measurements).
const ZSTD_LEVEL: u32 = 1;

enum Job {
    Steps(Vec<StepRecord>),
    State(Box<StateMsg>),
    Error(ErrorMsg),
    Attach(Vec<SourceFile>),
    Reload(ReloadMsg, String),
    Finish(EndMeta),
}

/// What a finished recording holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Written {
    /// The file.
    pub path: PathBuf,
    /// Its size.
    pub bytes: u64,
    /// Steps recorded (the last step's number).
    pub steps: u64,
    /// Full states written.
    pub states: u64,
}

/// Records a run. Create it after the scene is built, call [`Recorder::record`] after every
/// step, and [`Recorder::finish`] at the end (dropping it finishes the file too, marked
/// `aborted`).
pub struct Recorder {
    tx: Option<SyncSender<Job>>,
    thread: Option<JoinHandle<Result<Written, String>>>,
    path: PathBuf,
    every: u64,
    known_kinds: usize,
    last_step: u64,
    last_state: u64,
    batch: Vec<StepRecord>,
    /// The paths of the script files attached so far.
    attached: std::collections::BTreeSet<String>,
    /// How far [`Recorder::attach_since`] has read each of its caller's lists of files.
    cursors: Vec<usize>,
}

/// Lowers the calling thread's scheduling priority (nice 10), so that on a busy machine the
/// simulation thread and rayon's workers get the cores before the recorder does. The recorder
/// cannot fall behind for long: the queue is bounded, and a full queue makes the simulation
/// thread wait. Linux only, where nice belongs to a thread (elsewhere it would be the process).
/// docs/recording-format.md has what it saves.
fn yield_to_the_simulation() {
    #[cfg(target_os = "linux")]
    // SAFETY: setpriority reads its three integer arguments only; `who` 0 is the calling thread.
    // A failure (not possible when raising one's own nice value) leaves the priority as it was.
    unsafe {
        libc::setpriority(libc::PRIO_PROCESS, 0, 10);
    }
}

fn write_err(path: &Path, e: impl std::fmt::Display) -> RecordingError {
    RecordingError::CannotWrite {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

impl Recorder {
    /// Creates the file, writes the metadata, the script attachments and step 0 (a full state),
    /// and starts the writer thread. Full states are recorded every `every` steps.
    pub fn create(
        path: &Path,
        meta: &RunMeta,
        sources: &[SourceFile],
        world: &AnyWorld,
    ) -> Result<Recorder, RecordingError> {
        let (w, channels) = open(path, meta, sources)?;

        let (tx, rx) = mpsc::sync_channel::<Job>(QUEUE);
        let thread_path = path.to_path_buf();
        let thread = std::thread::Builder::new()
            .name("critterbox-recorder".into())
            .spawn(move || {
                yield_to_the_simulation();
                let out = Output {
                    w,
                    channels,
                    sequence: BTreeMap::new(),
                    colors: Vec::new(),
                    last_log_time: 0,
                    steps: 0,
                    states: 0,
                };
                out.run(rx).map(|(steps, states)| {
                    let bytes = std::fs::metadata(&thread_path).map_or(0, |m| m.len());
                    Written {
                        path: thread_path,
                        bytes,
                        steps,
                        states,
                    }
                })
            })
            .map_err(|e| write_err(path, e))?;
        let mut rec = Recorder {
            tx: Some(tx),
            thread: Some(thread),
            path: path.to_path_buf(),
            every: meta.record_every.max(1),
            known_kinds: 0,
            last_step: 0,
            last_state: 0,
            batch: Vec::with_capacity(BATCH),
            attached: sources.iter().map(|s| s.path.clone()).collect(),
            cursors: Vec::new(),
        };
        rec.capture(world, true)?;
        Ok(rec)
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Records the step just taken: hash, totals and events, and the full state on keyframes.
    pub fn record(&mut self, world: &AnyWorld) -> Result<(), RecordingError> {
        let full = world.step_count().is_multiple_of(self.every);
        self.capture(world, full)
    }

    fn capture(&mut self, world: &AnyWorld, full: bool) -> Result<(), RecordingError> {
        let rec = capture::capture(world, full, self.known_kinds);
        if let Some(k) = &rec.kinds {
            self.known_kinds = k.names.len();
        }
        self.last_step = rec.step;
        if full {
            self.last_state = rec.step;
        }
        self.batch.push(rec);
        if full || self.batch.len() >= BATCH {
            self.send_batch()?;
        }
        Ok(())
    }

    fn send_batch(&mut self) -> Result<(), RecordingError> {
        if self.batch.is_empty() {
            return Ok(());
        }
        let batch = std::mem::replace(&mut self.batch, Vec::with_capacity(BATCH));
        self.send_now(Job::Steps(batch))
    }

    /// Sends `job` after the steps still batched.
    fn send(&mut self, job: Job) -> Result<(), RecordingError> {
        self.send_batch()?;
        self.send_now(job)
    }

    fn send_now(&mut self, job: Job) -> Result<(), RecordingError> {
        let sent = match &self.tx {
            Some(tx) => tx.send(job).is_ok(),
            None => false,
        };
        if sent {
            return Ok(());
        }
        // The writer thread stopped: it failed; its error says why.
        self.tx = None;
        let message = match self.thread.take().map(JoinHandle::join) {
            Some(Ok(Err(e))) => e,
            Some(Err(_)) => "the recorder thread panicked".to_string(),
            _ => "the recorder is closed".to_string(),
        };
        Err(write_err(&self.path, message))
    }

    /// Records the error that stopped the run, in the step after the last one recorded.
    pub fn record_error(&mut self, world: &AnyWorld, message: &str) -> Result<(), RecordingError> {
        self.send(Job::Error(ErrorMsg {
            step: self.last_step + 1,
            time: Float(world.time()),
            message: message.to_string(),
        }))
    }

    /// Records that `text`, the new text of the kind file `file`, replaced the kinds `kinds`
    /// after the last step recorded: the text as an attachment, and a reload message naming
    /// it, so a replay makes the same swap at the same step.
    pub fn reload(
        &mut self,
        world: &AnyWorld,
        file: &str,
        text: &str,
        kinds: Vec<String>,
    ) -> Result<(), RecordingError> {
        let step = world.step_count();
        // The next step's record carries the kind table again: a kind's colour may have changed.
        self.known_kinds = 0;
        let msg = ReloadMsg {
            step,
            time: Float(world.time()),
            file: file.to_string(),
            attachment: reload_attachment(file, step),
            kinds,
        };
        self.send(Job::Reload(msg, text.to_string()))
    }

    /// Attaches more script files (kinds loaded after the scene was set up).
    pub fn attach(&mut self, sources: Vec<SourceFile>) -> Result<(), RecordingError> {
        if sources.is_empty() {
            return Ok(());
        }
        self.attached.extend(sources.iter().map(|s| s.path.clone()));
        self.send(Job::Attach(sources))
    }

    /// Attaches the files a growing list of loaded scripts gained since the last call for the
    /// same `list` (the caller's number for it), skipping paths attached already: a test's
    /// kinds, loaded by whichever runtime spawned them. `since(n)` gives the list from its
    /// `n`-th file on.
    pub fn attach_since(
        &mut self,
        list: usize,
        since: impl FnOnce(usize) -> Vec<SourceFile>,
    ) -> Result<(), RecordingError> {
        if self.cursors.len() <= list {
            self.cursors.resize(list + 1, 0);
        }
        let files = since(self.cursors[list]);
        self.cursors[list] += files.len();
        let new: Vec<SourceFile> = files
            .into_iter()
            .filter(|s| !self.attached.contains(&s.path))
            .collect();
        self.attach(new)
    }

    /// Writes the final full state (if the last step was not a keyframe), the end record and the
    /// summary, and closes the file.
    pub fn finish(mut self, world: &AnyWorld, end: EndMeta) -> Result<Written, RecordingError> {
        if world.step_count() == self.last_step && self.last_state != self.last_step {
            let state = capture::any_state(world);
            self.send(Job::State(Box::new(state)))?;
        }
        self.close(end)
    }

    fn close(&mut self, end: EndMeta) -> Result<Written, RecordingError> {
        self.send(Job::Finish(end))?;
        self.tx = None;
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(Ok(w))) => Ok(w),
            Some(Ok(Err(e))) => Err(write_err(&self.path, e)),
            Some(Err(_)) => Err(write_err(&self.path, "the recorder thread panicked")),
            None => Err(write_err(&self.path, "the recorder is closed")),
        }
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        if self.tx.is_some() {
            let end = EndMeta {
                steps: self.last_step,
                outcome: "aborted".into(),
                reason: "the recorder was dropped before the run finished".into(),
                hash: 0,
                ..EndMeta::default()
            };
            let _ = self.close(end);
        }
    }
}

/// The MCAP writer of a recording's file.
type McapFile = mcap::Writer<BufWriter<File>>;

/// Channel ids by topic.
type Channels = BTreeMap<&'static str, u16>;

/// Creates the file and writes the metadata, the schemas and channels, and the script
/// attachments, flushed so that they survive a kill.
fn open(
    path: &Path,
    meta: &RunMeta,
    sources: &[SourceFile],
) -> Result<(McapFile, Channels), RecordingError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| write_err(path, e))?;
    }
    let file = File::create(path).map_err(|e| write_err(path, e))?;
    let options = WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .compression_level(ZSTD_LEVEL)
        .compression_threads(0)
        .profile("critterbox")
        .library(format!("critterbox {}", env!("CARGO_PKG_VERSION")));
    let mut w = options
        .create(BufWriter::with_capacity(1 << 20, file))
        .map_err(|e| write_err(path, e))?;
    let mut channels = BTreeMap::new();
    for c in schema::channel_schemas() {
        let text = serde_json::to_vec(&c.schema).map_err(|e| write_err(path, e))?;
        let schema_id = w
            .add_schema(c.name, "jsonschema", &text)
            .map_err(|e| write_err(path, e))?;
        let id = w
            .add_channel(schema_id, c.topic, "json", &BTreeMap::new())
            .map_err(|e| write_err(path, e))?;
        channels.insert(c.topic, id);
    }
    w.write_metadata(&Metadata {
        name: schema::META.into(),
        metadata: meta.to_map(),
    })
    .map_err(|e| write_err(path, e))?;
    for s in sources {
        attach(&mut w, s).map_err(|e| write_err(path, e))?;
    }
    w.flush().map_err(|e| write_err(path, e))?;
    Ok((w, channels))
}

/// Records a run whose scene could not be built: the metadata, the script files read up to the
/// failure, the error (at step 0) and an end record with outcome [`SETUP_FAILED`] and the
/// error as its reason. The file holds no step, so nothing in it can be replayed or verified.
pub fn write_failed_setup(
    path: &Path,
    meta: &RunMeta,
    sources: &[SourceFile],
    message: &str,
) -> Result<Written, RecordingError> {
    let (w, channels) = open(path, meta, sources)?;
    let mut out = Output {
        w,
        channels,
        sequence: BTreeMap::new(),
        colors: Vec::new(),
        last_log_time: 0,
        steps: 0,
        states: 0,
    };
    let error = ErrorMsg {
        step: 0,
        time: Float(0.0),
        message: message.to_string(),
    };
    out.put_json(schema::ERROR, 0, &error)
        .map_err(|e| write_err(path, e))?;
    let end = EndMeta {
        steps: 0,
        outcome: SETUP_FAILED.into(),
        reason: message.to_string(),
        hash: 0,
        profile: Vec::new(),
    };
    out.close(&end).map_err(|e| write_err(path, e))?;
    Ok(Written {
        path: path.to_path_buf(),
        bytes: std::fs::metadata(path).map_or(0, |m| m.len()),
        steps: 0,
        states: 0,
    })
}

fn attach<W: std::io::Write + std::io::Seek>(
    w: &mut mcap::Writer<W>,
    s: &SourceFile,
) -> mcap::McapResult<()> {
    w.attach(&Attachment {
        log_time: 0,
        create_time: 0,
        name: s.path.clone(),
        media_type: schema::SCRIPT_MEDIA_TYPE.into(),
        data: Cow::Borrowed(s.text.as_bytes()),
    })
}

/// The name of the attachment holding the text `file` was reloaded with after step `step`.
pub fn reload_attachment(file: &str, step: u64) -> String {
    format!("{file}@{step}")
}

/// The writer thread's side.
struct Output {
    w: McapFile,
    channels: Channels,
    sequence: BTreeMap<u16, u32>,
    colors: Vec<foxglove::Rgba>,
    last_log_time: u64,
    steps: u64,
    states: u64,
}

impl Output {
    fn run(mut self, rx: mpsc::Receiver<Job>) -> Result<(u64, u64), String> {
        let mut last_flush = Instant::now();
        let mut dirty = false;
        loop {
            let job = match rx.recv_timeout(FLUSH_EVERY) {
                Ok(job) => Some(job),
                Err(RecvTimeoutError::Timeout) => None,
                Err(RecvTimeoutError::Disconnected) => Some(Job::Finish(EndMeta {
                    steps: self.steps,
                    outcome: "aborted".into(),
                    reason: "the run ended without closing the recording".into(),
                    hash: 0,
                    ..EndMeta::default()
                })),
            };
            match job {
                Some(Job::Finish(end)) => return self.close(&end),
                Some(job) => {
                    self.write(job).map_err(|e| e.to_string())?;
                    dirty = true;
                }
                None => {}
            }
            if dirty && last_flush.elapsed() >= FLUSH_EVERY {
                self.w.flush().map_err(|e| e.to_string())?;
                last_flush = Instant::now();
                dirty = false;
            }
        }
    }

    /// Writes the end record and the summary, and flushes the file.
    fn close(mut self, end: &EndMeta) -> Result<(u64, u64), String> {
        self.w
            .write_metadata(&Metadata {
                name: schema::END.into(),
                metadata: end.to_map(),
            })
            .map_err(|e| e.to_string())?;
        self.w.finish().map_err(|e| e.to_string())?;
        let mut file = self.w.into_inner();
        std::io::Write::flush(&mut file).map_err(|e| e.to_string())?;
        Ok((self.steps, self.states))
    }

    fn put(&mut self, topic: &str, log_time: u64, data: &[u8]) -> mcap::McapResult<()> {
        let channel_id = self.channels[topic];
        let seq = self.sequence.entry(channel_id).or_insert(0);
        *seq = seq.wrapping_add(1);
        self.w.write_to_known_channel(
            &MessageHeader {
                channel_id,
                sequence: *seq,
                log_time,
                publish_time: log_time,
            },
            data,
        )
    }

    fn log_time(&mut self, time: f64) -> u64 {
        // Simulated time in ns, never going back (a script may change dt).
        let t = if time.is_finite() && time > 0.0 {
            (time * 1e9).round() as u64
        } else {
            0
        };
        self.last_log_time = self.last_log_time.max(t);
        self.last_log_time
    }

    fn put_json<T: serde::Serialize>(
        &mut self,
        topic: &str,
        t: u64,
        msg: &T,
    ) -> mcap::McapResult<()> {
        let data = serde_json::to_vec(msg).map_err(std::io::Error::other)?;
        self.put(topic, t, &data)
    }

    fn put_state(&mut self, t: u64, state: &StateMsg) -> mcap::McapResult<()> {
        self.put_json(schema::STATE, t, state)?;
        let scene = foxglove::scene_update(state, t, &self.colors);
        self.put(schema::SCENE, t, scene.as_bytes())?;
        self.states += 1;
        Ok(())
    }

    fn write_step(&mut self, rec: StepRecord) -> mcap::McapResult<()> {
        if let Some(KindTable { colors, .. }) = rec.kinds {
            self.colors = colors;
        }
        let t = self.log_time(rec.time);
        self.steps = rec.step;
        let hash = HashMsg {
            step: rec.step,
            time: Float(rec.time),
            hash: format!("{:016x}", rec.hash),
        };
        self.put_json(schema::HASH, t, &hash)?;
        self.put_json(schema::TOTALS, t, &rec.totals)?;
        if let Some(m) = &rec.collisions {
            self.put_json(schema::COLLISIONS, t, m)?;
        }
        if let Some(m) = &rec.lifecycle {
            self.put_json(schema::LIFECYCLE, t, m)?;
        }
        if let Some(m) = &rec.log {
            self.put_json(schema::LOG, t, m)?;
        }
        if let Some(s) = &rec.state {
            self.put_state(t, s)?;
        }
        Ok(())
    }

    fn write(&mut self, job: Job) -> mcap::McapResult<()> {
        match job {
            Job::Steps(batch) => {
                for rec in batch {
                    self.write_step(rec)?;
                }
            }
            Job::State(state) => {
                let t = self.log_time(state.time.0);
                self.put_state(t, &state)?;
            }
            Job::Error(e) => {
                let t = self.log_time(e.time.0);
                self.put_json(schema::ERROR, t, &e)?;
            }
            Job::Attach(sources) => {
                for s in &sources {
                    attach(&mut self.w, s)?;
                }
            }
            Job::Reload(msg, text) => {
                let t = self.log_time(msg.time.0);
                self.w.attach(&Attachment {
                    log_time: t,
                    create_time: t,
                    name: msg.attachment.clone(),
                    media_type: schema::RELOAD_MEDIA_TYPE.into(),
                    data: Cow::Borrowed(text.as_bytes()),
                })?;
                self.put_json(schema::RELOAD, t, &msg)?;
            }
            Job::Finish(_) => {}
        }
        Ok(())
    }
}
