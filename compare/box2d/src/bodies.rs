//! A scene's bodies as plain data, and the measures taken the same way of both engines: kinetic
//! energy per unit mass, the deepest overlap and the disks that left the box.
//!
//! Both engines are measured from the same plain data (positions and velocities read out of each
//! engine), so neither engine's own diagnostics decide a figure: critterbox's in f64, Box2D's read
//! from f32 and widened.

use critterbox::glam::DVec2;
use critterbox::World;
use std::collections::HashMap;

/// One disk: where it is, how fast it moves, its size and bounce.
#[derive(Clone, Copy, Debug)]
pub struct Disk {
    pub pos: DVec2,
    pub vel: DVec2,
    pub radius: f64,
    pub restitution: f64,
}

/// One axis-aligned wall box.
#[derive(Clone, Copy, Debug)]
pub struct Wall {
    pub center: DVec2,
    pub half: DVec2,
}

/// The bodies of a critterbox world, with the settings Box2D needs to be built alike.
pub struct Bodies {
    pub disks: Vec<Disk>,
    pub walls: Vec<Wall>,
    pub dt: f64,
    pub gravity: DVec2,
}

impl Bodies {
    /// The disks and walls of `world` (every wall of the scenes here is axis-aligned).
    pub fn of(world: &World<DVec2>) -> Bodies {
        let mut walls = Vec::new();
        for c in world.critters().iter() {
            if let Some(wall) = c.wall() {
                walls.push(Wall {
                    center: wall.center,
                    half: wall.half,
                });
            }
        }
        Bodies {
            disks: disks_of(world),
            walls,
            dt: world.dt(),
            gravity: world.gravity(),
        }
    }
}

/// The live disks of a critterbox world (walls left out), in id order.
pub fn disks_of(world: &World<DVec2>) -> Vec<Disk> {
    world
        .critters()
        .iter()
        .filter(|c| c.is_alive() && !c.is_wall())
        .map(|c| Disk {
            pos: c.pos,
            vel: c.vel,
            radius: c.radius(),
            restitution: c.restitution(),
        })
        .collect()
}

/// Kinetic energy per unit mass, the sum of v^2 / 2: every disk of a scene here has the same
/// mass, so this is the energy over one disk's mass whatever mass each engine gives a disk.
pub fn energy(disks: &[Disk]) -> f64 {
    disks.iter().map(|d| 0.5 * d.vel.length_squared()).sum()
}

/// How far a disk reaches into an axis-aligned box: its radius plus the way out when its centre
/// is inside, its radius less the distance to the box otherwise (negative: not touching).
fn wall_depth(d: &Disk, w: &Wall) -> f64 {
    let q = (d.pos - w.center).abs() - w.half;
    if q.x <= 0.0 && q.y <= 0.0 {
        d.radius - q.x.max(q.y)
    } else {
        d.radius - q.max(DVec2::ZERO).length()
    }
}

/// The deepest overlap between two disks (in radii of the smaller) or a disk and a wall (in the
/// disk's radii); infinite when a position is not finite. Pairs are found on a grid of cells two
/// largest radii wide, so every touching pair is in neighbouring cells.
pub fn deepest_overlap(disks: &[Disk], walls: &[Wall]) -> f64 {
    if disks.iter().any(|d| !d.pos.is_finite()) {
        return f64::INFINITY;
    }
    let mut worst: f64 = 0.0;
    for d in disks {
        for w in walls {
            worst = worst.max(wall_depth(d, w) / d.radius);
        }
    }
    let cell = 2.0 * disks.iter().map(|d| d.radius).fold(0.0, f64::max);
    if cell <= 0.0 {
        return worst;
    }
    let key = |p: DVec2| ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64);
    let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, d) in disks.iter().enumerate() {
        grid.entry(key(d.pos)).or_default().push(i);
    }
    for (i, a) in disks.iter().enumerate() {
        let (cx, cy) = key(a.pos);
        for dx in -1..=1 {
            for dy in -1..=1 {
                let Some(cell) = grid.get(&(cx + dx, cy + dy)) else {
                    continue;
                };
                // Each pair once: from its lower index.
                for &j in cell.iter().filter(|&&j| j > i) {
                    let b = &disks[j];
                    let depth = a.radius + b.radius - a.pos.distance(b.pos);
                    worst = worst.max(depth / a.radius.min(b.radius));
                }
            }
        }
    }
    worst
}

/// Disks whose centres are not strictly inside the box from `min` to `max` (tunnelled through a
/// wall, or lost).
pub fn outside(disks: &[Disk], min: DVec2, max: DVec2) -> usize {
    disks
        .iter()
        .filter(|d| !(d.pos.cmpgt(min).all() && d.pos.cmplt(max).all()))
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disk(x: f64, y: f64) -> Disk {
        Disk {
            pos: DVec2::new(x, y),
            vel: DVec2::ZERO,
            radius: 0.5,
            restitution: 1.0,
        }
    }

    #[test]
    fn overlaps_are_in_radii() {
        let floor = Wall {
            center: DVec2::new(0.0, -1.0),
            half: DVec2::new(10.0, 1.0),
        };
        // Two disks 0.9 apart overlap by 0.1 = 0.2 radii; a disk at y = 0.45 reaches 0.05
        // (0.1 radii) into the floor, and one with its centre inside it 0.5 + 0.2 (1.4 radii).
        let pair = [disk(0.0, 3.0), disk(0.9, 3.0)];
        assert!((deepest_overlap(&pair, &[floor]) - 0.2).abs() < 1e-12);
        assert!((deepest_overlap(&[disk(3.0, 0.45)], &[floor]) - 0.1).abs() < 1e-12);
        assert!((deepest_overlap(&[disk(3.0, -0.2)], &[floor]) - 1.4).abs() < 1e-12);
        assert_eq!(
            deepest_overlap(&[disk(0.0, 3.0), disk(2.0, 3.0)], &[floor]),
            0.0
        );
    }
}
