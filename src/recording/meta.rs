//! The metadata records: how a run was made (written first) and how it ended (written last).
//!
//! MCAP metadata maps strings to strings; structured values are JSON text, floats are written
//! in their shortest round-trip form so they read back bit for bit.

use super::keyframes::default_record_every;
use super::schema::{FORMAT, FORMATS_READ, STATE_HASH};
use crate::profile::ProfileRow;
use crate::scenes::Scene;
use crate::script::Limits;
use serde_json::json;
use std::collections::BTreeMap;

/// Where a recorded scene came from.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSource {
    /// A built-in scene, rebuilt from its name and parameters.
    Builtin,
    /// A scene script, rebuilt from the attachments; `file` is the scene's attachment name.
    Script {
        /// Name of the scene file's attachment (the path it was loaded from).
        file: String,
    },
    /// A world a test function of `critterbox test` built itself (recorded when the test
    /// failed): it is replayed from its recorded states, but `replay --verify` cannot rebuild
    /// it, since the test function, not a scene, made it.
    Test {
        /// The test, as `critterbox test` names it (`file::function`).
        case: String,
    },
}

/// How a run was made: everything `replay --verify` needs besides the scripts.
#[derive(Clone, Debug, PartialEq)]
pub struct RunMeta {
    /// critterbox version that recorded.
    pub version: String,
    /// Scene name (built-in name or script file stem).
    pub scene: String,
    /// Built-in or script.
    pub source: SceneSource,
    /// The world's seed.
    pub seed: u64,
    /// `--seed`, if given.
    pub seed_override: Option<u64>,
    /// Time step at the start.
    pub dt: f64,
    /// `--dt`, if given.
    pub dt_override: Option<f64>,
    /// Steps asked for.
    pub steps: u64,
    /// Integration method.
    pub method: String,
    /// 2 or 3.
    pub dim: usize,
    /// Border rule.
    pub border: String,
    /// `-n` (built-in scenes).
    pub n: Option<usize>,
    /// `--set NAME=VALUE` overrides (already applied to the attached scene text).
    pub sets: Vec<String>,
    /// Script limits.
    pub limits: Limits,
    /// The command line.
    pub command_line: Vec<String>,
    /// Full state every this many steps.
    pub record_every: u64,
    /// Critters at the start (walls included).
    pub critters: usize,
    /// When the recording was made (UTC, informational).
    pub created: String,
}

/// What a run changes of its scene's own settings (the command line's `--seed`, `--dt`, `-n`,
/// `--set`, `--steps`, the script limits and `--record-every`), as its recording keeps them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunOverrides {
    /// `--seed`.
    pub seed: Option<u64>,
    /// `--dt`.
    pub dt: Option<f64>,
    /// `-n` (built-in scenes).
    pub n: Option<usize>,
    /// `--set NAME=VALUE`, already applied to the scene.
    pub sets: Vec<String>,
    /// `--steps` (default: the scene's own).
    pub steps: Option<u64>,
    /// The script limits the scene runs under.
    pub limits: Limits,
    /// `--record-every` (default: [`default_record_every`] of the scene's size).
    pub record_every: Option<u64>,
}

impl RunMeta {
    /// How `scene` is run with `overrides`: what a recording of the run starts with.
    pub fn for_scene(scene: &Scene, overrides: &RunOverrides) -> RunMeta {
        let world = &scene.world;
        let source = match scene.sources.first() {
            Some(file) => SceneSource::Script {
                file: file.path.clone(),
            },
            None => SceneSource::Builtin,
        };
        RunMeta {
            version: env!("CARGO_PKG_VERSION").to_string(),
            scene: scene.name.clone(),
            source,
            seed: world.seed(),
            seed_override: overrides.seed,
            dt: world.dt(),
            dt_override: overrides.dt,
            steps: overrides.steps.unwrap_or(scene.default_steps),
            method: world.method().to_string(),
            dim: world.dim(),
            border: format!("{:?}", world.border()).to_lowercase(),
            n: overrides.n,
            sets: overrides.sets.clone(),
            limits: overrides.limits.clone(),
            command_line: std::env::args().collect(),
            record_every: overrides
                .record_every
                .unwrap_or_else(|| default_record_every(world.len())),
            critters: world.len(),
            created: utc_now().1,
        }
    }
}

