//! The critters' part of the per-step state hash ([`crate::world::World::state_hash`]), and the
//! totals that a recording sums in the same pass.
//!
//! Recording hashes every step, so this pass must cost little next to a step. Each critter is
//! sixteen words ([`words`]): position, velocity, radius, mass, id, a word of flags (fixed,
//! alive), kind, priority, restitution and health, the rest zero. Each word goes through a lane
//! of its own, `lane = (rotl(lane, 5) ^ word) * K`, critter after critter in id order. Each
//! update is a bijection of the lane for a fixed word and of the word for a fixed lane, so a
//! change in any one word of any one critter always changes its lane, and the order of the
//! critters counts.
//!
//! - The first [`MOVING`] words (position, velocity, radius, mass; in 2D also id and flags) are
//!   all that a step without hooks changes. They go through [`SETS`] interleaved sets of lanes:
//!   the critter of id index `i` through set `i % SETS`. One chain of multiplies per lane would
//!   make every critter wait for the last one's multiply; four chains run side by side.
//! - The other words go through one set of lanes, which the critter set keeps between hashes
//!   until something may have written them ([`Statics`]). A step of a scene without hooks then
//!   reads each critter's record and the mass in its traits (shared by critters alike), not
//!   the rest of the traits.
//! - The totals (kinetic energy, momentum) are summed in [`SETS`] interleaved sums too, added in
//!   set order at the end ([`totals`], which [`crate::world::World::kinetic_energy`] uses).
//!
//! The words are eight bytes each, with the rule class, the wall flag and padding left out. On a
//! CPU with AVX-512 a critter's first eight words are one byte-masked load of its record, a
//! permutation and the mass put in its lane, and its step one rotate-xor-multiply of eight
//! lanes (`src/hash/avx512.rs`). Elsewhere the same arithmetic runs one lane at a time. Both
//! give the same bits; the tests compare them on 2D and 3D worlds with every bit of every field
//! flipped in turn.

#[cfg(target_arch = "x86_64")]
use super::avx512;
use super::statics::StaticHash;
pub use super::statics::{Statics, MOVING, STATIC, WORDS};
use super::{mix, scramble, StateHasher};
use crate::critter::{Critter, PropValue};
use crate::critter_set::InIdOrder;
use crate::vector::Vector;
use std::sync::PoisonError;

/// Interleaved sets of lanes for the moving words, and of sums for the totals.
pub const SETS: usize = 4;

/// Lanes in all: [`SETS`] sets for the moving words, one for the rest.
pub const LANES: usize = SETS * MOVING + STATIC;

/// The lanes' starting values (splitmix64 of 1 to [`LANES`]): the moving sets, then the rest.
const START: [u64; LANES] = start();

