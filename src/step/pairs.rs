//! The pairs stage: the broad phase's candidate pairs, Pop's roles for each (the rules), and
//! the pairs that really touch (the narrow phase), put in the order the response takes them.
//!
//! For speed the three are fused where they can be, all inside this stage: when every
//! candidate's rule is in the class table and no touching pair's roles are to be asked of a
//! script, the rules and the narrow phase are one pass over the candidates, run on each chunk
//! of the broad phase's re-test of its kept Verlet list while the chunk's critters are in
//! cache; and the move stage, which passes over every critter just before, checks each one
//! against the list for this stage ([`MoveCheck`]), so the broad phase need not pass over them
//! again. Every path gives the same lists in the same order.

use crate::border::Topology;
use crate::broad_phase::{BroadObject, BroadPhase, BroadPhaseMode, Escapes, Objects};
use crate::critter::{Critter, Shape, CLASS_UNSET};
use crate::critter_set::CritterSet;
use crate::error::Error;
use crate::pair_order::{pair_key, sort_pairs, RADIX_MIN};
use crate::parallel::{INPUT_CHUNK, PARALLEL_PAIRS};
use crate::prefetch::prefetch;
use crate::rules::{roles_of, roles_slots, RuleCache};
use crate::step::state::{at_step, State};
use crate::vector::Vector;

/// How many pairs ahead the fused rules and narrow phase ask for the critters of the next pairs
/// to be loaded (they are scattered over memory, and the loads overlap).
const CANDIDATES_AHEAD: usize = 8;

/// The broad phase's Verlet list is sorted once many contacts were (see
/// [`BroadPhase::sort_list`]), and leads only its fastest objects ([`BroadPhase::set_crowded`]):
/// when it holds at most this many pairs per contact.
const LISTED_PER_CONTACT: usize = 8;

/// The pairs stage's state and its lists of the last search.
pub(crate) struct Pairs<V: Vector> {
    pub(crate) broad: BroadPhase<V>,
    /// The broad phase's candidate pairs of slots.
    pub(crate) candidates: Vec<(u32, u32)>,
    /// Candidates that may collide: (caller, arg, roles still to ask the hooks for).
    ruled: Vec<(u32, u32, bool)>,
    /// Touching disk pairs as (caller, arg), in response order; the response adds the wall
    /// pairs that touched.
    pub(crate) contacts: Vec<(u32, u32)>,
    /// Candidate pairs with a wall: (first, second, roles still to ask the hooks for), tested in
    /// the response once the disk pairs have moved.
    pub(crate) wall_pairs: Vec<(u32, u32, bool)>,
}

/// How the rules and the narrow phase were done.
enum Narrowed {
    /// With the broad phase's re-test: how many candidates may collide.
    WithRetest(usize),
    /// A pair's rule is not in the class table, or its roles are to be asked of the hooks: the
    /// rules and the narrow phase run one after the other.
    Refused,
    /// Not with the re-test (the pairs came another way, or sleepers are about).
    Apart,
}

impl<V: Vector> Pairs<V> {
    pub(crate) fn new(mode: BroadPhaseMode) -> Self {
        Pairs {
            broad: BroadPhase::new(mode),
            candidates: Vec::new(),
            ruled: Vec::new(),
            contacts: Vec::new(),
            wall_pairs: Vec::new(),
        }
    }

    /// Lists no pair, as [`Pairs::find`] would in a step with nothing to test (no contact:
    /// the list is not crowded).
    pub(crate) fn forget_found(&mut self) {
        self.broad.set_crowded(false);
        self.candidates.clear();
        self.ruled.clear();
        self.contacts.clear();
        self.wall_pairs.clear();
    }

