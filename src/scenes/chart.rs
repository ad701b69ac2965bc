//! The sweep behind `critterbox chart`: each method's cost against its error over a range of
//! time steps, on a gas (error against the exact run) and on the deep pile of [`super::stress`]
//! (error the deepest overlap); and each method's cost per step against each part's error on the
//! mixed scenes of [`super::mixed`].

use super::mixed::MIXED;
use super::stress::{max_overlap, pile, DEEP_PILE_ROWS};
use super::{gas, GasParams};
use crate::critter::CritterId;
use crate::error::Error;
use crate::method::Method;
use crate::world::World;
use glam::DVec2;

/// One point of the speed-against-accuracy chart.
#[derive(Clone, Debug)]
pub struct ChartPoint {
    /// The method.
    pub method: Method,
    /// The time step.
    pub dt: f64,
    /// Wall time per simulated second per critter (seconds).
    pub cost: f64,
    /// The error at the end, in radii: the gas's root-mean-square position error against the
    /// event-driven reference, or the pile's deepest overlap.
    pub error: f64,
}

/// The chart's scene: 100 disks of radius 0.5 at packing fraction 0.3 in a walled box, speeds
/// up to 6 per axis, one simulated second.
fn chart_gas(method: Method, dt: f64) -> Result<World<DVec2>, Error> {
    let mut w = gas::<DVec2>(&GasParams {
        n: 100,
        packing: 0.3,
        dt,
        seed: 7,
        ..Default::default()
    })?;
    let ids: Vec<CritterId> = w.critters().iter().map(|c| c.id()).collect();
    for id in ids {
        if let Some(c) = w.get_mut(id) {
            c.vel *= 6.0;
        }
    }
    w.set_method(method)?;
    Ok(w)
}

/// Runs the chart's second sweep, where methods fail on resting contacts: the deep pile
/// ([`DEEP_PILE_ROWS`] rows under gravity) for two simulated seconds at dt = 1/15 ... 1/240, the
/// error being the deepest overlap at the end in radii (the stability table's measure).
pub fn chart_pile_points(methods: &[Method]) -> Result<Vec<ChartPoint>, Error> {
    let build = |method, dt| pile(method, DEEP_PILE_ROWS, dt);
    dt_sweep(methods, 5, 2.0, build, max_overlap)
}

/// Runs the chart's sweep: each method at dt = 1/15 ... 1/960 over one simulated second, error
/// against the event method at dt = 1 (one step: no step boundaries at all).
pub fn chart_points(methods: &[Method]) -> Result<Vec<ChartPoint>, Error> {
    let mut reference = chart_gas(Method::Event, 1.0)?;
    reference.step()?;
    let want: Vec<DVec2> = reference.critters().iter().map(|c| c.pos).collect();
    let error = |w: &World<DVec2>| {
        let (mut sum, mut n) = (0.0, 0.0);
        for (c, p) in w.critters().iter().zip(&want) {
            if !c.is_wall() {
                sum += (c.pos - *p).length_squared() / (c.radius() * c.radius());
                n += 1.0;
            }
        }
        (sum / n).sqrt()
    };
    dt_sweep(methods, 7, 1.0, chart_gas, error)
}

/// Runs each method at `dts` time steps, dt = 1/15, 1/30, ..., for `seconds` simulated seconds
/// on the scene `build` makes, and measures the cost (wall time per simulated second per
/// critter) and `error` of the world at the end.
fn dt_sweep(
    methods: &[Method],
    dts: i32,
    seconds: f64,
    build: impl Fn(Method, f64) -> Result<World<DVec2>, Error>,
    error: impl Fn(&World<DVec2>) -> f64,
) -> Result<Vec<ChartPoint>, Error> {
    let mut out = Vec::new();
    for &method in methods {
        for k in 0..dts {
            let dt = 1.0 / (15.0 * 2f64.powi(k));
            let mut w = build(method, dt)?;
            let steps = (seconds / dt).round() as u64;
            let n = w.critters().iter().filter(|c| !c.is_wall()).count() as f64;
            let start = std::time::Instant::now();
            w.run(steps)?;
            let cost = start.elapsed().as_secs_f64() / n / seconds;
            out.push(ChartPoint {
                method,
                dt,
                cost,
                error: error(&w),
            });
        }
    }
    Ok(out)
}

/// One point of the chart's mixed panel: a method's cost on a mixed scene and one part's error.
#[derive(Clone, Debug)]
pub struct MixedPoint {
    /// The method.
    pub method: Method,
    /// The scene's name.
    pub scene: &'static str,
    /// The part's name.
    pub part: &'static str,
    /// Wall time per step of the whole scene (seconds).
    pub cost: f64,
    /// The part's error (its own measure: [`super::mixed::Part`]).
    pub error: f64,
}

/// Runs each 2D mixed scene once under each method: a point per part.
pub fn chart_mixed_points(methods: &[Method]) -> Result<Vec<MixedPoint>, Error> {
    let mut out = Vec::new();
    for &method in methods {
        for scene in MIXED {
            let start = std::time::Instant::now();
            let errors = (scene.run)(method)?;
            let cost = start.elapsed().as_secs_f64() / scene.steps as f64;
            for (part, error) in scene.parts.iter().zip(errors) {
                out.push(MixedPoint {
                    method,
                    scene: scene.name,
                    part: part.name,
                    cost,
                    error,
                });
            }
        }
    }
    Ok(out)
}
