//! How often a full state is recorded: every step for small scenes, every K steps otherwise,
//! with K the smallest round number whose keyframes (capturing and encoding a full state,
//! spread over K steps) stay within their share of the step time, under a cost model measured
//! on the 10,000-critter gas (`cargo bench --bench recording`; the figures and the method are in
//! docs/recording-format.md).
//!
//! K does not change the cost of what every step records (hash, totals and events), so that
//! cost is not part of the model (docs/recording-format.md reports it).
//!
//! The model is conservative: it counts the writer thread's work (JSON, the Foxglove scene,
//! zstd) as if it ran on the simulation's core, because on a shared two-core machine it often
//! does.

/// Per-critter costs, in nanoseconds, measured on the benchmark machine (2 shared cores).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostModel {
    /// A gas step, per critter.
    pub step: f64,
    /// A keyframe on the simulation thread: copying the critters into columns, per critter.
    pub capture: f64,
    /// A keyframe on the writer thread: JSON, the Foxglove scene, zstd, per critter.
    pub encode: f64,
}

/// The measured model (see the module docs).
pub const MEASURED: CostModel = CostModel {
    step: 29.0,
    capture: 12.8,
    encode: 983.0,
};

/// Keyframes may add this fraction to the simulation thread's step time.
pub const KEYFRAME_BUDGET: f64 = 0.02;

/// Scenes with at most this many critters record their full state every step: a full state of
/// 100 critters costs about 0.15 ms on the writer thread and 5 KB in the file.
pub const SMALL_SCENE: usize = 100;

/// The round numbers K is chosen from.
const ROUND: [u64; 12] = [1, 2, 5, 10, 20, 30, 60, 120, 300, 600, 1200, 3000];

impl CostModel {
    /// The smallest round K with `(capture + encode) / K <= KEYFRAME_BUDGET * step`.
    pub fn every(&self) -> u64 {
        ROUND
            .iter()
            .copied()
            .find(|&k| self.fits(k))
            .unwrap_or(ROUND[ROUND.len() - 1])
    }

    /// Whether keyframes every `k` steps stay within their budget.
    fn fits(&self, k: u64) -> bool {
        (self.capture + self.encode) / k as f64 <= KEYFRAME_BUDGET * self.step
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
        // K is the smallest round number that fits: it fits, the round number before it does not.
        let m = MEASURED;
        assert!(m.fits(k), "{k}");
        let i = ROUND
            .iter()
            .position(|&r| r == k)
            .expect("K is a round number");
        assert!(!m.fits(ROUND[i - 1]), "{} would fit too", ROUND[i - 1]);
    }

    #[test]
    fn a_slower_step_gives_a_smaller_k() {
        let m = MEASURED;
        let slower_step = CostModel {
            step: m.step * 10.0,
            ..m
        };
        assert!(slower_step.every() < m.every());
        // A step of 95 ns per critter, with its capture and encoding, gives K = 1200.
        let before = CostModel {
            step: 95.0,
            capture: 19.0,
            encode: 1340.0,
        };
        assert_eq!(before.every(), 1200);
    }
}
