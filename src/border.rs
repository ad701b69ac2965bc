//! The world box and what its border does to critters that reach it: bounce, wrap or clamp.

use crate::vector::Vector;
use serde::{Deserialize, Serialize};

/// What happens at the edge of the world box.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Border {
    /// Reflect off the edge (with the critter's restitution).
    #[default]
    Bounce,
    /// Periodic: leave on one side, come back on the other; distances use the nearest image.
    Wrap,
    /// Stop at the edge: position clamped, the outward part of the velocity removed.
    Clamp,
}

impl std::str::FromStr for Border {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "bounce" => Ok(Border::Bounce),
            "wrap" => Ok(Border::Wrap),
            "clamp" => Ok(Border::Clamp),
            other => Err(format!(
                "unknown border '{other}': use bounce, wrap or clamp"
            )),
        }
    }
}

/// The world box and its border rule: everything that decides distances and cell coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Topology<V: Vector> {
    /// Lower corner.
    pub min: V,
    /// Upper corner.
    pub max: V,
    /// Border rule.
    pub border: Border,
}

impl<V: Vector> Topology<V> {
    /// Size of the box.
    #[inline]
    pub fn size(&self) -> V {
        self.max - self.min
    }

    /// True when the border is periodic.
    #[inline]
    pub fn wraps(&self) -> bool {
        self.border == Border::Wrap
    }

    /// `b - a`, reduced to the nearest periodic image when the border wraps.
    #[inline]
    pub fn delta(&self, a: V, b: V) -> V {
        let mut d = b - a;
        if self.wraps() {
            let size = self.size();
            // Most pairs are nearer than half the box on every axis: one test for all of them.
            if d.within(size * 0.5) {
                return d;
            }
            for axis in 0..V::DIM {
                let l = size.get(axis);
                let x = d.get(axis);
                if x.abs() > 0.5 * l {
                    d.set(axis, x - l * (x / l).round());
                }
            }
        }
        d
    }

    /// `p` mapped back into the box along every axis (for wrapped worlds).
    #[inline]
    pub fn wrap_position(&self, mut p: V) -> V {
        for axis in 0..V::DIM {
            let (lo, hi) = (self.min.get(axis), self.max.get(axis));
            let x = p.get(axis);
            if x < lo || x >= hi {
                let mut w = lo + (x - lo).rem_euclid(hi - lo);
                if w >= hi {
                    w = lo; // rem_euclid can round up to the period
                }
                p.set(axis, w);
            }
        }
        p
    }

    /// Applies the border to a disk of radius `r`: returns the new position and velocity.
    ///
    /// Bounce mirrors the position about the edge (exact for straight-line motion) and reflects
    /// the normal velocity with restitution `e` when it points outward. Wrap maps the centre back
    /// into the box. Clamp stops the disk at the edge.
    #[inline]
    pub fn apply(&self, pos: V, vel: V, r: f64, e: f64) -> (V, V) {
        if self.clear_of_edges(pos, r) {
            return (pos, vel);
        }
        self.apply_at_edges(pos, vel, r, e)
    }

    /// True when a disk of radius `r` at `pos` is clear of every edge, so that
    /// [`Topology::apply`] would change nothing.
    ///
    /// Most critters are: one branch-free test over the axes, with the same comparisons the
    /// edge code makes, so it passes exactly when that code would change nothing (and fails on
    /// NaN, which the edge code then sees as before).
    #[inline]
    pub(crate) fn clear_of_edges(&self, pos: V, r: f64) -> bool {
        let mut clear = true;
        for axis in 0..V::DIM {
            let (lo, hi, x) = (self.min.get(axis), self.max.get(axis), pos.get(axis));
            // `&`, not `&&`: no branch per comparison, whatever the optimiser decides.
            clear &= match self.border {
                Border::Wrap => (x >= lo) & (x < hi),
                Border::Bounce | Border::Clamp => (x >= lo + r) & (x <= hi - r),
            };
        }
        clear
    }