const fn start() -> [u64; LANES] {
    let mut out = [0u64; LANES];
    let mut i = 0;
    while i < LANES {
        out[i] = scramble((i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        i += 1;
    }
    out
}

/// Eight starting lanes, from lane `first` of [`START`]: the moving sets start at 0, the static
/// set at `SETS * MOVING` (the lanes between are not used).
const fn start_set(first: usize) -> [u64; MOVING] {
    let mut out = [0u64; MOVING];
    let mut j = 0;
    while j < MOVING {
        out[j] = START[first + j];
        j += 1;
    }
    out
}

/// The starting lanes of every moving set: the sets differ by the critters they take, not by
/// where they start.
pub(super) const fn start_moving() -> [u64; MOVING] {
    start_set(0)
}

/// The starting lanes of the static words (as many as the moving ones: one register each).
pub(super) const fn start_static() -> [u64; STATIC] {
    const _: () = assert!(MOVING == STATIC);
    start_set(SETS * MOVING)
}

/// The id as one word: index in the low half, generation in the high half (the bytes of a
/// `repr(C)` [`crate::critter::CritterId`] on a little-endian machine).
#[inline(always)]
fn id_word<V: Vector>(c: &Critter<V>) -> u64 {
    c.id.index as u64 | (c.id.generation as u64) << 32
}

/// Fixed and alive in one word, at the bits their bytes take in their word of the critter
/// (bytes 4 and 5; bytes 0 to 3 are the rule class, a cache, and byte 6 the wall flag, which
/// the kind says too: neither is hashed).
#[inline(always)]
fn flags_word<V: Vector>(c: &Critter<V>) -> u64 {
    (c.fixed as u64) << 32 | (c.alive as u64) << 40
}

/// A critter's sixteen words.
/// - 2D: x, y, vx, vy, radius, mass, id, flags | kind, priority, restitution, health, 0, 0, 0, 0.
/// - 3D: x, y, z, vx, vy, vz, radius, mass | id, flags, kind, priority, restitution, health, 0, 0.
///
/// This is the order of the fields in memory, eight bytes per word (the rule class, the wall
/// flag and padding read as zero), so the AVX-512 pass loads each half with one masked load.
#[inline(always)]
pub fn words<V: Vector>(c: &Critter<V>) -> [u64; WORDS] {
    let f = |x: f64| x.to_bits();
    let mut w = [0u64; WORDS];
    let d = V::DIM;
    for axis in 0..d {
        w[axis] = f(c.pos.get(axis));
        w[d + axis] = f(c.vel.get(axis));
    }
    let rest = [
        f(c.radius),
        f(c.mass()),
        id_word(c),
        flags_word(c),
        c.kind().0 as u64,
        f(c.priority()),
        f(c.restitution()),
        f(c.health()),
    ];
    w[2 * d..2 * d + rest.len()].copy_from_slice(&rest);
    w
}

/// The kinetic energy and momentum of the free critters, in [`SETS`] interleaved sums.
#[derive(Clone, Copy, Debug)]
pub(super) struct Sums<V> {
    energy: [f64; SETS],
    momentum: [V; SETS],
}

impl<V: Vector> Sums<V> {
    pub(super) fn new() -> Self {
        Sums {
            energy: [0.0; SETS],
            momentum: [V::zero(); SETS],
        }
    }

    /// Adds critter `c` to sum `s`.
    #[inline(always)]
    pub(super) fn add(&mut self, s: usize, c: &Critter<V>) {
        self.energy[s] += c.kinetic_energy();
        if !c.fixed {
            self.momentum[s] += c.vel * c.mass();
        }
    }

    /// The sums added in set order.
    #[inline(always)]
    pub(super) fn total(self) -> (f64, V) {
        let mut energy = self.energy[0];
        let mut momentum = self.momentum[0];
        for s in 1..SETS {
            energy += self.energy[s];
            momentum += self.momentum[s];
        }
        (energy, momentum)
    }
}

/// The kinetic energy and momentum of the free `critters`, summed as every pass sums them: the
/// critter of id index `i` into sum `i % SETS`, the sums added in order.
pub fn totals<V: Vector>(critters: InIdOrder<'_, V>) -> (f64, V) {
    let mut sums = Sums::new();
    for_each_in_sets(critters, |s, c| sums.add(s, c));
    sums.total()
}

/// What one pass over the critters gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pass<V> {
    /// The lanes after every critter: the [`SETS`] moving sets, then the static set.
    pub lanes: [u64; LANES],
    /// Kinetic energy of the free critters (as [`totals`]).
    pub energy: f64,
    /// Momentum of the free critters (as [`totals`]).
    pub momentum: V,
}

/// Calls `f(s, c)` for every critter `c` in id order, `s` its id index modulo [`SETS`], with
/// `s` a constant in the unrolled main loop while slot and id index are the same (so sets
/// indexed by it stay in registers).
#[inline(always)]
pub(super) fn for_each_in_sets<V: Vector>(
    critters: InIdOrder<'_, V>,
    mut f: impl FnMut(usize, &Critter<V>),
) {
    if !critters.place.is_empty() {
        // Stored in other slots than their ids' (see [`crate::critter_set::CritterSet::arrange`]):
        // the same order, set by set, through the table.
        for i in 0..critters.len() {
            if let Some(c) = critters.at(i) {
                f(i % SETS, c);
            }
        }
        return;
    }
    let slots = critters.slots;
    let mut chunks = slots.chunks_exact(SETS);
    for chunk in &mut chunks {
        for (s, slot) in chunk.iter().enumerate() {
            if let Some(c) = slot {
                f(s, c);
            }
        }
    }
    for (s, slot) in chunks.remainder().iter().enumerate() {
        if let Some(c) = slot {
            f(s, c);
        }
    }
}

/// One pass over every critter of `slots` (empty slots skipped): the lanes, the totals, and
/// non-empty properties hashed into `props`. Uses AVX-512 when the CPU has it.
pub fn pass<V: Vector>(slots: InIdOrder<'_, V>, props: &mut StateHasher) -> Pass<V> {
    #[cfg(target_arch = "x86_64")]
    if avx512::has_avx512() {
        // SAFETY: the CPU has the features the function is compiled for.
        return unsafe { avx512::pass(slots, props) };
    }
    portable_pass(slots, props)
}

/// [`pass`] one lane at a time, on any CPU.
pub fn portable_pass<V: Vector>(slots: InIdOrder<'_, V>, props: &mut StateHasher) -> Pass<V> {
    let mut moving = [start_moving(); SETS];
    let mut statics = start_static();
    let mut sums = Sums::new();
    for_each_in_sets(slots, |s, c| {
        sums.add(s, c);
        let w = words(c);
        for (lane, &w) in moving[s].iter_mut().zip(&w[..MOVING]) {
            *lane = mix(*lane, w);
        }
        for (lane, &w) in statics.iter_mut().zip(&w[MOVING..]) {
            *lane = mix(*lane, w);
        }
        if !c.props().is_empty() {
            hash_props(props, c);
        }
    });
    let (energy, momentum) = sums.total();
    Pass {
        lanes: join(moving, statics),
        energy,
        momentum,
    }
}

/// The moving sets and the static set as one row of lanes.
pub(super) fn join(moving: [[u64; MOVING]; SETS], statics: [u64; STATIC]) -> [u64; LANES] {
    let mut lanes = [0u64; LANES];
    for (s, set) in moving.iter().enumerate() {
        lanes[s * MOVING..(s + 1) * MOVING].copy_from_slice(set);
    }
    lanes[SETS * MOVING..].copy_from_slice(&statics);
    lanes
}

/// A critter's first [`MOVING`] words: the first half of [`words`].
#[inline(always)]
fn moving_words<V: Vector>(c: &Critter<V>) -> [u64; MOVING] {
    // Inlined, the loads of the words not kept are dropped.
    let mut w = [0u64; MOVING];
    w.copy_from_slice(&words(c)[..MOVING]);
    w
}

/// A critter's last [`STATIC`] words: the second half of [`words`].
#[inline(always)]
pub(super) fn static_words<V: Vector>(c: &Critter<V>) -> [u64; STATIC] {
    let mut w = [0u64; STATIC];
    w.copy_from_slice(&words(c)[MOVING..]);
    w
}

/// What a pass over the first [`MOVING`] words gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MovingPass<V> {
    /// The [`SETS`] moving sets of lanes after every critter.
    pub lanes: [[u64; MOVING]; SETS],
    /// As in [`Pass`].
    pub energy: f64,
    /// As in [`Pass`].
    pub momentum: V,
}

