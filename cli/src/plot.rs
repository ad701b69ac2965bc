//! `inspect --plot`: kinetic energy, momentum and collisions over the steps, as SVG or PNG; the
//! font and axis helpers the sweep's charts share.

use critterbox::recording::Recording;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// The labels' font: DejaVu Sans cut down to ASCII (see assets/fonts/LICENSE.txt), so PNG
/// charts need no system fonts.
pub(crate) const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans-ascii.ttf");

/// Draws the chart to `path`: SVG for `.svg`, PNG for `.png`.
pub fn totals_chart(rec: &Recording, path: &Path) -> anyhow::Result<()> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| anyhow::anyhow!("the chart font does not load"))?;
    let size = (1000, 900);
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("svg") => draw(rec, SVGBackend::new(path, size).into_drawing_area()),
        Some("png") => draw(rec, BitMapBackend::new(path, size).into_drawing_area()),
        _ => anyhow::bail!(
            "--plot {}: the chart is written as .svg or .png; name the file so",
            path.display()
        ),
    }
}

pub(crate) fn range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return 0.0..1.0;
    }
    let pad = ((hi - lo) * 0.05)
        .max(hi.abs().max(lo.abs()) * 1e-9)
        .max(1e-12);
    (lo - pad)..(hi + pad)
}

pub(crate) fn err(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("drawing the chart: {e}")
}

fn draw<DB: DrawingBackend>(rec: &Recording, root: DrawingArea<DB, Shift>) -> anyhow::Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let meta = rec.meta();
    let title = format!(
        "{} ({}D): {} steps, dt = {:.6}",
        meta.scene,
        meta.dim,
        rec.last_step(),
        meta.dt
    );
    let root = root.titled(&title, ("sans-serif", 22)).map_err(err)?;
    let panels = root.split_evenly((3, 1));
    let steps = 0f64..(rec.last_step().max(1) as f64);
    let t = &rec.totals;

    // Kinetic energy.
    let mut chart = ChartBuilder::on(&panels[0])
        .margin(12)
        .x_label_area_size(30)
        .y_label_area_size(90)
        .caption("kinetic energy", ("sans-serif", 18))
        .build_cartesian_2d(steps.clone(), range(t.iter().map(|x| x.kinetic_energy.0)))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("step")
        .x_label_formatter(&|x| format!("{x:.0}"))
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(err)?;
    chart
        .draw_series(LineSeries::new(
            t.iter().map(|x| (x.step as f64, x.kinetic_energy.0)),
            &BLUE,
        ))
        .map_err(err)?;

    // Momentum, one line per component.
    let all = t.iter().flat_map(|x| x.momentum.0.iter().copied());
    let mut chart = ChartBuilder::on(&panels[1])
        .margin(12)
        .x_label_area_size(30)
        .y_label_area_size(90)
        .caption("momentum", ("sans-serif", 18))
        .build_cartesian_2d(steps.clone(), range(all))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("step")
        .x_label_formatter(&|x| format!("{x:.0}"))
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(err)?;
    for (axis, (name, color)) in [("px", RED), ("py", GREEN), ("pz", MAGENTA)]
        .into_iter()
        .enumerate()
        .take(meta.dim)
    {
        chart
            .draw_series(LineSeries::new(
                t.iter()
                    .filter_map(|x| x.momentum.0.get(axis).map(|p| (x.step as f64, *p))),
                &color,
            ))
            .map_err(err)?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(err)?;

    // Collisions per step.
    let mut chart = ChartBuilder::on(&panels[2])
        .margin(12)
        .x_label_area_size(30)
        .y_label_area_size(90)
        .caption("collisions per step (handled, impacts)", ("sans-serif", 18))
        .build_cartesian_2d(
            steps,
            range(t.iter().map(|x| x.collisions as f64).chain([0.0])),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("step")
        .x_label_formatter(&|x| format!("{x:.0}"))
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(err)?;
    chart
        .draw_series(LineSeries::new(
            t.iter().map(|x| (x.step as f64, x.collisions as f64)),
            &BLACK,
        ))
        .map_err(err)?
        .label("handled")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK));
    chart
        .draw_series(LineSeries::new(
            t.iter().map(|x| (x.step as f64, x.impacts as f64)),
            &RED,
        ))
        .map_err(err)?
        .label("impacts")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], RED));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}
