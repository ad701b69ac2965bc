//! Where the critters are stored: laid out along the grid's rows, so that critters near each
//! other in space are near each other in memory, as the broad phase walks them.

use crate::border::Topology;
use crate::broad_phase::BroadPhase;
use crate::critter::Critter;
use crate::step::state::State;
use crate::vector::Vector;

/// When the world lays its critters out in memory (see [`Locality`]), by default: every 200
/// steps the layout is checked, from 50,000 critters on, and made anew when a quarter of them
/// are out of order.
pub const LOCALITY: Locality = Locality {
    every: 200,
    min_critters: 50_000,
    disorder: 0.25,
};

/// When the world lays its critters out in memory along its grid's rows, so that critters near
/// each other in space are near each other in memory, as the broad phase walks them (critters
/// spawned in any order, or mixed by a long run, are otherwise scattered over 128 MB at a
/// million). It changes where the critters are stored, never what happens: ids, the order of
/// every hook call and of the response, the state hash and every recorded byte stay the same.
/// Only under `discrete` and `substep:n`; the other methods keep state by slot and find the
/// critters back in id order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Locality {
    /// Steps between two layouts (0: never).
    pub every: u64,
    /// Fewest live critters for a layout (below, the critters fit in the caches anyway).
    pub min_critters: usize,
    /// Least share of critters out of order (more than a row away from the critter stored
    /// before it) for a layout: critters spawned row by row, as the built-in scenes do, are
    /// left where they are until they have mixed.
    pub disorder: f64,
}

/// The world's layout settings and how many layouts it made.
pub(crate) struct Layout {
    pub(crate) locality: Locality,
    /// Layouts made (diagnostics).
    pub(crate) count: u64,
}

impl Layout {
    pub(crate) fn new(locality: Locality) -> Self {
        Layout { locality, count: 0 }
    }

    /// Lays the critters out along the grid's rows when one is due (see [`Locality`]) and the
    /// step's method keeps no state by slot (`allowed`), or puts them back in id order for a
    /// method that does. The broad phase drops its list, which names slots, after either.
    pub(crate) fn lay_out<V: Vector>(
        &mut self,
        state: &mut State<V>,
        broad: &mut BroadPhase<V>,
        allowed: bool,
    ) {
        let critters = &mut state.critters;
        if !allowed {
            if critters.is_arranged() {
                critters.unarrange();
                broad.forget_list();
            }
            return;
        }
        let Locality {
            every,
            min_critters,
            disorder,
        } = self.locality;
        let step = state.step_count;
        if every == 0
            || step == 0
            || !step.is_multiple_of(every)
            || critters.len() < min_critters.max(2)
        {
            return;
        }
        let (keys, per_row) = layout_keys(&state.topo, critters.slot_slice(), critters.len());
        // Out of order: neighbours in memory more than a row apart.
        let mut live = keys
            .iter()
            .filter(|&&k| k != u32::MAX)
            .map(|&k| k / per_row);
        let (mut pairs, mut apart) = (0usize, 0usize);
        if let Some(mut last) = live.next() {
            for row in live {
                pairs += 1;
                apart += usize::from(row.abs_diff(last) > 1);
                last = row;
            }
        }
        if (apart as f64) < disorder * pairs as f64 {
            return;
        }
        critters.arrange(&keys);
        broad.forget_list();
        self.count += 1;
    }
}

