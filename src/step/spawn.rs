//! Spawning onto the state: every spawn checked, so a bad one is an error naming the critter and
//! the field, and nothing is added then. A spawn may also be *placed* under an [`OnOverlap`]
//! policy: what happens when it would overlap a wall or another critter (scripts'
//! `on_overlap`).

use super::pending::OnOverlap;
use super::state::State;
use crate::border::{Border, Topology};
use crate::contact::contact_wall_ball;
use crate::critter::{
    check_positive, check_restitution, Critter, CritterId, CritterSpec, Shape, Traits, CLASS_UNSET,
    CP_WALL,
};
use crate::error::Error;
use crate::kind::WALL;
use crate::tolerance::ROUNDING_MARGIN;
use crate::vector::{fmt_vec, Vector};
use crate::wall::WallBox;
use std::sync::Arc;

/// The largest radius a critter may have: its mass, density x radius^3, stays far from
/// overflowing f64 (about 1e308), and so do the squared distances the contacts compute.
pub const MAX_RADIUS: f64 = 1e100;
/// The smallest radius a critter may have: its mass, density x radius^3, stays far from
/// underflowing to zero.
pub const MIN_RADIUS: f64 = 1e-100;

/// Moves `OnOverlap::Push` makes before it gives up.
pub(crate) const MAX_PUSHES: usize = 16;

/// What became of a spawn placed under a policy.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Placed {
    /// Added with this id.
    Added(CritterId),
    /// Not added; why, in words.
    Skipped(String),
}

/// An overlap found when placing a spawn: with what, and the way out.
struct Overlap<V> {
    what: String,
    normal: V,
    depth: f64,
}

impl<V: Vector> State<V> {
    /// Adds a wall (always fixed, priority CP_WALL, kind `wall`).
    pub(crate) fn add_wall(&mut self, wall: WallBox<V>) -> Result<CritterId, Error> {
        wall.validate()?;
        self.check_clear_of_critters(&wall)?;
        let center = wall.center;
        let radius = wall.bounding_radius();
        let id = self.critters.insert(|id| Critter {
            id,
            class: CLASS_UNSET,
            pos: center,
            vel: V::zero(),
            radius,
            _align: [],
            fixed: true,
            alive: true,
            wall: true,
            aside: false,
            traits: Arc::new(Traits {
                kind: WALL,
                mass: f64::INFINITY,
                priority: CP_WALL,
                restitution: 1.0,
                health: 1.0,
                shape: Shape::Wall(Box::new(wall)),
                props: Default::default(),
                color: None,
            }),
        });
        self.walls.push(id);
        Ok(id)
    }

    /// Spawns a critter now. Errors name the critter and the bad field; nothing is added then.
    pub(crate) fn spawn(&mut self, spec: CritterSpec<V>) -> Result<CritterId, Error> {
        let critter = self.build(spec)?;
        let has_init = self.kinds.get(critter.kind()).has_init;
        let id = self.critters.insert(|id| Critter { id, ..critter });
        self.neighbours.moved(id);
        self.births.note(id, self.step_count);
        if has_init {
            self.run_init(id)?;
        }
        Ok(id)
    }

    /// Spawns a critter now, placed under `on_overlap` (see [`OnOverlap`]).
    pub(crate) fn spawn_placed(
        &mut self,
        mut spec: CritterSpec<V>,
        on_overlap: OnOverlap,
    ) -> Result<Placed, Error> {
        let radius = match self.kinds.id(&spec.kind) {
            Ok(k) => spec.radius.unwrap_or(self.kinds.get(k).defaults.radius),
            // Unknown kinds fail in `spawn`, with the usual message.
            Err(_) => return self.spawn(spec).map(Placed::Added),
        };
        let fits = spec.pos.all_finite() && radius.is_finite() && radius > 0.0;
        if fits && on_overlap != OnOverlap::Error {
            // An impossible radius is an error whatever the policy: pushing cannot fix it.
            let who = || format!("the {} spawned at {}", spec.kind, fmt_vec(spec.pos));
            self.check_radius(who, radius)?;
        }
        match on_overlap {
            OnOverlap::Error => return self.spawn(spec).map(Placed::Added),
            _ if !fits => return self.spawn(spec).map(Placed::Added),
            OnOverlap::Skip => {
                if let Some(o) = self.deepest_overlap(spec.pos, radius) {
                    return Ok(Placed::Skipped(format!(
                        "the {} to spawn at {} overlaps {} by {:.3}",
                        spec.kind,
                        fmt_vec(spec.pos),
                        o.what,
                        o.depth
                    )));
                }
            }
            OnOverlap::Push => match self.push_free(spec.pos, radius) {
                Ok(p) => spec.pos = p,
                Err(o) => {
                    return Ok(Placed::Skipped(format!(
                    "the {} to spawn at {} still overlaps {} by {:.3} after {MAX_PUSHES} pushes",
                    spec.kind,
                    fmt_vec(spec.pos),
                    o.what,
                    o.depth
                )))
                }
            },
        }
        self.spawn(spec).map(Placed::Added)
    }

