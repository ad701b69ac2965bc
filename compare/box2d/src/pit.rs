//! The ball pit: N disks of radius 0.5 dropped from rest into a walled box under gravity (9.81
//! down), dt = 1/60, restitution 0.5 and friction 0 in both engines.
//!
//! The start: a loose grid `SPACING` apart (a quarter radius between neighbours' edges), each
//! disk moved sideways by up to `JITTER` from the world's seeded generator so the pile does not
//! stack in columns, sqrt(2N) disks a row, so the box is about twice as wide as the start is
//! high. A floor, two side walls and a lid, `WALL` thick, close it.
//!
//! Three set-ups run from that same start: critterbox under `auto` and under `solve:8`, and
//! Box2D with its defaults but for friction (0), restitution (0.5) and its restitution
//! threshold, set to critterbox's resting speed (2 |g| dt, about 0.33 m/s: slower contacts do not
//! bounce) instead of its 1 m/s. Both engines let bodies at rest sleep.
//!
//! Timing: while the pit settles, the set-ups take turns of `--steps` steps, and the mean over
//! the settling steps is reported. A set-up whose disks are not all asleep then steps on,
//! untimed, for up to `--rest-within` seconds until they are (the table gives when each pile
//! was first all asleep). Then `--rounds` alternating rounds of `--steps` steps, whose median is
//! reported: at rest for every pile that came to rest. At the end, both
//! engines are measured alike (`bodies.rs`): the deepest overlap, the kinetic energy left and the
//! disks outside the box.
//!
//! The default settling time is the top row's fall to the floor plus 10 s: enough for 1e3 and 1e4
//! disks to come to rest in Box2D; a pile of 1e5 (about 180 rows deep) is still moving after it
//! in both engines, and its run takes 8 to 9 minutes per thread count here.

use crate::bodies::{deepest_overlap, disks_of, energy, outside, Bodies, Disk};
use crate::box2d::{Box2d, Settings};
use crate::{median, time, time_on, Args};
use critterbox::glam::DVec2;
use critterbox::{CritterSpec, Method, WallBox, World, WorldConfig};
use std::error::Error;

const RADIUS: f64 = 0.5;
const RESTITUTION: f64 = 0.5;
const GRAVITY: f64 = 9.81;
const DT: f64 = 1.0 / 60.0;
/// Pitch of the start's grid: a quarter radius between neighbours' edges.
const SPACING: f64 = 2.5 * RADIUS;
/// Largest sideways shift of a disk at the start (less than half the gap, so none overlap).
const JITTER: f64 = 0.1;
/// Walls' thickness: two radii, more than any disk here moves in a step near a wall.
const WALL: f64 = 1.0;
const SEED: u64 = 1;
/// Seconds of settling after the top row's fall time, by default.
const SETTLE_AFTER_FALL: f64 = 10.0;

/// Pits at least this large report their progress on stderr.
const PROGRESS_FROM: usize = 50_000;

/// The counts the pit runs at unless `--n` says otherwise: 1e5 takes 8 to 9 minutes per thread
/// count on this machine (`--n 100000`).
const SIZES: [usize; 2] = [1_000, 10_000];

/// The pit's inside: from the origin to (width, height).
struct Layout {
    columns: usize,
    width: f64,
    height: f64,
}

impl Layout {
    fn of(n: usize) -> Layout {
        let columns = (2.0 * n as f64).sqrt().ceil() as usize;
        let rows = n.div_ceil(columns);
        Layout {
            columns,
            width: columns as f64 * SPACING,
            // Two rows of head room under the lid.
            height: (rows + 2) as f64 * SPACING,
        }
    }
}

