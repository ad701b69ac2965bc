//! `--plot X:Y[:GROUP]`: a chart of two numeric columns of the table, one series per distinct
//! value of GROUP, as SVG and PNG.

use crate::plot::{err, range, FONT};
use anyhow::Context;
use critterbox::sweep::Table;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// One series: its name and its points, sorted along x.
type Series = (String, Vec<(f64, f64)>);

/// Draws the chart; gives the files written.
pub fn draw(
    table: &Table,
    spec: &str,
    dir: &Path,
    to: Option<&Path>,
) -> anyhow::Result<Vec<PathBuf>> {
    let parts: Vec<&str> = spec.split(':').collect();
    anyhow::ensure!(
        (2..=3).contains(&parts.len()) && parts.iter().all(|p| !p.is_empty()),
        "--plot {spec}: write X:Y or X:Y:GROUP with the table's column names, e.g. --plot dt:energy_change:method"
    );
    let col = |name: &str| {
        table.column(name).ok_or_else(|| {
            anyhow::anyhow!(
                "--plot {spec}: the table has no column '{name}'; its columns are {}",
                table.columns.join(", ")
            )
        })
    };
    let (x, y) = (col(parts[0])?, col(parts[1])?);
    let group = parts.get(2).map(|g| col(g)).transpose()?;
    let mut series: Vec<Series> = Vec::new();
    for row in &table.rows {
        let (Ok(px), Ok(py)) = (row[x].parse::<f64>(), row[y].parse::<f64>()) else {
            continue; // a failed run, or no value
        };
        let name = group.map_or(String::new(), |g| row[g].clone());
        match series.iter_mut().find(|s| s.0 == name) {
            Some(s) => s.1.push((px, py)),
            None => series.push((name, vec![(px, py)])),
        }
    }
    anyhow::ensure!(
        !series.is_empty(),
        "--plot {spec}: no row has numbers in both {} and {}",
        parts[0],
        parts[1]
    );
    for s in &mut series {
        s.1.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| anyhow::anyhow!("the chart font does not load"))?;
    let title = match parts.get(2) {
        Some(g) => format!("{} against {} by {g}", parts[1], parts[0]),
        None => format!("{} against {}", parts[1], parts[0]),
    };
    let files = match to {
        Some(p) => vec![p.to_path_buf()],
        None => ["svg", "png"]
            .iter()
            .map(|e| dir.join(format!("plot-{}-{}.{e}", parts[0], parts[1])))
            .collect(),
    };
    let size = (900, 600);
    for path in &files {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("svg") => chart(
                &series,
                &title,
                parts[0],
                parts[1],
                SVGBackend::new(path, size).into_drawing_area(),
            ),
            Some("png") => chart(
                &series,
                &title,
                parts[0],
                parts[1],
                BitMapBackend::new(path, size).into_drawing_area(),
            ),
            _ => anyhow::bail!(
                "--plot-out {}: the chart is written as .svg or .png; name the file so",
                path.display()
            ),
        }
        .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(files)
}

fn chart<DB: DrawingBackend>(
    series: &[Series],
    title: &str,
    xname: &str,
    yname: &str,
    root: DrawingArea<DB, Shift>,
) -> anyhow::Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let points = || series.iter().flat_map(|s| s.1.iter());
    let mut c = ChartBuilder::on(&root)
        .margin(16)
        .caption(title, ("sans-serif", 20))
        .x_label_area_size(40)
        .y_label_area_size(90)
        .build_cartesian_2d(range(points().map(|p| p.0)), range(points().map(|p| p.1)))
        .map_err(err)?;
    c.configure_mesh()
        .x_desc(xname)
        .y_desc(yname)
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(err)?;
    for (i, (name, pts)) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        c.draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))
            .map_err(err)?;
        let drawn = c
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
            .map_err(err)?;
        if !name.is_empty() {
            drawn
                .label(name.as_str())
                .legend(move |(x, y)| Circle::new((x + 8, y), 4, color.filled()));
        }
    }
    if series.iter().any(|s| !s.0.is_empty()) {
        c.configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .draw()
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}
