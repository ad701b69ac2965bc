//! What the broad phase reads: its objects, where it reads them from, and the view of fast
//! objects with their boxes led ahead along their strides for the Verlet list.

use super::LEAD_STEPS;
use crate::border::Topology;
use crate::vector::Vector;

/// An object for the broad phase: a centre and per-axis half sizes of its bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BroadObject<V> {
    /// Centre of the bounding box.
    pub center: V,
    /// Half sizes of the bounding box, per world axis.
    pub half: V,
    /// The id to report in pairs (the critter's slot index).
    pub slot: u32,
    /// Walls never pair with walls.
    pub is_wall: bool,
}

/// Where the broad phase reads its objects: indices `0..slots()`, each an object or a gap (a
/// slot with no live critter). Pairs are reported by the objects' `slot`s. A slice of objects is
/// one; the world reads its critters' slots in place, so no list of objects is kept per step.
pub(crate) trait Objects<V: Vector>: Sync {
    /// How many indices there are.
    fn slots(&self) -> usize;
    /// The object at index `i < slots()`, or `None` for a gap.
    fn object(&self, i: usize) -> Option<BroadObject<V>>;
    /// A hint that `object(i)` will be asked for soon: a source that reads scattered memory
    /// may start loading it.
    #[inline]
    fn prefetch(&self, _i: usize) {}
    /// Where the object at index `i` moves in a step at its velocity (zero for a gap or an
    /// object that does not know): the Verlet list widens a fast object's bound, and pushes it
    /// ahead, so that it lasts [`LEAD_STEPS`] steps, where the skin alone would make it rebuild
    /// every step or two.
    #[inline]
    fn step(&self, _i: usize) -> V {
        V::zero()
    }
    /// True when the object at index `i` stays where it is this step and needs no test against
    /// another such object (a sleeper or a wall, src/method/sleep.rs): the kept Verlet list
    /// drops their pairs without reading the objects.
    #[inline]
    fn still(&self, _i: usize) -> bool {
        false
    }
    /// False when no object is [`Objects::still`], so that the pair loops need not ask.
    #[inline]
    fn any_still(&self) -> bool {
        false
    }
}

/// The share of a lead ([`LEAD_STEPS`]) that stretches a fast object's box along its step rather
/// than all round: a disk is more likely to go on than to turn back, and a smaller box has fewer
/// pairs; more of it and a disk turned by a collision leaves its bound too soon.
pub(super) const LEAD_ALONG_STEP: f64 = 0.5;

/// In a crowd (a pile: the last step found a contact for every 8 listed pairs or fewer; the
/// world says so, [`super::BroadPhase::set_crowded`]) only objects whose stride is more than
/// this many times the median stride are led: a pile jostled by the discrete step's separations
/// moves in ways its velocities do not show, so leading everyone only adds pairs. Elsewhere
/// every object whose [`LEAD_STEPS`] strides pass half the skin is led.
pub(super) const CROWD_LEAD_OVER_MEDIAN: f64 = 2.0;

/// The objects of `O` with each box widened by its lead (see [`LEAD_STEPS`]), for the Verlet
/// list's build: its pairs and bounds.
pub(super) struct LeadBoxes<'a, O: ?Sized> {
    pub(super) objs: &'a O,
    /// Half the skin, which every box gets anyway.
    pub(super) half_skin: f64,
    /// Only objects with a longer stride than this are led.
    pub(super) led_above: f64,
}

impl<V: Vector, O: Objects<V> + ?Sized> Objects<V> for LeadBoxes<'_, O> {
    #[inline]
    fn slots(&self) -> usize {
        self.objs.slots()
    }

    #[inline]
    fn object(&self, i: usize) -> Option<BroadObject<V>> {
        let mut o = self.objs.object(i)?;
        let step = self.objs.step(i);
        let stride = step.length();
        let lead = LEAD_STEPS * stride - self.half_skin;
        if stride > self.led_above && lead > 0.0 {
            // Widened all round by `1 - LEAD_ALONG_STEP` of the lead, and by the rest along the
            // step.
            let ahead = step * (0.5 * LEAD_ALONG_STEP * lead / stride);
            o.center += ahead;
            for axis in 0..V::DIM {
                let half =
                    o.half.get(axis) + ahead.get(axis).abs() + (1.0 - LEAD_ALONG_STEP) * lead;
                o.half.set(axis, half);
            }
        }
        Some(o)
    }

    #[inline]
    fn prefetch(&self, i: usize) {
        self.objs.prefetch(i);
    }
}

impl<V: Vector> Objects<V> for [BroadObject<V>] {
    #[inline]
    fn slots(&self) -> usize {
        self.len()
    }

    #[inline]
    fn object(&self, i: usize) -> Option<BroadObject<V>> {
        self.get(i).copied()
    }
}

/// True when the exact boxes of `a` and `b` overlap (never for two walls).
#[inline]
pub(super) fn overlaps<V: Vector>(
    topo: &Topology<V>,
    a: &BroadObject<V>,
    b: &BroadObject<V>,
) -> bool {
    if a.is_wall && b.is_wall {
        return false;
    }
    let d = topo.delta(a.center, b.center);
    for axis in 0..V::DIM {
        if d.get(axis).abs() > a.half.get(axis) + b.half.get(axis) {
            return false;
        }
    }
    true
}
/// [`overlaps`] computed whole, without a branch on any axis (`&`, not `&&`): the re-test's
/// outcome is a coin toss the processor cannot predict.
#[inline(always)]
pub(super) fn overlap_flag<V: Vector>(
    topo: &Topology<V>,
    a: &BroadObject<V>,
    b: &BroadObject<V>,
) -> bool {
    let d = topo.delta(a.center, b.center);
    let mut hit = !(a.is_wall & b.is_wall);
    for axis in 0..V::DIM {
        hit &= d.get(axis).abs() <= a.half.get(axis) + b.half.get(axis);
    }
    hit
}

/// The widest side of `o`'s box widened by `pad` on every side.
#[inline]
pub(super) fn box_width<V: Vector>(o: &BroadObject<V>, pad: f64) -> f64 {
    let mut w: f64 = 0.0;
    for axis in 0..V::DIM {
        w = w.max(2.0 * (o.half.get(axis) + pad));
    }
    w
}
