//! The collision method of a world and what the methods keep between steps: the event flight,
//! the solve's warm starts and who sleeps. The world holds one [`MethodState`] and names none of
//! its parts; each method is handed the world's state and pair lists explicitly.

use super::aside;
use super::auto::{self, Why};
use super::discrete::{self, Respond};
use super::islands;
use super::mixed::{self, IslandSummary, EVENT_GROUP, POP_GROUP};
use super::solve::{self, Sweeps};
use super::{bullets, event, flight, sleep::Sleep, swept, Method};
use crate::border::Topology;
use crate::broad_phase::BroadPhase;
use crate::critter::Critter;
use crate::error::Error;
use crate::step::pairs::Pairs;
use crate::step::span::Span;
use crate::step::state::State;
use crate::step::stats::StepStats;
use crate::vector::Vector;

/// The method and its state between steps.
pub(crate) struct MethodState<V: Vector> {
    /// The method asked for.
    method: Method,
    /// What `auto` chose for the last step, and why.
    auto_choice: Option<(Method, Why)>,
    /// `auto`'s islands in the last step (under gravity).
    auto_islands: Option<IslandSummary>,
    /// Under a mixed step, each slot's group (see `mixed`), and the slots a group hid.
    groups: Vec<u8>,
    hidden: Vec<u32>,
    /// The groups of the last step when it was mixed (else empty): while they stay the same,
    /// each group keeps its broad phase's list, the event group's here.
    last_groups: Vec<u8>,
    event_broad: Option<BroadPhase<V>>,
    /// `auto`'s bullets of the coming step (see `bullets`), by slot, and marked by slot.
    bullets: Vec<u32>,
    is_bullet: Vec<bool>,
    /// The bullets set aside while the step is taken without them.
    bullets_aside: Vec<u32>,
    pub(super) flight: flight::Scratch<V>,
    solve: solve::Scratch<V>,
    sleep: Sleep<V>,
    /// The run was told once that a discrete step moved a critter farther than its radius.
    warned_tunnel: bool,
    /// Steps in which every critter sleeps or is a wall are skipped, and so is their check of
    /// the sleepers while no one touches the critters (tests turn it off to compare with the
    /// full step).
    rest_shortcut: bool,
}

/// What a step is taken with (under `auto`, what it chose for this step).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Plan {
    pub(crate) method: Method,
    /// A swept step taken per critter.
    per_critter: bool,
    /// Substeps of a solved step.
    substeps: u32,
    /// `auto`'s sweeps for a solved step.
    sweeps: Option<Sweeps>,
    /// `auto` steps two groups of islands apart: the fields above are the Pop-step group's
    /// plan, and the event group takes `event` (see `mixed`).
    mixed: bool,
    /// `auto` takes the step without its bullets, then flies them (see `bullets`).
    bullets: bool,
}

impl<V: Vector> MethodState<V> {
    pub(crate) fn new(method: Method, sleep: bool) -> Self {
        MethodState {
            method,
            auto_choice: None,
            auto_islands: None,
            groups: Vec::new(),
            hidden: Vec::new(),
            last_groups: Vec::new(),
            event_broad: None,
            bullets: Vec::new(),
            is_bullet: Vec::new(),
            bullets_aside: Vec::new(),
            flight: Default::default(),
            solve: Default::default(),
            sleep: Sleep::new(sleep),
            warned_tunnel: false,
            rest_shortcut: true,
        }
    }

    pub(crate) fn method(&self) -> Method {
        self.method
    }

    pub(crate) fn set_method(&mut self, method: Method) {
        self.method = method;
    }

    pub(crate) fn auto_choice(&self) -> Option<(Method, Why)> {
        self.auto_choice
    }

    /// `auto`'s islands in the last step, when it took them (under gravity).
    pub(crate) fn auto_islands(&self) -> Option<&IslandSummary> {
        self.auto_islands.as_ref()
    }

    /// The method for the coming step: the one asked for, or what `auto` chooses for `state`.
    /// (`auto` hides critters while it measures a group of islands, and shows them again.)
    pub(crate) fn plan(&mut self, state: &mut State<V>, span: Span) -> Plan {
        match self.method {
            Method::Auto => {
                if let Some(plan) = self.plan_islands(state, span) {
                    return plan;
                }
                self.auto_islands = None;
                self.plan_whole(state, span)
            }
            method => Plan {
                method,
                per_critter: false,
                substeps: 1,
                sweeps: None,
                mixed: false,
                bullets: false,
            },
        }
    }

    /// `auto`'s plan for the whole scene at once.
    fn plan_whole(&mut self, state: &State<V>, span: Span) -> Plan {
        let choice = auto::choose(state, &self.flight, self.sleep.count(), span.dt);
        self.auto_choice = Some((choice.method, choice.why));
        Plan {
            method: choice.method,
            per_critter: choice.per_critter,
            substeps: choice.substeps,
            sweeps: Some(choice.sweeps),
            mixed: false,
            bullets: false,
        }
    }

