//! The default collision response (Pop's `cCritter::collide`, with its failures fixed).
//!
//! Along the contact normal `n` (caller to arg), with relative velocity `v_rel = v_arg - v_caller`:
//!
//! * an impulse only while approaching (`v_rel . n < 0`), so separating pairs are never pulled back;
//! * one coefficient of restitution `e` (the smaller of the two) on the relative normal velocity:
//!   `J = -(1 + e)(v_rel . n) / (1/m_caller + 1/m_arg)`, which for `e = 1` is exactly Pop's 1-D
//!   elastic formula applied to the normal components, tangential parts untouched;
//! * fixed critters have inverse mass 0: they reflect what hits them and never move;
//! * overlap removed along the normal, split by inverse mass so the centre of mass stays put.

use crate::border::Topology;
use crate::contact::{contact_ball_ball, contact_wall_ball, Contact};
use crate::critter::{Critter, Shape};
use crate::vector::Vector;

/// What a default collision did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit<V> {
    /// Unit normal from caller to arg.
    pub normal: V,
    /// Contact point (world coordinates).
    pub point: V,
    /// Impulse given to the arg along the normal (the caller got its opposite); 0 when separating.
    pub impulse: f64,
    /// Overlap removed.
    pub depth: f64,
}

/// The contact between two critters, normal from `a` to `b`; `None` unless they touch.
#[inline]
pub fn contact_between<V: Vector>(
    topo: &Topology<V>,
    a: &Critter<V>,
    b: &Critter<V>,
) -> Option<Contact<V>> {
    let d = topo.delta(a.pos, b.pos);
    if !a.wall && !b.wall {
        // Two disks: the shapes (in the traits) need not be read.
        return contact_ball_ball(d, a.radius, b.radius);
    }
    match (a.shape(), b.shape()) {
        (Shape::Disk, Shape::Disk) => contact_ball_ball(d, a.radius, b.radius),
        (Shape::Wall(w), Shape::Disk) => contact_wall_ball(w, d, b.radius),
        (Shape::Disk, Shape::Wall(w)) => contact_wall_ball(w, -d, a.radius).map(|c| Contact {
            normal: -c.normal,
            depth: c.depth,
            point: c.point + d,
        }),
        (Shape::Wall(_), Shape::Wall(_)) => None,
    }
}

/// True when two different critters touch now.
pub fn touches<V: Vector>(topo: &Topology<V>, a: &Critter<V>, b: &Critter<V>) -> bool {
    a.id != b.id && contact_between(topo, a, b).is_some()
}

/// Pop's `contains`: disk `inner` lies wholly inside disk `outer` (false for walls).
pub fn contains<V: Vector>(topo: &Topology<V>, outer: &Critter<V>, inner: &Critter<V>) -> bool {
    outer.id != inner.id
        && !outer.is_wall()
        && !inner.is_wall()
        && crate::contact::contains_ball_ball(
            topo.delta(outer.pos, inner.pos),
            outer.radius,
            inner.radius,
        )
}

/// Applies the impulse and separation for a contact `c` (normal from `caller` to `arg`).
///
/// Returns the impulse magnitude given to `arg` along the normal.
#[inline]
pub fn respond<V: Vector>(caller: &mut Critter<V>, arg: &mut Critter<V>, c: &Contact<V>) -> f64 {
    let (im1, im2) = (caller.inv_mass(), arg.inv_mass());
    let im = im1 + im2;
    if im == 0.0 {
        return 0.0; // two fixed critters: nothing can move
    }
    let n = c.normal;
    let vn = (arg.vel - caller.vel).dot(n);
    let mut j = 0.0;
    if vn < 0.0 {
        let e = caller.restitution().min(arg.restitution());
        j = -(1.0 + e) * vn / im;
        caller.vel -= n * (j * im1);
        arg.vel += n * (j * im2);
    }
    if c.depth > 0.0 {
        let push = c.depth / im;
        caller.pos -= n * (push * im1);
        arg.pos += n * (push * im2);
    }
    j
}

/// Pop's default collide: if the two touch, respond and report what happened.
#[inline]
pub fn collide_default<V: Vector>(
    topo: &Topology<V>,
    caller: &mut Critter<V>,
    arg: &mut Critter<V>,
) -> Option<Hit<V>> {
    let c = contact_between(topo, caller, arg)?;
    let point = caller.pos + c.point;
    let impulse = respond(caller, arg, &c);
    Some(Hit {
        normal: c.normal,
        point,
        impulse,
        depth: c.depth,
    })
}
