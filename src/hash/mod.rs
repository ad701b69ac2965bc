//! A fast 64-bit hash over raw words, so a replay can check itself.
//!
//! Eight independent multiply-xor lanes take eight words at a time, so the multiplies overlap
//! instead of waiting on each other, and the lanes are combined at the end. Each lane update
//! `(h.rotate_left(5) ^ w) * K` is a bijection of `h` for a fixed `w` and of `w` for a fixed `h`,
//! so a change in any one word always changes that lane's state. The critters' fields, the bulk
//! of a world's state, have a pass of their own with the same update ([`critters`], on AVX-512
//! where the CPU has it); this hasher takes the world's few other words and that pass's lanes.

pub mod critters;
pub mod statics;

#[cfg(target_arch = "x86_64")]
mod avx512;

#[cfg(test)]
mod tests;

/// The odd multiplier of every lane (here and in [`critters`]).
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
        scramble(z)
    }
}

/// One lane's update: a bijection of `h` for a fixed `w`, and of `w` for a fixed `h`.
#[inline(always)]
fn mix(h: u64, w: u64) -> u64 {
    (h.rotate_left(5) ^ w).wrapping_mul(K)
}

/// splitmix64's finaliser: nearby inputs give unrelated outputs.
#[inline]
const fn scramble(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