    /// `auto`'s plan by islands (see `islands`), under gravity; `None` where islands do not
    /// apply (no gravity, where nothing rests; a fixed critter that moves). A scene that needs
    /// the swept step for a few bullets is planned without them, and flies them after; one that
    /// needs it for more takes it whole.
    fn plan_islands(&mut self, state: &mut State<V>, span: Span) -> Option<Plan> {
        if state.gravity == V::zero() {
            return None;
        }
        let moving_fixed = state
            .critters
            .iter()
            .any(|c| c.in_play() && c.fixed && !c.is_wall() && c.vel != V::zero());
        if moving_fixed {
            return None;
        }
        // Something fast meets something thin: the swept step flies the whole scene's impacts
        // in time order already, its resting contacts included, and islands would add nothing.
        let whole = (self.plan_whole(state, span), self.auto_choice);
        if whole.0.method != Method::Swept {
            self.bullets.clear();
            return Some(self.plan_settled(state, span, whole));
        }
        if !bullets::find(state, span.dt, &mut self.bullets) {
            self.auto_islands = None;
            return Some(whole.0);
        }
        self.hide_bullets(state);
        let whole = (self.plan_whole(state, span), self.auto_choice);
        let mut plan = self.plan_settled(state, span, whole);
        self.show_bullets(state);
        plan.bullets = true;
        let summary = self.auto_islands.get_or_insert_with(Default::default);
        summary.bullets = self.bullets.len();
        Some(plan)
    }

    /// Sets `auto`'s bullets aside (and marks them by slot in `is_bullet`).
    fn hide_bullets(&mut self, state: &mut State<V>) {
        let slots = state.critters.slot_slice();
        self.is_bullet.clear();
        self.is_bullet.resize(slots.len(), false);
        for &b in &self.bullets {
            if let Some(Some(_)) = slots.get(b as usize) {
                self.is_bullet[b as usize] = true;
            }
        }
        aside::set_aside(state, self.bullets.iter().copied(), &mut self.bullets_aside);
    }

    /// Brings `auto`'s bullets back.
    fn show_bullets(&mut self, state: &mut State<V>) {
        aside::bring_back(state, &mut self.bullets_aside);
    }

    /// `auto`'s plan by islands for a scene that needs no swept step (`whole` is its plan and
    /// choice for the whole scene).
    fn plan_settled(
        &mut self,
        state: &mut State<V>,
        span: Span,
        whole: (Plan, Option<(Method, Why)>),
    ) -> Plan {
        // Sleepers the update hooks moved wake now, as the step would wake them, so that the
        // partition takes only true sleepers as still.
        if self.sleep.count() > 0 {
            self.sleep.check(&mut state.critters, self.rest_shortcut);
        }
        if self.sleep.count() > 0 && self.all_asleep(state) {
            // Nothing to cut, and no partition to pay for.
            self.auto_islands = None;
            return whole.0;
        }
        let found = islands::partition(state, self.sleep.still(), span.dt);
        let plan = self.plan_found(state, span, &found, whole);
        if self.sleep.count() > 0 && !matches!(plan.method, Method::Solve(_)) {
            // Sleepers keep still only under a solve: otherwise they are disks like any other.
            let found = islands::partition(state, &[], span.dt);
            return self.plan_found(state, span, &found, whole);
        }
        plan
    }

    /// `auto`'s plan for the islands `found`: with no island of impacts and none solved (at
    /// rest, or an inelastic clump) beside free ones, the whole scene's choice; with none
    /// solved, `event` for all; otherwise a mixed step, the solved islands taking the whole
    /// scene's choice for them and the islands of impacts and in free flight `event`.
    /// True when every live critter that may move sleeps.
    fn all_asleep(&self, state: &State<V>) -> bool {
        let mut slots = state.critters.slot_slice().iter().enumerate();
        slots.all(|(i, c)| {
            c.as_ref()
                .is_none_or(|c| !c.in_play() || c.is_wall() || c.fixed || self.sleep.asleep(i))
        })
    }