/// The pit of `n` disks as a critterbox world under `method`; the same disks for every method
/// (the jitter comes from the seeded generator, drawn in the same order).
fn world(n: usize, method: Method) -> Result<World<DVec2>, critterbox::Error> {
    let l = Layout::of(n);
    let config = WorldConfig::new(
        DVec2::splat(-WALL - 1.0),
        DVec2::new(l.width + WALL + 1.0, l.height + WALL + 1.0),
    )
    .dt(DT)
    .gravity(DVec2::new(0.0, -GRAVITY))
    .seed(SEED)
    .method(method);
    let mut w = World::new(config)?;
    let (x0, x1, y1) = (-WALL, l.width + WALL, l.height);
    for (lo, hi) in [
        ((x0, -WALL), (x1, 0.0)),               // floor
        ((x0, y1), (x1, y1 + WALL)),            // lid
        ((x0, 0.0), (0.0, y1)),                 // left
        ((l.width, 0.0), (l.width + WALL, y1)), // right
    ] {
        w.add_wall(WallBox::aligned(DVec2::from(lo), DVec2::from(hi))?)?;
    }
    w.reserve(n)?;
    for i in 0..n {
        let (col, row) = (i % l.columns, i / l.columns);
        let shift = w.rng().uniform(-JITTER, JITTER);
        let pos = DVec2::new(
            (col as f64 + 0.5) * SPACING + shift,
            (row as f64 + 0.5) * SPACING,
        );
        w.spawn(
            CritterSpec::ball(pos)
                .radius(RADIUS)
                .restitution(RESTITUTION),
        )?;
    }
    Ok(w)
}

/// One set-up of the pit.
enum Engine {
    // Both boxed: the two engines' world handles are large and far apart in size.
    Critterbox(Method, Box<World<DVec2>>),
    Box2d(Box<Box2d>),
}

impl Engine {
    fn name(&self) -> String {
        match self {
            Engine::Critterbox(Method::Auto, w) => match w.auto_choice() {
                Some((m, _)) => format!("critterbox auto (last step: {m})"),
                None => "critterbox auto".into(),
            },
            Engine::Critterbox(m, _) => format!("critterbox {m}"),
            Engine::Box2d(_) => "Box2D".into(),
        }
    }

    /// Milliseconds per step of `steps` steps (critterbox on `pool`).
    fn time(&mut self, pool: &rayon::ThreadPool, steps: usize) -> f64 {
        match self {
            Engine::Critterbox(_, w) => time_on(pool, w, steps),
            Engine::Box2d(b) => time(steps, || b.step()),
        }
    }

    fn disks(&mut self) -> Result<Vec<Disk>, Box<dyn Error>> {
        match self {
            Engine::Critterbox(_, w) => Ok(disks_of(w)),
            Engine::Box2d(b) => b.disks(),
        }
    }

    fn asleep(&self) -> Result<usize, Box<dyn Error>> {
        match self {
            Engine::Critterbox(_, w) => Ok(w.sleepers()),
            Engine::Box2d(b) => b.asleep(),
        }
    }
}

