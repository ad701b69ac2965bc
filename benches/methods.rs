//! The event method's throughput and exactness (`docs/methods.md` reports the figures):
//!
//! * collisions per second, 2D gas of 10,000 disks at packing fraction 0.4 in a periodic box;
//! * the same for 32,000 spheres at packing fraction 0.40 (Smallenburg's system), with the
//!   compressibility factor from the collision virial (literature: about 6.91);
//! * kinetic-energy drift over 1e6 collisions at e = 1.
//!
//! `cargo bench --bench methods` runs criterion (throughput in collisions/s);
//! `CRITTERBOX_REPORT=1 cargo bench --bench methods` prints the report instead
//! (`CRITTERBOX_REPORT=2d` or `=3d` for one system; `CRITTERBOX_DT=0.0166667` measures steps
//! of that length instead of 5, after the same warm-up step of 5).

use criterion::{Criterion, Throughput};
use critterbox::glam::{DVec2, DVec3};
use critterbox::scenes::{gas, GasParams};
use critterbox::{Border, Method, Vector, World};
use std::time::{Duration, Instant};

fn periodic_gas<V: Vector>(n: usize, packing: f64, dt: f64) -> World<V> {
    let mut w = gas::<V>(&GasParams {
        n,
        packing,
        dt,
        border: Border::Wrap,
        ..GasParams::default()
    })
    .expect("the gas builds");
    w.set_method(Method::Event).expect("event");
    w
}

/// Runs until `collisions` impacts; returns (impacts, seconds, relative energy drift, Z).
fn measure<V: Vector>(w: &mut World<V>, collisions: usize) -> (usize, f64, f64, f64) {
    let e0 = w.kinetic_energy();
    let n = w.critters().len() as f64;
    let mut virial = 0.0;
    let mut impacts = 0;
    let t0 = w.time();
    let start = Instant::now();
    while impacts < collisions {
        w.step().expect("steps");
        impacts += w.stats().impacts;
        virial += w.collision_virial();
        assert_eq!(w.stats().budget_exceeded, 0, "event budget ran out");
    }
    let secs = start.elapsed().as_secs_f64();
    let t = w.totals();
    println!(
        "  {:.0} collisions per step; per collision: {:.2} events, {:.2} predictions, {:.1} pair tests",
        impacts as f64 / ((w.time() - t0) / w.dt()).round(),
        t.events as f64 / t.impacts as f64,
        t.candidates as f64 / t.impacts as f64,
        t.pair_tests as f64 / t.impacts as f64
    );
    let e = w.kinetic_energy();
    let d = V::DIM as f64;
    let kt = 2.0 * e / (d * n); // kT = (2/D) x mean kinetic energy (unit masses scaled out)
    let t = w.time() - t0;
    let z = 1.0 + virial / (d * n * kt * t);
    (impacts, secs, (e - e0) / e0, z)
}

/// `which`: "2d" or "3d" for one system, anything else for both.
fn report(which: &str) {
    // Warm up: relax from the grid start before measuring.
    if which != "3d" {
        report_2d();
    }
    if which != "2d" {
        report_3d();
    }
}

/// The measured steps' length: 5, or `CRITTERBOX_DT` (a frame's 1/60 shows the per-step cost).
fn measured_dt() -> f64 {
    std::env::var("CRITTERBOX_DT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5.0)
}

/// Collisions to measure: 2e6, or `CRITTERBOX_COLLISIONS` (shorter runs for profilers).
fn collisions() -> usize {
    std::env::var("CRITTERBOX_COLLISIONS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2_000_000)
}

fn report_2d() {
    let mut g2 = periodic_gas::<DVec2>(10_000, 0.4, 5.0);
    g2.run(1).expect("warm up");
    g2.set_dt(measured_dt()).expect("dt");
    let (c, s, drift, z) = measure(&mut g2, collisions());
    println!(
        "2D 10,000 disks, phi 0.4, periodic, dt {:.4}: {c} collisions in {s:.2} s = {:.3e} /s; energy drift {drift:.2e}; Z = {z:.4}",
        g2.dt(),
        c as f64 / s
    );
}

fn report_3d() {
    let mut g3 = periodic_gas::<DVec3>(32_000, 0.4, 5.0);
    g3.run(1).expect("warm up");
    g3.set_dt(measured_dt()).expect("dt");
    let (c, s, drift, z) = measure(&mut g3, collisions());
    println!(
        "3D 32,000 spheres, phi 0.40, periodic, dt {:.4}: {c} collisions in {s:.2} s = {:.3e} /s; energy drift {drift:.2e}; Z = {z:.4} (literature 6.91)",
        g3.dt(),
        c as f64 / s
    );
}

fn main() {
    if let Some(which) = std::env::var_os("CRITTERBOX_REPORT") {
        report(&which.to_string_lossy());
        return;
    }
    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5))
        .configure_from_args();
    let mut group = c.benchmark_group("event");
    let mut g2 = periodic_gas::<DVec2>(10_000, 0.4, 0.2);
    g2.run(10).expect("warm up");
    g2.step().expect("step");
    group.throughput(Throughput::Elements(g2.stats().impacts as u64));
    group.bench_function("gas2d_10k_phi0.4_step0.2", |b| {
        b.iter(|| g2.step().expect("step"))
    });
    let mut g3 = periodic_gas::<DVec3>(32_000, 0.4, 0.05);
    g3.run(4).expect("warm up");
    g3.step().expect("step");
    group.throughput(Throughput::Elements(g3.stats().impacts as u64));
    group.bench_function("gas3d_32k_phi0.4_step0.05", |b| {
        b.iter(|| g3.step().expect("step"))
    });
    group.finish();
    c.final_summary();
}