    /// `whole` is the whole scene's plan and choice.
    fn plan_found(
        &mut self,
        state: &mut State<V>,
        span: Span,
        found: &islands::Islands,
        whole: (Plan, Option<(Method, Why)>),
    ) -> Plan {
        use islands::Regime;
        let has = |r: Regime| found.list.iter().any(|i| i.regime == r);
        let solved =
            has(Regime::Resting) || has(Regime::Clump) || found.of_slot.contains(&islands::ASLEEP);
        let (impact, free) = (has(Regime::Impact), has(Regime::Free));
        if !(impact || solved && free) {
            // Everything rests, or flies free with nothing at rest: as without islands.
            self.auto_choice = whole.1;
            self.auto_islands = Some(IslandSummary::of(
                found,
                whole.0.method,
                Method::Event,
                false,
            ));
            return whole.0;
        }
        if !solved {
            let critters = found.list.iter().map(|i| i.size).sum();
            let why = Why::Impacts {
                islands: found.list.len(),
                critters,
            };
            self.auto_choice = Some((Method::Event, why));
            self.auto_islands = Some(IslandSummary::of(found, Method::Event, Method::Event, true));
            return Plan {
                method: Method::Event,
                per_critter: false,
                substeps: 1,
                sweeps: None,
                mixed: false,
                bullets: false,
            };
        }
        mixed::groups_by_slot(found, true, &mut self.groups);
        // The Pop-step group's plan, measured on its own critters.
        mixed::hide(state, &self.groups, POP_GROUP, &mut self.hidden);
        let mut plan = self.plan_whole(state, span);
        mixed::show(state, &mut self.hidden);
        plan.mixed = true;
        self.auto_islands = Some(IslandSummary::of(found, plan.method, Method::Event, true));
        plan
    }

    /// True when `plan` keeps no state by slot between steps, so the critters may be laid out
    /// anew in memory (see `world::layout`).
    pub(crate) fn allows_layout(&self, plan: &Plan) -> bool {
        let slot_free = |m: Method| matches!(m, Method::Discrete | Method::Substep(_));
        slot_free(self.method) && slot_free(plan.method) && !plan.mixed && !plan.bullets
    }

    /// Moves and collides the critters over the step under `plan` (after the update hooks,
    /// before the lifecycle).
    pub(crate) fn step(
        &mut self,
        plan: Plan,
        span: Span,
        state: &mut State<V>,
        pairs: &mut Pairs<V>,
        stats: &mut StepStats,
    ) -> Result<(), Error> {
        if !plan.bullets {
            return self.step_groups(plan, span, state, pairs, stats);
        }
        self.hide_bullets(state);
        let result = self.step_groups(plan, span, state, pairs, stats);
        self.show_bullets(state);
        state.neighbours.invalidate();
        result?;
        bullets::fly(state, span, &self.bullets, &self.is_bullet, stats)
    }

    /// [`Self::step`] without the bullets: the whole scene under one method, or each group
    /// under its own.
    fn step_groups(
        &mut self,
        plan: Plan,
        span: Span,
        state: &mut State<V>,
        pairs: &mut Pairs<V>,
        stats: &mut StepStats,
    ) -> Result<(), Error> {
        let solving = matches!(plan.method, Method::Solve(_));
        if !solving {
            self.solve.warm.clear(); // kept only from one solve step to the next
        }
        self.sleep.active = solving && !self.sleep.off && state.gravity != V::zero();
        if self.sleep.active {
            self.sleep.check(&mut state.critters, self.rest_shortcut);
        } else {
            self.sleep.clear();
        }
        if !plan.mixed {
            if !self.last_groups.is_empty() {
                // The list was the Pop-step group's.
                pairs.broad.forget_list();
                self.last_groups.clear();
            }
            return self.take(plan, span, state, pairs, stats);
        }
        let event = Plan {
            method: Method::Event,
            per_critter: false,
            substeps: 1,
            sweeps: None,
            mixed: false,
            bullets: false,
        };
        let mut groups = std::mem::take(&mut self.groups);
        let mut event_broad = self
            .event_broad
            .take()
            .unwrap_or_else(|| BroadPhase::new(pairs.broad.mode));
        if groups != self.last_groups {
            // A list holds only the critters its group had: a critter that changed group (or
            // came) is in neither.
            pairs.broad.forget_list();
            event_broad.forget_list();
        }
        let mut result = Ok(());
        for (group, part) in [(POP_GROUP, plan), (EVENT_GROUP, event)] {
            mixed::hide(state, &groups, group, &mut self.hidden);
            if group == EVENT_GROUP {
                std::mem::swap(&mut pairs.broad, &mut event_broad);
            }
            result = self.take(part, span, state, pairs, stats);
            if group == EVENT_GROUP {
                std::mem::swap(&mut pairs.broad, &mut event_broad);
            }
            mixed::show(state, &mut self.hidden);
            state.neighbours.invalidate();
            if result.is_err() {
                break;
            }
        }
        self.event_broad = Some(event_broad);
        self.last_groups.clone_from(&groups);
        std::mem::swap(&mut self.groups, &mut groups);
        result
    }

