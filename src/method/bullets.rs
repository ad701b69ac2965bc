//! `auto`'s bullets: under gravity, the few critters so fast that even the solve's most
//! substeps would let them pass through a wall or a disk (Box2D marks such bodies as bullets
//! and gives them a continuous pass after its solver).
//!
//! Sweeping the whole scene for their sake flies every resting contact of a pile as events,
//! hundreds of times the cost of solving it. Instead the step is taken without the bullets
//! (the rest solved, or split into islands, as usual), and then each bullet, in slot order, is
//! flown alone from where it was, after gravity's kick, over the whole step: its times of
//! impact against the walls and against every other critter where the step left it, in time
//! order. At each impact the pair goes to its rule and `collide` hook as in any flight, with
//! both critters' velocities, so a struck disk takes its share of the momentum; it moves on
//! with it from the next step. A bullet that meets a critter it no longer approaches (that
//! critter was pushed away faster than the bullet follows) stops there for the rest of the
//! step, as Box2D's continuous pass stops a body at its time of impact. So no bullet passes
//! through anything the step left in place. Two bullets do not see each other.

use crate::critter::CLASS_UNSET;
use crate::error::Error;
use crate::method::auto::{MOST_SOLVE_SUBSTEPS, SOLVE_FRACTION};
use crate::method::flight::SKIN;
use crate::method::toi::{toi_ball_ball, toi_wall_ball};
use crate::rules::roles_order;
use crate::step::span::Span;
use crate::step::state::{at_step, State};
use crate::step::stats::StepStats;
use crate::vector::Vector;

/// Bullets are at most this share of the moving critters; a scene with more is swept whole.
pub const BULLET_SHARE: f64 = 0.125;

/// A bullet's impacts in one step at most; after them it stops for the rest of the step.
pub const MOST_BULLET_IMPACTS: u32 = 32;

/// The bullets of the coming step (by slot, ascending): the critters whose tunnel fraction
/// (`auto::tunnel_fraction`) is beyond what the solve's most substeps keep from tunnelling.
/// True when bullets apply: some are found, they are at most [`BULLET_SHARE`] of the moving
/// critters, and the border does not wrap (a bullet's flight is not carried across it).
pub(crate) fn find<V: Vector>(state: &State<V>, dt: f64, out: &mut Vec<u32>) -> bool {
    out.clear();
    if state.topo.wraps() {
        return false;
    }
    let scale = crate::method::swept::motion_scale(state, dt);
    let spare = (0.5 * scale.thinnest_wall).min(scale.smallest_radius);
    let limit = SOLVE_FRACTION * f64::from(MOST_SOLVE_SUBSTEPS);
    let mut moving = 0usize;
    for (i, c) in state.critters.slot_slice().iter().enumerate() {
        let Some(c) = c
            .as_ref()
            .filter(|c| c.in_play() && !c.is_wall() && !c.fixed)
        else {
            continue;
        };
        moving += 1;
        let fraction = crate::method::swept::displacement(state, c, dt) / (c.radius + spare);
        // A NaN speed counts as a bullet: its flight finds no impact and changes nothing else.
        if fraction.is_nan() || fraction > limit {
            out.push(i as u32);
        }
    }
    !out.is_empty() && (out.len() as f64) <= BULLET_SHARE * moving as f64
}

/// What a bullet's flight met first.
#[derive(Clone, Copy)]
struct Hit {
    time: f64,
    slot: u32,
}

/// Flies each bullet of `bullets` (slots) alone over the step against the rest where the step
/// left it (see the module docs).
pub(crate) fn fly<V: Vector>(
    state: &mut State<V>,
    span: Span,
    bullets: &[u32],
    is_bullet: &[bool],
    stats: &mut StepStats,
) -> Result<(), Error> {
    let walls: Vec<u32> = state
        .critters
        .slot_slice()
        .iter()
        .enumerate()
        .filter(|(_, c)| c.as_ref().is_some_and(|c| c.in_play() && c.is_wall()))
        .map(|(i, _)| i as u32)
        .collect();
    let (g, dt) = (state.gravity, span.dt);
    let mut near = Vec::new();
    for &b in bullets {
        match state.critters.slot_mut_moving(b) {
            Some(c) if c.in_play() => c.vel += g * dt,
            _ => continue,
        }
        let mut left = dt;
        let mut impacts = 0;
        // Critters this bullet touched whose pair did not collide: it passes through them.
        let mut passed: Vec<u32> = Vec::new();
        while left > 0.0 {
            let Some(c) = state.critters.slot(b).filter(|c| c.in_play()) else {
                break;
            };
            let (p, v, r) = (c.pos, c.vel, c.radius);
            gather(state, b, p, v, left, r, is_bullet, &mut near);
            near.retain(|o| !passed.contains(o));
            let first = earliest(state, p, v, r, left, &walls, &near);
            let Some(hit) = first else {
                if let Some(c) = state.critters.slot_mut_moving(b) {
                    c.pos = p + v * left;
                }
                break;
            };
            if let Some(c) = state.critters.slot_mut_moving(b) {
                c.pos = p + v * hit.time;
            }
            left -= hit.time;
            if impacts == MOST_BULLET_IMPACTS || !approaching(state, b, hit.slot) {
                break; // it stays here for the rest of the step
            }
            impacts += 1;
            stats.contacts += 1;
            stats.events += 1;
            if collide(state, b, hit.slot)? {
                stats.collisions += 1;
            } else {
                passed.push(hit.slot);
            }
        }
        let topo = state.topo;
        if let Some(c) = state.critters.slot_mut_moving(b).filter(|c| c.in_play()) {
            let e = c.restitution();
            (c.pos, c.vel) = topo.apply(c.pos, c.vel, c.radius, e);
        }
    }
    state.neighbours.invalidate();
    Ok(())
}

