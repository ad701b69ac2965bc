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
//! lanes. Elsewhere the same arithmetic runs one lane at a time. Both give the same bits; the
//! tests compare them on 2D and 3D worlds with every bit of every field flipped in turn.

use crate::critter::{Critter, PropValue};
use crate::critter_set::InIdOrder;
use crate::hash::StateHasher;
use crate::vector::Vector;
use std::sync::{Mutex, PoisonError};

/// Words per critter.
pub const WORDS: usize = 16;

/// The first `MOVING` words of a critter hold everything a step changes when no hook writes to
/// the critters: position, velocity, radius and mass (and in 2D id and flags).
pub const MOVING: usize = 8;

/// The words after the first [`MOVING`]: kind, priority, restitution, health (and in 3D id and
/// flags).
pub const STATIC: usize = WORDS - MOVING;

/// Interleaved sets of lanes for the moving words, and of sums for the totals.
pub const SETS: usize = 4;

/// Lanes in all: [`SETS`] sets for the moving words, one for the rest.
pub const LANES: usize = SETS * MOVING + STATIC;

/// The odd multiplier of every lane (as in [`crate::hash`]).
const K: u64 = 0x5851_F42D_4C95_7F2D;

/// The lanes' starting values (splitmix64 of 1 to [`LANES`]): the moving sets, then the rest.
const START: [u64; LANES] = start();

const fn start() -> [u64; LANES] {
    let mut out = [0u64; LANES];
    let mut i = 0;
    while i < LANES {
        let mut z = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        out[i] = z ^ (z >> 31);
        i += 1;
    }
    out
}

/// Eight starting lanes, from lane `first` of [`START`]: moving set `s` starts at `s * MOVING`,
/// the static set at `SETS * MOVING`.
const fn start_set(first: usize) -> [u64; MOVING] {
    let mut out = [0u64; MOVING];
    let mut j = 0;
    while j < MOVING {
        out[j] = START[first + j];
        j += 1;
    }
    out
}

/// The starting lanes of moving set `s`.
const fn start_moving(s: usize) -> [u64; MOVING] {
    start_set(s * MOVING)
}

/// The starting lanes of the static words (as many as the moving ones: one register each).
const fn start_static() -> [u64; STATIC] {
    const _: () = assert!(MOVING == STATIC);
    start_set(SETS * MOVING)
}

