//! Storage for critters: slots addressed by generational ids, O(1) insert and remove.
//!
//! A removed critter's id index goes on a free list and is reused with the next generation, so
//! ids stay stable and a dead critter's id never names a new one. Iteration is in id order:
//! deterministic, whatever was added or removed.
//!
//! The critters are stored by *slot*. Until `CritterSet::arrange` is called a critter's slot is
//! its id's index; `arrange` moves them to other slots (the world lays a large gas out along its
//! grid, so that critters near each other in space are near each other in memory) and a table
//! then maps each id to its slot. The engine's passes go in slot order; everything seen from
//! outside (iteration, the state hash, the totals) goes in id order, so where the critters are
//! stored never shows.

use crate::critter::{Critter, CritterId, Traits};
use crate::hash::statics::Statics;
use crate::vector::Vector;
use std::sync::Arc;

/// The critters of a world.
///
/// Every mutable accessor marks the critters as possibly changed in any field, so the next
/// state hash reads them whole; the engine's own `*_moving` accessors, which write positions,
/// velocities and rule classes only, do not (see `hash::statics::Statics`).
#[derive(Clone, Debug)]
pub struct CritterSet<V: Vector> {
    /// The critters by slot.
    slots: Vec<Option<Critter<V>>>,
    /// By id index: the generation of its current or next critter.
    generations: Vec<u32>,
    /// Free id indices (the last is reused first).
    free: Vec<u32>,
    /// By id index: the slot of its critter ([`NO_SLOT`] if none). Empty while every critter's
    /// slot is its id's index.
    place: Vec<u32>,
    live: usize,
    statics: Statics,
    /// The mark of the last [`CritterSet::mark_untouched`], or 0 once a mutable accessor has
    /// been called since (the engine's `*_moving` ones too).
    untouched: u64,
    /// The traits of the critter added last, which the next one shares if it is alike (see
    /// [`Traits::same_plain`]): a gas spawned from one kind keeps one copy.
    shared: Option<Arc<Traits<V>>>,
}

/// In [`CritterSet`]'s table of slots: an id index with no critter.
const NO_SLOT: u32 = u32::MAX;

/// The critters of a set seen in id order: the slots, and by id index the slot of its critter
/// (empty when every critter's slot is its id's index). The state hash and totals go through
/// this, so they do not depend on where the critters are stored.
#[derive(Clone, Copy, Debug)]
pub(crate) struct InIdOrder<'a, V: Vector> {
    /// The critters by slot.
    pub slots: &'a [Option<Critter<V>>],
    /// By id index, the slot ([`u32::MAX`] for none); empty for slot = id index.
    pub place: &'a [u32],
}

impl<'a, V: Vector> From<&'a [Option<Critter<V>>]> for InIdOrder<'a, V> {
    fn from(slots: &'a [Option<Critter<V>>]) -> Self {
        InIdOrder { slots, place: &[] }
    }
}

impl<'a, V: Vector> InIdOrder<'a, V> {
    /// How many id indices there are.
    pub fn len(&self) -> usize {
        if self.place.is_empty() {
            self.slots.len()
        } else {
            self.place.len()
        }
    }

    /// The critter of id index `i`.
    #[inline]
    pub fn at(&self, i: usize) -> Option<&'a Critter<V>> {
        let slot = if self.place.is_empty() {
            i
        } else {
            self.place[i] as usize
        };
        self.slots.get(slot).and_then(Option::as_ref)
    }
}

impl<V: Vector> Default for CritterSet<V> {
    fn default() -> Self {
        CritterSet {
            slots: Vec::new(),
            generations: Vec::new(),
            free: Vec::new(),
            place: Vec::new(),
            live: 0,
            statics: Statics::default(),
            untouched: 0,
            shared: None,
        }
    }
}