/// The outcome of a run whose scene could not be built ([`EndMeta::outcome`]).
pub const SETUP_FAILED: &str = "setup_failed";

impl RunMeta {
    /// How a run was asked for whose scene could not be built: `scene` is the name asked for and
    /// `file` its script, if it is one. What only the built world would tell (dimension, border,
    /// method, critters) is written as unknown: `dim` 0, `border` and `method` `unknown` (or the
    /// `--method` asked for).
    pub fn for_failed_setup(
        scene: &str,
        file: Option<&str>,
        method: Option<String>,
        overrides: &RunOverrides,
    ) -> RunMeta {
        let source = match file {
            Some(f) => SceneSource::Script { file: f.into() },
            None => SceneSource::Builtin,
        };
        RunMeta {
            version: env!("CARGO_PKG_VERSION").to_string(),
            scene: scene.to_string(),
            source,
            seed: overrides.seed.unwrap_or(0),
            seed_override: overrides.seed,
            dt: overrides.dt.unwrap_or(0.0),
            dt_override: overrides.dt,
            steps: overrides.steps.unwrap_or(0),
            method: method.unwrap_or_else(|| "unknown".into()),
            dim: 0,
            border: "unknown".into(),
            n: overrides.n,
            sets: overrides.sets.clone(),
            limits: overrides.limits.clone(),
            command_line: std::env::args().collect(),
            record_every: overrides.record_every.unwrap_or(1),
            critters: 0,
            created: utc_now().1,
        }
    }
}

fn float(x: f64) -> String {
    let mut b = ryu::Buffer::new();
    b.format(x).to_string()
}

fn limits_json(l: &Limits) -> String {
    json!({
        "max_operations": l.max_operations,
        "max_step_operations": l.max_step_operations,
        "max_call_levels": l.max_call_levels,
        "max_string_size": l.max_string_size,
        "max_array_size": l.max_array_size,
        "max_map_size": l.max_map_size,
        "max_spawns_per_step": l.max_spawns_per_step,
    })
    .to_string()
}

impl RunMeta {
    /// As an MCAP metadata map.
    pub fn to_map(&self) -> BTreeMap<String, String> {
        let mut m = BTreeMap::new();
        let mut put = |k: &str, v: String| {
            m.insert(k.to_string(), v);
        };
        put("format", FORMAT.into());
        put("state_hash", STATE_HASH.into());
        put("critterbox_version", self.version.clone());
        put("scene", self.scene.clone());
        match &self.source {
            SceneSource::Builtin => put("scene_source", "builtin".into()),
            SceneSource::Script { file } => {
                put("scene_source", "script".into());
                put("scene_file", file.clone());
            }
            SceneSource::Test { case } => {
                put("scene_source", "test".into());
                put("test_case", case.clone());
            }
        }
        put("seed", self.seed.to_string());
        if let Some(s) = self.seed_override {
            put("seed_override", s.to_string());
        }
        put("dt", float(self.dt));
        if let Some(dt) = self.dt_override {
            put("dt_override", float(dt));
        }
        put("steps", self.steps.to_string());
        put("method", self.method.clone());
        put("dim", self.dim.to_string());
        put("border", self.border.clone());
        if let Some(n) = self.n {
            put("n", n.to_string());
        }
        put(
            "params",
            json!({ "n": self.n, "seed": self.seed_override.unwrap_or(self.seed),
                    "dt": self.dt_override })
            .to_string(),
        );
        put("sets", json!(self.sets).to_string());
        put("limits", limits_json(&self.limits));
        put("command_line", json!(self.command_line).to_string());
        put("record_every", self.record_every.to_string());
        put("critters", self.critters.to_string());
        put("created", self.created.clone());
        m
    }

