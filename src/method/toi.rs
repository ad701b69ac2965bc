//! Time of impact for straight-line motion, named `toi_[shape1]_[shape2]`.
//!
//! Offsets and velocities are relative (`d = b - a`, `w = v_b - v_a`). Each function returns the
//! smallest `s >= 0` at which the two first touch, `Some(0.0)` when they touch now and approach,
//! and `None` when they never touch or touch now but separate (the distance between a point
//! moving on a line and a convex set is convex in time, so a separating pair never comes back).

use crate::contact::contact_wall_ball;
use crate::tolerance::ROUNDING_MARGIN;
use crate::vector::Vector;
use crate::wall::WallBox;

/// First time two disks (spheres) whose centres are `d` apart, with relative velocity `w`, are
/// `r_sum` apart: the smaller root of `|d + w s|^2 = r_sum^2`.
#[inline]
pub fn toi_ball_ball<V: Vector>(d: V, w: V, r_sum: f64) -> Option<f64> {
    // No horizon: the early test never applies (its bound is infinite).
    toi_ball_ball_by(d, w, r_sum, f64::INFINITY)
}

/// [`toi_ball_ball`] for a caller that only wants a contact by `horizon`: `None` early, without
/// the square root and the division, when the contact is surely later. Otherwise (and whenever
/// the early test cannot be trusted) exactly `toi_ball_ball`'s answer.
///
/// The discriminant is at most `b^2`, so the smaller root `c / (-b + sqrt(disc))` is at least
/// `c / (-2b)`. The test asks for `c > -2b horizon (1 + ROUNDING_MARGIN)`: the computed root is then within
/// a few units in the last place of a value at least `horizon (1 + ROUNDING_MARGIN)`, so it is above
/// `horizon` too, and a caller that drops roots beyond `horizon` drops the same pairs. It is
/// skipped when `-2b horizon` is not a normal number (zero, subnormal, NaN, infinite).
#[inline]
pub fn toi_ball_ball_by<V: Vector>(d: V, w: V, r_sum: f64, horizon: f64) -> Option<f64> {
    let b = d.dot(w);
    if b >= 0.0 {
        return None; // not approaching
    }
    let c = d.length_squared() - r_sum * r_sum;
    if c <= 0.0 {
        return Some(0.0);
    }
    let bound = -2.0 * b * horizon;
    if bound.is_normal() && c > bound * (1.0 + ROUNDING_MARGIN) {
        return None;
    }
    let a = w.length_squared();
    let disc = b * b - a * c;
    if disc < 0.0 {
        return None;
    }
    // c / (-b + sqrt(disc)) is the smaller root without cancellation.
    Some(c / (-b + disc.sqrt()))
}

/// True when [`toi_ball_ball_by`] surely answers `None` by its first or third test (the two
/// do not approach, or their contact is surely past `horizon`) and they do not overlap now.
/// Computed whole, without a branch: a caller that drops most of its pairs, in no order a
/// processor can predict, then branches once, nearly always the same way. When false, the
/// caller asks `toi_ball_ball_by` (the same tests on the same values come first there).
#[inline(always)]
pub fn surely_no_toi_by<V: Vector>(d: V, w: V, r_sum: f64, horizon: f64) -> bool {
    let (b, dd) = (d.dot(w), d.length_squared());
    let c = dd - r_sum * r_sum;
    let bound = -2.0 * b * horizon;
    let later = (b >= 0.0) | (bound.is_normal() & (c > bound * (1.0 + ROUNDING_MARGIN)));
    later & (dd >= r_sum * r_sum)
}

