//! The mixed scenes of docs/stability.md (`critterbox::scenes::mixed`), part by part, and where
//! `solve:n` fails (`critterbox::scenes::solve_limits`), against laws and physical bounds: an
//! elastic strike hands all the momentum on, a resting pile does not sink or move, nothing
//! leaves a closed box, an elastic gas keeps its energy, Henderson's equation of state. Each
//! fixed method's failure is asserted where it fails and its success where it holds; `auto` only
//! where it will stay true.

use critterbox::scenes::mixed::{
    gas_above_pile_reading, gas_above_pile_world, gas_drift, Mixed, MIXED, MIXED_3D,
};
use critterbox::scenes::solve_limits::{cradle_reading, gas_reading};
use critterbox::{Method, Vector};
use glam::{DVec2, DVec3};

/// A relative error that a result exact up to rounding may carry.
const ROUND_OFF: f64 = 1e-12;

/// The event flight's exactness target for energy (`tests/integration/methods.rs`): round-off
/// carried through many collisions and parabolas.
const EXACT_FLIGHT: f64 = 1e-10;

/// The scene of `list` named `name`, run under `method`: its parts' errors by part name.
fn run(list: &[Mixed], name: &str, method: Method) -> Vec<(&'static str, f64)> {
    let scene = list.iter().find(|s| s.name == name).expect("a mixed scene");
    let errors = (scene.run)(method).unwrap();
    assert_eq!(errors.len(), scene.parts.len());
    scene.parts.iter().map(|p| p.name).zip(errors).collect()
}

/// The error of `part` in `errors`.
fn part(errors: &[(&str, f64)], part: &str) -> f64 {
    errors.iter().find(|(p, _)| *p == part).expect("a part").1
}

