//! Fuzzing the scene loader: arbitrary text, scripts built from the scripting API's pieces, the
//! shipped scenes and kinds with bytes and lines changed, and the committed corpus
//! (`tests/fuzz/corpus/scene/`), through `load_scene` (and three steps of what loads), `check`
//! and the linter, under small script limits that bound each case's work. None may panic or
//! hang. A longer run by hand is in `docs/testing.md`.

use crate::fuzz_harness as harness;

use critterbox::script::{check, check_file, load_scene, Limits, ScriptOptions};
use proptest::prelude::*;
use std::path::{Path, PathBuf};

/// Small limits: every script call stops after a bounded amount of work.
fn options() -> ScriptOptions {
    ScriptOptions {
        limits: Limits {
            max_operations: 20_000,
            max_step_operations: 200_000,
            max_call_levels: 16,
            max_string_size: 4096,
            max_array_size: 1024,
            max_map_size: 256,
            max_spawns_per_step: 256,
        },
        ..ScriptOptions::default()
    }
}

/// Most critters a loaded scene may have for the case to step it too.
const STEPPED: usize = 300;

/// A fresh scratch folder for one test, with `scenes/` and `kinds/` in it.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("fuzz-scene")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("scenes")).expect("scratch folder");
    std::fs::create_dir_all(dir.join("kinds")).expect("scratch folder");
    dir
}

/// Loads `scene` (with `kind` as `kinds/fuzzed.rhai`, if given), steps what loads, and checks
/// both files. Errors are fine; panics and hangs are not.
fn exercise(what: &str, scene: &str, kind: Option<&str>, dir: &Path) {
    let mut input = scene.as_bytes().to_vec();
    if let Some(k) = kind {
        input.extend(b"\n// ---- kinds/fuzzed.rhai ----\n");
        input.extend(k.as_bytes());
    }
    harness::case(what, &input, || {
        let path = dir.join("scenes/fuzzed.rhai");
        std::fs::write(&path, scene).expect("write scene");
        let kind_path = dir.join("kinds/fuzzed.rhai");
        match kind {
            Some(k) => std::fs::write(&kind_path, k).expect("write kind"),
            None => {
                let _ = std::fs::remove_file(&kind_path);
            }
        }
        let options = options();
        if let Ok(mut scene) = load_scene(&path, &[], &options) {
            if scene.world.len() <= STEPPED {
                for _ in 0..3 {
                    if scene.step().is_err() {
                        break;
                    }
                }
            }
        }
        let mut files = vec![path.clone()];
        if kind.is_some() {
            files.push(kind_path);
        }
        let _ = check(&files, &options);
        for f in &files {
            let _ = check_file(f, &options);
        }
    });
}

/// Pieces of scene scripts: the calls, maps and control flow scenes use, and odd values.
const PIECES: &[&str] = &[
    "let w = world(#{ dim: 2, size: vec(10, 10) });\n",
    "let w = world(#{ dim: 3, size: vec(10, 10, 10), seed: 3, dt: 0.01 });\n",
    "world(#{",
    "dim: 2, ",
    "dim: 3, ",
    "dim: 7, ",
    "size: vec(20, 10), ",
    "size: vec(1e300, 1e-300), ",
    "border: \"wrap\", ",
    "border: \"clamp\", ",
    "method: \"event\", ",
    "method: \"solve:4\", ",
    "steps: 5, ",
    "gravity: vec(0, -9.8), ",
    "})",
    "});\n",
    "w.walls_around();\n",
    "spawn(\"ball\", #{ pos: vec(5, 5), vel: vec(1, 0), radius: 0.5 });\n",
    "spawn(\"ball\", #{ pos: vec(5, 5, 5), radius: 0.5 });\n",
    "spawn(\"hunter\", #{ pos: vec(2, 2), vel: vec(1, 1) });\n",
    "spawn(\"prey\", #{ pos: vec(7, 7) });\n",
    "spawn(\"splitter\", #{ pos: vec(3, 3), vel: vec(2, 0) });\n",
    "spawn(\"bullet\", #{ pos: vec(1, 1), vel: vec(5, 0), props: #{ targets: [\"ball\"] } });\n",
    "spawn(\"fuzzed\", #{ pos: vec(4, 4) });\n",
    "spawn(",
    "\"ball\", ",
    "#{ ",
    "pos: vec(",
    "vel: vec(",
    "radius: ",
    "mass: ",
    "restitution: ",
    "health: ",
    "color: \"red\", ",
    "vec(",
    "1",
    "0",
    "-1",
    "0.5",
    "1e308",
    "1e-308",
    "9223372036854775807",
    ", ",
    "(",
    ")",
    "{",
    "}",
    "[",
    "]",
    ";",
    "\n",
    "\"",
    "for i in 0..100 { ",
    "for i in 0..1000000 { ",
    "while true { ",
    "loop { ",
    "if rand() < 0.5 { ",
    "fn on_step(world) { ",
    "fn on_step(a, b) { ",
    "world.step_count",
    "w.step_count",
    "stop(\"enough\"); ",
    "throw \"fuzz\"; ",
    "print(\"hi\"); ",
    "let a = []; ",
    "a.push(a); ",
    "let s = \"x\"; s += s; ",
    "const K = 5; ",
    "let x = K * 2; ",
    "x / 0",
    "x % 0",
    "rand(-1, 1)",
    "w.critters_of(\"ball\")",
    "w.count(\"ball\")",
    "load_kind(\"fuzzed\"); ",
    "import \"x\" as y; ",
    "eval(\"1\"); ",
];

fn pieces() -> impl Strategy<Value = String> {
    proptest::collection::vec(any::<prop::sample::Index>(), 0..40)
        .prop_map(|ix| ix.iter().map(|i| PIECES[i.index(PIECES.len())]).collect())
}

