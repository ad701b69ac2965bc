//! `auto` by islands against the fixed methods on a jumbled pile of 192 disks settling under
//! gravity beside a five-ball Newton's cradle struck in mid-air, 240 steps of 1/60 (issue 43's
//! target: `auto` at no more than 1.5 times the cheapest fixed method's cost). Rounds alternate
//! the methods; each figure is the median of the rounds. `docs/methods.md` keeps the table.
//!
//! `cargo bench --bench auto_islands` (`CRITTERBOX_ROUNDS=n` for another number of rounds).

use critterbox::glam::DVec2;
use critterbox::{CritterSpec, Method, WallBox, World, WorldConfig};
use std::time::Instant;

/// The scene of `tests/auto_islands.rs` (the same jumble, the same cradle).
fn pile_beside_cradle(method: Method) -> World<DVec2> {
    let mut w = World::new(
        WorldConfig::new(DVec2::new(-1.0, -1.0), DVec2::new(60.0, 120.0))
            .dt(1.0 / 60.0)
            .gravity(DVec2::new(0.0, -9.81))
            .method(method),
    )
    .expect("world");
    let t = 0.2;
    for (lo, hi) in [
        (DVec2::new(-t, -t), DVec2::new(10.0 + t, 0.0)),
        (DVec2::new(-t, 0.0), DVec2::new(0.0, 30.0)),
        (DVec2::new(10.0, 0.0), DVec2::new(10.0 + t, 30.0)),
    ] {
        w.add_wall(WallBox::aligned(lo, hi).expect("wall"))
            .expect("wall");
    }
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut rand = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for row in 0..16 {
        for k in 0..12 {
            let x = 0.41 + 0.81 * k as f64 + if row % 2 == 1 { 0.2 } else { 0.0 };
            let y = 0.41 + 0.86 * row as f64 + 0.05 * rand();
            let spec = CritterSpec::ball(DVec2::new(x, y))
                .radius(0.4)
                .restitution(0.5);
            w.spawn(spec).expect("disk");
        }
    }
    let striker = CritterSpec::ball(DVec2::new(20.0, 100.0))
        .vel(DVec2::new(5.0, 0.0))
        .radius(0.25);
    w.spawn(striker).expect("striker");
    for i in 0..5 {
        let at = DVec2::new(21.0 + 0.5 * i as f64, 100.0);
        w.spawn(CritterSpec::ball(at).radius(0.25)).expect("ball");
    }
    w
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let rounds: usize = std::env::var("CRITTERBOX_ROUNDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(7);
    let methods = [
        Method::Auto,
        Method::Solve(8),
        Method::Discrete,
        Method::Event,
    ];
    let steps = 240;
    let mut times = vec![Vec::new(); methods.len()];
    for _ in 0..rounds {
        for (k, &m) in methods.iter().enumerate() {
            let mut w = pile_beside_cradle(m);
            let start = Instant::now();
            w.run(steps).expect("run");
            times[k].push(start.elapsed().as_secs_f64() * 1e3 / steps as f64);
        }
    }
    let medians: Vec<f64> = times.iter_mut().map(|t| median(t)).collect();
    let cheapest = medians[1..].iter().copied().fold(f64::INFINITY, f64::min);
    println!("pile beside cradle, {steps} steps, median of {rounds} alternated rounds");
    println!("| method | ms per step | x cheapest fixed |");
    println!("|---|---|---|");
    for (m, t) in methods.iter().zip(&medians) {
        println!("| {m} | {t:.3} | {:.2} |", t / cheapest);
    }
}