/// By slot, the key of each critter's place in the layout (`u32::MAX` for an empty slot only),
/// and the keys per row.
///
/// The layout follows the broad phase's grid, whose cells run along x, then y, then z: the box
/// is cut into rows along x, two mean spacings of the critters high (and deep in 3D), taken one
/// after the other as the grid's cells are, and each row's critters are ordered by x. The pair
/// walk of the grid, and of the list it builds, then goes through the critters nearly in memory
/// order.
fn layout_keys<V: Vector>(
    topo: &Topology<V>,
    slots: &[Option<Critter<V>>],
    live: usize,
) -> (Vec<u32>, u32) {
    use rayon::prelude::*;
    let (min, size) = (topo.min, topo.max - topo.min);
    let volume: f64 = (0..V::DIM).map(|axis| size.get(axis)).product();
    let spacing = (volume / live.max(1) as f64).powf(1.0 / V::DIM as f64);
    // Rows along x over the other axes, at most 2^16 of them in all.
    let mut height = 2.0 * spacing;
    let rows_on = |height: f64, axis: usize| (size.get(axis) / height).ceil().max(1.0);
    let rows = |height: f64| {
        (1..V::DIM)
            .map(|axis| rows_on(height, axis))
            .product::<f64>()
    };
    while rows(height) > 65_536.0 {
        height *= 2.0;
    }
    let row_count = rows(height) as u64;
    // Steps along x within a row: the keys of all rows fit below u32::MAX.
    let steps = (u64::from(u32::MAX - 1) / row_count).max(1) as f64;
    let key = |c: &Critter<V>| {
        let mut row = 0.0;
        for axis in (1..V::DIM).rev() {
            let n = rows_on(height, axis);
            // NaN and positions outside the box clamp to its edges.
            let r = ((c.pos.get(axis) - min.get(axis)) / height)
                .floor()
                .clamp(0.0, n - 1.0);
            row = row * n + if r.is_nan() { 0.0 } else { r };
        }
        let t = (c.pos.get(0) - min.get(0)) / size.get(0);
        let x = (t * steps).floor().clamp(0.0, steps - 1.0);
        let x = if x.is_nan() { 0.0 } else { x };
        ((row * steps + x) as u64).min(u64::from(u32::MAX - 1)) as u32
    };
    let keys = slots
        .par_iter()
        .map(|c| c.as_ref().map_or(u32::MAX, key))
        .collect();
    (keys, steps as u32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::critter::{CritterId, CritterSpec};
    use crate::critter_set::CritterSet;
    use crate::world::tests::gas;
    use crate::world::World;
    use glam::DVec2;

    /// Every id finds its own critter, iteration goes in id order, and the hash and totals are
    /// those of the same critters in id order.
    fn check_ids(w: &World<DVec2>, what: &str) {
        let set = &w.state.critters;
        let ids: Vec<CritterId> = set.iter().map(|c| c.id).collect();
        assert_eq!(ids.len(), set.len(), "{what}: every critter once");
        assert!(ids.is_sorted(), "{what}: iteration in id order");
        for &id in &ids {
            let slot = set.slot_of(id).expect("a slot");
            assert_eq!(set.slot(slot).map(|c| c.id), Some(id), "{what}: {id}");
            assert_eq!(set.get(id).map(|c| c.id), Some(id), "{what}: {id}");
        }
        // The same critters put back in id order: a set of their own, built from its parts.
        let free: Vec<CritterId> = set.free_ids().collect();
        let plain = CritterSet::from_parts(set.iter().cloned().collect(), &free).expect("parts");
        assert!(!plain.is_arranged());
        let (a, b) = (
            crate::hash::critters::hash_critters(set.in_id_order(), set.statics()),
            crate::hash::critters::hash_critters(plain.in_id_order(), plain.statics()),
        );
        assert_eq!((a.lanes, a.props), (b.lanes, b.props), "{what}: hash");
        assert_eq!(
            (a.energy.to_bits(), a.momentum),
            (b.energy.to_bits(), b.momentum),
            "{what}: totals"
        );
    }

    /// `arrange` puts the critters in the order of their keys, with the empty slots dropped and
    /// ids unchanged; spawns, removals and `unarrange` after it keep every id on its critter.
    #[test]
    fn critters_laid_out_keep_their_ids() {
        let mut w = gas(400);
        for i in (10..300).step_by(7) {
            let id = w.state.critters.slot(i).expect("a critter").id;
            w.remove(id).expect("removed");
        }
        let live = w.state.critters.len();
        assert!(
            w.state.critters.slot_count() > live,
            "test setup: empty slots"
        );
        check_ids(&w, "before");
        // Keys that reverse the slots' order, the empty slots marked.
        let keys: Vec<u32> = (0..w.state.critters.slot_count())
            .map(|s| match w.state.critters.slot(s as u32) {
                Some(_) => 1_000_000 - s as u32,
                None => u32::MAX,
            })
            .collect();
        let before: Vec<CritterId> = w.state.critters.iter_stored().map(|c| c.id).collect();
        w.state.critters.arrange(&keys);
        assert!(w.state.critters.is_arranged());
        assert_eq!(w.state.critters.slot_count(), live, "empty slots dropped");
        let after: Vec<CritterId> = w.state.critters.iter_stored().map(|c| c.id).collect();
        assert_eq!(
            after,
            before.into_iter().rev().collect::<Vec<_>>(),
            "keys' order"
        );
        check_ids(&w, "arranged");
        // A spawn takes a free id and a new slot at the end; a removal leaves a gap.
        let spawned = w
            .spawn(CritterSpec::ball(DVec2::new(3.0, 3.0)))
            .expect("spawns");
        assert_eq!(w.state.critters.slot_of(spawned), Some(live as u32));
        check_ids(&w, "spawned");
        let gone = after[5];
        w.remove(gone).expect("removed");
        assert!(w.state.critters.get(gone).is_none() && w.state.critters.slot_of(gone).is_none());
        check_ids(&w, "removed");
        w.state.critters.unarrange();
        assert!(!w.state.critters.is_arranged());
        for c in w.state.critters.iter() {
            assert_eq!(
                w.state.critters.slot_of(c.id),
                Some(c.id.index),
                "back in id order"
            );
        }
        check_ids(&w, "unarranged");
    }

    /// The world's own layout follows the grid's rows: critters stored in a shuffled order
    /// (far apart in space when next to each other in memory) are laid out at the next check,
    /// after which neighbours in memory are about one spacing apart; critters spawned row by
    /// row are left as they are. Neither changes the run.
    #[test]
    fn the_layout_puts_neighbours_in_space_next_to_each_other_in_memory() {
        let checked = Locality {
            every: 1,
            min_critters: 0,
            disorder: LOCALITY.disorder,
        };
        let gap = |w: &World<DVec2>| {
            let cs: Vec<&Critter<DVec2>> =
                w.state.critters.iter_stored().filter(|c| !c.wall).collect();
            let sum: f64 = cs.windows(2).map(|p| (p[0].pos - p[1].pos).length()).sum();
            sum / (cs.len() - 1) as f64
        };
        let (mut shuffled, mut plain) = (gas(5_000), gas(5_000));
        plain.set_locality(Locality {
            every: 0,
            ..checked
        });
        shuffled.set_locality(checked);
        let keys: Vec<u32> = (0..shuffled.state.critters.slot_count() as u64)
            .map(|s| (s.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 33) as u32)
            .collect();
        shuffled.state.critters.arrange(&keys);
        shuffled.pairs.broad.forget_list();
        let (before, spawned) = (gap(&shuffled), gap(&plain));
        // The box is 140 wide: shuffled neighbours are some 70 apart, spawned ones a spacing (2)
        // and a jump at the end of each row of 71 (2 more on average).
        assert!(before > 30.0 && spawned < 5.0, "{before}, {spawned}");
        for step in 0..3 {
            shuffled.step().expect("steps");
            plain.step().expect("steps");
            assert_eq!(shuffled.state_hash(), plain.state_hash(), "step {step}");
        }
        let after = gap(&shuffled);
        assert!(
            after < 5.0,
            "mean gap in memory {after} laid out, {before} shuffled"
        );
        // Spawned row by row, the gas is in order: checked every step, never laid out.
        let mut spawned = gas(5_000);
        spawned.set_locality(checked);
        spawned.run(5).expect("runs");
        assert!(
            !spawned.state.critters.is_arranged(),
            "a gas in order is left alone"
        );
    }
}