    /// What the move stage checks for this stage as it moves each critter.
    pub(crate) fn move_check(&self) -> MoveCheck<'_, V> {
        MoveCheck { broad: &self.broad }
    }

    /// Finds the step's touching pairs where the critters are now, in response order: disk
    /// pairs by id in `contacts`, pairs with walls in `wall_pairs`. `moved` is the report of
    /// the move that ran just before, if one did; `still` marks sleepers and walls by slot
    /// (empty when nobody sleeps). `dt` is the step's, over which the boxes reach ahead.
    /// Returns how many candidates may collide.
    pub(crate) fn find(
        &mut self,
        state: &mut State<V>,
        dt: f64,
        moved: Option<MoveReport>,
        still: &[bool],
    ) -> Result<usize, Error> {
        let narrowed = self.broad_phase(state, dt, moved, still, true);
        if !still.is_empty() {
            // Two sleepers, or a sleeper and a wall, stay as they were.
            let is_still = |slot: u32| still.get(slot as usize).copied().unwrap_or(false);
            self.candidates
                .retain(|&(a, b)| !(is_still(a) && is_still(b)));
        }
        let ruled = match narrowed {
            Narrowed::WithRetest(ruled) => Some(ruled),
            // The pass over all the candidates would refuse them too.
            Narrowed::Refused => None,
            Narrowed::Apart => self.rules_and_narrow_phase_in_one_pass(state),
        };
        let ruled = match ruled {
            Some(ruled) => ruled,
            None => {
                self.rules_in_order(state)?;
                self.narrow_phase_in_order(state)?;
                self.ruled.len()
            }
        };
        self.sort_contacts(&state.critters);
        Ok(ruled)
    }

    /// The broad phase's candidates, and with `fuse` the rules and narrow phase done with its
    /// re-test where they can be.
    fn broad_phase(
        &mut self,
        state: &mut State<V>,
        dt: f64,
        moved: Option<MoveReport>,
        still: &[bool],
        fuse: bool,
    ) -> Narrowed {
        // What the move stage did, if it ran just before over the same slots.
        let moved = moved.filter(|m| m.chunks == state.critters.slot_count().div_ceil(INPUT_CHUNK));
        let seen = match &moved {
            Some(m) => m.seen,
            None => state
                .critters
                .iter_stored()
                .fold(CritterSurvey::default(), |s, c| s.and(CritterSurvey::of(c))),
        };
        // New critters and changed priorities need their rule class (rare; sequential).
        if seen.unset {
            for c in state
                .critters
                .iter_mut_moving()
                .filter(|c| c.in_play() && c.class == CLASS_UNSET)
            {
                c.class = state.rules.class_of(&state.kinds, c);
            }
        }
        // Wall pairs are tested after the disk pairs have been separated (see the response), and
        // a separation moves a disk by at most about its radius: widen walls' boxes by that much.
        let objs = SlotObjects {
            slots: state.critters.slot_slice(),
            wall_pad: seen.largest_radius,
            dt,
            still,
        };
        // The move checked every slot but the live walls' against the Verlet list; the walls
        // are checked here, and must be the ones it counted.
        let escapes = moved.map(|m| {
            let mut escapes = m.escapes;
            let (mut walls, disks) = (0, escapes.slots.len());
            for &id in &state.walls {
                let slot = state.critters.slot_of(id);
                if let Some(slot) = slot.filter(|&s| {
                    state
                        .critters
                        .slot(s)
                        .is_some_and(|c| c.in_play() && c.is_wall())
                }) {
                    walls += 1;
                    let i = slot as usize;
                    if !self
                        .broad
                        .list_holds(&state.topo, i, objs.object(i).as_ref())
                    {
                        escapes.slots.push(slot);
                    }
                }
            }
            if escapes.slots.len() > disks {
                escapes.slots.sort_unstable();
            }
            escapes.complete &= walls == m.walls;
            escapes
        });
        // With no sleepers (whose pairs are dropped after the broad phase), the rules and the
        // narrow phase run on each chunk of the kept list's re-test while its critters are in
        // cache: the same lists, in the same order, as the pass over all the candidates after.
        let (critters, rules, topo) = (&state.critters, &state.rules, &state.topo);
        let narrow = |chunk: &[(u32, u32)]| {
            let (mut contacts, mut walls) = (Vec::new(), Vec::new());
            let ruled = rules_and_narrow(critters, rules, topo, chunk, &mut contacts, &mut walls);
            ruled.map(|ruled| (ruled, contacts, walls))
        };
        let then = (fuse && still.is_empty()).then_some(&narrow);
        let parts = self
            .broad
            .find_pairs_then(&objs, topo, &mut self.candidates, escapes, then);
        match parts.map(|p| p.into_iter().collect::<Option<Vec<_>>>()) {
            None => Narrowed::Apart,
            Some(None) => Narrowed::Refused,
            Some(Some(parts)) => {
                self.contacts.clear();
                self.wall_pairs.clear();
                let mut ruled = 0;
                for (n, contacts, walls) in parts {
                    ruled += n;
                    self.contacts.extend(contacts);
                    self.wall_pairs.extend(walls);
                }
                Narrowed::WithRetest(ruled)
            }
        }
    }

    /// The rules, one candidate after another.
    fn rules_in_order(&mut self, state: &mut State<V>) -> Result<(), Error> {
        self.ruled.clear();
        for &(a, b) in &self.candidates {
            let (Some(ca), Some(cb)) = (state.critters.slot(a), state.critters.slot(b)) else {
                continue;
            };
            match state
                .rules
                .rule(&state.kinds, &state.topo, ca, cb)
                .map_err(|e| at_step(e, state.step_count))?
            {
                Some(rule) => {
                    if let Some((caller, arg)) = roles_slots(rule, (a, ca), (b, cb)) {
                        self.ruled.push((caller, arg, false));
                    }
                }
                // State-dependent rules are asked only for pairs that really touch.
                None => self.ruled.push((a, b, true)),
            }
        }
        Ok(())
    }

    /// The narrow phase, one ruled pair after another.
    fn narrow_phase_in_order(&mut self, state: &State<V>) -> Result<(), Error> {
        self.contacts.clear();
        self.wall_pairs.clear();
        let topo = &state.topo;
        for &(first, second, ask) in &self.ruled {
            let (Some(a), Some(b)) = (state.critters.slot(first), state.critters.slot(second))
            else {
                continue;
            };
            if a.is_wall() || b.is_wall() {
                // Tested in the response, once the disk pairs have moved.
                self.wall_pairs.push((first, second, ask));
                continue;
            }
            if !crate::contact::touching_ball_ball(topo.delta(a.pos, b.pos), a.radius, b.radius) {
                continue;
            }
            if ask {
                let rule =
                    roles_of(&state.kinds, topo, a, b).map_err(|e| at_step(e, state.step_count))?;
                if let Some(pair) = roles_slots(rule, (first, a), (second, b)) {
                    self.contacts.push(pair);
                }
            } else {
                self.contacts.push((first, second));
            }
        }
        Ok(())
    }

    /// The rules and narrow phase in one pass over the candidates, which reads each pair's
    /// critters once instead of once per stage, when every candidate's rule is already in the
    /// class table and no touching disk pair's roles are still to be asked (the rules would run
    /// a script). Returns how many pairs may collide, or `None`, with the lists to be redone,
    /// otherwise. With [`PARALLEL_PAIRS`] candidates or more and more than one thread the pass
    /// runs in chunks of [`INPUT_CHUNK`] pairs on all cores, joined in order, so the lists are
    /// the same for any thread count, and the same as the two one after the other.
    fn rules_and_narrow_phase_in_one_pass(&mut self, state: &State<V>) -> Option<usize> {
        use rayon::prelude::*;
        let (critters, rules, topo) = (&state.critters, &state.rules, &state.topo);
        let pass = |chunk: &[(u32, u32)],
                    contacts: &mut Vec<(u32, u32)>,
                    walls: &mut Vec<(u32, u32, bool)>| {
            rules_and_narrow(critters, rules, topo, chunk, contacts, walls)
        };
        self.contacts.clear();
        self.wall_pairs.clear();
        if self.candidates.len() < PARALLEL_PAIRS || rayon::current_num_threads() == 1 {
            let ruled = pass(&self.candidates, &mut self.contacts, &mut self.wall_pairs);
            if ruled.is_none() {
                self.contacts.clear();
                self.wall_pairs.clear();
            }
            return ruled;
        }
        type Part = (usize, Vec<(u32, u32)>, Vec<(u32, u32, bool)>);
        let parts: Vec<Part> = self
            .candidates
            .par_chunks(INPUT_CHUNK)
            .map(|chunk| {
                let (mut contacts, mut walls) = (Vec::new(), Vec::new());
                let ruled = pass(chunk, &mut contacts, &mut walls)?;
                Some((ruled, contacts, walls))
            })
            .collect::<Option<_>>()?;
        let mut ruled = 0;
        for (n, contacts, walls) in parts {
            ruled += n;
            self.contacts.extend(contacts);
            self.wall_pairs.extend(walls);
        }
        Some(ruled)
    }

    /// The contacts and wall pairs in the order of their lower id, then their higher one: the
    /// order the response takes them in, whatever order the broad phase found them in, and
    /// wherever the critters are stored.
    fn sort_contacts(&mut self, critters: &CritterSet<V>) {
        let crowded = !self.contacts.is_empty()
            && LISTED_PER_CONTACT * self.contacts.len() >= self.broad.listed();
        self.broad.set_crowded(crowded);
        let arranged = critters.is_arranged();
        // Stored elsewhere than their ids say: sorted as id indices, then back to slots.
        let slots = critters.slot_slice();
        let index = |s: u32| slots[s as usize].as_ref().map_or(u32::MAX, |c| c.id.index);
        if arranged {
            for p in &mut self.contacts {
                *p = (index(p.0), index(p.1));
            }
        }
        let n = critters.index_count().max(critters.slot_count());
        if !sort_pairs(&mut self.contacts, n) && self.contacts.len() >= RADIX_MIN && crowded {
            self.broad.sort_list();
        }
        if arranged {
            let slot = |i: u32| critters.slot_of_index(i).unwrap_or(u32::MAX);
            for p in &mut self.contacts {
                *p = (slot(p.0), slot(p.1));
            }
        }
        if arranged {
            self.wall_pairs
                .sort_unstable_by_key(|&(c, a, _)| pair_key(index(c), index(a)));
        } else {
            self.wall_pairs
                .sort_unstable_by_key(|&(c, a, _)| pair_key(c, a));
        }
    }
}

