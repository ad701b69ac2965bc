//! `critterbox stability`: run the stress scenes under every method and print the table of
//! `docs/stability.md` (scene x method -> measured error), in 2D and in 3D, the mixed scenes'
//! parts last; with `--bullets`, the bullet sweep behind the table's first row; with `--mixed`,
//! the mixed scenes' rows alone.

use clap::Args;
use critterbox::method::Method;
use critterbox::scenes::mixed::{Mixed, MIXED, MIXED_3D};
use critterbox::scenes::stress::{
    bullet, bullet_3d, bullet_speeds, first_tunnelling_speed, first_tunnelling_speed_3d, Stress,
    METHODS, STRESS, STRESS_3D,
};
use critterbox::Error;
use std::io::Write;
use std::time::Instant;

/// Arguments of `critterbox stability`.
#[derive(Args, Debug, Default)]
pub struct StabilityArgs {
    /// Print the bullet sweep instead of the tables: for each speed from 1 to 1e6 (four per
    /// decade), whether the bullet (radius 0.05, dt 1/60) ends past the wall 0.02 thick (2D) or
    /// the plate (3D) under each method. The tables' bullet row is the first speed that does.
    #[arg(long)]
    pub bullets: bool,
    /// Print only the mixed scenes' rows (a row per scene and part), 2D then 3D.
    #[arg(long)]
    pub mixed: bool,
}

/// The 2D bullet, as the tables and the sweep name it.
const BULLET_2D: &str = "bullet vs wall 0.02 thick, r 0.05, dt 1/60";
/// The 3D bullet, as the tables and the sweep name it.
const BULLET_3D: &str = "bullet vs plate 0.02 thick (3D), r 0.05, dt 1/60";

/// Runs the command: the 2D table, then the 3D one (or the two bullet sweeps).
pub fn run(args: &StabilityArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    if args.bullets {
        bullet_sweep(out, BULLET_2D, bullet)?;
        writeln!(out)?;
        return bullet_sweep(out, BULLET_3D, bullet_3d);
    }
    if args.mixed {
        header(out, &["scene", "error"])?;
        mixed_rows(out, MIXED)?;
        writeln!(out)?;
        header(out, &["scene", "error"])?;
        return mixed_rows(out, MIXED_3D);
    }
    table(out, BULLET_2D, first_tunnelling_speed, STRESS)?;
    mixed_rows(out, MIXED)?;
    writeln!(out)?;
    table(out, BULLET_3D, first_tunnelling_speed_3d, STRESS_3D)?;
    mixed_rows(out, MIXED_3D)
}

/// A row per part of each mixed scene: each method runs the scene once and measures every
/// part (the milliseconds are the whole run's, the same in each part's row).
fn mixed_rows(out: &mut dyn Write, scenes: &[Mixed]) -> anyhow::Result<()> {
    for s in scenes {
        let mut runs = Vec::new();
        for m in METHODS {
            let t = Instant::now();
            let errors = (s.run)(m)?;
            runs.push((errors, t.elapsed().as_secs_f64() * 1e3));
        }
        for (i, part) in s.parts.iter().enumerate() {
            let cells: Vec<String> = runs
                .iter()
                .map(|(errors, ms)| format!("{:.2e} ({ms:.0} ms)", errors[i]))
                .collect();
            writeln!(
                out,
                "| {}: {} | {} | {} |",
                s.name,
                part.name,
                part.error,
                cells.join(" | ")
            )?;
        }
    }
    Ok(())
}

/// The header of a table with a column per method, after `first` columns.
fn header(out: &mut dyn Write, first: &[&str]) -> anyhow::Result<()> {
    let methods: Vec<String> = METHODS.iter().map(|m| m.to_string()).collect();
    writeln!(out, "| {} | {} |", first.join(" | "), methods.join(" | "))?;
    writeln!(out, "|{}", "---|".repeat(first.len() + METHODS.len()))?;
    Ok(())
}

/// One table: the bullet's row, then a row per stress scene.
fn table(
    out: &mut dyn Write,
    bullet: &str,
    first_tunnelling: fn(Method) -> Result<Option<f64>, Error>,
    scenes: &[Stress],
) -> anyhow::Result<()> {
    header(out, &["scene", "error"])?;
    let mut cells = Vec::new();
    for m in METHODS {
        cells.push(match first_tunnelling(m)? {
            Some(v) => format!("tunnels from {v:.3e}"),
            None => "never tunnels (to 1e6)".into(),
        });
    }
    writeln!(
        out,
        "| {bullet} | slowest speed that ends past the wall | {} |",
        cells.join(" | ")
    )?;
    for s in scenes {
        let mut cells = Vec::new();
        for m in METHODS {
            let t = Instant::now();
            let e = (s.run)(m)?;
            cells.push(format!(
                "{e:.2e} ({:.0} ms)",
                t.elapsed().as_secs_f64() * 1e3
            ));
        }
        writeln!(out, "| {} | {} | {} |", s.name, s.error, cells.join(" | "))?;
    }
    Ok(())
}

/// The bullet at every speed of the sweep under every method: "past" where it ends past the
/// wall.
fn bullet_sweep(
    out: &mut dyn Write,
    title: &str,
    ends_past: fn(f64, Method) -> Result<bool, Error>,
) -> anyhow::Result<()> {
    writeln!(out, "{title}: ends past the wall?")?;
    header(out, &["speed"])?;
    for v in bullet_speeds() {
        let mut cells = Vec::new();
        for m in METHODS {
            cells.push(if ends_past(v, m)? { "past" } else { "-" });
        }
        writeln!(out, "| {v:.3e} | {} |", cells.join(" | "))?;
    }
    Ok(())
}
