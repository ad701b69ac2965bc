//! The touching spells going on (see the touch stage, `touch`): a pair that touches in
//! consecutive steps is one spell.

use super::access::HookContact;
use crate::critter::CritterId;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A pair, lower id first.
pub(super) type Pair = (CritterId, CritterId);

/// The spells going on, and the pairs touching in the current step.
#[derive(Clone, Debug)]
pub(crate) struct Spells<V> {
    /// Pairs whose spell went on at the end of the last step, ascending.
    pub(super) open: Vec<Pair>,
    /// Pairs touching in this step so far; for a pair not in `open`, its contact when it first
    /// touched, seen from the lower id. Hashed, as every `collide` call asks it; the touch
    /// stage sorts it.
    pub(super) now: HashMap<Pair, Option<HookContact<V>>, BuildHasherDefault<PairHasher>>,
}

/// A multiply-rotate hash of a pair's words: ids are small integers, which need no defence
/// against chosen collisions, and the std SipHash would cost more than the map's other work.
#[derive(Default)]
pub(super) struct PairHasher(u64);

impl Hasher for PairHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u32(&mut self, word: u32) {
        self.write_u64(u64::from(word));
    }
    fn write_u64(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
}

impl<V> Default for Spells<V> {
    fn default() -> Self {
        Spells {
            open: Vec::new(),
            now: HashMap::default(),
        }
    }
}

impl<V> Spells<V> {
    /// True while `a` and `b` are in a spell that went on at the end of the last step.
    pub(crate) fn is_open(&self, a: CritterId, b: CritterId) -> bool {
        self.open.binary_search(&ordered(a, b)).is_ok()
    }

    /// Forgets every spell (a world put back in a recorded state).
    pub(crate) fn clear(&mut self) {
        self.open.clear();
        self.now.clear();
    }
}

pub(super) fn ordered(a: CritterId, b: CritterId) -> Pair {
    if a <= b {
        (a, b)
    } else {
        (b, a)
    }
}
