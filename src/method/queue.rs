//! The event queue of the flight: one pending event per critter, in a calendar of time buckets
//! in front of an indexed binary min-heap (Paul, J. Comput. Phys. 221, 2007, as used by
//! event-driven hard-sphere codes).
//!
//! A critter's new prediction replaces its old event, so the queue never holds more than one
//! entry per critter and has no stale entries to pop and skip. Events are ordered by time, then
//! owner: each owner has one entry, so that order is total and a run repeats bit for bit.
//!
//! The flight's time span (a kept flight's whole life) is cut into about one bucket per critter. Only the events of the
//! buckets up to the current one are in the heap (a few, so a sift is a few levels); later ones
//! wait in their bucket's list, where adding and removing costs a few pointer writes. A bucket
//! follows from the time by a monotone formula, so every listed event is later than every event
//! in the heap, and the order of the pops is exactly the order of (time, owner).

const NONE: u32 = u32::MAX;
/// `Queue::loc` of an owner whose event is in the heap.
const IN_HEAP: u32 = u32::MAX - 1;

/// What the queue needs of an event: its time and its owner.
pub(crate) trait Owned: Copy {
    fn time(&self) -> f64;
    fn owner(&self) -> u32;
}

/// Where an owner's event is, kept in one place per owner (a queue operation on scattered
/// owners then touches one cache line each for this, not four).
#[derive(Clone, Copy, Debug)]
#[repr(align(16))]
struct Link {
    /// `NONE`, `IN_HEAP`, or the bucket whose list holds the event.
    loc: u32,
    /// The owner's neighbours in its bucket's list (while listed).
    next: u32,
    prev: u32,
    /// The owner's place in the heap's keys (while in the heap), or `NONE`.
    at: u32,
}

const UNLINKED: Link = Link {
    loc: NONE,
    next: NONE,
    prev: NONE,
    at: NONE,
};

pub(crate) struct Queue<E> {
    heap: Heap,
    links: Vec<Link>,
    /// The bucket lists: first owner per bucket (then `Link::next`).
    first: Vec<u32>,
    /// Each owner's event (meaningful while `loc` is set).
    events: Vec<Option<E>>,
    /// Bucket `b` holds the times from `start + b / per_time` on; the last bucket holds the
    /// rest.
    start: f64,
    per_time: f64,
    /// The heap holds the events of the buckets up to this one.
    current: usize,
}

