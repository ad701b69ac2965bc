//! Fuzzing the recording readers: `Recording::open` (what `inspect`, `replay` and `export`
//! read), the full states, `export_csv`, `verify` and `recover`'s rewrite, on arbitrary bytes, on
//! real recordings with bit flips, cuts, inserted, deleted and overwritten bytes, on files whose
//! chunks are intact but whose messages are damaged, and on the committed corpus
//! (`tests/fuzz/corpus/recording/`). None may panic or hang, and a file `recover` writes must
//! open. A longer run by hand is in `docs/testing.md`.

use crate::fuzz_harness as harness;

use critterbox::recording::export::export_csv;
use critterbox::recording::reader::{for_each_state, Flow};
use critterbox::recording::recover::rewrite;
use critterbox::recording::verify::verify;
use critterbox::recording::{EndMeta, Recorder, Recording, RunMeta, RunOverrides};
use critterbox::scenes::{builtin, SceneParams};
use critterbox::script::{load_scene, ScriptOptions};
use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("fuzz-recording")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// Two small real recordings: a built-in gas (full states every 4 steps, so replays fill in
/// steps) and a script scene that logs and then fails (log and error channels, attachments).
fn bases() -> &'static [Vec<u8>] {
    static BASES: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    BASES.get_or_init(|| {
        let dir = scratch("bases");
        vec![
            std::fs::read(record_gas(&dir.join("gas.mcap"))).expect("gas"),
            std::fs::read(record_failing_script(&dir.join("script.mcap"))).expect("script"),
        ]
    })
}

fn record_gas(path: &Path) -> PathBuf {
    let params = SceneParams {
        n: Some(6),
        seed: 3,
        dt: None,
    };
    let mut scene = builtin("gas", &params).expect("gas");
    let meta = RunMeta::builtin(&scene, &params, 24, 4);
    let mut rec = Recorder::create(path, &meta, &scene.sources, &scene.world).expect("create");
    for _ in 0..24 {
        scene.step().expect("step");
        rec.record(&scene.world).expect("record");
    }
    let end = EndMeta {
        steps: scene.world.step_count(),
        outcome: "completed".into(),
        hash: scene.world.state_hash(),
        ..EndMeta::default()
    };
    rec.finish(&scene.world, end).expect("finish").path
}

fn record_failing_script(path: &Path) -> PathBuf {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/logs_then_fails.rhai");
    let mut scene = load_scene(&file, &[], &ScriptOptions::default()).expect("scene");
    let overrides = RunOverrides {
        steps: Some(100),
        ..RunOverrides::default()
    };
    let meta = RunMeta::for_scene(&scene, &overrides);
    let mut rec = Recorder::create(path, &meta, &scene.sources, &scene.world).expect("create");
    loop {
        match scene.step() {
            Ok(_) => rec.record(&scene.world).expect("record"),
            Err(e) => {
                let message = e.to_string();
                rec.record_error(&scene.world, &message).expect("error");
                let end = EndMeta {
                    steps: scene.world.step_count(),
                    outcome: "error".into(),
                    reason: message,
                    hash: scene.world.state_hash(),
                    ..EndMeta::default()
                };
                return rec.finish(&scene.world, end).expect("finish").path;
            }
        }
    }
}

/// Everything the commands do with a recording. Errors are fine; panics and hangs are not, and
/// a file that `recover` writes must read back.
fn exercise(what: &str, bytes: &[u8], dir: &Path) {
    harness::case(what, bytes, || {
        let path = dir.join("input.mcap");
        std::fs::write(&path, bytes).expect("write input");
        if let Ok(rec) = Recording::open(&path) {
            let _ = rec.keyframe_at_or_before(rec.last_step());
            let _ = for_each_state(&path, |_| Ok(Flow::Continue));
            let _ = export_csv(&rec, &dir.join("csv"), false);
            let _ = verify(&rec, |_| {});
        }
        let out = dir.join("recovered.mcap");
        let _ = std::fs::remove_file(&out);
        if rewrite(&path, &out, |_, _| None).is_ok() {
            let back = Recording::open(&out);
            assert!(
                back.is_ok(),
                "recover wrote a file that does not open: {back:?}"
            );
        }
    });
}

/// One change to a byte string; positions are fractions of its length, so they fit any length.
#[derive(Clone, Debug)]
enum Mutation {
    Flip {
        at: u32,
        bit: u8,
    },
    Cut {
        at: u32,
    },
    Insert {
        at: u32,
        bytes: Vec<u8>,
    },
    Delete {
        at: u32,
        len: u16,
    },
    Overwrite {
        at: u32,
        bytes: Vec<u8>,
    },
    /// Replaces the run of digits at or after `at` with an extreme number (a step, a length, a
    /// count that a reader might trust).
    Number {
        at: u32,
        which: u8,
    },
}

const EXTREMES: [&str; 8] = [
    "0",
    "-1",
    "4294967296",
    "18446744073709551615",
    "99999999999999999999999",
    "1e308",
    "NaN",
    "9007199254740993",
];

fn mutation() -> impl Strategy<Value = Mutation> {
    let bytes = proptest::collection::vec(any::<u8>(), 1..16);
    prop_oneof![
        (any::<u32>(), 0u8..8).prop_map(|(at, bit)| Mutation::Flip { at, bit }),
        any::<u32>().prop_map(|at| Mutation::Cut { at }),
        (any::<u32>(), bytes.clone()).prop_map(|(at, bytes)| Mutation::Insert { at, bytes }),
        (any::<u32>(), 1u16..64).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (any::<u32>(), bytes).prop_map(|(at, bytes)| Mutation::Overwrite { at, bytes }),
        (any::<u32>(), any::<u8>()).prop_map(|(at, which)| Mutation::Number { at, which }),
    ]
}

