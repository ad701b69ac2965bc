//! The per-step state hash: a fast 64-bit hash over raw float bits, so a replay can check itself.
//!
//! Recording hashes every step, so the hash must cost little next to a step: eight independent
//! multiply-xor lanes take eight words at a time (two critters of four words each), so the
//! multiplies overlap instead of waiting on each other, and the lanes are combined at the end.
//! A critter's fields are folded into four words with [`pair`] and [`quad`] (fields XORed at
//! distinct rotations), which halves the multiplies of one word per field pair; any one field
//! changing alone still changes its word. Each lane update
//! `(h.rotate_left(5) ^ w) * K` is a bijection of `h` for a fixed `w` and of `w` for a fixed `h`,
//! so a change in any one word always changes that lane's state.

/// The odd multiplier of every lane.
const K: u64 = 0x5851_F42D_4C95_7F2D;

/// Hashes 64-bit words. Not cryptographic: it exists to notice that two runs differ.
#[derive(Clone, Debug)]
pub struct StateHasher {
    lanes: [u64; LANES],
}

/// Number of lanes, and words per [`StateHasher::words`] call.
pub const LANES: usize = 8;

impl Default for StateHasher {
    fn default() -> Self {
        StateHasher {
            lanes: [
                0xCBF2_9CE4_8422_2325,
                0x9E37_79B9_7F4A_7C15,
                0xBF58_476D_1CE4_E5B9,
                0x94D0_49BB_1331_11EB,
                0xA076_1D64_78BD_642F,
                0xE703_7ED1_A0B4_28DB,
                0x8EBC_6AF0_9C88_C6E3,
                0x5899_65CC_7537_4CC3,
            ],
        }
    }
}

impl StateHasher {
    /// Adds one word (to the first lane).
    #[inline]
    pub fn word(&mut self, w: u64) {
        self.lanes[0] = mix(self.lanes[0], w);
    }

    /// Adds eight words, one to each lane: the fast path for bulk state.
    #[inline]
    pub fn words(&mut self, w: [u64; LANES]) {
        for (lane, w) in self.lanes.iter_mut().zip(w) {
            *lane = mix(*lane, w);
        }
    }

    /// Adds the raw bits of a float (so -0.0 and 0.0 differ, as they do in a replay).
    #[inline]
    pub fn float(&mut self, x: f64) {
        self.word(x.to_bits());
    }

    /// The hash: the lanes folded in order, with a final mix so nearby states give unrelated
    /// values.
    pub fn finish(&self) -> u64 {
        let mut z = self.lanes[0];
        for &lane in &self.lanes[1..] {
            z = mix(z, lane);
        }
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// Two floats' bits in one word: `a ^ rotl(b, 32)` changes whenever either changes alone.
#[inline]
pub fn pair(a: f64, b: f64) -> u64 {
    a.to_bits() ^ b.to_bits().rotate_left(32)
}

/// Four floats' bits in one word, each at its own rotation (0, 32, 16, 48 bits): the word
/// changes whenever any one of them changes alone.
#[inline]
pub fn quad(a: f64, b: f64, c: f64, d: f64) -> u64 {
    pair(a, b) ^ pair(c, d).rotate_left(16)
}

#[inline]
fn mix(h: u64, w: u64) -> u64 {
    (h.rotate_left(5) ^ w).wrapping_mul(K)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        // Either half of a pair alone changes the pair.
        assert_ne!(
            pair(1.0, 2.0),
            pair(1.0, f64::from_bits(2.0f64.to_bits() ^ 1))
        );
        assert_ne!(
            pair(1.0, 2.0),
            pair(f64::from_bits(1.0f64.to_bits() ^ 1), 2.0)
        );
    }

    #[test]
    fn any_one_of_four_floats_changes_its_word_at_every_bit() {
        let base = [1.5f64, -2.25, 3.0e-7, 4.0e9];
        let word = |x: [f64; 4]| quad(x[0], x[1], x[2], x[3]);
        let w0 = word(base);
        for i in 0..4 {
            for bit in 0..64 {
                let mut x = base;
                x[i] = f64::from_bits(x[i].to_bits() ^ (1 << bit));
                assert_ne!(word(x), w0, "float {i} bit {bit}");
            }
        }
    }
}
