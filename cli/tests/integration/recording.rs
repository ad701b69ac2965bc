//! Recordings: written by every run, read back bit for bit, verified by re-simulating from the
//! file alone, recovered when cut off, and never a panic on a bad file.

use crate::common;
use common::{critterbox, critterbox_in, text, ROOT};

use critterbox::recording::compare::first_difference;
use critterbox::recording::reader::{for_each_state, state_at, Flow};
use critterbox::recording::recover::rewrite;
use critterbox::recording::replay::{state_at_step, StateSource};
use critterbox::recording::schema::{self, StateMsg};
use critterbox::recording::verify::verify;
use critterbox::recording::{capture, Recording};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A fresh folder for one test.
fn tmp(name: &str) -> PathBuf {
    common::tmp_in("recording-tests", name)
}

/// Runs `critterbox run ARGS --record PATH` and checks it succeeded.
fn record(path: &Path, args: &[&str]) {
    let mut all = vec!["run"];
    all.extend_from_slice(args);
    let p = path.to_str().expect("utf-8 path");
    all.extend_from_slice(&["--record", p]);
    let o = critterbox(&all);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains(&format!("recording    {p}")),
        "{}",
        text(&o)
    );
}

#[test]
fn round_trip_states_read_back_bit_for_bit() {
    use critterbox::recording::{Recorder, RunMeta, SceneSource};
    use critterbox::scenes::{builtin, SceneParams};
    let dir = tmp("round_trip");
    let path = dir.join("gas3d.mcap");
    let params = SceneParams {
        n: Some(60),
        seed: 5,
        dt: None,
    };
    let mut scene = builtin("gas3d", &params).expect("scene");
    let meta = RunMeta {
        version: env!("CARGO_PKG_VERSION").into(),
        scene: "gas3d".into(),
        source: SceneSource::Builtin,
        seed: 5,
        seed_override: Some(5),
        dt: scene.world.dt(),
        dt_override: None,
        steps: 40,
        method: "discrete".into(),
        dim: 3,
        border: "bounce".into(),
        n: Some(60),
        sets: vec![],
        limits: Default::default(),
        command_line: vec![],
        record_every: 1,
        critters: scene.world.len(),
        created: String::new(),
    };
    let mut rec = Recorder::create(&path, &meta, &[], &scene.world).expect("create");
    let mut expected = vec![capture::any_state(&scene.world)];
    let mut hashes = vec![scene.world.state_hash()];
    for _ in 0..40 {
        scene.step().expect("step");
        rec.record(&scene.world).expect("record");
        expected.push(capture::any_state(&scene.world));
        hashes.push(scene.world.state_hash());
    }
    let end = critterbox::recording::EndMeta {
        steps: 40,
        outcome: "completed".into(),
        reason: String::new(),
        hash: scene.world.state_hash(),
        ..Default::default()
    };
    let written = rec.finish(&scene.world, end).expect("finish");
    assert_eq!((written.steps, written.states), (40, 41));

    let mut read = Vec::new();
    for_each_state(&path, |s| {
        read.push(s);
        Ok(Flow::Continue)
    })
    .expect("read");
    assert_eq!(read.len(), expected.len());
    for (a, b) in expected.iter().zip(&read) {
        assert_eq!(b.dim(), 3);
        assert!(b.z.is_some());
        assert_eq!(first_difference(a, b, "written", "read"), None);
        assert_eq!(a, b);
    }
    let r = Recording::open(&path).expect("open");
    assert_eq!(r.truncated, None);
    for (step, h) in hashes.iter().enumerate() {
        assert_eq!(r.hashes.get(&(step as u64)), Some(h), "hash of step {step}");
    }
    assert_eq!(
        r.end.as_ref().map(|e| e.outcome.as_str()),
        Some("completed")
    );
    assert!(verify(&r, |_| {}).expect("verify").passed());
}

/// Flips the lowest bit of one float (critter `index`'s x) in the state message of `step`.
fn flip_one_bit(src: &Path, dst: &Path, step: u64, index: usize) {
    let mut flipped = false;
    rewrite(src, dst, |topic, data| {
        if topic != schema::STATE {
            return None;
        }
        let mut s: StateMsg = serde_json::from_slice(data).expect("state json");
        if s.step != step {
            return None;
        }
        s.x.0[index] = f64::from_bits(s.x.0[index].to_bits() ^ 1);
        flipped = true;
        Some(serde_json::to_vec(&s).expect("encode"))
    })
    .expect("rewrite");
    assert!(flipped, "test setup: step {step} has a state");
}

