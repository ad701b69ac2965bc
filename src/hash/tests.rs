//! The state hasher, and the critters' passes: every bit of every word counts, and the
//! AVX-512 passes give the portable passes' bits.

use super::critters::{moving_pass, pass, portable_moving_pass, portable_pass, Pass, MOVING, SETS};
use super::{StateHasher, LANES};
use crate::critter::{Critter, CritterId, PropValue};
use crate::method::Method;
use crate::scenes::{builtin, AnyWorld, SceneParams};
use crate::vector::Vector;
use crate::world::World;
#[test]
fn one_bit_changes_the_hash() {
    let mut a = StateHasher::default();
    let mut b = StateHasher::default();
    a.float(1.0);
    b.float(f64::from_bits(1.0f64.to_bits() ^ 1));
    assert_ne!(a.finish(), b.finish());
    let mut c = StateHasher::default();
    c.float(0.0);
    let mut d = StateHasher::default();
    d.float(-0.0);
    assert_ne!(c.finish(), d.finish());
}

#[test]
fn every_bit_of_every_lane_counts() {
    let base = [1u64, 2, 3, 4, 5, 6, 7, 8];
    let hash = |w: [u64; LANES]| {
        let mut h = StateHasher::default();
        h.words(w);
        h.words(base);
        h.finish()
    };
    let h0 = hash(base);
    for lane in 0..LANES {
        for bit in 0..64 {
            let mut w = base;
            w[lane] ^= 1 << bit;
            assert_ne!(hash(w), h0, "lane {lane} bit {bit}");
        }
    }
}

fn scene(name: &str) -> AnyWorld {
    let params = SceneParams {
        n: Some(40),
        ..SceneParams::default()
    };
    let mut scene = builtin(name, &params).expect("builds");
    for _ in 0..5 {
        scene.step().expect("steps");
    }
    scene.world
}

/// Both passes over `w`'s critters: the lanes and the totals.
fn both<V: Vector>(w: &World<V>) -> (Pass<V>, Pass<V>) {
    let slots = w.critters().in_id_order();
    let (mut p1, mut p2) = (StateHasher::default(), StateHasher::default());
    let fast = pass(slots, &mut p1);
    let portable = portable_pass(slots, &mut p2);
    assert_eq!(p1.finish(), p2.finish(), "properties");
    // The moving passes give the first lanes and the same totals.
    for m in [moving_pass(slots), portable_moving_pass(slots)] {
        assert_eq!(m.lanes.as_flattened(), &portable.lanes[..SETS * MOVING]);
        assert_eq!(m.energy.to_bits(), portable.energy.to_bits());
        assert_eq!(bits_of(m.momentum), bits_of(portable.momentum));
    }
    (fast, portable)
}

/// The lanes and the totals' bits (a wall made free has infinite mass: NaN totals).
fn bits<V: Vector>(p: &Pass<V>) -> (Vec<u64>, u64, Vec<u64>) {
    (p.lanes.to_vec(), p.energy.to_bits(), bits_of(p.momentum))
}

fn bits_of<V: Vector>(v: V) -> Vec<u64> {
    (0..V::DIM).map(|a| v.get(a).to_bits()).collect()
}

fn flip(x: &mut f64, bit: u32) {
    *x = f64::from_bits(x.to_bits() ^ 1 << bit);
}

fn flip_axis<V: Vector>(v: &mut V, axis: usize, bit: u32) {
    let mut x = v.get(axis);
    flip(&mut x, bit);
    v.set(axis, x);
}

