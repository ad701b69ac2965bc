//! The pairs stage against its parts taken one by one: the fused passes give the lists of
//! the rules and the narrow phase one after the other, and the move's check of the Verlet
//! list misses nothing a full check finds.

use super::*;
use crate::critter::CritterId;
use crate::critter::CritterSpec;
use crate::parallel::PARALLEL_MIN;
use crate::step::motion;
use crate::wall::WallBox;
use crate::world::tests::gas;
use crate::world::World;
use glam::DVec2;

/// One move of the world's critters by its dt, as a step makes it; what it reports.
fn move_once(w: &mut World<DVec2>) -> MoveReport {
    let dt = w.state.dt;
    let check = w.pairs.move_check();
    motion::run(&mut w.state, dt, &[], &check)
}

/// The rules and narrow stages in one pass give the lists of the two stages one after the
/// other, on one thread and in parallel chunks, and so do they when done with the broad
/// phase's re-test of the kept list, on a gas with walls that has settled into many
/// candidate pairs.
#[test]
fn rules_and_narrow_phase_in_one_pass_match_them_one_after_the_other() {
    let check = || {
        let mut w = crate::scenes::gas::<DVec2>(&crate::scenes::GasParams {
            n: 40_000,
            packing: 0.45,
            ..Default::default()
        })
        .unwrap();
        let mut checked = 0;
        for _ in 0..30 {
            w.step().unwrap();
            let (state, p) = (&mut w.state, &mut w.pairs);
            let dt = state.dt;
            p.broad_phase(state, dt, None, &[], false);
            if p.candidates.len() < PARALLEL_PAIRS {
                continue;
            }
            p.rules_in_order(state).unwrap();
            p.narrow_phase_in_order(state).unwrap();
            p.sort_contacts(&state.critters);
            let in_order = (p.ruled.len(), p.contacts.clone(), p.wall_pairs.clone());
            assert!(!in_order.1.is_empty() && !in_order.2.is_empty());
            let ruled = p.rules_and_narrow_phase_in_one_pass(state);
            p.sort_contacts(&state.critters);
            let fused = (
                ruled.expect("no roles to ask"),
                p.contacts.clone(),
                p.wall_pairs.clone(),
            );
            assert_eq!(fused, in_order);
            // And with the broad phase's re-test, chunk by chunk.
            p.contacts.clear();
            p.wall_pairs.clear();
            let dt = state.dt;
            let Narrowed::WithRetest(ruled) = p.broad_phase(state, dt, None, &[], true) else {
                panic!("not done with the re-test");
            };
            p.sort_contacts(&state.critters);
            let with_retest = (ruled, p.contacts.clone(), p.wall_pairs.clone());
            assert_eq!(with_retest, in_order);
            checked += 1;
        }
        checked
    };
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let checked = pool.install(check);
        assert!(checked >= 5, "only {checked} steps had enough candidates");
    }
}

/// The broad phase's objects as a fresh pass over the critters gives them.
fn fresh_objects<V: Vector>(w: &World<V>) -> Vec<BroadObject<V>> {
    let critters = &w.state.critters;
    let pad = critters
        .iter()
        .filter(|c| c.alive && !c.is_wall())
        .map(|c| c.radius)
        .fold(0.0, f64::max);
    (0..critters.slot_count() as u32)
        .filter_map(|i| broad_object(critters.slot(i)?, i, pad))
        .collect()
}

/// A move and a broad phase, whose pairs must be those a fresh grid finds in fresh objects;
/// true when the Verlet list was rebuilt or mended.
fn check_pairs(w: &mut World<DVec2>, what: &str) -> bool {
    let changes = |w: &World<DVec2>| {
        let d = w.diagnostics();
        d.list_rebuilds + d.list_repairs
    };
    let rebuilds = changes(w);
    let moved = move_once(w);
    let dt = w.dt();
    w.pairs
        .broad_phase(&mut w.state, dt, Some(moved), &[], false);
    assert_fresh_pairs(w, what);
    changes(w) > rebuilds
}

/// The broad phase's last pairs must be those a fresh grid finds in fresh objects.
fn assert_fresh_pairs(w: &World<DVec2>, what: &str) {
    let mut fresh = Vec::new();
    BroadPhase::new(BroadPhaseMode::Grid).find_pairs(&fresh_objects(w), &w.state.topo, &mut fresh);
    let sorted = |pairs: &[(u32, u32)]| {
        let mut v: Vec<_> = pairs.iter().map(|&(a, b)| (a.min(b), a.max(b))).collect();
        v.sort_unstable();
        v
    };
    assert_eq!(sorted(&w.pairs.candidates), sorted(&fresh), "{what}");
}

