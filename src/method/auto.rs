//! `auto`: the cheapest method that keeps the scene's tolerances, chosen each step (`choose`).
//! Under gravity `MethodState::plan` first cuts the critters into islands (`method::islands`):
//! islands of impacts in flight take `event`, and `choose` decides for the rest.
//!
//! * **Under gravity** critters come to rest on each other, and the discrete step lets stacks
//!   sink into themselves, so the step is solved: `solve:8`, with one sweep more per
//!   [`LAYERS_PER_SWEEP`] layers of a pile deeper than eight sweeps carry, up to
//!   [`AUTO_MOST_SWEEPS`] ([`Sweeps::ByDepth`]); its islands at rest sleep. So that nothing
//!   tunnels, the solved step is cut into as many substeps as keep every critter under
//!   [`SOLVE_FRACTION`] of what would carry it through a wall or a disk (`tunnel_fraction`),
//!   up to [`MOST_SOLVE_SUBSTEPS`]. Critters that would need more are bullets: while they are
//!   few, the step is taken without them and they are flown after it (`method::bullets`);
//!   otherwise the step is swept (resting contacts are the event step's worst case), and in a
//!   sparse scene (disks cover less than [`SPARSE`] of the box) only the critters that are
//!   fast or may meet something along their line predict.
//! * **Without gravity** nothing rests, and a solve would spread a Newton's cradle's momentum
//!   over its balls, so the step is never solved. It is `event`, exact, with its flight kept
//!   from step to step so that a step pays for its events, not for predicting everyone anew.
//!   The one exception is a slow step (no critter moves more than `SWEEP_FRACTION` of the
//!   smallest radius or wall thickness) in a scene where something outside the flight (hooks
//!   steering critters, critters coming and going) changed more than
//!   `flight::CHURN` of the critters since the last step: a kept flight would
//!   predict them all again every step, so such a step is discrete, which does not tunnel at
//!   that speed, until the next step where a flight is set up on schedule.
//!
//! `docs/methods.md` has the measured figures behind these thresholds, and
//! `docs/stability.md` where each fixed method fails.

use crate::method::flight;
use crate::method::solve::{Sweeps, LAYERS_PER_SWEEP};
use crate::method::swept::{count_fast, displacement, motion_scale, MotionScale, SWEEP_FRACTION};
use crate::method::Method;
use crate::step::state::State;
use crate::vector::Vector;

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
pub(crate) fn packing<V: Vector>(state: &State<V>) -> f64 {
    let size = state.topo.size();
    let volume: f64 = (0..V::DIM).map(|axis| size.get(axis)).product();
    let unit = if V::DIM == 2 {
        std::f64::consts::PI
    } else {
        4.0 / 3.0 * std::f64::consts::PI
    };
    let disks = state
        .critters
        .iter()
        .filter(|c| c.in_play() && !c.is_wall());
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
    /// A swept step taken per critter (a sparse scene under gravity).
    pub per_critter: bool,
    /// Substeps of a solved step (1 otherwise).
    pub substeps: u32,
    /// Sweeps of a solved step.
    pub sweeps: Sweeps,
    /// Why, for `critterbox run`.
    pub why: Why,
}

/// Why `auto` took its method: the figures it decided on. It is written out only when asked
/// (`Display`), since formatting them every step would cost a small scene a fifth of its step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Why {
    /// Solved under gravity, in `substeps` substeps.
    Solve {
        /// The largest `tunnel_fraction` of the step.
        tunnel: f64,
        /// The substeps that keep each under [`SOLVE_FRACTION`].
        substeps: u32,
        /// Critters asleep when the step began.
        asleep: usize,
    },
    /// Discrete: nobody moves far enough to tunnel, and the event step's flight could not be
    /// kept from step to step in the last steps (critters changed between them).
    Discrete {
        /// The largest displacement of a disk in the step.
        fastest: f64,
        /// The smallest radius or wall thickness.
        smallest: f64,
    },
    /// Event, though nobody moves far enough to tunnel: without gravity the event step, its
    /// flight kept from step to step, costs about what the discrete step does, and is exact.
    Calm {
        /// The largest displacement of a disk in the step.
        fastest: f64,
        /// The smallest radius or wall thickness.
        smallest: f64,
    },
    /// Swept or event: someone moves far enough to tunnel.
    Fast {
        /// The largest displacement of a disk in the step.
        fastest: f64,
        /// The smallest radius or wall thickness.
        smallest: f64,
        /// Disks that move more than `SWEEP_FRACTION` of `smallest`.
        fast: usize,
        /// All disks.
        all: usize,
        /// The fraction of the box the disks cover.
        packing: f64,
        /// Without gravity: the event step, which flies the swept step's events.
        event: bool,
    },
    /// Event under gravity: no island rests on anything and some hold impacts between critters
    /// in flight (see `method::islands`).
    Impacts {
        /// The islands.
        islands: usize,
        /// The critters in them.
        critters: usize,
    },
}