/// The shipped scenes and kinds, and the corpus's scenes.
fn texts(folder: &str) -> Vec<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(folder);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "rhai"))
        .collect();
    files.sort();
    files
        .iter()
        .map(|f| std::fs::read_to_string(f).expect("text"))
        .collect()
}

fn scenes() -> Vec<String> {
    let mut all = texts("scripts/scenes");
    for f in harness::corpus("scene") {
        all.push(std::fs::read_to_string(&f).expect("corpus scene"));
    }
    all
}

/// One change to a script: a byte flipped, a line dropped, doubled or swapped, text cut, or a
/// piece inserted.
#[derive(Clone, Debug)]
enum Edit {
    Flip {
        at: prop::sample::Index,
        bit: u8,
    },
    DropLine {
        line: prop::sample::Index,
    },
    DoubleLine {
        line: prop::sample::Index,
    },
    SwapLines {
        a: prop::sample::Index,
        b: prop::sample::Index,
    },
    Cut {
        at: prop::sample::Index,
    },
    Insert {
        at: prop::sample::Index,
        piece: prop::sample::Index,
    },
}

fn edit() -> impl Strategy<Value = Edit> {
    let ix = || any::<prop::sample::Index>();
    prop_oneof![
        (ix(), 0u8..7).prop_map(|(at, bit)| Edit::Flip { at, bit }),
        ix().prop_map(|line| Edit::DropLine { line }),
        ix().prop_map(|line| Edit::DoubleLine { line }),
        (ix(), ix()).prop_map(|(a, b)| Edit::SwapLines { a, b }),
        ix().prop_map(|at| Edit::Cut { at }),
        (ix(), ix()).prop_map(|(at, piece)| Edit::Insert { at, piece }),
    ]
}

fn apply(text: &str, e: &Edit) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let bytes = text.as_bytes();
    // Byte positions are moved to a char boundary so the text stays UTF-8 (ASCII flips only).
    let boundary = |at: &prop::sample::Index| {
        let mut i = at.index(bytes.len().max(1));
        while i > 0 && !text.is_char_boundary(i) {
            i -= 1;
        }
        i.min(text.len())
    };
    match e {
        Edit::Flip { at, bit } => {
            let i = boundary(at);
            let mut b = bytes.to_vec();
            if let Some(x) = b.get_mut(i) {
                if x.is_ascii() {
                    *x ^= 1 << bit;
                }
            }
            String::from_utf8(b).unwrap_or_else(|_| text.to_string())
        }
        Edit::DropLine { line } if !lines.is_empty() => {
            lines.remove(line.index(lines.len()));
            lines.join("\n")
        }
        Edit::DoubleLine { line } if !lines.is_empty() => {
            let i = line.index(lines.len());
            lines.insert(i, lines[i].clone());
            lines.join("\n")
        }
        Edit::SwapLines { a, b } if !lines.is_empty() => {
            let n = lines.len();
            lines.swap(a.index(n), b.index(n));
            lines.join("\n")
        }
        Edit::Cut { at } => text[..boundary(at)].to_string(),
        Edit::Insert { at, piece } => {
            let i = boundary(at);
            format!(
                "{}{}{}",
                &text[..i],
                PIECES[piece.index(PIECES.len())],
                &text[i..]
            )
        }
        _ => text.to_string(),
    }
}

#[test]
fn the_corpus_and_the_shipped_scenes_never_panic() {
    let dir = scratch("corpus");
    for f in harness::corpus("scene") {
        let text = std::fs::read_to_string(&f).expect("corpus scene");
        exercise(&f.display().to_string(), &text, None, &dir);
    }
    for text in texts("scripts/scenes") {
        exercise("a shipped scene", &text, None, &dir);
    }
}

proptest! {
    #![proptest_config(harness::config(192))]

    #[test]
    fn arbitrary_text_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        let dir = scratch("arbitrary");
        let text = String::from_utf8_lossy(&bytes).into_owned();
        exercise("arbitrary text", &text, None, &dir);
    }

    #[test]
    fn scripts_made_of_api_pieces_never_panic(scene in pieces(), kind in pieces()) {
        let dir = scratch("pieces");
        exercise("a script of pieces", &scene, Some(&kind), &dir);
    }

    #[test]
    fn edited_shipped_scenes_never_panic(
        which in any::<prop::sample::Index>(),
        edits in proptest::collection::vec(edit(), 1..5),
    ) {
        let dir = scratch("edited");
        let all = scenes();
        let mut text = all[which.index(all.len())].clone();
        for e in &edits {
            text = apply(&text, e);
        }
        exercise("an edited scene", &text, None, &dir);
    }

    /// A shipped kind, edited, spawned in a small walled scene and stepped.
    #[test]
    fn edited_shipped_kinds_never_panic(
        which in any::<prop::sample::Index>(),
        edits in proptest::collection::vec(edit(), 1..4),
    ) {
        let dir = scratch("kinds");
        let kinds = texts("scripts/kinds");
        let mut kind = kinds[which.index(kinds.len())].clone();
        for e in &edits {
            kind = apply(&kind, e);
        }
        let scene = "let w = world(#{ dim: 2, size: vec(10, 10) });\nw.walls_around();\n\
                     spawn(\"fuzzed\", #{ pos: vec(3, 5), vel: vec(2, 0) });\n\
                     spawn(\"fuzzed\", #{ pos: vec(7, 5), vel: vec(-2, 0) });\n\
                     spawn(\"ball\", #{ pos: vec(5, 2), vel: vec(0, 1) });\n";
        exercise("an edited kind", scene, Some(&kind), &dir);
    }
}