/// The rules and the narrow phase of a run of candidates: the pairs that may collide, in the
/// roles their rule gives, kept in `contacts` if they are two touching disks and in `walls` if
/// one is a wall (tested in the response); returns how many may collide. `None` when a pair's
/// rule is not in the class table, or a touching pair's roles are to be asked of the hooks (the
/// rules would run a script): the caller then runs the two one after the other.
fn rules_and_narrow<V: Vector>(
    critters: &CritterSet<V>,
    rules: &RuleCache,
    topo: &Topology<V>,
    chunk: &[(u32, u32)],
    contacts: &mut Vec<(u32, u32)>,
    walls: &mut Vec<(u32, u32, bool)>,
) -> Option<usize> {
    let slots = critters.slot_slice();
    let mut ruled = 0;
    // Every disk pair is written and the end moved on only for those that touch: in a gas most
    // candidates do not, in no order a processor could predict.
    let mut end = contacts.len();
    contacts.resize(end + chunk.len(), (0, 0));
    for (k, &(a, b)) in chunk.iter().enumerate() {
        if let Some(&(i, j)) = chunk.get(k + CANDIDATES_AHEAD) {
            prefetch(slots.get(i as usize));
            prefetch(slots.get(j as usize));
        }
        let (Some(ca), Some(cb)) = (critters.slot(a), critters.slot(b)) else {
            continue;
        };
        let (pair, ask) = match rules.cached(ca.class, cb.class)? {
            Some(rule) => match roles_slots(rule, (a, ca), (b, cb)) {
                Some(pair) => (pair, false),
                None => continue,
            },
            None => ((a, b), true),
        };
        ruled += 1;
        let (first, second) = if pair.0 == a { (ca, cb) } else { (cb, ca) };
        if first.is_wall() || second.is_wall() {
            // Tested in the response, once the disk pairs have moved.
            walls.push((pair.0, pair.1, ask));
        } else {
            let touching = crate::contact::touching_ball_ball(
                topo.delta(first.pos, second.pos),
                first.radius,
                second.radius,
            );
            if ask & touching {
                return None;
            }
            contacts[end] = pair;
            end += usize::from(touching);
        }
    }
    contacts.truncate(end);
    Some(ruled)
}

