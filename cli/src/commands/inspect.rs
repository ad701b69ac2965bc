//! `critterbox inspect FILE`: what a recording holds: scene, steps, critters by kind, collisions,
//! deaths, and energy and momentum over time as a table (`--plot` draws them). With `--critter
//! ID`, one critter's story instead (`critterbox::recording::story`), as text or `--json`.

use super::replay::{damage_outcome, sample, summary_head};
use crate::plot;
use clap::Args;
use critterbox::recording::story::story;
use critterbox::recording::Recording;
use critterbox::CritterId;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `critterbox inspect`.
#[derive(Args, Debug)]
#[command(after_help = super::replay::EXIT_CODES)]
pub struct InspectArgs {
    /// The recording (.mcap).
    pub file: PathBuf,
    /// Also draw energy, momentum and collisions over time to OUT (.svg or .png).
    #[arg(long, value_name = "OUT")]
    pub plot: Option<PathBuf>,
    /// Rows of the table over time.
    #[arg(long, default_value_t = 20)]
    pub rows: usize,
    /// Tell one critter's story instead: its spawn, kind reloads, touching spells and impacts,
    /// damage, changes of props and colour, and death with its cause. ID as ids print:
    /// `#20v5`, `20v5`, or `20` for generation 0.
    #[arg(long, value_name = "ID", value_parser = critter_id)]
    pub critter: Option<CritterId>,
    /// With --critter: the story as one JSON document.
    #[arg(long, requires = "critter")]
    pub json: bool,
}

/// Parses a critter id as critterbox prints them.
fn critter_id(text: &str) -> Result<CritterId, String> {
    text.parse()
        .map_err(|e: critterbox::ParseCritterIdError| e.to_string())
}

/// `--critter ID`: the critter's story, as text or JSON.
fn critter_story(
    rec: &Recording,
    who: CritterId,
    json: bool,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let story = story(rec, who)?;
    if json {
        writeln!(out, "{}", serde_json::to_string_pretty(&story)?)?;
        return damage_outcome(rec);
    }
    let kind = story.kind.as_deref().unwrap_or("?");
    writeln!(
        out,
        "critter      {} ({kind}) in {}",
        story.critter,
        rec.path.display()
    )?;
    if story.format < 2 {
        writeln!(
            out,
            "note         a format {} recording: it names no causes of spawns, damage and deaths",
            story.format
        )?;
    }
    let life = match (&story.spawn, &story.death) {
        (Some(s), Some(d)) => format!("steps {} to {}", s.step(), d.step()),
        (Some(s), None) => format!(
            "step {} to the end of the file (step {})",
            s.step(),
            story.last_step
        ),
        (None, Some(d)) => format!("until step {}", d.step()),
        (None, None) => "not seen spawned or dying".to_string(),
    };
    writeln!(out, "lived        {life}")?;
    writeln!(out, "timeline")?;
    for e in &story.timeline {
        writeln!(out, "  step {:>8}  {}", e.step(), e.text())?;
    }
    damage_outcome(rec)
}

