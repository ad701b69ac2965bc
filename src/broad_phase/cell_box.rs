//! The single-precision boxes the grid sorts into its cells and the Verlet list keeps as its
//! bounds: rounded outwards for a cell's copy of an object, inwards for a bound, so that neither
//! ever misses a pair the exact boxes would find.

use super::BroadObject;
use crate::border::Topology;
use crate::vector::Vector;

/// The tag bit of a wall's [`CellBox`].
pub(super) const WALL_BIT: u32 = 1 << 31;

/// The tag of a gap's bound (its centre is NaN too, so no object is ever inside it).
const GAP_TAG: u32 = u32::MAX;

/// An object's box in single precision, 20 bytes in 2D and 28 in 3D against 40 and 56 for a
/// [`BroadObject`]. Two kinds:
///
/// - A level's cell-sorted copy of an object ([`CellBox::new`]): the centre to the nearest `f32`
///   and the half sizes (widened by the pad) rounded up past the centre's rounding, so the box
///   holds the exact one. The grid's walk may therefore find a pair whose exact boxes only touch
///   through the rounding, never miss one whose exact boxes overlap; the Verlet list and the grid
///   mode test every pair it finds again against the exact boxes.
/// - A Verlet list's bound ([`CellBox::bound`]): where one index's object may be while the list
///   stays valid, its box at the build widened by half the skin, rounded inwards, so that a box
///   inside the bound is inside the widened box its pairs were found with. The half sizes are
///   then how far the object's box may reach from the centre. The bounds and a level's boxes
///   take turns with one buffer (see [`super::level::Level::keep_tags_only`]).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct CellBox<V: Vector> {
    pub(super) center: V::Single,
    pub(super) half: V::Single,
    /// The object's index in `objs` (a bound's: its slot), with [`WALL_BIT`] set for a wall.
    pub(super) tag: u32,
}

impl<V: Vector> CellBox<V> {
    /// The cell-sorted copy of `o`, at index `index`, widened by `pad` and rounded outwards.
    #[inline]
    pub(super) fn new(o: &BroadObject<V>, index: u32, pad: f64) -> Self {
        let (center, moved) = rounded(o.center);
        let mut half = V::Single::default();
        for (axis, h) in half.as_mut().iter_mut().enumerate() {
            *h = at_least(o.half.get(axis) + pad + moved.get(axis));
        }
        CellBox {
            center,
            half,
            tag: tagged(index, o.is_wall),
        }
    }

    /// The bound of `o` widened by `pad`: the centre to the nearest `f32`, the half sizes (how
    /// far the box may reach from the centre) the widened ones less the centre's rounding,
    /// rounded down; the slot as the tag, with [`WALL_BIT`] for a wall. A gap's is NaN, tagged
    /// [`GAP_TAG`].
    #[inline]
    pub(super) fn bound(o: Option<&BroadObject<V>>, pad: f64) -> Self {
        let Some(o) = o else {
            let mut nan = V::Single::default();
            nan.as_mut().fill(f32::NAN);
            return CellBox {
                center: nan,
                half: nan,
                tag: GAP_TAG,
            };
        };
        let (center, moved) = rounded(o.center);
        let mut room = V::Single::default();
        for (axis, r) in room.as_mut().iter_mut().enumerate() {
            *r = at_most(o.half.get(axis) + pad - moved.get(axis));
        }
        CellBox {
            center,
            half: room,
            tag: tagged(o.slot, o.is_wall),
        }
    }

    /// For a bound: true when `o` is what the bound was made from, a gap for a gap, or for an
    /// object the box of one with the same slot and wall flag that lies inside the bound. Never
    /// for a NaN.
    #[inline]
    pub(super) fn holds(&self, topo: &Topology<V>, o: Option<&BroadObject<V>>) -> bool {
        let Some(o) = o else {
            return self.tag == GAP_TAG;
        };
        if tagged(o.slot, o.is_wall) != self.tag {
            return false;
        }
        let d = topo.delta(V::from_single(self.center), o.center);
        let room = self.half.as_ref();
        (0..V::DIM).all(|axis| d.get(axis).abs() + o.half.get(axis) <= f64::from(room[axis]))
    }

