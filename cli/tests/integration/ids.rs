//! Critter ids as users meet them: a hook's `me.id`, for a critter given a dead one's index, is
//! the id the run's log, the recording and the CSV export write for it.

use crate::common::{critterbox_in, text, tmp_in};
use critterbox::recording::reader::state_at;
use critterbox::recording::schema::id_of;
use critterbox::recording::Recording;

/// A ball with index 0 dies before the teller is spawned, so the teller is given index 0 again.
const SCENE: &str = r#"
let w = world(#{ dim: 2, size: vec(20, 20), gravity: vec(0, 0), steps: 2 });
let first = spawn("ball", #{ pos: vec(5, 5) });
first.die();
spawn("teller", #{ pos: vec(5, 5) });
"#;

const TELLER: &str = "fn update(me, dt) {\n    log(`teller is ${me.id}`);\n}\n";

#[test]
fn a_hooks_id_is_the_one_the_log_the_recording_and_the_export_write() {
    let dir = tmp_in("ids", "log_recording_export");
    std::fs::create_dir_all(dir.join("kinds")).expect("kinds folder");
    std::fs::write(dir.join("scene.rhai"), SCENE).expect("scene");
    std::fs::write(dir.join("kinds/teller.rhai"), TELLER).expect("kind");
    let o = critterbox_in(
        &dir,
        &[
            "run",
            "scene.rhai",
            "--record",
            "run.mcap",
            "--record-every",
            "1",
        ],
    );
    let out = text(&o);
    assert!(o.status.success(), "{out}");

    // What the hook logged, once per step.
    let logged: Vec<&str> = out
        .lines()
        .filter_map(|l| l.split("teller is ").nth(1))
        .collect();
    assert_eq!(logged.len(), 2, "one line per step: {out}");
    assert_eq!(logged[0], logged[1], "one id for the whole run: {out}");
    let id = logged[0];
    // Index 0's second critter: the generation tells it from the ball that died.
    assert_eq!(id, "#0v1", "{out}");

    // The recording's state names the teller by the same text...
    let file = dir.join("run.mcap");
    let state = state_at(&file, 1)
        .expect("the recording reads")
        .expect("a full state at step 1");
    let teller = (0..state.len())
        .find(|&i| state.kind_name(i) == "teller")
        .expect("the teller is recorded");
    assert_eq!(id_of(state.id[teller]).to_string(), id);
    // ...and its log keeps the line as the hook wrote it.
    let rec = Recording::open(&file).expect("the recording opens");
    assert!(
        rec.log
            .iter()
            .flat_map(|m| &m.lines)
            .any(|l| l == &format!("teller is {id}")),
        "{:?}",
        rec.log
    );

    // The CSV export writes the same id in the teller's rows.
    let o = critterbox_in(&dir, &["export", "run.mcap", "--csv", "csv"]);
    assert!(o.status.success(), "{}", text(&o));
    let states = std::fs::read_to_string(dir.join("csv/states.csv")).expect("states.csv");
    assert!(
        states
            .lines()
            .any(|l| l.contains(&format!(",{id},teller,"))),
        "{states}"
    );
}