/// What the move stage checks for the pairs stage, critter by critter, while each is in cache
/// after its move: a survey of the critters, and which slots left their bound of the broad
/// phase's kept Verlet list (so that a repair need not look for them again).
pub(crate) struct MoveCheck<'a, V: Vector> {
    broad: &'a BroadPhase<V>,
}

impl<'a, V: Vector> MoveCheck<'a, V> {
    /// The check of one chunk of `len` slots in a world of topology `topo`.
    #[inline]
    pub(crate) fn chunk<'t>(&self, len: usize, topo: &'t Topology<V>) -> ChunkCheck<'t, V>
    where
        'a: 't,
    {
        ChunkCheck {
            broad: self.broad,
            topo,
            seen: CritterSurvey::default(),
            // Up to an eighth of a chunk (a repair mends at most a 32nd of all).
            most: len / 8 + 1,
            escapes: Escapes {
                slots: Vec::new(),
                complete: true,
            },
            walls: 0,
        }
    }

    /// The chunks' checks joined, in order.
    pub(crate) fn report(chunks: Vec<ChunkCheck<'_, V>>) -> MoveReport {
        let mut escapes = Escapes {
            slots: Vec::new(),
            complete: chunks.iter().all(|c| c.escapes.complete),
        };
        if escapes.complete {
            for c in &chunks {
                escapes.slots.extend_from_slice(&c.escapes.slots);
            }
        }
        MoveReport {
            escapes,
            walls: chunks.iter().map(|c| c.walls).sum(),
            chunks: chunks.len(),
            seen: chunks
                .iter()
                .fold(CritterSurvey::default(), |s, c| s.and(c.seen)),
        }
    }
}

