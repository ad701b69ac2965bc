//! `critterbox stability`: run the stress scenes under every method and print the table of
//! `docs/stability.md` (scene x method -> measured error), in 2D and in 3D.

use clap::Args;
use critterbox::method::Method;
use critterbox::stability::{
    first_tunnelling_speed, first_tunnelling_speed_3d, Stress, METHODS, STRESS, STRESS_3D,
};
use std::io::Write;
use std::time::Instant;

/// Arguments of `critterbox stability`.
#[derive(Args, Debug, Default)]
pub struct StabilityArgs {}

/// Runs the command: the 2D table, then the 3D one.
pub fn run(_args: &StabilityArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    table(
        out,
        "bullet vs wall 0.02 thick, r 0.05, dt 1/60",
        first_tunnelling_speed,
        STRESS,
    )?;
    writeln!(out)?;
    table(
        out,
        "bullet vs plate 0.02 thick (3D), r 0.05, dt 1/60",
        first_tunnelling_speed_3d,
        STRESS_3D,
    )
}

/// One table: the bullet's row, then a row per stress scene.
fn table(
    out: &mut dyn Write,
    bullet: &str,
    first_tunnelling: fn(Method) -> Result<Option<f64>, critterbox::error::Error>,
    scenes: &[Stress],
) -> anyhow::Result<()> {
    let header: Vec<String> = METHODS.iter().map(|m| m.to_string()).collect();
    writeln!(out, "| scene | error | {} |", header.join(" | "))?;
    writeln!(out, "|---|---|{}", "---|".repeat(METHODS.len()))?;
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
