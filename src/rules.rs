//! Collide roles: who calls `collide` on whom, decided per pair of rule classes and cached.
//!
//! A rule class is (kind, priority, fixed): everything Pop's default `collidesWith` reads. The
//! answer for two classes is computed once from both sides' [`KindHooks::collides_with`] and kept in
//! a table, so the per-pair cost in the step is one lookup. Kinds whose rule reads other state say
//! so ([`KindHooks::rule_depends_on_state`]) and are asked every time.
//!
//! [`KindHooks::collides_with`]: crate::kind::KindHooks::collides_with
//! [`KindHooks::rule_depends_on_state`]: crate::kind::KindHooks::rule_depends_on_state

use crate::border::Topology;
use crate::critter::{Critter, CLASS_UNSET};
use crate::error::Error;
use crate::kind::{CollideRule, KindId, KindSet, RuleCtx};
use crate::vector::Vector;
use std::collections::BTreeMap;

/// The roles of a pair (first, second), as decided from both sides' rules.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairRule {
    /// No collision between them.
    DontCollide,
    /// The first critter calls `collide` on the second.
    FirstCalls,
    /// The second critter calls `collide` on the first.
    SecondCalls,
    /// Either may call; the one with the lower id does (deterministic).
    LowerIdCalls,
}

impl PairRule {
    fn swapped(self) -> PairRule {
        match self {
            PairRule::FirstCalls => PairRule::SecondCalls,
            PairRule::SecondCalls => PairRule::FirstCalls,
            other => other,
        }
    }
}

/// Combines Pop's two `collidesWith` answers (`a_says` about b, `b_says` about a) into roles.
///
/// If either side says don't collide, they don't. A side gets to call when it asks to call or the
/// other asks to be the argument. When exactly one side gets to call, it calls; when neither or
/// both do (either way, or a conflict), the higher priority calls, and at equal priority the lower
/// id.
pub fn resolve_roles(
    a_says: CollideRule,
    b_says: CollideRule,
    a_priority: f64,
    b_priority: f64,
) -> PairRule {
    use CollideRule::*;
    if a_says == DontCollide || b_says == DontCollide {
        return PairRule::DontCollide;
    }
    let a_calls = a_says == AsCaller || b_says == AsArg;
    let b_calls = b_says == AsCaller || a_says == AsArg;
    match (a_calls, b_calls) {
        (true, false) => PairRule::FirstCalls,
        (false, true) => PairRule::SecondCalls,
        _ if a_priority > b_priority => PairRule::FirstCalls,
        _ if a_priority < b_priority => PairRule::SecondCalls,
        _ => PairRule::LowerIdCalls,
    }
}

/// The roles of critters `a` and `b`, asking both kinds' hooks.
pub fn roles_of<V: Vector>(
    kinds: &KindSet<V>,
    topo: &Topology<V>,
    a: &Critter<V>,
    b: &Critter<V>,
) -> Result<PairRule, Error> {
    let ask = |me: &Critter<V>, other: &Critter<V>| {
        let ctx = RuleCtx {
            me,
            other,
            kinds,
            topo,
        };
        kinds
            .get(me.kind())
            .hooks
            .collides_with(&ctx)
            .map_err(|e| match e {
                Error::Script(mut s) => {
                    s.critter.get_or_insert(me.id());
                    Error::Script(s)
                }
                Error::Hook { .. } => e,
                other_err => Error::Hook {
                    kind: kinds.name(me.kind()).to_string(),
                    critter: me.id(),
                    step: 0,
                    message: other_err.to_string(),
                },
            })
    };
    let a_says = ask(a, b)?;
    let b_says = ask(b, a)?;
    Ok(resolve_roles(a_says, b_says, a.priority(), b.priority()))
}

const UNKNOWN: u8 = u8::MAX;

fn encode(rule: PairRule) -> u8 {
    rule as u8
}

fn decode(code: u8) -> PairRule {
    match code {
        0 => PairRule::DontCollide,
        1 => PairRule::FirstCalls,
        2 => PairRule::SecondCalls,
        _ => PairRule::LowerIdCalls,
    }
}

/// [`roles_order`] for critters `ca` in slot `a` and `cb` in slot `b`: the slots of (caller, arg).
#[inline]
pub(crate) fn roles_slots<V: Vector>(
    rule: PairRule,
    (a, ca): (u32, &Critter<V>),
    (b, cb): (u32, &Critter<V>),
) -> Option<(u32, u32)> {
    roles_order(rule, ca, cb).map(|(caller, _)| {
        if std::ptr::eq(caller, ca) {
            (a, b)
        } else {
            (b, a)
        }
    })
}

/// (caller, arg) for a pair under `rule`, or `None` when they don't collide.
pub(crate) fn roles_order<'c, V: Vector>(
    rule: PairRule,
    a: &'c Critter<V>,
    b: &'c Critter<V>,
) -> Option<(&'c Critter<V>, &'c Critter<V>)> {
    match rule {
        PairRule::DontCollide => None,
        PairRule::FirstCalls => Some((a, b)),
        PairRule::SecondCalls => Some((b, a)),
        PairRule::LowerIdCalls if a.id < b.id => Some((a, b)),
        PairRule::LowerIdCalls => Some((b, a)),
    }
}