    #[inline]
    pub(super) fn center(&self) -> V {
        V::from_single(self.center)
    }

    #[inline]
    pub(super) fn half(&self) -> V {
        V::from_single(self.half)
    }

    /// The object's index in `objs`.
    #[inline]
    pub(super) fn index(&self) -> u32 {
        self.tag & !WALL_BIT
    }
}

/// `index` with [`WALL_BIT`] set for a wall.
#[inline]
fn tagged(index: u32, is_wall: bool) -> u32 {
    if is_wall {
        index | WALL_BIT
    } else {
        index
    }
}

/// [`super::objects::overlaps`] for cells' boxes.
#[inline(always)]
pub(super) fn cells_overlap<V: Vector>(topo: &Topology<V>, a: &CellBox<V>, b: &CellBox<V>) -> bool {
    if a.tag & b.tag & WALL_BIT != 0 {
        return false;
    }
    let d = topo.delta(a.center(), b.center());
    let (ha, hb) = (a.half(), b.half());
    for axis in 0..V::DIM {
        if d.get(axis).abs() > ha.get(axis) + hb.get(axis) {
            return false;
        }
    }
    true
}

/// [`cells_overlap`] computed whole, without a branch on any axis (`&`, not `&&`).
#[inline(always)]
pub(super) fn cells_overlap_flag<V: Vector>(
    topo: &Topology<V>,
    a: &CellBox<V>,
    b: &CellBox<V>,
) -> bool {
    let d = topo.delta(a.center(), b.center());
    let (ha, hb) = (a.half(), b.half());
    let mut hit = a.tag & b.tag & WALL_BIT == 0;
    for axis in 0..V::DIM {
        hit &= d.get(axis).abs() <= ha.get(axis) + hb.get(axis);
    }
    hit
}

/// Pushes onto `out` the pair `name(a, b)` of indices for each `b` of `run` whose box overlaps
/// `a`'s. Every pair is written past the end of `out`, which moves on only past those that
/// overlap: no branch on a coin toss.
#[inline(always)]
pub(super) fn push_overlapping<V: Vector>(
    topo: &Topology<V>,
    a: &CellBox<V>,
    run: &[CellBox<V>],
    out: &mut Vec<(u32, u32)>,
    name: impl Fn(u32, u32) -> (u32, u32),
) {
    let mut end = out.len();
    out.resize(end + run.len(), (0, 0));
    for b in run {
        out[end] = name(a.index(), b.index());
        end += usize::from(cells_overlap_flag(topo, a, b));
    }
    out.truncate(end);
}

/// `v` to the nearest `f32` on each axis, and how far each component moved (its magnitude).
#[inline]
fn rounded<V: Vector>(v: V) -> (V::Single, V) {
    let mut single = V::Single::default();
    let mut moved = V::zero();
    for (axis, x) in single.as_mut().iter_mut().enumerate() {
        *x = v.get(axis) as f32;
        moved.set(axis, (f64::from(*x) - v.get(axis)).abs());
    }
    (single, moved)
}

/// The smallest `f32` not below `x`, or one just above it (NaN for NaN).
#[inline]
fn at_least(x: f64) -> f32 {
    -at_most(-x)
}

/// The largest `f32` not above `x`, or one just below it (NaN for NaN, so a bound made from it
/// holds nothing).
#[inline]
pub(super) fn at_most(x: f64) -> f32 {
    let size = x.abs();
    if size >= f64::from(f32::MIN_POSITIVE) && size <= f64::from(f32::MAX) {
        // Stepping down by f32's relative epsilon before rounding to nearest lands at or below
        // `x` (the rounding moves by at most half that), without a branch on whether the
        // rounding went up: a coin toss per value, which a branch would mispredict.
        (x - size * f64::from(f32::EPSILON)) as f32
    } else {
        let y = x as f32;
        if f64::from(y) > x {
            y.next_down()
        } else {
            y
        }
    }
}
