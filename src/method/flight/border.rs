//! Border hits: a disk reaching a bounce or clamp border of the world box, predicted along its
//! flight and resolved by the border's rule.

use super::bodies::Motion;
use super::events::{offer, EventKind};
use super::{Scratch, BORDER_PARTNER};
use crate::border::Border;
use crate::method::toi::smallest_nonneg_root;
use crate::step::state::State;
use crate::vector::Vector;

/// Offers the border hits of disk `a` (`motion`: at `t`).
pub(super) fn predict_border<V: Vector>(
    state: &State<V>,
    sc: &mut Scratch<V>,
    a: u32,
    t: f64,
    motion: Motion<V>,
) {
    if state.topo.border == Border::Wrap {
        return;
    }
    let r = sc.body[a as usize].radius;
    let Motion { pos, vel, acc } = motion;
    let last = sc.last_partner[a as usize];
    for axis in 0..V::DIM {
        let lo = state.topo.min.get(axis) + r;
        let hi = state.topo.max.get(axis) - r;
        if lo > hi {
            continue;
        }
        let (x, vx, ax) = (pos.get(axis), vel.get(axis), acc.get(axis));
        for (side, bound) in [(0u32, lo), (1u32, hi)] {
            let outward = if side == 1 { 1.0 } else { -1.0 };
            // Distance to the bound, positive inside.
            let gap = (bound - x) * outward;
            let s = if gap <= 0.0 {
                on_bound(vx * outward, ax * outward)
            } else {
                smallest_nonneg_root(0.5 * ax * outward, vx * outward, -gap)
            };
            let tag = axis as u32 * 2 + side;
            if let Some(s) = s {
                if s == 0.0 && last == BORDER_PARTNER + tag {
                    continue;
                }
                if t + s <= sc.horizon {
                    offer(sc, t + s, a, tag, EventKind::Border);
                }
            }
        }
    }
}

/// When a critter on (or a hair past) a bound leaves through it, given its outward velocity
/// `v` and acceleration `a`: now if moving (or, at rest, accelerating) outward; after the
/// parabola returns, `-2 v / a`, if moving inward but accelerated outward; never otherwise.
pub(super) fn on_bound(v: f64, a: f64) -> Option<f64> {
    if v > 0.0 || (v == 0.0 && a > 0.0) {
        Some(0.0)
    } else if v < 0.0 && a > 0.0 {
        Some(-2.0 * v / a)
    } else {
        None
    }
}

/// Puts critter `a` on the border side `tag` (`axis * 2 + side`) and bounces it (or, on a clamp
/// border, stops it along the axis) if it moves outward.
pub(super) fn bounce_border<V: Vector>(state: &mut State<V>, a: u32, tag: u32) {
    let (axis, side) = ((tag / 2) as usize, tag % 2);
    let border = state.topo.border;
    let (lo, hi) = (state.topo.min.get(axis), state.topo.max.get(axis));
    let c = state.critters.slot_mut_moving(a).expect("live slot");
    let bound = if side == 1 {
        hi - c.radius
    } else {
        lo + c.radius
    };
    c.pos.set(axis, bound);
    let v = c.vel.get(axis);
    let outward = if side == 1 { v > 0.0 } else { v < 0.0 };
    if outward {
        match border {
            Border::Bounce => c.vel.set(axis, -c.restitution() * v),
            _ => c.vel.set(axis, 0.0),
        }
    }
}
