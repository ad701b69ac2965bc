//! The event queue of the flight: one pending event per critter, in an indexed binary min-heap.
//!
//! A critter's new prediction replaces its old event in place (sifted up or down), so the heap
//! never holds more than one entry per critter and has no stale entries to pop and skip (lazy
//! deletion let it grow to several per critter). Entries are ordered by time, then owner: each
//! owner has one entry, so that order is total and a run repeats bit for bit. The two are packed
//! into one integer key (the time's bits mapped to an order-keeping integer, then the owner), so
//! a comparison is one integer comparison.

const NONE: u32 = u32::MAX;
/// Children per node. Measured on the 2D gas: 2 beat 4 (more instructions per level).
const ARITY: usize = 2;

/// What the queue needs of an event: its time and its owner.
pub(crate) trait Owned: Copy {
    fn time(&self) -> f64;
    fn owner(&self) -> u32;
}

pub(crate) struct Queue<E> {
    /// Keys (`key`: time, then owner), a min-heap: the children of `i` are `ARITY i + 1..`.
    heap: Vec<u128>,
    /// Each owner's place in `heap`, or `NONE`.
    at: Vec<u32>,
    /// Each owner's event (meaningful while `at` is set).
    events: Vec<Option<E>>,
}

impl<E> Default for Queue<E> {
    fn default() -> Self {
        Self {
            heap: Vec::new(),
            at: Vec::new(),
            events: Vec::new(),
        }
    }
}

/// The heap key of an event at `time` owned by `owner`: ordered as `f64::total_cmp` orders the
/// times, then by owner.
#[inline]
fn key(time: f64, owner: u32) -> u128 {
    let bits = time.to_bits() as i64;
    // total_cmp's map to a signed integer, then shifted to unsigned.
    let ordered = (bits ^ ((((bits >> 63) as u64) >> 1) as i64)) as u64 ^ (1 << 63);
    (u128::from(ordered) << 32) | u128::from(owner)
}

#[inline]
fn owner_of(key: u128) -> u32 {
    key as u32
}

impl<E: Owned> Queue<E> {
    /// Empties the queue for owners `0..n`.
    pub fn reset(&mut self, n: usize) {
        self.heap.clear();
        self.at.clear();
        self.at.resize(n, NONE);
        self.events.clear();
        self.events.resize_with(n, || None);
    }

    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.heap.len()
    }

    /// Makes `e` its owner's pending event, replacing the one it had.
    pub fn set(&mut self, e: E) {
        let a = e.owner();
        let entry = key(e.time(), a);
        self.events[a as usize] = Some(e);
        let i = self.at[a as usize];
        if i == NONE {
            self.heap.push(entry);
            self.sift_up(self.heap.len() - 1);
        } else {
            let i = i as usize;
            let old = self.heap[i];
            self.heap[i] = entry;
            if entry < old {
                self.sift_up(i);
            } else {
                self.sift_down(i);
            }
        }
    }

    /// Drops owner `a`'s pending event, if it has one.
    pub fn remove(&mut self, a: u32) {
        let i = self.at[a as usize];
        if i == NONE {
            return;
        }
        self.at[a as usize] = NONE;
        self.events[a as usize] = None;
        let last = self.heap.pop().expect("an entry is in the heap");
        let i = i as usize;
        if i < self.heap.len() {
            self.heap[i] = last;
            if i > 0 && last < self.heap[(i - 1) / ARITY] {
                self.sift_up(i);
            } else {
                self.sift_down(i);
            }
        }
    }

    /// The earliest event, left in the queue: a caller that predicts its owner again next
    /// replaces it in place, one sift instead of a removal and an insertion.
    #[inline]
    pub fn peek(&self) -> Option<E> {
        let &k = self.heap.first()?;
        self.events[owner_of(k) as usize]
    }

    /// Takes the earliest event out of the queue.
    #[cfg(test)]
    pub fn pop(&mut self) -> Option<E> {
        let a = owner_of(*self.heap.first()?);
        let e = self.events[a as usize];
        self.remove(a);
        e
    }

    fn sift_up(&mut self, mut i: usize) {
        let entry = self.heap[i];
        while i > 0 {
            let parent = (i - 1) / ARITY;
            if entry >= self.heap[parent] {
                break;
            }
            self.heap[i] = self.heap[parent];
            self.at[owner_of(self.heap[i]) as usize] = i as u32;
            i = parent;
        }
        self.heap[i] = entry;
        self.at[owner_of(entry) as usize] = i as u32;
    }

    fn sift_down(&mut self, mut i: usize) {
        let entry = self.heap[i];
        let n = self.heap.len();
        loop {
            let first = ARITY * i + 1;
            if first >= n {
                break;
            }
            let mut child = first;
            for c in first + 1..(first + ARITY).min(n) {
                if self.heap[c] < self.heap[child] {
                    child = c;
                }
            }
            if self.heap[child] >= entry {
                break;
            }
            self.heap[i] = self.heap[child];
            self.at[owner_of(self.heap[i]) as usize] = i as u32;
            i = child;
        }
        self.heap[i] = entry;
        self.at[owner_of(entry) as usize] = i as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use std::collections::BTreeMap;

    #[derive(Clone, Copy, Debug, PartialEq)]
    struct E {
        t: f64,
        a: u32,
        tag: u64,
    }
    impl Owned for E {
        fn time(&self) -> f64 {
            self.t
        }
        fn owner(&self) -> u32 {
            self.a
        }
    }

    #[test]
    fn keys_order_as_total_cmp_then_owner() {
        let times = [
            f64::NEG_INFINITY,
            -1.5,
            -0.0,
            0.0,
            f64::MIN_POSITIVE,
            1e-300,
            0.25,
            1.0,
            1.0 + f64::EPSILON,
            1e300,
            f64::INFINITY,
        ];
        for &x in &times {
            for &y in &times {
                for (p, q) in [(0u32, 1u32), (1, 0), (7, 7), (u32::MAX, 0)] {
                    let want = x.total_cmp(&y).then(p.cmp(&q));
                    assert_eq!(key(x, p).cmp(&key(y, q)), want, "{x} {p} vs {y} {q}");
                }
            }
        }
    }

    /// The queue against a plain model (a map from owner to event; the earliest found by a
    /// scan) under random sets, removes and pops, with many equal times so ties are tested.
    #[test]
    fn the_queue_pops_what_a_scan_of_the_pending_events_finds_first() {
        let mut rng = Rng::new(7);
        let mut below = |k: u64| (rng.next_u64() % k) as u32;
        let n = 50u32;
        let mut q = Queue::<E>::default();
        q.reset(n as usize);
        let mut model: BTreeMap<u32, E> = BTreeMap::new();
        let mut pops = 0;
        for tag in 0..20_000u64 {
            match below(10) {
                0..=5 => {
                    let e = E {
                        t: f64::from(below(40)) * 0.25,
                        a: below(u64::from(n)),
                        tag,
                    };
                    q.set(e);
                    model.insert(e.a, e);
                }
                6 => {
                    let a = below(u64::from(n));
                    q.remove(a);
                    model.remove(&a);
                }
                _ => {
                    let want = model
                        .values()
                        .min_by(|x, y| x.t.total_cmp(&y.t).then(x.a.cmp(&y.a)))
                        .copied();
                    if let Some(w) = want {
                        model.remove(&w.a);
                        pops += 1;
                    }
                    assert_eq!(q.pop(), want);
                }
            }
            assert_eq!(q.len(), model.len());
        }
        assert!(pops > 1000, "the test popped only {pops} events");
    }
}
