//! Hints to the processor to start loading memory that a loop will read a few iterations on:
//! the critters of a pair list are scattered, and their loads overlap only when asked early.

/// A hint to start loading `slot`'s first cache line (nothing for `None`).
#[inline]
pub(crate) fn prefetch<T>(slot: Option<&T>) {
    #[cfg(target_arch = "x86_64")]
    if let Some(slot) = slot {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: a prefetch only hints the cache (it never faults, whatever the address),
        // and SSE is in every x86_64 target.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(slot).cast()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = slot;
}

/// A hint to start loading every cache line `slot` spans (nothing for `None`): a critter
/// record that straddles lines is read in more than its first.
#[inline]
pub(crate) fn prefetch_whole<T>(slot: Option<&T>) {
    #[cfg(target_arch = "x86_64")]
    if let Some(slot) = slot {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let start = std::ptr::from_ref(slot).cast::<i8>();
        // The offsets from `start` of each line's first byte, from `start`'s line to the
        // line of the value's last byte.
        let into = start as usize % 64;
        let span = into + std::mem::size_of::<T>().max(1);
        for line in (0..span).step_by(64) {
            // SAFETY: as in `prefetch` (the address is only hinted, never read).
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(line).wrapping_sub(into)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = slot;
}