impl<E> Default for Queue<E> {
    fn default() -> Self {
        Self {
            heap: Heap::default(),
            links: Vec::new(),
            first: Vec::new(),
            events: Vec::new(),
            start: 0.0,
            per_time: 0.0,
            current: 0,
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
    /// Empties the queue for owners `0..n` and events between `start` and `end` (later events
    /// are kept too, in the last bucket).
    pub fn reset(&mut self, n: usize, start: f64, end: f64) {
        self.reset_buckets(n, start, end, n.next_power_of_two());
    }

    /// [`Queue::reset`] with about `buckets` buckets (at least 64, at most 2^22).
    pub fn reset_buckets(&mut self, n: usize, start: f64, end: f64, buckets: usize) {
        self.heap.keys.clear();
        self.links.clear();
        self.links.resize(n, UNLINKED);
        self.events.clear();
        self.events.resize_with(n, || None);
        let span = end - start;
        let buckets = if span > 0.0 && span.is_finite() && n > 0 {
            buckets.next_power_of_two().clamp(64, 1 << 22)
        } else {
            0 // no span: everything in the heap
        };
        self.first.clear();
        self.first.resize(buckets + 1, NONE);
        self.start = start;
        self.per_time = if buckets > 0 {
            buckets as f64 / span
        } else {
            0.0
        };
        self.current = 0;
    }

    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.links.iter().filter(|l| l.loc != NONE).count()
    }

    /// The bucket of time `t`: non-decreasing in `t`, so a later bucket means a later time.
    #[inline]
    fn bucket(&self, t: f64) -> usize {
        // `as` saturates (and maps NaN to 0): monotone for every t.
        let b = ((t - self.start) * self.per_time) as usize;
        b.min(self.first.len() - 1)
    }

    /// Makes `e` its owner's pending event, replacing the one it had.
    pub fn set(&mut self, e: E) {
        let a = e.owner();
        let k = key(e.time(), a);
        self.events[a as usize] = Some(e);
        let b = self.bucket(e.time());
        let loc = self.links[a as usize].loc;
        if b <= self.current {
            if loc == IN_HEAP {
                self.heap.update(k, &mut self.links);
            } else {
                if loc != NONE {
                    self.unlink(a, loc as usize);
                }
                self.heap.push(k, &mut self.links);
                self.links[a as usize].loc = IN_HEAP;
            }
        } else {
            if loc == IN_HEAP {
                self.heap.remove(a, &mut self.links);
            } else if loc != NONE {
                self.unlink(a, loc as usize);
            }
            self.link(a, b);
        }
    }

    /// Drops owner `a`'s pending event, if it has one.
    pub fn remove(&mut self, a: u32) {
        match self.links[a as usize].loc {
            NONE => return,
            IN_HEAP => self.heap.remove(a, &mut self.links),
            b => self.unlink(a, b as usize),
        }
        self.links[a as usize].loc = NONE;
        self.events[a as usize] = None;
    }

    /// The earliest event, left in the queue: a caller that predicts its owner again next
    /// replaces it in place.
    #[cfg(test)]
    pub fn peek(&mut self) -> Option<E> {
        loop {
            if let Some(k) = self.heap.top() {
                return self.events[owner_of(k) as usize];
            }
            if self.current + 1 >= self.first.len() {
                return None;
            }
            self.current += 1;
            self.open(self.current);
        }
    }

    /// The earliest event if it may be at `limit` or before: `None` when every pending event is
    /// surely later (the buckets after the one `limit` falls in are not opened, nor the last;
    /// a flight kept for the next step leaves its later events where they are).
    #[inline]
    pub fn peek_until(&mut self, limit: f64) -> Option<E> {
        let last = self.bucket(limit);
        loop {
            if let Some(k) = self.heap.top() {
                return self.events[owner_of(k) as usize];
            }
            if self.current + 1 >= self.first.len() || self.current + 1 > last {
                return None;
            }
            self.current += 1;
            self.open(self.current);
        }
    }

    /// The event after the earliest among those in the heap, if the heap holds two: most often
    /// the next one to come up (a hint for what to load early; the earliest's new prediction
    /// may still come first).
    #[inline]
    pub fn runner_up(&self) -> Option<E> {
        let keys = &self.heap.keys;
        let k = match keys.len() {
            0 | 1 => return None,
            2 => keys[1],
            _ => keys[1].min(keys[2]),
        };
        self.events[owner_of(k) as usize]
    }

    /// Takes the earliest event out of the queue.
    #[cfg(test)]
    pub fn pop(&mut self) -> Option<E> {
        let e = self.peek()?;
        self.remove(e.owner());
        Some(e)
    }

    /// Moves bucket `b`'s events into the heap.
    fn open(&mut self, b: usize) {
        let mut a = self.first[b];
        self.first[b] = NONE;
        while a != NONE {
            let next = self.links[a as usize].next;
            let e = self.events[a as usize].expect("a listed owner has an event");
            self.heap.push(key(e.time(), a), &mut self.links);
            self.links[a as usize].loc = IN_HEAP;
            a = next;
        }
    }

    fn link(&mut self, a: u32, b: usize) {
        let head = self.first[b];
        let link = &mut self.links[a as usize];
        link.next = head;
        link.prev = NONE;
        link.loc = b as u32;
        if head != NONE {
            self.links[head as usize].prev = a;
        }
        self.first[b] = a;
    }

    fn unlink(&mut self, a: u32, b: usize) {
        let Link {
            prev: p, next: n, ..
        } = self.links[a as usize];
        if p == NONE {
            self.first[b] = n;
        } else {
            self.links[p as usize].next = n;
        }
        if n != NONE {
            self.links[n as usize].prev = p;
        }
    }
}

/// An indexed binary min-heap of keys (`key`: time, then owner), at most one per owner; each
/// owner's place in it is kept in its `Link::at`.
#[derive(Default)]
struct Heap {
    keys: Vec<u128>,
}

impl Heap {
    #[inline]
    fn top(&self) -> Option<u128> {
        self.keys.first().copied()
    }

    fn push(&mut self, k: u128, at: &mut [Link]) {
        self.keys.push(k);
        self.sift_up(self.keys.len() - 1, at);
    }

    /// Replaces the key of `k`'s owner (which has one in the heap) by `k`.
    fn update(&mut self, k: u128, at: &mut [Link]) {
        let i = at[owner_of(k) as usize].at as usize;
        let old = self.keys[i];
        self.keys[i] = k;
        if k < old {
            self.sift_up(i, at);
        } else {
            self.sift_down(i, at);
        }
    }

