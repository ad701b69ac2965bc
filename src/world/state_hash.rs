//! The state hash: one 64-bit word over the raw bits of everything a step depends on, so equal
//! hashes mean bit-identical worlds. Recordings write it every step; replays compare it.

use super::World;
use crate::hash::{StateHasher, LANES};
use crate::vector::Vector;

/// Marks where `world().vars` starts in the hashed words ("vars" in ASCII).
const VARS_TAG: u64 = 0x7661_7273;

impl<V: Vector> World<V> {
    /// A hash of the whole dynamic state over raw float bits: equal hashes mean (with
    /// overwhelming probability) bit-identical worlds. It covers the step count, dt, the
    /// generator's state and, for every critter, id, kind, fixed, alive, position, velocity,
    /// radius, mass, priority, restitution, health and properties, under `solve:n` the
    /// critters' counts of quiet steps towards sleep, and the scripts' `world().vars` when not
    /// empty.
    pub fn state_hash(&self) -> u64 {
        self.state_hash_and_totals().0
    }

    /// [`World::state_hash`], [`World::kinetic_energy`] and [`World::momentum`] (the same bits)
    /// from one pass over the critters, so a recorder walks them once.
    pub fn state_hash_and_totals(&self) -> (u64, f64, V) {
        let mut h = StateHasher::default();
        h.word(self.state.step_count);
        h.float(self.state.dt);
        for w in self.state.rng.state() {
            h.word(w);
        }
        // Every critter's fields in lanes (src/hash/critters.rs), the rarely changing ones reused
        // from the last hash when nothing could have written them; properties go to a hasher of
        // their own, after their owner's id.
        const _: () = assert!(crate::hash::critters::LANES.is_multiple_of(LANES));
        let pass = crate::hash::critters::hash_critters(
            self.state.critters.in_id_order(),
            self.state.critters.statics(),
        );
        for half in pass.lanes.chunks_exact(LANES) {
            let mut w = [0u64; LANES];
            w.copy_from_slice(half);
            h.words(w);
        }
        h.word(pass.props);
        // The quiet steps, when there are any (a world without them hashes as it did before
        // sleep existed).
        for (slot, q, island) in self.methods.quiet_counts() {
            h.word((slot as u64) << 16 | u64::from(q));
            h.word(u64::from(island));
        }
        // The scripts' shared state, when there is any (a world without it hashes as it did
        // before it existed); the tag keeps it apart from the quiet steps' words.
        if !self.state.vars.is_empty() {
            h.word(VARS_TAG);
            crate::hash::critters::hash_named(&mut h, &self.state.vars);
        }
        (h.finish(), pass.energy, pass.momentum)
    }
}

#[cfg(test)]
mod tests {
    use crate::critter::{CritterSpec, PropValue};
    use crate::world::{World, WorldConfig};
    use glam::DVec2;

    fn world() -> World<DVec2> {
        let config = WorldConfig::new(DVec2::ZERO, DVec2::new(10.0, 10.0));
        let mut w = World::new(config).expect("a world");
        w.spawn(CritterSpec::ball(DVec2::new(1.0, 1.0)).vel(DVec2::new(0.5, 0.0)))
            .expect("a ball");
        w
    }

    /// Vars are hashed when there are any, every name and value counts, and a world whose
    /// vars are empty hashes as one that never had any (so scenes without vars keep their
    /// hashes).
    #[test]
    fn vars_change_the_hash_and_empty_vars_hash_as_none() {
        let mut w = world();
        let none = w.state_hash();
        let mut seen = vec![none];
        let mut differs = |w: &World<DVec2>, what: &str| {
            let h = w.state_hash();
            assert!(!seen.contains(&h), "{what}: the hash did not change");
            seen.push(h);
        };
        w.vars_mut().insert("score".into(), PropValue::Int(1));
        differs(&w, "a var");
        w.vars_mut().insert("score".into(), PropValue::Int(2));
        differs(&w, "its value");
        w.vars_mut().insert("score".into(), PropValue::Float(2.0));
        differs(&w, "its type");
        let nested = |hits| {
            PropValue::Map(
                [("hits".to_string(), PropValue::Int(hits))]
                    .into_iter()
                    .collect(),
            )
        };
        w.vars_mut().insert("best".into(), nested(0));
        differs(&w, "a map var");
        w.vars_mut().insert("best".into(), nested(1));
        differs(&w, "a value inside it");
        let renamed = w.vars_mut().remove("best");
        w.vars_mut().insert("bets".into(), renamed.expect("there"));
        differs(&w, "a name");
        w.vars_mut().clear();
        assert_eq!(w.state_hash(), none, "empty vars hash as no vars");
        // A colour changes what is drawn, not what happens: not hashed.
        let id = w.critters().iter().next().expect("the ball").id();
        w.get_mut(id)
            .expect("there")
            .set_color(Some("red"))
            .expect("a colour");
        assert_eq!(w.state_hash(), none);
    }
}
