//! `critterbox diff A B`: what two recordings recorded, compared message by message: the first
//! step, critter and field that differ, with both values.

use clap::Args;
use critterbox::recording::compare::first_difference;
use critterbox::recording::diff::diff;
use critterbox::recording::reader::state_at;
use critterbox::recording::replay::state_at_step;
use critterbox::recording::Recording;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `critterbox diff`.
#[derive(Args, Debug)]
#[command(
    after_help = "Exit codes: 0 the recordings agree on everything both recorded; 1 they \
    differ (or an error); 2 bad arguments; 3 one of them is damaged or cut off and nothing both \
    hold differs (steps only one file kept are not compared)."
)]
pub struct DiffArgs {
    /// The first recording.
    pub a: PathBuf,
    /// The second recording.
    pub b: PathBuf,
}

/// How the library starts the line of a full state that differs.
const STATE_PREFIX: &str = "full state: ";

/// Metadata keys that differ between runs of the same scene without changing it.
const INCIDENTAL: [&str; 3] = ["created", "command_line", "record_every"];

/// Runs the command: metadata, scripts, then every step's hash, totals, events and (where both
/// have one) full state. Exits 0 when all agree, 1 when something differs (after printing the
/// first step that does), 3 when a file is damaged and nothing else differs.
pub fn run(args: &DiffArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let a = Recording::open(&args.a)?;
    let b = Recording::open(&args.b)?;
    let mut differs = false;
    let keys: std::collections::BTreeSet<&String> =
        a.meta_map.keys().chain(b.meta_map.keys()).collect();
    for k in keys {
        let (x, y) = (a.meta_map.get(k), b.meta_map.get(k));
        if x != y && !INCIDENTAL.contains(&k.as_str()) {
            let show = |v: Option<&String>| v.map_or("(none)".to_string(), |v| v.clone());
            writeln!(out, "metadata     {k}: {} | {}", show(x), show(y))?;
            differs = true;
        }
    }
    let report = diff(&a, &b)?;
    for s in &report.scripts {
        writeln!(out, "{s}")?;
        differs = true;
    }
    match &report.first {
        None => {
            let unchecked = match report.unchecked {
                0 => String::new(),
                n => format!(" ({n} steps only one file kept were not compared)"),
            };
            writeln!(
                out,
                "same         {} steps, every state hash equal, and every total, event, log line \
                 and full state both recorded{unchecked}",
                report.steps
            )?;
        }
        Some((step, what)) => {
            differs = true;
            let step = *step;
            // A full state's difference names the critter: it gets the line the hash's would.
            let (critter, rest): (Vec<&String>, Vec<&String>) =
                what.iter().partition(|w| w.starts_with(STATE_PREFIX));
            let head = rest.first().map_or("full state", |w| w.as_str());
            writeln!(out, "first differs at step {step}: {head}")?;
            for w in rest.iter().skip(1) {
                writeln!(out, "             {w}")?;
            }
            for c in critter {
                let c = c.trim_start_matches(STATE_PREFIX);
                writeln!(out, "first critter (step {step}): {c}")?;
            }
            if report.hash_differs && !report.states_compared {
                match critter_at(&a, &b, step) {
                    Ok(Some(d)) => writeln!(out, "first critter {d}")?,
                    Ok(None) => writeln!(
                        out,
                        "the critters are equal; the difference is in the step count, dt or the random generator"
                    )?,
                    Err(e) => writeln!(out, "no critter named: {e:#}")?,
                }
            }
        }
    }
    if differs {
        for r in [&a, &b] {
            super::replay::warn_damage(r);
        }
        let at = report
            .first
            .as_ref()
            .map_or("in their scripts or metadata".to_string(), |(s, _)| {
                format!("from step {s}")
            });
        anyhow::bail!("{} and {} differ {at}", args.a.display(), args.b.display())
    }
    super::replay::damage_outcome(&a)?;
    super::replay::damage_outcome(&b)
}

/// The first critter that differs at `step`: from the recorded states when both have one, else
/// from the two runs re-simulated to that step.
fn critter_at(a: &Recording, b: &Recording, step: u64) -> anyhow::Result<Option<String>> {
    let (sa, sb) = match (state_at(&a.path, step)?, state_at(&b.path, step)?) {
        (Some(x), Some(y)) => (x, y),
        _ => (state_at_step(a, step)?.0, state_at_step(b, step)?.0),
    };
    Ok(first_difference(&sa, &sb, "A", "B").map(|d| format!("(step {step}): {d}")))
}