/// [`MoveCheck`] of one chunk of slots.
pub(crate) struct ChunkCheck<'a, V: Vector> {
    broad: &'a BroadPhase<V>,
    topo: &'a Topology<V>,
    seen: CritterSurvey,
    most: usize,
    escapes: Escapes,
    walls: usize,
}

impl<V: Vector> ChunkCheck<'_, V> {
    /// Slot `i`, empty.
    #[inline]
    pub(crate) fn empty(&mut self, i: usize) {
        self.note(i, None);
    }

    /// Slot `i`, holding `c` where it has just moved to. Live walls are counted and left to the
    /// pairs stage, which knows how far to widen their boxes only when the survey is done.
    #[inline]
    pub(crate) fn moved(&mut self, i: usize, c: &Critter<V>) {
        self.seen = self.seen.and(CritterSurvey::of(c));
        if c.in_play() && c.is_wall() {
            self.walls += 1;
        } else {
            self.note(i, broad_object(c, i as u32, 0.0).as_ref());
        }
    }

    #[inline]
    fn note(&mut self, i: usize, o: Option<&BroadObject<V>>) {
        if self.escapes.complete && !self.broad.list_holds(self.topo, i, o) {
            self.escapes.complete = self.escapes.slots.len() < self.most;
            self.escapes.slots.push(i as u32);
        }
    }
}