/// Runs the pit at every N and thread count, and prints one table.
pub fn run(args: &Args, pools: &[(usize, rayon::ThreadPool)]) -> Result<(), Box<dyn Error>> {
    let sizes = args.sizes.clone().unwrap_or(SIZES.to_vec());
    let threshold = 2.0 * GRAVITY * DT;
    println!("## Ball pit\n");
    println!(
        "N disks of radius {RADIUS} dropped from rest (a loose grid {SPACING} apart, sqrt(2N) a \
         row) into a box closed by walls, gravity {GRAVITY}, dt = 1/60, restitution \
         {RESTITUTION}, friction 0, sleep on in both. Box2D: {} substeps, restitution threshold \
         {threshold:.3} m/s (critterbox's resting speed, 2 |g| dt). Settling: mean ms/step over \
         the settling steps, taken in turns of {} steps. A pile not all asleep then steps on \
         untimed, up to {} s, until it is. At rest: median of {} alternating rounds of {} steps \
         (at rest where the asleep column has every disk). Then, measured \
         alike for both: the deepest overlap (disk-disk in radii of the smaller, disk-wall in \
         the disk's), the kinetic energy left over N m g r, disks asleep and disks outside the \
         box.\n",
        args.substeps, args.steps, args.rest_within, args.rounds, args.steps
    );
    println!("| N | threads | engine | settle steps | settling ms/step | all asleep at (s) | at rest ms/step | deepest overlap (r) | KE / (N m g r) | asleep | outside |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for &n in &sizes {
        let l = Layout::of(n);
        let settle = args
            .settle
            .unwrap_or((2.0 * l.height / GRAVITY).sqrt() + SETTLE_AFTER_FALL);
        let settle_steps = (settle / DT).round() as usize;
        for (threads, pool) in pools {
            let (auto, solve) = (Method::Auto, Method::Solve(args.solve));
            let first = world(n, auto)?;
            let scene = Bodies::of(&first);
            let settings = Settings {
                workers: u32::try_from(*threads)?,
                substeps: args.substeps,
                restitution_threshold: threshold as f32,
                sleep: true,
            };
            let mut engines = [
                Engine::Critterbox(auto, Box::new(first)),
                Engine::Critterbox(solve, Box::new(world(n, solve)?)),
                Engine::Box2d(Box::new(Box2d::from(&scene, &settings)?)),
            ];
            // Settling: turns of `steps` steps, each set-up in turn, so a load spike hits all.
            let mut settling = vec![0.0; engines.len()];
            // The step after which each set-up first had every disk asleep (to a turn).
            let mut slept = vec![None; engines.len()];
            let mut done = 0;
            while done < settle_steps {
                let turn = args.steps.min(settle_steps - done);
                for ((e, total), slept) in engines.iter_mut().zip(&mut settling).zip(&mut slept) {
                    *total += e.time(pool, turn) * turn as f64;
                    if slept.is_none() && e.asleep()? == n {
                        *slept = Some(done + turn);
                    }
                }
                done += turn;
                // Progress on stderr, about every tenth of the settling, for the large pits that
                // take minutes.
                let tenth = (settle_steps / 10).max(args.steps);
                if n >= PROGRESS_FROM && (done % tenth < turn || done == settle_steps) {
                    let so_far: Vec<String> = settling
                        .iter()
                        .map(|t| format!("{:.2}", t / done as f64))
                        .collect();
                    eprintln!(
                        "pit N = {n}, {threads} thread(s): {done}/{settle_steps} steps settled, \
                         ms/step so far (auto, solve:{}, Box2D): {}",
                        args.solve,
                        so_far.join(", ")
                    );
                }
            }
            // Untimed: the set-ups still awake step on until they sleep, so that the rounds
            // after settling find every pile at rest that comes to rest within the time given.
            let rest_steps = (args.rest_within / DT).round() as usize;
            for (e, slept) in engines.iter_mut().zip(&mut slept) {
                let mut steps = done;
                while slept.is_none() && steps < done + rest_steps {
                    e.time(pool, args.steps);
                    steps += args.steps;
                    if e.asleep()? == n {
                        *slept = Some(steps);
                    }
                }
            }
            let mut at_rest = vec![Vec::new(); engines.len()];
            for _ in 0..args.rounds {
                for (e, times) in engines.iter_mut().zip(&mut at_rest) {
                    times.push(e.time(pool, args.steps));
                }
            }
            let zipped = engines.iter_mut().zip(settling).zip(at_rest).zip(slept);
            for (((e, total), times), slept) in zipped {
                let disks = e.disks()?;
                let overlap = deepest_overlap(&disks, &scene.walls);
                let ke = energy(&disks) / (n as f64 * GRAVITY * RADIUS);
                let out = outside(&disks, DVec2::ZERO, DVec2::new(l.width, l.height));
                let settling = if settle_steps > 0 {
                    format!("{:.3}", total / settle_steps as f64)
                } else {
                    "-".into()
                };
                let slept = match slept {
                    Some(steps) => format!("{:.1}", steps as f64 * DT),
                    None => format!("> {:.0}", (settle_steps + rest_steps) as f64 * DT),
                };
                println!(
                    "| {n} | {threads} | {} | {settle_steps} | {settling} | {slept} | {:.4} | {overlap:.4} | {ke:.1e} | {} | {out} |",
                    e.name(),
                    median(times),
                    e.asleep()?,
                );
            }
        }
    }
    println!();
    Ok(())
}
