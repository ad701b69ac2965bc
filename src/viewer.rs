//! Watching a run in the Rerun viewer (cargo feature `rerun`).
//!
//! What is logged, per step on the `step` (sequence) and `sim_time` (duration) timelines:
//! critters as 2D points or 3D spheres with their true radii under `world/critters/<kind>`
//! (colour per kind, labels with id, kind and health), velocity arrows under
//! `world/velocities/<kind>` (small scenes), contact points and impulses under `world/contacts`
//! on the step they happen, spawns, deaths and script log lines under `log`, and per-step kinetic
//! energy, momentum, collisions and step time under `stats/...`. Walls and the world border are
//! logged once, as static data.
//!
//! Viewing never stops a run: a missing viewer or a dropped connection is a warning.

use crate::critter::CritterId;
use crate::scenes::AnyWorld;
use crate::vector::Vector;
use crate::world::World;
use rerun::RecordingStream;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, TrySendError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Where the viewer data goes.
#[derive(Clone, Debug, PartialEq)]
pub enum RerunTarget {
    /// Start a viewer (the `rerun` program on PATH) and stream to it.
    Spawn,
    /// Stream to a running viewer at this URL (e.g. `rerun+http://127.0.0.1:9876/proxy`).
    Connect(String),
    /// Write an `.rrd` file.
    Save(PathBuf),
}

/// Velocity arrows are drawn by default up to this many critters.
pub const ARROWS_UP_TO: usize = 2_000;

/// Steps the logging thread may be behind before a live viewer skips one.
const QUEUE: usize = 4;

/// Streams a run to Rerun.
pub struct RerunSink {
    rec: RecordingStream,
    target: RerunTarget,
    arrows: bool,
    labels: bool,
    /// Time taken from the simulation thread.
    logging: Duration,
    /// Steps not sent to a live viewer because the logging thread was behind.
    skipped: u64,
    tx: Option<SyncSender<Frame>>,
    /// Frames sent and not yet drawn: a live viewer's step is skipped before it is copied when
    /// the queue is full.
    in_flight: Arc<AtomicUsize>,
    /// Frames the logging thread is done with, to be filled again (no allocation per step).
    spare: Option<Receiver<Frame>>,
    /// Told when the logging thread has drawn everything.
    done: Option<Receiver<()>>,
    thread: Option<JoinHandle<()>>,
    /// Lines to show with the next step drawn (a kind reloaded, `run --watch`).
    notes: Vec<String>,
}

/// A colour for a kind: its `color` default if it names one we know, else one from a palette.
fn color_of(name: Option<&str>, index: usize) -> [u8; 3] {
    const PALETTE: [[u8; 3]; 8] = [
        [76, 114, 176],
        [221, 132, 82],
        [85, 168, 104],
        [196, 78, 82],
        [129, 114, 179],
        [147, 120, 96],
        [218, 139, 195],
        [140, 140, 140],
    ];
    let named = match name.map(str::to_ascii_lowercase).as_deref() {
        Some("red") => Some([220, 50, 47]),
        Some("orange") => Some([255, 140, 0]),
        Some("yellow") => Some([230, 200, 0]),
        Some("green") | Some("mediumseagreen") => Some([60, 179, 113]),
        Some("blue") | Some("royalblue") => Some([65, 105, 225]),
        Some("silver") | Some("gray") | Some("grey") => Some([192, 192, 192]),
        Some("saddlebrown") | Some("brown") => Some([139, 69, 19]),
        Some("black") => Some([30, 30, 30]),
        Some("white") => Some([245, 245, 245]),
        Some(hex) if hex.len() == 7 && hex.starts_with('#') => {
            let p = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok();
            match (p(1), p(3), p(5)) {
                (Some(r), Some(g), Some(b)) => Some([r, g, b]),
                _ => None,
            }
        }
        _ => None,
    };
    named.unwrap_or(PALETTE[index % PALETTE.len()])
}

fn f32x3<V: Vector>(v: V) -> [f32; 3] {
    let a = v.to_array3();
    [a[0] as f32, a[1] as f32, a[2] as f32]
}

