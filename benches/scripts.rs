//! The cost of script kinds on the standard gas (10,000 disks, packing fraction 0.4): native
//! balls against balls whose `collide` is a script calling `collide_default`, and against balls
//! with an `update` hook, in one run; `+profiled` cases time every hook call as `run --stats`
//! does. `docs/scripting.md` reports the figures.

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

criterion_group!(benches, script_kinds);
criterion_main!(benches);