/// The slots the move notes as having left their bound of the Verlet list are exactly those
/// a full check of every slot finds, in order, so a repair may mend them without a pass of
/// its own; and the pairs stay those of a fresh grid through the repairs.
#[test]
fn the_move_notes_every_slot_that_left_its_bound() {
    for n in [3_000, PARALLEL_MIN + 5000] {
        let mut w = gas(n);
        // A few fast disks leave their bounds every few steps, too few to rebuild for.
        let ids: Vec<CritterId> = w.critters().iter().map(|c| c.id()).collect();
        for id in ids.iter().step_by(97) {
            if let Some(c) = w.get_mut(*id).filter(|c| !c.is_wall()) {
                c.vel *= 20.0;
            }
        }
        let (mut noted, mut repairs) = (0, 0);
        for step in 0..40 {
            let before = w.diagnostics().list_repairs;
            let moved = move_once(&mut w);
            let slots = w.state.critters.slot_slice();
            let full: Vec<u32> = (0..slots.len())
                .filter(|&i| {
                    let o = slots[i]
                        .as_ref()
                        .and_then(|c| broad_object(c, i as u32, 0.0));
                    !w.pairs.broad.list_holds(&w.state.topo, i, o.as_ref())
                        && !slots[i].as_ref().is_some_and(|c| c.alive && c.is_wall())
                })
                .map(|i| i as u32)
                .collect();
            if moved.escapes.complete {
                assert_eq!(moved.escapes.slots, full, "n {n}, step {step}");
                noted += full.len();
            }
            let dt = w.dt();
            w.pairs
                .broad_phase(&mut w.state, dt, Some(moved), &[], false);
            assert_fresh_pairs(&w, &format!("n {n}, step {step}"));
            repairs += w.diagnostics().list_repairs - before;
        }
        assert!(
            noted > 0 && repairs > 0,
            "n {n}: {noted} noted, {repairs} repairs"
        );
    }
}

/// Above PARALLEL_MIN the move checks each critter against the Verlet list and the broad
/// phase the walls: a critter teleported, removed or spawned onto another, one grown, and a
/// wall put down across the gas each make the list be rebuilt or mended, and the pairs are
/// always those of a fresh grid.
#[test]
fn the_move_s_check_of_the_verlet_list_misses_no_change() {
    let mut w = gas(PARALLEL_MIN + 5000);
    assert!(!w.state.walls.is_empty(), "the gas has walls");
    assert!(check_pairs(&mut w, "first step"), "the first step builds");
    assert!(
        !check_pairs(&mut w, "second step"),
        "a quiet step keeps the list"
    );
    let disks: Vec<CritterId> = w
        .critters()
        .iter()
        .filter(|c| !c.is_wall())
        .map(|c| c.id())
        .collect();
    let (a, b, c) = (disks[100], disks[20_000], disks[7000]);

    let there = w.get(b).expect("there").pos;
    w.get_mut(a).expect("there").pos = there;
    assert!(check_pairs(&mut w, "a teleport"));
    assert!(w
        .pairs
        .candidates
        .iter()
        .any(|&(p, q)| [p, q] == [a.index, b.index] || [q, p] == [a.index, b.index]));
    assert!(!check_pairs(&mut w, "a quiet step"));

    w.remove(c).expect("there");
    assert!(check_pairs(&mut w, "a removal"));
    let there = w.get(b).expect("there").pos;
    let spawned = w.spawn(CritterSpec::new("ball", there)).expect("spawns");
    assert_eq!(spawned.index, c.index, "the freed slot is reused");
    assert!(check_pairs(&mut w, "a spawn onto a critter"));
    assert!(!check_pairs(&mut w, "a quiet step"));

    w.get_mut(disks[300]).expect("there").radius *= 4.0;
    assert!(check_pairs(&mut w, "a critter grown"));

    // A wall in a freed slot: only the broad phase's check of the walls sees it. A wall may
    // not be put down through critters, so its place is cleared first.
    let middle = 0.5 * (w.state.topo.min + w.state.topo.max);
    let wall = WallBox::aligned(
        middle - DVec2::new(20.0, 0.5),
        middle + DVec2::new(20.0, 0.5),
    )
    .expect("a wall");
    for id in w.state.critters_under(&wall) {
        if id != disks[400] {
            w.remove(id).expect("there");
        }
    }
    assert!(check_pairs(&mut w, "removals"));
    w.remove(disks[400]).expect("there");
    assert!(check_pairs(&mut w, "a removal"));
    let id = w.add_wall(wall).expect("added");
    assert_eq!(id.index, disks[400].index, "the freed slot is reused");
    let slots = w.state.critters.slot_count();
    assert!(check_pairs(&mut w, "a wall put down"));
    assert_eq!(w.state.critters.slot_count(), slots);
    assert!(w
        .pairs
        .candidates
        .iter()
        .any(|&(p, q)| p == id.index || q == id.index));
    assert!(!check_pairs(&mut w, "a quiet step"));
}
