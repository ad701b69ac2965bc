//! Damaged recordings lose only what is damaged, the exit codes say so (3: damaged or cut off),
//! and `diff` compares every recorded message, not only the hashes.

use crate::common;
use common::{critterbox, text};

use critterbox::recording::recover::rewrite;
use critterbox::recording::schema;
use critterbox::recording::Recording;
use serde_json::Value;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// A fresh folder for one test.
fn tmp(name: &str) -> PathBuf {
    common::tmp_in("damaged-tests", name)
}

/// The exit code of a command that read a damaged or cut-off recording.
const DAMAGED: i32 = 3;

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn record(path: &Path, args: &[&str]) {
    let mut all = vec!["run"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--record", s(path)]);
    let o = critterbox(&all);
    assert!(o.status.success(), "{}", text(&o));
}

/// The chunks of an intact file, from its summary: (offset, length, the steps whose hash
/// message the chunk holds).
fn chunks(path: &Path) -> Vec<(u64, u64, Vec<u64>)> {
    let bytes = std::fs::read(path).expect("read");
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("an intact file has a summary");
    summary
        .chunk_indexes
        .iter()
        .map(|idx| {
            let mut steps = Vec::new();
            for m in summary.stream_chunk(&bytes, idx).expect("chunk") {
                let m = m.expect("message");
                if m.channel.topic == schema::HASH {
                    let v: Value = serde_json::from_slice(&m.data).expect("json");
                    steps.push(v["step"].as_u64().expect("step"));
                }
            }
            (idx.chunk_start_offset, idx.chunk_length, steps)
        })
        .collect()
}

/// A copy of `src` with one byte flipped in the middle of chunk `which`'s compressed data.
fn flip_in_chunk(src: &Path, dst: &Path, offset: u64, length: u64) {
    let mut bytes = std::fs::read(src).expect("read");
    let at = (offset + length / 2) as usize;
    bytes[at] ^= 0x10;
    std::fs::write(dst, bytes).expect("write");
}

#[test]
fn a_damaged_chunk_loses_only_its_own_steps_and_every_reader_says_which() {
    let dir = tmp("one_chunk");
    let clean = dir.join("clean.mcap");
    record(
        &clean,
        &["gas", "-n", "100", "--steps", "900", "--record-every", "1"],
    );
    let all = chunks(&clean);
    assert!(all.len() >= 5, "test setup: several chunks ({})", all.len());
    // The first chunk with steps from 38.7 % of the file on.
    let len = std::fs::metadata(&clean).expect("size").len();
    let (offset, length, lost) = all
        .iter()
        .find(|(o, l, steps)| *o * 1000 >= len * 387 && *l > 1000 && steps.len() > 1)
        .cloned()
        .expect("test setup: a chunk with steps after 38.7 %");
    let bad = dir.join("bad.mcap");
    flip_in_chunk(&clean, &bad, offset, length);

    let truth = Recording::open(&clean).expect("clean");
    let r = Recording::open(&bad).expect("a damaged file still opens");
    let lost_set: BTreeSet<u64> = lost.iter().copied().collect();
    let kept: BTreeSet<u64> = truth
        .hashes
        .keys()
        .copied()
        .filter(|k| !lost_set.contains(k))
        .collect();
    assert_eq!(
        r.hashes.keys().copied().collect::<BTreeSet<u64>>(),
        kept,
        "every step outside the damaged chunk is kept"
    );
    for (step, hash) in &r.hashes {
        assert_eq!(truth.hashes.get(step), Some(hash), "step {step}");
    }
    let (first, last) = (lost[0], lost[lost.len() - 1]);
    assert_eq!(r.gaps.len(), 1, "{:?}", r.gaps);
    assert_eq!(r.gaps[0].missing(), Some((first, Some(last))));
    assert_eq!(r.gaps[0].damage.offset, offset);
    let named = format!("steps {first}..{last} missing: chunk at byte {offset} is damaged");

    for args in [
        vec!["inspect", s(&bad)],
        vec!["replay", s(&bad), "--verify"],
        vec!["export", s(&bad), "--csv", s(&dir.join("csv"))],
        vec!["recover", s(&bad), "-o", s(&dir.join("recovered.mcap"))],
    ] {
        let o = critterbox(&args);
        assert_eq!(o.status.code(), Some(DAMAGED), "{args:?}: {}", text(&o));
        let (out, err) = (
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr),
        );
        assert!(err.contains(&named), "{args:?} names the steps: {err}");
        assert!(!out.contains("warning"), "warnings go to stderr: {out}");
        assert!(!out.contains("verify       ok"), "{out}");
    }
    let steps = std::fs::read_to_string(dir.join("csv/steps.csv")).expect("steps.csv");
    assert_eq!(
        steps.lines().count(),
        1 + kept.len(),
        "one row per kept step"
    );
    let recovered = Recording::open(&dir.join("recovered.mcap")).expect("recovered");
    assert_eq!(recovered.hashes, r.hashes);
    // The copy lacks the steps too, and says so.
    let o = critterbox(&["inspect", s(&dir.join("recovered.mcap"))]);
    assert_eq!(o.status.code(), Some(DAMAGED), "{}", text(&o));
    // Verifying re-simulates through the hole: no false mismatch.
    let o = critterbox(&["replay", s(&bad), "--verify"]);
    assert!(
        text(&o).contains("verify       incomplete: 900 steps re-simulated"),
        "{}",
        text(&o)
    );
    // Against the intact file: nothing differs where both hold the step.
    let o = critterbox(&["diff", s(&clean), s(&bad)]);
    assert_eq!(o.status.code(), Some(DAMAGED), "{}", text(&o));
}