fn f32x2<V: Vector>(v: V) -> [f32; 2] {
    let a = v.to_array3();
    [a[0] as f32, a[1] as f32]
}

impl RerunSink {
    /// Opens the stream. Errors here are the caller's to report (as warnings for live viewing).
    pub fn new(target: RerunTarget, critters: usize) -> Result<Self, String> {
        let builder = rerun::RecordingStreamBuilder::new("critterbox");
        let rec = match &target {
            RerunTarget::Spawn => builder.spawn(),
            RerunTarget::Connect(url) => builder.connect_grpc_opts(url.clone()),
            RerunTarget::Save(path) => builder.save(path),
        }
        .map_err(|e| e.to_string())?;
        Ok(RerunSink {
            rec,
            target,
            arrows: critters <= ARROWS_UP_TO,
            labels: critters <= ARROWS_UP_TO,
            logging: Duration::ZERO,
            skipped: 0,
            tx: None,
            in_flight: Arc::new(AtomicUsize::new(0)),
            spare: None,
            done: None,
            thread: None,
            notes: Vec::new(),
        })
    }

    /// Shows `line` in the log with the next step drawn (a kind reloaded between steps).
    pub fn note(&mut self, line: String) {
        self.notes.push(line);
    }

    /// Turns velocity arrows on or off (before the first step is logged).
    pub fn set_arrows(&mut self, on: bool) {
        self.arrows = on;
    }

    /// Starts the logging thread on the first step.
    fn start(&mut self) {
        if self.tx.is_some() || self.thread.is_some() {
            return;
        }
        let (tx, rx) = std::sync::mpsc::sync_channel::<Frame>(QUEUE);
        let (give_back, spare) = std::sync::mpsc::channel::<Frame>();
        let (finished, done) = std::sync::mpsc::channel::<()>();
        let in_flight = Arc::clone(&self.in_flight);
        let mut drawer = Drawer {
            rec: self.rec.clone(),
            arrows: self.arrows,
            labels: self.labels,
            kinds: BTreeMap::new(),
        };
        match std::thread::Builder::new()
            .name("critterbox-rerun".into())
            .spawn(move || {
                for frame in rx {
                    drawer.draw(&frame);
                    in_flight.fetch_sub(1, Ordering::AcqRel);
                    let _ = give_back.send(frame);
                }
                let _ = finished.send(());
            }) {
            Ok(thread) => {
                self.tx = Some(tx);
                self.spare = Some(spare);
                self.done = Some(done);
                self.thread = Some(thread);
            }
            Err(e) => eprintln!("warning: no Rerun logging thread ({e}); nothing more is logged"),
        }
    }

    /// Time taken from the simulation thread so far (the cost to the run).
    pub fn logging_time(&self) -> Duration {
        self.logging
    }

    /// Steps a live viewer did not get because the logging thread was behind.
    pub fn skipped(&self) -> u64 {
        self.skipped
    }

    /// Logs walls and the border, once, as static data.
    pub fn log_static(&mut self, world: &AnyWorld) {
        let started = Instant::now();
        match world {
            AnyWorld::D2(w) => self.static_2d(w),
            AnyWorld::D3(w) => self.static_3d(w),
        }
        self.logging += started.elapsed();
    }

    fn static_2d(&mut self, w: &World<glam::DVec2>) {
        let t = w.topology();
        let (lo, hi) = (f32x2(t.min), f32x2(t.max));
        let border = vec![
            [lo[0], lo[1]],
            [hi[0], lo[1]],
            [hi[0], hi[1]],
            [lo[0], hi[1]],
            [lo[0], lo[1]],
        ];
        let _ = self.rec.log_static(
            "world/border",
            &rerun::LineStrips2D::new([border]).with_colors([[120, 120, 120]]),
        );
        let mut outlines = Vec::new();
        for c in w.critters().iter() {
            if let Some(wall) = c.wall() {
                let corner = |sx: f64, sy: f64| {
                    let local = glam::DVec2::new(sx * wall.half.x, sy * wall.half.y);
                    f32x2(c.pos + glam::DVec2::from_local(&wall.frame, local))
                };
                outlines.push(vec![
                    corner(-1., -1.),
                    corner(1., -1.),
                    corner(1., 1.),
                    corner(-1., 1.),
                    corner(-1., -1.),
                ]);
            }
        }
        if !outlines.is_empty() {
            let _ = self.rec.log_static(
                "world/walls",
                &rerun::LineStrips2D::new(outlines).with_colors([[90, 90, 90]]),
            );
        }
    }

