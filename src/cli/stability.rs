//! `critterbox stability`: run the stress scenes under every method and print the table of
//! `docs/stability.md` (scene x method -> measured error).

use crate::stability::{first_tunnelling_speed, METHODS, STRESS};
use clap::Args;
use std::io::Write;
use std::time::Instant;

/// Arguments of `critterbox stability`.
#[derive(Args, Debug, Default)]
pub struct StabilityArgs {}

/// Runs the command.
pub fn run(_args: &StabilityArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let header: Vec<String> = METHODS.iter().map(|m| m.to_string()).collect();
    writeln!(out, "| scene | error | {} |", header.join(" | "))?;
    writeln!(out, "|---|---|{}", "---|".repeat(METHODS.len()))?;
    let mut cells = Vec::new();
    for m in METHODS {
        cells.push(match first_tunnelling_speed(m)? {
            Some(v) => format!("tunnels from {v:.3e}"),
            None => "never tunnels (to 1e6)".into(),
        });
    }
    writeln!(
        out,
        "| bullet vs wall 0.02 thick, r 0.05, dt 1/60 | slowest speed that ends past the wall | {} |",
        cells.join(" | ")
    )?;
    for s in STRESS {
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