    fn remove(&mut self, a: u32, at: &mut [Link]) {
        let i = at[a as usize].at;
        if i == NONE {
            return;
        }
        at[a as usize].at = NONE;
        let last = self.keys.pop().expect("an entry is in the heap");
        let i = i as usize;
        if i < self.keys.len() {
            self.keys[i] = last;
            if i > 0 && last < self.keys[(i - 1) / 2] {
                self.sift_up(i, at);
            } else {
                self.sift_down(i, at);
            }
        }
    }

    fn sift_up(&mut self, mut i: usize, at: &mut [Link]) {
        let entry = self.keys[i];
        while i > 0 {
            let parent = (i - 1) / 2;
            if entry >= self.keys[parent] {
                break;
            }
            self.keys[i] = self.keys[parent];
            at[owner_of(self.keys[i]) as usize].at = i as u32;
            i = parent;
        }
        self.keys[i] = entry;
        at[owner_of(entry) as usize].at = i as u32;
    }

    fn sift_down(&mut self, mut i: usize, at: &mut [Link]) {
        let entry = self.keys[i];
        let n = self.keys.len();
        loop {
            let left = 2 * i + 1;
            if left >= n {
                break;
            }
            let right = left + 1;
            let child = if right < n && self.keys[right] < self.keys[left] {
                right
            } else {
                left
            };
            if self.keys[child] >= entry {
                break;
            }
            self.keys[i] = self.keys[child];
            at[owner_of(self.keys[i]) as usize].at = i as u32;
            i = child;
        }
        self.keys[i] = entry;
        at[owner_of(entry) as usize].at = i as u32;
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

    /// With everything in the heap, the runner-up is the second earliest event, whatever the
    /// number of events (one, two, three or many).
    #[test]
    fn the_runner_up_is_the_second_earliest_in_the_heap() {
        let times = [5.0, 3.0, 4.0, 1.0, 2.0, 0.5, 6.0];
        for count in 0..=times.len() {
            let mut q = Queue::<E>::default();
            q.reset(times.len(), 0.0, 0.0); // no span: one heap
            for (a, &t) in times.iter().take(count).enumerate() {
                q.set(E {
                    t,
                    a: a as u32,
                    tag: 0,
                });
            }
            let mut sorted: Vec<f64> = times[..count].to_vec();
            sorted.sort_by(f64::total_cmp);
            assert_eq!(
                q.runner_up().map(|e| e.t),
                sorted.get(1).copied(),
                "{count} events"
            );
        }
    }

    /// The queue against a plain model (a map from owner to event; the earliest found by a
    /// scan) under random sets, removes and pops, as the flight uses it: new events are never
    /// earlier than the last one popped. Many equal times, so ties are tested, and times past
    /// the calendar's end and exactly on bucket edges.
    #[test]
    fn the_queue_pops_what_a_scan_of_the_pending_events_finds_first() {
        let mut rng = Rng::new(7);
        let mut below = |k: u64| (rng.next_u64() % k) as u32;
        let n = 50u32;
        for (start, end) in [(0.0, 10.0), (2.0, 3.0), (0.0, 0.0), (1.0, f64::INFINITY)] {
            let mut q = Queue::<E>::default();
            q.reset(n as usize, start, end);
            let mut model: BTreeMap<u32, E> = BTreeMap::new();
            let mut now = start;
            let mut pops = 0;
            for tag in 0..20_000u64 {
                match below(10) {
                    0..=5 => {
                        // From now to a little past the end, in steps of a 64th of the span.
                        let e = E {
                            t: now + f64::from(below(80)) * 0.125,
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
                        // The runner-up is a pending event after the earliest; with no
                        // span (everything in the heap) it is the second earliest.
                        let order = |x: &E, y: &E| x.t.total_cmp(&y.t).then(x.a.cmp(&y.a));
                        if q.peek().is_some() {
                            let up = q.runner_up();
                            if let (Some(r), Some(w)) = (up, want) {
                                assert_eq!(model.get(&r.a), Some(&r), "a pending event");
                                assert_eq!(order(&w, &r), std::cmp::Ordering::Less);
                            }
                            if end == start {
                                let mut all: Vec<E> = model.values().copied().collect();
                                all.sort_by(order);
                                assert_eq!(up, all.get(1).copied(), "the second earliest");
                            }
                        }
                        if let Some(w) = want {
                            model.remove(&w.a);
                            now = w.t;
                            pops += 1;
                        }
                        assert_eq!(q.pop(), want, "span {start}..{end}");
                    }
                }
                assert_eq!(q.len(), model.len());
            }
            assert!(pops > 1000, "the test popped only {pops} events");
        }
    }
}
