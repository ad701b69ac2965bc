//! `critterbox replay FILE`: a recording played back headless: a summary and per-step totals,
//! the exact state of any step (`--step N`), or a check that re-simulating from the file alone
//! gives every recorded step bit for bit (`--verify`); with `--rerun`, `--rerun-connect` or
//! `--rerun-save`, the run is re-simulated from the file and sent to the Rerun viewer step by
//! step, each step's hash checked against the recording on the way.

use clap::Args;
use critterbox::recording::replay::{state_at_step, Replay, StateSource};
use critterbox::recording::schema::{id_of, StateMsg};
use critterbox::recording::story::prop_text;
use critterbox::recording::verify::verify;
use critterbox::recording::{Recording, SceneSource};
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// The exit codes of the commands that read recordings (`--help`).
pub const EXIT_CODES: &str = "Exit codes: 0 ok; 1 an error, or a difference (a replay that \
    departs from its recording, two recordings that differ); 2 bad arguments; 3 the recording is \
    damaged or cut off: a damaged chunk is skipped and the rest used, the missing steps are \
    named on stderr.";

/// Arguments of `critterbox replay`.
#[derive(Args, Debug)]
#[command(after_help = EXIT_CODES)]
pub struct ReplayArgs {
    /// The recording (.mcap).
    pub file: PathBuf,
    /// Re-simulate from the recording alone and check every step's hash, totals and events and
    /// every full state; exit non-zero at the first difference.
    #[arg(long)]
    pub verify: bool,
    /// Print the exact state after step N (re-simulated when it was not recorded), with each
    /// critter's own colour and properties.
    #[arg(long, value_name = "N")]
    pub step: Option<u64>,
    /// With --step: print the state as the recording's JSON state message.
    #[arg(long, requires = "step")]
    pub json: bool,
    /// Rows of the per-step totals table.
    #[arg(long, default_value_t = 12)]
    pub rows: usize,
    /// Watching the recorded run (re-simulated from the file; every step's hash is checked).
    #[command(flatten)]
    pub view: super::view::ViewArgs,
}

/// Runs the command.
pub fn run(args: &ReplayArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let rec = Recording::open(&args.file)?;
    if let Some(step) = args.step {
        let (state, source) = state_at_step(&rec, step)?;
        if args.json {
            writeln!(out, "{}", serde_json::to_string(&state)?)?;
        } else {
            let how = match source {
                StateSource::Recorded => "recorded".to_string(),
                StateSource::Restored { keyframe } => format!(
                    "re-simulated from the recorded full state at step {keyframe}; every hash \
                     matched"
                ),
                StateSource::Resimulated {
                    keyframe,
                    why_not_restored,
                } => format!(
                    "re-simulated from step 0; every hash matched{}{}",
                    keyframe.map_or(String::new(), |k| format!(
                        ", and the full state at step {k}"
                    )),
                    why_not_restored
                        .map_or(String::new(), |w| format!(" (not started from it: {w})"))
                ),
            };
            writeln!(out, "step {step} (t = {}): {how}", state.time.0)?;
            print_state(out, &state)?;
        }
        return damage_outcome(&rec);
    }
    summary(&rec, out, args.rows)?;
    if args.view.wanted() {
        to_viewer(&rec, &args.view, out)?;
    }
    if args.verify {
        let report = verify(&rec, |_| {})?;
        if let Some(m) = &report.mismatch {
            writeln!(out, "verify       MISMATCH at step {}: {}", m.step, m.what)?;
            match &m.critter {
                Some((at, c)) => writeln!(out, "first critter that differs (step {at}): {c}")?,
                None => writeln!(out, "no recorded full state after it to name a critter")?,
            }
            warn_damage(&rec);
            anyhow::bail!(
                "{}: the replay differs from the recording at step {}",
                args.file.display(),
                m.step
            );
        }
        let checked = format!(
            "{} steps re-simulated from the recording alone; {} hashes, {} full states and {} event messages identical{}",
            report.steps,
            report.hashes,
            report.states,
            report.events,
            report
                .error_reproduced
                .map_or(String::new(), |s| format!("; the error in step {s} reproduced"))
        );
        if rec.is_damaged() {
            // Steps missing from the file were re-simulated but not checked against it.
            let mut unchecked = Vec::new();
            if rec.missing_steps() > 0 {
                unchecked.push(format!(
                    "{} steps missing from the file could not be checked",
                    rec.missing_steps()
                ));
            } else if !rec.gaps.is_empty() {
                unchecked.push("part of the file is damaged".to_string());
            }
            if rec.truncated.is_some() {
                unchecked.push(format!(
                    "the file is cut off after step {}, so the steps after it could not be checked",
                    rec.last_step()
                ));
            }
            writeln!(
                out,
                "verify       incomplete: {checked}; {}",
                unchecked.join("; ")
            )?;
        } else if report.hashes == 0 {
            anyhow::bail!(
                "{}: nothing to verify: the file holds no step hash",
                args.file.display()
            );
        } else {
            writeln!(out, "verify       ok: {checked}")?;
        }
    }
    damage_outcome(&rec)
}