    fn static_3d(&mut self, w: &World<glam::DVec3>) {
        let t = w.topology();
        let half = (t.max - t.min) * 0.5;
        let _ = self.rec.log_static(
            "world/border",
            &rerun::Boxes3D::from_centers_and_half_sizes([f32x3(t.min + half)], [f32x3(half)])
                .with_colors([[120, 120, 120]]),
        );
        let (mut centers, mut halves, mut rotations) = (Vec::new(), Vec::new(), Vec::new());
        for c in w.critters().iter() {
            if let Some(wall) = c.wall() {
                centers.push(f32x3(c.pos));
                halves.push(f32x3(wall.half));
                let q = glam::DQuat::from_mat3(&wall.frame);
                rotations.push(rerun::Quaternion::from_xyzw([
                    q.x as f32, q.y as f32, q.z as f32, q.w as f32,
                ]));
            }
        }
        if !centers.is_empty() {
            let _ = self.rec.log_static(
                "world/walls",
                &rerun::Boxes3D::from_centers_and_half_sizes(centers, halves)
                    .with_quaternions(rotations)
                    .with_colors([[90, 90, 90]]),
            );
        }
    }

    /// Logs the state after a step that took `step_time` to compute. On this (the simulation's)
    /// thread only a compact copy of the step is taken; the logging thread builds what Rerun
    /// gets from it.
    pub fn log_step(&mut self, world: &AnyWorld, step_time: Duration) {
        let started = Instant::now();
        self.start();
        let live = !matches!(self.target, RerunTarget::Save(_));
        if live && self.tx.is_some() && self.in_flight.load(Ordering::Acquire) >= QUEUE {
            // A live viewer never holds the run up: the logging thread is behind, so this step
            // is not even copied.
            self.skipped += 1;
            self.logging += started.elapsed();
            return;
        }
        let mut frame = self
            .spare
            .as_ref()
            .and_then(|r| r.try_recv().ok())
            .unwrap_or_else(Frame::empty);
        match world {
            AnyWorld::D2(w) => frame.fill(w, step_time),
            AnyWorld::D3(w) => frame.fill(w, step_time),
        }
        frame.notes = std::mem::take(&mut self.notes);
        self.send(frame);
        self.logging += started.elapsed();
    }

    fn send(&mut self, frame: Frame) {
        let Some(tx) = &self.tx else { return };
        self.in_flight.fetch_add(1, Ordering::AcqRel);
        if matches!(self.target, RerunTarget::Save(_)) {
            // A file gets every step: wait for the logging thread if it is behind.
            if tx.send(frame).is_err() {
                self.tx = None;
            }
            return;
        }
        // A live viewer never holds the run up: a step the logging thread has no room for is
        // skipped (and counted).
        match tx.try_send(frame) {
            Ok(()) => {}
            Err(TrySendError::Full(_)) => {
                self.in_flight.fetch_sub(1, Ordering::AcqRel);
                self.skipped += 1;
            }
            Err(TrySendError::Disconnected(_)) => self.tx = None,
        }
    }
    /// Flushes what is buffered. For a live viewer, waits at most a few seconds and returns a
    /// warning if it never answered (a connect to an absent viewer only fails here).
    pub fn finish(mut self) -> Option<String> {
        let live = !matches!(self.target, RerunTarget::Save(_));
        // Rerun's own shutdown waits for its sink without a limit; a live viewer that stopped
        // taking data would hold the program forever. So the stream is let go of (not shut
        // down) when a live viewer does not answer in time: the process ends without it.
        let wait = if live {
            Duration::from_secs(5)
        } else {
            Duration::from_secs(600)
        };
        // The logging thread ends when it has drawn every step sent.
        self.tx = None;
        if let (Some(thread), Some(done)) = (self.thread.take(), self.done.take()) {
            match done.recv_timeout(wait) {
                Ok(()) | Err(RecvTimeoutError::Disconnected) => {
                    if thread.join().is_err() {
                        return Some(
                            "the Rerun logging thread failed; the viewer's data stops early".into(),
                        );
                    }
                }
                Err(RecvTimeoutError::Timeout) => {
                    let message = self.stalled("the viewer stopped taking data");
                    std::mem::forget(self.rec);
                    return Some(message);
                }
            }
        }
        match self.rec.flush_with_timeout(wait) {
            Ok(()) => None,
            Err(e) => {
                let message = self.stalled(&e.to_string());
                if live {
                    std::mem::forget(self.rec);
                }
                Some(message)
            }
        }
    }