    /// The deepest overlap of a disk of radius `r` at `p` with a wall or a live critter.
    fn deepest_overlap(&self, p: V, r: f64) -> Option<Overlap<V>> {
        let margin = ROUNDING_MARGIN * r.max(1.0);
        let mut deepest: Option<Overlap<V>> = None;
        let mut consider = |o: Overlap<V>| {
            if o.depth > margin && deepest.as_ref().is_none_or(|d| o.depth > d.depth) {
                deepest = Some(o);
            }
        };
        for c in self.critters.iter() {
            if !c.alive {
                continue;
            }
            let d = self.topo.delta(c.pos, p);
            match c.shape() {
                Shape::Wall(geom) => {
                    if let Some(hit) = contact_wall_ball(geom, d, r) {
                        consider(Overlap {
                            what: format!("wall {}", c.id),
                            normal: hit.normal,
                            depth: hit.depth,
                        });
                    }
                }
                Shape::Disk => {
                    let dist = d.length();
                    let depth = c.radius + r - dist;
                    if depth > 0.0 {
                        // Coincident centres: out along the x axis, as contacts do.
                        let normal = if dist > 0.0 { d / dist } else { V::unit_x() };
                        consider(Overlap {
                            what: format!("critter {}", c.id),
                            normal,
                            depth,
                        });
                    }
                }
            }
        }
        deepest
    }

    /// `p` moved out of the walls and critters a disk of radius `r` there overlaps, or the
    /// overlap left after [`MAX_PUSHES`] moves.
    fn push_free(&self, mut p: V, r: f64) -> Result<V, Overlap<V>> {
        let margin = ROUNDING_MARGIN * r.max(1.0);
        for _ in 0..MAX_PUSHES {
            let Some(o) = self.deepest_overlap(p, r) else {
                return Ok(p);
            };
            p += o.normal * (o.depth + margin);
            for axis in 0..V::DIM {
                let (lo, hi) = (self.topo.min.get(axis), self.topo.max.get(axis));
                p.set(axis, p.get(axis).clamp(lo, hi));
            }
        }
        self.deepest_overlap(p, r).map_or(Ok(p), Err)
    }

