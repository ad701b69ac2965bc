//! The world's neighbour queries (for Rust callers and scene scripts), through the grid hooks
//! use ([`crate::step::neighbours`]).

use super::World;
use crate::critter::CritterId;
use crate::kind::KindId;
use crate::vector::Vector;

impl<V: Vector> World<V> {
    /// Live critters other than walls whose centres lie within `r` of `centre` (through the
    /// border when it wraps), of `kind` or a kind extending it when given, leaving out
    /// `exclude`, in id order. Looks only at the grid cells the ball overlaps.
    pub fn nearby(
        &mut self,
        centre: V,
        r: f64,
        kind: Option<KindId>,
        exclude: Option<CritterId>,
    ) -> Vec<CritterId> {
        self.access().nearby(centre, r, kind, exclude)
    }

    /// The live critter other than walls nearest to `centre`, of `kind` (or a kind extending
    /// it) when given, leaving out `exclude`; ties go to the lower id.
    pub fn nearest(
        &mut self,
        centre: V,
        kind: Option<KindId>,
        exclude: Option<CritterId>,
    ) -> Option<CritterId> {
        self.access().nearest(centre, kind, exclude)
    }

    /// True when a disk of radius `r` at `p` would overlap a critter other than a wall (live
    /// or dying): `w.scatter`'s test, not `|delta| > r + radius`, asked only of nearby critters.
    pub(crate) fn overlaps_critter(&mut self, p: V, r: f64) -> bool {
        let (grid, at) = self.state.scope();
        let topo = at.topo;
        grid.any_overlapping(at, p, r, |c| {
            // As `!(a > b)`, so a NaN radius overlaps everything, as the scan it replaces did.
            topo.delta(c.pos, p).length().partial_cmp(&(c.radius() + r))
                != Some(std::cmp::Ordering::Greater)
        })
    }
}
