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

/// Streams a run to Rerun.
pub struct RerunSink {
    rec: RecordingStream,
    target: RerunTarget,
    arrows: bool,
    labels: bool,
    logging: Duration,
    kinds_seen: BTreeMap<String, ()>,
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
            kinds_seen: BTreeMap::new(),
        })
    }

    /// Turns velocity arrows on or off.
    pub fn set_arrows(&mut self, on: bool) {
        self.arrows = on;
    }

    /// Time spent logging so far (the cost to the simulation).
    pub fn logging_time(&self) -> Duration {
        self.logging
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

    /// Logs the state after a step that took `step_time` to compute.
    pub fn log_step(&mut self, world: &AnyWorld, step_time: Duration) {
        let started = Instant::now();
        match world {
            AnyWorld::D2(w) => self.step_generic(w, step_time),
            AnyWorld::D3(w) => self.step_generic(w, step_time),
        }
        self.logging += started.elapsed();
    }

    fn step_generic<V: Vector>(&mut self, w: &World<V>, step_time: Duration) {
        let rec = &self.rec;
        rec.set_time_sequence("step", w.step_count() as i64);
        rec.set_duration_secs("sim_time", w.time());
        let kinds = w.kinds();
        // Group critters by kind, in id order.
        let mut by_kind: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        let critters: Vec<_> = w
            .critters()
            .iter()
            .filter(|c| c.is_alive() && !c.is_wall())
            .collect();
        for (i, c) in critters.iter().enumerate() {
            by_kind
                .entry(kinds.name(c.kind()).to_string())
                .or_default()
                .push(i);
        }
        // Kinds that have died out are cleared, so they do not linger.
        for name in self.kinds_seen.keys() {
            if !by_kind.contains_key(name) {
                let _ = rec.log(format!("world/critters/{name}"), &rerun::Clear::flat());
                let _ = rec.log(format!("world/velocities/{name}"), &rerun::Clear::flat());
            }
        }
        for (name, members) in &by_kind {
            self.kinds_seen.insert(name.clone(), ());
            let kind_id = critters[members[0]].kind();
            let color = color_of(
                kinds.get(kind_id).defaults.color.as_deref(),
                kind_id.0 as usize,
            );
            let radii: Vec<f32> = members
                .iter()
                .map(|&i| critters[i].radius() as f32)
                .collect();
            let labels: Vec<String> = if self.labels {
                members
                    .iter()
                    .map(|&i| format!("{} {} hp {}", critters[i].id(), name, critters[i].health))
                    .collect()
            } else {
                Vec::new()
            };
            let path = format!("world/critters/{name}");
            if V::DIM == 2 {
                let pos: Vec<[f32; 2]> = members.iter().map(|&i| f32x2(critters[i].pos)).collect();
                let mut points = rerun::Points2D::new(pos.clone())
                    .with_radii(radii)
                    .with_colors([color]);
                if self.labels {
                    points = points.with_labels(labels);
                }
                let _ = rec.log(path, &points);
                if self.arrows {
                    let vel: Vec<[f32; 2]> =
                        members.iter().map(|&i| f32x2(critters[i].vel)).collect();
                    let _ = rec.log(
                        format!("world/velocities/{name}"),
                        &rerun::Arrows2D::from_vectors(vel)
                            .with_origins(pos)
                            .with_colors([color]),
                    );
                }
            } else {
                let pos: Vec<[f32; 3]> = members.iter().map(|&i| f32x3(critters[i].pos)).collect();
                let mut spheres = rerun::Ellipsoids3D::from_centers_and_radii(pos.clone(), radii)
                    .with_colors([color]);
                if self.labels {
                    spheres = spheres.with_labels(labels);
                }
                let _ = rec.log(path, &spheres);
                if self.arrows {
                    let vel: Vec<[f32; 3]> =
                        members.iter().map(|&i| f32x3(critters[i].vel)).collect();
                    let _ = rec.log(
                        format!("world/velocities/{name}"),
                        &rerun::Arrows3D::from_vectors(vel)
                            .with_origins(pos)
                            .with_colors([color]),
                    );
                }
            }
        }

        // Contacts: shown on the step they happen only.
        let events = w.events();
        if events.collisions.is_empty() {
            let _ = rec.log("world/contacts", &rerun::Clear::flat());
        } else if V::DIM == 2 {
            let points: Vec<[f32; 2]> = events.collisions.iter().map(|e| f32x2(e.point)).collect();
            let impulses: Vec<[f32; 2]> = events
                .collisions
                .iter()
                .map(|e| f32x2(e.normal * e.impulse))
                .collect();
            let _ = rec.log(
                "world/contacts",
                &rerun::Arrows2D::from_vectors(impulses)
                    .with_origins(points)
                    .with_colors([[230, 60, 60]]),
            );
        } else {
            let points: Vec<[f32; 3]> = events.collisions.iter().map(|e| f32x3(e.point)).collect();
            let impulses: Vec<[f32; 3]> = events
                .collisions
                .iter()
                .map(|e| f32x3(e.normal * e.impulse))
                .collect();
            let _ = rec.log(
                "world/contacts",
                &rerun::Arrows3D::from_vectors(impulses)
                    .with_origins(points)
                    .with_colors([[230, 60, 60]]),
            );
        }
        let describe = |id: CritterId| format!("critter {id}");
        for id in &events.spawns {
            let _ = rec.log(
                "log",
                &rerun::TextLog::new(format!("spawned {}", describe(*id))).with_level("INFO"),
            );
        }
        for id in &events.deaths {
            let _ = rec.log(
                "log",
                &rerun::TextLog::new(format!("{} died", describe(*id))).with_level("WARN"),
            );
        }
        for line in &events.log {
            let _ = rec.log(
                "log",
                &rerun::TextLog::new(line.clone()).with_level("DEBUG"),
            );
        }

        // Totals.
        let p = w.momentum().to_array3();
        let _ = rec.log(
            "stats/kinetic_energy",
            &rerun::Scalars::single(w.kinetic_energy()),
        );
        for (axis, name) in ["x", "y", "z"].iter().enumerate().take(V::DIM) {
            let _ = rec.log(
                format!("stats/momentum/{name}"),
                &rerun::Scalars::single(p[axis]),
            );
        }
        let _ = rec.log(
            "stats/collisions",
            &rerun::Scalars::single(w.stats().collisions as f64),
        );
        let _ = rec.log(
            "stats/step_ms",
            &rerun::Scalars::single(step_time.as_secs_f64() * 1e3),
        );
    }

    /// Flushes what is buffered. For a live viewer, waits at most a few seconds and returns a
    /// warning if it never answered (a connect to an absent viewer only fails here).
    pub fn finish(self) -> Option<String> {
        let wait = match self.target {
            RerunTarget::Save(_) => Duration::from_secs(600),
            _ => Duration::from_secs(5),
        };
        match self.rec.flush_with_timeout(wait) {
            Ok(()) => None,
            Err(e) => Some(match &self.target {
                RerunTarget::Save(p) => format!("the Rerun file {} may be incomplete: {e}", p.display()),
                _ => format!(
                    "no Rerun viewer took the data ({e}); start one with `rerun` (pip install rerun-sdk==0.36.3) and try again"
                ),
            }),
        }
    }
}
