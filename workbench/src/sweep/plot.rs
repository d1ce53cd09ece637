//! A case's error-against-time plot: relative RMSE against median frame time on log axes,
//! one line per series, each time's spread (fastest to slowest run) as a bar, the Pareto front
//! marked. Drawn by plotters as SVG, and into an RGB buffer saved as PNG; text in the Ubuntu
//! Light font egui bundles, so no system font is needed.

use std::path::Path;
use std::sync::OnceLock;

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;

use super::CaseResult;
use crate::output::save_png_rgb8;

pub const WIDTH: u32 = 960;
pub const HEIGHT: u32 = 600;

const FONT: &str = "sans-serif";

/// Series colours (Okabe–Ito's colour-blind-safe set, then greys).
const COLOURS: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(230, 159, 0),
    RGBColor(0, 158, 115),
    RGBColor(213, 94, 0),
    RGBColor(204, 121, 167),
    RGBColor(86, 180, 233),
    RGBColor(240, 228, 66),
    RGBColor(100, 100, 100),
];

/// Registers the bundled font for plotters' text, once; an error if the font is refused.
fn register_font() -> Result<()> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            plotters::style::register_font(
                FONT,
                FontStyle::Normal,
                epaint_default_fonts::UBUNTU_LIGHT,
            )
            .map_err(|_| "not a TrueType font plotters can read".to_string())
        })
        .clone()
        .map_err(|e| anyhow!("the plot's font (Ubuntu Light) was refused: {e}"))
}

/// The plot of `case` as an SVG document.
pub fn svg(case: &CaseResult) -> Result<String> {
    register_font()?;
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, (WIDTH, HEIGHT)).into_drawing_area();
        draw(&root, case).map_err(|e| anyhow!("drawing the plot: {e:?}"))?;
        root.present()
            .map_err(|e| anyhow!("drawing the plot: {e:?}"))?;
    }
    Ok(s)
}

/// The plot of `case` as 8-bit RGB pixels, `WIDTH × HEIGHT`.
pub fn rgb(case: &CaseResult) -> Result<Vec<u8>> {
    register_font()?;
    let mut buf = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
        draw(&root, case).map_err(|e| anyhow!("drawing the plot: {e:?}"))?;
        root.present()
            .map_err(|e| anyhow!("drawing the plot: {e:?}"))?;
    }
    Ok(buf)
}

/// Writes `stem.svg` and `stem.png`.
pub fn save(case: &CaseResult, stem: &Path) -> Result<()> {
    let svg_path = stem.with_extension("svg");
    flarebench_sdk::io::write_atomically(&svg_path, svg(case)?.as_bytes())
        .map_err(|e| anyhow!("writing {}: {e}", svg_path.display()))?;
    save_png_rgb8(
        rgb(case)?,
        WIDTH as usize,
        HEIGHT as usize,
        &stem.with_extension("png"),
    )
}

