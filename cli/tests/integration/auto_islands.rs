//! A mixed `auto` run (a pile solved beside a cradle flying exact events, in one step) is
//! recorded, reports its islands, and replays and verifies from the recording alone.

use crate::common;
use common::{critterbox_in, text};

/// A pile settling on the floor of a walled box beside a cradle struck in mid-air.
const SCENE: &str = r#"
let w = world(#{ dim: 2, size: vec(40, 60), gravity: vec(0, -9.81), method: "auto",
                 seed: 5, steps: 90 });
w.walls_around();
for row in 0..6 {
    for col in 0..12 {
        let x = 1.0 + col * 1.1 + (row % 2) * 0.5;
        spawn("ball", #{ pos: vec(x, 1.0 + row * 1.05), vel: vec(rand(-0.2, 0.2), 0),
                         radius: 0.5, restitution: 0.5 });
    }
}
spawn("ball", #{ pos: vec(20, 50), vel: vec(5, 0), radius: 0.25 });
w.row("ball", vec(21, 50), vec(0.5, 0), 5, #{ radius: 0.25 });
"#;

#[test]
fn a_mixed_auto_run_reports_its_islands_and_replays_bit_for_bit() {
    let dir = common::tmp_in("auto-islands-tests", "mixed");
    std::fs::write(dir.join("mixed.rhai"), SCENE).expect("scene written");
    let islands_after = |steps: &str| {
        let o = critterbox_in(
            &dir,
            &["run", "mixed.rhai", "--steps", steps, "--no-record"],
        );
        assert!(o.status.success(), "{}", text(&o));
        let out = text(&o);
        out.lines()
            .find(|l| l.starts_with("islands "))
            .unwrap_or_else(|| panic!("no islands line: {out}"))
            .to_string()
    };
    // The striker meets the cradle in step 7, before the pile lands: nothing rests, and all
    // flies by events.
    let islands = islands_after("7");
    assert!(
        islands.contains("6 critters in 1 island event (impacts in flight)")
            && islands.contains("72 critters in 72 islands event (in flight, no two meet)"),
        "{islands}"
    );
    // Landed, the pile is solved while the cradle's balls fly by events, in one step.
    let islands = islands_after("30");
    assert!(
        islands.contains("72 critters in 1 island solve:8 (resting contacts under gravity)")
            && islands.contains("6 critters in 2 islands event (in flight, no two meet)"),
        "{islands}"
    );
    let o = critterbox_in(&dir, &["run", "mixed.rhai", "--record", "mixed.mcap"]);
    assert!(o.status.success(), "{}", text(&o));
    let o = critterbox_in(&dir, &["replay", "mixed.mcap", "--verify"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("verify       ok: 90 steps"),
        "{}",
        text(&o)
    );
}

/// Bullets fired into a pile in a closed box.
const BULLETS: &str = r#"
let w = world(#{ dim: 2, size: vec(20, 20), gravity: vec(0, -9.81), method: "auto",
                 seed: 3, steps: 60 });
w.walls_around();
for row in 0..4 {
    for col in 0..16 {
        let x = 1.0 + col * 1.1 + (row % 2) * 0.5;
        spawn("ball", #{ pos: vec(x, 1.0 + row * 1.05), radius: 0.5, restitution: 0.5 });
    }
}
for k in 0..3 {
    spawn("ball", #{ pos: vec(4.0 + 5.0 * k, 15), vel: vec(30 - 30 * k, -150), radius: 0.05 });
}
"#;

/// A few critters too fast for the solve's substeps are flown after the solved step against
/// the pile (`method::bullets`): the run says so, and its recording verifies.
#[test]
fn bullets_among_a_pile_are_flown_after_the_solve_and_replay_bit_for_bit() {
    let dir = common::tmp_in("auto-islands-tests", "bullets");
    std::fs::write(dir.join("bullets.rhai"), BULLETS).expect("scene written");
    let o = critterbox_in(
        &dir,
        &["run", "bullets.rhai", "--steps", "3", "--no-record"],
    );
    assert!(o.status.success(), "{}", text(&o));
    let out = text(&o);
    assert!(
        out.contains("3 bullets too fast for the solve's substeps, flown after it"),
        "{out}"
    );
    let o = critterbox_in(&dir, &["run", "bullets.rhai", "--record", "bullets.mcap"]);
    assert!(o.status.success(), "{}", text(&o));
    let o = critterbox_in(&dir, &["replay", "bullets.mcap", "--verify"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("verify       ok: 60 steps"),
        "{}",
        text(&o)
    );
}
