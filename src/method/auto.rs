//! `auto`: the cheapest method that keeps the scene's tolerances, decided each step and per
//! critter.
//!
//! The discrete step is exact enough while no critter moves more than a fraction of the smallest
//! radius or wall thickness per step (`docs/stability.md` measures where it starts to tunnel).
//! Beyond that the step is swept. In a sparse scene (disks cover less than [`SPARSE`] of the
//! box) it is swept per critter ([`crate::method::swept::step_where_needed`]): a slow critter
//! that can meet nothing along its line this step makes no prediction until a collision changes
//! its flight. The events are the swept step's, so the accuracy is too; a few bullets among many
//! spread-out slow critters cost the bullets' predictions, not everyone's. In a dense scene
//! nearly every critter has something within reach, and the check would only add its cost (and
//! wider cells), so everyone would be swept; without gravity nothing rests there, and the
//! event-driven step flies the same events without the swept step's closing discrete pass, so
//! the step is `event` (the chart's gas: the same error at event's cost, where swept costs 1.2
//! to 1.3 times more). Under gravity a step too fast for solved substeps stays swept, since
//! resting contacts are the event step's worst case.
//!
//! Under gravity, critters come to rest on each other, and the discrete step lets stacks sink
//! into themselves (the deep pile of `docs/stability.md`: 1.92 radii after 2 s). So a step under
//! gravity is solved, `solve:8`, at about the discrete step's cost (0.036 radii there), and its
//! islands at rest sleep. Eight sweeps carry a pile about 16 contacts deep; a deeper one gets one
//! sweep more per [`LAYERS_PER_SWEEP`] layers, up to [`AUTO_MOST_SWEEPS`], counted by the solve
//! each time ([`Sweeps::ByDepth`]): without them a 90-layer pile never comes to rest, and never
//! sleeps. So that no critter can tunnel, the solved step is cut into as many
//! substeps as keep each critter under half of what would carry it through a wall or a disk in
//! one substep ([`tunnel_fraction`]), up to [`MOST_SOLVE_SUBSTEPS`]; a step that would need more
//! is swept. A heap falling fast is then solved as it lands: swept, a dense heap runs out of the
//! swept step's event budget every step, and its discrete substeps let the heap sink into itself
//! and through the floor. A pair that
//! meets alone gets Pop's impulse from the solve, and a step with no contacts builds nothing to
//! solve. Critters sliding down a pile move faster than the sweep threshold, which guards the
//! angles of glancing hits; the solve's angles are the discrete step's, and it is the stack that
//! matters there.
//! Without gravity nothing rests, and `solve:n` would spread a Newton's cradle's momentum over
//! its balls: the step stays discrete.

use crate::method::solve::{Sweeps, LAYERS_PER_SWEEP};
use crate::method::swept::{count_fast, displacement, motion_scale, MotionScale, SWEEP_FRACTION};
use crate::method::Method;
use crate::vector::Vector;
use crate::world::World;

/// The sweeps of the `solve:n` step `auto` takes under gravity (the stability table's
/// `solve:8`), at least.
pub const AUTO_SWEEPS: u32 = 8;

/// The most sweeps of `auto`'s solve: beyond [`AUTO_SWEEPS`] a pile gets one sweep per
/// [`LAYERS_PER_SWEEP`] layers of weight-bearing contacts, as a deep pile needs to carry
/// its weight.
pub const AUTO_MOST_SWEEPS: u32 = 64;

/// Below this packing fraction (disk area, or sphere volume, over the box's) a swept step is
/// taken per critter.
pub const SPARSE: f64 = 0.05;

/// The fraction of the box the live disks cover.
pub fn packing<V: Vector>(world: &World<V>) -> f64 {
    let size = world.topo.size();
    let volume: f64 = (0..V::DIM).map(|axis| size.get(axis)).product();
    let unit = if V::DIM == 2 {
        std::f64::consts::PI
    } else {
        4.0 / 3.0 * std::f64::consts::PI
    };
    let disks = world.critters.iter().filter(|c| c.alive && !c.is_wall());
    let covered: f64 = disks.map(|c| unit * c.radius.powi(V::DIM as i32)).sum();
    covered / volume
}

/// The sweeps of `auto`'s solve.
const AUTO: Sweeps = Sweeps::ByDepth {
    least: AUTO_SWEEPS,
    most: AUTO_MOST_SWEEPS,
};

/// What `auto` takes for the coming step.
pub struct Choice {
    /// Discrete, swept, event or `solve:8`.
    pub method: Method,
    /// A swept step taken per critter (a sparse scene).
    pub per_critter: bool,
    /// Substeps of a solved step (1 otherwise).
    pub substeps: u32,
    /// Sweeps of a solved step.
    pub sweeps: Sweeps,
    /// Why, for `critterbox run`.
    pub why: String,
}

