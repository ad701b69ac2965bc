//! `critterbox check` as a linter: every file and every problem reported, positions given,
//! warnings failing only under `--strict`; and `critterbox test --filter` that matches nothing
//! fails.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

fn critterbox(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args(args)
        .current_dir(ROOT)
        .output()
        .expect("the command runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A scratch folder with `kinds/prey.rhai` (a good kind), removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Scratch {
        let dir =
            std::env::temp_dir().join(format!("critterbox-check-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("kinds")).expect("temp dir");
        let s = Scratch(dir);
        s.write("kinds/prey.rhai", "defaults(#{ radius: 0.3 });\n");
        s
    }
    fn write(&self, name: &str, text: &str) -> String {
        let path = self.0.join(name);
        std::fs::write(&path, text).expect("write");
        path.display().to_string()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// `file:line:col` of the first `needle` in `text` (1-based), as check prints it.
fn place(file: &str, text: &str, needle: &str) -> String {
    let (i, line) = text
        .lines()
        .enumerate()
        .find(|(_, l)| l.contains(needle))
        .expect("needle in text");
    let col = line[..line.find(needle).unwrap()].chars().count() + 1;
    format!("{file}:{}:{col}", i + 1)
}

const HUNTER: &str = "fn colide(me, other) {\n    if other.is_kind(\"pray\") {\n        me.die();\n    }\n    true\n}\n";

#[test]
fn check_warns_on_a_misspelt_hook_and_an_unknown_kind_with_their_places() {
    let s = Scratch::new("warn");
    let file = s.write("kinds/hunter.rhai", HUNTER);
    let o = critterbox(&["check", &file]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "warnings alone pass: {err}");
    assert!(
        err.contains(&format!(
            "{}: function 'colide'",
            place(&file, HUNTER, "colide")
        )) && err.contains("did you mean 'collide'"),
        "{err}"
    );
    assert!(
        err.contains(&format!(
            "{}: unknown kind 'pray'",
            place(&file, HUNTER, "\"pray\"")
        )) && err.contains("did you mean 'prey'"),
        "{err}"
    );
}

#[test]
fn check_strict_fails_on_warnings() {
    let s = Scratch::new("strict");
    let file = s.write("kinds/hunter.rhai", HUNTER);
    let o = critterbox(&["check", "--strict", &file]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--strict"), "{}", stderr(&o));
}

#[test]
fn check_reports_every_bad_file_not_only_the_first() {
    let s = Scratch::new("two");
    let a = s.write(
        "kinds/broken.rhai",
        "fn update(me, dt) {\n    let x = ;\n}\n",
    );
    let b_text = "let w = world(#{ dim: 2, size: vec(10, 10) });\nspawn(\"ball\", #{ pos: vec(5, 5), colour: 1 });\n";
    let b = s.write("scene.rhai", b_text);
    let good = format!("{ROOT}/scripts/kinds/bullet.rhai");
    let o = critterbox(&["check", &a, &good, &b]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains(&format!("{a}:2:")), "{err}");
    assert!(err.contains(&format!("{b}:2:")), "{err}");
    assert!(err.contains("2 errors"), "{err}");
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("kind 'bullet' ok"),
        "the good file between them is checked too"
    );
}

#[test]
fn check_warns_on_hooks_with_the_wrong_number_of_parameters() {
    let s = Scratch::new("arity");
    let text = "fn on_death(me, other) {}\nfn touch_begin(me, other) {}\nfn touch_end(me, other) {}\nfn collide(me, other, contact) { true }\n";
    let file = s.write("kinds/odd.rhai", text);
    let o = critterbox(&["check", &file]);
    let err = stderr(&o);
    assert!(
        err.contains(&format!("{file}:1:4: hook on_death takes 1")),
        "{err}"
    );
    assert!(
        // Loading the kind fails on it too, so it may come as the load's error (column 1).
        err.contains(&format!("{file}:2:")) && err.contains("hook touch_begin takes 3"),
        "{err}"
    );
    assert!(!err.contains(":3:4: hook"), "touch_end takes 2: {err}");
    assert!(
        !err.contains(":4:4: hook collide"),
        "collide may take 3: {err}"
    );
}

#[test]
fn check_checks_test_files() {
    let s = Scratch::new("tests");
    let text = "fn test_a() {\n    let w = world(#{ dim: 2 });\n    spawn(\"pray\", #{ pos: vec(1, 1) });\n}\n";
    let file = s.write("t.rhai", text);
    let o = critterbox(&["check", &file]);
    let err = stderr(&o);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("tests ok (1 tests)"),
        "{err}"
    );
    assert!(err.contains(&place(&file, text, "\"pray\"")), "{err}");
    assert!(Path::new(&file).exists());
}

#[test]
fn test_filter_matching_nothing_fails() {
    let o = critterbox(&[
        "test",
        "scripts/tests/spawning.rhai",
        "--filter",
        "no_such_test_anywhere",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("nothing ran"), "{}", stderr(&o));
}

/// The `error: FILE:LINE:COL: message` lines `check` printed for `file`, as (line, message).
fn errors_in(err: &str, file: &str) -> Vec<(usize, String)> {
    let prefix = format!("error: {file}:");
    err.lines()
        .filter_map(|l| l.strip_prefix(&prefix))
        .filter_map(|rest| {
            let (line, rest) = rest.split_once(':')?;
            let (_col, message) = rest.split_once(": ")?;
            Some((line.parse().ok()?, message.to_string()))
        })
        .collect()
}

#[test]
fn check_gives_a_wrong_arity_hook_the_same_verdict_whatever_else_is_wrong() {
    let s = Scratch::new("arity_verdict");
    // touch_begin is wrong in both; in the first, update is wrong too, and the loader stops at
    // update, the first hook it checks.
    let both = s.write(
        "kinds/both.rhai",
        "fn update(me) {}\nfn touch_begin(me, other) {}\n",
    );
    let one = s.write(
        "kinds/one.rhai",
        "fn update(me, dt) {}\nfn touch_begin(me, other) {}\n",
    );
    // A wrong default stops the loader before it looks at the hooks at all.
    let defaults = s.write(
        "kinds/defaults.rhai",
        "defaults(#{ radius: \"big\" });\nfn touch_begin(me, other) {}\n",
    );
    for (file, lines) in [
        (&both, vec![1, 2]),
        (&one, vec![2]),
        (&defaults, vec![1, 2]),
    ] {
        let o = critterbox(&["check", file]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        let errors = errors_in(&err, file);
        assert_eq!(
            errors.iter().map(|(l, _)| *l).collect::<Vec<_>>(),
            lines,
            "{err}"
        );
        assert!(
            errors
                .iter()
                .any(|(l, m)| *l == 2 && m.starts_with("hook touch_begin takes 3")),
            "{err}"
        );
        assert!(!err.contains("warning: "), "{err}");
    }
}

#[test]
fn check_reports_a_bad_spawn_field_and_goes_on_through_the_scene() {
    let s = Scratch::new("spawn_fields");
    let text = "let w = world(#{ dim: 2, size: vec(20, 20) });\n\
                spawn(\"ball\", #{ pos: vec(2, 2), colour: \"red\" });\n\
                spawn(\"ball\", #{ pos: vec(6, 2), radius: \"big\" });\n\
                spawn(\"pray\", #{ pos: vec(10, 2) });\n\
                fn on_step(world, extra) {}\n";
    let file = s.write("scene.rhai", text);
    let o = critterbox(&["check", &file]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let errors = errors_in(&err, &file);
    assert_eq!(
        errors.iter().map(|(l, _)| *l).collect::<Vec<_>>(),
        vec![2, 3, 4, 5],
        "{err}"
    );
    assert!(errors[0].1.contains("unknown field 'colour'"), "{err}");
    assert!(err.contains("did you mean 'color'?"), "{err}");
    assert!(errors[1].1.contains("radius"), "{err}");
    assert!(errors[2].1.contains("unknown kind 'pray'"), "{err}");
    assert!(errors[3].1.starts_with("hook on_step takes 1"), "{err}");
    assert!(err.contains("4 errors"), "{err}");
    assert!(
        !String::from_utf8_lossy(&o.stdout).contains("scene ok"),
        "a scene with errors is not ok"
    );
}

#[test]
fn check_accepts_color_in_a_spawn_map_and_refuses_a_bad_one() {
    let s = Scratch::new("spawn_color");
    let good = s.write(
        "good.rhai",
        "let w = world(#{ dim: 2, size: vec(20, 20) });\n\
         spawn(\"ball\", #{ pos: vec(2, 2), color: \"red\" });\n\
         spawn(\"prey\", #{ pos: vec(6, 2), color: \"#33aa55\" });\n",
    );
    let o = critterbox(&["check", &good]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("scene ok"),
        "{}",
        stderr(&o)
    );
    let bad = s.write(
        "bad.rhai",
        "let w = world(#{ dim: 2, size: vec(20, 20) });\n\
         spawn(\"ball\", #{ pos: vec(2, 2), color: \"reddish\" });\n",
    );
    let o = critterbox(&["check", &bad]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let errors = errors_in(&err, &bad);
    assert_eq!(errors.len(), 1, "{err}");
    assert!(
        errors[0].0 == 2 && errors[0].1.contains("color") && errors[0].1.contains("reddish"),
        "{err}"
    );
}

#[test]
fn check_does_not_take_scene_files_for_kinds() {
    let s = Scratch::new("scenes_no_kinds");
    // A scene beside the kind, named as the kind's typo and as a name with no close kind.
    s.write(
        "kinds/pray.rhai",
        "let w = world(#{ dim: 2, size: vec(10, 10) });\n",
    );
    s.write(
        "kinds/arena_scene.rhai",
        "let w = world(#{ dim: 2, size: vec(10, 10) });\n",
    );
    let text = "fn collide(me, other) {\n    if other.is_kind(\"pray\") || other.is_kind(\"zzz\") { me.die(); }\n    true\n}\n";
    let file = s.write("kinds/hunter.rhai", text);
    let o = critterbox(&["check", &file]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "warnings only: {err}");
    assert!(
        err.contains(&format!(
            "{}: unknown kind 'pray'",
            place(&file, text, "\"pray\"")
        )) && err.contains("did you mean 'prey'"),
        "{err}"
    );
    // The hint under the warning for 'zzz' lists the known kinds.
    let hint = err
        .lines()
        .skip_while(|l| !l.contains("unknown kind 'zzz'"))
        .find(|l| l.contains("hint: "))
        .unwrap_or_default();
    assert!(
        hint.contains("the known kinds are") && hint.contains("prey"),
        "{err}"
    );
    assert!(
        !hint.contains("arena_scene") && !hint.contains("pray"),
        "{err}"
    );
}