/// [`pass`] over each critter's first [`MOVING`] words only (no properties).
pub fn moving_pass<V: Vector>(slots: InIdOrder<'_, V>) -> MovingPass<V> {
    #[cfg(target_arch = "x86_64")]
    if avx512::has_avx512() {
        // SAFETY: the CPU has the features the function is compiled for.
        return unsafe { avx512::moving_pass(slots) };
    }
    portable_moving_pass(slots)
}

/// [`moving_pass`] one lane at a time, on any CPU.
pub fn portable_moving_pass<V: Vector>(slots: InIdOrder<'_, V>) -> MovingPass<V> {
    let mut lanes = [start_moving(); SETS];
    let mut sums = Sums::new();
    for_each_in_sets(slots, |s, c| {
        sums.add(s, c);
        for (lane, w) in lanes[s].iter_mut().zip(moving_words(c)) {
            *lane = mix(*lane, w);
        }
    });
    let (energy, momentum) = sums.total();
    MovingPass {
        lanes,
        energy,
        momentum,
    }
}

/// What [`hash_critters`] gives: every lane, the properties' hash, and the totals.
#[derive(Clone, Copy, Debug)]
pub struct Hashed<V> {
    /// The lanes, as in [`Pass`].
    pub lanes: [u64; LANES],
    /// The properties' hash (see [`pass`]).
    pub props: u64,
    /// Kinetic energy of the free critters (as [`totals`]).
    pub energy: f64,
    /// Momentum of the free critters (as [`totals`]).
    pub momentum: V,
}

