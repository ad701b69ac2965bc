//! Where `solve:n` fails (`docs/stability.md`, "Where solve fails"): readings of an elastic gas
//! (its kinetic energy and its pressure from the collision virial) and of Newton's cradle (the
//! striker's velocity and the energy kept), for any method, so that the tests and the doc
//! compare `solve:8` with the exact methods on the same scenes. A simultaneous solve of the
//! contacts is not a sequence of pair collisions: where the sequence is the physics, it fails.

use super::builtin::spawn_cradle;
use super::{gas, GasParams};
use crate::border::Border;
use crate::error::Error;
use crate::method::Method;
use crate::world::{World, WorldConfig};
use glam::DVec2;

/// What [`gas_reading`] measures.
#[derive(Clone, Copy, Debug)]
pub struct GasReading {
    /// Disk-disk collisions that exchanged an impulse.
    pub impacts: u64,
    /// Steps taken.
    pub steps: u64,
    /// Relative change of the kinetic energy (0 for an elastic gas).
    pub energy_drift: f64,
    /// The compressibility factor `Z = PA / (NkT) = 1 + sum(d J) / (2 N kT t)` from the collision
    /// virial (contact distance times impulse, summed over the collisions of the run), with kT
    /// the mean kinetic energy per disk averaged over the steps (a gas that loses energy is
    /// read at its mean temperature).
    pub z: f64,
}

/// The standard gas of the benchmarks ([`GasParams`]'s defaults: 1,000 disks of radius 0.5 at
/// packing fraction 0.2, elastic, dt 1/60) in a periodic box, run under `method` until at least
/// `impacts` collisions (or 10 steps per collision asked): its energy drift and pressure. The virial is summed from the
/// collisions each step records with their impulses, so every method is read the same way.
pub fn gas_reading(method: Method, impacts: u64) -> Result<GasReading, Error> {
    let mut w: World<DVec2> = gas(&GasParams {
        border: Border::Wrap,
        ..GasParams::default()
    })?;
    w.set_method(method)?;
    let n = w.critters().len() as f64;
    let e0 = w.kinetic_energy();
    let (mut counted, mut steps, mut virial, mut energy) = (0, 0, 0.0, 0.0);
    // A gas that stops colliding (or blows up) ends the run: `impacts` then says so.
    while counted < impacts && steps < 10 * impacts + 1000 && w.kinetic_energy().is_finite() {
        w.step()?;
        steps += 1;
        energy += w.kinetic_energy();
        for ev in &w.events().collisions {
            let (Some(a), Some(b)) = (w.get(ev.caller), w.get(ev.arg)) else {
                continue;
            };
            if ev.impulse > 0.0 && !a.is_wall() && !b.is_wall() {
                counted += 1;
                virial += (a.radius() + b.radius()) * ev.impulse;
            }
        }
    }
    let e = w.kinetic_energy();
    let kt = energy / steps.max(1) as f64 / n; // kT = (2/D) x mean kinetic energy per disk, D = 2
    Ok(GasReading {
        impacts: counted,
        steps,
        energy_drift: (e - e0) / e0,
        z: 1.0 + virial / (2.0 * n * kt * w.time()),
    })
}

/// What [`cradle_reading`] measures of Newton's cradle.
#[derive(Clone, Copy, Debug)]
pub struct CradleReading {
    /// The striker's velocity along the row after the strike, relative to its speed before
    /// (exact: 0; negative: it rebounds).
    pub striker: f64,
    /// The last ball's, relative (exact: 1).
    pub last: f64,
    /// Kinetic energy after the strike over before (exact: 1).
    pub energy_kept: f64,
}

/// The stress scenes' cradle (the built-in scene's striker at 1 and five touching balls, no
/// gravity) run for 3 s under `method`: the striker's and last ball's velocities and the energy
/// kept.
pub fn cradle_reading(method: Method) -> Result<CradleReading, Error> {
    let mut w = World::new(
        WorldConfig::new(DVec2::ZERO, DVec2::new(40.0, 4.0))
            .dt(1.0 / 60.0)
            .method(method),
    )?;
    let ids = spawn_cradle(&mut w, 5)?;
    let e0 = w.kinetic_energy();
    w.run(180)?;
    let vx = |id| w.get(id).map_or(f64::NAN, |c| c.vel.x);
    Ok(CradleReading {
        striker: vx(ids[0]),
        last: vx(ids[ids.len() - 1]),
        energy_kept: w.kinetic_energy() / e0,
    })
}
