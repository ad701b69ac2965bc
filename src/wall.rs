//! Wall geometry: an immovable oriented box (Pop's cCritterWall): length x thickness in 2D, a box in 3D.

use crate::error::Error;
use crate::tolerance::ROUNDING_MARGIN;
use crate::vector::fmt_vec;
use crate::vector::Vector;
use glam::{DMat3, DVec2, DVec3};

/// Pop's default wall thickness.
pub const DEFAULT_WALL_THICKNESS: f64 = 0.2;

/// An oriented box: centre, orthonormal frame, half extents along the frame's axes.
#[derive(Clone, Debug, PartialEq)]
pub struct WallBox<V: Vector> {
    /// Centre of the box.
    pub center: V,
    /// Orientation: the box's axes in world coordinates.
    pub frame: V::Frame,
    /// Half extents along the frame's axes, all > 0.
    pub half: V,
}

/// Where a point is relative to a box: its closest point on the box surface and whether it is inside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestFeature<V> {
    /// Closest point on the box's surface, relative to the box centre, in world axes.
    pub offset: V,
    /// True when the query point is strictly inside the box.
    pub inside: bool,
    /// For points inside: the outward normal of the nearest face.
    pub face_normal: V,
}

impl<V: Vector> WallBox<V> {
    /// A box with the given centre, half extents and frame. Errors name the bad field.
    pub fn new(center: V, half: V, frame: V::Frame) -> Result<Self, Error> {
        let wall = WallBox {
            center,
            frame,
            half,
        };
        wall.validate()?;
        Ok(wall)
    }

    /// An axis-aligned box between two corners.
    pub fn aligned(min: V, max: V) -> Result<Self, Error> {
        Self::new((min + max) * 0.5, (max - min) * 0.5, V::identity_frame())
    }

    /// Checks the box: finite centre, positive half extents, orthonormal frame.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, value: String, reason: &str| Error::InvalidWall {
            field,
            value,
            reason: reason.to_string(),
        };
        if !self.center.all_finite() {
            return Err(bad("center", fmt_vec(self.center), "must be finite"));
        }
        for axis in 0..V::DIM {
            let h = self.half.get(axis);
            if !(h.is_finite() && h > 0.0) {
                return Err(bad(
                    "size",
                    fmt_vec(self.half * 2.0),
                    "every side (length, thickness) must be finite and greater than zero",
                ));
            }
            for other in 0..V::DIM {
                let d = V::frame_axis(&self.frame, axis).dot(V::frame_axis(&self.frame, other));
                let want = if axis == other { 1.0 } else { 0.0 };
                let orthonormal = (d - want).abs() < ROUNDING_MARGIN; // false for NaN too
                if !orthonormal {
                    return Err(bad(
                        "orientation",
                        format!("{:?}", self.frame),
                        "the frame's axes must be orthonormal",
                    ));
                }
            }
        }
        Ok(())
    }

    /// Half sizes of the axis-aligned bounding box, per world axis.
    pub fn aabb_half(&self) -> V {
        let mut out = V::zero();
        for axis in 0..V::DIM {
            let a = V::frame_axis(&self.frame, axis);
            for w in 0..V::DIM {
                out.set(w, out.get(w) + a.get(w).abs() * self.half.get(axis));
            }
        }
        out
    }

    /// Radius of the sphere around the centre that holds the box.
    pub fn bounding_radius(&self) -> f64 {
        self.half.length()
    }

    /// The closest surface feature to a point given relative to the box centre (`rel = p - center`).
    ///
    /// Outside the box the closest point is the clamp of `rel` to the box (a face, edge or corner
    /// point: exact, no randomness). Inside, it is the projection onto the nearest face; ties go to
    /// the lowest axis, then to the positive side, so the answer is deterministic.
    pub fn closest_feature(&self, rel: V) -> ClosestFeature<V> {
        let local = V::to_local(&self.frame, rel);
        let mut clamped = local;
        let mut inside = true;
        for axis in 0..V::DIM {
            let h = self.half.get(axis);
            let x = local.get(axis);
            if x > h {
                clamped.set(axis, h);
                inside = false;
            } else if x < -h {
                clamped.set(axis, -h);
                inside = false;
            } else if x == h || x == -h {
                inside = false;
            }
        }
        if !inside {
            return ClosestFeature {
                offset: V::from_local(&self.frame, clamped),
                inside: false,
                face_normal: V::zero(),
            };
        }
        let mut best_axis = 0;
        let mut best_gap = f64::INFINITY;
        for axis in 0..V::DIM {
            let gap = self.half.get(axis) - local.get(axis).abs();
            if gap < best_gap {
                best_gap = gap;
                best_axis = axis;
            }
        }
        let sign = if local.get(best_axis) < 0.0 {
            -1.0
        } else {
            1.0
        };
        let mut surface = local;
        surface.set(best_axis, sign * self.half.get(best_axis));
        ClosestFeature {
            offset: V::from_local(&self.frame, surface),
            inside: true,
            face_normal: V::frame_axis(&self.frame, best_axis) * sign,
        }
    }
}

impl WallBox<DVec2> {
    /// A 2D wall from `a` to `b` with the given thickness (Pop's cCritterWall(enda, endb, thickness)).
    pub fn segment(a: DVec2, b: DVec2, thickness: f64) -> Result<Self, Error> {
        let along = b - a;
        let length = along.length();
        if !(a.is_finite() && b.is_finite()) {
            return Err(Error::InvalidWall {
                field: "ends",
                value: format!("{} to {}", fmt_vec(a), fmt_vec(b)),
                reason: "must be finite".into(),
            });
        }
        let has_length = length > 0.0; // false for NaN too
        if !has_length {
            return Err(Error::InvalidWall {
                field: "ends",
                value: format!("{} to {}", fmt_vec(a), fmt_vec(b)),
                reason: "the two ends must differ (a wall needs a length)".into(),
            });
        }
        Self::new(
            (a + b) * 0.5,
            DVec2::new(0.5 * length, 0.5 * thickness),
            along / length,
        )
    }
}

impl WallBox<DVec3> {
    /// A 3D box wall with centre, full size and rotation (columns are the box's axes).
    pub fn cuboid(center: DVec3, size: DVec3, rotation: DMat3) -> Result<Self, Error> {
        Self::new(center, size * 0.5, rotation)
    }
}