/// Runs the command.
pub fn run(args: &InspectArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let rec = Recording::open(&args.file)?;
    if let Some(who) = args.critter {
        return critter_story(&rec, who, args.json, out);
    }
    summary_head(&rec, out)?;
    let (first, last) = (rec.totals.first(), rec.totals.last());
    let kinds = |c: Option<(&u64, &std::collections::BTreeMap<String, u64>)>| {
        c.map_or("-".to_string(), |(step, c)| {
            let list: Vec<String> = c.iter().map(|(k, n)| format!("{k} {n}")).collect();
            format!("{} (step {step})", list.join(", "))
        })
    };
    let counts = &rec.kind_counts;
    writeln!(
        out,
        "critters     at start: {}",
        kinds(counts.iter().next())
    )?;
    writeln!(
        out,
        "             at end:   {}",
        kinds(counts.iter().next_back())
    )?;
    let collisions: u64 = rec.totals.iter().map(|t| t.collisions).sum();
    let impacts: u64 = rec.totals.iter().map(|t| t.impacts).sum();
    let spawns: usize = rec.lifecycle.iter().map(|l| l.spawn.len()).sum();
    let deaths: usize = rec.lifecycle.iter().map(|l| l.die.len()).sum();
    let damages: usize = rec.lifecycle.iter().map(|l| l.damage_id.len()).sum();
    let lines: usize = rec.log.iter().map(|l| l.lines.len()).sum();
    writeln!(
        out,
        "collisions   {collisions} handled, {impacts} impacts, {} collision events",
        rec.collisions.values().sum::<usize>()
    )?;
    writeln!(
        out,
        "lifecycle    {spawns} spawns, {deaths} deaths, {damages} damage events"
    )?;
    writeln!(out, "log          {lines} lines")?;
    if rec.reloads.is_empty() {
        writeln!(out, "reloads      none")?;
    }
    for (i, r) in rec.reloads.iter().enumerate() {
        writeln!(
            out,
            "{}after step {}: {} ({}), text in attachment '{}'",
            if i == 0 {
                "reloads      "
            } else {
                "             "
            },
            r.step,
            r.file,
            r.kinds.join(", "),
            r.attachment
        )?;
    }
    let channels: Vec<String> = rec
        .messages
        .iter()
        .map(|(t, n)| format!("{t} {n}"))
        .collect();
    writeln!(out, "messages     {}", channels.join(", "))?;
    if let (Some(a), Some(b)) = (first, last) {
        let (e0, e1) = (a.kinetic_energy.0, b.kinetic_energy.0);
        let drift = if e0 != 0.0 { (e1 - e0) / e0 } else { 0.0 };
        writeln!(
            out,
            "energy       {e1:.9e} at the end (start {e0:.9e}, relative change {drift:+.3e})"
        )?;
    }

    // Over time: each row sums the events since the previous row.
    let dim = rec.meta().dim;
    writeln!(out, "over time")?;
    let mut head = format!(
        "  {:>8} {:>10} {:>8} {:>10} {:>8} {:>7} {:>17}",
        "step", "time", "critters", "collisions", "impacts", "deaths", "kinetic energy"
    );
    for axis in ["px", "py", "pz"].iter().take(dim) {
        head.push_str(&format!(" {axis:>13}"));
    }
    writeln!(out, "{head}")?;
    let mut prev = 0u64;
    let mut deaths_by_step = std::collections::BTreeMap::new();
    for l in &rec.lifecycle {
        *deaths_by_step.entry(l.step).or_insert(0usize) += l.die.len();
    }
    for t in sample(&rec.totals, args.rows) {
        let range = |lo: u64, hi: u64| {
            rec.totals
                .iter()
                .filter(move |x| x.step > lo && x.step <= hi)
        };
        let (lo, hi) = (if t.step == 0 { 0 } else { prev }, t.step);
        let coll: u64 = range(lo, hi).map(|x| x.collisions).sum();
        let imp: u64 = range(lo, hi).map(|x| x.impacts).sum();
        // Deaths in steps lo+1..=hi (none for the first row, where lo == hi).
        let died: usize = if hi > lo {
            deaths_by_step.range(lo + 1..=hi).map(|(_, n)| n).sum()
        } else {
            0
        };
        let mut line = format!(
            "  {:>8} {:>10.4} {:>8} {:>10} {:>8} {:>7} {:>17.9e}",
            t.step, t.time.0, t.critters, coll, imp, died, t.kinetic_energy.0
        );
        for p in &t.momentum.0 {
            line.push_str(&format!(" {p:>13.5e}"));
        }
        writeln!(out, "{line}")?;
        prev = t.step;
    }
    if let Some(path) = &args.plot {
        plot::totals_chart(&rec, path)?;
        writeln!(out, "plot         {}", path.display())?;
    }
    damage_outcome(&rec)
}
