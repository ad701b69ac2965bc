//! The standard gas (`critterbox::scenes::gas`, the scene `compare/rapier` runs): N disks of
//! radius 0.5 at packing fraction 0.2 in a square box walled on four sides, dt = 1/60,
//! restitution 1, no friction, no gravity, a grid start with velocities uniform in [-1, 1].
//! critterbox runs it with the scene's own method (`discrete`, as in the benchmarks).
//!
//! Box2D gets the same disks and walls, with its restitution threshold at 0 (by default it drops
//! the bounce of contacts slower than 1 m/s, which would cool the gas) and sleep off (a slow disk
//! of a gas must not fall asleep).

use crate::bodies::{disks_of, energy, Bodies};
use crate::box2d::{Box2d, Settings};
use crate::{median, time, time_on, Args};
use critterbox::glam::DVec2;
use critterbox::scenes::{gas, GasParams};
use std::error::Error;

/// The counts the gas runs at unless `--n` says otherwise.
const SIZES: [usize; 3] = [1_000, 10_000, 100_000];

/// Times both engines at every N and thread count, and prints one table.
pub fn run(args: &Args, pools: &[(usize, rayon::ThreadPool)]) -> Result<(), Box<dyn Error>> {
    let sizes = args.sizes.clone().unwrap_or(SIZES.to_vec());
    // The method the scene gives its worlds, for the heading.
    let one = GasParams {
        n: 1,
        ..GasParams::default()
    };
    let method = gas::<DVec2>(&one)?.method();
    println!("## Standard gas\n");
    println!(
        "Restitution 1, friction 0, no gravity, walled box, radius 0.5, packing 0.2, dt = 1/60. \
         critterbox: method {method}. Box2D: {} substeps, restitution threshold 0, sleep off. \
         ms/step: median of {} alternating rounds of {} steps after {} untimed steps from the \
         grid start. KE drift: relative change of the kinetic energy over the whole run from the \
         grid start (the steps column).\n",
        args.substeps, args.rounds, args.steps, args.warmup
    );
    println!("| N | threads | critterbox ms/step | Box2D ms/step | Box2D / critterbox | critterbox KE drift | Box2D KE drift | steps |");
    println!("|---|---|---|---|---|---|---|---|");
    for &n in &sizes {
        for (threads, pool) in pools {
            let params = GasParams {
                n,
                ..GasParams::default()
            };
            let mut ours = gas::<DVec2>(&params)?;
            let settings = Settings {
                workers: u32::try_from(*threads)?,
                substeps: args.substeps,
                restitution_threshold: 0.0,
                sleep: false,
            };
            let mut theirs = Box2d::from(&Bodies::of(&ours), &settings)?;
            let (e0_ours, e0_theirs) = (energy(&disks_of(&ours)), energy(&theirs.disks()?));
            if args.warmup > 0 {
                time_on(pool, &mut ours, args.warmup);
                time(args.warmup, || theirs.step());
            }
            let (mut t_ours, mut t_theirs) = (Vec::new(), Vec::new());
            for _ in 0..args.rounds {
                t_ours.push(time_on(pool, &mut ours, args.steps));
                t_theirs.push(time(args.steps, || theirs.step()));
            }
            // The rest of the drift run, untimed.
            let timed = args.warmup + args.rounds * args.steps;
            let done = timed.max(args.drift_steps);
            let rest = done - timed;
            if rest > 0 {
                time_on(pool, &mut ours, rest);
                time(rest, || theirs.step());
            }
            let drift_ours = energy(&disks_of(&ours)) / e0_ours - 1.0;
            let drift_theirs = energy(&theirs.disks()?) / e0_theirs - 1.0;
            let (a, b) = (median(t_ours), median(t_theirs));
            println!(
                "| {n} | {threads} | {a:.3} | {b:.3} | {:.2} | {drift_ours:+.1e} | {drift_theirs:+.1e} | {done} |",
                b / a
            );
        }
    }
    println!();
    Ok(())
}
