//! Storage for critters: slots addressed by generational ids, O(1) insert and remove.
//!
//! A removed critter's slot goes on a free list and is reused with the next generation, so ids
//! stay stable and a dead critter's id never names a new one. Iteration is in slot order:
//! deterministic, whatever was added or removed.

use crate::critter::{Critter, CritterId};
use crate::critter_hash::Statics;
use crate::vector::Vector;

/// The critters of a world.
///
/// Every mutable accessor marks the critters as possibly changed in any field, so the next
/// state hash reads them whole; the engine's own `*_moving` accessors, which write positions,
/// velocities and rule classes only, do not (see [`Statics`]).
#[derive(Clone, Debug)]
pub struct CritterSet<V: Vector> {
    slots: Vec<Option<Critter<V>>>,
    generations: Vec<u32>,
    free: Vec<u32>,
    live: usize,
    statics: Statics,
}

impl<V: Vector> Default for CritterSet<V> {
    fn default() -> Self {
        CritterSet {
            slots: Vec::new(),
            generations: Vec::new(),
            free: Vec::new(),
            live: 0,
            statics: Statics::default(),
        }
    }
}

impl<V: Vector> CritterSet<V> {
    /// Inserts the critter built by `make` for its new id. O(1) amortised.
    pub fn insert(&mut self, make: impl FnOnce(CritterId) -> Critter<V>) -> CritterId {
        self.statics.forget();
        let index = match self.free.pop() {
            Some(i) => i,
            None => {
                self.slots.push(None);
                self.generations.push(0);
                (self.slots.len() - 1) as u32
            }
        };
        let id = CritterId {
            index,
            generation: self.generations[index as usize],
        };
        self.slots[index as usize] = Some(make(id));
        self.live += 1;
        id
    }

    /// Makes room for `additional` more critters than there are slots now, exactly: a scene that
    /// knows how many it will spawn does not leave the slots' doubling growth unused (at a
    /// million critters up to 64 MB).
    pub fn reserve(&mut self, additional: usize) {
        self.slots.reserve_exact(additional);
        self.generations.reserve_exact(additional);
    }

    /// Removes critter `id`, if it is there. O(1).
    pub fn remove(&mut self, id: CritterId) -> Option<Critter<V>> {
        let i = id.index as usize;
        if self.generations.get(i) != Some(&id.generation) {
            return None;
        }
        self.statics.forget();
        let critter = self.slots[i].take()?;
        self.live -= 1;
        // A slot whose generation would wrap is retired rather than reused.
        if let Some(next) = self.generations[i].checked_add(1) {
            self.generations[i] = next;
            self.free.push(id.index);
        }
        Some(critter)
    }

    /// The critter with id `id`, if it is still there.
    #[inline]
    pub fn get(&self, id: CritterId) -> Option<&Critter<V>> {
        match self.slots.get(id.index as usize) {
            Some(Some(c)) if c.id == id => Some(c),
            _ => None,
        }
    }

    /// The critter with id `id`, mutably.
    #[inline]
    pub fn get_mut(&mut self, id: CritterId) -> Option<&mut Critter<V>> {
        self.statics.forget();
        match self.slots.get_mut(id.index as usize) {
            Some(Some(c)) if c.id == id => Some(c),
            _ => None,
        }
    }

    /// The critter in slot `index`.
    #[inline]
    pub fn slot(&self, index: u32) -> Option<&Critter<V>> {
        self.slots.get(index as usize).and_then(Option::as_ref)
    }

    /// The critter in slot `index`, mutably.
    #[inline]
    pub fn slot_mut(&mut self, index: u32) -> Option<&mut Critter<V>> {
        self.statics.forget();
        self.slot_mut_moving(index)
    }

    /// [`CritterSet::slot_mut`] for the engine's writes of position, velocity and rule class
    /// only (anything else written through it would leave the next state hash stale).
    #[inline]
    pub(crate) fn slot_mut_moving(&mut self, index: u32) -> Option<&mut Critter<V>> {
        self.slots.get_mut(index as usize).and_then(Option::as_mut)
    }

    /// Two different occupied slots, both mutably.
    ///
    /// # Panics
    /// If `a == b` or either slot is empty: callers pass slots from this step's pairs.
    #[inline]
    pub fn pair_mut(&mut self, a: u32, b: u32) -> (&mut Critter<V>, &mut Critter<V>) {
        self.statics.forget();
        self.pair_mut_moving(a, b)
    }