/// Every bit of every hashed field of one critter (a disk and a wall, in turn), flipped
/// alone, changes the world's hash, and both passes agree on every one of those worlds.
fn every_bit_counts<V: Vector>(mut w: World<V>) {
    let (fast, portable) = both(&w);
    assert_eq!(fast, portable);
    assert_eq!(fast.energy, w.kinetic_energy());
    assert_eq!(fast.momentum, w.momentum());
    let h0 = w.state_hash();
    let disk = w
        .critters()
        .iter()
        .find(|c| !c.is_wall())
        .expect("a disk")
        .id;
    let wall = w
        .critters()
        .iter()
        .find(|c| c.is_wall())
        .expect("a wall")
        .id;
    type Flip<V> = Box<dyn Fn(&mut Critter<V>, u32)>;
    type Float<V> = fn(&mut Critter<V>) -> &mut f64;
    type Other<V> = fn(&mut Critter<V>, u32);
    // Each entry flips bit `b` of one field.
    let mut fields: Vec<(String, u32, Flip<V>)> = Vec::new();
    for axis in 0..V::DIM {
        fields.push((
            format!("pos[{axis}]"),
            64,
            Box::new(move |c, b| flip_axis(&mut c.pos, axis, b)),
        ));
        fields.push((
            format!("vel[{axis}]"),
            64,
            Box::new(move |c, b| flip_axis(&mut c.vel, axis, b)),
        ));
    }
    let floats: [(&str, Float<V>); 5] = [
        ("radius", |c| &mut c.radius),
        ("mass", |c| &mut c.traits_mut().mass),
        ("priority", |c| &mut c.traits_mut().priority),
        ("restitution", |c| &mut c.traits_mut().restitution),
        ("health", |c| &mut c.traits_mut().health),
    ];
    for (name, field) in floats {
        fields.push((name.into(), 64, Box::new(move |c, b| flip(field(c), b))));
    }
    let others: [(&str, u32, Other<V>); 6] = [
        ("id.index", 32, |c, b| c.id.index ^= 1 << b),
        ("id.generation", 32, |c, b| c.id.generation ^= 1 << b),
        ("kind", 32, |c, b| c.traits_mut().kind.0 ^= 1 << b),
        ("fixed", 1, |c, _| c.fixed = !c.fixed),
        ("alive", 1, |c, _| c.alive = !c.alive),
        ("props", 1, |c, _| {
            c.props_mut().insert("tag".into(), PropValue::Int(1));
        }),
    ];
    for (name, width, f) in others {
        fields.push((name.into(), width, Box::new(f)));
    }
    for who in [disk, wall] {
        for (field, width, flip) in &fields {
            for bit in 0..*width {
                let slot = who.index;
                let c = w.state.critters.slot_mut(slot).expect("there");
                let saved = c.clone();
                flip(c, bit);
                let (fast, portable) = both(&w);
                assert_eq!(bits(&fast), bits(&portable), "{field} bit {bit}");
                assert_ne!(w.state_hash(), h0, "{field} bit {bit} of {who:?}");
                *w.state.critters.slot_mut(slot).expect("there") = saved;
            }
        }
    }
    assert_eq!(w.state_hash(), h0, "restored");
    // The rule class is a cache: it is not part of the state.
    w.get_mut(disk).expect("there").class ^= 1;
    assert_eq!(w.state_hash(), h0, "class");
}

#[test]
fn every_bit_of_every_field_counts_and_both_passes_agree_in_2d() {
    match scene("gas") {
        AnyWorld::D2(w) => every_bit_counts(w),
        AnyWorld::D3(_) => panic!("gas is 2D"),
    }
}

#[test]
fn every_bit_of_every_field_counts_and_both_passes_agree_in_3d() {
    match scene("gas3d") {
        AnyWorld::D3(w) => every_bit_counts(w),
        AnyWorld::D2(_) => panic!("gas3d is 3D"),
    }
}

/// The hash of `w` from every word: what is kept is dropped first.
fn whole_hash<V: Vector>(w: &mut World<V>) -> u64 {
    w.state.critters.forget_statics();
    assert!(!w.state.critters.statics().is_kept());
    w.state_hash()
}

/// Steps `w` by `method`, checking after each step that the kept lanes are still there and
/// that the hash that reuses them is the hash of every word.
fn steps_keep_the_lanes<V: Vector>(mut w: World<V>, method: Method) {
    w.set_method(method).expect("a method");
    w.state_hash();
    for step in 0..20 {
        w.step().expect("steps");
        // Moving, colliding and bouncing off the walls leave the kept lanes in place...
        assert!(
            w.state.critters.statics().is_kept(),
            "{method:?}, step {step}"
        );
        // ...and the hash that reuses them is the hash of every word.
        let kept = w.state_hash();
        assert_eq!(kept, whole_hash(&mut w), "{method:?}, step {step}");
    }
}

