//! The ids that name critters and kinds: small copyable handles that every layer passes around.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A stable critter id: a slot index and the generation of that slot.
///
/// When a critter dies its slot may be reused, but with the next generation, so the id of a dead
/// critter never names a new one. Ids order by index, then generation.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[repr(C)]
pub struct CritterId {
    /// Slot index in the world's critter set.
    pub index: u32,
    /// How many times the slot has been reused.
    pub generation: u32,
}

impl fmt::Debug for CritterId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "#{}", self.index)?;
        if self.generation > 0 {
            write!(f, "v{}", self.generation)?;
        }
        Ok(())
    }
}

impl fmt::Display for CritterId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self, f)
    }
}

/// Index of a kind in a world's [`KindSet`](crate::KindSet).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct KindId(pub u32);
