//! How often a full state is recorded: every step for small scenes, every K steps otherwise,
//! with K the smallest round number that keeps recording within its time budget under a cost
//! model measured on the 10,000-critter gas (`cargo bench --bench recording`; the figures and
//! the method are in docs/recording-format.md).
//!
//! The model is conservative: it counts the writer thread's work (JSON, the Foxglove scene,
//! zstd) as if it ran on the simulation's core, because on a shared two-core machine it often
//! does.

/// Per-critter costs, in nanoseconds, measured on the benchmark machine (2 shared cores).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostModel {
    /// A gas step, per critter.
    pub step: f64,
    /// Every step on the simulation thread: hash, totals and events, per critter.
    pub per_step: f64,
    /// A keyframe on the simulation thread: copying the critters into columns, per critter.
    pub capture: f64,
    /// A keyframe on the writer thread: JSON, the Foxglove scene, zstd, per critter.
    pub encode: f64,
}

/// The measured model (see the module docs).
pub const MEASURED: CostModel = CostModel {
    step: 95.0,
    per_step: 8.1,
    capture: 19.0,
    encode: 1340.0,
};

/// Recording may add this fraction to the simulation thread's step time.
pub const BUDGET: f64 = 0.10;

/// Scenes with at most this many critters record their full state every step: a full state of
/// 100 critters costs about 0.15 ms on the writer thread and 5 KB in the file.
pub const SMALL_SCENE: usize = 100;

/// The round numbers K is chosen from.
const ROUND: [u64; 12] = [1, 2, 5, 10, 20, 30, 60, 120, 300, 600, 1200, 3000];

impl CostModel {
    /// The smallest round K with `per_step + (capture + encode) / K <= BUDGET * step`.
    pub fn every(&self) -> u64 {
        let fits = |k: f64| self.per_step + (self.capture + self.encode) / k <= BUDGET * self.step;
        ROUND
            .iter()
            .copied()
            .find(|&k| fits(k as f64))
            .unwrap_or(ROUND[ROUND.len() - 1])
    }
}

/// The default `--record-every` for a scene of `critters` critters.
pub fn default_record_every(critters: usize) -> u64 {
    if critters <= SMALL_SCENE {
        1
    } else {
        MEASURED.every()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_scenes_record_every_step_large_ones_keyframes() {
        assert_eq!(default_record_every(16), 1);
        let k = default_record_every(10_000);
        assert!(k > 1, "{k}");
        let m = MEASURED;
        assert!(m.per_step + (m.capture + m.encode) / k as f64 <= BUDGET * m.step);
    }
}
