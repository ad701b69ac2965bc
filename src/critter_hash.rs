//! The critters' part of the per-step state hash ([`crate::world::World::state_hash`]), and the
//! totals that a recording sums in the same pass.
//!
//! Recording hashes every step, so this pass must cost little next to a step. Each critter is
//! sixteen words ([`words`]): position, velocity, radius, mass, id, a word of flags (fixed,
//! alive), kind, priority, restitution and health, the rest zero. Word `j` of every critter goes
//! through its own lane `j`, `lane = (rotl(lane, 5) ^ word) * K`, critter after critter in slot
//! order. Each update is a bijection of the lane for a fixed word and of the word for a fixed
//! lane, so a change in any one word of any one critter always changes its lane, and the order
//! of the critters counts.
//!
//! The words are the critter's fields in memory order (`repr(C)`, eight bytes a word, with the
//! rule class and padding read as zero), and the lanes are independent, so on a CPU with
//! AVX-512 the sixteen lanes are two vector registers and a critter costs two byte-masked loads
//! and two rotate-xor-multiply steps: about 2.7 ns for a 2D critter against 4.9 ns for the
//! scalar hash it replaced (`cargo bench --bench recording`, `recording_parts/hash`). Elsewhere
//! the same arithmetic runs one lane at a time. Both give the same bits; the tests compare them
//! on 2D and 3D worlds with every bit of every field flipped in turn.

use crate::critter::{Critter, PropValue};
use crate::hash::StateHasher;
use crate::vector::Vector;

/// Words per critter, and lanes.
pub const WORDS: usize = 16;

/// The odd multiplier of every lane (as in [`crate::hash`]).
const K: u64 = 0x5851_F42D_4C95_7F2D;

/// The lanes' starting values (splitmix64 of 1 to 16).
const START: [u64; WORDS] = start();

const fn start() -> [u64; WORDS] {
    let mut out = [0u64; WORDS];
    let mut i = 0;
    while i < WORDS {
        let mut z = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        out[i] = z ^ (z >> 31);
        i += 1;
    }
    out
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
/// (bytes 4 and 5; bytes 0 to 3 are the rule class, which is a cache and not hashed).
#[inline(always)]
fn flags_word<V: Vector>(c: &Critter<V>) -> u64 {
    (c.fixed as u64) << 32 | (c.alive as u64) << 40
}

/// A critter's sixteen words.
/// - 2D: x, y, vx, vy, radius, mass, id, flags | kind, priority, restitution, health, 0, 0, 0, 0.
/// - 3D: x, y, z, vx, vy, vz, radius, mass | id, flags, kind, priority, restitution, health, 0, 0.
///
/// This is the order of the fields in memory, eight bytes per word (the rule class, a cache,
/// and padding read as zero), so the AVX-512 pass loads each half with one masked load.
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
        f(c.mass),
        id_word(c),
        flags_word(c),
        c.kind.0 as u64,
        f(c.priority),
        f(c.restitution),
        f(c.health),
    ];
    w[2 * d..2 * d + rest.len()].copy_from_slice(&rest);
    w
}

/// What one pass over the critters gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pass<V> {
    /// The lanes after every critter.
    pub lanes: [u64; WORDS],
    /// Kinetic energy of the free critters, summed in slot order (as
    /// [`crate::world::World::kinetic_energy`] sums it).
    pub energy: f64,
    /// Momentum of the free critters, summed in slot order.
    pub momentum: V,
}

/// One pass over every critter of `slots` (empty slots skipped): the lanes, the totals, and
/// non-empty properties hashed into `props`. Uses AVX-512 when the CPU has it.
pub fn pass<V: Vector>(slots: &[Option<Critter<V>>], props: &mut StateHasher) -> Pass<V> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512dq")
        && std::arch::is_x86_feature_detected!("avx512bw")
    {
        // SAFETY: the CPU has the features the function is compiled for.
        return unsafe { avx512::pass(slots, props) };
    }
    portable_pass(slots, props)
}

