//! Golden state hashes: each run below must end on the hash it had when it was written down.
//!
//! Determinism is a feature: the same scene, seed and method give a bit-identical run. These
//! hashes guard that promise across refactors (a change that should not change behaviour keeps
//! every one of them). A change that is meant to change a run's bits updates its row here, and
//! says why in its commit.

use std::process::Command;

/// The repository, where the scripts are.
const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// (arguments of `critterbox run`, the state hash it ends on)
const RUNS: &[(&str, &str)] = &[
    ("", "151c0aeda8443ef9"),
    ("gas3d --seed 7 --steps 200", "f7c50535fce94e57"),
    ("scripts/scenes/billiards.rhai", "c02ace5aaf1eb598"),
    ("scripts/scenes/pile.rhai", "2b1184202c45e783"),
    ("pegs --method auto --steps 300", "e96c265a50357a8f"),
    ("gas --method event -n 2000 --steps 200", "d9cea4352889a91e"),
    (
        "gas --method substep:3 --steps 150 -n 400",
        "fd6ba7710b33235f",
    ),
    (
        "gas --method solve:8 --steps 150 -n 400",
        "200a5e7364258e28",
    ),
    (
        "gas-wrap --method discrete --steps 150 -n 400",
        "59370d26ebebce9d",
    ),
    (
        "gas-wrap --method event --steps 150 -n 400",
        "a9e8c20d534868e9",
    ),
    (
        "gas-wrap --method solve:8 --steps 150 -n 400",
        "0adcce5a5d06dc01",
    ),
    (
        "gas3d --method substep:3 --steps 150 -n 400",
        "8aa56640c0478093",
    ),
    (
        "gas3d --method event --steps 150 -n 400",
        "be6543abda4c3b04",
    ),
    (
        "gas3d --method solve:8 --steps 150 -n 400",
        "9b5e847a889b714b",
    ),
    (
        "billiards --method swept --steps 150 -n 400",
        "43c2197e56633f90",
    ),
    (
        "billiards --method event --steps 150 -n 400",
        "9cf8c43b26ba901d",
    ),
    (
        "billiards --method solve:8 --steps 150 -n 400",
        "58b70c524e5b6764",
    ),
    (
        "cradle --method discrete --steps 150 -n 400",
        "fea85c167ef2493a",
    ),
    (
        "cradle --method event --steps 150 -n 400",
        "e59d412d0435efda",
    ),
    (
        "cradle --method solve:8 --steps 150 -n 400",
        "3b17bb55b054e99f",
    ),
    ("pegs --method event --steps 150 -n 400", "25a32b64ba28cdaf"),
    ("scripts/scenes/basket_game.rhai", "9257cba92e7b5c66"),
    ("scripts/scenes/bullets_vs_player.rhai", "bbb0df3d2a87fecd"),
    (
        "scripts/scenes/bullets_vs_player.rhai --method event --steps 200",
        "5431fea8df5e4e1d",
    ),
    ("scripts/scenes/children.rhai", "c04571bed7904e95"),
    ("scripts/scenes/cradle.rhai", "d32c7630a8953b8c"),
    (
        "scripts/scenes/gas.rhai --method auto --steps 200",
        "ff4abd5ae63f697a",
    ),
    (
        "scripts/scenes/pile.rhai --method auto --steps 200",
        "bf14155d71620790",
    ),
    (
        "scripts/scenes/pile.rhai --method event --steps 200",
        "db291ef0f42c720f",
    ),
    // Large enough for the parallel passes and the kept pair list's parallel re-test.
    ("gas -n 30000 --steps 100", "3a136377d1d47956"),
    (
        "gas -n 30000 --steps 60 --method solve:8",
        "92f7ede20410c077",
    ),
    ("gas3d -n 25000 --steps 80", "12a0f3db6cd7a065"),
];

fn state_hash(args: &str) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .arg("run")
        .args(args.split_whitespace())
        .arg("--no-record")
        .current_dir(ROOT)
        .output()
        .expect("the critterbox binary runs");
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "critterbox run {args} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    out.lines()
        .find_map(|l| l.strip_prefix("state hash"))
        .map(|h| h.trim().to_string())
        .unwrap_or_else(|| panic!("no state hash in the output of `run {args}`:\n{out}"))
}

#[test]
fn every_run_ends_on_its_golden_state_hash() {
    let wrong: Vec<String> = RUNS
        .iter()
        .filter_map(|&(args, want)| {
            let got = state_hash(args);
            (got != want).then(|| format!("  run {args}: {got}, expected {want}"))
        })
        .collect();
    assert!(
        wrong.is_empty(),
        "{} of {} runs changed their bits:\n{}",
        wrong.len(),
        RUNS.len(),
        wrong.join("\n")
    );
}