impl<V: Vector> CritterSet<V> {
    /// Inserts the critter built by `make` for its new id. O(1) amortised.
    pub fn insert(&mut self, make: impl FnOnce(CritterId) -> Critter<V>) -> CritterId {
        self.untouched = 0;
        self.statics.forget();
        let index = match self.free.pop() {
            Some(i) => i,
            None => {
                self.generations.push(0);
                if self.place.is_empty() {
                    self.slots.push(None);
                } else {
                    self.place.push(NO_SLOT);
                }
                (self.generations.len() - 1) as u32
            }
        };
        let id = CritterId {
            index,
            generation: self.generations[index as usize],
        };
        let mut critter = make(id);
        self.share(&mut critter);
        let critter = Some(critter);
        if self.place.is_empty() {
            self.slots[index as usize] = critter;
        } else {
            // Arranged: a new critter goes in a new slot at the end, until the next arrangement.
            self.place[index as usize] = self.slots.len() as u32;
            self.slots.push(critter);
        }
        self.live += 1;
        id
    }

    /// Gives `c` the traits of the critter added before it, if the two are alike.
    fn share(&mut self, c: &mut Critter<V>) {
        match &self.shared {
            Some(s) if Arc::ptr_eq(s, &c.traits) => {}
            Some(s) if s.same_plain(&c.traits) => c.traits = Arc::clone(s),
            _ => self.shared = Some(Arc::clone(&c.traits)),
        }
    }

    /// Makes room for `additional` more critters than there are slots now, exactly: a scene that
    /// knows how many it will spawn does not leave the slots' doubling growth unused (at a
    /// million critters up to 64 MB).
    pub fn reserve(&mut self, additional: usize) -> Result<(), std::collections::TryReserveError> {
        self.slots.try_reserve_exact(additional)?;
        self.generations.try_reserve_exact(additional)?;
        if !self.place.is_empty() {
            self.place.try_reserve_exact(additional)?;
        }
        Ok(())
    }

    /// The slot of critter `id`, if it is there.
    #[inline]
    pub fn slot_of(&self, id: CritterId) -> Option<u32> {
        self.slot_of_index(id.index).filter(|&slot| {
            self.slots[slot as usize]
                .as_ref()
                .is_some_and(|c| c.id == id)
        })
    }

    /// How many id indices there are (live or free): id indices are below this.
    pub(crate) fn index_count(&self) -> usize {
        self.generations.len()
    }

    /// The slot of the critter with id index `index`, if there is one.
    #[inline]
    pub(crate) fn slot_of_index(&self, index: u32) -> Option<u32> {
        let slot = if self.place.is_empty() {
            index
        } else {
            *self.place.get(index as usize)?
        };
        self.slots
            .get(slot as usize)
            .is_some_and(Option::is_some)
            .then_some(slot)
    }

    /// True once `CritterSet::arrange` has put critters in slots other than their ids'.
    pub fn is_arranged(&self) -> bool {
        !self.place.is_empty()
    }