    fn stalled(&self, why: &str) -> String {
        match &self.target {
            RerunTarget::Save(p) => {
                format!("the Rerun file {} may be incomplete: {why}", p.display())
            }
            _ => format!(
                "no Rerun viewer took all the data ({why}); start one with `rerun` (pip install \
                 rerun-sdk==0.36.3) and try again"
            ),
        }
    }
}

/// One step, as the logging thread needs it: taken on the simulation thread, so it holds only
/// what the viewer shows, in f32 (what Rerun draws with).
struct Frame {
    dim: usize,
    step: u64,
    time: f64,
    step_ms: f64,
    /// Kind names and colours, by kind id.
    kinds: Vec<(String, [u8; 3])>,
    /// The live critters that are not walls, in slot order.
    kind: Vec<u32>,
    id: Vec<CritterId>,
    health: Vec<f64>,
    radius: Vec<f32>,
    pos: Vec<[f32; 3]>,
    vel: Vec<[f32; 3]>,
    /// The colour a script gave each critter (`me.color`), if any.
    color: Vec<Option<[u8; 3]>>,
    /// Contact points and impulses (normal times impulse).
    contacts: Vec<([f32; 3], [f32; 3])>,
    spawns: Vec<CritterId>,
    deaths: Vec<CritterId>,
    log: Vec<String>,
    /// Lines from the run around the world (a kind reloaded before this step).
    notes: Vec<String>,
    kinetic_energy: f64,
    momentum: [f64; 3],
    collisions: u64,
}

impl Frame {
    fn empty() -> Frame {
        Frame {
            dim: 2,
            step: 0,
            time: 0.0,
            step_ms: 0.0,
            kinds: Vec::new(),
            kind: Vec::new(),
            id: Vec::new(),
            health: Vec::new(),
            radius: Vec::new(),
            pos: Vec::new(),
            vel: Vec::new(),
            color: Vec::new(),
            contacts: Vec::new(),
            spawns: Vec::new(),
            deaths: Vec::new(),
            log: Vec::new(),
            notes: Vec::new(),
            kinetic_energy: 0.0,
            momentum: [0.0; 3],
            collisions: 0,
        }
    }

    /// Fills this frame (a recycled one: its buffers are reused) with the step just taken.
    fn fill<V: Vector>(&mut self, w: &World<V>, step_time: Duration) {
        let f = self;
        f.dim = V::DIM;
        f.step = w.step_count();
        f.time = w.time();
        f.step_ms = step_time.as_secs_f64() * 1e3;
        if f.kinds.len() != w.kinds().len() {
            f.kinds = w
                .kinds()
                .iter()
                .map(|(id, k)| {
                    let i = id.0 as usize;
                    (k.name.clone(), color_of(k.defaults.color.as_deref(), i))
                })
                .collect();
        }
        let n = w.critters().len();
        refill(&mut f.kind, n);
        refill(&mut f.id, n);
        refill(&mut f.health, n);
        refill(&mut f.radius, n);
        refill(&mut f.pos, n);
        refill(&mut f.vel, n);
        refill(&mut f.color, n);
        // The same sums, in the same order, as World::kinetic_energy and World::momentum.
        let mut energy = 0.0;
        let mut momentum = V::zero();
        for c in w.critters().iter() {
            energy += c.kinetic_energy();
            if !c.is_fixed() {
                momentum += c.vel * c.mass();
            }
            if !c.is_alive() || c.is_wall() {
                continue;
            }
            f.kind.push(c.kind().0);
            f.id.push(c.id());
            f.health.push(c.health());
            f.radius.push(c.radius() as f32);
            f.pos.push(f32x3(c.pos));
            f.vel.push(f32x3(c.vel));
            f.color
                .push(c.color().and_then(crate::color::parse).map(|rgba| {
                    let ch = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
                    [ch(rgba[0]), ch(rgba[1]), ch(rgba[2])]
                }));
        }
        f.kinetic_energy = energy;
        f.momentum = momentum.to_array3();
        f.collisions = w.stats().collisions as u64;
        let events = w.events();
        f.contacts.clear();
        f.contacts.extend(
            events
                .collisions
                .iter()
                .map(|e| (f32x3(e.point), f32x3(e.normal * e.impulse))),
        );
        f.spawns.clone_from(&events.spawns);
        f.deaths.clone_from(&events.deaths);
        f.log.clone_from(&events.log);
    }
}