    /// The critter `spec` asks for, checked: errors name the critter and the bad field.
    fn build(&self, spec: CritterSpec<V>) -> Result<Critter<V>, Error> {
        let kind_id = self.kinds.id(&spec.kind)?;
        if kind_id == WALL {
            return Err(Error::InvalidKind {
                kind: spec.kind,
                reason: "walls are added with add_wall (they need a box, not a radius)".into(),
            });
        }
        let kind = self.kinds.get(kind_id);
        let d = &kind.defaults;
        let who = || format!("the {} spawned at {}", spec.kind, fmt_vec(spec.pos));
        if !spec.pos.all_finite() {
            return Err(Error::InvalidCritter {
                critter: who(),
                field: "position",
                value: fmt_vec(spec.pos),
                reason: "every coordinate must be a finite number".into(),
            });
        }
        for axis in 0..V::DIM {
            let x = spec.pos.get(axis);
            if x < self.topo.min.get(axis) || x > self.topo.max.get(axis) {
                return Err(Error::InvalidCritter {
                    critter: who(),
                    field: "position",
                    value: fmt_vec(spec.pos),
                    reason: format!(
                        "outside the world box {} to {}",
                        fmt_vec(self.topo.min),
                        fmt_vec(self.topo.max)
                    ),
                });
            }
        }
        if !spec.vel.all_finite() {
            return Err(Error::InvalidCritter {
                critter: who(),
                field: "velocity",
                value: fmt_vec(spec.vel),
                reason: "every component must be a finite number".into(),
            });
        }
        let radius = spec.radius.unwrap_or(d.radius);
        check_positive(who, "radius", radius)?;
        self.check_radius(who, radius)?;
        let density = spec.density.unwrap_or(d.density);
        check_positive(who, "density", density)?;
        let mass = spec
            .mass
            .or(if spec.density.is_some() { None } else { d.mass });
        let derived = mass.is_none();
        let mass = mass.unwrap_or(density * radius * radius * radius);
        if derived && !(mass.is_finite() && mass > 0.0) {
            // The user gave the density and the radius, not the mass: name those.
            return Err(Error::InvalidCritter {
                critter: who(),
                field: "density",
                value: fmt_number(density),
                reason: format!(
                    "with radius {} it gives the mass density x radius^3 = {}; give a density nearer 1, or the mass itself",
                    fmt_number(radius),
                    fmt_number(mass)
                ),
            });
        }
        check_positive(who, "mass", mass)?;
        let restitution = spec.restitution.unwrap_or(d.restitution);
        check_restitution(who, restitution)?;
        let priority = spec.priority.unwrap_or(d.priority);
        if !priority.is_finite() {
            return Err(Error::InvalidCritter {
                critter: who(),
                field: "priority",
                value: priority.to_string(),
                reason: "must be a finite number; use the CP_* constants".into(),
            });
        }
        let health = spec.health.unwrap_or(d.health);
        if !health.is_finite() {
            return Err(Error::InvalidCritter {
                critter: who(),
                field: "health",
                value: health.to_string(),
                reason: "must be a finite number".into(),
            });
        }
        for &wall_id in &self.walls {
            let Some(wall) = self.critters.get(wall_id) else {
                continue;
            };
            let Shape::Wall(geom) = wall.shape() else {
                continue;
            };
            let d = self.topo.delta(wall.pos, spec.pos);
            if let Some(c) = contact_wall_ball(geom, d, radius) {
                if c.depth > ROUNDING_MARGIN * radius.max(1.0) {
                    return Err(Error::SpawnInsideWall {
                        critter: who(),
                        wall: wall_id,
                        depth: c.depth,
                    });
                }
            }
        }
        let fixed = spec.fixed.unwrap_or(d.fixed);
        let color = match spec.color.as_deref() {
            Some(c) => Some(
                crate::color::checked(c).map_err(|reason| Error::InvalidCritter {
                    critter: who(),
                    field: "color",
                    value: c.to_string(),
                    reason,
                })?,
            ),
            None => None,
        };
        Ok(Critter {
            id: CritterId {
                index: 0,
                generation: 0,
            },
            class: CLASS_UNSET,
            pos: spec.pos,
            vel: spec.vel,
            radius,
            _align: [],
            fixed,
            alive: true,
            wall: false,
            aside: false,
            traits: Arc::new(Traits {
                kind: kind_id,
                mass,
                priority,
                restitution,
                health,
                shape: Shape::Disk,
                props: {
                    let mut props = d.props.clone();
                    props.extend(spec.props);
                    props
                },
                color,
            }),
        })
    }
}

