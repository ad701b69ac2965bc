//! The cost of script kinds on the standard gas (10,000 disks, packing fraction 0.4): native
//! balls against balls whose `collide` is a script calling `collide_default`, and against balls
//! with an `update` hook, in one run; and a `collide` that reads its contact against one that
//! does not (`contact_collide`). `docs/scripting.md` reports the figures.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use critterbox::glam::DVec2;
use critterbox::scenes::{gas_with, GasParams};
use critterbox::script::{ScriptOptions, ScriptWorld};
use critterbox::World;
use std::path::Path;
use std::time::Duration;

fn world(kind: &str) -> World<DVec2> {
    let params = GasParams {
        n: 10_000,
        packing: 0.4,
        ..GasParams::default()
    };
    gas_with::<DVec2>(&params, kind, |w| {
        if kind != "ball" {
            let path =
                Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("benches/kinds/{kind}.rhai"));
            w.load_kind(&path, &ScriptOptions::default())?;
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
    for kind in ["ball", "scripted_ball", "empty_update", "updated_ball"] {
        let mut w = world(kind);
        group.bench_with_input(BenchmarkId::new(kind, 10_000), &kind, |b, _| {
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

/// A three-parameter `collide` that reads its contact (`contact_ball`), and one that takes it
/// but reads nothing (`contact_unread`), against the same scene's two-parameter `collide`
/// (`scripted_ball`): rounds of steps of each, alternated; the median ms per step of each and
/// the medians of the per-round ratios are printed.
fn contact_collide(_c: &mut Criterion) {
    const ROUNDS: usize = 9;
    const STEPS: u32 = 10;
    let kinds = ["scripted_ball", "contact_unread", "contact_ball"];
    let mut worlds: Vec<World<DVec2>> = kinds.iter().map(|k| world(k)).collect();
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

criterion_group!(benches, script_kinds);
criterion_group!(contacts, contact_collide);
criterion_main!(benches, contacts);
