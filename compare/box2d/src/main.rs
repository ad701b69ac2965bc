//! critterbox against Box2D v3 (through the `boxdd` bindings), measured in one process.
//!
//! Two scenes, each built once by critterbox and handed to Box2D as plain data, so both engines
//! start from the same positions and velocities:
//!
//! * the standard gas (`gas.rs`): critterbox's benchmark scene, the one `compare/rapier` runs;
//! * a ball pit (`pit.rs`): disks dropped into a walled box under gravity, timed while they
//!   settle and after (at rest once they sleep), then checked for overlap and leftover energy.
//!
//! The engines are stepped in alternating rounds, so a load spike on this shared machine hits
//! both; critterbox runs on a rayon pool of the asked size, Box2D with that many workers.
//!
//! Usage, from this directory (its `.cargo/config.toml` builds Box2D with NDEBUG):
//! `cargo run --release -- [--scene gas|pit|both] [--n LIST] [--threads LIST] ...` (`--help`
//! lists every flag); `--features avx2` builds Box2D's AVX2 solver instead of SSE2.

mod bodies;
mod box2d;
mod gas;
mod pit;

use std::time::Instant;

const USAGE: &str = "\
critterbox against Box2D v3 (boxdd) on the standard 2D gas and a ball pit, in one process

Usage: critterbox-vs-box2d [--scene gas|pit|both] [--n LIST] [--threads LIST] [--rounds R]
                           [--steps S] [--warmup W] [--drift-steps D] [--substeps K]
                           [--settle SECONDS] [--rest-within SECONDS] [--solve N]

  --scene S        gas, pit or both (default both)
  --n LIST         critter counts, comma separated, 1e5 accepted (default 1000,10000,100000 for
                   the gas, 1000,10000 for the pit: a pit of 1e5 takes 8 to 9 minutes per
                   thread count here)
  --threads LIST   thread counts (default 1,2): critterbox's rayon pool, Box2D's worker count
  --rounds R       alternating timed rounds; medians are reported (default 3)
  --steps S        steps per timed round, and per turn while the pit settles (default 20)
  --warmup W       gas: untimed steps before the rounds (default 300: the grid start has no
                   contact, and collisions take a few mean free times, ~100 steps each, to reach
                   their steady rate; 0 times from the grid start as compare/rapier does)
  --drift-steps D  gas: steps from the start over which kinetic energy drift is measured, at
                   least the warm-up and the rounds (default 600)
  --substeps K     Box2D's substeps per step (default 4, its recommended count)
  --settle T       pit: seconds of settling before the later rounds (default: the fall time from
                   the top of the start to the floor, plus 10 s)
  --rest-within T  pit: after the settling, seconds a set-up whose disks are not all asleep
                   steps on (untimed) until they are, before the rounds at rest (default 30;
                   0 measures right after the settling)
  --solve N        pit: the sweeps of the solve:N set-up beside auto (default 8)";

/// The command line.
pub struct Args {
    pub scene: Scene,
    pub sizes: Option<Vec<usize>>,
    pub threads: Vec<usize>,
    pub rounds: usize,
    pub steps: usize,
    pub warmup: usize,
    pub drift_steps: usize,
    pub substeps: i32,
    pub settle: Option<f64>,
    /// Pit: seconds of untimed steps, after the settling, for the piles to fall asleep.
    pub rest_within: f64,
    /// The sweeps of the pit's `solve:N` set-up.
    pub solve: u32,
}

/// Which scenes to run.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Scene {
    Gas,
    Pit,
    Both,
}

/// A whole number above 0, written plainly or as `1e5`.
fn count(s: &str) -> Option<usize> {
    let n = s.parse::<usize>().ok().or_else(|| {
        s.parse::<f64>()
            .ok()
            .filter(|x| x.fract() == 0.0)
            .map(|x| x as usize)
    })?;
    (n > 0).then_some(n)
}