#[test]
fn verify_passes_on_a_clean_file_and_names_a_one_bit_change() {
    let dir = tmp("verify");
    let clean = dir.join("billiards.mcap");
    record(&clean, &["billiards", "--steps", "80"]);
    let o = critterbox(&["replay", clean.to_str().unwrap(), "--verify"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("verify       ok: 80 steps"),
        "{}",
        text(&o)
    );

    let bad = dir.join("billiards-flipped.mcap");
    flip_one_bit(&clean, &bad, 37, 9);
    let o = critterbox(&["replay", bad.to_str().unwrap(), "--verify"]);
    assert!(!o.status.success(), "a changed bit must fail: {}", text(&o));
    let out = text(&o);
    assert!(out.contains("MISMATCH at step 37"), "{out}");
    assert!(out.contains("critter #9 (ball): x"), "{out}");
}

#[test]
fn hashes_made_by_another_state_hash_are_refused_with_what_to_do() {
    let dir = tmp("hash-version");
    let path = dir.join("billiards.mcap");
    record(
        &path,
        &["billiards", "--steps", "30", "--record-every", "10"],
    );
    let mut rec = Recording::open(&path).expect("opens");
    assert_eq!(
        rec.meta_map.get("state_hash").map(String::as_str),
        Some(schema::STATE_HASH)
    );
    assert!(verify(&rec, |_| {}).is_ok());
    // A file from before the key existed (or from another state hash) is refused, not reported
    // as a replay that diverged at step 0.
    for old in [None, Some("1"), Some("2")] {
        match old {
            None => rec.meta_map.remove("state_hash"),
            Some(v) => rec.meta_map.insert("state_hash".into(), v.into()),
        };
        let version = format!("state hash version {}", old.unwrap_or("1"));
        let err = format!("{:#}", verify(&rec, |_| {}).expect_err("must refuse"));
        assert!(err.contains(&version), "{err}");
        assert!(err.contains("record the run again"), "{err}");
        let err = format!("{:#}", state_at_step(&rec, 15).expect_err("must refuse"));
        assert!(err.contains(&version), "{err}");
    }
}

#[test]
fn record_every_k_still_shows_an_unrecorded_step_exactly() {
    let dir = tmp("every_k");
    let (all, sparse) = (dir.join("every1.mcap"), dir.join("every10.mcap"));
    record(
        &all,
        &["gas", "-n", "150", "--steps", "45", "--record-every", "1"],
    );
    record(
        &sparse,
        &["gas", "-n", "150", "--steps", "45", "--record-every", "10"],
    );
    let r = Recording::open(&sparse).expect("open");
    assert_eq!(
        r.keyframes,
        vec![0, 10, 20, 30, 40, 45],
        "the last step is kept too"
    );
    assert_eq!(r.hashes.len(), 46, "every step has its hash");
    let (shown, source) = state_at_step(&r, 27).expect("step 27");
    assert_eq!(source, StateSource::Restored { keyframe: 20 });
    let truth = state_at(&all, 27)
        .expect("read")
        .expect("every step recorded");
    assert_eq!(
        first_difference(&truth, &shown, "recorded", "replayed"),
        None
    );

    // The command line prints the same exact state.
    let o = critterbox(&["replay", sparse.to_str().unwrap(), "--step", "27", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let printed: StateMsg = serde_json::from_slice(&o.stdout).expect("json state");
    assert_eq!(
        first_difference(&truth, &printed, "recorded", "printed"),
        None
    );
    // Past the end is a clear error.
    let o = critterbox(&["replay", sparse.to_str().unwrap(), "--step", "46"]);
    assert!(!o.status.success());
    assert!(text(&o).contains("ends at step 45"), "{}", text(&o));
}

#[test]
fn a_script_scene_verifies_from_its_attachments_alone() {
    let dir = tmp("script_alone");
    let original = dir.join("bullets.mcap");
    record(
        &original,
        &[
            "scripts/scenes/bullets_vs_player.rhai",
            "--steps",
            "150",
            "--set",
            "FIRE_EVERY=20",
        ],
    );
    // Elsewhere, with no scripts folder in sight.
    let away = tmp("script_alone_elsewhere");
    std::fs::copy(&original, away.join("copy.mcap")).expect("copy");
    let o = critterbox_in(&away, &["replay", "copy.mcap", "--verify"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("verify       ok"), "{}", text(&o));
    let r = Recording::open(&away.join("copy.mcap")).expect("open");
    let names: Vec<&str> = r.scripts.iter().map(|(n, _)| n.as_str()).collect();
    assert!(
        names.iter().any(|n| n.ends_with("bullets_vs_player.rhai")),
        "{names:?}"
    );
    assert!(
        names.iter().any(|n| n.ends_with("armed_player.rhai")),
        "{names:?}"
    );
    assert!(
        names.iter().any(|n| n.ends_with("silver_bullet.rhai")),
        "{names:?}"
    );
    assert_eq!(r.meta().sets, vec!["FIRE_EVERY=20".to_string()]);
    assert!(
        r.scripts[0].1.contains("const FIRE_EVERY = 20"),
        "the --set value is in the text"
    );
    assert!(!r.lifecycle.is_empty(), "bullets were spawned");
}

#[test]
fn a_cut_off_file_reads_up_to_its_last_complete_chunk_and_recovers() {
    let dir = tmp("truncated");
    let full = dir.join("full.mcap");
    record(
        &full,
        &["gas", "-n", "1500", "--steps", "60", "--record-every", "1"],
    );
    let bytes = std::fs::read(&full).expect("read");
    let cut = dir.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 6 / 10]).expect("write");

    let r = Recording::open(&cut).expect("a cut-off file still opens");
    assert!(r.truncated.is_some());
    let kept = r.last_step();
    assert!(kept > 0 && kept < 60, "kept {kept} steps");
    let o = critterbox(&["replay", cut.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(3), "cut off: {}", text(&o));
    assert!(text(&o).contains("cut off"), "{}", text(&o));

    let fixed = dir.join("fixed.mcap");
    let o = critterbox(&[
        "recover",
        cut.to_str().unwrap(),
        "-o",
        fixed.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(3),
        "the source lacked data: {}",
        text(&o)
    );
    assert!(text(&o).contains("recovered"), "{}", text(&o));
    let r2 = Recording::open(&fixed).expect("open recovered");
    assert_eq!(r2.truncated, None, "the recovered file is complete");
    assert_eq!(r2.last_step(), kept);
    assert_eq!(r2.hashes, r.hashes);
    let o = critterbox(&["replay", fixed.to_str().unwrap(), "--verify"]);
    assert!(o.status.success(), "{}", text(&o));
}

#[cfg(unix)]
#[test]
fn a_killed_run_leaves_a_recoverable_file_and_ctrl_c_finishes_it() {
    use std::time::{Duration, Instant};
    let dir = tmp("killed");
    let run = |file: &str| {
        Command::new(env!("CARGO_BIN_EXE_critterbox"))
            .args(["run", "gas", "-n", "3000", "--steps", "10000000"])
            .args(["--record", dir.join(file).to_str().unwrap()])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("spawn")
    };
    let wait_for_steps = |file: &str| {
        // Until the file holds a few closed chunks.
        let start = Instant::now();
        while std::fs::metadata(dir.join(file)).map_or(0, |m| m.len()) < 200_000 {
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "the run never wrote"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
        std::thread::sleep(Duration::from_millis(600));
    };
    let signal = |pid: u32, sig: &str| {
        let ok = Command::new("kill")
            .args([sig, &pid.to_string()])
            .status()
            .expect("kill runs");
        assert!(ok.success());
    };

    let mut killed = run("killed.mcap");
    wait_for_steps("killed.mcap");
    signal(killed.id(), "-KILL");
    killed.wait().expect("wait");
    let r = Recording::open(&dir.join("killed.mcap")).expect("readable after SIGKILL");
    assert!(r.end.is_none() && r.last_step() > 0);
    let o = critterbox(&["recover", dir.join("killed.mcap").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(3), "cut off: {}", text(&o));
    let r2 = Recording::open(&dir.join("killed.recovered.mcap")).expect("recovered");
    assert_eq!(
        (r2.truncated.clone(), r2.last_step()),
        (None, r.last_step())
    );

    let stopped = run("ctrl-c.mcap");
    wait_for_steps("ctrl-c.mcap");
    signal(stopped.id(), "-INT");
    let o = stopped.wait_with_output().expect("wait");
    assert!(!o.status.success(), "Ctrl-C exits non-zero");
    assert!(text(&o).contains("interrupted by Ctrl-C"), "{}", text(&o));
    let r = Recording::open(&dir.join("ctrl-c.mcap")).expect("open");
    assert_eq!(r.truncated, None, "Ctrl-C finishes the file");
    let end = r.end.clone().expect("end record");
    assert_eq!(
        (end.outcome.as_str(), end.steps),
        ("interrupted", r.last_step())
    );
    assert_eq!(
        r.keyframes.last(),
        Some(&r.last_step()),
        "the final state is kept"
    );
}

#[test]
fn a_script_error_is_written_into_the_recording_before_it_is_reported() {
    let dir = tmp("script_error");
    let scene = dir.join("fails.rhai");
    std::fs::write(
        &scene,
        "let w = world(#{ dim: 2, size: vec(10, 10), seed: 3 });\n\
         spawn(\"ball\", #{ pos: vec(5, 5), vel: vec(1, 0) });\n\
         fn on_step(world) {\n    if world.step_count == 7 { throw \"boom at seven\"; }\n}\n",
    )
    .expect("write scene");
    let file = dir.join("fails.mcap");
    let o = critterbox(&[
        "run",
        scene.to_str().unwrap(),
        "--steps",
        "20",
        "--record",
        file.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let out = text(&o);
    assert!(out.contains("boom at seven"), "{out}");
    assert!(out.contains("ended: error"), "the path is printed: {out}");
    let r = Recording::open(&file).expect("the file is complete");
    assert_eq!(r.truncated, None);
    let e = r.error.as_ref().expect("an error message");
    assert!(e.message.contains("boom at seven"), "{}", e.message);
    assert_eq!(r.end.as_ref().map(|e| e.outcome.as_str()), Some("error"));
    let o = critterbox(&["replay", file.to_str().unwrap(), "--verify"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("reproduced"), "{}", text(&o));
}

#[test]
fn a_run_stopped_by_the_step_budget_records_it_and_its_replay_stops_at_the_same_step() {
    let dir = tmp("step_budget");
    let scene = dir.join("busy.rhai");
    // on_step's work grows with the step count, so the budget stops it at a later step.
    std::fs::write(
        &scene,
        "let w = world(#{ dim: 2, size: vec(10, 10), seed: 3 });\n\
         spawn(\"ball\", #{ pos: vec(5, 5), vel: vec(1, 0) });\n\
         fn on_step(world) {\n    let i = 0;\n    while i < world.step_count * 2000 { i += 1; }\n}\n",
    )
    .expect("write scene");
    let file = dir.join("busy.mcap");
    let run = critterbox(&[
        "run",
        scene.to_str().unwrap(),
        "--steps",
        "50",
        "--max-step-ops",
        "100000",
        "--record",
        file.to_str().unwrap(),
    ]);
    assert!(!run.status.success(), "{}", text(&run));
    assert!(text(&run).contains("--max-step-ops"), "{}", text(&run));
    let r = Recording::open(&file).expect("the file is complete");
    assert_eq!(r.meta().limits.max_step_operations, 100_000);
    let e = r.error.as_ref().expect("an error message");
    assert!(e.message.contains("100000 operations"), "{}", e.message);
    let stopped = r.end.as_ref().map(|e| e.steps);
    assert!(stopped.is_some_and(|s| s > 1), "a later step: {stopped:?}");
    let o = critterbox(&["replay", file.to_str().unwrap(), "--verify"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("reproduced"), "{}", text(&o));
}

#[test]
fn bad_files_are_clear_errors_never_panics() {
    let dir = tmp("bad_files");
    let good = dir.join("good.mcap");
    record(&good, &["cradle", "--steps", "30"]);
    let bytes = std::fs::read(&good).expect("read");

    // Command line: missing, empty, random bytes, text, a header cut short.
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("empty.mcap", vec![], "not an MCAP file"),
        (
            "random.mcap",
            (0..4096u32)
                .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
                .collect(),
            "not an MCAP file",
        ),
        (
            "text.mcap",
            b"hello, not a recording\n".to_vec(),
            "not an MCAP file",
        ),
        (
            "header.mcap",
            bytes[..20].to_vec(),
            "not a critterbox recording",
        ),
    ];
    for (name, data, expect) in &cases {
        let p = dir.join(name);
        std::fs::write(&p, data).expect("write");
        for cmd in ["replay", "inspect", "recover"] {
            let o = critterbox(&[cmd, p.to_str().unwrap()]);
            assert_eq!(o.status.code(), Some(1), "{cmd} {name}: {}", text(&o));
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(err.contains(expect), "{cmd} {name}: {err}");
            assert!(!err.contains("panicked"), "{cmd} {name}: {err}");
        }
    }
    let o = critterbox(&["replay", dir.join("missing.mcap").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("cannot read"), "{}", text(&o));

    // An MCAP file that critterbox did not write.
    let other = dir.join("other.mcap");
    {
        let mut w = mcap::Writer::new(std::io::BufWriter::new(
            std::fs::File::create(&other).unwrap(),
        ))
        .unwrap();
        let ch = w
            .add_channel(0, "/chatter", "json", &Default::default())
            .unwrap();
        let header = mcap::records::MessageHeader {
            channel_id: ch,
            sequence: 1,
            log_time: 1,
            publish_time: 1,
        };
        w.write_to_known_channel(&header, b"{}").unwrap();
        w.finish().unwrap();
    }
    let o = critterbox(&["inspect", other.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o).contains("not a critterbox recording"),
        "{}",
        text(&o)
    );

    // Fuzz the library: every cut and a few hundred byte changes of a good file, read with
    // every reader. Errors are fine; panics are not.
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let p = dir.join("fuzz.mcap");
    let try_all = |data: &[u8]| {
        std::fs::write(&p, data).expect("write");
        let result = std::panic::catch_unwind(|| {
            if let Ok(r) = Recording::open(&p) {
                let _ = for_each_state(&p, |_| Ok(Flow::Continue));
                let _ = verify(&r, |_| {});
                let _ = rewrite(&p, &dir.join("fuzz-out.mcap"), |_, _| None);
            }
        });
        assert!(result.is_ok(), "a panic on a damaged file");
    };
    for cut in (0..bytes.len()).step_by((bytes.len() / 150).max(1)) {
        try_all(&bytes[..cut]);
    }
    for _ in 0..300 {
        let mut data = bytes.clone();
        for _ in 0..1 + next() % 4 {
            let at = (next() % data.len() as u64) as usize;
            data[at] ^= 1 << (next() % 8);
        }
        try_all(&data);
    }
}

#[test]
fn commands_inspect_diff_export_and_their_exit_codes() {
    let dir = tmp("commands");
    let (a, b, c) = (dir.join("a.mcap"), dir.join("b.mcap"), dir.join("c.mcap"));
    record(&a, &["gas", "-n", "120", "--steps", "40", "--seed", "3"]);
    record(
        &b,
        &[
            "gas",
            "-n",
            "120",
            "--steps",
            "40",
            "--seed",
            "3",
            "--record-every",
            "7",
        ],
    );
    record(&c, &["gas", "-n", "120", "--steps", "40", "--seed", "4"]);
    let s = |p: &Path| p.to_str().unwrap().to_string();

    let o = critterbox(&["inspect", &s(&a), "--rows", "5"]);
    assert!(o.status.success(), "{}", text(&o));
    let out = text(&o);
    for line in [
        "scene        gas",
        "critters     at start: ball 120, wall 4 (step 0)",
        "collisions",
        "over time",
        "kinetic energy",
    ] {
        assert!(out.contains(line), "{line} missing:\n{out}");
    }

    for chart in ["chart.svg", "chart.png"] {
        let o = critterbox(&["inspect", &s(&a), "--plot", &s(&dir.join(chart))]);
        assert!(o.status.success(), "{}", text(&o));
        assert!(
            std::fs::metadata(dir.join(chart)).map_or(0, |m| m.len()) > 1000,
            "{chart}"
        );
    }
    let svg = std::fs::read_to_string(dir.join("chart.svg")).expect("svg");
    assert!(svg.contains("<svg") && svg.contains("kinetic energy"));

    let o = critterbox(&["diff", &s(&a), &s(&b)]);
    assert!(
        o.status.success(),
        "same run, other keyframes: {}",
        text(&o)
    );
    assert!(text(&o).contains("every state hash equal"), "{}", text(&o));
    let o = critterbox(&["diff", &s(&a), &s(&c)]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let out = text(&o);
    assert!(out.contains("metadata     seed: 3 | 4"), "{out}");
    assert!(out.contains("first differs at step 0"), "{out}");
    assert!(
        out.contains("first critter (step 0): critter #4 (ball): vx"),
        "{out}"
    );

    let csv = dir.join("csv");
    let o = critterbox(&["export", &s(&b), "--csv", &s(&csv)]);
    assert!(o.status.success(), "{}", text(&o));
    let states = std::fs::read_to_string(csv.join("states.csv")).expect("states.csv");
    assert!(
        states.starts_with("step,time,id,kind,x,y,vx,vy,radius,mass"),
        "{states:.80}"
    );
    // Keyframes 0, 7, ..., 35 and the last step 40: 7 states of 124 critters.
    assert_eq!(states.lines().count(), 1 + 7 * 124);
    let steps = std::fs::read_to_string(csv.join("steps.csv")).expect("steps.csv");
    assert_eq!(steps.lines().count(), 1 + 41);
    for f in ["collisions.csv", "lifecycle.csv", "log.csv"] {
        assert!(csv.join(f).is_file(), "{f}");
    }
    let o = critterbox(&["export", &s(&b), "--csv", &s(&csv), "--every-step"]);
    assert!(o.status.success(), "{}", text(&o));
    let states = std::fs::read_to_string(csv.join("states.csv")).expect("states.csv");
    assert_eq!(states.lines().count(), 1 + 41 * 124);

    let o = critterbox(&["run", "gas", "--record-every", "0"]);
    assert_eq!(o.status.code(), Some(2), "usage error: {}", text(&o));
    let o = critterbox(&["run", "cradle", "--record", &s(&a), "--no-record"]);
    assert_eq!(o.status.code(), Some(2), "conflicting flags: {}", text(&o));
}

/// Every recording shipped in `recordings/` verifies from the file alone, as the README's
/// readers will try: the goldens `critterbox test --bless` writes record the script limits the
/// run had (they once recorded zeros, and a replay then refused the scene's first spawn).
#[test]
fn the_shipped_recordings_verify_from_their_files_alone() {
    let dir = Path::new(ROOT).join("recordings");
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).expect("recordings/") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "mcap") {
            let o = critterbox(&["replay", path.to_str().unwrap(), "--verify"]);
            assert!(o.status.success(), "{}: {}", path.display(), text(&o));
            assert!(text(&o).contains("verify       ok"), "{}", text(&o));
            checked += 1;
        }
    }
    assert!(checked >= 3, "only {checked} recordings in recordings/");
}

#[test]
fn run_records_by_default_under_the_recordings_folder() {
    let dir = tmp("default_path");
    let o = critterbox_in(&dir, &["run", "cradle", "--steps", "10"]);
    assert!(o.status.success(), "{}", text(&o));
    let files: Vec<_> = std::fs::read_dir(dir.join("recordings"))
        .expect("recordings/ made")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    assert!(
        files[0].starts_with("cradle-") && files[0].ends_with(".mcap"),
        "{files:?}"
    );
    assert!(
        text(&o).contains(&files[0]),
        "the path is printed: {}",
        text(&o)
    );
    let o = critterbox_in(&dir, &["run", "cradle", "--steps", "10", "--no-record"]);
    assert!(o.status.success());
    assert!(!text(&o).contains("recording "), "{}", text(&o));
    assert_eq!(
        std::fs::read_dir(dir.join("recordings")).unwrap().count(),
        1
    );
}

/// A run with deaths: the inspect table's deaths column adds up to the deaths the file records
/// (the first row, step 0, has none and must not fail).
#[test]
fn inspect_counts_the_deaths_of_a_run_with_deaths() {
    let dir = tmp("inspect_deaths");
    let file = dir.join("bullets.mcap");
    let scene = Path::new(ROOT).join("scripts/scenes/bullets_vs_player.rhai");
    record(&file, &[scene.to_str().unwrap(), "--steps", "400"]);
    let rec = Recording::open(&file).expect("opens");
    let recorded: usize = rec.lifecycle.iter().map(|l| l.die.len()).sum();
    assert!(recorded > 0, "test setup: something died");
    let o = critterbox(&["inspect", file.to_str().unwrap(), "--rows", "100000"]);
    assert!(o.status.success(), "{}", text(&o));
    let out = text(&o);
    let table: Vec<&str> = out
        .lines()
        .skip_while(|l| !l.starts_with("over time"))
        .skip(2)
        .take_while(|l| l.starts_with("  "))
        .collect();
    assert_eq!(table.len(), rec.totals.len(), "one row per step:\n{out}");
    let shown: usize = table
        .iter()
        .map(|l| {
            l.split_whitespace()
                .nth(5)
                .and_then(|d| d.parse::<usize>().ok())
                .expect("a deaths column")
        })
        .sum();
    assert_eq!(shown, recorded, "{out}");
}

/// A run with spawns and deaths (slots freed and reused), recorded every 40 steps: any step,
/// started from the recorded full state before it, equals the same run recorded at every step;
/// and a file whose states lack the generator (as older versions wrote them) falls back to
/// re-simulating from step 0, with the reason, and still gives the exact state.
#[test]
fn a_step_is_replayed_from_the_keyframe_before_it_exactly() {
    let dir = tmp("restore");
    let (all, sparse) = (dir.join("every1.mcap"), dir.join("every40.mcap"));
    let scene = Path::new(ROOT).join("scripts/scenes/bullets_vs_player.rhai");
    let scene = scene.to_str().unwrap();
    record(&all, &[scene, "--record-every", "1"]);
    record(&sparse, &[scene, "--record-every", "40"]);
    let r = Recording::open(&sparse).expect("open");
    let died: usize = r.lifecycle.iter().map(|l| l.die.len()).sum();
    let spawned: usize = r.lifecycle.iter().map(|l| l.spawn.len()).sum();
    assert!(died > 0 && spawned > 0, "test setup: spawns and deaths");
    for step in [1, 39, 41, 99, 130, r.last_step() - 2, r.last_step() - 1] {
        let (shown, source) = state_at_step(&r, step).expect("a step");
        let key = r.keyframe_at_or_before(step).expect("a keyframe");
        let expected = if key == step {
            StateSource::Recorded
        } else if key > 0 {
            StateSource::Restored { keyframe: key }
        } else {
            StateSource::Resimulated {
                keyframe: Some(0),
                why_not_restored: None,
            }
        };
        assert_eq!(source, expected, "step {step}");
        let truth = state_at(&all, step)
            .expect("read")
            .expect("every step recorded");
        assert_eq!(
            first_difference(&truth, &shown, "recorded", "replayed"),
            None,
            "step {step}"
        );
    }

    // The same file without the generator in its states.
    let old = dir.join("old.mcap");
    rewrite(&sparse, &old, |topic, data| {
        if topic != schema::STATE {
            return None;
        }
        let mut s: StateMsg = serde_json::from_slice(data).expect("state json");
        s.rng = None;
        Some(serde_json::to_vec(&s).expect("encode"))
    })
    .expect("rewrite");
    let r = Recording::open(&old).expect("open");
    let (shown, source) = state_at_step(&r, 130).expect("step 130");
    match source {
        StateSource::Resimulated {
            keyframe: Some(120),
            why_not_restored: Some(why),
        } => assert!(why.contains("no generator state"), "{why}"),
        other => panic!("expected a re-simulation from step 0, got {other:?}"),
    }
    let truth = state_at(&all, 130).expect("read").expect("recorded");
    assert_eq!(
        first_difference(&truth, &shown, "recorded", "replayed"),
        None
    );
}

/// A restored world that is not the recorded one is never shown: a state whose generator was
/// changed restores, fails the recorded hash of its step, and the replay starts from step 0.
#[test]
fn a_restore_that_does_not_match_the_recorded_hash_is_not_used() {
    let dir = tmp("restore_bad");
    let (sparse, bad) = (dir.join("every10.mcap"), dir.join("bad.mcap"));
    record(
        &sparse,
        &["gas", "-n", "60", "--steps", "30", "--record-every", "10"],
    );
    rewrite(&sparse, &bad, |topic, data| {
        if topic != schema::STATE {
            return None;
        }
        let mut s: StateMsg = serde_json::from_slice(data).expect("state json");
        if let Some(r) = &mut s.rng {
            r[0] ^= 1;
        }
        Some(serde_json::to_vec(&s).expect("encode"))
    })
    .expect("rewrite");
    let r = Recording::open(&bad).expect("open");
    let (_, source) = state_at_step(&r, 25).expect("step 25");
    match source {
        StateSource::Resimulated {
            why_not_restored: Some(why),
            ..
        } => assert!(why.contains("not the recorded one"), "{why}"),
        other => panic!("expected a re-simulation from step 0, got {other:?}"),
    }
}

/// A kind the scene loads while running (from `on_step`) is attached when it is loaded, not at
/// the end: a run killed later still re-simulates from its recovered file alone, in a folder
/// where no kind file could be found on disk.
#[test]
fn a_kind_loaded_mid_run_survives_a_killed_run() {
    use std::time::{Duration, Instant};
    let dir = tmp("late_kind_killed");
    let file = dir.join("late.mcap");
    let root = Path::new(ROOT);
    let mut child = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args(["run", "tests/scenes/late_kind.rhai", "--steps", "100000000"])
        .args(["--record-every", "500", "--record", file.to_str().unwrap()])
        .current_dir(root)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("spawn");
    // Until the readable part of the file is well past the step the kind was loaded in.
    let start = Instant::now();
    loop {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the run never got far"
        );
        std::thread::sleep(Duration::from_millis(200));
        if Recording::open(&file).is_ok_and(|r| r.last_step() > 2_000) {
            break;
        }
    }
    let ok = Command::new("kill")
        .args(["-KILL", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(ok.success());
    child.wait().expect("wait");

    let o = critterbox(&["recover", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(3), "cut off: {}", text(&o));
    let recovered = dir.join("late.recovered.mcap");
    let r = Recording::open(&recovered).expect("recovered");
    assert!(
        r.last_step() > 2_000,
        "recovered up to step {}",
        r.last_step()
    );
    assert!(
        r.scripts
            .iter()
            .any(|(name, _)| name.ends_with("bullet.rhai")),
        "the late kind is attached: {:?}",
        r.scripts.iter().map(|(n, _)| n).collect::<Vec<_>>()
    );
    let o = critterbox_in(&dir, &["replay", recovered.to_str().unwrap(), "--verify"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("verify       ok"), "{}", text(&o));
}

/// Under `solve:n` each step starts from the last step's contact impulses: the full states carry
/// them, so a step replayed from the keyframe before it is still the recorded one, and the
/// whole file verifies.
#[test]
fn a_solve_run_is_replayed_from_its_keyframes_with_its_contact_impulses() {
    let dir = tmp("restore_solve");
    let (all, sparse) = (dir.join("every1.mcap"), dir.join("every25.mcap"));
    let scene = Path::new(ROOT).join("scripts/scenes/pile.rhai");
    let args = [
        scene.to_str().unwrap(),
        "--method",
        "solve:8",
        "--steps",
        "240",
    ];
    record(&all, &[&args[..], &["--record-every", "1"]].concat());
    record(&sparse, &[&args[..], &["--record-every", "25"]].concat());
    let r = Recording::open(&sparse).expect("open");
    let mut carried = 0;
    for_each_state(&sparse, |s| {
        carried += s.contact_impulses.len();
        Ok(Flow::Continue)
    })
    .expect("states");
    assert!(
        carried > 0,
        "test setup: the keyframes carry contact impulses"
    );
    replayed_from_keyframes_as_recorded(&all, &r, &[60, 130, 239]);
}

/// Under `event` a step's flight is kept for the next steps (`method::flight`), with events the
/// full states do not hold: a replay restores only the full states at steps whose number is a
/// multiple of `FLIGHT_STEPS`, where the recorded run set its flight up anew, and flies on from
/// there exactly. With keyframes every 5 steps, steps 37 and 68 come from the states at 30 and
/// 60, not 35 and 65 (restored there, the replay would set up a flight the recorded run did not,
/// and the hashes would differ: the replay would fall back to step 0).
#[test]
fn an_event_run_is_replayed_from_the_keyframes_where_its_flight_was_set_up() {
    use critterbox::method::FLIGHT_STEPS;
    let dir = tmp("restore_event");
    let (all, sparse) = (dir.join("every1.mcap"), dir.join("every5.mcap"));
    let args = [
        "gas", "-n", "200", "--method", "event", "--steps", "90", "--seed", "3",
    ];
    record(&all, &[&args[..], &["--record-every", "1"]].concat());
    record(&sparse, &[&args[..], &["--record-every", "5"]].concat());
    let r = Recording::open(&sparse).expect("open");
    assert_eq!(FLIGHT_STEPS, 30, "the steps below assume it");
    assert_eq!(r.keyframe_at_or_before(37), Some(30));
    assert_eq!(r.keyframe_at_or_before(68), Some(60));
    replayed_from_keyframes_as_recorded(&all, &r, &[37, 68, 89]);
}

/// Each of `steps`, replayed from the keyframe before it in `sparse`, is the state `all` (every
/// step recorded) holds for it; and the whole of `sparse` verifies.
fn replayed_from_keyframes_as_recorded(all: &Path, sparse: &Recording, steps: &[u64]) {
    for &step in steps {
        let (shown, source) = state_at_step(sparse, step).expect("a step");
        let key = sparse.keyframe_at_or_before(step).expect("a keyframe");
        assert_eq!(
            source,
            StateSource::Restored { keyframe: key },
            "step {step}"
        );
        let truth = state_at(all, step)
            .expect("read")
            .expect("every step recorded");
        assert_eq!(
            first_difference(&truth, &shown, "recorded", "replayed"),
            None,
            "step {step}"
        );
        assert_eq!(truth.quiet_steps, shown.quiet_steps, "step {step}");
        assert_eq!(
            truth.contact_impulses, shown.contact_impulses,
            "step {step}"
        );
    }
    let report = verify(sparse, |_| {}).expect("verifies");
    assert!(report.passed(), "{report:?}");
}

/// Under `solve:n` the pile falls asleep: the full states carry each critter's count of quiet
/// steps and each sleeper's island, so a step replayed from the keyframe before it is still the
/// recorded one (sleepers stay put, the counting ones fall asleep on the same step), and the
/// whole file verifies.
#[test]
fn a_sleeping_pile_is_replayed_from_its_keyframes_with_its_quiet_steps() {
    let dir = tmp("restore_sleep");
    let (all, sparse) = (dir.join("every1.mcap"), dir.join("every40.mcap"));
    let scene = Path::new(ROOT).join("scripts/scenes/pile.rhai");
    let args = [scene.to_str().unwrap(), "--steps", "600"];
    record(&all, &[&args[..], &["--record-every", "1"]].concat());
    record(&sparse, &[&args[..], &["--record-every", "40"]].concat());
    let r = Recording::open(&sparse).expect("open");
    let (mut counting, mut asleep) = (0, 0);
    for_each_state(&sparse, |s| {
        counting += s.quiet_steps.iter().filter(|q| q.1 < 30).count();
        asleep += s.quiet_steps.iter().filter(|q| q.1 == 30).count();
        Ok(Flow::Continue)
    })
    .expect("states");
    assert!(
        counting > 0 && asleep > 0,
        "test setup: the keyframes carry counting critters ({counting}) and sleepers ({asleep})"
    );
    let mut steps: Vec<u64> = Vec::new();
    for_each_state(&all, |s| {
        let before = s.quiet_steps.iter().filter(|q| q.1 == 30).count();
        if before > 0 && steps.len() < 3 && s.step % 40 != 0 {
            steps.push(s.step);
        }
        Ok(Flow::Continue)
    })
    .expect("states");
    steps.extend([r.last_step() - 1]);
    replayed_from_keyframes_as_recorded(&all, &r, &steps);
}