#[test]
fn a_damaged_first_chunk_is_bridged_by_the_summary() {
    let dir = tmp("first_chunk");
    let clean = dir.join("clean.mcap");
    record(&clean, &["gas", "-n", "60", "--steps", "120"]);
    // The first chunk holds the schemas and channels every later message refers to.
    let (offset, length, _) = chunks(&clean)[0].clone();
    let bad = dir.join("bad.mcap");
    flip_in_chunk(&clean, &bad, offset, length);
    let truth = Recording::open(&clean).expect("clean");
    let r = Recording::open(&bad).expect("opens");
    assert_eq!(r.hashes, truth.hashes);
    assert_eq!(r.gaps.len(), 1);
    let o = critterbox(&["inspect", s(&bad)]);
    assert_eq!(o.status.code(), Some(DAMAGED), "{}", text(&o));
}

#[test]
fn a_file_cut_at_ten_percent_is_never_verified_ok() {
    let dir = tmp("cut");
    let clean = dir.join("clean.mcap");
    record(
        &clean,
        &["gas", "-n", "100", "--steps", "300", "--record-every", "1"],
    );
    let bytes = std::fs::read(&clean).expect("read");
    let cut = dir.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 10]).expect("write");
    for args in [
        vec!["replay", s(&cut), "--verify"],
        vec!["inspect", s(&cut)],
        vec!["export", s(&cut), "--csv", s(&dir.join("csv"))],
    ] {
        let o = critterbox(&args);
        assert_eq!(o.status.code(), Some(DAMAGED), "{args:?}: {}", text(&o));
        assert!(!text(&o).contains("verify       ok"), "{}", text(&o));
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("cut off"),
            "{}",
            text(&o)
        );
    }
}

/// A copy of `src` with the first message of `topic` (at `step`, if given) changed by `edit`.
fn edit_message(src: &Path, dst: &Path, topic: &str, step: Option<u64>, edit: impl Fn(&mut Value)) {
    let mut done = false;
    rewrite(src, dst, |t, data| {
        if done || t != topic {
            return None;
        }
        let mut v: Value = serde_json::from_slice(data).expect("json");
        if step.is_some_and(|s| v["step"].as_u64() != Some(s)) {
            return None;
        }
        edit(&mut v);
        done = true;
        Some(serde_json::to_vec(&v).expect("encode"))
    })
    .expect("rewrite");
    assert!(done, "test setup: a {topic} message to edit");
}

/// The float at `v[field][index]` (or `v[field]`) with its lowest bit flipped; returns the old
/// and new value as JSON text.
fn flip(v: &mut Value, field: &str, index: Option<usize>) -> (String, String) {
    let slot = match index {
        Some(i) => &mut v[field][i],
        None => &mut v[field],
    };
    let old = slot.as_f64().expect("a float");
    let new = f64::from_bits(old.to_bits() ^ 1);
    *slot = Value::from(new);
    (Value::from(old).to_string(), Value::from(new).to_string())
}