#[test]
fn a_step_without_hooks_reuses_the_kept_lanes_and_gets_the_whole_hash() {
    for method in [
        Method::Discrete,
        Method::Substep(3),
        Method::Swept,
        Method::Event,
    ] {
        match scene("gas") {
            AnyWorld::D2(w) => steps_keep_the_lanes(w, method),
            AnyWorld::D3(_) => panic!("gas is 2D"),
        }
        match scene("gas3d") {
            AnyWorld::D3(w) => steps_keep_the_lanes(w, method),
            AnyWorld::D2(_) => panic!("gas3d is 3D"),
        }
    }
}

#[test]
fn every_mutable_accessor_forgets_the_kept_lanes() {
    let AnyWorld::D2(mut w) = scene("gas") else {
        panic!("gas is 2D")
    };
    let id = w.critters().iter().next().expect("a critter").id;
    type Write = fn(&mut World<glam::DVec2>, CritterId);
    let writes: [(&str, Write); 6] = [
        ("World::get_mut", |w, id| {
            w.get_mut(id).expect("there").traits_mut().health -= 1.0
        }),
        ("CritterSet::get_mut", |w, id| {
            w.state
                .critters
                .get_mut(id)
                .expect("there")
                .traits_mut()
                .restitution = 0.5
        }),
        ("CritterSet::slot_mut", |w, id| {
            let c = w.state.critters.slot_mut(id.index).expect("there");
            c.set_priority(1.0).expect("a priority");
        }),
        ("CritterSet::pair_mut", |w, id| {
            let (a, _) = w.state.critters.pair_mut(id.index, id.index + 1);
            a.props_mut().insert("tag".into(), PropValue::Int(7));
        }),
        ("CritterSet::iter_mut", |w, _| {
            w.state
                .critters
                .iter_mut()
                .for_each(|c| c.traits_mut().health += 1.0)
        }),
        ("CritterSet::par_iter_mut", |w, _| {
            use rayon::prelude::*;
            w.state
                .critters
                .par_iter_mut()
                .for_each(|c| c.traits_mut().kind.0 ^= 0)
        }),
    ];
    for (name, write) in writes {
        let before = w.state_hash();
        assert!(w.state.critters.statics().is_kept(), "{name}");
        write(&mut w, id);
        assert!(!w.state.critters.statics().is_kept(), "{name}");
        let after = w.state_hash();
        assert_eq!(after, whole_hash(&mut w), "{name}");
        if name != "CritterSet::par_iter_mut" {
            assert_ne!(after, before, "{name} changed a field");
        }
    }
    // Removing and spawning change the slots.
    w.state_hash();
    w.remove(id).expect("there");
    assert!(!w.state.critters.statics().is_kept(), "remove");
    let after = w.state_hash();
    assert_eq!(after, whole_hash(&mut w), "remove");
}

#[cfg(target_arch = "x86_64")]
#[test]
fn the_moving_words_sit_where_the_avx512_load_reads_them() {
    // Otherwise the fast passes would quietly build the words field by field.
    assert!(super::avx512::moving_load::<glam::DVec2>().is_some());
    assert!(super::avx512::moving_load::<glam::DVec3>().is_some());
}

/// What the debug check is for: a write of a kept field through an accessor that promises
/// to write only positions and velocities is caught at the next hash.
#[cfg(debug_assertions)]
#[test]
#[should_panic(expected = "the kept hash lanes are stale")]
fn a_kept_field_written_behind_the_hash_is_caught() {
    let AnyWorld::D2(mut w) = scene("gas") else {
        panic!("gas is 2D")
    };
    w.state_hash();
    w.state
        .critters
        .slot_mut_moving(0)
        .expect("there")
        .traits_mut()
        .health = -5.0;
    w.state_hash();
}
