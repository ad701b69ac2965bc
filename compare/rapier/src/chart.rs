//! `--chart PREFIX`: ms per step and bytes per critter against N, for critterbox (2D and 3D, one
//! and two threads) and rapier2d-f64 (one thread), measured in one run, drawn to PREFIX.svg and
//! PREFIX.png and printed as a table.
//!
//! Time: at each N the five set-ups are stepped in alternating rounds (critterbox on its own
//! one- and two-thread rayon pools), each round at least `steps` steps and at least about two
//! million critter-steps, and the medians of the rounds are reported.
//!
//! `--warmup W` steps every world W times, untimed, before the rounds: the gas starts on a grid
//! with no disk touching another, and its collisions take hundreds of steps to reach their
//! steady rate (the anchor figures for rapier are from the grid start, as the default here).
//!
//! Memory: each engine and N is built and stepped in a child process of its own (this program
//! with `--memory-of ENGINE N`), which resets its peak resident size just before building
//! (`/proc/self/clear_refs`), then reports the peak (`VmHWM`) less the resident size it started
//! from, per critter. So a figure is what building and stepping that engine's world needed at
//! its peak, with nothing else in the process. rapier's bodies are copied out of a critterbox
//! world that is freed (and the allocator trimmed) before the reset.

use crate::{median, Bodies, Rapier};
use critterbox::glam::{DVec2, DVec3};
use critterbox::scenes::{gas, GasParams};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::time::Instant;

/// The set-ups, in table and legend order.
pub const SETUPS: [&str; 5] = [
    "critterbox 2D, 1 thread",
    "critterbox 2D, 2 threads",
    "critterbox 3D, 1 thread",
    "critterbox 3D, 2 threads",
    "rapier2d-f64 2D, 1 thread",
];

/// The engines whose memory is measured (one child process each), the set-up their figure
/// belongs to, and their label in the chart.
const MEMORY: [(&str, usize, &str); 3] = [
    ("critterbox2d", 0, "critterbox 2D"),
    ("critterbox3d", 2, "critterbox 3D"),
    ("rapier2d", 4, "rapier2d-f64 2D"),
];

/// One N's figures: ms per step and bytes per critter of each set-up (`None`: not run).
pub struct Row {
    pub n: usize,
    pub ms: [Option<f64>; 5],
    pub bytes: [Option<f64>; 5],
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

/// A world handed to a pool's thread for the length of one `install` call.
struct Lent<'a, W>(&'a mut W);

// SAFETY: `ThreadPool::install` blocks the lending thread until the closure has returned, so the
// world (whose kind hooks are `Rc`s, hence not `Send`) is only ever used by one thread at a time,
// and `install`'s hand-over orders those uses.
unsafe impl<W> Send for Lent<'_, W> {}

/// Milliseconds per step of `steps` steps of `world` on `pool`'s threads.
fn time_on<V: critterbox::Vector>(
    pool: &rayon::ThreadPool,
    world: &mut critterbox::World<V>,
    steps: usize,
) -> f64 {
    let lent = Lent(world);
    pool.install(move || {
        let lent = lent;
        time(steps, || lent.0.step().expect("critterbox steps"))
    })
}

/// Milliseconds per step of `steps` calls of `step`.
fn time(steps: usize, mut step: impl FnMut()) -> f64 {
    let t = Instant::now();
    for _ in 0..steps {
        step();
    }
    t.elapsed().as_secs_f64() * 1e3 / steps as f64
}