/// Both tables: the 2D scene `name` and its 3D twin.
fn both(name: &str) -> [(&'static [Mixed], String); 2] {
    [
        (MIXED, name.to_string()),
        (MIXED_3D, format!("{name} (3D)")),
    ]
}

/// The pile beside the cradle under the cheap fixed methods: discrete and 8 substeps strike the
/// falling cradle exactly (only the last ball moves on, relative to the common fall) but let the
/// jumbled pile sink into itself (discrete over a radius: 1.94, 3D 1.71; substep:8 0.53 and
/// 0.18); `solve:8` holds the pile (0.066 and 0.074 radii) but spreads the cradle's momentum,
/// more than the striker's whole momentum ending outside the last ball (2.5 and 1.6).
#[test]
fn beside_a_falling_cradle_discrete_sinks_the_pile_and_solve_breaks_the_cradle() {
    for (list, name) in both("pile beside cradle") {
        let discrete = run(list, &name, Method::Discrete);
        assert!(
            part(&discrete, "cradle") <= ROUND_OFF,
            "{name}: {discrete:?}"
        );
        assert!(part(&discrete, "pile") > 1.0, "{name}: {discrete:?}");
        let substep = run(list, &name, Method::Substep(8));
        assert!(part(&substep, "cradle") <= ROUND_OFF, "{name}: {substep:?}");
        assert!(part(&substep, "pile") > 0.1, "{name}: {substep:?}");
        let solve = run(list, &name, Method::Solve(8));
        assert!(part(&solve, "cradle") > 1.0, "{name}: {solve:?}");
        assert!(part(&solve, "pile") < 0.15, "{name}: {solve:?}");
    }
}

/// `auto` by islands (`src/method/islands.rs`) takes each part's method: the falling cradle
/// flies by exact events (to round-off) while the pile beside it is solved and held within the
/// solve's bound; the gas above a pile flies by events clear of it and keeps its energy better
/// than the best cheap fixed method, 8 substeps (auto 4.2e-4 against 6.7e-3, 3D 2.2e-3 against
/// 5.0e-3), while the pile is solved.
#[test]
fn auto_flies_the_cradle_and_the_gas_by_events_and_solves_the_piles() {
    for (list, name) in both("pile beside cradle") {
        let auto = run(list, &name, Method::Auto);
        assert!(part(&auto, "cradle") <= ROUND_OFF, "{name}: {auto:?}");
        assert!(part(&auto, "pile") < 0.15, "{name}: {auto:?}");
    }
    for (list, name) in both("gas above pile") {
        let auto = run(list, &name, Method::Auto);
        let substep = run(list, &name, Method::Substep(8));
        assert!(
            part(&auto, "gas energy") < part(&substep, "gas energy"),
            "{name}: auto {auto:?}, substep:8 {substep:?}"
        );
        assert!(part(&auto, "pile") < 0.02, "{name}: {auto:?}");
    }
}

/// The pile beside the cradle under the exact methods, ignored for their time (16 to 64 s in
/// release): they strike the cradle to round-off, but the pile's resting contacts run their steps
/// out of events and end them in discrete substeps, and it sinks (0.21 and 0.23 radii, 3D 0.12
/// and 0.13). `cargo test --release -p critterbox --test integration -- --ignored exact_methods`.
#[test]
#[ignore]
fn beside_a_falling_cradle_the_exact_methods_strike_exactly_and_sink_the_pile() {
    for (list, name) in both("pile beside cradle") {
        for m in [Method::Swept, Method::Event] {
            let errors = run(list, &name, m);
            assert!(
                part(&errors, "cradle") <= ROUND_OFF,
                "{name} {m}: {errors:?}"
            );
            assert!(part(&errors, "pile") > 0.05, "{name} {m}: {errors:?}");
        }
    }
}

/// Bullets fired at 100 (1.67 a step) into a resting pile in a closed box: whole discrete steps
/// carry them through the floor, the walls or the lid (discrete 4 of 4, 3D 4; solve:8 2, 3D 4),
/// and the discrete step lets the pile sink (0.75 and 1.19 radii). Swept and event never let
/// anything out, and the pile stays put (a thousandth of a radius: the bullets are a thousandth
/// of a ball's mass) with no overlap to speak of; solve:8 holds it within its slop. Auto solves
/// the pile and flies the bullets after each step against it (`method::bullets`): it lets
/// nothing out and holds the pile within the same bounds as solve:8 (the pile moves as the
/// solve settles it alone, 0.066 radii, and the bullets' kicks add a few thousandths).
#[test]
fn bullets_leave_the_box_only_in_whole_discrete_steps_and_the_pile_stays_put() {
    for (list, name) in both("bullets into pile") {
        let dim3 = name.ends_with("(3D)");
        for m in [Method::Discrete, Method::Solve(8)] {
            let errors = run(list, &name, m);
            assert!(part(&errors, "escaped") >= 1.0, "{name} {m}: {errors:?}");
        }
        let discrete = run(list, &name, Method::Discrete);
        assert!(part(&discrete, "pile moved") > 0.3, "{name}: {discrete:?}");
        assert!(
            part(&discrete, "pile overlap") > 0.1,
            "{name}: {discrete:?}"
        );
        let solve = run(list, &name, Method::Solve(8));
        assert!(part(&solve, "pile moved") < 0.15, "{name}: {solve:?}");
        assert!(part(&solve, "pile overlap") < 0.02, "{name}: {solve:?}");
        // The 3D event run takes 9 s in release: it is checked by the ignored test below.
        let exact: &[Method] = if dim3 {
            &[Method::Swept]
        } else {
            &[Method::Swept, Method::Event]
        };
        let auto = run(list, &name, Method::Auto);
        assert_eq!(part(&auto, "escaped"), 0.0, "{name}: {auto:?}");
        assert!(part(&auto, "pile moved") < 0.15, "{name}: {auto:?}");
        assert!(part(&auto, "pile overlap") < 0.02, "{name}: {auto:?}");
        for &m in exact {
            let errors = run(list, &name, m);
            assert_eq!(part(&errors, "escaped"), 0.0, "{name} {m}: {errors:?}");
            assert!(part(&errors, "pile moved") < 0.01, "{name} {m}: {errors:?}");
            assert!(
                part(&errors, "pile overlap") < 0.005,
                "{name} {m}: {errors:?}"
            );
        }
    }
}

/// The event method's 3D cell of the bullets' rows (9 s in release).
#[test]
#[ignore]
fn no_bullet_leaves_the_3d_box_under_event() {
    let errors = run(MIXED_3D, "bullets into pile (3D)", Method::Event);
    assert_eq!(part(&errors, "escaped"), 0.0, "{errors:?}");
    assert!(part(&errors, "pile moved") < 0.01, "{errors:?}");
}

/// The gas above the pile: nothing but the pile exchanges energy with the elastic gas, so over
/// the steps clear of the pile its energy (kinetic plus potential) is kept by an exact flight.
/// Discrete steps lose it (the semi-implicit step is off by g dt v / 2 a step: 5.4e-2, 3D
/// 4.0e-2; solve:8 6.1e-2 and 4.0e-2) and let the pile sink (0.13 and 0.11 radii), which
/// solve:8 holds within its slop.
#[test]
fn a_gas_above_a_pile_loses_energy_in_discrete_steps_and_solve_holds_the_pile() {
    for (list, name) in both("gas above pile") {
        for m in [Method::Discrete, Method::Solve(8)] {
            let errors = run(list, &name, m);
            assert!(part(&errors, "gas energy") > 0.01, "{name} {m}: {errors:?}");
        }
        let discrete = run(list, &name, Method::Discrete);
        assert!(part(&discrete, "pile") > 0.05, "{name}: {discrete:?}");
        for m in [Method::Solve(8), Method::Auto] {
            let errors = run(list, &name, m);
            assert!(part(&errors, "pile") < 0.02, "{name} {m}: {errors:?}");
        }
    }
}

/// The gas's measure is exact where the flight is: the event method on the gas alone (the pile
/// removed) keeps its energy to round-off over the same steps. With the pile, whose resting
/// contacts run event's steps out of their budget (finished in discrete substeps for everyone),
/// the gas drifts (1.6e-2): ignored for its time, 9 s in release.
#[test]
fn the_event_flight_keeps_the_gas_s_energy_where_no_pile_runs_it_out_of_events() {
    fn alone<V: Vector>() {
        let (mut w, gas, pile) = gas_above_pile_world::<V>(Method::Event).unwrap();
        for id in pile {
            w.remove(id).unwrap();
        }
        let drift = gas_drift(&mut w, &gas, &[], 120).unwrap();
        assert_eq!(drift.clear_steps, 120);
        assert!(drift.drift <= EXACT_FLIGHT, "{drift:?}");
    }
    alone::<DVec2>();
    alone::<DVec3>();
}

/// See [`the_event_flight_keeps_the_gas_s_energy_where_no_pile_runs_it_out_of_events`].
#[test]
#[ignore]
fn beside_a_resting_pile_the_event_flight_loses_the_gas_s_energy() {
    let (drift, overlap) = gas_above_pile_reading::<DVec2>(Method::Event).unwrap();
    assert!(drift.clear_steps >= 20, "{drift:?}");
    assert!(drift.drift > 1e-3, "{drift:?}");
    assert!(overlap < 0.02, "{overlap}");
}

/// The gas's measure is not vacuous: the gas spends steps clear of the pile under every method.
#[test]
fn the_gas_spends_steps_clear_of_the_pile() {
    for m in [Method::Discrete, Method::Solve(8)] {
        let (drift, _) = gas_above_pile_reading::<DVec2>(m).unwrap();
        assert!(drift.clear_steps >= 20, "{m}: {drift:?}");
        let (drift, _) = gas_above_pile_reading::<DVec3>(m).unwrap();
        assert!(drift.clear_steps >= 20, "{m} (3D): {drift:?}");
    }
}

/// Henderson's equation of state for hard disks: `Z = (1 + phi^2 / 8) / (1 - phi)^2`.
fn henderson(phi: f64) -> f64 {
    (1.0 + phi * phi / 8.0) / ((1.0 - phi) * (1.0 - phi))
}

/// `solve:8` in an elastic gas without gravity (the standard gas, 1,000 disks at packing 0.2,
/// periodic): its simultaneous solve does not keep the kinetic energy, which the event flight
/// keeps to round-off over the same number of impacts.
#[test]
fn solve_loses_an_elastic_gas_s_energy_and_event_keeps_it() {
    let event = gas_reading(Method::Event, 20_000).unwrap();
    assert!(event.impacts >= 20_000, "{event:?}");
    assert!(event.energy_drift.abs() <= ROUND_OFF, "{event:?}");
    let solve = gas_reading(Method::Solve(8), 20_000).unwrap();
    assert!(solve.impacts >= 20_000, "{solve:?}");
    assert!(solve.energy_drift < -1e-6, "{solve:?}");
}

/// The long version (a million impacts, ignored): the event flight reads the pressure of
/// Henderson's equation of state and keeps the energy to round-off; `solve:8` loses energy (its
/// pressure is printed beside event's, not asserted). Prints both readings (docs/stability.md, "Where solve fails"):
/// `cargo test --release -p critterbox --test integration -- --ignored --nocapture million_impacts`.
#[test]
#[ignore]
fn solve_over_a_million_impacts_loses_energy_and_event_reads_henderson_s_pressure() {
    let z = henderson(0.2);
    let event = gas_reading(Method::Event, 1_000_000).unwrap();
    let solve = gas_reading(Method::Solve(8), 1_000_000).unwrap();
    println!("Henderson Z = {z:.4}\nevent: {event:?}\nsolve:8: {solve:?}");
    assert!(event.energy_drift.abs() <= 1e-10, "{event:?}");
    assert!((event.z / z - 1.0).abs() < 0.005, "{event:?} against {z}");
    assert!(solve.energy_drift < -1e-3, "{solve:?}");
}

/// Newton's cradle without gravity: the exact methods and the discrete step stop the striker and
/// move the last ball on at its speed, keeping the energy; `solve:8` sends the striker back and
/// loses energy (a simultaneous solve is not a sequence of pair collisions).
#[test]
fn solve_makes_the_cradle_s_striker_rebound_and_loses_energy() {
    for m in [Method::Discrete, Method::Swept, Method::Event] {
        let c = cradle_reading(m).unwrap();
        assert!(c.striker.abs() <= ROUND_OFF, "{m}: {c:?}");
        assert!((c.last - 1.0).abs() <= ROUND_OFF, "{m}: {c:?}");
        assert!((c.energy_kept - 1.0).abs() <= ROUND_OFF, "{m}: {c:?}");
    }
    let c = cradle_reading(Method::Solve(8)).unwrap();
    println!("solve:8 cradle: {c:?}");
    assert!(c.striker < -0.01, "{c:?}");
    assert!(c.energy_kept < 0.95, "{c:?}");
}
