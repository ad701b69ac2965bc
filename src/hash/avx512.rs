//! The critters' passes of [`super::critters`] with each set of eight lanes in an AVX-512
//! register: a critter's first eight words are one byte-masked load of its record, a
//! permutation and the mass put in its lane, and its step one rotate-xor-multiply of eight
//! lanes. The same bits as the portable passes (`super::tests` compares them).

use super::critters::{
    for_each_in_sets, hash_props, join, portable_moving_pass, portable_pass, start_moving,
    start_static, static_words, MovingPass, Pass, Sums, MOVING, SETS,
};
use super::{StateHasher, K};
use crate::critter::Critter;
use crate::critter_set::InIdOrder;
use crate::vector::Vector;
use std::arch::x86_64::*;
use std::mem::offset_of;

/// True when the CPU has what the passes here are compiled for.
pub(super) fn has_avx512() -> bool {
    std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512dq")
        && std::arch::is_x86_feature_detected!("avx512bw")
}

/// How the AVX-512 passes read a critter's first [`MOVING`] words from its record: one
/// byte-masked load of the record's first 64 bytes, a permutation of its eight words into
/// the order of [`words`](super::critters::words), and the mass (in the traits) put in its lane.
#[derive(Clone, Copy, Debug)]
pub(super) struct MovingLoad {
    /// The record's bytes that are read (one bit per byte).
    mask: u64,
    /// For each word of [`words`](super::critters::words), the word of the record it comes from.
    from: [u64; MOVING],
    /// The word that is the mass.
    mass: usize,
}

/// The [`MovingLoad`] for `V`'s layout, if every moving word but the mass lies whole in the
/// record's first 64 bytes at the byte of its word that [`words`](super::critters::words) puts
/// it at; `None` otherwise (the passes then build the words field by field).
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
        // Index, then generation (`repr(C)`), as [`super::critters::id_word`] puts them; then fixed
        // and alive at bytes 4 and 5 of their word, as [`super::critters::flags_word`] does.
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

/// A critter's first [`MOVING`] words, as [`super::critters::moving_words`] gives them.
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

/// [`super::critters::pass`] with each set of eight lanes in an AVX-512 register: each half of a
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
    let mut moving = [start_moving(); SETS];
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

/// [`super::critters::moving_pass`]: one rotate-xor-multiply of eight lanes per critter.
///
/// # Safety
/// The CPU must have AVX-512F, DQ and BW.
#[target_feature(enable = "avx512f,avx512dq,avx512bw")]
pub unsafe fn moving_pass<V: Vector>(slots: InIdOrder<'_, V>) -> MovingPass<V> {
    let Some(load) = moving_load::<V>() else {
        return portable_moving_pass(slots);
    };
    let k = _mm512_set1_epi64(K as i64);
    let mut moving = [start_moving(); SETS];
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
