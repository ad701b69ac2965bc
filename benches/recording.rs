//! What recording costs on the 10,000-critter gas (`critterbox run gas -n 10000`), in one run:
//! a step without recording, with the default recording, and with every step's full state;
//! the parts of that cost (hash and totals every step, a keyframe's capture and encoding); the
//! file's bytes per critter per step; and replaying a recording to CSV.
//!
//! `cargo bench --bench recording`; docs/recording-format.md has the figures and how the
//! default keyframe interval follows from them. Times include the writer thread: each sample
//! closes its file, so work still queued is waited for.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use critterbox::recording::export::export_csv;
use critterbox::recording::keyframes::default_record_every;
use critterbox::recording::{capture, foxglove, EndMeta, Recorder, Recording, RunMeta};
use critterbox::scenes::{builtin, Scene, SceneParams};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const N: usize = 10_000;

fn params() -> SceneParams {
    SceneParams {
        n: Some(N),
        ..SceneParams::default()
    }
}

fn gas() -> Scene {
    let mut scene = builtin("gas", &params()).expect("the gas builds");
    // Past the grid start, into the steady state.
    for _ in 0..30 {
        scene.step().expect("steps");
    }
    scene
}

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("critterbox-bench-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("bench dir");
    d
}

/// Steps `scene` `steps` times, recording into `path` with keyframes every `every` steps
/// (no recording for `None`); the time includes closing the file.
fn run(scene: &mut Scene, steps: u64, every: Option<u64>, path: &Path) -> Duration {
    let start = Instant::now();
    let mut rec = every.map(|k| {
        let meta = RunMeta::builtin(scene, &params(), steps, k);
        Recorder::create(path, &meta, &[], &scene.world).expect("recorder")
    });
    for _ in 0..steps {
        scene.step().expect("steps");
        if let Some(r) = &mut rec {
            r.record(&scene.world).expect("records");
        }
    }
    if let Some(r) = rec {
        let end = EndMeta {
            steps: scene.world.step_count(),
            outcome: "completed".into(),
            reason: String::new(),
            hash: 0,
            ..EndMeta::default()
        };
        r.finish(&scene.world, end).expect("finishes");
    }
    start.elapsed()
}

fn step_with_recording(c: &mut Criterion) {
    let d = dir();
    let default_k = default_record_every(N + 4);
    // One iteration is a whole default run, `critterbox run gas -n 10000` (600 steps, first and
    // last state included), so the per-step figure is the run's time / 600; every step's full
    // state is measured on runs of 60 steps (it is slow).
    let mut group = c.benchmark_group("recording_gas2d_run");
    group.sample_size(10);
    group.warm_up_time(Duration::from_secs(1));
    group.measurement_time(Duration::from_secs(10));
    for (name, every, steps) in [
        ("none", None, 600),
        ("default", Some(default_k), 600),
        ("every1", Some(1), 60),
    ] {
        let path = d.join(format!("{name}.mcap"));
        group.bench_with_input(
            BenchmarkId::new(format!("{name}_{steps}_steps"), N),
            &N,
            |b, _| {
                b.iter_custom(|iters| {
                    let mut total = Duration::ZERO;
                    for _ in 0..iters {
                        let mut scene = builtin("gas", &params()).expect("the gas builds");
                        total += run(&mut scene, steps, every, &path);
                    }
                    total
                });
            },
        );
    }
    group.finish();

    // Bytes per critter per step, with every step's full state and with the default.
    for (name, every) in [("every1", 1), ("default", default_k)] {
        let mut scene = gas();
        let path = d.join(format!("size-{name}.mcap"));
        let steps = if every == 1 { 120 } else { 600 };
        run(&mut scene, steps, Some(every), &path);
        let bytes = std::fs::metadata(&path).map_or(0, |m| m.len());
        eprintln!(
            "bytes per critter per step, {name} (K = {every}): {:.2} ({bytes} bytes, {steps} steps of {} critters)",
            bytes as f64 / (steps as f64 * scene.world.len() as f64),
            scene.world.len()
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

fn recording_parts(c: &mut Criterion) {
    let scene = gas();
    let mut group = c.benchmark_group("recording_parts");
    group.sample_size(20);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(3));
    group.bench_with_input(BenchmarkId::new("hash", N), &N, |b, _| {
        b.iter(|| black_box(scene.world.state_hash()));
    });
    group.bench_with_input(BenchmarkId::new("hash_totals_events", N), &N, |b, _| {
        b.iter(|| black_box(capture::capture(&scene.world, false, 2)));
    });
    group.bench_with_input(BenchmarkId::new("capture_state", N), &N, |b, _| {
        b.iter(|| black_box(capture::any_state(&scene.world)));
    });
    let state = capture::any_state(&scene.world);
    group.bench_with_input(BenchmarkId::new("encode_state_json", N), &N, |b, _| {
        b.iter(|| black_box(serde_json::to_vec(&state).expect("encodes")));
    });
    let colors = [[0.5f32; 4]; 2];
    group.bench_with_input(BenchmarkId::new("encode_foxglove", N), &N, |b, _| {
        b.iter(|| black_box(foxglove::scene_update(&state, 0, &colors)));
    });
    group.finish();
}

fn replay_to_csv(c: &mut Criterion) {
    let d = dir();
    let steps = 60;
    let every1 = d.join("every1.mcap");
    let default = d.join("default.mcap");
    run(
        &mut builtin("gas", &params()).expect("gas"),
        steps,
        Some(1),
        &every1,
    );
    let k = default_record_every(N + 4);
    run(
        &mut builtin("gas", &params()).expect("gas"),
        steps,
        Some(k),
        &default,
    );
    let (r1, rk) = (
        Recording::open(&every1).expect("opens"),
        Recording::open(&default).expect("opens"),
    );
    let mut group = c.benchmark_group("replay_csv_61_steps");
    group.sample_size(10);
    group.warm_up_time(Duration::from_secs(1));
    group.measurement_time(Duration::from_secs(8));
    let out = d.join("csv");
    group.bench_with_input(BenchmarkId::new("recorded_states", N), &N, |b, _| {
        b.iter(|| export_csv(&r1, &out, false).expect("exports"));
    });
    group.bench_with_input(BenchmarkId::new("resimulated_states", N), &N, |b, _| {
        b.iter(|| export_csv(&rk, &out, true).expect("exports"));
    });
    group.finish();
    let _ = std::fs::remove_dir_all(&d);
}

criterion_group!(benches, step_with_recording, recording_parts, replay_to_csv);
criterion_main!(benches);