impl std::fmt::Display for Why {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Why::Solve {
                tunnel,
                substeps,
                asleep,
            } => {
                write!(f, "solve:{AUTO_SWEEPS}: under gravity critters come to rest on each other, and the discrete step would let them sink into each other; ")?;
                match substeps {
                    1 => write!(f, "no critter moves more than {tunnel:.3e} of what would carry it through a wall or a disk (under {SOLVE_FRACTION})")?,
                    k => write!(f, "the fastest critter moves {tunnel:.3e} of what would carry it through a wall or a disk, so the step is cut into {k} substeps of under {SOLVE_FRACTION} each")?,
                }
                write!(
                    f,
                    "; a pile more than {deep} contacts deep gets one sweep more per {per} layers (up to {AUTO_MOST_SWEEPS}), as its weight needs; {asleep} asleep",
                    deep = AUTO_SWEEPS * LAYERS_PER_SWEEP,
                    per = LAYERS_PER_SWEEP,
                )
            }
            Why::Discrete { fastest, smallest } => write!(
                f,
                "discrete: the fastest critter moves {fastest:.3e} per step, within {SWEEP_FRACTION} of the smallest radius or wall thickness ({smallest:.3e}); the event step could not keep its flight from step to step here (more than {churn} of the critters changed between steps, or came or went), so it would cost several discrete steps",
                churn = crate::method::flight::CHURN
            ),
            Why::Calm { fastest, smallest } => write!(
                f,
                "event: the fastest critter moves {fastest:.3e} per step, within {SWEEP_FRACTION} of the smallest radius or wall thickness ({smallest:.3e}), so discrete would not tunnel either; without gravity the exact event step, its flight kept from step to step, costs about what the discrete step does"
            ),
            Why::Impacts { islands, critters } => write!(
                f,
                "event: under gravity, but none of the {islands} islands ({critters} critters) rests on a wall, a fixed critter or an edge, and in some two critters approach each other: their contacts are impacts between critters in flight, which only the exact event flight keeps (a solve would spread a cradle's momentum), and the others fly free, which it keeps exactly too"
            ),
            Why::Fast {
                fastest,
                smallest,
                fast,
                all,
                packing: phi,
                event,
            } => {
                let fast_why = format!("the fastest critter moves {fastest:.3e} per step, more than {SWEEP_FRACTION} of the smallest radius or wall thickness ({smallest:.3e}), so discrete could tunnel; {fast} of {all} critters move that far");
                let nothing_rests = "without gravity nothing rests: the exact event-driven step flies the swept step's events without its closing discrete pass, and keeps its flight for the next step";
                if event {
                    write!(f, "event: {fast_why}; {nothing_rests} (the disks cover {phi:.3} of the box)")
                } else if phi < SPARSE {
                    write!(f, "swept: {fast_why}; the disks cover {phi:.3} of the box (under {SPARSE}), so the slow ones are swept only where something is within reach")
                } else {
                    write!(f, "swept: {fast_why}; the disks cover {phi:.3} of the box ({SPARSE} or more), so everyone is swept")
                }
            }
        }
    }
}

/// A step under gravity is solved in as many substeps as keep each substep's
/// `tunnel_fraction` under this.
pub const SOLVE_FRACTION: f64 = 0.5;

/// The most substeps of a solved step; critters that would need more are bullets
/// (`method::bullets`), or the step is swept.
pub const MOST_SOLVE_SUBSTEPS: u32 = 8;

/// The largest fraction, over the critters, of what would carry a critter through something in
/// the coming step: its centre must pass a wall's mid-plane (its radius plus half the thinnest
/// wall), or another disk's centre (the two radii). Each critter is measured against its radius
/// plus the smaller of half the thinnest wall and the smallest radius, so that two critters
/// under half their own bounds together move less than their two radii. 0 with nothing moving.
/// `scale` is the world's [`motion_scale`].
pub(crate) fn tunnel_fraction<V: Vector>(state: &State<V>, scale: &MotionScale, dt: f64) -> f64 {
    let spare = (0.5 * scale.thinnest_wall).min(scale.smallest_radius);
    let disks = state
        .critters
        .iter()
        .filter(|c| c.in_play() && !c.is_wall());
    disks
        .map(|c| displacement(state, c, dt) / (c.radius + spare))
        .fold(0.0, f64::max)
}