/// The critters other than bullets and walls whose centres the bullet at `p` moving `v` for
/// `left` may come within reach of (the neighbour grid's cells along its path), in `out`,
/// ascending.
#[allow(clippy::too_many_arguments)]
fn gather<V: Vector>(
    state: &mut State<V>,
    me: u32,
    p: V,
    v: V,
    left: f64,
    r: f64,
    is_bullet: &[bool],
    out: &mut Vec<u32>,
) {
    out.clear();
    let half = v * (0.5 * left);
    let reach = half.length() + r;
    let at = crate::step::neighbours::Scope {
        critters: &state.critters,
        kinds: &state.kinds,
        topo: &state.topo,
    };
    state.neighbours.any_overlapping(at, p + half, reach, |c| {
        let slot = c.id.index;
        if slot != me && c.in_play() && !is_bullet.get(slot as usize).copied().unwrap_or(false) {
            out.push(slot);
        }
        false
    });
    out.sort_unstable();
}

/// The first impact within `left` of a disk at `p` moving `v` (radius `r`) against the walls
/// and the critters `near`, held where they are; ties go to the lower slot.
fn earliest<V: Vector>(
    state: &State<V>,
    p: V,
    v: V,
    r: f64,
    left: f64,
    walls: &[u32],
    near: &[u32],
) -> Option<Hit> {
    let topo = &state.topo;
    let mut best: Option<Hit> = None;
    let mut offer = |time: Option<f64>, slot: u32| {
        if let Some(time) = time.filter(|&t| t <= left) {
            if best.is_none_or(|b| time < b.time || (time == b.time && slot < b.slot)) {
                best = Some(Hit { time, slot });
            }
        }
    };
    for &w in walls {
        let Some(c) = state.critters.slot(w) else {
            continue;
        };
        if let crate::critter::Shape::Wall(wall) = c.shape() {
            offer(
                toi_wall_ball(wall, topo.delta(c.pos, p), v, r * (1.0 - SKIN)),
                w,
            );
        }
    }
    for &o in near {
        let Some(c) = state.critters.slot(o) else {
            continue;
        };
        let r_sum = (r + c.radius) * (1.0 - SKIN);
        offer(toi_ball_ball(topo.delta(p, c.pos), -v, r_sum), o);
    }
    best
}

/// True when the bullet `b` and the critter `o` it touches approach each other at their
/// velocities (a wall or fixed critter by the bullet's alone).
fn approaching<V: Vector>(state: &State<V>, b: u32, o: u32) -> bool {
    let (Some(cb), Some(co)) = (state.critters.slot(b), state.critters.slot(o)) else {
        return false;
    };
    if co.is_wall() {
        return true; // the time of impact found it approaching
    }
    let d = state.topo.delta(cb.pos, co.pos);
    (co.vel - cb.vel).dot(d) < 0.0
}

/// Hands the pair to its rule and `collide` hook, as a flight does: true when it collided
/// (false when the rule keeps the two apart or the hook let the pair be).
fn collide<V: Vector>(state: &mut State<V>, b: u32, o: u32) -> Result<bool, Error> {
    let step = state.step_count;
    for x in [b, o] {
        // A bullet was out of the step that sets the classes the rules are cached by.
        if let Some(c) = state.critters.slot_mut_moving(x) {
            if c.class == CLASS_UNSET {
                c.class = state.rules.class_of(&state.kinds, c);
            }
        }
    }
    let (Some(cb), Some(co)) = (state.critters.slot(b), state.critters.slot(o)) else {
        return Ok(false);
    };
    let rule = match state
        .rules
        .rule(&state.kinds, &state.topo, cb, co)
        .map_err(|e| at_step(e, step))?
    {
        Some(r) => r,
        None => crate::rules::roles_of(&state.kinds, &state.topo, cb, co)
            .map_err(|e| at_step(e, step))?,
    };
    let Some((caller, arg)) = roles_order(rule, cb, co) else {
        return Ok(false);
    };
    let (caller, arg) = (caller.id.index, arg.id.index);
    state.collide_pair(caller, arg)
}