    /// [`CritterSet::pair_mut`] for the engine's writes of position and velocity only.
    #[inline]
    pub(crate) fn pair_mut_moving(&mut self, a: u32, b: u32) -> (&mut Critter<V>, &mut Critter<V>) {
        assert_ne!(a, b, "a critter cannot collide with itself");
        let (a, b) = (a as usize, b as usize);
        let (first, second) = if a < b {
            let (lo, hi) = self.slots.split_at_mut(b);
            (&mut lo[a], &mut hi[0])
        } else {
            let (lo, hi) = self.slots.split_at_mut(a);
            (&mut hi[0], &mut lo[b])
        };
        match (first.as_mut(), second.as_mut()) {
            (Some(x), Some(y)) => (x, y),
            _ => panic!("pair_mut on an empty slot"),
        }
    }

    /// Number of critters.
    pub fn len(&self) -> usize {
        self.live
    }

    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// Number of slots (live or free): slot indices are below this.
    pub fn slot_count(&self) -> usize {
        self.slots.len()
    }

    /// The critters, in slot order.
    pub fn iter(&self) -> impl Iterator<Item = &Critter<V>> {
        self.slots.iter().filter_map(Option::as_ref)
    }

    /// The critters, in slot order, in parallel (each is visited by one thread).
    pub fn par_iter_mut(&mut self) -> impl rayon::iter::ParallelIterator<Item = &mut Critter<V>> {
        self.statics.forget();
        use rayon::prelude::*;
        self.slots.par_iter_mut().filter_map(Option::as_mut)
    }

    /// Every slot, in order (empty ones are `None`).
    pub(crate) fn slot_slice(&self) -> &[Option<Critter<V>>] {
        &self.slots
    }

    /// Every slot, mutably, for the engine's writes of position and velocity only.
    pub(crate) fn slots_mut_moving(&mut self) -> &mut [Option<Critter<V>>] {
        &mut self.slots
    }

    /// The hash lanes kept for the critters' rarely changing words.
    pub(crate) fn statics(&self) -> &Statics {
        &self.statics
    }

    /// Drops the kept hash lanes (tests compare a hash that reused them with one that did not).
    #[cfg(test)]
    pub(crate) fn forget_statics(&mut self) {
        self.statics.forget();
    }

    /// The free slots, in the order they are kept (the last is reused first), as the ids their
    /// next critters will get.
    pub fn free_ids(&self) -> impl Iterator<Item = CritterId> + '_ {
        self.free.iter().map(|&index| CritterId {
            index,
            generation: self.generations[index as usize],
        })
    }

    /// A set rebuilt from its parts: the critters by slot (their ids give the slots'
    /// generations) and the free list as the ids their next critters get. Slots that are
    /// neither are retired. `None` if the parts contradict each other.
    pub(crate) fn from_parts(critters: Vec<Critter<V>>, free: &[CritterId]) -> Option<Self> {
        let slots_needed = critters
            .iter()
            .map(|c| c.id.index)
            .chain(free.iter().map(|id| id.index))
            .max()
            .map_or(0, |m| m as usize + 1);
        let mut set = CritterSet {
            slots: (0..slots_needed).map(|_| None).collect(),
            generations: vec![u32::MAX; slots_needed],
            free: Vec::with_capacity(free.len()),
            live: 0,
            statics: Statics::default(),
        };
        for c in critters {
            let i = c.id.index as usize;
            if set.slots[i].is_some() {
                return None;
            }
            set.generations[i] = c.id.generation;
            set.slots[i] = Some(c);
            set.live += 1;
        }
        for id in free {
            let i = id.index as usize;
            if set.slots[i].is_some() || set.generations[i] != u32::MAX {
                return None;
            }
            set.generations[i] = id.generation;
            set.free.push(id.index);
        }
        Some(set)
    }

    /// The critters, in slot order, mutably.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = &mut Critter<V>> {
        self.statics.forget();
        self.iter_mut_moving()
    }

    /// [`CritterSet::iter_mut`] for the engine's writes of position, velocity and rule class
    /// only.
    pub(crate) fn iter_mut_moving(&mut self) -> impl Iterator<Item = &mut Critter<V>> {
        self.slots.iter_mut().filter_map(Option::as_mut)
    }
}
