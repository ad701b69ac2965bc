//! The results table: one row per finished run, in the sweep's order; the parameters first,
//! then the outcome and the figures. Written as CSV.

use super::{RunResult, SweepFile};
use serde_json::Value;
use std::collections::BTreeSet;

/// The figures every row may carry, in column order (`alive.KIND` and `vars.NAME` follow).
pub const FIGURES: [&str; 11] = [
    "steps_done",
    "time",
    "collisions",
    "impacts",
    "energy_start",
    "energy_end",
    "energy_change",
    "momentum_change",
    "state_hash",
    "wall_s",
    "reason",
];

/// Columns and rows of text (empty where a run has no value).
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// Column names.
    pub columns: Vec<String>,
    /// One row per run, as many cells as columns.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// The table of `results`: `(k, result)` with k the run's place in the sweep's list.
    pub fn assemble(file: &SweepFile, results: &[(usize, RunResult)]) -> Table {
        let sets = file.set_names();
        let mut alive = BTreeSet::new();
        let mut vars = BTreeSet::new();
        for (_, r) in results {
            if let Some(s) = &r.summary {
                alive.extend(s.alive.keys().map(|k| format!("alive.{k}")));
                vars.extend(s.vars.keys().map(|k| format!("vars.{k}")));
            }
        }
        let params = ["run", "hash", "scene", "method", "dt", "n", "steps", "seed"];
        let figures: Vec<String> = FIGURES
            .iter()
            .map(|s| s.to_string())
            .chain(alive)
            .chain(vars)
            .filter(|c| {
                file.collect.as_ref().is_none_or(|keep| {
                    keep.iter().any(|k| {
                        k == c
                            || c.strip_prefix(k.as_str())
                                .is_some_and(|r| r.starts_with('.'))
                    })
                })
            })
            .collect();
        let mut columns: Vec<String> = params.iter().map(|s| s.to_string()).collect();
        columns.extend(sets.iter().map(|s| format!("set.{s}")));
        columns.extend(["outcome".to_string(), "error".to_string()]);
        columns.extend(figures.iter().cloned());
        let opt = |v: Option<String>| v.unwrap_or_default();
        let rows = results
            .iter()
            .map(|(k, r)| {
                let p = &r.params;
                let mut row = vec![
                    k.to_string(),
                    r.hash.clone(),
                    p.scene.clone(),
                    opt(p.method.clone()),
                    opt(p.dt.map(num)),
                    opt(p.n.map(|v| v.to_string())),
                    opt(p.steps.map(|v| v.to_string())),
                    opt(p.seed.map(|v| v.to_string())),
                ];
                for name in &sets {
                    row.push(opt(p
                        .sets
                        .iter()
                        .find(|(k, _)| k == name)
                        .map(|(_, v)| v.clone())));
                }
                let outcome = match (&r.error, &r.summary) {
                    (Some(_), _) => "error".to_string(),
                    (None, Some(s)) => s.outcome.clone(),
                    (None, None) => String::new(),
                };
                row.push(outcome);
                // One line per row, for line-based tools; the result file keeps the full text.
                row.push(opt(r.error.as_ref().map(|e| {
                    e.lines()
                        .map(str::trim)
                        .filter(|l| !l.is_empty())
                        .collect::<Vec<_>>()
                        .join(" / ")
                })));
                for c in &figures {
                    row.push(r.summary.as_ref().map_or(String::new(), |s| figure(s, c)));
                }
                row
            })
            .collect();
        Table { columns, rows }
    }

    /// The column's index.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// The table as CSV (RFC 4180: a header line, cells quoted when they hold `,`, `"` or a
    /// line break).
    pub fn to_csv(&self) -> String {
        let line = |cells: &[String]| {
            let quoted: Vec<String> = cells.iter().map(|c| csv_cell(c)).collect();
            quoted.join(",") + "\n"
        };
        let mut s = line(&self.columns);
        for row in &self.rows {
            s.push_str(&line(row));
        }
        s
    }
}

/// A number in its shortest exact form, with an exponent when very large or small.
fn num(v: f64) -> String {
    ryu::Buffer::new().format(v).to_string()
}

fn csv_cell(c: &str) -> String {
    if c.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", c.replace('"', "\"\""))
    } else {
        c.to_string()
    }
}

/// One figure of a summary as text: numbers in their shortest exact form.
fn figure(s: &super::RunSummary, column: &str) -> String {
    if let Some(kind) = column.strip_prefix("alive.") {
        return s.alive.get(kind).map_or("0".into(), |n| n.to_string());
    }
    if let Some(name) = column.strip_prefix("vars.") {
        return match s.vars.get(name) {
            None | Some(Value::Null) => String::new(),
            Some(Value::String(t)) => t.clone(),
            Some(v) => v.to_string(),
        };
    }
    match column {
        "steps_done" => s.steps.to_string(),
        "time" => num(s.time),
        "collisions" => s.collisions.to_string(),
        "impacts" => s.impacts.to_string(),
        "energy_start" => num(s.energy_start),
        "energy_end" => num(s.energy_end),
        "energy_change" => num(s.energy_change),
        "momentum_change" => num(s.momentum_change),
        "state_hash" => s.state_hash.clone(),
        "wall_s" => num(s.wall_s),
        "reason" => s.reason.clone(),
        _ => String::new(),
    }
}
