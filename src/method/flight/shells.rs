//! Smallenburg's neighbour shells (straight 3D flights without walls): each sphere lists the
//! spheres whose shells overlap its own, predicts against that list only, and is listed again
//! when it leaves its shell. The cells then hold each sphere by its shell's centre, for the
//! listing only.

use super::bodies::Motion;
use super::cells::{cell_of, cells_around, move_cell};
use super::{Scratch, ROUNDING_MARGIN};
use crate::border::Topology;
use crate::step::state::State;
use crate::vector::Vector;

/// A shell's centre and its critter's radius (the body's, kept equal by `refresh_body`; NaN for
/// walls and the dead): 32 bytes in 3D, aligned so that one is never split between two cache
/// lines (a listing reads one per candidate).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
pub(super) struct ShellCentre<V> {
    pub(super) pos: V,
    pub(super) radius: f64,
}

/// Lists every pair whose shells overlap (at the start of a flight, every shell is centred on
/// its critter).
pub(super) fn list_all_neighbours<V: Vector>(state: &State<V>, sc: &mut Scratch<V>) {
    let n = sc.body.len();
    sc.shell_centres.clear();
    sc.shell_centres.extend(sc.body.iter().map(|b| ShellCentre {
        pos: b.pos,
        radius: b.radius,
    }));
    // Room for the neighbours a random fluid at close packing would give, and some.
    sc.neighbours.reset(n, 24);
    let mut around = [0usize; 27];
    for a in 0..n as u32 {
        if sc.body[a as usize].radius.is_nan() {
            continue;
        }
        let count = cells_around(state, sc, a, &mut around);
        for &k in &around[..count] {
            for &b in sc.cells.members(k) {
                if b > a && shells_overlap(&state.topo, &sc.shell_centres, sc.shell_width, a, b) {
                    sc.neighbours.push(a as usize, b);
                    sc.neighbours.push(b as usize, a);
                }
            }
        }
    }
}

/// Whether the shells of `a` and `b` (a live disk) overlap: only such pairs can touch before
/// one of them leaves its shell. Takes the flight's fields rather than the flight, so that the
/// listing can push to `neighbours` while it walks `cells`.
#[inline]
fn shells_overlap<V: Vector>(
    topo: &Topology<V>,
    centres: &[ShellCentre<V>],
    shell_width: f64,
    a: u32,
    b: u32,
) -> bool {
    let (ca, cb) = (centres[a as usize], centres[b as usize]);
    // (A NaN radius, a wall's or the dead's, makes `reach` NaN and the test false.)
    let reach = (ca.radius + cb.radius + shell_width) * (1.0 + ROUNDING_MARGIN);
    topo.delta(ca.pos, cb.pos).length_squared() < reach * reach
}

/// Lists `a` again, centring its shell on where it is now (its body holds now): it empties its
/// list, moves to the cell of its new centre, and lists the critters whose shells overlap the
/// new one (and joins their lists). Its flight is unchanged, so no event is made stale.
pub(super) fn relist<V: Vector>(state: &mut State<V>, sc: &mut Scratch<V>, a: u32) {
    let ai = a as usize;
    // The old neighbours keep `a` in their lists until they list again themselves: a pair
    // test too many costs less than finding `a` in every old list.
    sc.neighbours.clear(ai);
    let old = sc.cell[ai] as usize;
    if sc.body[ai].radius.is_nan() {
        sc.cells.remove(old, a);
        return;
    }
    let mut p = sc.body[ai].pos;
    if state.topo.wraps() {
        let q = state.topo.wrap_position(p);
        if q != p {
            p = q;
            sc.body[ai].pos = p;
            if let Some(c) = state.critters.slot_mut_moving(a) {
                c.pos = p;
            }
        }
    }
    sc.shell_centres[ai] = ShellCentre {
        pos: p,
        radius: sc.body[ai].radius,
    };
    let (new, cc) = cell_of(state, sc, p);
    move_cell(sc, a, old, new, cc);
    let mut around = [0usize; 27];
    let count = cells_around(state, sc, a, &mut around);
    // The loads are scattered, so each stage asks for what the next one reads before it
    // reads any: the cells' stripes, then the candidates' shell centres (with their radii),
    // then the new neighbours' lists.
    use crate::prefetch::prefetch;
    for &k in &around[..count] {
        prefetch(sc.cells.head(k));
    }
    let mut gathered = std::mem::take(&mut sc.gathered);
    gathered.clear();
    for &k in &around[..count] {
        gathered.extend_from_slice(sc.cells.members(k));
    }
    for &b in &gathered {
        prefetch(sc.shell_centres.get(b as usize));
    }
    // The candidates kept in place, without a branch on each (few are kept, in no order a
    // processor can predict).
    let mut kept = 0;
    for i in 0..gathered.len() {
        let b = gathered[i];
        let hit = (b != a) & shells_overlap(&state.topo, &sc.shell_centres, sc.shell_width, a, b);
        gathered[kept] = b;
        kept += usize::from(hit);
    }
    gathered.truncate(kept);
    for &b in &gathered {
        prefetch(sc.neighbours.head(b as usize));
    }
    for &b in &gathered {
        sc.neighbours.push(ai, b);
    }
    // `a`'s new neighbours, each joined by `a` unless it kept `a` from before.
    // (By index: a push may grow the stripes and move `a`'s.)
    for j in 0..sc.neighbours.members(ai).len() {
        let b = sc.neighbours.members(ai)[j] as usize;
        if !sc.neighbours.members(b).contains(&a) {
            sc.neighbours.push(b, a);
        }
    }
    sc.gathered = gathered;
}

/// The time straight-flying `a` (`motion`: at `t`) leaves its shell, if that is within the
/// flight.
#[inline]
pub(super) fn shell_exit<V: Vector>(
    state: &State<V>,
    sc: &Scratch<V>,
    a: u32,
    t: f64,
    motion: Motion<V>,
) -> Option<f64> {
    let Motion { pos, vel, .. } = motion;
    let d = state.topo.delta(sc.shell_centres[a as usize].pos, pos);
    let h = 0.5 * sc.shell_width;
    let c = d.length_squared() - h * h;
    let s = if c >= 0.0 {
        0.0
    } else {
        let (qa, qb) = (vel.length_squared(), d.dot(vel));
        if qa == 0.0 {
            return None;
        }
        // The positive root; c < 0, so -c / (b + sqrt(disc)) when b > 0 avoids cancellation.
        let root = (qb * qb - qa * c).sqrt();
        if qb > 0.0 {
            -c / (qb + root)
        } else {
            (root - qb) / qa
        }
    };
    (t + s <= sc.horizon).then_some(t + s)
}