/// First time a disk of radius `r` at `d` from the wall's centre, moving with `w`, touches the
/// wall: the entry of the ray `d + w s` into the box expanded by `r`.
///
/// The expanded box is the union of the box stretched by `r` along each axis (faces), the
/// cylinders of radius `r` around its edges (3D), and the spheres (circles in 2D) of radius `r`
/// at its corners, so its entry time is the smallest entry time of those pieces.
pub fn toi_wall_ball<V: Vector>(wall: &WallBox<V>, d: V, w: V, r: f64) -> Option<f64> {
    if let Some(c) = contact_wall_ball(wall, d, r) {
        // Normal points from the wall to the disk: approaching means moving against it.
        return (w.dot(c.normal) < 0.0).then_some(0.0);
    }
    let p = local3(V::to_local(&wall.frame, d));
    let u = local3(V::to_local(&wall.frame, w));
    let h = local3(wall.half);
    let dim = V::DIM;
    let mut best = f64::INFINITY;
    // Faces: the box stretched by r along one axis.
    for k in 0..dim {
        let mut hk = h;
        hk[k] += r;
        if let Some(s) = enter_box(&p, &u, &hk, dim) {
            best = best.min(s);
        }
    }
    // Corners: spheres (circles).
    let corners = 1 << dim;
    for m in 0..corners {
        let mut q = [0.0; 3];
        for (axis, qa) in q.iter_mut().enumerate().take(dim) {
            let sign = if m >> axis & 1 == 1 { 1.0 } else { -1.0 };
            *qa = p[axis] - sign * h[axis];
        }
        if let Some(s) = enter_sphere(&q, &u, r, dim) {
            best = best.min(s);
        }
    }
    // Edges (3D): cylinders around the 12 edges, limited to the edge's length.
    if dim == 3 {
        for k in 0..3 {
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            for m in 0..4 {
                let si = if m & 1 == 1 { 1.0 } else { -1.0 };
                let sj = if m & 2 == 2 { 1.0 } else { -1.0 };
                let q = [p[i] - si * h[i], p[j] - sj * h[j], 0.0];
                let uu = [u[i], u[j], 0.0];
                if let Some(s) = enter_sphere(&q, &uu, r, 2) {
                    let along = p[k] + u[k] * s;
                    if along.abs() <= h[k] {
                        best = best.min(s);
                    }
                }
            }
        }
    }
    best.is_finite().then_some(best)
}

fn local3<V: Vector>(v: V) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (axis, o) in out.iter_mut().enumerate().take(V::DIM) {
        *o = v.get(axis);
    }
    out
}

/// Entry time (>= 0) of the ray `p + u s` into the centred box of half extents `h` (slab method).
fn enter_box(p: &[f64; 3], u: &[f64; 3], h: &[f64; 3], dim: usize) -> Option<f64> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for axis in 0..dim {
        let (x, v, e) = (p[axis], u[axis], h[axis]);
        if v == 0.0 {
            if x.abs() > e {
                return None;
            }
            continue;
        }
        let (a, b) = ((-e - x) / v, (e - x) / v);
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        t0 = t0.max(lo);
        t1 = t1.min(hi);
        if t0 > t1 {
            return None;
        }
    }
    Some(t0)
}

/// Entry time (>= 0) of the ray `q + u s` into the ball of radius `r` at the origin.
fn enter_sphere(q: &[f64; 3], u: &[f64; 3], r: f64, dim: usize) -> Option<f64> {
    let dot = |a: &[f64; 3], b: &[f64; 3]| (0..dim).map(|i| a[i] * b[i]).sum::<f64>();
    let b = dot(q, u);
    if b >= 0.0 {
        return None;
    }
    let c = dot(q, q) - r * r;
    if c <= 0.0 {
        return Some(0.0);
    }
    let a = dot(u, u);
    let disc = b * b - a * c;
    if disc < 0.0 {
        return None;
    }
    Some(c / (-b + disc.sqrt()))
}

