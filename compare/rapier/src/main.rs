//! critterbox against rapier2d-f64 on the standard 2D gas, measured in one process.
//!
//! The scene (the engine's benchmark scene, `critterbox::scenes::gas`): N disks of radius 0.5 at
//! packing fraction 0.2 in a square box walled on four sides, dt = 1/60, restitution 1, no
//! friction, rotations locked, a grid start with velocities uniform in [-1, 1]. Both engines get
//! the same initial positions and velocities (taken from critterbox's world).
//!
//! The two engines are stepped in alternating rounds, so a load spike on this shared machine hits
//! both; medians of the rounds are reported, and their ratio.
//!
//! Usage: `cargo run --release -- [N ...] [--steps S] [--rounds R] [--drift-steps D]`, or
//! `--chart PREFIX` for the chart of `docs/performance.md` (see `chart.rs`).

mod chart;

use critterbox::glam::DVec2;
use critterbox::scenes::{gas, GasParams};
use rapier2d_f64::prelude::*;
use std::time::Instant;

struct Rapier {
    pipeline: PhysicsPipeline,
    params: IntegrationParameters,
    islands: IslandManager,
    broad: DefaultBroadPhase,
    narrow: NarrowPhase,
    bodies: RigidBodySet,
    colliders: ColliderSet,
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
    soft: SoftBodySet,
    ccd: CCDSolver,
    handles: Vec<RigidBodyHandle>,
}

/// The bodies of a critterbox gas as plain data, so rapier can be built after the critterbox
/// world is gone (the memory measurement).
struct Bodies {
    /// Position, velocity and radius of each disk.
    disks: Vec<(DVec2, DVec2, f64)>,
    /// Centre and half sizes of each wall.
    walls: Vec<(DVec2, DVec2)>,
    dt: f64,
}

impl Bodies {
    fn of(world: &critterbox::World<DVec2>) -> Bodies {
        let mut b = Bodies {
            disks: Vec::new(),
            walls: Vec::new(),
            dt: world.dt(),
        };
        for c in world.critters().iter() {
            match c.wall() {
                Some(wall) => b.walls.push((c.pos, wall.half)),
                None => b.disks.push((c.pos, c.vel, c.radius())),
            }
        }
        b
    }
}

impl Rapier {
    fn from(scene: &Bodies) -> Rapier {
        let mut bodies = RigidBodySet::new();
        let mut colliders = ColliderSet::new();
        let mut handles = Vec::new();
        for &(center, half) in &scene.walls {
            let body = bodies
                .insert(RigidBodyBuilder::fixed().translation(Vector::new(center.x, center.y)));
            let collider = ColliderBuilder::cuboid(half.x, half.y)
                .restitution(1.0)
                .friction(0.0)
                .restitution_combine_rule(CoefficientCombineRule::Max)
                .friction_combine_rule(CoefficientCombineRule::Min);
            colliders.insert_with_parent(collider, body, &mut bodies);
        }
        for &(pos, vel, radius) in &scene.disks {
            let body = bodies.insert(
                RigidBodyBuilder::dynamic()
                    .translation(Vector::new(pos.x, pos.y))
                    .linvel(Vector::new(vel.x, vel.y))
                    .lock_rotations(),
            );
            let collider = ColliderBuilder::ball(radius)
                .restitution(1.0)
                .friction(0.0)
                .restitution_combine_rule(CoefficientCombineRule::Max)
                .friction_combine_rule(CoefficientCombineRule::Min);
            colliders.insert_with_parent(collider, body, &mut bodies);
            handles.push(body);
        }
        let params = IntegrationParameters {
            dt: scene.dt,
            ..IntegrationParameters::default()
        };
        Rapier {
            pipeline: PhysicsPipeline::new(),
            params,
            islands: IslandManager::new(),
            broad: DefaultBroadPhase::new(),
            narrow: NarrowPhase::new(),
            bodies,
            colliders,
            impulse_joints: ImpulseJointSet::new(),
            multibody_joints: MultibodyJointSet::new(),
            soft: SoftBodySet::new(),
            ccd: CCDSolver::new(),
            handles,
        }
    }

    fn step(&mut self) {
        self.pipeline.step(
            Vector::ZERO,
            &self.params,
            &mut self.islands,
            &mut self.broad,
            &mut self.narrow,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.impulse_joints,
            &mut self.multibody_joints,
            &mut self.soft,
            &mut self.ccd,
            &(),
            &(),
        );
    }

