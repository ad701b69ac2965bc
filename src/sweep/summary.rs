//! A run's summary as data: what `critterbox run` prints, written as JSON by
//! `critterbox run --summary-json FILE` and read back by the sweep.

use crate::critter::PropValue;
use crate::scenes::AnyWorld;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::time::Duration;

/// What a run ended with.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// The scene's name.
    pub scene: String,
    /// 2 or 3.
    pub dim: usize,
    /// The collision method the world ran.
    pub method: String,
    /// The seed of the world's generator.
    pub seed: u64,
    /// The time step.
    pub dt: f64,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time at the end.
    pub time: f64,
    /// Live critters by kind at the end.
    pub alive: BTreeMap<String, usize>,
    /// Contacts handled, summed over the steps.
    pub collisions: u64,
    /// Impacts (approaching contacts) summed over the steps.
    pub impacts: u64,
    /// Kinetic energy at the start.
    pub energy_start: f64,
    /// Kinetic energy at the end.
    pub energy_end: f64,
    /// (end - start) / start, 0 when the start is 0.
    pub energy_change: f64,
    /// Momentum at the start, `[x, y, z]`.
    pub momentum_start: [f64; 3],
    /// Momentum at the end.
    pub momentum_end: [f64; 3],
    /// The length of (end - start).
    pub momentum_change: f64,
    /// The final state hash, 16 hex digits as `critterbox run` prints it.
    pub state_hash: String,
    /// Wall time of the steps, in seconds.
    pub wall_s: f64,
    /// `completed`, `stopped` (by the scene) or `interrupted` (by a signal).
    pub outcome: String,
    /// Why it stopped or was interrupted (empty when completed).
    pub reason: String,
    /// The scripts' `world().vars` at the end.
    pub vars: serde_json::Map<String, serde_json::Value>,
}

impl RunSummary {
    /// The summary of `world` after a run that started with `energy0` and `momentum0`.
    pub fn of(
        world: &AnyWorld,
        scene: &str,
        energy0: f64,
        momentum0: [f64; 3],
        wall: Duration,
        outcome: &str,
        reason: &str,
    ) -> RunSummary {
        let totals = world.totals();
        let energy = world.kinetic_energy();
        let momentum = world.momentum();
        let dp: f64 = (0..3).map(|i| (momentum[i] - momentum0[i]).powi(2)).sum();
        RunSummary {
            scene: scene.to_string(),
            dim: world.dim(),
            method: world.method().to_string(),
            seed: world.seed(),
            dt: world.dt(),
            steps: world.step_count(),
            time: world.time(),
            alive: world.count_by_kind(),
            collisions: totals.collisions as u64,
            impacts: totals.impacts as u64,
            energy_start: energy0,
            energy_end: energy,
            energy_change: if energy0 > 0.0 {
                (energy - energy0) / energy0
            } else {
                0.0
            },
            momentum_start: momentum0,
            momentum_end: momentum,
            momentum_change: dp.sqrt(),
            state_hash: format!("{:016x}", world.state_hash()),
            wall_s: wall.as_secs_f64(),
            outcome: outcome.to_string(),
            reason: reason.to_string(),
            vars: world
                .vars()
                .iter()
                .map(|(k, v)| (k.clone(), prop_to_json(v)))
                .collect(),
        }
    }
}

/// A property as plain JSON: numbers, text, booleans, lists and maps as such, a critter as
/// its id's number, a vector as a list of three numbers.
pub fn prop_to_json(v: &PropValue) -> serde_json::Value {
    use serde_json::Value;
    match v {
        PropValue::Bool(b) => Value::Bool(*b),
        PropValue::Int(i) => Value::from(*i),
        PropValue::Float(f) => Value::from(*f),
        PropValue::Text(s) => Value::String(s.clone()),
        PropValue::Critter(id) => Value::String(id.to_string()),
        PropValue::List(l) => Value::Array(l.iter().map(prop_to_json).collect()),
        PropValue::Vector(x) => Value::from(x.to_vec()),
        PropValue::Map(m) => Value::Object(
            m.iter()
                .map(|(k, v)| (k.clone(), prop_to_json(v)))
                .collect(),
        ),
    }
}
