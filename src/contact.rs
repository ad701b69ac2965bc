//! Narrow-phase queries, named `contact_[shape1]_[shape2]`: is a pair touching, and along which normal.
//!
//! Offsets are passed in (`b - a`, already reduced to the nearest periodic image in wrapped worlds),
//! so these functions know nothing about borders.

use crate::vector::Vector;
use crate::wall::WallBox;

/// Contact geometry between a first and a second shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact<V> {
    /// Unit normal pointing from the first shape towards the second.
    pub normal: V,
    /// Penetration depth: sum of radii minus distance (>= 0 while touching).
    pub depth: f64,
    /// Contact point, relative to the first shape's centre.
    pub point: V,
}

/// Contact between two disks (spheres) with centre offset `d = b - a`; `None` unless touching
/// (distance <= ra + rb).
///
/// Coincident centres get the x axis as normal: deterministic, never NaN.
#[inline]
pub fn contact_ball_ball<V: Vector>(d: V, ra: f64, rb: f64) -> Option<Contact<V>> {
    let sum = ra + rb;
    let dist2 = d.length_squared();
    if dist2 > sum * sum {
        return None;
    }
    let dist = dist2.sqrt();
    // Divide rather than multiply by 1/dist: an axis-aligned offset then gives the exact axis.
    let normal = if dist > 0.0 { d / dist } else { V::unit_x() };
    let depth = sum - dist;
    Some(Contact {
        normal,
        depth,
        point: normal * (ra - 0.5 * depth),
    })
}

/// True when two disks with centre offset `d` touch (distance <= ra + rb).
#[inline]
pub fn touching_ball_ball<V: Vector>(d: V, ra: f64, rb: f64) -> bool {
    let sum = ra + rb;
    d.length_squared() <= sum * sum
}

/// Contact between a wall box and a disk whose centre is at `d` from the box centre; `None` unless
/// touching. The normal points from the wall to the disk, through the closest face, edge or corner.
#[inline]
pub fn contact_wall_ball<V: Vector>(wall: &WallBox<V>, d: V, r: f64) -> Option<Contact<V>> {
    let feature = wall.closest_feature(d);
    if feature.inside {
        // Centre inside the box: leave through the nearest face.
        let gap = (feature.offset - d).length();
        return Some(Contact {
            normal: feature.face_normal,
            depth: r + gap,
            point: feature.offset,
        });
    }
    let away = d - feature.offset;
    let dist2 = away.length_squared();
    if dist2 > r * r {
        return None;
    }
    let dist = dist2.sqrt();
    let normal = if dist > 0.0 {
        away / dist
    } else {
        // Centre exactly on the surface: take the outward direction of the surface point.
        let inward = wall.closest_feature(feature.offset * (1.0 - 1e-12));
        inward.face_normal
    };
    Some(Contact {
        normal,
        depth: r - dist,
        point: feature.offset,
    })
}

/// True when disk `inner` (offset `d` from `outer`'s centre) lies wholly inside disk `outer`:
/// distance + inner radius < outer radius (Pop's `contains`).
#[inline]
pub fn contains_ball_ball<V: Vector>(d: V, r_outer: f64, r_inner: f64) -> bool {
    d.length() + r_inner < r_outer
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, DVec2, DVec3};

    #[test]
    fn coincident_centres_get_the_x_axis() {
        let c = contact_ball_ball(DVec2::ZERO, 1.0, 1.0).expect("touching");
        assert_eq!(c.normal, DVec2::X);
        assert_eq!(c.depth, 2.0);
    }

    #[test]
    fn disks_just_touching_count_and_just_apart_do_not() {
        assert!(contact_ball_ball(DVec2::new(2.0, 0.0), 1.0, 1.0).is_some());
        assert!(contact_ball_ball(DVec2::new(2.0 + 1e-12, 0.0), 1.0, 1.0).is_none());
    }

    #[test]
    fn wall_face_edge_and_corner_in_2d() {
        let wall = WallBox::segment(DVec2::new(-2.0, 0.0), DVec2::new(2.0, 0.0), 0.2).unwrap();
        // Face: straight above.
        let c = contact_wall_ball(&wall, DVec2::new(0.5, 0.5), 0.5).unwrap();
        assert!((c.normal - DVec2::Y).length() < 1e-15);
        assert!((c.depth - 0.1).abs() < 1e-15);
        // Corner: diagonal beyond the end (2, 0.1).
        let d = DVec2::new(2.3, 0.4);
        let c = contact_wall_ball(&wall, d, 0.5).unwrap();
        let want = (d - DVec2::new(2.0, 0.1)).normalize();
        assert!((c.normal - want).length() < 1e-15);
        assert!((c.depth - (0.5 - 0.3 * 2f64.sqrt())).abs() < 1e-15);
        // Just out of reach of the corner.
        assert!(contact_wall_ball(&wall, DVec2::new(2.4, 0.5), 0.5).is_none());
        // Inside: pushed out through the nearer face (top, since y > 0).
        let c = contact_wall_ball(&wall, DVec2::new(0.0, 0.05), 0.5).unwrap();
        assert_eq!(c.normal, DVec2::Y);
        assert!((c.depth - 0.55).abs() < 1e-15);
    }

    #[test]
    fn wall_edge_in_3d() {
        let wall =
            WallBox::cuboid(DVec3::ZERO, DVec3::new(2.0, 2.0, 2.0), DMat3::IDENTITY).unwrap();
        // Near the edge x = 1, y = 1 (parallel to z).
        let d = DVec3::new(1.3, 1.4, 0.2);
        let c = contact_wall_ball(&wall, d, 0.6).unwrap();
        let want = DVec3::new(0.3, 0.4, 0.0).normalize();
        assert!((c.normal - want).length() < 1e-15);
        assert!((c.depth - 0.1).abs() < 1e-15);
    }
}
