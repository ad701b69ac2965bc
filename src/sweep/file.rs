//! The sweep file (TOML): the scene, the values every run fixes, the axes that vary, and what
//! the table keeps. `docs/sweeps.md` documents every key.

use super::SweepError;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The file as written; unknown keys are errors (a misspelt axis must not be ignored).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    scene: String,
    seed: Option<u64>,
    method: Option<String>,
    dt: Option<f64>,
    n: Option<usize>,
    steps: Option<u64>,
    #[serde(default)]
    set: BTreeMap<String, toml::Value>,
    record: Option<bool>,
    collect: Option<Vec<String>>,
    #[serde(default)]
    axes: RawAxes,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAxes {
    seed: Option<SeedAxis>,
    method: Option<Vec<String>>,
    dt: Option<Vec<f64>>,
    n: Option<Vec<usize>>,
    steps: Option<Vec<u64>>,
    #[serde(default)]
    set: BTreeMap<String, Vec<toml::Value>>,
}

/// Seeds as a list, or an inclusive range `{ from = 1, to = 8 }`.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum SeedAxis {
    List(Vec<u64>),
    Range { from: u64, to: u64 },
}

/// A parsed, checked sweep file.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepFile {
    /// Where it was read from.
    pub path: PathBuf,
    /// The scene as written: a built-in's name, or a script's path (ends in `.rhai`) relative
    /// to the sweep file's folder.
    pub scene: String,
    /// Values every run fixes (`None`: the scene's own).
    pub seed: Option<u64>,
    /// See [`SweepFile::seed`].
    pub method: Option<String>,
    /// See [`SweepFile::seed`].
    pub dt: Option<f64>,
    /// See [`SweepFile::seed`].
    pub n: Option<usize>,
    /// See [`SweepFile::seed`].
    pub steps: Option<u64>,
    /// Scene constants every run sets, by name, as `--set` text.
    pub sets: BTreeMap<String, String>,
    /// Whether each run writes its recording (default true).
    pub record: bool,
    /// The figure columns the table keeps (`None`: all).
    pub collect: Option<Vec<String>>,
    /// The axes, each a list of values; empty when the sweep does not vary it.
    pub axes: Axes,
}

/// The values each axis takes, in the file's order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Axes {
    /// Seeds.
    pub seed: Vec<u64>,
    /// Methods.
    pub method: Vec<String>,
    /// Time steps.
    pub dt: Vec<f64>,
    /// Critter counts.
    pub n: Vec<usize>,
    /// Step counts.
    pub steps: Vec<u64>,
    /// Scene constants, by name, as `--set` text.
    pub sets: BTreeMap<String, Vec<String>>,
}

