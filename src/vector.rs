//! The dimension a world lives in.
//!
//! Everything in the engine is generic over [`Vector`], implemented for [`DVec2`] (2D scenes) and
//! [`DVec3`] (3D scenes). A 2D world is a `World<DVec2>`: it stores two floats per position and never
//! computes a z, so a slow 2D scene does not pay for what a 3D one needs.

use glam::{DMat3, DVec2, DVec3};
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// A position or velocity in 2D or 3D, f64 throughout.
pub trait Vector:
    Copy
    + Debug
    + PartialEq
    + Default
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
{
    /// Number of components: 2 or 3.
    const DIM: usize;
    /// An orthonormal frame, used to orient walls: a unit direction in 2D, a rotation matrix in 3D.
    type Frame: Copy + Debug + PartialEq + Send + Sync;
    /// What aligns a [`crate::critter::Critter`] of this dimension (a zero-length array of it is
    /// one of its fields): 64 bytes in 2D, so a critter's record is one cache line.
    type CritterAlign: Clone + Copy + Debug + Send + Sync;
    /// What aligns the event engine's per-critter body (position, velocity, clock, radius: 64
    /// bytes in 3D, so one body is one cache line, never two; 48 in 2D, left unpadded).
    type BodyAlign: Clone + Copy + Debug + Default + Send + Sync;
    /// The same number of components in single precision, for compact copies (the broad phase's
    /// cell-sorted boxes and the bounds of its Verlet list).
    type Single: Clone + Copy + Debug + Default + Send + Sync + AsRef<[f32]> + AsMut<[f32]>;

    /// The zero vector.
    fn zero() -> Self;
    /// All components equal to `v`.
    fn splat(v: f64) -> Self;
    /// Component `axis` (0 = x, 1 = y, 2 = z).
    fn get(self, axis: usize) -> f64;
    /// Sets component `axis`.
    fn set(&mut self, axis: usize, v: f64);
    /// Dot product.
    fn dot(self, other: Self) -> f64;
    /// True when every component is finite.
    fn all_finite(self) -> bool;
    /// True when every component's magnitude is at most the same component of `bound`.
    fn within(self, bound: Self) -> bool;
    /// The vector with the components of `s` (exactly: every `f32` is an `f64`).
    fn from_single(s: Self::Single) -> Self;
    /// The frame whose axes are the world axes.
    fn identity_frame() -> Self::Frame;
    /// Axis `axis` of `frame`, in world coordinates.
    fn frame_axis(frame: &Self::Frame, axis: usize) -> Self;
    /// The components of `v` along the axes of `frame`.
    fn to_local(frame: &Self::Frame, v: Self) -> Self;
    /// The world vector whose components along the axes of `frame` are `v`.
    fn from_local(frame: &Self::Frame, v: Self) -> Self;
    /// Components as `[x, y, z]`, with z = 0 in 2D (for printing and recording only).
    fn to_array3(self) -> [f64; 3];

    /// Squared length.
    #[inline]
    fn length_squared(self) -> f64 {
        self.dot(self)
    }
    /// Length.
    #[inline]
    fn length(self) -> f64 {
        self.dot(self).sqrt()
    }
    /// The unit vector along x: the deterministic normal used when two centres coincide.
    #[inline]
    fn unit_x() -> Self {
        let mut v = Self::zero();
        v.set(0, 1.0);
        v
    }
}

impl Vector for DVec2 {
    const DIM: usize = 2;
    type Frame = DVec2;
    type CritterAlign = Align64;
    type BodyAlign = u64;
    type Single = [f32; 2];