    /// The metadata of a built-in scene built with `params` (for programs and benchmarks that
    /// record without the command line).
    pub fn builtin(
        scene: &crate::scenes::Scene,
        params: &crate::scenes::SceneParams,
        steps: u64,
        record_every: u64,
    ) -> RunMeta {
        let w = &scene.world;
        RunMeta {
            version: env!("CARGO_PKG_VERSION").to_string(),
            scene: scene.name.clone(),
            source: SceneSource::Builtin,
            seed: params.seed,
            seed_override: Some(params.seed),
            dt: w.dt(),
            dt_override: params.dt,
            steps,
            method: "discrete".into(),
            dim: w.dim(),
            border: format!("{:?}", w.border()).to_lowercase(),
            n: params.n,
            sets: Vec::new(),
            limits: Limits::default(),
            command_line: Vec::new(),
            record_every,
            critters: w.len(),
            created: utc_now().1,
        }
    }

    /// From an MCAP metadata map; errors name the missing or bad key.
    pub fn from_map(m: &BTreeMap<String, String>) -> Result<RunMeta, String> {
        let get = |k: &str| {
            m.get(k)
                .map(String::as_str)
                .ok_or_else(|| format!("metadata key '{k}' is missing"))
        };
        fn parse<T: std::str::FromStr>(k: &str, v: &str) -> Result<T, String> {
            v.parse()
                .map_err(|_| format!("metadata key '{k}' has a bad value '{v}'"))
        }
        let opt = |k: &str| m.get(k).map(String::as_str);
        let format = get("format")?;
        if !FORMATS_READ.contains(&format) {
            return Err(format!(
                "recording format '{format}' is not one this critterbox reads ({}): it was made by another critterbox; read it with that one, or record the run again",
                FORMATS_READ.join(", ")
            ));
        }
        let source = match get("scene_source")? {
            "builtin" => SceneSource::Builtin,
            "script" => SceneSource::Script {
                file: get("scene_file")?.to_string(),
            },
            "test" => SceneSource::Test {
                case: get("test_case")?.to_string(),
            },
            other => return Err(format!("unknown scene_source '{other}'")),
        };
        let limits: serde_json::Value = serde_json::from_str(get("limits")?)
            .map_err(|e| format!("metadata key 'limits' is not JSON: {e}"))?;
        let d = Limits::default();
        let lim = |k: &str, default: u64| limits.get(k).and_then(|v| v.as_u64()).unwrap_or(default);
        let limits = Limits {
            max_operations: lim("max_operations", d.max_operations),
            // A recording from before the step budget ran without one.
            max_step_operations: lim("max_step_operations", 0),
            max_call_levels: lim("max_call_levels", d.max_call_levels as u64) as usize,
            max_string_size: lim("max_string_size", d.max_string_size as u64) as usize,
            max_array_size: lim("max_array_size", d.max_array_size as u64) as usize,
            max_map_size: lim("max_map_size", d.max_map_size as u64) as usize,
            max_spawns_per_step: lim("max_spawns_per_step", d.max_spawns_per_step),
        };
        let list = |k: &str| -> Result<Vec<String>, String> {
            match opt(k) {
                None => Ok(Vec::new()),
                Some(v) => serde_json::from_str(v)
                    .map_err(|e| format!("metadata key '{k}' is not a JSON list: {e}")),
            }
        };
        Ok(RunMeta {
            version: get("critterbox_version")?.to_string(),
            scene: get("scene")?.to_string(),
            source,
            seed: parse("seed", get("seed")?)?,
            seed_override: opt("seed_override")
                .map(|v| parse("seed_override", v))
                .transpose()?,
            dt: parse("dt", get("dt")?)?,
            dt_override: opt("dt_override")
                .map(|v| parse("dt_override", v))
                .transpose()?,
            steps: parse("steps", get("steps")?)?,
            method: get("method")?.to_string(),
            dim: parse("dim", get("dim")?)?,
            border: get("border")?.to_string(),
            n: opt("n").map(|v| parse("n", v)).transpose()?,
            sets: list("sets")?,
            limits,
            command_line: list("command_line")?,
            record_every: parse("record_every", get("record_every")?)?,
            critters: parse("critters", get("critters")?)?,
            created: opt("created").unwrap_or_default().to_string(),
        })
    }
}

