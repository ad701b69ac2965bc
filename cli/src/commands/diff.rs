//! `critterbox diff A B`: the first step and critter where two recordings differ.

use clap::Args;
use critterbox::recording::compare::first_difference;
use critterbox::recording::reader::state_at;
use critterbox::recording::replay::state_at_step;
use critterbox::recording::Recording;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `critterbox diff`.
#[derive(Args, Debug)]
pub struct DiffArgs {
    /// The first recording.
    pub a: PathBuf,
    /// The second recording.
    pub b: PathBuf,
}

/// Metadata keys that differ between runs of the same scene without changing it.
const INCIDENTAL: [&str; 3] = ["created", "command_line", "record_every"];

/// Runs the command: exit 0 when the recordings agree on every step's hash, non-zero when they
/// differ (after printing where).
pub fn run(args: &DiffArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let a = Recording::open(&args.a)?;
    let b = Recording::open(&args.b)?;
    let keys: std::collections::BTreeSet<&String> =
        a.meta_map.keys().chain(b.meta_map.keys()).collect();
    for k in keys {
        let (x, y) = (a.meta_map.get(k), b.meta_map.get(k));
        if x != y && !INCIDENTAL.contains(&k.as_str()) {
            let show = |v: Option<&String>| v.map_or("(none)".to_string(), |v| v.clone());
            writeln!(out, "metadata     {k}: {} | {}", show(x), show(y))?;
        }
    }
    let (la, lb) = (a.last_step(), b.last_step());
    let first = (0..=la.max(lb)).find(|s| a.hashes.get(s) != b.hashes.get(s));
    let Some(step) = first else {
        writeln!(out, "same         {} steps, every state hash equal", la + 1)?;
        return Ok(());
    };
    let (ha, hb) = (a.hashes.get(&step), b.hashes.get(&step));
    let hex = |h: Option<&u64>| h.map_or("(no step)".to_string(), |h| format!("{h:016x}"));
    writeln!(
        out,
        "first differs at step {step}: state hash {} | {}",
        hex(ha),
        hex(hb)
    )?;
    if ha.is_some() && hb.is_some() {
        match critter_at(&a, &b, step) {
            Ok(Some(d)) => writeln!(out, "first critter {d}")?,
            Ok(None) => writeln!(
                out,
                "the critters are equal; the difference is in the step count, dt or the random generator"
            )?,
            Err(e) => writeln!(out, "no critter named: {e:#}")?,
        }
    } else {
        writeln!(
            out,
            "one recording ends at step {}, the other at step {}",
            la, lb
        )?;
    }
    anyhow::bail!(
        "{} and {} differ from step {step}",
        args.a.display(),
        args.b.display()
    )
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
