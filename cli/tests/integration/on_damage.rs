//! `on_damage(me, amount, source)` as `critterbox check` knows it: a hook of three parameters,
//! whose misspellings and wrong arities are warned about like any other hook's.

use crate::common;
use common::{critterbox_in, text};

#[test]
fn check_knows_on_damage_as_a_hook_of_three_parameters() {
    let dir = common::tmp_in("on-damage-tests", "check");
    std::fs::create_dir_all(dir.join("kinds")).expect("kinds dir");
    let write = |name: &str, body: &str| {
        let path = dir.join("kinds").join(name);
        std::fs::write(&path, body).expect("write");
        path.display().to_string()
    };
    let good = write(
        "good.rhai",
        "fn on_damage(me, amount, source) { me.health += amount; }\n",
    );
    let short = write("short.rhai", "fn on_damage(me, amount) {}\n");
    let typo = write("typo.rhai", "fn on_damag(me, amount, source) {}\n");

    let o = critterbox_in(&dir, &["check", "--strict", &good]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "three parameters are right: {}",
        text(&o)
    );

    let o = critterbox_in(&dir, &["check", &short]);
    assert!(
        text(&o).contains(&format!("{short}:1:")) && text(&o).contains("on_damage takes 3"),
        "{}",
        text(&o)
    );
    let o = critterbox_in(&dir, &["check", &typo]);
    assert!(
        text(&o).contains("did you mean 'on_damage'"),
        "{}",
        text(&o)
    );
}