/// Re-simulates the recorded run from the file and sends every step to the viewer. Stops at the
/// first step whose hash differs from the recording, so the viewer never shows a run that was
/// not the one recorded.
fn to_viewer(
    rec: &Recording,
    view: &super::view::ViewArgs,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let mut replay = Replay::new(rec)?;
    let mut viewer = super::view::Viewer::open(view, replay.world())?;
    let last = rec.last_step();
    let bar = super::run::progress_bar(last);
    let mut diverged: Option<(u64, u64, u64)> = None;
    let mut since = Instant::now();
    let reached = replay.step_to(last, |world| {
        let step = world.step_count();
        if let Some(&recorded) = rec.hashes.get(&step) {
            let got = world.state_hash();
            if got != recorded {
                diverged = Some((step, recorded, got));
                anyhow::bail!("diverged");
            }
        }
        viewer.step(world, since.elapsed());
        if step % 16 == 0 {
            bar.set_position(step);
        }
        since = Instant::now();
        Ok(())
    });
    bar.finish_and_clear();
    let shown = replay.step_count() - u64::from(diverged.is_some());
    let spent = viewer.finish();
    writeln!(
        out,
        "viewer       steps 0 to {shown} re-simulated from the recording and sent to Rerun{}",
        spent.map_or(String::new(), |(d, skipped)| format!(
            " ({:.3} s logging{})",
            d.as_secs_f64(),
            if skipped > 0 {
                format!("; {skipped} steps not shown: the viewer fell behind")
            } else {
                String::new()
            }
        ))
    )?;
    if let Some((step, recorded, got)) = diverged {
        anyhow::bail!(
            "{}: the replay departs from the recording at step {step} (hash {got:016x}, recorded \
             {recorded:016x}); the viewer shows steps 0 to {shown} only. `critterbox replay \
             --verify` names the first critter that differs",
            rec.path.display()
        );
    }
    if let Err(e) = reached {
        anyhow::bail!(
            "{}: the replay stopped at step {} of {last}: {e:#}",
            rec.path.display(),
            replay.step_count()
        );
    }
    Ok(())
}

/// Warns on stderr about each damaged stretch of the file and a cut-off end.
pub fn warn_damage(rec: &Recording) {
    for line in rec.damage_report() {
        eprintln!("warning: {line}");
    }
}

/// After a command's output: warnings on stderr and the damaged-data error (exit code 3) when
/// part of the file could not be read.
pub fn damage_outcome(rec: &Recording) -> anyhow::Result<()> {
    warn_damage(rec);
    match rec.damage_error() {
        Some(e) => Err(e.into()),
        None => Ok(()),
    }
}

fn fnum(x: f64) -> String {
    ryu::Buffer::new().format(x).to_string()
}