    /// [`Topology::apply`] for a disk at or past an edge.
    #[cold]
    pub(crate) fn apply_at_edges(&self, mut pos: V, mut vel: V, r: f64, e: f64) -> (V, V) {
        for axis in 0..V::DIM {
            let lo = self.min.get(axis);
            let hi = self.max.get(axis);
            let x = pos.get(axis);
            match self.border {
                Border::Wrap => {
                    if x < lo || x >= hi {
                        pos = self.wrap_position(pos);
                    }
                }
                Border::Bounce => {
                    let (lo, hi) = (lo + r, hi - r);
                    if lo > hi {
                        pos.set(axis, 0.5 * (lo + hi));
                        vel.set(axis, 0.0);
                    } else if x < lo {
                        pos.set(axis, (lo + (lo - x)).min(hi));
                        let v = vel.get(axis);
                        if v < 0.0 {
                            vel.set(axis, -e * v);
                        }
                    } else if x > hi {
                        pos.set(axis, (hi - (x - hi)).max(lo));
                        let v = vel.get(axis);
                        if v > 0.0 {
                            vel.set(axis, -e * v);
                        }
                    }
                }
                Border::Clamp => {
                    let (lo, hi) = (lo + r, hi - r);
                    if lo > hi {
                        pos.set(axis, 0.5 * (lo + hi));
                        vel.set(axis, 0.0);
                    } else if x < lo {
                        pos.set(axis, lo);
                        vel.set(axis, vel.get(axis).max(0.0));
                    } else if x > hi {
                        pos.set(axis, hi);
                        vel.set(axis, vel.get(axis).min(0.0));
                    }
                }
            }
        }
        (pos, vel)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;

    fn topo(border: Border) -> Topology<DVec2> {
        Topology {
            min: DVec2::ZERO,
            max: DVec2::new(10.0, 5.0),
            border,
        }
    }

    #[test]
    fn wrap_maps_back_into_the_box_and_uses_the_nearest_image() {
        let t = topo(Border::Wrap);
        let (p, v) = t.apply(DVec2::new(10.5, -0.25), DVec2::new(1.0, -1.0), 0.5, 1.0);
        assert_eq!(p, DVec2::new(0.5, 4.75));
        assert_eq!(v, DVec2::new(1.0, -1.0));
        let d = t.delta(DVec2::new(0.2, 0.1), DVec2::new(9.9, 4.9));
        assert!((d - DVec2::new(-0.3, -0.2)).length() < 1e-12);
    }

    #[test]
    fn bounce_mirrors_position_and_reflects_outward_velocity() {
        let t = topo(Border::Bounce);
        let (p, v) = t.apply(DVec2::new(9.8, 2.0), DVec2::new(2.0, 1.0), 0.5, 1.0);
        assert!((p.x - 9.2).abs() < 1e-12);
        assert_eq!(v, DVec2::new(-2.0, 1.0));
    }

    #[test]
    fn clamp_stops_at_the_edge() {
        let t = topo(Border::Clamp);
        let (p, v) = t.apply(DVec2::new(-1.0, 2.0), DVec2::new(-2.0, 1.0), 0.5, 1.0);
        assert_eq!(p, DVec2::new(0.5, 2.0));
        assert_eq!(v, DVec2::new(0.0, 1.0));
    }

    #[test]
    fn the_clear_of_the_edges_shortcut_changes_nothing() {
        // Positions on and around every edge (exactly at lo + r and hi - r, one ulp either side,
        // inside, outside, NaN), radii that fit and one that does not: apply must give the
        // same bits as the edge code alone.
        let near = |x: f64| [x, x.next_down(), x.next_up()];
        let mut xs = vec![-1.0, 0.0, 2.5, 7.0, 10.0, 11.0, f64::NAN];
        for r in [0.5, 3.0] {
            for edge in [0.0 + r, 10.0 - r, 5.0 - r, 0.0, 10.0, 5.0] {
                xs.extend(near(edge));
            }
        }
        let mut checked = 0;
        for border in [Border::Wrap, Border::Bounce, Border::Clamp] {
            let t = topo(border);
            for r in [0.5, 3.0] {
                for &x in &xs {
                    for &y in &xs {
                        let (pos, vel) = (DVec2::new(x, y), DVec2::new(1.5, -2.0));
                        let (p, v) = t.apply(pos, vel, r, 0.5);
                        let (pe, ve) = t.apply_at_edges(pos, vel, r, 0.5);
                        let bits = |a: DVec2| [a.x.to_bits(), a.y.to_bits()];
                        assert_eq!(
                            (bits(p), bits(v)),
                            (bits(pe), bits(ve)),
                            "{border:?} r {r} at ({x}, {y})"
                        );
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 3000);
    }
}