/// How a run ended.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EndMeta {
    /// Steps taken.
    pub steps: u64,
    /// `completed`, `stopped` (by the scene), `interrupted` (by a signal), `error` (in a step),
    /// `setup_failed` ([`SETUP_FAILED`]: the scene could not be built), or `aborted`.
    pub outcome: String,
    /// The scene's reason, the error, or the signal that interrupted the run (`SIGTERM`).
    pub reason: String,
    /// The final state hash.
    pub hash: u64,
    /// The script profile (calls and time per kind and hook), when the run was profiled.
    pub profile: Vec<ProfileRow>,
}

impl EndMeta {
    /// As an MCAP metadata map.
    pub fn to_map(&self) -> BTreeMap<String, String> {
        let mut m = BTreeMap::from([
            ("steps".to_string(), self.steps.to_string()),
            ("outcome".to_string(), self.outcome.clone()),
            ("reason".to_string(), self.reason.clone()),
            ("hash".to_string(), format!("{:016x}", self.hash)),
        ]);
        if !self.profile.is_empty() {
            if let Ok(json) = serde_json::to_string(&self.profile) {
                m.insert("profile".to_string(), json);
            }
        }
        m
    }

    /// From an MCAP metadata map.
    pub fn from_map(m: &BTreeMap<String, String>) -> EndMeta {
        let get = |k: &str| m.get(k).cloned().unwrap_or_default();
        EndMeta {
            steps: get("steps").parse().unwrap_or(0),
            outcome: get("outcome"),
            reason: get("reason"),
            hash: u64::from_str_radix(&get("hash"), 16).unwrap_or(0),
            profile: m
                .get("profile")
                .and_then(|p| serde_json::from_str(p).ok())
                .unwrap_or_default(),
        }
    }
}

/// The current UTC time as `YYYYMMDD-HHMMSS` (for file names) and as ISO 8601.
pub fn utc_now() -> (String, String) {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rem) = ((secs / 86_400) as i64, secs % 86_400);
    let (h, mi, s) = (rem / 3600, rem % 3600 / 60, rem % 60);
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    (
        format!("{y:04}{m:02}{d:02}-{h:02}{mi:02}{s:02}"),
        format!("{y:04}-{m:02}-{d:02}T{h:02}:{mi:02}:{s:02}Z"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_meta_round_trips_through_the_map() {
        let meta = RunMeta {
            version: "0.1.0".into(),
            scene: "billiards".into(),
            source: SceneSource::Script {
                file: "scripts/scenes/billiards.rhai".into(),
            },
            seed: 7,
            seed_override: Some(7),
            dt: 1.0 / 120.0,
            dt_override: None,
            steps: 900,
            method: "discrete".into(),
            dim: 2,
            border: "bounce".into(),
            n: None,
            sets: vec!["SPEED=20".into()],
            limits: Limits::default(),
            command_line: vec!["critterbox".into(), "run".into()],
            record_every: 1,
            critters: 20,
            created: "2024-01-01T00:00:00Z".into(),
        };
        let back = RunMeta::from_map(&meta.to_map()).expect("parses");
        assert_eq!(back, meta);
        assert_eq!(back.dt.to_bits(), (1.0f64 / 120.0).to_bits());
    }

    #[test]
    fn utc_now_is_a_plausible_date() {
        let (file, iso) = utc_now();
        assert_eq!(file.len(), 15);
        assert!(iso.starts_with("20"), "{iso}");
    }
}
