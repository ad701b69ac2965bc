//! Touching spells: a pair that touches in consecutive steps is one spell, which begins and
//! ends once (`touch_begin`, `touch_end`) and whose first step `collide`'s contact marks
//! (`contact.first`).
//!
//! Kept only when some kind tracks touch ([`crate::kind::KindSet::tracks_touch`]); otherwise
//! nothing here runs. A pair *touches in a step* when a method hands it to a caller's `collide`
//! or, under `solve:n`, solves its contact: wherever a method decides that a pair touched, it
//! calls [`State::note_touch`]. A spell whose pair the method did not report but which still
//! touches where the critters are (two sleepers, a sleeper on a wall) goes on.
//!
//! The events of a step are sent by the touch stage, after the collision method and before the
//! lifecycle: first every spell that ended (pairs in id order), then every spell that began
//! (pairs in id order), each to the lower id's kind and then to the higher's, each from its own
//! side. A critter that dies ends its spells in the lifecycle, before its `on_death`; a spell
//! that began in the step it died in gets its begin here first.

use super::access::{CollideCtx, HookContact};
use super::spells::{ordered, Pair};
use super::state::{hook_error, State};
use crate::critter::CritterId;
use crate::error::Error;
use crate::vector::Vector;

impl<V: Vector> State<V> {
    /// Notes that the critters in slots `caller` and `arg` touch in this step; returns true when
    /// this begins their spell (the first touch of the step, and no spell went on before).
    /// Only called while spells are kept.
    pub(crate) fn note_touch(&mut self, caller: u32, arg: u32) -> bool {
        let (Some(c), Some(a)) = (self.critters.slot(caller), self.critters.slot(arg)) else {
            return false;
        };
        let pair = ordered(c.id, a.id);
        if self.touch.now.contains_key(&pair) {
            return false;
        }
        if self.touch.is_open(c.id, a.id) {
            self.touch.now.insert(pair, None);
            return false;
        }
        let contact = HookContact::between(&self.topo, c, a, true);
        let seen = if pair.0 == c.id {
            contact
        } else {
            contact.flipped()
        };
        self.touch.now.insert(pair, Some(seen));
        true
    }

    /// Calls `touch_end` on both critters of `pair` (lower id first).
    fn send_end(&mut self, pair: Pair) -> Result<(), Error> {
        self.send(pair, None)
    }

    /// Calls `touch_begin` on both critters of `pair` (lower id first), `contact` seen from the
    /// lower id.
    fn send_begin(&mut self, pair: Pair, contact: HookContact<V>) -> Result<(), Error> {
        self.send(pair, Some(contact))
    }

    /// `touch_begin` (with the contact seen from the lower id) or `touch_end` (without), on both
    /// critters of `pair`, lower id first, each from its own side.
    fn send(&mut self, pair: Pair, contact: Option<HookContact<V>>) -> Result<(), Error> {
        for (me, other, seen) in [
            (pair.0, pair.1, contact),
            (pair.1, pair.0, contact.map(|c| c.flipped())),
        ] {
            let Some((ms, os, kind_id)) = self.hook_pair(me, other) else {
                continue;
            };
            let hooks = self.kinds.get(kind_id).hooks.clone();
            let step = self.step_count;
            let hook = if seen.is_some() {
                "touch_begin"
            } else {
                "touch_end"
            };
            let outer = self.enter_hook(me, hook);
            let mut ctx = CollideCtx {
                access: self.access(),
                me: ms,
                other: os,
                first: seen.is_some(),
            };
            let done = match &seen {
                Some(seen) => hooks.touch_begin(&mut ctx, seen),
                None => hooks.touch_end(&mut ctx),
            };
            self.hook = outer;
            done.map_err(|e| hook_error(e, &self.kinds, kind_id, me, step))?;
        }
        Ok(())
    }

    /// The slots of `me` and `other` and `me`'s kind, when both are there and the kind has
    /// touch hooks.
    fn hook_pair(
        &self,
        me: CritterId,
        other: CritterId,
    ) -> Option<(u32, u32, crate::kind::KindId)> {
        let (ms, os) = (self.critters.slot_of(me)?, self.critters.slot_of(other)?);
        let kind = self.critters.slot(ms)?.kind();
        self.kinds
            .get(kind)
            .has_touch_hooks
            .then_some((ms, os, kind))
    }

    /// Ends every spell of the critters `dying` (touch_end on both sides), in pair order.
    pub(crate) fn end_spells_of(&mut self, dying: &[CritterId]) -> Result<(), Error> {
        let (ended, kept): (Vec<Pair>, Vec<Pair>) = std::mem::take(&mut self.touch.open)
            .into_iter()
            .partition(|(a, b)| dying.contains(a) || dying.contains(b));
        self.touch.open = kept;
        ended.into_iter().try_for_each(|pair| self.send_end(pair))
    }
}

/// The touch stage: compares the pairs that touched in this step with the spells that went on,
/// and sends the ends, then the begins (see the module docs). Runs only while spells are kept.
pub(crate) fn run<V: Vector>(state: &mut State<V>) -> Result<(), Error> {
    let mut now: Vec<_> = state.touch.now.drain().collect();
    now.sort_unstable_by_key(|(pair, _)| *pair);
    let open = std::mem::take(&mut state.touch.open);
    let present = |state: &State<V>, id: CritterId| state.critters.get(id).is_some();
    let mut kept = Vec::with_capacity(open.len() + now.len());
    let mut ended = Vec::new();
    let mut begun = Vec::new();
    let mut old = open.into_iter().peekable();
    let mut new = now.into_iter().peekable();
    loop {
        let take_old = match (old.peek(), new.peek()) {
            (None, None) => break,
            (Some(_), None) => true,
            (None, Some(_)) => false,
            (Some(o), Some(next)) => *o <= next.0,
        };
        if take_old {
            let Some(pair) = old.next() else { break };
            if new.peek().is_some_and(|next| next.0 == pair) {
                new.next();
                kept.push(pair);
                continue;
            }
            let (Some(a), Some(b)) = (state.critters.get(pair.0), state.critters.get(pair.1))
            else {
                continue; // removed: its spells were ended then
            };
            if !a.in_play() || !b.in_play() || crate::default_response::touches(&state.topo, a, b) {
                // The dying end their spells in the lifecycle; a pair the method did not
                // report (sleepers) but that still touches goes on.
                kept.push(pair);
            } else {
                ended.push(pair);
            }
        } else {
            let Some((pair, contact)) = new.next() else {
                break;
            };
            if present(state, pair.0) && present(state, pair.1) {
                // A spell whose critter died in this step (a shot dying in its own `collide`)
                // begins all the same: the lifecycle ends it, so every spell has its begin and
                // its end.
                kept.push(pair);
                if let Some(contact) = contact {
                    begun.push((pair, contact));
                }
            }
        }
    }
    state.touch.open = kept;
    for pair in ended {
        state.send_end(pair)?;
    }
    for (pair, contact) in begun {
        state.send_begin(pair, contact)?;
    }
    Ok(())
}