/// Measures every set-up at every N.
pub fn measure(
    sizes: &[usize],
    steps: usize,
    rounds: usize,
    rapier_max: usize,
    warmup: usize,
) -> Vec<Row> {
    let (one, two) = (pool(1), pool(2));
    let mut rows = Vec::new();
    for &n in sizes {
        let params = GasParams {
            n,
            ..GasParams::default()
        };
        let mut d2 = gas::<DVec2>(&params).expect("the 2D gas builds");
        let mut d3 = gas::<DVec3>(&params).expect("the 3D gas builds");
        let mut rapier = (n <= rapier_max).then(|| Rapier::from(&Bodies::of(&d2)));
        // Untimed steps first, if asked: the gas starts on a grid with no disk touching another
        // and takes hundreds of steps to reach its steady state of collisions.
        if warmup > 0 {
            time_on(&two, &mut d2, warmup);
            time_on(&two, &mut d3, warmup);
            if let Some(r) = &mut rapier {
                time(warmup, || r.step());
            }
        }
        // At least about 2 million critter-steps per timed round, so handing the world to a
        // pool's thread (tens of microseconds) is lost in the round.
        let steps = steps.max(2_000_000 / n);
        let mut times: [Vec<f64>; 5] = Default::default();
        for _ in 0..rounds {
            times[0].push(time_on(&one, &mut d2, steps));
            times[1].push(time_on(&two, &mut d2, steps));
            times[2].push(time_on(&one, &mut d3, steps));
            times[3].push(time_on(&two, &mut d3, steps));
            if let Some(r) = &mut rapier {
                times[4].push(time(steps, || r.step()));
            }
        }
        let ms = times.map(|t| (!t.is_empty()).then(|| median(t)));
        let mut bytes = [None; 5];
        for (engine, setup, _) in MEMORY {
            if engine != "rapier2d" || n <= rapier_max {
                bytes[setup] = memory_of_child(engine, n);
            }
        }
        eprintln!("N = {n} measured");
        rows.push(Row { n, ms, bytes });
    }
    rows
}

/// Runs this program as `--memory-of ENGINE N` and reads the bytes per critter it prints.
fn memory_of_child(engine: &str, n: usize) -> Option<f64> {
    let exe = std::env::current_exe().ok()?;
    let out = std::process::Command::new(exe)
        .args(["--memory-of", engine, &n.to_string()])
        .output()
        .ok()?;
    if !out.status.success() {
        eprintln!(
            "memory of {engine} at N = {n} failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        return None;
    }
    String::from_utf8_lossy(&out.stdout).trim().parse().ok()
}

/// A `/proc/self/status` field in KiB.
fn status_kib(field: &str) -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("/proc/self/status");
    status
        .lines()
        .find_map(|l| l.strip_prefix(field))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or_else(|| panic!("{field} in /proc/self/status"))
}

/// The child's work: build `engine`'s gas of `n` and step it 20 times on one thread; prints the
/// peak resident bytes it needed per critter.
pub fn memory_of(engine: &str, n: usize) -> Result<(), String> {
    let params = GasParams {
        n,
        ..GasParams::default()
    };
    let steps = 20;
    // Everything before the reset is not counted: for rapier, its input copied out of a
    // critterbox world, which is then freed and given back to the system.
    let bodies =
        (engine == "rapier2d").then(|| Bodies::of(&gas::<DVec2>(&params).expect("the gas builds")));
    // SAFETY: malloc_trim only releases free memory of the allocator.
    unsafe {
        libc::malloc_trim(0);
    }
    std::fs::write("/proc/self/clear_refs", "5")
        .map_err(|e| format!("cannot reset the peak resident size: {e}"))?;
    let base = status_kib("VmRSS:");
    match engine {
        "critterbox2d" => {
            let mut w = gas::<DVec2>(&params).map_err(|e| e.to_string())?;
            for _ in 0..steps {
                w.step().map_err(|e| e.to_string())?;
            }
        }
        "critterbox3d" => {
            let mut w = gas::<DVec3>(&params).map_err(|e| e.to_string())?;
            for _ in 0..steps {
                w.step().map_err(|e| e.to_string())?;
            }
        }
        "rapier2d" => {
            let mut r = Rapier::from(bodies.as_ref().expect("built above"));
            for _ in 0..steps {
                r.step();
            }
        }
        other => return Err(format!("unknown engine {other:?}")),
    }
    let peak = status_kib("VmHWM:");
    println!("{}", (peak.saturating_sub(base) * 1024) as f64 / n as f64);
    Ok(())
}

/// The table, in Markdown.
pub fn print_table(rows: &[Row]) {
    let f = |x: Option<f64>, digits: usize| x.map_or("-".to_string(), |x| format!("{x:.digits$}"));
    println!(
        "| N | {} | rapier / critterbox 2D (1 thread) | 2D speed-up on 2 threads | bytes per critter: critterbox 2D | critterbox 3D | rapier2d-f64 |",
        SETUPS.map(|s| format!("{s} ms/step")).join(" | ")
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        let ratio = match (r.ms[4], r.ms[0]) {
            (Some(a), Some(b)) => Some(a / b),
            _ => None,
        };
        let speedup = match (r.ms[0], r.ms[1]) {
            (Some(a), Some(b)) => Some(a / b),
            _ => None,
        };
        println!(
            "| {} | {} | {} | {} | {} | {} | {} |",
            r.n,
            r.ms.map(|m| f(m, 4)).join(" | "),
            f(ratio, 1),
            f(speedup, 2),
            f(r.bytes[0], 0),
            f(r.bytes[2], 0),
            f(r.bytes[4], 0)
        );
    }
}