/// A critter's kinetic energy and momentum, added to the sums (in registers: a closure that
/// captured the sums by reference kept them in memory, a store-to-load wait per critter).
#[inline(always)]
fn add_totals<V: Vector>(c: &Critter<V>, energy: &mut f64, momentum: &mut V) {
    *energy += c.kinetic_energy();
    if !c.fixed {
        *momentum += c.vel * c.mass;
    }
}

/// [`pass`] one lane at a time, on any CPU.
pub fn portable_pass<V: Vector>(slots: &[Option<Critter<V>>], props: &mut StateHasher) -> Pass<V> {
    let mut lanes = START;
    let (mut energy, mut momentum) = (0.0, V::zero());
    for c in slots.iter().flatten() {
        add_totals(c, &mut energy, &mut momentum);
        let w = words(c);
        for (lane, w) in lanes.iter_mut().zip(w) {
            *lane = mix(*lane, w);
        }
        if !c.props.is_empty() {
            hash_props(props, c);
        }
    }
    Pass {
        lanes,
        energy,
        momentum,
    }
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use super::*;
    use std::arch::x86_64::*;
    use std::mem::offset_of;

    /// The bytes of the sixteen words that hold state, as two 64-bit load masks (one bit per
    /// byte), if the critter's fields sit where [`words`] says; `None` otherwise.
    pub(super) fn byte_masks<V: Vector>() -> Option<[u64; 2]> {
        let d = V::DIM;
        let word = |i: usize| 8 * i;
        // (offset, size) of each field, and the byte [`words`] puts it at.
        let fields = [
            (offset_of!(Critter<V>, pos), 8 * d, word(0)),
            (offset_of!(Critter<V>, vel), 8 * d, word(d)),
            (offset_of!(Critter<V>, radius), 8, word(2 * d)),
            (offset_of!(Critter<V>, mass), 8, word(2 * d + 1)),
            // Index, then generation (`repr(C)`), as [`super::id_word`] puts them.
            (offset_of!(Critter<V>, id), 8, word(2 * d + 2)),
            (offset_of!(Critter<V>, fixed), 1, word(2 * d + 3) + 4),
            (offset_of!(Critter<V>, alive), 1, word(2 * d + 3) + 5),
            (offset_of!(Critter<V>, kind), 4, word(2 * d + 4)),
            (offset_of!(Critter<V>, priority), 8, word(2 * d + 5)),
            (offset_of!(Critter<V>, restitution), 8, word(2 * d + 6)),
            (offset_of!(Critter<V>, health), 8, word(2 * d + 7)),
        ];
        let mut masks = [0u64; 2];
        for (offset, size, at) in fields {
            if offset != at || at + size > 128 {
                return None;
            }
            for byte in at..at + size {
                masks[byte / 64] |= 1 << (byte % 64);
            }
        }
        Some(masks)
    }

    /// [`super::pass`] with the sixteen lanes in two AVX-512 registers: each half of a critter's
    /// words is one byte-masked load of its fields (masked bytes are not read, so neither the
    /// rule class nor any padding is), then one rotate-xor-multiply.
    ///
    /// # Safety
    /// The CPU must have AVX-512F, DQ and BW.
    #[target_feature(enable = "avx512f,avx512dq,avx512bw")]
    pub unsafe fn pass<V: Vector>(
        slots: &[Option<Critter<V>>],
        props: &mut StateHasher,
    ) -> Pass<V> {
        let Some([mask_a, mask_b]) = byte_masks::<V>() else {
            return portable_pass(slots, props);
        };
        let k = _mm512_set1_epi64(K as i64);
        let mut a = _mm512_loadu_si512(START[..8].as_ptr().cast());
        let mut b = _mm512_loadu_si512(START[8..].as_ptr().cast());
        let (mut energy, mut momentum) = (0.0, V::zero());
        for c in slots.iter().flatten() {
            add_totals(c, &mut energy, &mut momentum);
            let p: *const i8 = (c as *const Critter<V>).cast();
            // SAFETY: both loads stay inside the critter (`byte_masks` checked every byte they
            // read), and every byte they read is an initialised field.
            let (wa, wb) = unsafe {
                (
                    _mm512_maskz_loadu_epi8(mask_a, p),
                    _mm512_maskz_loadu_epi8(mask_b, p.add(64)),
                )
            };
            a = _mm512_mullo_epi64(_mm512_xor_si512(_mm512_rol_epi64::<5>(a), wa), k);
            b = _mm512_mullo_epi64(_mm512_xor_si512(_mm512_rol_epi64::<5>(b), wb), k);
            if !c.props.is_empty() {
                hash_props(props, c);
            }
        }
        let mut out = [0u64; WORDS];
        // SAFETY: `out` has room for both stores.
        unsafe {
            _mm512_storeu_si512(out[..8].as_mut_ptr().cast(), a);
            _mm512_storeu_si512(out[8..].as_mut_ptr().cast(), b);
        }
        Pass {
            lanes: out,
            energy,
            momentum,
        }
    }
}