/// Empties a reused buffer and makes room for `n` items, so filling it does not reallocate.
fn refill<T>(v: &mut Vec<T>, n: usize) {
    v.clear();
    v.reserve(n);
}

/// What was last logged in full for a kind: the critters (ids, health bits, radius bits,
/// colours). While they stay the same, a step logs only positions and velocities; labels, radii and colours
/// carry over in the viewer.
#[derive(PartialEq)]
struct Logged {
    id: Vec<CritterId>,
    health: Vec<u64>,
    radius: Vec<u32>,
    color: Vec<[u8; 3]>,
}

/// The logging thread's side: builds Rerun's archetypes from frames, in step order.
struct Drawer {
    rec: RecordingStream,
    arrows: bool,
    labels: bool,
    /// Kinds seen so far, with what was last logged in full for each (`None` after a clear).
    kinds: BTreeMap<String, Option<Logged>>,
}

fn xy(p: [f32; 3]) -> [f32; 2] {
    [p[0], p[1]]
}

impl Drawer {
    fn draw(&mut self, f: &Frame) {
        let rec = &self.rec;
        rec.set_time_sequence("step", f.step as i64);
        rec.set_duration_secs("sim_time", f.time);
        let name_of = |k: usize| f.kinds.get(k).map_or("?", |(n, _)| n.as_str());
        // Group critters by kind, in slot order.
        let mut members_of: Vec<Vec<usize>> = vec![Vec::new(); f.kinds.len()];
        for (i, &k) in f.kind.iter().enumerate() {
            if let Some(m) = members_of.get_mut(k as usize) {
                m.push(i);
            }
        }
        let by_kind: BTreeMap<&str, Vec<usize>> = members_of
            .into_iter()
            .enumerate()
            .filter(|(_, m)| !m.is_empty())
            .map(|(k, m)| (name_of(k), m))
            .collect();
        // Kinds that have died out are cleared, so they do not linger.
        for (name, logged) in self.kinds.iter_mut() {
            if !by_kind.contains_key(name.as_str()) && logged.is_some() {
                let _ = rec.log(format!("world/critters/{name}"), &rerun::Clear::flat());
                let _ = rec.log(format!("world/velocities/{name}"), &rerun::Clear::flat());
                *logged = None;
            }
        }
        for (name, members) in &by_kind {
            let kind = f.kind[members[0]];
            let color = f.kinds.get(kind as usize).map_or([128; 3], |(_, c)| *c);
            // Each critter in its own colour where a script gave it one, else its kind's.
            let colors: Vec<[u8; 3]> = members
                .iter()
                .map(|&i| f.color[i].unwrap_or(color))
                .collect();
            let now = Logged {
                id: members.iter().map(|&i| f.id[i]).collect(),
                health: members.iter().map(|&i| f.health[i].to_bits()).collect(),
                radius: members.iter().map(|&i| f.radius[i].to_bits()).collect(),
                color: colors.clone(),
            };
            let slot = self.kinds.entry(name.to_string()).or_insert(None);
            let full = slot.as_ref() != Some(&now);
            let path = format!("world/critters/{name}");
            let radii = || members.iter().map(|&i| f.radius[i]).collect::<Vec<f32>>();
            let labels = || {
                members
                    .iter()
                    .map(|&i| format!("{} {} hp {}", f.id[i], name, f.health[i]))
                    .collect::<Vec<String>>()
            };
            if f.dim == 2 {
                let pos: Vec<[f32; 2]> = members.iter().map(|&i| xy(f.pos[i])).collect();
                let mut points = if full {
                    rerun::Points2D::new(pos.clone())
                        .with_radii(radii())
                        .with_colors(colors.clone())
                } else {
                    rerun::Points2D::update_fields().with_positions(pos.clone())
                };
                if full && self.labels {
                    points = points.with_labels(labels());
                }
                let _ = rec.log(path, &points);
                if self.arrows {
                    let vel: Vec<[f32; 2]> = members.iter().map(|&i| xy(f.vel[i])).collect();
                    let _ = rec.log(
                        format!("world/velocities/{name}"),
                        &rerun::Arrows2D::from_vectors(vel)
                            .with_origins(pos)
                            .with_colors(colors.clone()),
                    );
                }
            } else {
                let pos: Vec<[f32; 3]> = members.iter().map(|&i| f.pos[i]).collect();
                let mut spheres = if full {
                    rerun::Ellipsoids3D::from_centers_and_radii(pos.clone(), radii())
                        .with_colors(colors.clone())
                } else {
                    rerun::Ellipsoids3D::update_fields().with_centers(pos.clone())
                };
                if full && self.labels {
                    spheres = spheres.with_labels(labels());
                }
                let _ = rec.log(path, &spheres);
                if self.arrows {
                    let vel: Vec<[f32; 3]> = members.iter().map(|&i| f.vel[i]).collect();
                    let _ = rec.log(
                        format!("world/velocities/{name}"),
                        &rerun::Arrows3D::from_vectors(vel)
                            .with_origins(pos)
                            .with_colors(colors.clone()),
                    );
                }
            }
            if full {
                *slot = Some(now);
            }
        }

        // Contacts: shown on the step they happen only.
        if f.contacts.is_empty() {
            let _ = rec.log("world/contacts", &rerun::Clear::flat());
        } else if f.dim == 2 {
            let points: Vec<[f32; 2]> = f.contacts.iter().map(|c| xy(c.0)).collect();
            let impulses: Vec<[f32; 2]> = f.contacts.iter().map(|c| xy(c.1)).collect();
            let _ = rec.log(
                "world/contacts",
                &rerun::Arrows2D::from_vectors(impulses)
                    .with_origins(points)
                    .with_colors([[230, 60, 60]]),
            );
        } else {
            let points: Vec<[f32; 3]> = f.contacts.iter().map(|c| c.0).collect();
            let impulses: Vec<[f32; 3]> = f.contacts.iter().map(|c| c.1).collect();
            let _ = rec.log(
                "world/contacts",
                &rerun::Arrows3D::from_vectors(impulses)
                    .with_origins(points)
                    .with_colors([[230, 60, 60]]),
            );
        }
        for id in &f.spawns {
            let _ = rec.log(
                "log",
                &rerun::TextLog::new(format!("spawned critter {id}")).with_level("INFO"),
            );
        }
        for id in &f.deaths {
            let _ = rec.log(
                "log",
                &rerun::TextLog::new(format!("critter {id} died")).with_level("WARN"),
            );
        }
        for line in &f.log {
            let _ = rec.log(
                "log",
                &rerun::TextLog::new(line.clone()).with_level("DEBUG"),
            );
        }
        for line in &f.notes {
            let _ = rec.log("log", &rerun::TextLog::new(line.clone()).with_level("INFO"));
        }

        // Totals.
        let _ = rec.log(
            "stats/kinetic_energy",
            &rerun::Scalars::single(f.kinetic_energy),
        );
        for (axis, name) in ["x", "y", "z"].iter().enumerate().take(f.dim) {
            let _ = rec.log(
                format!("stats/momentum/{name}"),
                &rerun::Scalars::single(f.momentum[axis]),
            );
        }
        let _ = rec.log(
            "stats/collisions",
            &rerun::Scalars::single(f.collisions as f64),
        );
        let _ = rec.log("stats/step_ms", &rerun::Scalars::single(f.step_ms));
    }
}