    #[inline]
    fn zero() -> Self {
        DVec2::ZERO
    }
    #[inline]
    fn splat(v: f64) -> Self {
        DVec2::splat(v)
    }
    #[inline]
    fn get(self, axis: usize) -> f64 {
        self[axis]
    }
    #[inline]
    fn set(&mut self, axis: usize, v: f64) {
        self[axis] = v;
    }
    #[inline]
    fn dot(self, other: Self) -> f64 {
        DVec2::dot(self, other)
    }
    #[inline]
    fn all_finite(self) -> bool {
        self.is_finite()
    }
    #[inline]
    fn within(self, bound: Self) -> bool {
        self.abs().cmple(bound).all()
    }
    #[inline]
    fn from_single(s: [f32; 2]) -> Self {
        DVec2::new(f64::from(s[0]), f64::from(s[1]))
    }
    #[inline]
    fn identity_frame() -> Self::Frame {
        DVec2::X
    }
    #[inline]
    fn frame_axis(frame: &Self::Frame, axis: usize) -> Self {
        if axis == 0 {
            *frame
        } else {
            frame.perp()
        }
    }
    #[inline]
    fn to_local(frame: &Self::Frame, v: Self) -> Self {
        DVec2::new(v.dot(*frame), v.dot(frame.perp()))
    }
    #[inline]
    fn from_local(frame: &Self::Frame, v: Self) -> Self {
        *frame * v.x + frame.perp() * v.y
    }
    fn to_array3(self) -> [f64; 3] {
        [self.x, self.y, 0.0]
    }
}

impl Vector for DVec3 {
    const DIM: usize = 3;
    type Frame = DMat3;
    type CritterAlign = u64;
    type BodyAlign = Align64;
    type Single = [f32; 3];

    #[inline]
    fn zero() -> Self {
        DVec3::ZERO
    }
    #[inline]
    fn splat(v: f64) -> Self {
        DVec3::splat(v)
    }
    #[inline]
    fn get(self, axis: usize) -> f64 {
        self[axis]
    }
    #[inline]
    fn set(&mut self, axis: usize, v: f64) {
        self[axis] = v;
    }
    #[inline]
    fn dot(self, other: Self) -> f64 {
        DVec3::dot(self, other)
    }
    #[inline]
    fn all_finite(self) -> bool {
        self.is_finite()
    }
    #[inline]
    fn within(self, bound: Self) -> bool {
        self.abs().cmple(bound).all()
    }
    #[inline]
    fn from_single(s: [f32; 3]) -> Self {
        DVec3::new(f64::from(s[0]), f64::from(s[1]), f64::from(s[2]))
    }
    #[inline]
    fn identity_frame() -> Self::Frame {
        DMat3::IDENTITY
    }
    #[inline]
    fn frame_axis(frame: &Self::Frame, axis: usize) -> Self {
        frame.col(axis)
    }
    #[inline]
    fn to_local(frame: &Self::Frame, v: Self) -> Self {
        frame.transpose() * v
    }
    #[inline]
    fn from_local(frame: &Self::Frame, v: Self) -> Self {
        *frame * v
    }
    fn to_array3(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
}

/// "(1, 2.5)" or "(1, 2.5, 0)".
pub(crate) fn fmt_vec<V: Vector>(v: V) -> String {
    let parts: Vec<String> = (0..V::DIM).map(|a| format!("{}", v.get(a))).collect();
    format!("({})", parts.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_round_trip_in_2d() {
        let f = DVec2::new(3.0, 4.0).normalize();
        let v = DVec2::new(-1.5, 2.25);
        let back = DVec2::from_local(&f, DVec2::to_local(&f, v));
        assert!((back - v).length() < 1e-15);
        assert!(DVec2::frame_axis(&f, 0).dot(DVec2::frame_axis(&f, 1)).abs() < 1e-15);
    }

    #[test]
    fn frames_round_trip_in_3d() {
        let f = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let v = DVec3::new(-1.5, 2.25, 0.5);
        let back = DVec3::from_local(&f, DVec3::to_local(&f, v));
        assert!((back - v).length() < 1e-14);
    }
}

/// A zero-sized type aligned to a cache line (see [`Vector::CritterAlign`]).
#[derive(Clone, Copy, Debug, Default)]
#[repr(align(64))]
pub struct Align64;