fn diff(a: &Path, b: &Path) -> (Option<i32>, String) {
    let o = critterbox(&["diff", s(a), s(b)]);
    (o.status.code(), text(&o))
}

#[test]
fn diff_names_the_first_velocity_energy_and_impulse_that_differ() {
    let dir = tmp("diff_fields");
    let a = dir.join("a.mcap");
    record(
        &a,
        &["gas", "-n", "100", "--steps", "120", "--record-every", "1"],
    );
    assert_eq!(diff(&a, &a).0, Some(0), "a file equals itself");

    let v = dir.join("velocity.mcap");
    let shown = std::cell::RefCell::new((String::new(), String::new()));
    edit_message(&a, &v, schema::STATE, Some(37), |m| {
        *shown.borrow_mut() = flip(m, "vx", Some(9));
    });
    let (code, out) = diff(&a, &v);
    assert_eq!(code, Some(1), "{out}");
    assert!(out.contains("first differs at step 37"), "{out}");
    let id = {
        let r = Recording::open(&a).expect("open");
        let s = critterbox::recording::reader::state_at(&r.path, 37)
            .expect("read")
            .expect("state");
        critterbox::recording::schema::id_of(s.id[9]).to_string()
    };
    assert!(
        out.contains(&format!("critter {id} (ball): vx A ")),
        "{out}"
    );

    let e = dir.join("energy.mcap");
    edit_message(&a, &e, schema::TOTALS, Some(40), |m| {
        *shown.borrow_mut() = flip(m, "kinetic_energy", None);
    });
    let (old, new) = shown.borrow().clone();
    let (code, out) = diff(&a, &e);
    assert_eq!(code, Some(1), "{out}");
    assert!(
        out.contains(&format!(
            "first differs at step 40: totals kinetic_energy: A {old} | B {new}"
        )),
        "{out}"
    );

    let i = dir.join("impulse.mcap");
    let step = std::cell::Cell::new(0);
    edit_message(&a, &i, schema::COLLISIONS, None, |m| {
        step.set(m["step"].as_u64().expect("step"));
        *shown.borrow_mut() = flip(m, "impulse", Some(0));
    });
    let (old, new) = shown.borrow().clone();
    let (code, out) = diff(&a, &i);
    assert_eq!(code, Some(1), "{out}");
    assert!(
        out.contains(&format!(
            "first differs at step {}: collisions impulse[0]",
            step.get()
        )),
        "{out}"
    );
    assert!(out.contains(&format!("A {old} | B {new}")), "{out}");
    assert!(out.contains("(collision 0: critter "), "{out}");
}

#[test]
fn diff_names_a_changed_scene_text_and_log_line() {
    let dir = tmp("diff_scene");
    let scene = dir.join("ticks.rhai");
    let text_a = "let w = world(#{ dim: 2, size: vec(10, 10), seed: 3 });\n\
                  spawn(\"ball\", #{ pos: vec(5, 5), vel: vec(1, 0) });\n\
                  fn on_step(world) {\n    if world.step_count % 5 == 0 { log(`tick ${world.step_count}`); }\n}\n";
    std::fs::write(&scene, text_a).expect("write scene");
    let a = dir.join("a.mcap");
    record(&a, &[s(&scene), "--steps", "30"]);
    // The same run from a scene whose text differs in a comment only.
    std::fs::write(&scene, format!("{text_a}// a comment\n")).expect("write scene");
    let b = dir.join("b.mcap");
    record(&b, &[s(&scene), "--steps", "30"]);
    assert_eq!(
        Recording::open(&a).expect("a").hashes,
        Recording::open(&b).expect("b").hashes,
        "test setup: the same run"
    );
    let (code, out) = diff(&a, &b);
    assert_eq!(code, Some(1), "{out}");
    assert!(
        out.contains("line 6: A (no line) | B `// a comment`"),
        "{out}"
    );

    let l = dir.join("log.mcap");
    edit_message(&a, &l, schema::LOG, None, |m| {
        m["lines"][0] = Value::from("tock");
    });
    let (code, out) = diff(&a, &l);
    assert_eq!(code, Some(1), "{out}");
    assert!(
        out.contains("log lines[0]: A \"tick 5\" | B \"tock\""),
        "{out}"
    );
}