/// The command line, or a message saying what is wrong with it (empty for --help).
fn parse(mut args: impl Iterator<Item = String>) -> Result<Args, String> {
    let mut a = Args {
        scene: Scene::Both,
        sizes: None,
        threads: vec![1, 2],
        rounds: 3,
        steps: 20,
        warmup: 300,
        drift_steps: 600,
        substeps: 4,
        settle: None,
        rest_within: 30.0,
        solve: 8,
    };
    while let Some(flag) = args.next() {
        let mut value = || args.next().ok_or(format!("{flag} needs a value"));
        let number = |s: String| count(&s).ok_or(format!("{flag} needs a whole number above 0"));
        let list = |s: String| -> Result<Vec<usize>, String> {
            s.split(',')
                .map(|x| count(x.trim()))
                .collect::<Option<Vec<_>>>()
                .filter(|v| !v.is_empty())
                .ok_or(format!(
                    "{flag} needs whole numbers above 0, comma separated"
                ))
        };
        match flag.as_str() {
            "-h" | "--help" => return Err(String::new()),
            "--scene" => {
                a.scene = match value()?.as_str() {
                    "gas" => Scene::Gas,
                    "pit" => Scene::Pit,
                    "both" => Scene::Both,
                    other => return Err(format!("--scene {other:?}: use gas, pit or both")),
                }
            }
            "--n" => a.sizes = Some(list(value()?)?),
            "--threads" => a.threads = list(value()?)?,
            "--rounds" => a.rounds = number(value()?)?,
            "--steps" => a.steps = number(value()?)?,
            "--warmup" => {
                let w = value()?;
                a.warmup = w
                    .parse()
                    .map_err(|_| format!("--warmup {w:?}: a whole number"))?
            }
            "--drift-steps" => a.drift_steps = number(value()?)?,
            "--substeps" => {
                a.substeps = i32::try_from(number(value()?)?).map_err(|e| e.to_string())?
            }
            "--solve" => a.solve = u32::try_from(number(value()?)?).map_err(|e| e.to_string())?,
            "--settle" => {
                let t = value()?.parse::<f64>().ok().filter(|t| *t >= 0.0);
                a.settle = Some(t.ok_or("--settle needs seconds, 0 or more")?);
            }
            "--rest-within" => {
                let t = value()?.parse::<f64>().ok().filter(|t| *t >= 0.0);
                a.rest_within = t.ok_or("--rest-within needs seconds, 0 or more")?;
            }
            other => return Err(format!("unknown argument {other:?}")),
        }
    }
    Ok(a)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Milliseconds per step of `steps` calls of `step`.
fn time(steps: usize, mut step: impl FnMut()) -> f64 {
    let t = Instant::now();
    for _ in 0..steps {
        step();
    }
    t.elapsed().as_secs_f64() * 1e3 / steps as f64
}

/// A world handed to a pool's thread for the length of one `install` call.
struct Lent<'a, W>(&'a mut W);

// SAFETY: `ThreadPool::install` blocks the lending thread until the closure has returned, so the
// world (whose kind hooks are `Rc`s, hence not `Send`) is only ever used by one thread at a time,
// and `install`'s hand-over orders those uses.
unsafe impl<W> Send for Lent<'_, W> {}

/// Milliseconds per step of `steps` steps of `world` on `pool`'s threads.
fn time_on(
    pool: &rayon::ThreadPool,
    world: &mut critterbox::World<critterbox::glam::DVec2>,
    steps: usize,
) -> f64 {
    let lent = Lent(world);
    pool.install(move || {
        let lent = lent;
        time(steps, || lent.0.step().expect("critterbox steps"))
    })
}

fn main() {
    let args = match parse(std::env::args().skip(1)) {
        Ok(parsed) => parsed,
        Err(message) if message.is_empty() => {
            println!("{USAGE}");
            return;
        }
        Err(message) => {
            eprintln!("error: {message}\n\n{USAGE}");
            std::process::exit(2);
        }
    };
    // One pool per thread count, kept for the whole run (critterbox's parallel stages use the
    // pool they are installed on).
    let pools: Vec<(usize, rayon::ThreadPool)> = args
        .threads
        .iter()
        .map(|&t| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(t).build();
            (t, pool.expect("a thread pool"))
        })
        .collect();
    println!("{}\n", box2d::describe());
    let mut result = Ok(());
    if args.scene != Scene::Pit {
        result = gas::run(&args, &pools);
    }
    if result.is_ok() && args.scene != Scene::Gas {
        result = pit::run(&args, &pools);
    }
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
