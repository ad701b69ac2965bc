//! A critter's story from its recording alone (`inspect FILE --critter ID`, `--json`), and what
//! it stands on: the causes the lifecycle channel keeps (format 2), the kinds of die and damage
//! rows in `export`, props and colours in `replay --step`'s table, and older recordings still
//! read.

use crate::common;
use common::{critterbox_in, text, ROOT};

use critterbox::recording::export::export_csv;
use critterbox::recording::schema::{id_of, LifecycleMsg};
use critterbox::recording::Recording;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A target (#0, health 2) and a fixed gun (#1) that fires a shot at steps 1 and 41; each shot
/// damages the target by 1 in its own `collide` and dies there. The target's `on_damage` counts
/// its hits and turns it red; the second hit kills it.
const SCENE: &str = r#"
let w = world(#{ dim: 2, size: vec(20, 10), seed: 1, steps: 200 });
spawn("target", #{ pos: vec(15, 5) });
spawn("gun", #{ pos: vec(3, 5) });
"#;

const GUN: &str = r#"
defaults(#{ radius: 0.5, fixed: true, props: #{ shots: 0 } });
fn update(me, dt) {
    if world().step_count % 40 == 0 && me.shots < 2 {
        me.shots += 1;
        spawn("shot", #{ pos: me.pos + vec(0.8, 0), vel: vec(10, 0) });
    }
}
"#;

const SHOT: &str = r#"
defaults(#{ radius: 0.2, priority: CP_BULLET });
fn collides_with(me, other) {
    if other.is_kind("gun") { DONT_COLLIDE } else { default_collides_with(me, other) }
}
fn collide(me, other) {
    other.damage(1);
    me.die();
    true
}
"#;

const TARGET: &str = r#"
defaults(#{ radius: 0.5, fixed: true, health: 2, props: #{ hits: 0 } });
fn on_damage(me, amount, source) {
    me.hits += 1;
    me.color = "red";
}
"#;

/// The scene, recorded in a fresh folder: (folder, recording).
fn recorded(name: &str) -> (PathBuf, PathBuf) {
    let dir = common::tmp_in("story-tests", name);
    std::fs::create_dir_all(dir.join("scenes")).expect("scenes dir");
    std::fs::create_dir_all(dir.join("kinds")).expect("kinds dir");
    std::fs::write(dir.join("scenes/shots.rhai"), SCENE).expect("scene");
    for (kind, text) in [("gun", GUN), ("shot", SHOT), ("target", TARGET)] {
        std::fs::write(dir.join(format!("kinds/{kind}.rhai")), text).expect("kind");
    }
    let file = dir.join("shots.mcap");
    let o = critterbox_in(
        &dir,
        &[
            "run",
            "scenes/shots.rhai",
            "--record",
            file.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", text(&o));
    (dir, file)
}

/// `inspect FILE --critter ID --json`, parsed.
fn story_json(dir: &Path, file: &Path, id: &str) -> Value {
    let o = critterbox_in(
        dir,
        &["inspect", file.to_str().unwrap(), "--critter", id, "--json"],
    );
    assert!(o.status.success(), "{}", text(&o));
    serde_json::from_slice(&o.stdout).expect("one JSON document")
}

/// The entries of a story's timeline that are `event`.
fn events<'a>(story: &'a Value, event: &str) -> Vec<&'a Value> {
    story["timeline"]
        .as_array()
        .expect("a timeline")
        .iter()
        .filter(|e| e["event"] == event)
        .collect()
}

/// An event as the lifecycle channel has it: the critter, the amount or cause, the critter and
/// hook that caused it, the critter's kind.
type Event<'a, T> = (u64, T, Option<u64>, Option<&'a str>, &'a str);

/// The recording's lifecycle messages, read with the library.
fn lifecycle(file: &Path) -> Vec<LifecycleMsg> {
    Recording::open(file).expect("readable").lifecycle
}

#[test]
fn the_lifecycle_channel_names_who_caused_each_spawn_damage_and_death() {
    let (_dir, file) = recorded("causes");
    let rec = Recording::open(&file).expect("readable");
    assert_eq!(rec.format_version(), 2);
    let life = rec.lifecycle;
    let (gun, target) = (1u64, 0u64);
    let spawns: Vec<(u64, Option<u64>, Option<&str>, &str)> = life
        .iter()
        .flat_map(|l| {
            (0..l.spawn.len()).map(move |i| {
                (
                    l.step,
                    l.spawn_by[i],
                    l.spawn_hook[i].as_deref(),
                    l.spawn_kind[i].as_str(),
                )
            })
        })
        .collect();
    assert_eq!(
        spawns,
        vec![
            (1, Some(gun), Some("update"), "shot"),
            (41, Some(gun), Some("update"), "shot")
        ],
        "the gun's update spawned both shots, in steps 1 and 41"
    );
    let shots: Vec<u64> = life.iter().flat_map(|l| l.spawn.clone()).collect();
    let damages: Vec<Event<f64>> = life
        .iter()
        .flat_map(|l| {
            (0..l.damage_id.len()).map(move |i| {
                (
                    l.damage_id[i],
                    l.damage.0[i],
                    l.damage_source[i],
                    l.damage_hook[i].as_deref(),
                    l.damage_kind[i].as_str(),
                )
            })
        })
        .collect();
    assert_eq!(
        damages,
        vec![
            (target, 1.0, Some(shots[0]), Some("collide"), "target"),
            (target, 1.0, Some(shots[1]), Some("collide"), "target")
        ]
    );
    let deaths: Vec<Event<&str>> = life
        .iter()
        .flat_map(|l| {
            (0..l.die.len()).map(move |i| {
                (
                    l.die[i],
                    l.die_cause[i].as_str(),
                    l.die_by[i],
                    l.die_hook[i].as_deref(),
                    l.die_kind[i].as_str(),
                )
            })
        })
        .collect();
    assert!(
        deaths.contains(&(shots[0], "die", Some(shots[0]), Some("collide"), "shot")),
        "the first shot called die() in its own collide: {deaths:?}"
    );
    assert!(
        deaths.contains(&(target, "damage", Some(shots[1]), Some("collide"), "target")),
        "the second shot's damage took the target to 0: {deaths:?}"
    );
    assert_eq!(deaths.len(), 3, "two shots and the target: {deaths:?}");
}

#[test]
fn a_critters_story_tells_its_spawn_damage_changes_and_death() {
    let (dir, file) = recorded("target");
    let life = lifecycle(&file);
    let died_at = |id: u64| life.iter().find(|l| l.die.contains(&id)).map(|l| l.step);
    let shots: Vec<u64> = life.iter().flat_map(|l| l.spawn.clone()).collect();
    let name = |id: u64| id_of(id).to_string();

    let story = story_json(&dir, &file, "#0");
    assert_eq!(story["critter"], "#0");
    assert_eq!(story["kind"], "target");
    assert_eq!(story["spawn"]["step"], 0);
    assert_eq!(story["spawn"]["by"], Value::Null, "made by the scene");
    let damages = events(&story, "damage");
    assert_eq!(damages.len(), 2, "{story:#}");
    for (d, shot) in damages.iter().zip(&shots) {
        assert_eq!(d["amount"], 1.0);
        assert_eq!(d["source"], name(*shot).as_str());
        assert_eq!(d["source_kind"], "shot");
        assert_eq!(d["hook"], "collide");
    }
    let death = &story["death"];
    assert_eq!(death["step"], died_at(0).expect("the target died"));
    assert_eq!(death["cause"], "damage");
    assert_eq!(death["by"], name(shots[1]).as_str());
    assert_eq!(death["hook"], "collide");
    // on_damage turned it red and counted the hit: seen at the full state of the first hit.
    let first_hit = damages[0]["step"].as_u64().expect("a step");
    let colours = events(&story, "color");
    assert_eq!(colours.len(), 1, "{story:#}");
    assert_eq!(colours[0]["step"], first_hit);
    assert_eq!(colours[0]["after"], "red");
    let props = events(&story, "props");
    let hits: Vec<(u64, &Value)> = props
        .iter()
        .flat_map(|p| {
            p["changes"]
                .as_array()
                .into_iter()
                .flatten()
                .filter(|c| c["name"] == "hits")
                .map(|c| (p["step"].as_u64().unwrap_or(0), &c["after"]))
        })
        .collect();
    assert_eq!(
        hits,
        vec![(0, &Value::from(0)), (first_hit, &Value::from(1))]
    );
    // The shots touched it: one spell each, in the step of its damage.
    let spells = events(&story, "spell");
    assert_eq!(spells.len(), 2, "{story:#}");
    assert_eq!(spells[0]["partner"], name(shots[0]).as_str());
    assert_eq!(spells[0]["step"], first_hit);
    // The timeline is in step order, the death last.
    let steps: Vec<u64> = story["timeline"]
        .as_array()
        .expect("timeline")
        .iter()
        .map(|e| e["step"].as_u64().expect("step"))
        .collect();
    assert!(steps.windows(2).all(|w| w[0] <= w[1]), "{steps:?}");
    assert_eq!(
        story["timeline"].as_array().and_then(|t| t.last()),
        Some(death)
    );

    // The text tells the same, with ids as they print.
    let o = critterbox_in(&dir, &["inspect", file.to_str().unwrap(), "--critter", "0"]);
    assert!(o.status.success(), "{}", text(&o));
    let out = text(&o);
    assert!(out.contains("spawned by the scene"), "{out}");
    assert!(
        out.contains(&format!(
            "damage 1.0 from {} (shot) in collide",
            name(shots[0])
        )),
        "{out}"
    );
    assert!(
        out.contains(&format!(
            "died: health at or below 0 after damage from {} (shot)'s collide",
            name(shots[1])
        )),
        "{out}"
    );
    assert!(out.contains("colour its kind's -> red"), "{out}");
}

#[test]
fn a_shots_story_names_the_critter_and_hook_that_spawned_it() {
    let (dir, file) = recorded("shot");
    let life = lifecycle(&file);
    let shot = life
        .iter()
        .flat_map(|l| l.spawn.clone())
        .next()
        .expect("a shot");
    let printed = id_of(shot).to_string();
    // The three ways to write the id give the same story.
    let story = story_json(&dir, &file, &printed);
    let bare = printed.trim_start_matches('#').to_string();
    assert_eq!(story_json(&dir, &file, &bare), story);
    assert_eq!(story_json(&dir, &file, &format!("{bare}v0")), story);
    assert_eq!(story["spawn"]["step"], 1);
    assert_eq!(story["spawn"]["by"], "#1");
    assert_eq!(story["spawn"]["by_kind"], "gun");
    assert_eq!(story["spawn"]["hook"], "update");
    assert_eq!(story["death"]["cause"], "die");
    assert_eq!(story["death"]["by"], printed.as_str());
    assert_eq!(story["death"]["hook"], "collide");
    let spells = events(&story, "spell");
    assert_eq!(spells.len(), 1, "{story:#}");
    assert_eq!(spells[0]["partner"], "#0");
    assert_eq!(spells[0]["partner_kind"], "target");
    assert_eq!(
        spells[0]["step"], story["death"]["step"],
        "it died touching"
    );
}

#[test]
fn a_critter_the_file_does_not_hold_and_a_bad_id_are_errors() {
    let (dir, file) = recorded("missing");
    let o = critterbox_in(
        &dir,
        &["inspect", file.to_str().unwrap(), "--critter", "#40v2"],
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("critter #40v2 is not in"), "{}", text(&o));
    let o = critterbox_in(
        &dir,
        &["inspect", file.to_str().unwrap(), "--critter", "shot"],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("is not a critter id"), "{}", text(&o));
}

#[test]
fn export_names_the_kind_of_every_die_and_damage_row() {
    let (dir, file) = recorded("export");
    let rec = Recording::open(&file).expect("readable");
    let out = dir.join("csv");
    export_csv(&rec, &out, false).expect("exported");
    let csv = std::fs::read_to_string(out.join("lifecycle.csv")).expect("lifecycle.csv");
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).expect(name);
    let (event, kind, by, hook) = (col("event"), col("kind"), col("by"), col("hook"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let of = |e: &str| {
        rows.iter()
            .filter(move |r| r[event] == e)
            .collect::<Vec<_>>()
    };
    assert_eq!(of("die").len(), 3);
    assert_eq!(of("damage").len(), 2);
    for r in of("die").iter().chain(&of("damage")) {
        assert!(matches!(r[kind], "shot" | "target"), "{r:?}");
        assert_eq!(r[hook], "collide", "{r:?}");
    }
    for r in of("damage") {
        assert_eq!(r[kind], "target");
        assert!(r[by].starts_with('#'), "the shot that did it: {r:?}");
    }
}

#[test]
fn replay_step_shows_props_and_colours_by_name() {
    let (dir, file) = recorded("replay");
    let life = lifecycle(&file);
    let hit = life
        .iter()
        .find(|l| !l.damage_id.is_empty())
        .map(|l| l.step)
        .expect("a hit");
    let o = critterbox_in(
        &dir,
        &["replay", file.to_str().unwrap(), "--step", &hit.to_string()],
    );
    assert!(o.status.success(), "{}", text(&o));
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    let head = out
        .lines()
        .find(|l| l.starts_with("id\t"))
        .expect("a table header");
    let cols: Vec<&str> = head.split('\t').collect();
    let (color, props) = (
        cols.iter()
            .position(|c| *c == "color")
            .expect("color column"),
        cols.iter()
            .position(|c| *c == "props")
            .expect("props column"),
    );
    let row = |id: &str| -> Vec<String> {
        out.lines()
            .find(|l| l.starts_with(&format!("{id}\t")))
            .unwrap_or_else(|| panic!("no row {id} in\n{out}"))
            .split('\t')
            .map(str::to_string)
            .collect()
    };
    let target = row("#0");
    assert_eq!(target[color], "red");
    assert_eq!(target[props], "hits=1");
    let gun = row("#1");
    assert_eq!(gun[color], "-", "the kind's colour");
    assert_eq!(gun[props], "shots=2");
}

/// The committed sample is a format 1 recording (made before causes were recorded): it still
/// reads, a story is told without causes, and export finds the kinds of its deaths and damage.
#[test]
fn a_format_1_recording_still_reads() {
    let sample = Path::new(ROOT).join("recordings/sample-bullets_vs_player.mcap");
    let rec = Recording::open(&sample).expect("a format 1 file opens");
    assert_eq!(rec.format_version(), 1);
    assert_eq!(
        rec.meta_map.get("format").map(String::as_str),
        Some("critterbox-recording/1")
    );
    let damaged: Vec<u64> = rec
        .lifecycle
        .iter()
        .flat_map(|l| l.damage_id.clone())
        .collect();
    assert!(!damaged.is_empty(), "test setup: the sample has damage");
    assert!(rec.lifecycle.iter().all(|l| l.damage_source.is_empty()));

    let dir = common::tmp_in("story-tests", "format1");
    let player = id_of(damaged[0]).to_string();
    let story = story_json(&dir, &sample, &player);
    assert_eq!(story["format"], 1);
    assert_eq!(story["kind"], "armed_player");
    let damages = events(&story, "damage");
    assert_eq!(
        damages.len(),
        damaged.iter().filter(|&&d| d == damaged[0]).count()
    );
    assert!(damages
        .iter()
        .all(|d| d["known"] == false && d["source"].is_null()));

    let out = dir.join("csv");
    export_csv(&rec, &out, false).expect("exported");
    let csv = std::fs::read_to_string(out.join("lifecycle.csv")).expect("lifecycle.csv");
    for line in csv
        .lines()
        .skip(1)
        .filter(|l| l.contains(",die,") || l.contains(",damage,"))
    {
        let kind = line.split(',').nth(4).unwrap_or("");
        assert!(
            !kind.is_empty(),
            "a die or damage row without its kind: {line}"
        );
    }
}