/// A critter's properties (how many, then names and values), after its id.
#[inline(never)]
fn hash_props<V: Vector>(h: &mut StateHasher, c: &Critter<V>) {
    h.word(id_word(c));
    h.word(c.props.len() as u64);
    for (name, value) in &c.props {
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
    use crate::critter::PropValue;
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
        let slots = w.critters().slot_slice();
        let (mut p1, mut p2) = (StateHasher::default(), StateHasher::default());
        let fast = pass(slots, &mut p1);
        let portable = portable_pass(slots, &mut p2);
        assert_eq!(p1.finish(), p2.finish(), "properties");
        (fast, portable)
    }

    /// The lanes and the totals' bits (a wall made free has infinite mass: NaN totals).
    fn bits<V: Vector>(p: &Pass<V>) -> (Vec<u64>, u64, Vec<u64>) {
        let momentum = (0..V::DIM).map(|a| p.momentum.get(a).to_bits()).collect();
        (p.lanes.to_vec(), p.energy.to_bits(), momentum)
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
            ("mass", |c| &mut c.mass),
            ("priority", |c| &mut c.priority),
            ("restitution", |c| &mut c.restitution),
            ("health", |c| &mut c.health),
        ];
        for (name, field) in floats {
            fields.push((name.into(), 64, Box::new(move |c, b| flip(field(c), b))));
        }
        let others: [(&str, u32, Other<V>); 6] = [
            ("id.index", 32, |c, b| c.id.index ^= 1 << b),
            ("id.generation", 32, |c, b| c.id.generation ^= 1 << b),
            ("kind", 32, |c, b| c.kind.0 ^= 1 << b),
            ("fixed", 1, |c, _| c.fixed = !c.fixed),
            ("alive", 1, |c, _| c.alive = !c.alive),
            ("props", 1, |c, _| {
                c.props.insert("tag".into(), PropValue::Int(1));
            }),
        ];
        for (name, width, f) in others {
            fields.push((name.into(), width, Box::new(f)));
        }
        for who in [disk, wall] {
            for (field, width, flip) in &fields {
                for bit in 0..*width {
                    let slot = who.index;
                    let c = w.critters.slot_mut(slot).expect("there");
                    let saved = c.clone();
                    flip(c, bit);
                    let (fast, portable) = both(&w);
                    assert_eq!(bits(&fast), bits(&portable), "{field} bit {bit}");
                    assert_ne!(w.state_hash(), h0, "{field} bit {bit} of {who:?}");
                    *w.critters.slot_mut(slot).expect("there") = saved;
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

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_fields_sit_where_the_avx512_loads_read_them() {
        // Otherwise the fast pass would quietly fall back to the portable one.
        assert!(avx512::byte_masks::<glam::DVec2>().is_some());
        assert!(avx512::byte_masks::<glam::DVec3>().is_some());
    }
}