/// `x` as a user writes it: plain for ordinary sizes, `1e300` for extreme ones.
fn fmt_number(x: f64) -> String {
    if x != 0.0 && x.is_finite() && !(1e-4..1e15).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// The box's sides, `10 x 10` (or `10 x 10 x 10`).
fn fmt_sides<V: Vector>(size: V) -> String {
    let sides: Vec<String> = (0..V::DIM).map(|a| fmt_number(size.get(a))).collect();
    sides.join(" x ")
}

/// A radius (finite and positive) within [`MIN_RADIUS`]..=[`MAX_RADIUS`] and whose disk fits in
/// the world box `topo` when its border bounds it (bounce, clamp): errors name the radius and
/// the box. For spawns and for a live critter's new radius alike.
pub(crate) fn check_radius_in_box<V: Vector>(
    topo: &Topology<V>,
    who: impl Fn() -> String,
    radius: f64,
) -> Result<(), Error> {
    let bad = |reason: String| Error::InvalidRadius {
        critter: who(),
        radius: fmt_number(radius),
        reason,
    };
    if radius > MAX_RADIUS {
        return Err(bad(format!(
            "is too large: a radius is at most {MAX_RADIUS:e} (beyond it the mass, density x radius^3, is not a finite number)"
        )));
    }
    if radius < MIN_RADIUS {
        return Err(bad(format!(
            "is too small: a radius is at least {MIN_RADIUS:e} (below it the mass, density x radius^3, is zero)"
        )));
    }
    if matches!(topo.border, Border::Bounce | Border::Clamp) {
        let size = topo.size();
        let diameter = 2.0 * radius;
        let side = (0..V::DIM)
            .map(|a| size.get(a))
            .fold(f64::INFINITY, f64::min);
        if diameter > side {
            return Err(bad(format!(
                "does not fit in the world box {} (its diameter {} exceeds the side {}): give a radius of at most {}, or make the world larger",
                fmt_sides(size),
                fmt_number(diameter),
                fmt_number(side),
                fmt_number(0.5 * side)
            )));
        }
    }
    Ok(())
}

impl<V: Vector> State<V> {
    /// A radius (finite and positive) within [`MIN_RADIUS`]..=[`MAX_RADIUS`] whose disk fits in
    /// the world box ([`check_radius_in_box`]) and between the walls lining it.
    fn check_radius(&self, who: impl Fn() -> String, radius: f64) -> Result<(), Error> {
        check_radius_in_box(&self.topo, &who, radius)?;
        self.check_fits_between_walls(who, radius)
    }

    /// The disk fits between the walls that line the world box (axis-aligned walls that cover
    /// a whole face of it, as `walls_around` adds): errors name the radius and the space left.
    fn check_fits_between_walls(&self, who: impl Fn() -> String, radius: f64) -> Result<(), Error> {
        let (min, max) = (self.topo.min, self.topo.max);
        let (mut lo, mut hi) = (min, max);
        for &id in &self.walls {
            let Some(Shape::Wall(geom)) = self.critters.get(id).map(|c| c.shape()) else {
                continue;
            };
            if geom.frame != V::identity_frame() {
                continue;
            }
            let (a, b) = (geom.center - geom.half, geom.center + geom.half);
            for axis in 0..V::DIM {
                let covers_face = (0..V::DIM)
                    .filter(|&o| o != axis)
                    .all(|o| a.get(o) <= min.get(o) && b.get(o) >= max.get(o));
                if !covers_face {
                    continue;
                }
                if a.get(axis) <= min.get(axis) && b.get(axis) < max.get(axis) {
                    lo.set(axis, lo.get(axis).max(b.get(axis)));
                }
                if b.get(axis) >= max.get(axis) && a.get(axis) > min.get(axis) {
                    hi.set(axis, hi.get(axis).min(a.get(axis)));
                }
            }
        }
        if lo == min && hi == max {
            return Ok(());
        }
        let space = hi - lo;
        let diameter = 2.0 * radius;
        let side = (0..V::DIM)
            .map(|a| space.get(a))
            .fold(f64::INFINITY, f64::min);
        if diameter > side {
            return Err(Error::InvalidRadius {
                critter: who(),
                radius: fmt_number(radius),
                reason: format!(
                    "does not fit between the walls lining the world box, {} to {}, a space of {} (its diameter {} exceeds the side {}): give a radius of at most {}",
                    fmt_vec(lo),
                    fmt_vec(hi),
                    fmt_sides(space),
                    fmt_number(diameter),
                    fmt_number(side),
                    fmt_number(0.5 * side.max(0.0))
                ),
            });
        }
        Ok(())
    }

    /// The live critters `wall` would reach into, and by how much.
    fn reached_by<'a>(
        &'a self,
        wall: &'a WallBox<V>,
    ) -> impl Iterator<Item = (&'a Critter<V>, f64)> + 'a {
        self.critters.iter().filter_map(move |c| {
            if !c.alive || c.is_wall() {
                return None;
            }
            let d = self.topo.delta(wall.center, c.pos);
            let hit = contact_wall_ball(wall, d, c.radius)?;
            (hit.depth > ROUNDING_MARGIN * c.radius.max(1.0)).then_some((c, hit.depth))
        })
    }

    /// The critters a wall would reach into (tests clear its place before they put it down).
    #[cfg(test)]
    pub(crate) fn critters_under(&self, wall: &WallBox<V>) -> Vec<CritterId> {
        self.reached_by(wall).map(|(c, _)| c.id).collect()
    }

    /// A new wall must not reach into a live critter, as a new critter must not reach into a
    /// wall ([`Error::SpawnInsideWall`]): both orders are errors.
    fn check_clear_of_critters(&self, wall: &WallBox<V>) -> Result<(), Error> {
        let Some((c, depth)) = self.reached_by(wall).next() else {
            return Ok(());
        };
        let size = wall.aabb_half() * 2.0;
        Err(Error::WallThroughCritter {
            wall: format!(
                "the wall at {} (size {})",
                fmt_vec(wall.center),
                fmt_sides(size)
            ),
            critter: format!(
                "critter {} ({} at {}, radius {})",
                c.id,
                self.kinds.name(c.kind()),
                fmt_vec(c.pos),
                fmt_number(c.radius)
            ),
            depth,
        })
    }
}