    /// Kinetic energy with every disk's mass taken as 1 (all disks have the same mass, so the
    /// relative drift does not depend on it).
    fn energy(&self) -> f64 {
        self.handles
            .iter()
            .map(|h| 0.5 * self.bodies[*h].linvel().length_squared())
            .sum()
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

const USAGE: &str = "\
critterbox against rapier2d-f64 on the standard 2D gas, in one process

Usage: critterbox-vs-rapier [N ...] [--steps S] [--rounds R] [--drift-steps D] [--threads T]
       critterbox-vs-rapier --chart PREFIX [N ...] [--steps S] [--rounds R] [--rapier-max M]
                            [--warmup W]

  N                critter counts to compare (default: 1000 10000 100000)
  --steps S        steps per timed round (default 20)
  --rounds R       alternating rounds; the medians are reported (default 7)
  --drift-steps D  steps over which kinetic energy drift is measured (default 300)
  --threads T      critterbox's threads (default 1, as rapier here; its stages go parallel
                   from 20,000 critters)
  --chart PREFIX   instead: ms per step of critterbox 2D and 3D on 1 and 2 threads and of
                   rapier2d-f64 on 1, in alternating rounds, and bytes per critter of each
                   engine built and stepped alone in a child process; a table, and a chart in
                   PREFIX.svg and PREFIX.png (default N: 1000 10000 100000 1000000)
  --rapier-max M   with --chart: the largest N rapier is run at (default 100000)
  --warmup W       with --chart: W untimed steps of every world first (default 0: timed from
                   the grid start, as the anchor figures for rapier are)";

/// The command line.
struct Args {
    chart: Option<String>,
    rapier_max: usize,
    warmup: usize,
    sizes: Vec<usize>,
    steps: usize,
    rounds: usize,
    drift_steps: usize,
    threads: usize,
}

/// The command line, or a message saying what is wrong with it (empty for --help).
fn parse(mut args: impl Iterator<Item = String>) -> Result<Args, String> {
    let mut sizes = Vec::new();
    let (mut steps, mut rounds, mut drift_steps, mut threads) = (20, 7, 300, 1);
    let (mut chart, mut rapier_max, mut warmup) = (None, 100_000, 0);
    while let Some(a) = args.next() {
        let mut number = |what: &str| -> Result<usize, String> {
            args.next()
                .and_then(|s| s.parse().ok())
                .filter(|&n| n > 0)
                .ok_or_else(|| format!("{what} needs a whole number above 0"))
        };
        match a.as_str() {
            "-h" | "--help" => return Err(String::new()),
            "--steps" => steps = number("--steps")?,
            "--rounds" => rounds = number("--rounds")?,
            "--drift-steps" => drift_steps = number("--drift-steps")?,
            "--threads" => threads = number("--threads")?,
            "--rapier-max" => rapier_max = number("--rapier-max")?,
            "--warmup" => warmup = number("--warmup")?,
            "--chart" => {
                chart = Some(args.next().ok_or("--chart needs a file name prefix")?);
            }
            n => match n.parse::<usize>() {
                Ok(n) if n > 0 => sizes.push(n),
                _ => return Err(format!("unknown argument {n:?}")),
            },
        }
    }
    Ok(Args {
        chart,
        rapier_max,
        warmup,
        sizes,
        steps,
        rounds,
        drift_steps,
        threads,
    })
}

fn main() {
    // The child of `--chart` that measures one engine's memory.
    let argv: Vec<String> = std::env::args().collect();
    if argv.get(1).map(String::as_str) == Some("--memory-of") {
        let n = argv.get(3).and_then(|n| n.parse().ok()).unwrap_or(0);
        if let Err(e) = chart::memory_of(argv.get(2).map_or("", String::as_str), n) {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
        return;
    }
    let Args {
        chart,
        rapier_max,
        warmup,
        mut sizes,
        steps,
        rounds,
        drift_steps,
        threads,
    } = match parse(std::env::args().skip(1)) {
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
    if let Some(prefix) = chart {
        if sizes.is_empty() {
            sizes = vec![1_000, 10_000, 100_000, 1_000_000];
        }
        let rows = chart::measure(&sizes, steps, rounds, rapier_max, warmup);
        chart::print_table(&rows);
        if let Err(e) = chart::draw_files(&rows, &prefix) {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
        return;
    }
    if sizes.is_empty() {
        sizes = vec![1_000, 10_000, 100_000];
    }
    if let Err(e) = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
    {
        eprintln!("error: cannot start {threads} threads: {e}");
        std::process::exit(1);
    }
    println!("critterbox on {threads} thread(s), rapier2d-f64 on one\n");
    println!("| N | critterbox ms/step | rapier2d-f64 ms/step | rapier / critterbox | critterbox KE drift | rapier KE drift |");
    println!("|---|---|---|---|---|---|");
    for &n in &sizes {
        let params = GasParams {
            n,
            ..GasParams::default()
        };
        let mut ours = gas::<DVec2>(&params).expect("the gas builds");
        let mut theirs = Rapier::from(&Bodies::of(&ours));
        // Energy drift over `drift_steps` steps, from the same start.
        let (e0_ours, e0_theirs) = (ours.kinetic_energy(), theirs.energy());
        let (mut t_ours, mut t_theirs) = (Vec::new(), Vec::new());
        let mut done = 0;
        for _ in 0..rounds {
            let t = Instant::now();
            for _ in 0..steps {
                ours.step().expect("critterbox steps");
            }
            t_ours.push(t.elapsed().as_secs_f64() * 1e3 / steps as f64);
            let t = Instant::now();
            for _ in 0..steps {
                theirs.step();
            }
            t_theirs.push(t.elapsed().as_secs_f64() * 1e3 / steps as f64);
            done += steps;
        }
        while done < drift_steps {
            ours.step().expect("critterbox steps");
            theirs.step();
            done += 1;
        }
        let drift_ours = (ours.kinetic_energy() - e0_ours) / e0_ours;
        let drift_theirs = (theirs.energy() - e0_theirs) / e0_theirs;
        let (a, b) = (median(t_ours), median(t_theirs));
        println!(
            "| {n} | {a:.3} | {b:.3} | {:.1} | {drift_ours:+.1e} over {done} steps | {drift_theirs:+.1e} over {done} steps |",
            b / a
        );
    }
}
