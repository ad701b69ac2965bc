//! The ids that name critters and kinds: small copyable handles that every layer passes around.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// A stable critter id: a slot index and the generation of that slot.
///
/// When a critter dies its slot may be reused, but with the next generation, so the id of a dead
/// critter never names a new one. Ids order by index, then generation.
///
/// Written `#20v5` (index 20, generation 5), or `#20` for generation 0: so scripts (`me.id`),
/// logs, recordings, `inspect`, `export` and `diff` print it. [`str::parse`] reads that form
/// back, and also `20v5` and `20`.
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

/// The error of a text that is no critter id (see [`CritterId`]'s `FromStr`).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("'{text}' is not a critter id: an id reads #20v5 (index 20, generation 5), 20v5, or #20 or 20 for generation 0, as me.id and the logs print it")]
pub struct ParseCritterIdError {
    /// The text as given.
    pub text: String,
}

impl FromStr for CritterId {
    type Err = ParseCritterIdError;

    /// Reads `#20v5`, `20v5`, `#20` and `20`, and the handle's `critter #20v5`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || ParseCritterIdError {
            text: s.to_string(),
        };
        let t = s.trim();
        let t = t.strip_prefix("critter ").unwrap_or(t);
        let t = t.strip_prefix('#').unwrap_or(t);
        let (index, generation) = t.split_once('v').unwrap_or((t, "0"));
        // `u32::from_str` takes a leading `+`; an id is digits only.
        let number = |d: &str| {
            if d.is_empty() || !d.bytes().all(|b| b.is_ascii_digit()) {
                None
            } else {
                d.parse::<u32>().ok()
            }
        };
        Ok(CritterId {
            index: number(index).ok_or_else(bad)?,
            generation: number(generation).ok_or_else(bad)?,
        })
    }
}

/// Index of a kind in a world's [`KindSet`](crate::KindSet).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct KindId(pub u32);

#[cfg(test)]
mod tests {
    use super::*;

    fn id(index: u32, generation: u32) -> CritterId {
        CritterId { index, generation }
    }

    #[test]
    fn an_id_reads_back_what_it_prints() {
        for c in [id(0, 0), id(20, 5), id(7, 0), id(u32::MAX, u32::MAX)] {
            assert_eq!(c.to_string().parse::<CritterId>(), Ok(c));
        }
        assert_eq!(id(20, 5).to_string(), "#20v5");
        assert_eq!(id(20, 0).to_string(), "#20");
    }

    #[test]
    fn an_id_reads_without_its_hash_and_generation() {
        assert_eq!("20v5".parse::<CritterId>(), Ok(id(20, 5)));
        assert_eq!("20".parse::<CritterId>(), Ok(id(20, 0)));
        assert_eq!("#20".parse::<CritterId>(), Ok(id(20, 0)));
        assert_eq!(" critter #3v1 ".parse::<CritterId>(), Ok(id(3, 1)));
    }

    #[test]
    fn a_text_that_is_no_id_is_an_error_that_shows_the_form() {
        for bad in [
            "",
            "#",
            "v5",
            "#20v",
            "20 v5",
            "+20",
            "-1",
            "#20v5v1",
            "x20",
            "4294967296",
        ] {
            let e = bad.parse::<CritterId>().expect_err(bad);
            assert_eq!(e.text, bad);
            assert!(e.to_string().contains("#20v5"), "{e}");
        }
    }
}