/// Smallest root `s >= 0` of `a s^2 + b s + c = 0`, or `None`.
pub fn smallest_nonneg_root(a: f64, b: f64, c: f64) -> Option<f64> {
    if a == 0.0 {
        if b == 0.0 {
            return None;
        }
        let s = -c / b;
        return (s >= 0.0).then_some(s);
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let mut best = f64::INFINITY;
    for s in [q / a, if q != 0.0 { c / q } else { f64::NAN }] {
        if s >= 0.0 && s < best {
            best = s;
        }
    }
    best.is_finite().then_some(best)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, DVec2, DVec3};

    /// The early answer by a horizon drops exactly the contacts beyond it: over random pairs
    /// and horizons, among them horizons within a few units in the last place of the contact
    /// time, `toi_ball_ball_by` gives `toi_ball_ball`'s time bit for bit whenever that time is
    /// within the horizon, and `None` only when there is none or it is beyond.
    #[test]
    fn the_early_answer_by_a_horizon_drops_only_contacts_beyond_it() {
        let mut rng = crate::rng::Rng::new(5);
        let (mut early, mut kept) = (0, 0);
        for i in 0..200_000 {
            let d = DVec2::new(rng.uniform(-4.0, 4.0), rng.uniform(-4.0, 4.0));
            let w = DVec2::new(rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0));
            let r = rng.uniform(0.1, 2.0);
            let full = toi_ball_ball(d, w, r);
            let horizon = match (i % 4, full) {
                (0, Some(s)) if s > 0.0 => s * (1.0 + 4e-16 * rng.uniform(-8.0, 8.0)),
                (1, Some(s)) if s > 0.0 => s * (1.0 + 1e-9 * rng.uniform(-2.0, 2.0)),
                (2, _) => rng.uniform(-0.1, 0.1),
                _ => rng.uniform(0.0, 3.0),
            };
            let by = toi_ball_ball_by(d, w, r, horizon);
            match full {
                Some(s) if s <= horizon => {
                    assert_eq!(
                        by.map(f64::to_bits),
                        Some(s.to_bits()),
                        "{d} {w} {r} {horizon}"
                    );
                    kept += 1;
                }
                _ => {
                    if by.is_none() && full.is_some() {
                        early += 1;
                    }
                    assert!(by.is_none_or(|s| s > horizon), "{d} {w} {r} {horizon}");
                }
            }
        }
        assert!(
            early > 3_000 && kept > 10_000,
            "{early} dropped early, {kept} kept"
        );
    }

    /// The branch-free test answers true only where `toi_ball_ball_by` answers `None` and the
    /// disks do not overlap, and it takes most such pairs (random pairs and horizons, as
    /// above).
    #[test]
    fn a_surely_missed_pair_has_no_contact_by_the_horizon() {
        let mut rng = crate::rng::Rng::new(7);
        let (mut dropped, mut missed) = (0, 0);
        for i in 0..200_000 {
            let d = DVec3::new(
                rng.uniform(-4.0, 4.0),
                rng.uniform(-4.0, 4.0),
                rng.uniform(-4.0, 4.0),
            );
            let w = DVec3::new(
                rng.uniform(-3.0, 3.0),
                rng.uniform(-3.0, 3.0),
                rng.uniform(-3.0, 3.0),
            );
            let r = rng.uniform(0.1, 2.5);
            let horizon = match (i % 3, toi_ball_ball(d, w, r)) {
                (0, Some(s)) if s > 0.0 => s * (1.0 + 1e-9 * rng.uniform(-2.0, 2.0)),
                _ => rng.uniform(0.0, 3.0),
            };
            let by = toi_ball_ball_by(d, w, r, horizon);
            if by.is_none() && d.length_squared() >= r * r {
                missed += 1;
            }
            if surely_no_toi_by(d, w, r, horizon) {
                assert_eq!(by, None, "{d} {w} {r} {horizon}");
                assert!(d.length() >= r, "{d} {r}");
                dropped += 1;
            }
        }
        // Only the discriminant's misses are left to `toi_ball_ball_by`.
        assert!(
            dropped > missed * 3 / 4 && dropped > 50_000,
            "{dropped} of {missed} dropped"
        );
    }

    #[test]
    fn ball_ball_head_on_meets_when_the_gap_closes() {
        // Gap 10 - 2 = 8 closed at relative speed 4: s = 2.
        let s = toi_ball_ball(DVec2::new(10.0, 0.0), DVec2::new(-4.0, 0.0), 2.0).unwrap();
        assert!((s - 2.0).abs() < 1e-15);
        // Offset by b = 1.2 across: contact when the along-gap is sqrt(4 - 1.44) = 1.6.
        let s = toi_ball_ball(DVec2::new(10.0, 1.2), DVec2::new(-4.0, 0.0), 2.0).unwrap();
        assert!((s - (10.0 - 1.6) / 4.0).abs() < 1e-14);
        // Misses, separating, touching and approaching.
        assert!(toi_ball_ball(DVec2::new(10.0, 2.1), DVec2::new(-4.0, 0.0), 2.0).is_none());
        assert!(toi_ball_ball(DVec2::new(10.0, 0.0), DVec2::new(4.0, 0.0), 2.0).is_none());
        assert_eq!(
            toi_ball_ball(DVec2::new(1.0, 0.0), DVec2::new(-1.0, 0.0), 2.0),
            Some(0.0)
        );
    }

    #[test]
    fn wall_ball_faces_corners_and_edges() {
        let wall = WallBox::segment(DVec2::new(-2.0, 0.0), DVec2::new(2.0, 0.0), 0.2).unwrap();
        // Face from above: centre at y = 5 falls at 2 until y = 0.1 + 0.5.
        let s = toi_wall_ball(&wall, DVec2::new(0.0, 5.0), DVec2::new(0.0, -2.0), 0.5).unwrap();
        assert!((s - (5.0 - 0.6) / 2.0).abs() < 1e-15);
        // Corner (2, 0.1): moving left along y = 0.4 from x = 10: hits the corner circle where
        // (x - 2)^2 + 0.3^2 = 0.25, x = 2.4.
        let s = toi_wall_ball(&wall, DVec2::new(10.0, 0.4), DVec2::new(-1.0, 0.0), 0.5).unwrap();
        assert!((s - 7.6).abs() < 1e-12);
        // A bullet far faster than the wall is thick still hits it.
        let s = toi_wall_ball(&wall, DVec2::new(0.0, 1e3), DVec2::new(0.0, -1e6), 0.01).unwrap();
        assert!((s - (1e3 - 0.11) / 1e6).abs() < 1e-18);
        // Rotated wall: same answer in its own frame.
        let f = DVec2::new(3.0, 4.0) / 5.0;
        let rot = WallBox::new(DVec2::ZERO, DVec2::new(2.0, 0.1), f).unwrap();
        let s = toi_wall_ball(&rot, f.perp() * 5.0, -f.perp() * 2.0, 0.5).unwrap();
        assert!((s - 2.2).abs() < 1e-14);
        // 3D edge x = 1, y = 1: moving along -x at y = 1.3, z = 0: cylinder radius 0.5 met at
        // x = 1 + 0.4.
        let cube =
            WallBox::cuboid(DVec3::ZERO, DVec3::new(2.0, 2.0, 2.0), DMat3::IDENTITY).unwrap();
        let s = toi_wall_ball(
            &cube,
            DVec3::new(5.0, 1.3, 0.0),
            DVec3::new(-1.0, 0.0, 0.0),
            0.5,
        )
        .unwrap();
        assert!((s - 3.6).abs() < 1e-12);
        // Past the end of the edge the corner sphere takes over: z = 1.3.
        let s = toi_wall_ball(
            &cube,
            DVec3::new(5.0, 1.3, 1.3),
            DVec3::new(-1.0, 0.0, 0.0),
            0.5,
        )
        .unwrap();
        let x = 1.0 + (0.25f64 - 0.18).sqrt();
        assert!((s - (5.0 - x)).abs() < 1e-12);
    }

    #[test]
    fn quadratic_roots() {
        assert_eq!(smallest_nonneg_root(1.0, -3.0, 2.0), Some(1.0));
        assert_eq!(smallest_nonneg_root(0.0, 2.0, -4.0), Some(2.0));
        assert_eq!(smallest_nonneg_root(1.0, 0.0, 1.0), None);
        // Falling from 5 under g = 10: 5 - 5 s^2 = 0 at s = 1.
        assert_eq!(smallest_nonneg_root(-5.0, 0.0, 5.0), Some(1.0));
    }
}
