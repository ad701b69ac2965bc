//! `critterbox chart`: cost against error for every method over a sweep of dt on two scenes (a
//! gas, where the error is the position error against the exact run, and a deep pile under
//! gravity, where it is the deepest overlap), and cost per step against each part's error on the
//! 2D mixed scenes (a point per method and part, labelled with the part), written as
//! `docs/speed-vs-accuracy.svg` and `.png` (see the README for how to read it). Text is laid out
//! with a TrueType font (`--font`), for both files.

use anyhow::Context;
use clap::Args;
use critterbox::scenes::chart::{
    chart_mixed_points, chart_pile_points, chart_points, ChartPoint, MixedPoint,
};
use critterbox::scenes::stress::METHODS;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `critterbox chart`.
#[derive(Args, Debug)]
pub struct ChartArgs {
    /// Output path without extension: writes PATH.svg and PATH.png.
    #[arg(long, default_value = "docs/speed-vs-accuracy")]
    pub out: PathBuf,
    /// A TrueType font for the chart's text.
    #[arg(
        long,
        default_value = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"
    )]
    pub font: PathBuf,
}

/// Each method's colour, in the order of [`METHODS`].
const COLOURS: [RGBColor; 6] = [
    RGBColor(214, 39, 40),   // discrete: red
    RGBColor(44, 160, 44),   // substep: green
    RGBColor(255, 127, 14),  // swept: orange
    RGBColor(31, 119, 180),  // event: blue
    RGBColor(23, 190, 207),  // solve: cyan
    RGBColor(148, 103, 189), // auto: purple
];

/// One panel of the chart: its points, title, axes and where its legend is out of the way; a
/// sweep's points are joined per method, a mixed panel's are labelled each with its part.
struct Panel {
    points: Vec<ChartPoint>,
    title: &'static str,
    error: &'static str,
    cost: &'static str,
    labels: Vec<&'static str>,
    legend: SeriesLabelPosition,
}

/// A short label for a mixed scene's part on the chart.
fn part_label(p: &MixedPoint) -> &'static str {
    match (p.scene, p.part) {
        ("gas above pile", "pile") => "gas's pile",
        ("bullets into pile", "escaped") => "bullets out",
        (_, part) => part,
    }
}

/// The mixed panel: a point per method and part, labelled with the part.
fn mixed_panel(points: Vec<MixedPoint>) -> Panel {
    let labels = points.iter().map(part_label).collect();
    let points = points
        .into_iter()
        .map(|p| ChartPoint {
            method: p.method,
            dt: 1.0 / 60.0,
            cost: p.cost,
            error: p.error,
        })
        .collect();
    Panel {
        points,
        title: "mixed scenes, dt 1/60, a point per part",
        error: "each part's error (its own measure, docs/stability.md)",
        cost: "wall s per step",
        labels,
        legend: SeriesLabelPosition::MiddleMiddle,
    }
}

/// The sweeps' cost axis.
const SWEEP_COST: &str = "wall s per simulated s per critter";

/// Runs the command.
pub fn run(args: &ChartArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let panels = [
        Panel {
            points: chart_points(&METHODS)?,
            title: "100-disk gas, 1 s, dt 1/15 to 1/960",
            error: "RMS position error against the exact event-driven run (radii)",
            cost: SWEEP_COST,
            labels: Vec::new(),
            legend: SeriesLabelPosition::UpperMiddle,
        },
        Panel {
            points: chart_pile_points(&METHODS)?,
            title: "20-row pile under gravity, 2 s, dt 1/15 to 1/240",
            error: "deepest overlap at the end (radii)",
            cost: SWEEP_COST,
            labels: Vec::new(),
            legend: SeriesLabelPosition::UpperLeft,
        },
        mixed_panel(chart_mixed_points(&METHODS)?),
    ];
    for panel in &panels {
        writeln!(out, "{}: {}", panel.title, panel.error)?;
        writeln!(
            out,
            "method      dt          cost ({})  error  part",
            panel.cost
        )?;
        for (i, p) in panel.points.iter().enumerate() {
            writeln!(
                out,
                "{:<11} {:<11.3e} {:<11.3e} {:.3e}  {}",
                p.method.to_string(),
                p.dt,
                p.cost,
                p.error,
                panel.labels.get(i).copied().unwrap_or("")
            )?;
        }
    }
    let svg = args.out.with_extension("svg");
    let png = args.out.with_extension("png");
    let font = std::fs::read(&args.font).with_context(|| {
        format!(
            "{}: the PNG needs a TrueType font (--font)",
            args.font.display()
        )
    })?;
    let font: &'static [u8] = Box::leak(font.into_boxed_slice());
    plotters::style::register_font("sans-serif", FontStyle::Normal, font)
        .map_err(|_| anyhow::anyhow!("{}: not a usable TrueType font", args.font.display()))?;
    draw(
        SVGBackend::new(&svg, (2400, 600)).into_drawing_area(),
        &panels,
    )
    .map_err(|e| anyhow::anyhow!("{}: {e}", svg.display()))?;
    draw(
        BitMapBackend::new(&png, (2400, 600)).into_drawing_area(),
        &panels,
    )
    .map_err(|e| anyhow::anyhow!("{}: {e}", png.display()))?;
    writeln!(out, "wrote {} and {}", svg.display(), png.display())?;
    Ok(())
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    panels: &[Panel],
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let areas = root.split_evenly((1, panels.len()));
    for (area, panel) in areas.iter().zip(panels) {
        draw_panel(area, panel)?;
    }
    root.present()?;
    Ok(())
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    const FLOOR: f64 = 1e-16; // errors below this are drawn at it (exact to round-off)
    let points = &panel.points;
    let err = |p: &ChartPoint| p.error.max(FLOOR);
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in points {
        x0 = x0.min(err(p));
        x1 = x1.max(err(p));
        y0 = y0.min(p.cost);
        y1 = y1.max(p.cost);
    }
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("critterbox: cost against error ({})", panel.title),
            ("sans-serif", 20),
        )
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(
            (x0 / 3.0..x1 * 3.0).log_scale(),
            (y0 / 2.0..y1 * 2.0).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc(panel.error)
        .y_desc(panel.cost)
        .x_label_formatter(&|x| format!("{x:.0e}"))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw()?;
    for (m, colour) in METHODS.iter().zip(COLOURS) {
        let color = colour.to_rgba();
        let pts: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.method == *m)
            .map(|p| (err(p), p.cost))
            .collect();
        let line = if panel.labels.is_empty() {
            pts.clone()
        } else {
            Vec::new()
        };
        chart
            .draw_series(LineSeries::new(line, color.stroke_width(2)))?
            .label(m.to_string())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
            });
        chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))?;
        let labelled = points
            .iter()
            .zip(&panel.labels)
            .filter(|(p, _)| p.method == *m);
        chart.draw_series(labelled.map(|(p, label)| {
            Text::new(
                *label,
                (err(p), p.cost),
                ("sans-serif", 11).into_font().color(&color),
            )
        }))?;
    }
    chart
        .configure_series_labels()
        .position(panel.legend.clone())
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}