/// The error axis's value: relative RMSE in percent, kept above zero for the log axis.
fn err_pct(rmse: f64) -> f64 {
    (100.0 * rmse).max(1e-4)
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    case: &CaseResult,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let ok: Vec<usize> = (0..case.cells.len())
        .filter(|&i| {
            let c = &case.cells[i];
            c.failure.is_none() && c.median_ms.is_finite() && c.relative_rmse.is_finite()
        })
        .collect();
    let cells = &case.cells;
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for &i in &ok {
        x0 = x0.min(cells[i].min_ms);
        x1 = x1.max(cells[i].max_ms);
        y0 = y0.min(err_pct(cells[i].relative_rmse));
        y1 = y1.max(err_pct(cells[i].relative_rmse));
    }
    if ok.is_empty() {
        (x0, x1, y0, y1) = (1.0, 10.0, 0.1, 10.0);
    }
    // Whole decades, so each axis has its labelled powers of ten.
    let decade_down = |v: f64| 10f64.powf(v.log10().floor());
    let decade_up = |v: f64| 10f64.powf(v.log10().ceil());
    let (x0, x1) = (decade_down(x0.max(1e-3) / 1.2), decade_up(x1.max(x0) * 1.2));
    let (y0, y1) = (decade_down(y0 / 1.2), decade_up(y1.max(y0) * 1.2));
    let mut chart = ChartBuilder::on(root)
        .caption(case.case.title(), (FONT, 20))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("median frame time (ms)")
        .y_desc("relative RMSE against the reference (%)")
        .label_style((FONT, 14))
        .x_labels(12)
        .y_labels(12)
        .x_label_formatter(&|v| format!("{v}"))
        .y_label_formatter(&|v| format!("{v}"))
        .axis_desc_style((FONT, 15))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;

    // The Pareto front first, under the series.
    let front = case.pareto();
    let front_pts: Vec<(f64, f64)> = front
        .iter()
        .map(|&i| (cells[i].median_ms, err_pct(cells[i].relative_rmse)))
        .collect();
    let grey = RGBColor(150, 150, 150);
    chart
        .draw_series(LineSeries::new(
            front_pts.iter().copied(),
            grey.stroke_width(6),
        ))?
        .label("Pareto front")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(6)));
    chart.draw_series(
        front_pts
            .iter()
            .map(|&p| Circle::new(p, 8, BLACK.stroke_width(2))),
    )?;

    let mut series: Vec<&str> = Vec::new();
    for &i in &ok {
        if !series.contains(&cells[i].series.as_str()) {
            series.push(&cells[i].series);
        }
    }
    for (k, name) in series.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let idx: Vec<usize> = ok
            .iter()
            .copied()
            .filter(|&i| cells[i].series == *name)
            .collect();
        let pts: Vec<(f64, f64)> = idx
            .iter()
            .map(|&i| (cells[i].median_ms, err_pct(cells[i].relative_rmse)))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), colour.stroke_width(2)))?
            .label(*name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart.draw_series(idx.iter().map(|&i| {
            let c = &cells[i];
            ErrorBar::new_horizontal(
                err_pct(c.relative_rmse),
                c.min_ms,
                c.median_ms,
                c.max_ms,
                colour.stroke_width(1),
                6,
            )
        }))?;
        // Each point, named beside it by its value (the label's part after the last `=`).
        chart.draw_series(idx.iter().zip(&pts).map(|(&i, &p)| {
            let l = &cells[i].label;
            let short = l
                .rsplit_once('=')
                .map_or(l.as_str(), |(_, v)| v)
                .to_string();
            EmptyElement::at(p)
                + Circle::new((0, 0), 4, colour.filled())
                + Text::new(short, (7, -14), (FONT, 12).into_font().color(&colour))
        }))?;
    }
    let placed: Vec<(f64, f64)> = ok
        .iter()
        .map(|&i| {
            let (x, y) = (cells[i].median_ms, err_pct(cells[i].relative_rmse));
            (
                (x / x0).log10() / (x1 / x0).log10(),
                (y / y0).log10() / (y1 / y0).log10(),
            )
        })
        .collect();
    chart
        .configure_series_labels()
        .position(legend_corner(&placed))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(180, 180, 180))
        .label_font((FONT, 13))
        .draw()?;
    Ok(())
}

/// The share of the plot's width and height the legend box may cover from its corner.
const LEGEND_REACH: (f64, f64) = (0.45, 0.4);

/// The corner of the plot for the legend: the one that covers the fewest points (`points` in
/// the plot's unit square, x right and y up). Ties go, in turn, to the upper right (slow and
/// wrong: rarely anything there), the lower left, the upper left and the lower right.
fn legend_corner(points: &[(f64, f64)]) -> SeriesLabelPosition {
    let (w, h) = LEGEND_REACH;
    // Each corner with its box: x range, then y range.
    let corners = [
        (
            SeriesLabelPosition::UpperRight,
            (1.0 - w, 1.0),
            (1.0 - h, 1.0),
        ),
        (SeriesLabelPosition::LowerLeft, (0.0, w), (0.0, h)),
        (SeriesLabelPosition::UpperLeft, (0.0, w), (1.0 - h, 1.0)),
        (SeriesLabelPosition::LowerRight, (1.0 - w, 1.0), (0.0, h)),
    ];
    let covered = |(xr, yr): ((f64, f64), (f64, f64))| {
        points
            .iter()
            .filter(|(x, y)| (xr.0..=xr.1).contains(x) && (yr.0..=yr.1).contains(y))
            .count()
    };
    let mut best = (usize::MAX, SeriesLabelPosition::UpperRight);
    for (pos, xr, yr) in corners {
        let n = covered((xr, yr));
        if n < best.0 {
            best = (n, pos);
        }
    }
    best.1
}

#[cfg(test)]
mod legend_tests {
    use super::*;

    fn corner(points: &[(f64, f64)]) -> &'static str {
        match legend_corner(points) {
            SeriesLabelPosition::UpperRight => "upper right",
            SeriesLabelPosition::LowerLeft => "lower left",
            SeriesLabelPosition::UpperLeft => "upper left",
            SeriesLabelPosition::LowerRight => "lower right",
            _ => "elsewhere",
        }
    }

    #[test]
    fn the_legend_goes_to_the_corner_with_the_fewest_points() {
        assert_eq!(corner(&[]), "upper right");
        // A slow, noisy series in the upper right (the sweep's splat points).
        let slow = [(0.8, 0.9), (0.9, 0.8), (0.95, 0.7), (0.1, 0.5)];
        assert_eq!(corner(&slow), "lower left");
        // Points in every corner but the upper left.
        let three = [(0.9, 0.9), (0.1, 0.1), (0.9, 0.1), (0.5, 0.5)];
        assert_eq!(corner(&three), "upper left");
        let all = [(0.9, 0.9), (0.1, 0.1), (0.1, 0.9), (0.9, 0.1)];
        assert_eq!(corner(&all), "upper right");
    }
}