/// A step under gravity is solved in as many substeps as keep each substep's
/// [`tunnel_fraction`] under this.
pub const SOLVE_FRACTION: f64 = 0.5;

/// The most substeps of a solved step; a step that would need more is swept.
pub const MOST_SOLVE_SUBSTEPS: u32 = 8;

/// The largest fraction, over the critters, of what would carry a critter through something in
/// the coming step: its centre must pass a wall's mid-plane (its radius plus half the thinnest
/// wall), or another disk's centre (the two radii). Each critter is measured against its radius
/// plus the smaller of half the thinnest wall and the smallest radius, so that two critters
/// under half their own bounds together move less than their two radii. 0 with nothing moving.
/// `scale` is the world's [`motion_scale`].
pub fn tunnel_fraction<V: Vector>(world: &World<V>, scale: &MotionScale) -> f64 {
    let spare = (0.5 * scale.thinnest_wall).min(scale.smallest_radius);
    let disks = world.critters.iter().filter(|c| c.alive && !c.is_wall());
    disks
        .map(|c| displacement(world, c) / (c.radius + spare))
        .fold(0.0, f64::max)
}

/// The method for the coming step and why.
pub fn choose<V: Vector>(world: &World<V>) -> Choice {
    let scale = motion_scale(world);
    let (fastest, smallest) = (scale.fastest, scale.smallest());
    let limit = SWEEP_FRACTION * smallest;
    let falling = world.gravity() != V::zero();
    let tunnel = if falling {
        tunnel_fraction(world, &scale)
    } else {
        1.0
    };
    if falling && tunnel <= SOLVE_FRACTION * f64::from(MOST_SOLVE_SUBSTEPS) {
        // Integer-valued and from 1 to MOST_SOLVE_SUBSTEPS: the cast is exact.
        let substeps = (tunnel / SOLVE_FRACTION).ceil().max(1.0) as u32;
        let how = match substeps {
            1 => format!("no critter moves more than {tunnel:.3e} of what would carry it through a wall or a disk (under {SOLVE_FRACTION})"),
            k => format!("the fastest critter moves {tunnel:.3e} of what would carry it through a wall or a disk, so the step is cut into {k} substeps of under {SOLVE_FRACTION} each"),
        };
        Choice {
            method: Method::Solve(AUTO_SWEEPS),
            per_critter: false,
            substeps,
            sweeps: AUTO,
            why: format!(
                "solve:{AUTO_SWEEPS}: under gravity critters come to rest on each other, and the discrete step would let them sink into each other; {how}; a pile more than {deep} contacts deep gets one sweep more per {per} layers (up to {AUTO_MOST_SWEEPS}), as its weight needs; {asleep} asleep",
                deep = AUTO_SWEEPS * LAYERS_PER_SWEEP,
                per = LAYERS_PER_SWEEP,
                asleep = world.sleepers()
            ),
        }
    } else if fastest <= limit {
        Choice {
            method: Method::Discrete,
            per_critter: false,
            substeps: 1,
            sweeps: AUTO,
            why: format!(
                "discrete: the fastest critter moves {fastest:.3e} per step, within {SWEEP_FRACTION} of the smallest radius or wall thickness ({smallest:.3e})"
            ),
        }
    } else {
        let (fast, all) = count_fast(world, limit);
        let phi = packing(world);
        let per_critter = phi < SPARSE;
        let slow = if per_critter {
            format!("the disks cover {phi:.3} of the box (under {SPARSE}), so the slow ones are swept only where something is within reach")
        } else {
            format!("the disks cover {phi:.3} of the box ({SPARSE} or more), so everyone is swept")
        };
        let fast_why = format!("the fastest critter moves {fastest:.3e} per step, more than {SWEEP_FRACTION} of the smallest radius or wall thickness ({smallest:.3e}), so discrete could tunnel; {fast} of {all} critters move that far");
        if !falling && !per_critter {
            // Everyone would be swept, and nothing rests: the event-driven step flies the same
            // events without the swept step's closing discrete pass.
            Choice {
                method: Method::Event,
                per_critter: false,
                substeps: 1,
                sweeps: AUTO,
                why: format!("event: {fast_why}; the disks cover {phi:.3} of the box ({SPARSE} or more), so everyone would be swept, and without gravity nothing rests: the exact event-driven step flies the same events without the swept step's closing discrete pass"),
            }
        } else {
            Choice {
                method: Method::Swept,
                per_critter,
                substeps: 1,
                sweeps: AUTO,
                why: format!("swept: {fast_why}; {slow}"),
            }
        }
    }
}
