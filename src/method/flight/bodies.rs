//! What the flight knows of each critter, kept compact and contiguous beside the critters (which
//! are large and scattered), and each critter's own clock.

use super::Scratch;
use crate::step::state::State;
use crate::vector::Vector;

/// What predictions read about a critter; refreshed whenever the flight or a hook changes the
/// critter. 48 bytes in 2D, one cache line in 3D: what a pair test reads and nothing else.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Body<V: Vector> {
    pub(super) pos: V,
    pub(super) vel: V,
    /// The body's own clock: `pos` and `vel` hold at this time.
    pub(super) t: f64,
    /// The radius of a live disk; NaN for a wall or a dead critter (one test sends those to
    /// the general path).
    pub(super) radius: f64,
    _align: [V::BodyAlign; 0],
}

/// The rest of what the flight knows about a critter (16 bytes: one never straddles two
/// cache lines).
#[derive(Clone, Copy, Debug, Default)]
#[repr(align(16))]
pub(super) struct Status {
    /// Accelerates with the flight's gravity (free disks).
    pub(super) free: bool,
    pub(super) in_play: bool,
    pub(super) wall: bool,
    /// The critter's rule class (pair rules are looked up by class).
    pub(super) class: u32,
    /// How many times its flight has changed (collisions, bounces): an event predicted with
    /// another count is stale. Kept here, beside what a validity check reads anyway.
    pub(super) changes: u32,
}

/// A critter's position, velocity and acceleration at one time: what a prediction starts from.
#[derive(Clone, Copy, Debug)]
pub(super) struct Motion<V> {
    pub(super) pos: V,
    pub(super) vel: V,
    pub(super) acc: V,
}

/// Copies critter `a` into its body (after the flight or a hook changed it).
#[inline]
pub(super) fn refresh_body<V: Vector>(state: &State<V>, sc: &mut Scratch<V>, a: u32) {
    // Field by field into place: a body built whole on the stack and copied is read back
    // across two of its stores (a stall on every collision).
    let (body, status) = (&mut sc.body[a as usize], &mut sc.status[a as usize]);
    match state.critters.slot(a) {
        Some(c) => {
            body.pos = c.pos;
            body.vel = c.vel;
            body.radius = if c.in_play() && !c.is_wall() {
                c.radius
            } else {
                f64::NAN
            };
            status.free = !c.fixed && !c.is_wall();
            status.in_play = c.in_play();
            status.wall = c.is_wall();
            status.class = c.class;
        }
        None => {
            *body = Body {
                radius: f64::NAN,
                ..Body::default()
            };
            *status = Status {
                changes: status.changes,
                ..Status::default()
            };
        }
    }
    let radius = body.radius;
    if let Some(c) = sc.shell_centres.get_mut(a as usize) {
        c.radius = radius; // (unread without shells)
    }
}

/// The motion of body `a` at time `t` (its own clock is `body.t`).
#[inline(always)]
pub(super) fn motion_at<V: Vector>(sc: &Scratch<V>, a: u32, t: f64) -> Motion<V> {
    let b = &sc.body[a as usize];
    if sc.straight {
        // A line: no zero acceleration to multiply and add (a pair test's most common call).
        return Motion {
            pos: b.pos + b.vel * (t - b.t),
            vel: b.vel,
            acc: V::zero(),
        };
    }
    let acc = if !sc.status[a as usize].free {
        V::zero()
    } else {
        sc.acc
    };
    let h = t - b.t;
    if h == 0.0 {
        return Motion {
            pos: b.pos,
            vel: b.vel,
            acc,
        };
    }
    Motion {
        pos: b.pos + b.vel * h + acc * (0.5 * h * h),
        vel: b.vel + acc * h,
        acc,
    }
}

/// Brings critter `a` (and its body) to time `t` along its flight.
pub(super) fn advance<V: Vector>(state: &mut State<V>, sc: &mut Scratch<V>, a: u32, t: f64) {
    let s = sc.status[a as usize];
    if !s.in_play || s.wall {
        return;
    }
    let Motion { pos, vel, .. } = motion_at(sc, a, t);
    let body = &mut sc.body[a as usize];
    body.pos = pos;
    body.vel = vel;
    body.t = t;
    if let Some(c) = state.critters.slot_mut_moving(a) {
        c.pos = pos;
        c.vel = vel;
    }
}