#[inline(always)]
fn mix(lane: u64, w: u64) -> u64 {
    (lane.rotate_left(5) ^ w).wrapping_mul(K)
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
struct Sums<V> {
    energy: [f64; SETS],
    momentum: [V; SETS],
}

impl<V: Vector> Sums<V> {
    fn new() -> Self {
        Sums {
            energy: [0.0; SETS],
            momentum: [V::zero(); SETS],
        }
    }

    /// Adds critter `c` to sum `s`.
    #[inline(always)]
    fn add(&mut self, s: usize, c: &Critter<V>) {
        self.energy[s] += c.kinetic_energy();
        if !c.fixed {
            self.momentum[s] += c.vel * c.mass();
        }
    }

    /// The sums added in set order.
    #[inline(always)]
    fn total(self) -> (f64, V) {
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
fn for_each_in_sets<V: Vector>(critters: InIdOrder<'_, V>, mut f: impl FnMut(usize, &Critter<V>)) {
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
    if has_avx512() {
        // SAFETY: the CPU has the features the function is compiled for.
        return unsafe { avx512::pass(slots, props) };
    }
    portable_pass(slots, props)
}

#[cfg(target_arch = "x86_64")]
fn has_avx512() -> bool {
    std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512dq")
        && std::arch::is_x86_feature_detected!("avx512bw")
}

/// [`pass`] one lane at a time, on any CPU.
pub fn portable_pass<V: Vector>(slots: InIdOrder<'_, V>, props: &mut StateHasher) -> Pass<V> {
    let mut moving = [0; SETS].map(start_moving);
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
fn join(moving: [[u64; MOVING]; SETS], statics: [u64; STATIC]) -> [u64; LANES] {
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
fn static_words<V: Vector>(c: &Critter<V>) -> [u64; STATIC] {
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
    if has_avx512() {
        // SAFETY: the CPU has the features the function is compiled for.
        return unsafe { avx512::moving_pass(slots) };
    }
    portable_moving_pass(slots)
}

/// [`moving_pass`] one lane at a time, on any CPU.
pub fn portable_moving_pass<V: Vector>(slots: InIdOrder<'_, V>) -> MovingPass<V> {
    let mut lanes = [0; SETS].map(start_moving);
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

/// What the last whole pass over a set of critters left in the static lanes and in the
/// properties' hash.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Kept {
    lanes: [u64; STATIC],
    props: u64,
}

/// The static lanes of a critter set, kept between hashes.
///
/// A step without hooks writes only positions and velocities (and the rule class, which is not
/// hashed), so the next hash needs only the first [`MOVING`] words of each critter: one cache
/// line of a 2D critter instead of two. The critter set drops what is kept on every write that
/// could change anything else: insert, remove, and every mutable accessor but the engine's own
/// `*_moving` ones, which write positions, velocities and rule classes only. Debug builds (the
/// tests) check every reuse against a whole pass.
#[derive(Debug, Default)]
pub struct Statics(Mutex<Option<Kept>>);

impl Clone for Statics {
    /// A copy starts with nothing kept (its first hash is a whole pass).
    fn clone(&self) -> Self {
        Statics::default()
    }
}

impl Statics {
    /// Forgets what is kept: the next hash reads every word again.
    #[inline]
    pub(crate) fn forget(&mut self) {
        *self.0.get_mut().unwrap_or_else(PoisonError::into_inner) = None;
    }

    /// True when the next hash can reuse the kept lanes.
    #[cfg(test)]
    pub(crate) fn is_kept(&self) -> bool {
        self.0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .is_some()
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
    *kept = Some(Kept { lanes, props });
    Hashed {
        lanes: whole.lanes,
        props,
        energy: whole.energy,
        momentum: whole.momentum,
    }
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use super::*;
    use std::arch::x86_64::*;
    use std::mem::offset_of;

    /// How the AVX-512 passes read a critter's first [`MOVING`] words from its record: one
    /// byte-masked load of the record's first 64 bytes, a permutation of its eight words into
    /// the order of [`words`], and the mass (in the traits) put in its lane.
    #[derive(Clone, Copy, Debug)]
    pub(super) struct MovingLoad {
        /// The record's bytes that are read (one bit per byte).
        mask: u64,
        /// For each word of [`words`], the word of the record it comes from.
        from: [u64; MOVING],
        /// The word that is the mass.
        mass: usize,
    }

    /// The [`MovingLoad`] for `V`'s layout, if every moving word but the mass lies whole in the
    /// record's first 64 bytes at the byte of its word that [`words`] puts it at; `None`
    /// otherwise (the passes then build the words field by field).
    pub(super) fn moving_load<V: Vector>() -> Option<MovingLoad> {
        let d = V::DIM;
        // (offset in the record, size, the byte of `words` it goes to).
        let word = |i: usize| 8 * i;
        let mut fields = vec![
            (offset_of!(Critter<V>, pos), 8 * d, word(0)),
            (offset_of!(Critter<V>, vel), 8 * d, word(d)),
            (offset_of!(Critter<V>, radius), 8, word(2 * d)),
        ];
        let mass = 2 * d + 1;
        if d == 2 {
            // Index, then generation (`repr(C)`), as [`super::id_word`] puts them; then fixed
            // and alive at bytes 4 and 5 of their word, as [`super::flags_word`] does.
            fields.push((offset_of!(Critter<V>, id), 8, word(2 * d + 2)));
            fields.push((offset_of!(Critter<V>, fixed), 1, word(2 * d + 3) + 4));
            fields.push((offset_of!(Critter<V>, alive), 1, word(2 * d + 3) + 5));
        }
        let (mut mask, mut from, mut set) = (0u64, [0u64; MOVING], [false; MOVING]);
        // Each field a word at a time (position and velocity are several).
        let chunks = fields.into_iter().flat_map(|(offset, size, at)| {
            (0..size.div_ceil(8)).map(move |k| (offset + 8 * k, (size - 8 * k).min(8), at + 8 * k))
        });
        for (offset, size, at) in chunks {
            let (target, source) = (at / 8, offset / 8);
            let fits = offset % 8 == at % 8 && offset + size <= 64 && at % 8 + size <= 8;
            if !fits || target >= MOVING || (set[target] && from[target] != source as u64) {
                return None;
            }
            for byte in offset..offset + size {
                mask |= 1 << byte;
            }
            (from[target], set[target]) = (source as u64, true);
        }
        // The mass's lane takes a word with no byte read (zero) until the mass is put in.
        let zero = (0..MOVING).find(|&w| (mask >> (8 * w)) & 0xff == 0)?;
        from[mass] = zero as u64;
        // Every other word of the first half is a field.
        (set.iter().filter(|&&s| s).count() == MOVING - 1 && !set[mass]).then_some(MovingLoad {
            mask,
            from,
            mass,
        })
    }

    /// A critter's first [`MOVING`] words, as [`super::moving_words`] gives them.
    ///
    /// # Safety
    /// `load` must come from [`moving_load`] for `V` (it reads only bytes of the record's
    /// fields), and the CPU must have AVX-512F, DQ and BW.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx512bw")]
    unsafe fn moving_vector<V: Vector>(c: &Critter<V>, load: &MovingLoad) -> __m512i {
        let p: *const i8 = (c as *const Critter<V>).cast();
        // SAFETY: the masked bytes are not read; the rest lie in initialised fields of the
        // record (the caller's promise).
        let record = unsafe { _mm512_maskz_loadu_epi8(load.mask, p) };
        let words = _mm512_permutexvar_epi64(load8(&load.from), record);
        _mm512_mask_set1_epi64(words, 1 << load.mass, c.mass().to_bits() as i64)
    }

    /// One rotate-xor-multiply of eight lanes.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx512bw")]
    fn mix8(lanes: __m512i, w: __m512i, k: __m512i) -> __m512i {
        _mm512_mullo_epi64(_mm512_xor_si512(_mm512_rol_epi64::<5>(lanes), w), k)
    }

    /// Eight lanes from memory.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx512bw")]
    fn load8(lanes: &[u64; MOVING]) -> __m512i {
        // SAFETY: eight u64 are 64 bytes (an unaligned load).
        unsafe { _mm512_loadu_si512(lanes.as_ptr().cast()) }
    }

    /// Eight lanes to memory.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx512bw")]
    fn store8(v: __m512i) -> [u64; MOVING] {
        let mut out = [0u64; MOVING];
        // SAFETY: `out` is 64 bytes (an unaligned store).
        unsafe { _mm512_storeu_si512(out.as_mut_ptr().cast(), v) };
        out
    }

    /// [`super::pass`] with each set of eight lanes in an AVX-512 register: each half of a
    /// critter's words is one rotate-xor-multiply of eight lanes at once.
    ///
    /// # Safety
    /// The CPU must have AVX-512F, DQ and BW.
    #[target_feature(enable = "avx512f,avx512dq,avx512bw")]
    pub unsafe fn pass<V: Vector>(slots: InIdOrder<'_, V>, props: &mut StateHasher) -> Pass<V> {
        let Some(load) = moving_load::<V>() else {
            return portable_pass(slots, props);
        };
        let k = _mm512_set1_epi64(K as i64);
        // The lanes are kept as words, not as vectors: an array of vectors across the closure
        // was stored to a stack slot the frame had not aligned to 64 bytes (a fault).
        let mut moving = [0; SETS].map(start_moving);
        let mut statics = start_static();
        let mut sums = Sums::new();
        for_each_in_sets(slots, |s, c| {
            sums.add(s, c);
            // SAFETY: `load` is `moving_load`'s for `V`.
            let wa = unsafe { moving_vector(c, &load) };
            moving[s] = store8(mix8(load8(&moving[s]), wa, k));
            statics = store8(mix8(load8(&statics), load8(&static_words(c)), k));
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

    /// [`super::moving_pass`]: one rotate-xor-multiply of eight lanes per critter.
    ///
    /// # Safety
    /// The CPU must have AVX-512F, DQ and BW.
    #[target_feature(enable = "avx512f,avx512dq,avx512bw")]
    pub unsafe fn moving_pass<V: Vector>(slots: InIdOrder<'_, V>) -> MovingPass<V> {
        let Some(load) = moving_load::<V>() else {
            return portable_moving_pass(slots);
        };
        let k = _mm512_set1_epi64(K as i64);
        let mut moving = [0; SETS].map(start_moving);
        let mut sums = Sums::new();
        for_each_in_sets(slots, |s, c| {
            sums.add(s, c);
            // SAFETY: `load` is `moving_load`'s for `V`.
            let wa = unsafe { moving_vector(c, &load) };
            moving[s] = store8(mix8(load8(&moving[s]), wa, k));
        });
        let (energy, momentum) = sums.total();
        MovingPass {
            lanes: moving,
            energy,
            momentum,
        }
    }
}

/// A critter's properties (how many, then names and values), after its id.
#[inline(never)]
fn hash_props<V: Vector>(h: &mut StateHasher, c: &Critter<V>) {
    h.word(id_word(c));
    h.word(c.props().len() as u64);
    for (name, value) in c.props() {
        hash_bytes(h, name.as_bytes());
        hash_prop(h, value);
    }
}

fn hash_prop(h: &mut StateHasher, value: &PropValue) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::critter::{CritterId, PropValue};
    use crate::method::Method;
    use crate::scenes::{builtin, AnyWorld, SceneParams};
    use crate::world::World;

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
        assert!(avx512::moving_load::<glam::DVec2>().is_some());
        assert!(avx512::moving_load::<glam::DVec3>().is_some());
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
}