/// The critters of `slots` hashed: the same bits as a whole [`pass`] (and the properties' hash),
/// but reading only each critter's first [`MOVING`] words when `statics` still holds the rest.
pub fn hash_critters<V: Vector>(slots: InIdOrder<'_, V>, statics: &Statics) -> Hashed<V> {
    let mut kept = statics.0.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some(k) = *kept {
        let m = moving_pass(slots);
        let out = Hashed {
            lanes: join(m.lanes, k.lanes),
            props: k.props,
            energy: m.energy,
            momentum: m.momentum,
        };
        #[cfg(debug_assertions)]
        {
            let mut props = StateHasher::default();
            let whole = pass(slots, &mut props);
            assert!(
                whole.lanes == out.lanes && props.finish() == out.props,
                "the kept hash lanes are stale: a write to a critter's kind, priority, \
                 restitution, health or properties went through a `*_moving` accessor"
            );
        }
        return out;
    }
    let mut props = StateHasher::default();
    let whole = pass(slots, &mut props);
    let props = props.finish();
    let mut lanes = [0u64; STATIC];
    lanes.copy_from_slice(&whole.lanes[SETS * MOVING..]);
    *kept = Some(StaticHash { lanes, props });
    Hashed {
        lanes: whole.lanes,
        props,
        energy: whole.energy,
        momentum: whole.momentum,
    }
}

/// A critter's properties (how many, then names and values), after its id.
#[inline(never)]
pub(super) fn hash_props<V: Vector>(h: &mut StateHasher, c: &Critter<V>) {
    h.word(id_word(c));
    h.word(c.props().len() as u64);
    for (name, value) in c.props() {
        hash_bytes(h, name.as_bytes());
        hash_prop(h, value);
    }
}

pub(crate) fn hash_prop(h: &mut StateHasher, value: &PropValue) {
    match value {
        PropValue::Bool(b) => h.word(*b as u64),
        PropValue::Int(i) => h.word(*i as u64),
        PropValue::Float(x) => h.float(*x),
        PropValue::Text(s) => hash_bytes(h, s.as_bytes()),
        PropValue::Critter(id) => h.word(((id.index as u64) << 32) | id.generation as u64),
        PropValue::Vector(v) => {
            for x in v {
                h.float(*x);
            }
        }
        PropValue::List(items) => {
            h.word(items.len() as u64);
            for item in items {
                hash_prop(h, item);
            }
        }
        PropValue::Map(map) => hash_named(h, map),
    }
}

/// Named values (a map property, `world().vars`): how many, then names and values in order.
pub(crate) fn hash_named(h: &mut StateHasher, map: &std::collections::BTreeMap<String, PropValue>) {
    h.word(map.len() as u64);
    for (name, value) in map {
        hash_bytes(h, name.as_bytes());
        hash_prop(h, value);
    }
}

fn hash_bytes(h: &mut StateHasher, bytes: &[u8]) {
    h.word(bytes.len() as u64);
    for chunk in bytes.chunks(8) {
        let mut w = [0u8; 8];
        w[..chunk.len()].copy_from_slice(chunk);
        h.word(u64::from_le_bytes(w));
    }
}
