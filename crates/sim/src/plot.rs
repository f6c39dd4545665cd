//! Time-series line plots to PNG and SVG (plotters, embedded DejaVu Sans).
//!
//! ```no_run
//! use helicon_sim::plot::{LinePlot, Series};
//! let xy: Vec<(f64, f64)> = (0..100).map(|i| (i as f64 * 0.1, (i as f64 * 0.1).sin())).collect();
//! LinePlot::new("Sine", "time [s]", "value [-]")
//!     .series(Series::new("sin", &xy))
//!     .write(std::path::Path::new("sine.png"))?;
//! # Ok::<(), helicon_sim::plot::PlotError>(())
//! ```

use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

/// DejaVu Sans (Bitstream Vera licence, see `assets/DejaVuSans-LICENSE.txt`).
static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// Error drawing a plot.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The output extension is neither `.png` nor `.svg`.
    #[error("{path}: unsupported plot format (use .png or .svg)")]
    Format {
        /// Output path.
        path: String,
    },
    /// No finite points to plot.
    #[error("plot `{title}`: no finite data")]
    Empty {
        /// Plot title.
        title: String,
    },
    /// The font could not be registered.
    #[error("embedded font could not be loaded")]
    Font,
    /// Drawing or writing failed.
    #[error("{path}: {message}")]
    Draw {
        /// Output path.
        path: String,
        /// Backend message.
        message: String,
    },
}

/// One named line. Consecutive points whose y differs by more than half the
/// plot's y-range are not connected (angle wrap-arounds).
#[derive(Debug, Clone, Copy)]
pub struct Series<'a> {
    /// Legend name.
    pub name: &'a str,
    /// Points `(x, y)`; non-finite points are skipped.
    pub points: &'a [(f64, f64)],
}

impl<'a> Series<'a> {
    /// A named series.
    pub fn new(name: &'a str, points: &'a [(f64, f64)]) -> Self {
        Self { name, points }
    }
}

/// A line plot with any number of series.
#[derive(Debug, Clone)]
pub struct LinePlot<'a> {
    /// Title.
    pub title: String,
    /// X-axis label (with unit).
    pub x_label: String,
    /// Y-axis label (with unit).
    pub y_label: String,
    /// Lines.
    pub series: Vec<Series<'a>>,
    /// Image size in pixels.
    pub size_px: (u32, u32),
}

fn register_font() -> Result<(), PlotError> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    });
    if ok { Ok(()) } else { Err(PlotError::Font) }
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

impl<'a> LinePlot<'a> {
    /// An empty plot, 1000×600 px.
    pub fn new(title: &str, x_label: &str, y_label: &str) -> Self {
        Self {
            title: title.to_string(),
            x_label: x_label.to_string(),
            y_label: y_label.to_string(),
            series: Vec::new(),
            size_px: (1000, 600),
        }
    }

    /// Add a series.
    pub fn series(mut self, s: Series<'a>) -> Self {
        self.series.push(s);
        self
    }

    fn bounds(&self) -> Option<(f64, f64, f64, f64)> {
        let mut b = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for s in &self.series {
            for &(x, y) in s.points {
                if x.is_finite() && y.is_finite() {
                    b = (b.0.min(x), b.1.max(x), b.2.min(y), b.3.max(y));
                }
            }
        }
        if !b.0.is_finite() {
            return None;
        }
        if b.1 - b.0 <= 0.0 {
            b.0 -= 0.5;
            b.1 += 0.5;
        }
        let pad = ((b.3 - b.2) * 0.05).max(1e-9 * b.3.abs().max(1.0));
        Some((b.0, b.1, b.2 - pad, b.3 + pad))
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, Shift>,
        path: &str,
    ) -> Result<(), PlotError> {
        let err = |e: &dyn std::fmt::Display| PlotError::Draw {
            path: path.to_string(),
            message: e.to_string(),
        };
        let (x0, x1, y0, y1) = self.bounds().ok_or_else(|| PlotError::Empty {
            title: self.title.clone(),
        })?;
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, ("sans-serif", 24))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc(self.x_label.as_str())
            .y_desc(self.y_label.as_str())
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| err(&e))?;
        let jump = 0.5 * (y1 - y0);
        for (i, s) in self.series.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            // Split into runs at jumps larger than half the y-range (angle
            // wrap-arounds): no vertical connector, and no miter spike where
            // the wide polyline would reverse direction.
            let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
            for &(x, y) in s
                .points
                .iter()
                .filter(|(x, y)| x.is_finite() && y.is_finite())
            {
                if let Some(run) = runs.last_mut()
                    && let Some(&(_, yl)) = run.last()
                    && (y - yl).abs() > jump
                {
                    runs.push(Vec::new());
                }
                if let Some(run) = runs.last_mut() {
                    run.push((x, y));
                }
            }
            for (r, run) in runs.into_iter().enumerate() {
                let anno = chart
                    .draw_series(LineSeries::new(run, color.stroke_width(2)))
                    .map_err(|e| err(&e))?;
                if r == 0 {
                    anno.label(s.name).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                    });
                }
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
        Ok(())
    }

    /// Write the plot; the format follows the extension (`.png` or `.svg`).
    pub fn write(&self, path: &Path) -> Result<(), PlotError> {
        register_font()?;
        let name = path.display().to_string();
        match path.extension().and_then(|e| e.to_str()) {
            Some("png") => self.draw(
                BitMapBackend::new(path, self.size_px).into_drawing_area(),
                &name,
            ),
            Some("svg") => self.draw(
                SVGBackend::new(path, self.size_px).into_drawing_area(),
                &name,
            ),
            _ => Err(PlotError::Format { path: name }),
        }
    }
}

/// Convenience: one call for the common case (title, labels, series, path).
pub fn line_plot(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series<'_>],
    path: &Path,
) -> Result<(), PlotError> {
    let mut p = LinePlot::new(title, x_label, y_label);
    p.series.extend_from_slice(series);
    p.write(path)
}