/// The labels' font: DejaVu Sans cut down to ASCII (the main crate's asset).
const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans-ascii.ttf");

/// Draws the chart to `prefix`.svg and `prefix`.png.
pub fn draw_files(rows: &[Row], prefix: &str) -> Result<(), String> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| "the chart font does not load".to_string())?;
    let size = (1400, 600);
    let svg = format!("{prefix}.svg");
    let png = format!("{prefix}.png");
    draw(rows, SVGBackend::new(&svg, size).into_drawing_area())
        .map_err(|e| format!("{svg}: {e}"))?;
    draw(rows, BitMapBackend::new(&png, size).into_drawing_area())
        .map_err(|e| format!("{png}: {e}"))?;
    eprintln!("wrote {svg} and {png}");
    Ok(())
}

fn draw<DB: DrawingBackend>(
    rows: &[Row],
    root: DrawingArea<DB, Shift>,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(700);
    let n0 = rows.iter().map(|r| r.n).min().unwrap_or(1) as f64;
    let n1 = rows.iter().map(|r| r.n).max().unwrap_or(10) as f64;
    let all = |pick: fn(&Row) -> [Option<f64>; 5]| -> (f64, f64) {
        let v: Vec<f64> = rows.iter().flat_map(pick).flatten().collect();
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(0.0, f64::max);
        (lo, hi)
    };
    let (ms0, ms1) = all(|r| r.ms);
    let (_, b1) = all(|r| r.bytes);
    let series = |pick: fn(&Row) -> [Option<f64>; 5], i: usize| -> Vec<(f64, f64)> {
        rows.iter()
            .filter_map(|r| pick(r)[i].map(|v| (r.n as f64, v)))
            .collect()
    };
    // Two shades per critterbox set-up (one and two threads), rapier apart.
    let style = |i: usize| {
        [
            RGBColor(200, 30, 30),
            RGBColor(240, 140, 140),
            RGBColor(30, 70, 200),
            RGBColor(130, 170, 240),
            RGBColor(230, 130, 0),
        ][i]
            .to_rgba()
    };

    let mut chart = ChartBuilder::on(&left)
        .caption(
            "ms per step (standard gas, packing 0.2)",
            ("sans-serif", 20),
        )
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (n0 / 1.5..n1 * 1.5).log_scale(),
            (ms0 / 2.0..ms1 * 2.0).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("critters (N)")
        .y_desc("ms per step")
        .x_label_formatter(&|x| format!("{x:.0e}"))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw()?;
    let lines = SETUPS.iter().enumerate();
    let lines = lines.map(|(i, name)| (*name, style(i), series(|r| r.ms, i)));
    draw_lines(&mut chart, lines, SeriesLabelPosition::UpperLeft)?;

    let mut chart = ChartBuilder::on(&right)
        .caption(
            "bytes per critter (peak, built and stepped alone)",
            ("sans-serif", 20),
        )
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((n0 / 1.5..n1 * 1.5).log_scale(), 0.0..b1 * 1.15)?;
    chart
        .configure_mesh()
        .x_desc("critters (N)")
        .y_desc("bytes per critter")
        .x_label_formatter(&|x| format!("{x:.0e}"))
        .y_label_formatter(&|y| format!("{y:.0}"))
        .draw()?;
    let lines = MEMORY.map(|(_, i, label)| (label, style(i), series(|r| r.bytes, i)));
    draw_lines(&mut chart, lines, SeriesLabelPosition::UpperRight)?;
    root.present()?;
    Ok(())
}

/// Each line of `lines` (label, colour, points) as a line with a dot at every point, and the
/// legend at `legend`.
fn draw_lines<'a, DB: DrawingBackend + 'a, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    lines: impl IntoIterator<Item = (&'static str, RGBAColor, Vec<(f64, f64)>)>,
    legend: SeriesLabelPosition,
) -> Result<(), Box<dyn std::error::Error>>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
    DB::ErrorType: 'static,
{
    for (label, color, pts) in lines {
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))?;
    }
    chart
        .configure_series_labels()
        .position(legend)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}