    /// Takes the step's method over the critters that are alive.
    fn take(
        &mut self,
        plan: Plan,
        span: Span,
        state: &mut State<V>,
        pairs: &mut Pairs<V>,
        stats: &mut StepStats,
    ) -> Result<(), Error> {
        // `auto` takes the discrete step only where nobody moves far: it is not watched.
        let watch = |m: Method| matches!(m, Method::Discrete | Method::Substep(_));
        let watching = !self.warned_tunnel && watch(self.method) && watch(plan.method);
        match plan.method {
            Method::Discrete | Method::Substep(_) if watching => {
                let n = match plan.method {
                    Method::Substep(n) => n.max(1),
                    _ => 1,
                };
                self.warned_tunnel =
                    discrete::substeps_watching(state, pairs, span.split(n), stats)?;
                Ok(())
            }
            Method::Discrete | Method::Auto => {
                discrete::substeps(state, pairs, &mut Respond::Pop, span, stats)
            }
            Method::Substep(n) => {
                discrete::substeps(state, pairs, &mut Respond::Pop, span.split(n.max(1)), stats)
            }
            Method::Swept => swept::step(
                state,
                pairs,
                &mut self.flight,
                plan.per_critter,
                span,
                stats,
            ),
            Method::Event => event::step(state, pairs, &mut self.flight, span, stats),
            Method::Solve(_)
                if self.rest_shortcut && self.sleep.active && self.sleep.all_still() =>
            {
                // Everyone sleeps: nothing moves, and every pair is two sleepers or a sleeper
                // and a wall, which the step would skip one by one.
                pairs.forget_found();
                let removed = self.sleep.take_removed();
                solve::rest(&mut self.solve, &self.sleep, removed);
                Ok(())
            }
            Method::Solve(n) => {
                let mut respond = Respond::Solve {
                    scratch: &mut self.solve,
                    sleep: &mut self.sleep,
                    sweeps: plan.sweeps.unwrap_or(Sweeps::Fixed(n)),
                };
                discrete::substeps(state, pairs, &mut respond, span.split(plan.substeps), stats)
            }
        }
    }

    /// Forgets everything kept between steps (the world was put in a recorded state).
    pub(crate) fn forget(&mut self) {
        self.auto_choice = None;
        self.auto_islands = None;
        self.last_groups.clear();
        self.event_broad = None;
        // The warnings are said once per run, restored or not.
        let warned = self.flight.warned_budget;
        self.flight = Default::default();
        self.flight.warned_budget = warned;
        self.solve = Default::default();
        self.sleep.forget();
    }

    /// The collision virial of the last event or swept step (see
    /// [`crate::World::collision_virial`]).
    pub(crate) fn collision_virial(&self) -> f64 {
        self.flight.virial
    }

    // ----- sleep ------------------------------------------------------------------------------

    /// Takes the full step even when every critter sleeps.
    #[cfg(test)]
    pub(crate) fn no_rest_shortcut(&mut self) {
        self.rest_shortcut = false;
    }

    /// Lets critters sleep under `solve:n`, or keeps every one awake (and wakes the sleepers).
    pub(crate) fn set_sleep(&mut self, on: bool) {
        self.sleep.off = !on;
        if !on {
            self.sleep.clear();
        }
    }

    pub(crate) fn sleep_allowed(&self) -> bool {
        !self.sleep.off
    }

    pub(crate) fn is_asleep(&self, slot: u32) -> bool {
        self.sleep.asleep(slot as usize)
    }

    pub(crate) fn sleepers(&self) -> usize {
        self.sleep.count()
    }

    /// True when removals must be reported to [`Self::removed`] (sleepers may rest on them).
    pub(crate) fn watches_removals(&self) -> bool {
        self.sleep.active
    }

    /// The critters of `gone` (slot, position, radius) were removed: what rested on them wakes.
    pub(crate) fn removed(
        &mut self,
        topo: &Topology<V>,
        gone: &[(usize, V, f64)],
        slots: &[Option<Critter<V>>],
    ) {
        self.sleep.removed(topo, gone, slots);
    }

    /// Quiet steps and island by slot, for the slots whose count is not 0.
    pub(crate) fn quiet_counts(&self) -> impl Iterator<Item = (usize, u16, u32)> + '_ {
        self.sleep.counts()
    }

    /// Restores recorded counts of quiet steps, as (slot, count, island) in ascending slots.
    pub(crate) fn restore_quiet_counts(
        &mut self,
        list: &[(u32, u16, u32)],
        slots: &[Option<Critter<V>>],
    ) -> Result<(), String> {
        self.sleep.restore(list, slots)
    }

    // ----- the solve's warm starts ------------------------------------------------------------

    /// The last solve's impulses by pair key, ascending.
    pub(crate) fn warm_impulses(&self) -> &[(u64, f64)] {
        &self.solve.warm
    }

    /// Restores recorded impulses by pair key, ascending.
    pub(crate) fn set_warm_impulses(&mut self, warm: Vec<(u64, f64)>) {
        self.solve.warm = warm;
    }
}