/// Interned rule classes and the class-pair table.
#[derive(Debug, Default)]
pub struct RuleCache {
    index: BTreeMap<(KindId, u64, bool), u32>,
    /// Per class: does its kind's rule depend on state?
    uncached: Vec<bool>,
    /// Row-major `classes x classes`, `UNKNOWN` until first asked.
    table: Vec<u8>,
    lookups_computed: u64,
}

impl RuleCache {
    /// The class of (kind, priority, fixed), interned.
    pub(crate) fn class_of<V: Vector>(&mut self, kinds: &KindSet<V>, c: &Critter<V>) -> u32 {
        let key = (c.kind(), c.priority().to_bits(), c.is_fixed());
        if let Some(&class) = self.index.get(&key) {
            return class;
        }
        let n = self.uncached.len();
        let class = n as u32;
        self.index.insert(key, class);
        self.uncached
            .push(kinds.get(c.kind()).rule_depends_on_state);
        let mut table = vec![UNKNOWN; (n + 1) * (n + 1)];
        for row in 0..n {
            table[row * (n + 1)..row * (n + 1) + n]
                .copy_from_slice(&self.table[row * n..row * n + n]);
        }
        self.table = table;
        class
    }

    /// The roles of `a` and `b` (whose classes are set) from the table, or `None` when one of their
    /// kinds' rules depends on state: then the caller asks the hooks, once it knows the pair touches.
    #[inline]
    pub(crate) fn rule<V: Vector>(
        &mut self,
        kinds: &KindSet<V>,
        topo: &Topology<V>,
        a: &Critter<V>,
        b: &Critter<V>,
    ) -> Result<Option<PairRule>, Error> {
        let (ca, cb) = (a.class as usize, b.class as usize);
        debug_assert!(a.class != CLASS_UNSET && b.class != CLASS_UNSET);
        if self.uncached[ca] || self.uncached[cb] {
            return Ok(None);
        }
        let n = self.uncached.len();
        let code = self.table[ca * n + cb];
        if code != UNKNOWN {
            return Ok(Some(decode(code)));
        }
        let rule = roles_of(kinds, topo, a, b)?;
        self.lookups_computed += 1;
        self.table[ca * n + cb] = encode(rule);
        self.table[cb * n + ca] = encode(rule.swapped());
        Ok(Some(rule))
    }

    /// What `rule` would return for critters of classes `ca` and `cb`, when that is known without
    /// the critters: `Some(None)` for an uncached class, `Some(rule)` for a computed pair, `None`
    /// when the pair's roles are still to be computed.
    #[inline]
    pub(crate) fn cached(&self, ca: u32, cb: u32) -> Option<Option<PairRule>> {
        let (ca, cb) = (ca as usize, cb as usize);
        let n = self.uncached.len();
        if ca >= n || cb >= n {
            return None;
        }
        if self.uncached[ca] || self.uncached[cb] {
            return Some(None);
        }
        let code = self.table[ca * n + cb];
        (code != UNKNOWN).then(|| Some(decode(code)))
    }

    /// Forgets every pair's roles and asks `kinds` again whether each class's rule depends on
    /// state (a kind's hooks were replaced). The classes stay as they are.
    pub(crate) fn forget_roles<V: Vector>(&mut self, kinds: &KindSet<V>) {
        self.table.fill(UNKNOWN);
        for (&(kind, _, _), &class) in &self.index {
            self.uncached[class as usize] = kinds.get(kind).rule_depends_on_state;
        }
    }

    /// Number of class pairs whose roles were computed from the hooks so far.
    pub fn computed(&self) -> u64 {
        self.lookups_computed
    }

    /// Number of rule classes seen so far.
    pub fn classes(&self) -> usize {
        self.uncached.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use CollideRule::*;

    #[test]
    fn pop_default_roles() {
        assert_eq!(
            resolve_roles(AsCaller, AsArg, 500.0, 100.0),
            PairRule::FirstCalls
        );
        assert_eq!(
            resolve_roles(AsArg, AsCaller, 100.0, 500.0),
            PairRule::SecondCalls
        );
        assert_eq!(
            resolve_roles(EitherWay, EitherWay, 100.0, 100.0),
            PairRule::LowerIdCalls
        );
        assert_eq!(
            resolve_roles(DontCollide, AsCaller, 1.0, 2.0),
            PairRule::DontCollide
        );
        assert_eq!(
            resolve_roles(AsCaller, DontCollide, 1.0, 2.0),
            PairRule::DontCollide
        );
    }

    #[test]
    fn a_side_that_asks_to_call_wins_over_either_way() {
        assert_eq!(
            resolve_roles(EitherWay, AsCaller, 500.0, 100.0),
            PairRule::SecondCalls
        );
        assert_eq!(
            resolve_roles(AsArg, EitherWay, 500.0, 100.0),
            PairRule::SecondCalls
        );
    }

    #[test]
    fn conflicts_fall_back_to_priority_then_id() {
        assert_eq!(
            resolve_roles(AsCaller, AsCaller, 100.0, 200.0),
            PairRule::SecondCalls
        );
        assert_eq!(
            resolve_roles(AsArg, AsArg, 300.0, 200.0),
            PairRule::FirstCalls
        );
        assert_eq!(
            resolve_roles(AsCaller, AsCaller, 100.0, 100.0),
            PairRule::LowerIdCalls
        );
    }
}
