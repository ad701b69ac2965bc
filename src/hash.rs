//! The per-step state hash: a fast 64-bit hash over raw float bits, so a replay can check itself.

/// Hashes 64-bit words. Not cryptographic: it exists to notice that two runs differ.
#[derive(Clone, Debug)]
pub struct StateHasher {
    h: u64,
}

impl Default for StateHasher {
    fn default() -> Self {
        StateHasher {
            h: 0xCBF2_9CE4_8422_2325,
        }
    }
}

impl StateHasher {
    /// Adds one word.
    #[inline]
    pub fn word(&mut self, w: u64) {
        self.h = (self.h.rotate_left(5) ^ w).wrapping_mul(0x5851_F42D_4C95_7F2D);
    }

    /// Adds the raw bits of a float (so -0.0 and 0.0 differ, as they do in a replay).
    #[inline]
    pub fn float(&mut self, x: f64) {
        self.word(x.to_bits());
    }

    /// The hash, with a final mix so nearby states give unrelated values.
    pub fn finish(&self) -> u64 {
        let mut z = self.h;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
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
}
