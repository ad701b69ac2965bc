//! `critterbox sweep`: many runs of one scene from a TOML file (`docs/sweeps.md`).
//!
//! Each run is a child process, `critterbox run ... --summary-json`, on one thread, so runs fill
//! the machine and each one's result is what it would be alone. A run is finished when its
//! result file (`DIR/runs/<hash>.json`) exists; a rerun does only what is missing. Shards,
//! collecting, scheduler scripts and plots build on that one rule.

mod collect;
mod emit;
mod local;
mod plot;
mod signals;

pub use local::Interrupted;

use anyhow::Context;
use clap::{Args, ValueEnum};
use critterbox::sweep::{RunParams, RunResult, Shard, SweepFile};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `critterbox sweep`.
#[derive(Args, Debug)]
#[command(
    after_help = "Exit codes: 0 when every run of the sweep (or of its shard) finished \
without error; 1 when a run failed (its row carries the error; the others ran), when \
--collect finds runs missing, or on a bad sweep file; 128 + the signal (130 SIGINT, 143 SIGTERM, \
129 SIGHUP) when a signal stopped it: runs under way are stopped, no result is left half \
written, and a rerun does what is left."
)]
pub struct SweepArgs {
    /// The sweep file (TOML; see docs/sweeps.md and scripts/sweeps/).
    pub file: PathBuf,
    /// Where the runs' recordings and results and the table go.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Runs at once (default: the number of cores); each run is single-threaded.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub jobs: Option<u64>,
    /// Run only the I-th of N slices: run k (from 0) belongs to shard (k mod N) + 1; I counts
    /// from 1. The table is then left to --collect.
    #[arg(long, value_name = "I/N", value_parser = parse_shard)]
    pub shard: Option<Shard>,
    /// Rerun the runs whose result is an error.
    #[arg(long)]
    pub retry_failed: bool,
    /// Build the table from the results in these folders (any set of shards' outputs), without
    /// running anything; it goes to --out, or the first DIR.
    #[arg(long, value_name = "DIR", num_args = 1.., conflicts_with_all = ["shard", "emit"])]
    pub collect: Vec<PathBuf>,
    /// Write a scheduler's job instead of running: a Slurm job array or a Kubernetes Indexed Job,
    /// one task per shard.
    #[arg(long, value_name = "SCHEDULER", conflicts_with = "shard")]
    pub emit: Option<Emit>,
    /// Shards of the emitted job (default: one per run, at most 16).
    #[arg(long, value_name = "N", requires = "emit", value_parser = clap::value_parser!(u64).range(1..))]
    pub shards: Option<u64>,
    /// Cores per emitted task (its runs at once).
    #[arg(long, value_name = "N", default_value_t = 1, requires = "emit", value_parser = clap::value_parser!(u64).range(1..))]
    pub cpus: u64,
    /// The container image of the Kubernetes job (it must hold critterbox and the sweep's files).
    #[arg(long, default_value = "critterbox:latest", requires = "emit")]
    pub image: String,
    /// Draw a chart from the table: X and Y columns (numbers), one series per distinct GROUP.
    #[arg(long, value_name = "X:Y[:GROUP]")]
    pub plot: Option<String>,
    /// The chart's file (.svg or .png; default: DIR/plot-X-Y.svg and .png).
    #[arg(long, value_name = "FILE", requires = "plot")]
    pub plot_out: Option<PathBuf>,
}

/// The schedulers `--emit` writes for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Emit {
    /// An sbatch script with `#SBATCH --array`.
    Slurm,
    /// A batch/v1 Job with `completionMode: Indexed`.
    K8s,
}

fn parse_shard(s: &str) -> Result<Shard, String> {
    s.parse().map_err(|e: critterbox::sweep::SweepError| {
        // clap prefixes the flag already.
        e.to_string()
            .trim_start_matches(&format!("--shard {s}: "))
            .to_string()
    })
}

/// Runs the command.
pub fn run(args: &SweepArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let file = SweepFile::read(&args.file)?;
    if args.is_collect() {
        let dir = args.out.clone().unwrap_or_else(|| args.collect[0].clone());
        return collect::run(&file, &args.collect, &dir, args, out);
    }
    let dir = args
        .out
        .clone()
        .context("say where the runs go: --out DIR (or --collect DIR to build the table)")?;
    if let Some(emit) = args.emit {
        return emit::run(emit, &file, &dir, args, out);
    }
    local::run(&file, &dir, args, out)
}

impl SweepArgs {
    fn is_collect(&self) -> bool {
        !self.collect.is_empty()
    }
}

/// A run of the sweep: its place in the list, parameters and hash.
#[derive(Clone, Debug)]
pub(crate) struct Planned {
    pub k: usize,
    pub params: RunParams,
    pub hash: String,
}

/// The sweep's runs, in order.
pub(crate) fn plan(file: &SweepFile) -> Vec<Planned> {
    file.runs()
        .into_iter()
        .enumerate()
        .map(|(k, params)| {
            let hash = params.hash();
            Planned { k, params, hash }
        })
        .collect()
}

/// Where a run's result file is.
pub(crate) fn result_path(dir: &Path, hash: &str) -> PathBuf {
    dir.join("runs").join(format!("{hash}.json"))
}

/// The run's finished result in `dir`, if there is one (an unreadable file counts as missing,
/// so the run is done again).
pub(crate) fn finished(dir: &Path, hash: &str) -> Option<RunResult> {
    RunResult::read(&result_path(dir, hash)).ok()
}

/// Writes the table of the results present in `dirs` to `dir/results.csv`, draws the plot if
/// asked; gives the results' count and the failed count.
pub(crate) fn write_table(
    file: &SweepFile,
    runs: &[Planned],
    dirs: &[PathBuf],
    dir: &Path,
    args: &SweepArgs,
    out: &mut dyn Write,
) -> anyhow::Result<(usize, usize)> {
    let results: Vec<(usize, RunResult)> = runs
        .iter()
        .filter_map(|r| {
            dirs.iter()
                .find_map(|d| finished(d, &r.hash))
                .map(|res| (r.k, res))
        })
        .collect();
    let failed = results.iter().filter(|(_, r)| r.failed()).count();
    let table = critterbox::sweep::Table::assemble(file, &results);
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let csv = dir.join("results.csv");
    critterbox::sweep::write_atomic(&csv, table.to_csv().as_bytes())
        .with_context(|| format!("writing {}", csv.display()))?;
    writeln!(
        out,
        "table        {} ({} rows, {failed} failed)",
        csv.display(),
        results.len()
    )?;
    if let Some(spec) = &args.plot {
        for path in plot::draw(&table, spec, dir, args.plot_out.as_deref())? {
            writeln!(out, "plot         {}", path.display())?;
        }
    }
    Ok((results.len(), failed))
}
