//! Log-log line plots written as SVG with plotters (no font library: the SVG viewer
//! draws the text).

use std::path::Path;

use plotters::prelude::*;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// A solid line through the points, with a circle at each.
    LineAndMarkers,
    /// A solid line only.
    Line,
    /// A dashed line only.
    Dashed,
    /// Markers only (crosses).
    Crosses,
}

/// One labelled series of `(x, y)` points (non-positive or non-finite points are skipped).
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Points in data units.
    pub points: Vec<(f64, f64)>,
    /// Index into the palette.
    pub color: usize,
    /// Line style.
    pub style: Style,
}

/// Colours, one per integrator in [`crate::sim::Integrator::ALL`] order.
const PALETTE: [RGBColor; 8] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(23, 190, 207),
    RGBColor(127, 127, 127),
    RGBColor(140, 86, 75),
];

fn usable(p: &(f64, f64)) -> bool {
    p.0.is_finite() && p.1.is_finite() && p.0 > 0.0 && p.1 > 0.0
}

fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if !(lo.is_finite() && hi > 0.0) {
        return (0.1, 10.0);
    }
    let (lo, hi) = if hi / lo < 10.0 {
        let mid = (lo * hi).sqrt();
        (mid / 3.2, mid * 3.2)
    } else {
        (lo, hi)
    };
    // Whole decades around the data.
    (
        10f64.powf(lo.log10().floor()),
        10f64.powf(hi.log10().ceil()),
    )
}

/// Draws a log-log chart of `series` into an SVG file at `path`.
pub fn loglog(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<(), String> {
    let points = || {
        series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|p| usable(p))
    };
    let (x0, x1) = log_range(points().map(|p| p.0));
    let (y0, y1) = log_range(points().map(|p| p.1));
    // Drawn into memory, then written whole (never half a file on a full disk).
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (900, 620)).into_drawing_area();
    let err = |e: &dyn std::fmt::Display| format!("plot {}: {e}", path.display());
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| err(&e))?;
    for s in series {
        let color = PALETTE[s.color % PALETTE.len()];
        let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(usable).collect();
        if pts.is_empty() {
            continue;
        }
        let legend_style = ShapeStyle::from(color).stroke_width(2);
        let anno = match s.style {
            Style::LineAndMarkers => {
                chart
                    .draw_series(LineSeries::new(pts.clone(), legend_style))
                    .map_err(|e| err(&e))?;
                chart
                    .draw_series(
                        pts.iter()
                            .map(|&p| Circle::new(p, 3, ShapeStyle::from(color).filled())),
                    )
                    .map_err(|e| err(&e))?
            }
            Style::Line => chart
                .draw_series(LineSeries::new(
                    pts,
                    ShapeStyle::from(color).stroke_width(1),
                ))
                .map_err(|e| err(&e))?,
            Style::Dashed => chart
                .draw_series(DashedLineSeries::new(
                    pts,
                    6,
                    4,
                    ShapeStyle::from(color).stroke_width(1),
                ))
                .map_err(|e| err(&e))?,
            Style::Crosses => chart
                .draw_series(
                    pts.iter()
                        .map(|&p| Cross::new(p, 5, ShapeStyle::from(color).stroke_width(2))),
                )
                .map_err(|e| err(&e))?,
        };
        let dashed = s.style == Style::Dashed;
        anno.label(s.label.clone()).legend(move |(x, y)| {
            if dashed {
                PathElement::new(vec![(x, y), (x + 8, y)], color)
            } else {
                PathElement::new(vec![(x, y), (x + 20, y)], legend_style)
            }
        });
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerLeft)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    drop(chart);
    drop(root);
    let folder = path.parent().unwrap_or(Path::new("."));
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
    super::write_file(folder, &name.unwrap_or_default(), &svg)
}
