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
//! Usage: `cargo run --release -- [N ...] [--steps S] [--rounds R] [--drift-steps D]`

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

impl Rapier {
    fn from(world: &critterbox::World<DVec2>) -> Rapier {
        let mut bodies = RigidBodySet::new();
        let mut colliders = ColliderSet::new();
        let mut handles = Vec::new();
        for c in world.critters().iter() {
            if let Some(wall) = c.wall() {
                let body = bodies
                    .insert(RigidBodyBuilder::fixed().translation(Vector::new(c.pos.x, c.pos.y)));
                let collider = ColliderBuilder::cuboid(wall.half.x, wall.half.y)
                    .restitution(1.0)
                    .friction(0.0)
                    .restitution_combine_rule(CoefficientCombineRule::Max)
                    .friction_combine_rule(CoefficientCombineRule::Min);
                colliders.insert_with_parent(collider, body, &mut bodies);
                continue;
            }
            let body = bodies.insert(
                RigidBodyBuilder::dynamic()
                    .translation(Vector::new(c.pos.x, c.pos.y))
                    .linvel(Vector::new(c.vel.x, c.vel.y))
                    .lock_rotations(),
            );
            let collider = ColliderBuilder::ball(c.radius())
                .restitution(1.0)
                .friction(0.0)
                .restitution_combine_rule(CoefficientCombineRule::Max)
                .friction_combine_rule(CoefficientCombineRule::Min);
            colliders.insert_with_parent(collider, body, &mut bodies);
            handles.push(body);
        }
        let params = IntegrationParameters {
            dt: world.dt(),
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

  N                critter counts to compare (default: 1000 10000 100000)
  --steps S        steps per timed round (default 20)
  --rounds R       alternating rounds; the medians are reported (default 7)
  --drift-steps D  steps over which kinetic energy drift is measured (default 300)
  --threads T      critterbox's threads (default 1, as rapier here; its stages go parallel
                   from 20,000 critters)";

/// The command line.
struct Args {
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
            n => match n.parse::<usize>() {
                Ok(n) if n > 0 => sizes.push(n),
                _ => return Err(format!("unknown argument {n:?}")),
            },
        }
    }
    Ok(Args {
        sizes,
        steps,
        rounds,
        drift_steps,
        threads,
    })
}

fn main() {
    let Args {
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
        let mut theirs = Rapier::from(&ours);
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
