//! Pairs of slots: their keys, and the order every list of pairs is put in (lower slot, then
//! higher), which is what makes the response's order independent of how the pairs were found.

/// The key of a pair of slots, whichever comes first: lower slot, then higher, so that keys sort
/// by lower slot and then higher.
pub(crate) fn pair_key(a: u32, b: u32) -> u64 {
    (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
}

/// The (lower, higher) slots of a [`pair_key`].
pub(crate) fn unpair_key(key: u64) -> (u32, u32) {
    ((key >> 32) as u32, key as u32)
}

/// Lists of fewer pairs than this are sorted by comparison; longer ones (a pile's contacts)
/// by radix.
pub(crate) const RADIX_MIN: usize = 256;

/// Bits per digit of the radix sort of pairs.
const RADIX_BITS: u32 = 11;

/// Sorts `pairs` of slots below `slots` by their lower slot, then their higher one, keeping
/// each pair's own order; no pair may be in the list twice (as `(a, b)` and `(b, a)` either).
/// Each pair becomes one integer (lower slot, higher slot, then a bit for "the first is the
/// higher"), sorted a digit at a time from the lowest: a pile's 100,000 contacts in a few
/// passes over them instead of a comparison sort's 17.
/// Returns true when they were in that order already (and nothing was done).
pub(crate) fn sort_pairs(pairs: &mut [(u32, u32)], slots: usize) -> bool {
    if pairs.is_sorted_by_key(|&(a, b)| (a.min(b), a.max(b))) {
        return true;
    }
    let bits = usize::BITS - slots.saturating_sub(1).leading_zeros();
    let width = 2 * bits + 1;
    let key = |&(a, b): &(u32, u32)| {
        (u64::from(a.min(b)) << (bits + 1)) | (u64::from(a.max(b)) << 1) | u64::from(a > b)
    };
    if pairs.len() < RADIX_MIN || width > u64::BITS {
        pairs.sort_unstable_by_key(|&(a, b)| (a.min(b), a.max(b)));
        return false;
    }
    let mut keys: Vec<u64> = pairs.iter().map(key).collect();
    let mut spare = vec![0u64; keys.len()];
    let mask = (1u64 << RADIX_BITS) - 1;
    for shift in (0..width).step_by(RADIX_BITS as usize) {
        let mut start = [0usize; 1 << RADIX_BITS];
        for &k in &keys {
            start[((k >> shift) & mask) as usize] += 1;
        }
        let mut sum = 0;
        for s in &mut start {
            (*s, sum) = (sum, sum + *s);
        }
        for &k in &keys {
            let d = ((k >> shift) & mask) as usize;
            spare[start[d]] = k;
            start[d] += 1;
        }
        std::mem::swap(&mut keys, &mut spare);
    }
    let slot_mask = (1u64 << bits) - 1;
    for (pair, k) in pairs.iter_mut().zip(keys) {
        let (lo, hi) = ((k >> (bits + 1)) as u32, ((k >> 1) & slot_mask) as u32);
        *pair = if k & 1 == 1 { (hi, lo) } else { (lo, hi) };
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The radix sort of pairs gives the comparison sort's order, each pair kept the way round
    /// it was, for slot counts from a handful to 2^31 (where the key no longer fits and the
    /// comparison sort takes over).
    #[test]
    fn pairs_sorted_by_radix_are_in_the_comparison_sort_s_order() {
        let mut rng = crate::Rng::new(11);
        for (slots, n) in [
            (3, 2),
            (40, 300),
            (10_004, 20_000),
            (1 << 20, 5_000),
            (1 << 31, 600),
        ] {
            let mut seen = std::collections::BTreeSet::new();
            let mut pairs = Vec::new();
            while pairs.len() < n {
                let a = (rng.next_f64() * slots as f64) as u32;
                let b = (rng.next_f64() * slots as f64) as u32;
                if a != b && seen.insert((a.min(b), a.max(b))) {
                    pairs.push((a, b));
                }
            }
            let mut expected = pairs.clone();
            expected.sort_by_key(|&(a, b)| (a.min(b), a.max(b)));
            sort_pairs(&mut pairs, slots);
            assert_eq!(pairs, expected, "{slots} slots");
            if n > 100 {
                let ways = |first_higher: bool| pairs.iter().any(|&(a, b)| (a > b) == first_higher);
                assert!(
                    ways(true) && ways(false),
                    "test setup: pairs both ways round"
                );
            }
        }
    }
}
