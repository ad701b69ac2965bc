//! `auto` (by islands) against the fixed methods on the mixed scenes of `docs/stability.md`
//! (`critterbox::scenes::mixed`, 2D and 3D): ms per step of each whole run, rounds alternating
//! the methods, each figure the median of the rounds (issue 43's target: `auto` at no more
//! than 1.5 times the cheapest fixed method's cost). `event` and `swept` cost ten to a thousand
//! times more on piles (`critterbox stability` prints their cost) and are left out of the rounds.
//! `docs/methods.md` keeps the table.
//!
//! `cargo bench --bench auto_islands` (`CRITTERBOX_ROUNDS=n` for another number of rounds,
//! `CRITTERBOX_METHODS=auto,solve:8` for other methods, `CRITTERBOX_SCENES=cradle` to keep
//! the scenes whose name holds that word).

use critterbox::scenes::mixed::{Mixed, MIXED, MIXED_3D};
use critterbox::Method;
use std::time::Instant;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let rounds: usize = std::env::var("CRITTERBOX_ROUNDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let methods: Vec<Method> = std::env::var("CRITTERBOX_METHODS")
        .unwrap_or_else(|_| "auto,discrete,substep:4,solve:8".into())
        .split(',')
        .map(|m| m.trim().parse().expect("a method"))
        .collect();
    let only = std::env::var("CRITTERBOX_SCENES").unwrap_or_default();
    let scenes: Vec<&Mixed> = MIXED
        .iter()
        .chain(MIXED_3D)
        .filter(|s| s.name.contains(only.as_str()))
        .collect();
    println!("median of {rounds} alternated rounds, ms per step");
    let header: Vec<String> = methods.iter().map(|m| m.to_string()).collect();
    println!("| scene | {} | auto / cheapest fixed |", header.join(" | "));
    println!("|---|{}---|", "---|".repeat(methods.len()));
    for scene in scenes {
        let mut times = vec![Vec::new(); methods.len()];
        for _ in 0..rounds {
            for (k, &m) in methods.iter().enumerate() {
                let start = Instant::now();
                (scene.run)(m).expect("run");
                times[k].push(start.elapsed().as_secs_f64() * 1e3 / scene.steps as f64);
            }
        }
        let medians: Vec<f64> = times.iter_mut().map(|t| median(t)).collect();
        let auto = methods.iter().position(|&m| m == Method::Auto);
        let cheapest = methods
            .iter()
            .zip(&medians)
            .filter(|(&m, _)| m != Method::Auto)
            .map(|(_, &t)| t)
            .fold(f64::INFINITY, f64::min);
        let cells: Vec<String> = medians.iter().map(|t| format!("{t:.3}")).collect();
        let ratio = auto.map_or("-".into(), |k| format!("{:.2}", medians[k] / cheapest));
        println!("| {} | {} | {ratio} |", scene.name, cells.join(" | "));
    }
}