/// What the move stage found for the pairs stage (see [`MoveCheck`]).
#[derive(Clone, Debug)]
pub(crate) struct MoveReport {
    /// How many chunks of [`INPUT_CHUNK`] slots it went through.
    chunks: usize,
    /// What it saw of the critters.
    seen: CritterSurvey,
    /// The slots but the live walls' that were no longer inside their bound of the broad
    /// phase's Verlet list.
    pub(crate) escapes: Escapes,
    /// How many live walls it passed over.
    walls: usize,
}

/// What the pairs stage needs to know of all the critters before the broad phase.
#[derive(Clone, Copy, Debug, Default)]
struct CritterSurvey {
    /// Some live critter has no rule class yet.
    unset: bool,
    /// The largest radius of a live disk (0 if none).
    largest_radius: f64,
}

impl CritterSurvey {
    /// What one critter adds.
    #[inline]
    fn of<V: Vector>(c: &Critter<V>) -> CritterSurvey {
        CritterSurvey {
            unset: c.in_play() && c.class == CLASS_UNSET,
            largest_radius: if c.in_play() && !c.is_wall() {
                c.radius
            } else {
                0.0
            },
        }
    }

    fn and(self, other: CritterSurvey) -> CritterSurvey {
        CritterSurvey {
            unset: self.unset || other.unset,
            largest_radius: self.largest_radius.max(other.largest_radius),
        }
    }
}

/// A live critter's box for the broad phase, a wall's widened by `wall_pad`. Only a wall's box
/// is read from its shape, so a disk's traits stay untouched.
#[inline]
pub(crate) fn broad_object<V: Vector>(
    c: &Critter<V>,
    slot: u32,
    wall_pad: f64,
) -> Option<BroadObject<V>> {
    if !c.in_play() {
        return None;
    }
    let mut o = BroadObject {
        center: c.pos,
        half: V::splat(c.radius),
        slot,
        is_wall: c.is_wall(),
    };
    if o.is_wall {
        o.half = wall_half(c) + V::splat(wall_pad);
    }
    Some(o)
}

/// A wall's box half sizes.
#[inline]
fn wall_half<V: Vector>(c: &Critter<V>) -> V {
    match c.shape() {
        Shape::Wall(w) => w.aabb_half(),
        Shape::Disk => V::splat(c.radius),
    }
}

/// The broad phase's objects read in place from the critters' slots: index `i` is slot `i`, a
/// gap where no live critter is.
struct SlotObjects<'a, V: Vector> {
    slots: &'a [Option<Critter<V>>],
    /// How far to widen the walls' boxes.
    wall_pad: f64,
    /// The step's length, for the critters' strides.
    dt: f64,
    /// Sleepers and walls by slot, or empty (see [`Objects::still`]).
    still: &'a [bool],
}

impl<V: Vector> Objects<V> for SlotObjects<'_, V> {
    #[inline]
    fn slots(&self) -> usize {
        self.slots.len()
    }

    #[inline]
    fn object(&self, i: usize) -> Option<BroadObject<V>> {
        self.slots
            .get(i)?
            .as_ref()
            .and_then(|c| broad_object(c, i as u32, self.wall_pad))
    }

    #[inline]
    fn prefetch(&self, i: usize) {
        prefetch(self.slots.get(i));
    }

    #[inline]
    fn still(&self, i: usize) -> bool {
        self.still.get(i).copied().unwrap_or(false)
    }

    #[inline]
    fn any_still(&self) -> bool {
        !self.still.is_empty()
    }

    #[inline]
    fn step(&self, i: usize) -> V {
        match self.slots.get(i) {
            Some(Some(c)) if c.in_play() && !c.fixed && !c.is_wall() => c.vel * self.dt,
            _ => V::zero(),
        }
    }
}

#[cfg(test)]
mod tests;