fn place(at: u32, len: usize) -> usize {
    (u64::from(at) * len as u64 / (u64::from(u32::MAX) + 1)) as usize
}

fn apply(data: &mut Vec<u8>, m: &Mutation) {
    let len = data.len();
    match m {
        Mutation::Flip { at, bit } if len > 0 => data[place(*at, len)] ^= 1 << bit,
        Mutation::Cut { at } => data.truncate(place(*at, len)),
        Mutation::Insert { at, bytes } => {
            let i = place(*at, len + 1);
            data.splice(i..i, bytes.iter().copied());
        }
        Mutation::Delete { at, len: n } => {
            let i = place(*at, len);
            let j = (i + usize::from(*n)).min(len);
            data.drain(i..j);
        }
        Mutation::Overwrite { at, bytes } => {
            let i = place(*at, len);
            for (k, b) in bytes.iter().enumerate() {
                if let Some(x) = data.get_mut(i + k) {
                    *x = *b;
                }
            }
        }
        Mutation::Number { at, which } => {
            let start = place(*at, len);
            if let Some(i) = (start..len).find(|&i| data[i].is_ascii_digit()) {
                let j = (i..len).find(|&j| !data[j].is_ascii_digit()).unwrap_or(len);
                let n = EXTREMES[usize::from(*which) % EXTREMES.len()];
                data.splice(i..j, n.bytes());
            }
        }
        Mutation::Flip { .. } => {}
    }
}

/// The real recordings to mutate: the two made here and the corpus.
fn all_bases() -> Vec<Vec<u8>> {
    let mut all = bases().to_vec();
    for f in harness::corpus("recording") {
        all.push(std::fs::read(&f).expect("corpus file"));
    }
    all
}

#[test]
fn the_corpus_and_the_real_recordings_never_panic() {
    let dir = scratch("corpus");
    for f in harness::corpus("recording") {
        let bytes = std::fs::read(&f).expect("corpus file");
        exercise(&f.display().to_string(), &bytes, &dir);
    }
    for (i, b) in bases().iter().enumerate() {
        // The intact recordings verify: the harness exercises real files, not only errors.
        let path = dir.join(format!("base{i}.mcap"));
        std::fs::write(&path, b).expect("write");
        let rec = Recording::open(&path).expect("opens");
        assert!(verify(&rec, |_| {}).expect("verifies").passed());
        exercise(&format!("base {i}"), b, &dir);
    }
}

/// Found by this fuzzing: a hash message whose step was changed inside a sound chunk (to
/// 4294967296 with its hash damaged, or to 9007199254740993 with its hash intact) made `verify`
/// re-simulate billions of steps. It is damage, reported at once.
#[test]
fn a_damaged_step_number_is_reported_not_simulated() {
    for step in ["4294967296", "9007199254740993"] {
        let file = harness::corpus("recording")
            .into_iter()
            .find(|f| f.ends_with(format!("hash-step-{step}.mcap")))
            .expect("the corpus file");
        let rec = Recording::open(&file).expect("opens");
        let report = harness::case(step, b"", || verify(&rec, |_| {})).expect("verify reads it");
        let mismatch = report.mismatch.expect("the damage is reported");
        assert!(mismatch.what.contains(step), "{}", mismatch.what);
        assert!(mismatch.step <= rec.hashes.len() as u64);
    }
}

proptest! {
    #![proptest_config(harness::config(256))]

    #[test]
    fn arbitrary_bytes_never_panic(
        magic in any::<bool>(),
        tail in proptest::collection::vec(any::<u8>(), 0..2048),
    ) {
        let dir = scratch("arbitrary");
        let mut bytes = if magic { mcap::MAGIC.to_vec() } else { Vec::new() };
        bytes.extend(tail);
        exercise("arbitrary bytes", &bytes, &dir);
    }

    #[test]
    fn mutated_recordings_never_panic(
        base in any::<prop::sample::Index>(),
        mutations in proptest::collection::vec(mutation(), 1..4),
    ) {
        let dir = scratch("mutated");
        let all = all_bases();
        let mut bytes = all[base.index(all.len())].clone();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        exercise("a mutated recording", &bytes, &dir);
    }

    /// Damage a chunk CRC cannot catch: a message changed before its chunk was written (as a
    /// bug or a tool rewriting the file would), in a file that is otherwise sound.
    #[test]
    fn damaged_messages_in_sound_chunks_never_panic(
        base in any::<prop::sample::Index>(),
        message in any::<prop::sample::Index>(),
        mutations in proptest::collection::vec(mutation(), 1..3),
    ) {
        let dir = scratch("messages");
        let bases = bases();
        let src = dir.join("base.mcap");
        std::fs::write(&src, &bases[base.index(bases.len())]).expect("write");
        let total = Recording::open(&src).expect("opens").messages.values().sum::<u64>();
        let target = message.index(total.max(1) as usize);
        let mut k = 0;
        let damaged = dir.join("damaged.mcap");
        rewrite(&src, &damaged, |_, data| {
            k += 1;
            (k - 1 == target).then(|| {
                let mut d = data.to_vec();
                for m in &mutations {
                    apply(&mut d, m);
                }
                d
            })
        })
        .expect("rewrite");
        let bytes = std::fs::read(&damaged).expect("read");
        exercise("a damaged message", &bytes, &dir);
    }
}