    /// The critters seen in id order (see [`InIdOrder`]).
    pub(crate) fn in_id_order(&self) -> InIdOrder<'_, V> {
        InIdOrder {
            slots: &self.slots,
            place: &self.place,
        }
    }

    /// Moves the critters to new slots in the order of `keys` (one per slot, below `u32::MAX`
    /// for an occupied one and `u32::MAX` for an empty one; ties in slot order), the empty
    /// slots dropped. Ids do not change. The moves follow the permutation's
    /// cycles in place, so no second copy of the critters is made; the only other memory is the
    /// table from ids to slots, which the moves use first for the order.
    ///
    /// # Panics
    /// If `keys` is not one per slot, or there are 2^31 slots or more.
    pub(crate) fn arrange(&mut self, keys: &[u32]) {
        self.untouched = 0;
        use rayon::prelude::*;
        const DONE: u32 = 1 << 31;
        let n = self.slots.len();
        assert!(keys.len() == n && n < DONE as usize, "a key per slot");
        // Slot k takes the critter of slot order[k]; the empty slots go last.
        let mut order = std::mem::take(&mut self.place);
        order.clear();
        order.extend(0..n as u32);
        order.par_sort_unstable_by_key(|&s| (keys[s as usize], s));
        // Follow each cycle, marking what is done.
        for start in 0..n {
            if order[start] & DONE != 0 {
                continue;
            }
            let mut k = start;
            loop {
                let from = order[k] as usize;
                order[k] |= DONE;
                if from == start {
                    break;
                }
                self.slots.swap(k, from);
                k = from;
            }
        }
        self.slots.truncate(self.live);
        debug_assert!(self.slots.iter().all(Option::is_some));
        order.clear();
        order.resize(self.generations.len(), NO_SLOT);
        for (slot, c) in self.slots.iter().enumerate() {
            if let Some(c) = c {
                order[c.id.index as usize] = slot as u32;
            }
        }
        self.place = order;
    }

    /// Puts every critter back in the slot its id's index names (undoes `CritterSet::arrange`).
    pub(crate) fn unarrange(&mut self) {
        self.untouched = 0;
        if self.place.is_empty() {
            return;
        }
        let n = self.generations.len();
        self.slots.resize_with(self.slots.len().max(n), || None);
        // Slot k takes the critter of id index k: follow each cycle by the critters' ids.
        for start in 0..self.slots.len() {
            while let Some(c) = &self.slots[start] {
                let home = c.id.index as usize;
                if home == start {
                    break;
                }
                self.slots.swap(start, home);
            }
        }
        self.slots.truncate(n);
        self.place = Vec::new();
    }

    /// Removes critter `id`, if it is there. O(1).
    pub fn remove(&mut self, id: CritterId) -> Option<Critter<V>> {
        self.untouched = 0;
        let i = id.index as usize;
        let slot = self.slot_of(id)? as usize;
        self.statics.forget();
        let critter = self.slots[slot].take()?;
        if !self.place.is_empty() {
            self.place[i] = NO_SLOT;
        }
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
        self.slot(self.slot_of(id)?)
    }

    /// The critter with id `id`, mutably.
    #[inline]
    pub fn get_mut(&mut self, id: CritterId) -> Option<&mut Critter<V>> {
        let slot = self.slot_of(id)?;
        self.slot_mut(slot)
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
        self.untouched = 0;
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
        self.untouched = 0;
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

    /// The critters, in id order.
    pub fn iter(&self) -> impl Iterator<Item = &Critter<V>> {
        let view = self.in_id_order();
        (0..view.len()).filter_map(move |i| view.at(i))
    }

    /// The critters, in slot order (the engine's passes, where order does not count).
    pub(crate) fn iter_stored(&self) -> impl Iterator<Item = &Critter<V>> {
        self.slots.iter().filter_map(Option::as_ref)
    }

    /// The critters, in parallel (each is visited by one thread).
    pub fn par_iter_mut(&mut self) -> impl rayon::iter::ParallelIterator<Item = &mut Critter<V>> {
        self.untouched = 0;
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
        self.untouched = 0;
        &mut self.slots
    }

    /// Marks the critters as untouched from now on: the mark returned, unique to this call, is
    /// what [`CritterSet::untouched_since`] compares (a clone keeps it, with the same critters).
    pub(crate) fn mark_untouched(&mut self) -> u64 {
        static MARKS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        self.untouched = MARKS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.untouched
    }

    /// No mutable accessor was called since the [`CritterSet::mark_untouched`] that returned
    /// `mark`.
    pub(crate) fn untouched_since(&self, mark: u64) -> bool {
        mark != 0 && self.untouched == mark
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
            place: Vec::new(),
            live: 0,
            statics: Statics::default(),
            untouched: 0,
            shared: None,
        };
        for mut c in critters {
            let i = c.id.index as usize;
            if set.slots[i].is_some() {
                return None;
            }
            set.share(&mut c);
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

    /// The critters, mutably, in slot order: id order unless [`CritterSet::is_arranged`].
    pub fn iter_mut(&mut self) -> impl Iterator<Item = &mut Critter<V>> {
        self.statics.forget();
        self.iter_mut_moving()
    }

    /// The critters in slot order, mutably, for the engine's writes of position, velocity and
    /// rule class only.
    pub(crate) fn iter_mut_moving(&mut self) -> impl Iterator<Item = &mut Critter<V>> {
        self.untouched = 0;
        self.slots.iter_mut().filter_map(Option::as_mut)
    }
}
