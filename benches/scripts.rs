//! The cost of script kinds on the standard gas (10,000 disks, packing fraction 0.4): native
//! balls against balls whose `collide` is a script calling `collide_default`, and against balls
//! with an `update` hook, in one run; `+profiled` cases time every hook call as `run --stats`
//! does; a `collide` that reads its contact against one that does not (`contact_collide`); and
//! prey fleeing hunters through `nearby` (`hunt_alternated`). `docs/scripting.md` reports the
//! figures.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use critterbox::glam::DVec2;
use critterbox::scenes::{gas_with, GasParams};
use critterbox::script::{ScriptOptions, ScriptWorld};
use critterbox::World;
use std::path::Path;
use std::time::Duration;

fn world(kind: &str, profile: bool) -> World<DVec2> {
    let params = GasParams {
        n: 10_000,
        packing: 0.4,
        ..GasParams::default()
    };
    gas_with::<DVec2>(&params, kind, |w| {
        if kind != "ball" {
            let path =
                Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("benches/kinds/{kind}.rhai"));
            let options = ScriptOptions {
                profile,
                ..ScriptOptions::default()
            };
            w.load_kind(&path, &options)?;
        }
        Ok(())
    })
    .expect("the bench gas builds")
}

fn script_kinds(c: &mut Criterion) {
    let mut group = c.benchmark_group("script_gas10k");
    group.sample_size(20);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(3));
    // `+profiled`: the same kind with the script profiler on (`run --stats`).
    for case in [
        "ball",
        "scripted_ball",
        "scripted_ball+profiled",
        "empty_update",
        "empty_update+profiled",
        "updated_ball",
    ] {
        let kind = case.trim_end_matches("+profiled");
        let mut w = world(kind, case.ends_with("+profiled"));
        group.bench_with_input(BenchmarkId::new(case, 10_000), &kind, |b, _| {
            b.iter(|| w.step().expect("gas steps"));
        });
        eprintln!(
            "{kind}: {:.1} collide calls and {} update calls per step",
            w.totals().contacts as f64 / w.step_count().max(1) as f64,
            if kind.contains("update") { 10_000 } else { 0 }
        );
    }
    group.finish();
}

/// The hunt scene (`scripts/scenes/hunt.rhai`) with 5,000 prey of `prey_kind` and 50 of the
/// bench's plain hunters (`benches/kinds/hunter.rhai`).
fn hunt(prey_kind: &str) -> critterbox::scenes::Scene {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let options = ScriptOptions {
        kind_dirs: vec![root.join("benches/kinds"), root.join("scripts/kinds")],
        ..ScriptOptions::default()
    };
    let sets = [
        ("N_PREY", "5000"),
        ("N_HUNTERS", "50"),
        ("SIZE", "120.0"),
        ("PREY_KIND", prey_kind),
    ]
    .map(|(k, v)| (k.to_string(), v.to_string()));
    critterbox::script::load_scene(&root.join("scripts/scenes/hunt.rhai"), &sets, &options)
        .expect("the hunt scene loads")
}

/// Prey fleeing the nearest hunter within 5 through `nearby` (`prey`), against the same scene
/// with an empty `update` (`prey_idle`), with the rule's code but no query (`prey_unseeing`),
/// and with the rule as a scan over every hunter (`prey_scan`). They are stepped in turn, one
/// step each per round, so load on the machine falls on all alike; the medians and ratios are
/// printed (`docs/scripting.md`).
fn hunt_alternated(_: &mut Criterion) {
    use std::time::Instant;
    if !wanted("hunt_alternated") {
        return;
    }
    let kinds = ["prey_idle", "prey_unseeing", "prey", "prey_scan"];
    let mut scenes: Vec<_> = kinds.iter().map(|k| hunt(k)).collect();
    let rounds = 40;
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); kinds.len()];
    for round in 0..rounds + 5 {
        for (scene, t) in scenes.iter_mut().zip(&mut times) {
            let start = Instant::now();
            scene.step().expect("the hunt steps");
            // The first rounds warm the caches and the grids up.
            if round >= 5 {
                t.push(start.elapsed().as_secs_f64() * 1e3);
            }
        }
    }
    let median = |mut t: Vec<f64>| {
        t.sort_by(f64::total_cmp);
        t[t.len() / 2]
    };
    // Ratios within each round, where the load fell alike on both cases, then their median.
    let ratio =
        |a: usize, b: usize| median(times[a].iter().zip(&times[b]).map(|(x, y)| x / y).collect());
    eprintln!(
        "hunt, 5,000 prey and 50 hunters, median ms per step over {rounds} alternated rounds:"
    );
    for (k, t) in kinds.iter().zip(&times) {
        eprintln!("  {k:14} {:9.3} ms", median(t.clone()));
    }
    eprintln!(
        "  medians of the per-round ratios: nearby / empty update = {:.2}x; \
         no query / empty update = {:.2}x; scan / nearby = {:.1}x",
        ratio(2, 0),
        ratio(1, 0),
        ratio(3, 2)
    );
}

/// A three-parameter `collide` that reads its contact (`contact_ball`), and one that takes it
/// but reads nothing (`contact_unread`), against the same scene's two-parameter `collide`
/// (`scripted_ball`): rounds of steps of each, alternated; the median ms per step of each and
/// the medians of the per-round ratios are printed.
fn contact_collide(_c: &mut Criterion) {
    if !wanted("contact_collide") {
        return;
    }
    const ROUNDS: usize = 9;
    const STEPS: u32 = 10;
    let kinds = ["scripted_ball", "contact_unread", "contact_ball"];
    let mut worlds: Vec<World<DVec2>> = kinds.iter().map(|k| world(k, false)).collect();
    let time = |w: &mut World<DVec2>| {
        let start = std::time::Instant::now();
        for _ in 0..STEPS {
            w.step().expect("gas steps");
        }
        start.elapsed().as_secs_f64() * 1e3 / f64::from(STEPS)
    };
    // One round of each first, so all start warm.
    for w in &mut worlds {
        time(w);
    }
    let mut ms = vec![Vec::new(); kinds.len()];
    let mut ratios = vec![Vec::new(); kinds.len()];
    for _ in 0..ROUNDS {
        let round: Vec<f64> = worlds.iter_mut().map(&time).collect();
        for (k, t) in round.iter().enumerate() {
            ms[k].push(*t);
            ratios[k].push(t / round[0]);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    eprintln!(
        "{:.1} collide calls per step; medians of {ROUNDS} alternated rounds of {STEPS} steps:",
        worlds[0].totals().contacts as f64 / worlds[0].step_count().max(1) as f64
    );
    for (k, kind) in kinds.iter().enumerate() {
        eprintln!(
            "  {kind}: {:.3} ms/step, {:.3} x scripted_ball",
            median(&mut ms[k]),
            median(&mut ratios[k])
        );
    }
}

/// True when the bench's filter (its first argument that is not a flag, as criterion takes it)
/// is absent or part of `name`: `cargo bench --bench scripts -- hunt` runs the hunt alone.
fn wanted(name: &str) -> bool {
    let mut args = std::env::args().skip(1).filter(|a| !a.starts_with('-'));
    args.next().is_none_or(|filter| name.contains(&filter))
}

criterion_group!(benches, script_kinds);
criterion_group!(contacts, contact_collide);
criterion_group!(hunt_benches, hunt_alternated);
criterion_main!(benches, contacts, hunt_benches);
