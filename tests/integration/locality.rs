//! Where the critters are stored never shows: a world that lays its critters out along its grid
//! every few steps ([`critterbox::Locality`]) runs bit for bit as one that keeps them in id
//! order: the same state hash, the same events in the same order, the same log, the same critters
//! in id order. Built-in scenes and every scene script, and a world whose method changes under it.

use critterbox::scenes::{self, AnyWorld, Scene, SceneParams};
use critterbox::script::{load_scene, ScriptOptions};
use critterbox::{Locality, Method, Vector, World};
use std::path::Path;

/// Lays out every `every` steps from two critters on.
fn often(every: u64) -> Locality {
    Locality {
        every,
        min_critters: 2,
        disorder: 0.0,
    }
}

const NEVER: Locality = Locality {
    every: 0,
    min_critters: 0,
    disorder: 0.0,
};

/// Everything a step shows: the hash, the events and log, the critters in id order.
fn seen(w: &AnyWorld) -> (u64, String, String) {
    fn shown<V: Vector>(w: &World<V>) -> (String, String) {
        (
            format!("{:?}", w.events()),
            format!("{:?}", w.critters().iter().collect::<Vec<_>>()),
        )
    }
    let (events, critters) = match w {
        AnyWorld::D2(w) => shown(w),
        AnyWorld::D3(w) => shown(w),
    };
    (w.state_hash(), events, critters)
}

/// Runs `a` (laid out often) and `b` (never) side by side for `steps`, comparing every step;
/// returns how many steps `a` ended laid out, and how many collisions there were.
fn side_by_side(name: &str, mut a: Scene, mut b: Scene, steps: u64) -> (u64, usize) {
    a.world.set_locality(often(3));
    b.world.set_locality(NEVER);
    let (mut laid_out, mut collisions) = (0, 0);
    for step in 0..steps {
        let (ra, rb) = (a.step(), b.step());
        assert_eq!(
            ra.as_ref().map_err(ToString::to_string),
            rb.as_ref().map_err(ToString::to_string),
            "{name}: step {step}"
        );
        assert!(!b.world.is_laid_out(), "{name}: NEVER laid out");
        laid_out += u64::from(a.world.is_laid_out());
        collisions += a.world.stats().collisions;
        let (sa, sb) = (seen(&a.world), seen(&b.world));
        assert_eq!(sa.0, sb.0, "{name}: state hash at step {step}");
        assert_eq!(sa.1, sb.1, "{name}: events at step {step}");
        assert_eq!(sa.2, sb.2, "{name}: critters at step {step}");
        if matches!(ra, Ok(Some(_)) | Err(_)) {
            break;
        }
    }
    (laid_out, collisions)
}

fn builtin(name: &str, n: Option<usize>) -> Scene {
    let params = SceneParams {
        n,
        seed: 7,
        ..SceneParams::default()
    };
    scenes::builtin(name, &params).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn built_in_scenes_laid_out_run_as_in_id_order() {
    for (name, n, steps) in [
        ("gas", Some(3_000), 60),
        ("gas3d", Some(1_500), 40),
        ("gas-wrap", Some(2_000), 60),
        ("pegs", None, 300),
        ("billiards", None, 200),
        ("cradle", None, 150),
    ] {
        let (laid_out, collisions) = side_by_side(name, builtin(name, n), builtin(name, n), steps);
        // Every built-in scene runs under `discrete`, so the layout really happened.
        assert!(
            laid_out > steps / 2,
            "{name}: laid out {laid_out} of {steps} steps"
        );
        assert!(collisions > 0, "{name}: test setup: something collided");
    }
}

#[test]
fn scene_scripts_laid_out_run_as_in_id_order() {
    let mut scripts: Vec<_> = std::fs::read_dir(Path::new("scripts/scenes"))
        .expect("scripts/scenes")
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "rhai"))
        .collect();
    scripts.sort();
    assert!(
        scripts.len() >= 5,
        "test setup: the scene scripts are there"
    );
    let (mut laid_out_scenes, mut hooked) = (0, 0);
    for path in &scripts {
        let name = path.display().to_string();
        let load = || load_scene(path, &[], &ScriptOptions::default()).expect("loads");
        let (laid_out, _) = side_by_side(&name, load(), load(), 240);
        laid_out_scenes += usize::from(laid_out > 0);
        hooked += usize::from(std::fs::read_to_string(path).unwrap().contains("kind"));
    }
    // The scripts under `discrete` (all but the pile) were laid out while their hooks ran.
    assert!(
        laid_out_scenes + 1 >= scripts.len(),
        "laid out in {laid_out_scenes} of {} scripts",
        scripts.len()
    );
    assert!(hooked > 0, "test setup: some scripts define kinds");
}

#[test]
fn a_method_that_keeps_state_by_slot_sees_the_critters_in_id_order() {
    let (mut a, mut b) = (builtin("gas", Some(2_000)), builtin("gas", Some(2_000)));
    a.world.set_locality(often(2));
    b.world.set_locality(NEVER);
    let mut laid_out = std::collections::BTreeMap::new();
    for (method, steps) in [
        (Method::Discrete, 9),
        (Method::Event, 5),
        (Method::Solve(4), 5),
        (Method::Auto, 5),
        (Method::Substep(2), 9),
        (Method::Swept, 5),
    ] {
        a.world.set_method(method).unwrap();
        b.world.set_method(method).unwrap();
        for step in 0..steps {
            a.step().unwrap();
            b.step().unwrap();
            if matches!(method, Method::Discrete | Method::Substep(_)) {
                laid_out.insert(method.to_string(), a.world.is_laid_out());
            } else {
                assert!(!a.world.is_laid_out(), "{method} step {step}: laid out");
            }
            assert_eq!(seen(&a.world), seen(&b.world), "{method} step {step}");
        }
    }
    // Laid out again after each method that keeps state by slot.
    assert_eq!(laid_out.len(), 2);
    assert!(laid_out.values().all(|&l| l), "{laid_out:?}");
}
