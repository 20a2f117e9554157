//! Line plots for the results document (spectra, error against α, error distributions),
//! drawn with plotters into memory and saved as PNG atomically. The font is DejaVu Sans from
//! the `dejavu` crate, so plots render the same on machines without system fonts.

use std::path::Path;
use std::sync::Once;

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::report::render::save_png_atomic;

/// One named curve.
pub struct Series {
    /// Legend label.
    pub name: String,
    /// Points, in drawing order.
    pub points: Vec<(f64, f64)>,
    /// Also mark each point (for sparse curves).
    pub markers: bool,
    /// Join the points with a line (a scatter of unrelated settings has none).
    pub line: bool,
}

/// A plot's axes and labels.
pub struct Axes<'a> {
    /// Title above the plot.
    pub title: &'a str,
    /// x-axis label.
    pub x: &'a str,
    /// y-axis label.
    pub y: &'a str,
    /// Logarithmic x axis (non-positive x values are left out).
    pub log_x: bool,
    /// Logarithmic y axis (non-positive y values are left out).
    pub log_y: bool,
}

const WIDTH: u32 = 720;
const HEIGHT: u32 = 440;
const COLORS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(127, 127, 127),
];

/// Registers the bundled font as `sans-serif` (once).
pub(crate) fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // Registration fails only for a malformed font; the bundled one is not.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

/// Draws `series` on `axes` and writes the PNG to `path`.
pub fn line_plot(path: &Path, axes: &Axes<'_>, series: &[Series]) -> Result<()> {
    let (x, y) = ranges(path, axes, series)?;
    let mut buffer = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (WIDTH, HEIGHT)).into_drawing_area();
        draw(&root, axes, series, x, y, keeper(axes))
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
        root.present()
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
    }
    let image = image::RgbImage::from_raw(WIDTH, HEIGHT, buffer)
        .ok_or_else(|| anyhow!("{}: plot buffer has the wrong size", path.display()))?;
    save_png_atomic(path, &image)?;
    Ok(())
}

/// [`line_plot`] as an SVG document at `path` (vector, for documents that zoom).
pub fn line_plot_svg(path: &Path, axes: &Axes<'_>, series: &[Series]) -> Result<()> {
    let (x, y) = ranges(path, axes, series)?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, (WIDTH, HEIGHT)).into_drawing_area();
        draw(&root, axes, series, x, y, keeper(axes))
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
        root.present()
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
    }
    crate::io::atomic::write_atomic(path, text.as_bytes())
        .map_err(|e| anyhow!("cannot write {}: {e}", path.display()))
}

/// Whether a point can be drawn on the axes (finite, positive on a log axis).
fn keeper(axes: &Axes<'_>) -> impl Fn(&(f64, f64)) -> bool {
    let (log_x, log_y) = (axes.log_x, axes.log_y);
    move |&(x, y): &(f64, f64)| {
        x.is_finite() && y.is_finite() && (!log_x || x > 0.0) && (!log_y || y > 0.0)
    }
}

/// The x and y ranges that hold every drawable point, padded; an error when there is none.
fn ranges(path: &Path, axes: &Axes<'_>, series: &[Series]) -> Result<((f64, f64), (f64, f64))> {
    register_font();
    let keep = keeper(axes);
    let points: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied().filter(&keep))
        .collect();
    if points.is_empty() {
        return Err(anyhow!("{}: nothing to plot", path.display()));
    }
    let range = |values: Vec<f64>, log: bool| {
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if log {
            (lo / 1.5, hi * 1.5)
        } else {
            let pad = ((hi - lo) * 0.05).max(1e-12);
            (lo - pad, hi + pad)
        }
    };
    Ok((
        range(points.iter().map(|p| p.0).collect(), axes.log_x),
        range(points.iter().map(|p| p.1).collect(), axes.log_y),
    ))
}

/// A short tick label: plain decimals for moderate values, `1e-6` style otherwise.
fn tick(v: &f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e4).contains(&a) {
        format!("{v:.0e}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    }
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// The four axis combinations need four chart types; this picks one and draws into it.
fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    axes: &Axes<'_>,
    series: &[Series],
    x: (f64, f64),
    y: (f64, f64),
    keep: impl Fn(&(f64, f64)) -> bool,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let mut builder = ChartBuilder::on(root);
    builder
        .caption(axes.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(64);
    macro_rules! finish {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(axes.x)
                .y_desc(axes.y)
                .x_label_formatter(&tick)
                .y_label_formatter(&tick)
                .light_line_style(RGBColor(235, 235, 235))
                .draw()?;
            for (i, s) in series.iter().enumerate() {
                let color = COLORS[i % COLORS.len()];
                let points: Vec<(f64, f64)> = s.points.iter().copied().filter(&keep).collect();
                let line = if s.line { points.clone() } else { Vec::new() };
                chart
                    .draw_series(LineSeries::new(line, color.stroke_width(2)))?
                    .label(s.name.clone())
                    .legend(move |(px, py)| {
                        PathElement::new(vec![(px, py), (px + 20, py)], color.stroke_width(2))
                    });
                if s.markers {
                    chart.draw_series(
                        points
                            .into_iter()
                            .map(|p| Circle::new(p, 3, color.filled())),
                    )?;
                }
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()?;
        }};
    }
    match (axes.log_x, axes.log_y) {
        (false, false) => finish!(builder.build_cartesian_2d(x.0..x.1, y.0..y.1)?),
        (true, false) => finish!(builder.build_cartesian_2d((x.0..x.1).log_scale(), y.0..y.1)?),
        (false, true) => finish!(builder.build_cartesian_2d(x.0..x.1, (y.0..y.1).log_scale())?),
        (true, true) => {
            finish!(builder.build_cartesian_2d((x.0..x.1).log_scale(), (y.0..y.1).log_scale())?)
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plots_are_written_and_empty_plots_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.png");
        let axes = Axes {
            title: "spectrum",
            x: "k",
            y: "eigenvalue",
            log_x: false,
            log_y: true,
        };
        let series = [Series {
            name: "pose".into(),
            points: (0..10).map(|k| (k as f64, 0.5f64.powi(k))).collect(),
            markers: true,
            line: true,
        }];
        line_plot(&path, &axes, &series).unwrap();
        let image = image::open(&path).unwrap();
        assert_eq!((image.width(), image.height()), (WIDTH, HEIGHT));
        let none = [Series {
            name: "zeros".into(),
            points: vec![(1.0, 0.0)],
            markers: false,
            line: true,
        }];
        assert!(line_plot(&path, &axes, &none).is_err());
    }
}
