//! `run --set` as users meet it: a kind's constant (`--set KIND.NAME=VALUE`) beside the scene's
//! (`--set NAME=VALUE`), seen by the kind's hooks, kept in the recording (so the replay runs
//! what ran) and in the printed summary's `vars` line; an unknown kind or constant is an error.

use crate::common;
use common::{critterbox_in, text, ROOT};

use critterbox::recording::verify::verify;
use critterbox::recording::Recording;
use std::path::Path;

const SCENE: &str = "scripts/tests/scenes/kind_constants.rhai";

fn scene() -> String {
    Path::new(ROOT).join(SCENE).display().to_string()
}

/// The value of the printed summary's line `name`.
fn field<'a>(out: &'a str, name: &str) -> &'a str {
    out.lines()
        .find_map(|l| l.strip_prefix(name))
        .map(str::trim)
        .unwrap_or_else(|| panic!("no '{name}' line in:\n{out}"))
}

#[test]
fn a_kinds_constant_is_set_beside_the_scenes_recorded_and_shown_in_the_summary() {
    let dir = common::tmp_in("sets-tests", "kind");
    let rec = dir.join("run.mcap");
    let json = dir.join("summary.json");
    let o = critterbox_in(
        &dir,
        &[
            "run",
            &scene(),
            "--set",
            "const_probe.SIGHT=3",
            "--set",
            "const_probe.LABEL=wide",
            "--set",
            "N=3",
            "--steps",
            "2",
            "--record",
            rec.to_str().expect("utf-8"),
            "--summary-json",
            json.to_str().expect("utf-8"),
        ],
    );
    let out = text(&o);
    assert!(o.status.success(), "{out}");
    assert_eq!(field(&out, "critters"), "const_probe 3", "the scene's N");
    // The vars line: what the kind's update wrote, its constants set.
    assert_eq!(field(&out, "vars"), r#"label = "wide", sight = 3"#, "{out}");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).expect("summary")).expect("json");
    assert_eq!(summary["vars"]["sight"], 3, "{summary}");
    // The recording keeps the kind's text with the values set, so the replay verifies.
    let recording = Recording::open(&rec).expect("reads");
    let kind = recording
        .scripts
        .iter()
        .find(|(name, _)| name.ends_with("const_probe.rhai"))
        .map(|(_, text)| text.clone())
        .expect("the kind's text is recorded");
    assert!(kind.contains("const SIGHT = 3;"), "{kind}");
    let report = verify(&recording, |_| {}).expect("verifies");
    assert!(report.passed(), "{report:?}");
}

#[test]
fn a_summary_without_vars_has_no_vars_line() {
    let dir = common::tmp_in("sets-tests", "novars");
    let o = critterbox_in(
        &dir,
        &["run", "gas", "-n", "20", "--steps", "2", "--no-record"],
    );
    let out = text(&o);
    assert!(o.status.success(), "{out}");
    assert!(!out.lines().any(|l| l.starts_with("vars")), "{out}");
}

#[test]
fn an_unknown_kind_or_constant_in_set_is_an_error_naming_what_is_known() {
    let dir = common::tmp_in("sets-tests", "unknown");
    let run = |set: &str| {
        let o = critterbox_in(
            &dir,
            &["run", &scene(), "--set", set, "--steps", "1", "--no-record"],
        );
        (o.status.code(), text(&o))
    };
    let (code, out) = run("const_probe.SIGTH=3");
    assert_eq!(code, Some(1), "{out}");
    assert!(
        out.contains("--set const_probe.SIGTH: the kind 'const_probe' has no constant SIGTH"),
        "{out}"
    );
    assert!(
        out.contains("its constants are SIGHT, LABEL, RADIUS"),
        "{out}"
    );
    let (code, out) = run("const_prob.SIGHT=3");
    assert_eq!(code, Some(1), "{out}");
    assert!(out.contains("no kind 'const_prob' in this run"), "{out}");
    assert!(out.contains("did you mean 'const_probe'?"), "{out}");
}