/// The header lines every recording command prints.
pub fn summary_head(rec: &Recording, out: &mut dyn Write) -> anyhow::Result<()> {
    let m = rec.meta();
    let bytes = std::fs::metadata(&rec.path).map_or(0, |x| x.len());
    writeln!(
        out,
        "recording    {} ({:.1} KiB)",
        rec.path.display(),
        bytes as f64 / 1024.0
    )?;
    let source = match &m.source {
        SceneSource::Builtin => format!(
            "built-in{}",
            m.n.map_or(String::new(), |n| format!(", n = {n}"))
        ),
        SceneSource::Script { file } => format!("script {file}"),
        SceneSource::Test { case } => format!("built by the test {case}"),
    };
    writeln!(
        out,
        "scene        {} ({source}; {}D, {} border)",
        m.scene, m.dim, m.border
    )?;
    writeln!(
        out,
        "recorded     by critterbox {} at {}: seed {}, dt {}, method {}",
        m.version,
        m.created,
        m.seed,
        fnum(m.dt),
        m.method
    )?;
    if !m.command_line.is_empty() {
        writeln!(out, "command      {}", m.command_line.join(" "))?;
    }
    let ended = match (&rec.end, &rec.error) {
        (Some(e), _) if e.outcome == critterbox::recording::SETUP_FAILED => {
            format!("failed during set-up: {}", e.reason)
        }
        (Some(e), _) if e.outcome == "interrupted" => format!("interrupted ({})", e.reason),
        (_, Some(e)) => format!("ended by an error in step {}: {}", e.step, e.message),
        (Some(e), _) if e.outcome == "stopped" => format!("stopped by the scene: {}", e.reason),
        (Some(e), _) => e.outcome.clone(),
        (None, _) => "no end record (the run did not finish writing)".into(),
    };
    let missing = match rec.missing_steps() {
        0 => String::new(),
        n => format!("; {n} of them missing from the file (damaged)"),
    };
    writeln!(
        out,
        "steps        {} of {} asked ({ended}){missing}",
        rec.last_step(),
        m.steps
    )?;
    writeln!(
        out,
        "full states  every {} step{} ({} in the file); hash, totals and events every step",
        m.record_every,
        if m.record_every == 1 { "" } else { "s" },
        rec.keyframes.len()
    )?;
    Ok(())
}

fn summary(rec: &Recording, out: &mut dyn Write, rows: usize) -> anyhow::Result<()> {
    summary_head(rec, out)?;
    let dim = rec.meta().dim;
    writeln!(out, "per-step totals")?;
    let mut head = format!(
        "  {:>8} {:>10} {:>8} {:>10} {:>22}",
        "step", "time", "critters", "collisions", "kinetic energy"
    );
    for axis in ["px", "py", "pz"].iter().take(dim) {
        head.push_str(&format!(" {axis:>14}"));
    }
    writeln!(out, "{head}")?;
    for t in sample(&rec.totals, rows) {
        let mut line = format!(
            "  {:>8} {:>10.4} {:>8} {:>10} {:>22}",
            t.step,
            t.time.0,
            t.critters,
            t.collisions,
            fnum(t.kinetic_energy.0)
        );
        for p in &t.momentum.0 {
            line.push_str(&format!(" {p:>14.6e}"));
        }
        writeln!(out, "{line}")?;
    }
    Ok(())
}

/// At most `rows` items, evenly spread, always with the first and the last.
pub fn sample<T>(items: &[T], rows: usize) -> Vec<&T> {
    let n = items.len();
    if n <= rows.max(2) {
        return items.iter().collect();
    }
    let rows = rows.max(2);
    (0..rows)
        .map(|i| &items[i * (n - 1) / (rows - 1)])
        .collect()
}

/// A full state as a table, floats in shortest round-trip form (exact).
pub fn print_state(out: &mut dyn Write, s: &StateMsg) -> anyhow::Result<()> {
    let dim = s.dim();
    let mut head = vec!["id", "kind", "x", "y"];
    if dim == 3 {
        head.push("z");
    }
    head.extend(["vx", "vy"]);
    if dim == 3 {
        head.push("vz");
    }
    head.extend(["radius", "mass", "health", "color", "props"]);
    writeln!(out, "{}", head.join("\t"))?;
    for i in 0..s.len() {
        let mut row = vec![id_of(s.id[i]).to_string(), s.kind_name(i).to_string()];
        let fields = s.fields(i);
        for (name, x) in &fields {
            if matches!(*name, "restitution" | "priority") {
                continue;
            }
            row.push(fnum(*x));
        }
        // The recording keys both by the raw id; the table names them as ids print.
        let key = s.id[i].to_string();
        row.push(s.colors.get(&key).cloned().unwrap_or_else(|| "-".into()));
        row.push(s.props.get(&key).map_or("-".into(), |props| {
            let items: Vec<String> = props
                .iter()
                .map(|(name, v)| format!("{name}={}", prop_text(v)))
                .collect();
            items.join(" ")
        }));
        writeln!(out, "{}", row.join("\t"))?;
    }
    Ok(())
}
