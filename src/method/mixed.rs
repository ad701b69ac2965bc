//! A step of `auto` that takes two methods at once, on islands that cannot meet within it (see
//! [`super::islands`]): the Pop-step group (islands at rest and inelastic clumps, solved, with
//! the solve's sleepers)
//! and the event group (islands of impacts in flight, and islands in free flight, which would
//! otherwise cut the solve into substeps for their speed and keep it awake).
//!
//! Each group is stepped by its method's ordinary whole-scene step while the other group's
//! critters are hidden (marked not alive for the length of that step, then shown again): every
//! method already passes over dead critters, so none needs a mask of its own, and the fixed
//! methods stay as they are. Walls and fixed critters are never hidden; a fixed critter that
//! moves would be moved once per group, so a scene with one is stepped whole. The groups go in
//! a fixed order (Pop-step first), so the step's events come in a deterministic order. Each
//! group keeps a broad phase of its own (its Verlet list holds only its critters), both
//! forgotten when a critter changes group; the event flight, under gravity, is set up anew
//! every step anyway, so nothing a group keeps between steps changes the result, and a
//! recording restores and verifies as for any step.
//!
//! While a group is stepped, hooks that look around (`nearby`) do not see the other group:
//! it is out of reach for the whole step.

use super::aside::{bring_back, set_aside};
use super::islands::{Islands, Regime, ASLEEP, NO_ISLAND};
use super::Method;
use crate::step::state::State;
use crate::vector::Vector;

/// A slot's group: the Pop-step group, the event group, or none (walls, fixed, empty).
pub(crate) const POP_GROUP: u8 = 0;
pub(crate) const EVENT_GROUP: u8 = 1;
pub(crate) const NO_GROUP: u8 = u8::MAX;

/// The group of an island's regime. Free islands fly with the event group when `free_flies`
/// (beside islands at rest, whose solve they would otherwise cut into substeps and keep awake).
pub(crate) fn group_of(regime: Regime, free_flies: bool) -> u8 {
    match regime {
        Regime::Resting | Regime::Clump => POP_GROUP,
        Regime::Free if !free_flies => POP_GROUP,
        Regime::Free | Regime::Impact => EVENT_GROUP,
    }
}

/// Each slot's group, from the step's islands (sleepers with the solve).
pub(crate) fn groups_by_slot(islands: &Islands, free_flies: bool, out: &mut Vec<u8>) {
    out.clear();
    out.extend(islands.of_slot.iter().map(|&i| {
        if i == NO_ISLAND {
            NO_GROUP
        } else if i == ASLEEP {
            POP_GROUP // the solve's sleepers
        } else {
            group_of(islands.list[i as usize].regime, free_flies)
        }
    }));
}

/// Sets aside every critter in play of another group than `keep` (their slots in `hidden`).
pub(crate) fn hide<V: Vector>(
    state: &mut State<V>,
    groups: &[u8],
    keep: u8,
    hidden: &mut Vec<u32>,
) {
    let slots = state.critters.slot_count();
    let others = (0..slots).filter(|&i| {
        let group = groups.get(i).copied().unwrap_or(NO_GROUP);
        group != NO_GROUP && group != keep
    });
    set_aside(state, others.map(|i| i as u32), hidden);
}

/// Brings back the critters [`hide`] set aside.
pub(crate) fn show<V: Vector>(state: &mut State<V>, hidden: &mut Vec<u32>) {
    bring_back(state, hidden);
}

/// The step's islands as `critterbox run` reports them: per regime, how many islands and
/// critters, and the method they got.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IslandSummary {
    /// All islands.
    pub islands: usize,
    /// Per regime present (resting, clump, impact, free, in that order).
    pub parts: Vec<IslandPart>,
    /// Sleepers in no island (stepped by the solve, which keeps them still).
    pub asleep: usize,
    /// Bullets flown after the step (see `method::bullets`), in no island.
    pub bullets: usize,
}

/// The islands of one regime.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IslandPart {
    /// Their regime.
    pub regime: Regime,
    /// How many islands.
    pub islands: usize,
    /// How many critters they hold.
    pub critters: usize,
    /// The method they were stepped with.
    pub method: Method,
}

impl IslandSummary {
    /// Sums the islands up, the Pop-step group taking `pop` and the event group `event`
    /// (`free_flies` as for [`group_of`]).
    pub(crate) fn of(
        islands: &Islands,
        pop: Method,
        event: Method,
        free_flies: bool,
    ) -> IslandSummary {
        let mut parts: Vec<IslandPart> = Vec::new();
        for regime in [Regime::Resting, Regime::Clump, Regime::Impact, Regime::Free] {
            let (mut count, mut critters) = (0, 0);
            for island in islands.list.iter().filter(|i| i.regime == regime) {
                count += 1;
                critters += island.size;
            }
            if count > 0 {
                parts.push(IslandPart {
                    regime,
                    islands: count,
                    critters,
                    method: if group_of(regime, free_flies) == POP_GROUP {
                        pop
                    } else {
                        event
                    },
                });
            }
        }
        IslandSummary {
            islands: islands.list.len(),
            parts,
            asleep: islands.of_slot.iter().filter(|&&i| i == ASLEEP).count(),
            bullets: 0,
        }
    }

    /// True when the islands took more than one method.
    pub fn mixed(&self) -> bool {
        self.parts.windows(2).any(|w| w[0].method != w[1].method)
    }
}

impl std::fmt::Display for IslandSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let plural =
            |n: usize, one: &'static str, many: &'static str| if n == 1 { one } else { many };
        write!(
            f,
            "{} {}",
            self.islands,
            plural(self.islands, "island", "islands")
        )?;
        for (k, p) in self.parts.iter().enumerate() {
            write!(
                f,
                "{} {} {} in {} {} {} ({})",
                if k == 0 { ":" } else { ";" },
                p.critters,
                plural(p.critters, "critter", "critters"),
                p.islands,
                plural(p.islands, "island", "islands"),
                p.method,
                p.regime.describe()
            )?;
        }
        let mut sep = if self.parts.is_empty() { ":" } else { ";" };
        if self.asleep > 0 {
            write!(f, "{sep} {} asleep", self.asleep)?;
            sep = ";";
        }
        if self.bullets > 0 {
            write!(
                f,
                "{sep} {} {} too fast for the solve's substeps, flown after it against the rest",
                self.bullets,
                plural(self.bullets, "bullet", "bullets")
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::method::islands::Island;

    /// The summary names each regime's islands, critters and method, as `critterbox run` prints.
    #[test]
    fn the_summary_names_sizes_methods_and_reasons() {
        let island = |first, size, regime| Island {
            first,
            size,
            regime,
        };
        let islands = Islands {
            of_slot: vec![],
            list: vec![
                island(0, 192, Regime::Resting),
                island(192, 5, Regime::Impact),
                island(197, 1, Regime::Free),
            ],
        };
        let s = IslandSummary::of(&islands, Method::Solve(8), Method::Event, false);
        assert!(s.mixed());
        assert_eq!(
            s.to_string(),
            "3 islands: 192 critters in 1 island solve:8 (resting contacts under gravity); \
             5 critters in 1 island event (impacts in flight); \
             1 critter in 1 island solve:8 (in flight, no two meet)"
        );
        let same = IslandSummary::of(&islands, Method::Event, Method::Event, false);
        let flies = IslandSummary::of(&islands, Method::Solve(8), Method::Event, true);
        assert_eq!(flies.parts[2].method, Method::Event);
        assert!(!same.mixed());
    }
}
