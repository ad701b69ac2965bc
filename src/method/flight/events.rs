//! A predicted event: what it is, its order among the others, whether it still holds, and how
//! a running prediction keeps the earliest.

use super::Scratch;
use crate::method::queue::Owned;
use crate::step::state::State;
use crate::vector::Vector;
use std::cmp::Ordering;

/// What an event is. An enum, not a plain byte, so that `Option<Event>` needs no tag of its own
/// (it fits the 32 bytes `Event` takes). The order of the variants breaks ties between events of
/// one time and pair: it is part of every run's bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[repr(u8)]
pub(super) enum EventKind {
    /// Two disks touch.
    Pair,
    /// A disk touches a wall.
    Wall,
    /// A disk hits a bounding border (`other`: the axis and side, `axis * 2 + side`).
    Border,
    /// A disk crosses into the next cell (`other`: the axis and direction, `axis * 2 + dir`).
    CellCrossing,
    /// A curved prediction that did not settle goes on from here.
    Recheck,
    /// A sphere leaves its neighbour shell.
    ShellExit,
}

/// A predicted event (32 bytes, aligned so that one never straddles two cache lines).
#[derive(Clone, Copy, Debug)]
#[repr(align(32))]
pub(super) struct Event {
    pub(super) time: f64,
    /// The critter whose event it is.
    pub(super) owner: u32,
    /// The partner (a disk or a wall), or for borders and crossings which way (see
    /// [`EventKind`]).
    pub(super) other: u32,
    pub(super) kind: EventKind,
    /// The owner's count of changes when predicted: another count makes the event stale.
    pub(super) owner_changes: u32,
    /// The partner's count of changes when predicted (pairs only, else 0).
    pub(super) other_changes: u32,
}

const _: () = assert!(std::mem::size_of::<Option<Event>>() == 32);

impl Owned for Event {
    #[inline]
    fn time(&self) -> f64 {
        self.time
    }
    #[inline]
    fn owner(&self) -> u32 {
        self.owner
    }
}

impl PartialEq for Event {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Event {}
impl PartialOrd for Event {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Event {
    fn cmp(&self, o: &Self) -> Ordering {
        // Ties are rare: compare the rest only on one.
        self.time.total_cmp(&o.time).then_with(|| {
            (
                self.owner,
                self.other,
                self.kind,
                self.owner_changes,
                self.other_changes,
            )
                .cmp(&(o.owner, o.other, o.kind, o.owner_changes, o.other_changes))
        })
    }
}

pub(super) enum Validity {
    Valid,
    /// The owner has changed since: it has a newer event already.
    Stale,
    /// The partner has changed: the owner must predict again.
    PartnerChanged,
}

pub(super) fn validity<V: Vector>(sc: &Scratch<V>, ev: &Event) -> Validity {
    let in_play = |x: u32| sc.status[x as usize].in_play;
    if !in_play(ev.owner) || sc.status[ev.owner as usize].changes != ev.owner_changes {
        return Validity::Stale;
    }
    let ok = match ev.kind {
        EventKind::Pair => {
            in_play(ev.other) && sc.status[ev.other as usize].changes == ev.other_changes
        }
        EventKind::Wall => in_play(ev.other),
        _ => true,
    };
    if ok {
        Validity::Valid
    } else {
        Validity::PartnerChanged
    }
}

/// Offers an event to the running prediction: each critter keeps only its earliest event in
/// the queue (a stale partner makes it predict again when that event comes up).
#[inline]
pub(super) fn offer(sc: &mut Scratch<impl Vector>, time: f64, a: u32, b: u32, kind: EventKind) {
    if sc.earliest.is_some_and(|e| time > e.time) {
        return;
    }
    let other_changes = if kind == EventKind::Pair {
        sc.status.get(b as usize).map_or(0, |s| s.changes)
    } else {
        0
    };
    let ev = Event {
        time,
        owner: a,
        other: b,
        kind,
        owner_changes: sc.status[a as usize].changes,
        other_changes,
    };
    if sc.earliest.is_none_or(|e| ev < e) {
        sc.earliest = Some(ev);
    }
}

/// Asks for what processing `ev` will read first (its critters, bodies and neighbour lists:
/// with shells), so that the loads overlap the work on the event before it. Only a hint:
/// nothing is read.
#[inline]
pub(super) fn prefetch_event<V: Vector>(state: &State<V>, sc: &Scratch<V>, ev: &Event) {
    use crate::prefetch::prefetch;
    let slots = state.critters.slot_slice();
    for x in [ev.owner, ev.other] {
        let x = x as usize;
        prefetch(sc.body.get(x));
        prefetch(sc.shell_centres.get(x));
        crate::prefetch::prefetch_whole(slots.get(x));
        prefetch(sc.status.get(x));
        prefetch(sc.neighbours.head(x));
    }
}