impl SweepFile {
    /// Reads and checks a sweep file.
    pub fn read(path: &Path) -> Result<SweepFile, SweepError> {
        let text = std::fs::read_to_string(path).map_err(|source| SweepError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        SweepFile::parse(path, &text)
    }

    /// Parses and checks the text of a sweep file read from `path`.
    pub fn parse(path: &Path, text: &str) -> Result<SweepFile, SweepError> {
        let raw: Raw = toml::from_str(text).map_err(|e| SweepError::Parse {
            path: path.to_path_buf(),
            message: e.to_string().trim_end().to_string(),
        })?;
        let invalid = |key: &str, reason: String| SweepError::Invalid {
            path: path.to_path_buf(),
            key: key.to_string(),
            reason,
        };
        let sets = raw
            .set
            .iter()
            .map(|(k, v)| {
                Ok((
                    k.clone(),
                    set_text(v).map_err(|r| invalid(&format!("set.{k}"), r))?,
                ))
            })
            .collect::<Result<BTreeMap<_, _>, SweepError>>()?;
        let mut axis_sets = BTreeMap::new();
        for (k, values) in &raw.axes.set {
            let key = format!("axes.set.{k}");
            if sets.contains_key(k) {
                return Err(invalid(
                    &key,
                    format!("set.{k} fixes it already; keep one of the two"),
                ));
            }
            let texts = values
                .iter()
                .map(set_text)
                .collect::<Result<Vec<_>, _>>()
                .map_err(|r| invalid(&key, r))?;
            axis_sets.insert(k.clone(), texts);
        }
        for (key, empty) in [
            (
                "method",
                raw.axes.method.as_ref().is_some_and(Vec::is_empty),
            ),
            ("dt", raw.axes.dt.as_ref().is_some_and(Vec::is_empty)),
            ("n", raw.axes.n.as_ref().is_some_and(Vec::is_empty)),
            ("steps", raw.axes.steps.as_ref().is_some_and(Vec::is_empty)),
            (
                "seed",
                matches!(&raw.axes.seed, Some(SeedAxis::List(v)) if v.is_empty()),
            ),
        ] {
            if empty {
                return Err(invalid(
                    &format!("axes.{key}"),
                    "an axis needs at least one value (or leave it out)".into(),
                ));
            }
        }
        let seed = match raw.axes.seed {
            None => Vec::new(),
            Some(SeedAxis::List(v)) => v,
            Some(SeedAxis::Range { from, to }) => {
                if from > to {
                    return Err(invalid(
                        "axes.seed",
                        format!("from = {from} is after to = {to} (the range includes both ends)"),
                    ));
                }
                (from..=to).collect()
            }
        };
        let axes = Axes {
            seed,
            method: raw.axes.method.unwrap_or_default(),
            dt: raw.axes.dt.unwrap_or_default(),
            n: raw.axes.n.unwrap_or_default(),
            steps: raw.axes.steps.unwrap_or_default(),
            sets: axis_sets,
        };
        let file = SweepFile {
            path: path.to_path_buf(),
            scene: raw.scene,
            seed: raw.seed,
            method: raw.method,
            dt: raw.dt,
            n: raw.n,
            steps: raw.steps,
            sets,
            record: raw.record.unwrap_or(true),
            collect: raw.collect,
            axes,
        };
        file.check()
            .map_err(|(key, reason)| invalid(&key, reason))?;
        Ok(file)
    }

    /// True when the scene is a script rather than a built-in.
    pub fn is_script(&self) -> bool {
        self.scene.ends_with(".rhai")
    }

    /// What `critterbox run` is given as its scene: a script's path from the sweep file's
    /// folder, or the built-in's name.
    pub fn scene_arg(&self) -> String {
        if !self.is_script() || Path::new(&self.scene).is_absolute() {
            return self.scene.clone();
        }
        let dir = self.path.parent().unwrap_or(Path::new(""));
        dir.join(&self.scene).to_string_lossy().into_owned()
    }

    /// The names of the constants set, fixed or varied, sorted.
    pub fn set_names(&self) -> Vec<String> {
        let mut names: Vec<String> = self
            .sets
            .keys()
            .chain(self.axes.sets.keys())
            .cloned()
            .collect();
        names.sort();
        names
    }

    fn check(&self) -> Result<(), (String, String)> {
        let a = &self.axes;
        for (key, fixed, varied) in [
            ("seed", self.seed.is_some(), !a.seed.is_empty()),
            ("method", self.method.is_some(), !a.method.is_empty()),
            ("dt", self.dt.is_some(), !a.dt.is_empty()),
            ("n", self.n.is_some(), !a.n.is_empty()),
            ("steps", self.steps.is_some(), !a.steps.is_empty()),
        ] {
            if fixed && varied {
                return Err((
                    format!("axes.{key}"),
                    format!("{key} is fixed at the top of the file too; keep one of the two"),
                ));
            }
        }
        for (name, values) in &a.sets {
            if values.is_empty() {
                return Err((
                    format!("axes.set.{name}"),
                    "an axis needs at least one value".into(),
                ));
            }
        }
        if self.is_script() && (self.n.is_some() || !a.n.is_empty()) {
            return Err((
                "n".into(),
                "n works on built-in scenes; a scene script sets its own counts (vary a constant with [axes.set])".into(),
            ));
        }
        let sets_any = !self.sets.is_empty() || !a.sets.is_empty();
        if !self.is_script() && sets_any {
            return Err((
                "set".into(),
                format!("constants are set on scene scripts; '{}' is a built-in scene (vary n, dt, seed or method)", self.scene),
            ));
        }
        for m in self.method.iter().chain(&a.method) {
            m.parse::<crate::method::Method>()
                .map_err(|e| ("method".to_string(), format!("'{m}': {e}")))?;
        }
        for &dt in self.dt.iter().chain(&a.dt) {
            if !(dt.is_finite() && dt > 0.0) {
                return Err((
                    "dt".into(),
                    format!("{dt}: a time step must be a finite number above zero"),
                ));
            }
        }
        Ok(())
    }
}

/// A TOML value as the text `--set NAME=VALUE` takes: numbers and booleans as written (floats
/// keep their point), strings as they are (the scene quotes text that is not a number).
fn set_text(v: &toml::Value) -> Result<String, String> {
    match v {
        toml::Value::String(s) => Ok(s.clone()),
        toml::Value::Integer(i) => Ok(i.to_string()),
        toml::Value::Float(f) => Ok(super::params::fmt_f64(*f)),
        toml::Value::Boolean(b) => Ok(b.to_string()),
        other => Err(format!(
            "{} is not a constant's value; write a number, a boolean or a string",
            other.type_str()
        )),
    }
}
