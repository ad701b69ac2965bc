//! The split of a critter's hashed words into the moving ones (what a step without hooks
//! writes) and the static rest, and the static lanes a critter set keeps between hashes.

use std::sync::{Mutex, PoisonError};

/// Words per critter.
pub const WORDS: usize = 16;

/// The first `MOVING` words of a critter hold everything a step changes when no hook writes to
/// the critters: position, velocity, radius and mass (and in 2D id and flags).
pub const MOVING: usize = 8;

/// The words after the first [`MOVING`]: kind, priority, restitution, health (and in 3D id and
/// flags).
pub const STATIC: usize = WORDS - MOVING;

/// What the last whole pass over a set of critters left in the static lanes and in the
/// properties' hash.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct StaticHash {
    pub(super) lanes: [u64; STATIC],
    pub(super) props: u64,
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
pub struct Statics(pub(super) Mutex<Option<StaticHash>>);

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