/// The method for the coming step of `dt` and why, for `state` whose event flight is `flight`
/// and in which `asleep` critters sleep.
pub(crate) fn choose<V: Vector>(
    state: &State<V>,
    flight: &flight::Scratch<V>,
    asleep: usize,
    dt: f64,
) -> Choice {
    let scale = motion_scale(state, dt);
    let (fastest, smallest) = (scale.fastest, scale.smallest());
    let limit = SWEEP_FRACTION * smallest;
    let falling = state.gravity != V::zero();
    let tunnel = if falling {
        tunnel_fraction(state, &scale, dt)
    } else {
        1.0
    };
    if falling && tunnel <= SOLVE_FRACTION * f64::from(MOST_SOLVE_SUBSTEPS) {
        // Integer-valued and from 1 to MOST_SOLVE_SUBSTEPS: the cast is exact.
        let substeps = (tunnel / SOLVE_FRACTION).ceil().max(1.0) as u32;
        Choice {
            method: Method::Solve(AUTO_SWEEPS),
            per_critter: false,
            substeps,
            sweeps: AUTO,
            why: Why::Solve {
                tunnel,
                substeps,
                asleep,
            },
        }
    } else if fastest <= limit {
        // Without gravity (under it the step was solved above), the event step where its flight
        // can be kept: tried again from every step where a flight is set up on schedule, so the
        // choice does not depend on anything before such a step (a replay restores there).
        let calm = !falling && !flight.churned(state.step_count);
        Choice {
            method: if calm {
                Method::Event
            } else {
                Method::Discrete
            },
            per_critter: false,
            substeps: 1,
            sweeps: AUTO,
            why: if calm {
                Why::Calm { fastest, smallest }
            } else {
                Why::Discrete { fastest, smallest }
            },
        }
    } else {
        let (fast, all) = count_fast(state, limit, dt);
        let phi = packing(state);
        // Without gravity nothing rests: the event-driven step flies the same events without
        // the swept step's closing discrete pass, and keeps its flight for the next step.
        let event = !falling;
        let per_critter = phi < SPARSE && !event;
        Choice {
            method: if event { Method::Event } else { Method::Swept },
            per_critter,
            substeps: 1,
            sweeps: AUTO,
            why: Why::Fast {
                fastest,
                smallest,
                fast,
                all,
                packing: phi,
                event,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each reason names its method and the figures it was decided on, as `critterbox run`
    /// prints them.
    #[test]
    fn each_reason_names_its_method_and_its_figures() {
        let solve = Why::Solve {
            tunnel: 1.25,
            substeps: 3,
            asleep: 7,
        }
        .to_string();
        assert!(solve.starts_with("solve:8: "), "{solve}");
        assert!(solve.contains("1.250e0") && solve.contains("cut into 3 substeps"));
        assert!(solve.ends_with("7 asleep"), "{solve}");
        let discrete = Why::Discrete {
            fastest: 1.78e-3,
            smallest: 0.2,
        }
        .to_string();
        assert!(discrete.starts_with("discrete: "), "{discrete}");
        assert!(discrete.contains("1.780e-3") && discrete.contains("(2.000e-1)"));
        assert!(discrete.contains("could not keep its flight"), "{discrete}");
        let calm = Why::Calm {
            fastest: 1.78e-3,
            smallest: 0.2,
        }
        .to_string();
        assert!(calm.starts_with("event: "), "{calm}");
        assert!(calm.contains("1.780e-3") && calm.contains("(2.000e-1)"));
        assert!(calm.contains("kept from step to step"), "{calm}");
        let fast = |packing, event| {
            Why::Fast {
                fastest: 0.5,
                smallest: 0.2,
                fast: 3,
                all: 10,
                packing,
                event,
            }
            .to_string()
        };
        assert!(fast(0.3, true).starts_with("event: "));
        assert!(fast(0.01, true).starts_with("event: "));
        assert!(fast(0.01, true).contains("keeps its flight for the next step"));
        assert!(fast(0.01, true).contains("cover 0.010 of the box"));
        assert!(fast(0.3, false).contains("so everyone is swept"));
        assert!(fast(0.01, false).contains("swept only where something is within reach"));
        assert!(fast(0.3, true).contains("3 of 10 critters"));
    }
}
