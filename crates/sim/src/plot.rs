//! The one plot style of every command, to PNG and SVG (plotters, embedded
//! DejaVu Sans): [`Figure`], stacked [`Panel`]s sharing the x-axis (linear,
//! or logarithmic for frequency responses, [`Figure::log_x`]) with legends
//! beside the data; [`LinePlot`], one panel drawn as a [`Figure`];
//! [`Histogram`], outlined bars with integer counts; one theme ([`PALETTE`],
//! [`style_of`]: ten colours, then the same dashed), tick labels with the
//! digits their step needs; [`Decimator`], bounded min/max decimation of
//! long series.
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
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
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

/// One named line. In a [`LinePlot`], consecutive points whose y differs by
/// more than half the plot's y-range are not connected (angle wrap-arounds);
/// in a [`Figure`] panel, only jumps beyond [`Series::break_jumps_over`].
#[derive(Debug, Clone, Copy)]
pub struct Series<'a> {
    /// Legend name.
    pub name: &'a str,
    /// Points `(x, y)`; non-finite points are skipped.
    pub points: &'a [(f64, f64)],
    /// Drawn dashed (references, limits).
    pub dashed: bool,
    /// Colour `[r, g, b]`; `None` takes the next palette colour.
    pub color: Option<[u8; 3]>,
    /// In a [`Figure`]: do not connect points whose y jumps by more than
    /// this (an angle wrapping through ±π: use π).
    pub break_jumps_over: Option<f64>,
    /// In a [`Figure`]: a non-finite point ends the line (a gap), instead of
    /// being skipped and its neighbours joined.
    pub gaps: bool,
    /// In a [`Figure`]: drawn as points (a circle each), not joined
    /// (readings, measurements at a few settings).
    pub markers: bool,
}

impl<'a> Series<'a> {
    /// A named solid series in the next palette colour.
    pub fn new(name: &'a str, points: &'a [(f64, f64)]) -> Self {
        Self {
            name,
            points,
            dashed: false,
            color: None,
            break_jumps_over: None,
            gaps: false,
            markers: false,
        }
    }

    /// Drawn dashed.
    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }

    /// In this colour.
    pub fn color(mut self, rgb: [u8; 3]) -> Self {
        self.color = Some(rgb);
        self
    }

    /// Not connected across jumps larger than `jump` (angles: π).
    pub fn break_jumps_over(mut self, jump: f64) -> Self {
        self.break_jumps_over = Some(jump);
        self
    }

    /// In a [`Figure`]: not connected across non-finite points (a curve
    /// drawn only where it is defined, as a confidence band over the
    /// coherent frequencies).
    pub fn with_gaps(mut self) -> Self {
        self.gaps = true;
        self
    }

    /// In a [`Figure`]: drawn as points, a circle each, not joined.
    pub fn markers(mut self) -> Self {
        self.markers = true;
        self
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

/// The theme's line colours (matplotlib's tab10, distinguishable in print);
/// past the tenth series a panel repeats them dashed ([`style_of`]).
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The colour and dash of the `k`-th series of a panel: the series' own
/// colour, else the palette's `k mod 10`-th; dashed when the series asks, or
/// when the palette has come round an odd number of times (so no two of 20
/// series look alike).
pub fn style_of(k: usize, s: &Series<'_>) -> (RGBColor, bool) {
    let color = s.color.map_or(PALETTE[k % PALETTE.len()], rgb);
    (color, s.dashed || (k / PALETTE.len()) % 2 == 1)
}

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

    /// The plot as a one-panel [`Figure`] (the one style of every plot):
    /// legend beside the data, tick labels with the digits their step
    /// needs; a series without its own [`Series::break_jumps_over`] is not
    /// connected across jumps over half the y-range (angle wrap-arounds).
    pub fn to_figure(&self) -> Figure<'a> {
        let jump = self.bounds().map(|(_, _, y0, y1)| 0.5 * (y1 - y0));
        let mut panel = Panel::new(&self.y_label);
        for s in &self.series {
            let mut s = *s;
            if s.break_jumps_over.is_none() {
                s.break_jumps_over = jump;
            }
            panel.series.push(s);
        }
        let mut fig = Figure::new(&self.title, &self.x_label).panel(panel);
        fig.width_px = self.size_px.0.max(LEGEND_W + 300);
        fig.panel_height_px = self.size_px.1.saturating_sub(TITLE_H + X_AXIS_H).max(150);
        fig
    }

    /// Write the plot; the format follows the extension (`.png` or `.svg`).
    pub fn write(&self, path: &Path) -> Result<(), PlotError> {
        if self.bounds().is_none() {
            return Err(PlotError::Empty {
                title: self.title.clone(),
            });
        }
        self.to_figure().write(path)
    }
}

/// A chart with f64 axes.
type Chart2d<'c, DB> = ChartContext<'c, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draw one connected run of points, 2 px wide. Solid on a bitmap: 1 px
/// lines at three 1 px offsets, because plotters fills a wide polyline as one
/// polygon whose joins spike far past the data and tear where noisy data
/// reverse direction; SVG viewers draw wide polylines properly.
fn draw_run<DB: DrawingBackend>(
    chart: &mut Chart2d<'_, DB>,
    root: &DrawingArea<DB, Shift>,
    run: Vec<(f64, f64)>,
    color: RGBColor,
    dashed: bool,
    raster: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    if run.len() < 2 {
        return Ok(());
    }
    if dashed {
        chart.draw_series(DashedLineSeries::new(run, 9, 6, color.stroke_width(2)))?;
    } else if raster {
        let pix: Vec<(i32, i32)> = run.iter().map(|p| chart.backend_coord(p)).collect();
        for (dx, dy) in [(0, 0), (1, 0), (0, 1)] {
            let shifted: Vec<(i32, i32)> = pix.iter().map(|&(x, y)| (x + dx, y + dy)).collect();
            root.draw(&PathElement::new(shifted, color.stroke_width(1)))?;
        }
    } else {
        chart.draw_series(LineSeries::new(run, color.stroke_width(2)))?;
    }
    Ok(())
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

/// The tick step plotters takes on an axis `[lo, hi]` with at most `n`
/// labels: its own search (plotters 0.3's `compute_f64_key_points`),
/// 10^k, then ÷2, ÷5, ÷10 while the ticks aligned inside the range stay at
/// most `n`, so the labels' decimals follow the step actually drawn.
fn tick_step(lo: f64, hi: f64, n: usize) -> f64 {
    let span = hi - lo;
    if span.is_nan() || span <= 0.0 || span.is_infinite() || n == 0 {
        return 1.0;
    }
    let rem_euclid = |a: f64, b: f64| {
        let r = a - (a / b).floor() * b;
        if (r - b).abs() < f64::EPSILON { 0.0 } else { r }
    };
    let mut scale = 10f64.powf(span.log10().floor());
    if 1 + (span / scale).floor() as usize > n {
        scale *= 10.0;
    }
    for _ in 0..60 {
        let old = scale;
        for nxt in [2.0, 5.0, 10.0] {
            let s = old / nxt;
            let mut left = lo - rem_euclid(lo, s);
            if left < lo {
                left += s;
            }
            let right = hi - rem_euclid(hi, s);
            let points = 1.0 + (right - left) / old * nxt;
            if points.round() as usize > n {
                return scale;
            }
            scale = s;
        }
        scale = old / 10.0;
    }
    scale
}

/// Tick label for `v` on an axis `[lo, hi]` with at most `n` labels: the
/// decimals the tick step needs; for an axis whose values are all below
/// 1e-3 or reach 1e6, `m e k` with one exponent `k` per axis.
fn tick_label(v: f64, lo: f64, hi: f64, n: usize) -> String {
    let step = tick_step(lo, hi, n);
    // a tick at zero computed as 1e-19 reads as zero
    if v.abs() < 1e-6 * step {
        return "0".to_string();
    }
    // 0.005 needs three decimals, 0.01 two, 0.2 one: ⌈−log10 step⌉
    let decimals = |step: f64| (-step.log10() - 1e-9).ceil().clamp(0.0, 8.0) as usize;
    let big = lo.abs().max(hi.abs());
    if (1e-3..1e6).contains(&big) {
        let d = decimals(step);
        return format!("{v:.d$}");
    }
    let e = big.log10().floor() as i32;
    let scale = 10f64.powi(e);
    let d = decimals(step / scale);
    format!("{:.d$}e{e}", v / scale)
}

/// The marks of a logarithmic axis over `[lo, hi]` (log10 of the
/// quantity): `(position, major, label)` for 1 … 9 × each decade inside;
/// decades are major and labelled in plain numbers (0.1, 1, 10, 100); on
/// less than two decades 2 and 5 are labelled too, and a span without a
/// decade inside labels every mark.
pub fn log_ticks(lo: f64, hi: f64) -> Vec<(f64, bool, Option<String>)> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Vec::new();
    }
    let few = hi - lo < 2.0;
    let mut marks = Vec::new();
    let (d0, d1) = (lo.floor() as i32, hi.ceil() as i32);
    for d in d0..=d1 {
        for m in 1..=9 {
            let v = f64::from(d) + f64::from(m).log10();
            if v < lo - 1e-9 || v > hi + 1e-9 {
                continue;
            }
            marks.push((v, m == 1, d, m));
        }
    }
    let any_decade = marks.iter().any(|m| m.1);
    marks
        .into_iter()
        .map(|(v, major, d, m)| {
            let show = major || (few && (m == 2 || m == 5)) || !any_decade;
            let label = show.then(|| {
                let x = f64::from(m) * 10f64.powi(d);
                let digits = usize::try_from(-d).unwrap_or(0);
                format!("{x:.digits$}")
            });
            (v, major, label)
        })
        .collect()
}

/// The axis label of a quantity named with its unit as a suffix
/// (`thrust_n` → `thrust [N]`, `omega_rad_s` → `omega [rad/s]`,
/// `liftoff_drift_m` → `liftoff_drift [m]`); a name without a known suffix
/// is labelled `[-]`.
pub fn column_label(name: &str) -> String {
    const SUFFIXES: [(&str, &str); 10] = [
        ("_n_m", "N·m"),
        ("_m_s", "m/s"),
        ("_rad_s", "rad/s"),
        ("_kg_m2", "kg·m²"),
        ("_rad", "rad"),
        ("_deg", "deg"),
        ("_pct", "%"),
        ("_m", "m"),
        ("_s", "s"),
        ("_n", "N"),
    ];
    for (suffix, unit) in SUFFIXES {
        if let Some(stem) = name.strip_suffix(suffix)
            && !stem.is_empty()
        {
            return format!("{stem} [{unit}]");
        }
    }
    format!("{name} [-]")
}

/// A dashed horizontal line of a [`Panel`] (a limit), labelled in the legend.
#[derive(Debug, Clone, PartialEq)]
pub struct HLine {
    /// Height.
    pub y: f64,
    /// Legend label.
    pub label: String,
    /// Colour `[r, g, b]`.
    pub color: [u8; 3],
}

/// One panel of a [`Figure`]: its own y-axis, series, limits and legend.
#[derive(Debug, Clone, Default)]
pub struct Panel<'a> {
    /// Y-axis label (with unit).
    pub y_label: String,
    /// Lines.
    pub series: Vec<Series<'a>>,
    /// Dashed horizontal lines; drawn when inside the y-range (put their
    /// heights in `y_include` to force them in).
    pub hlines: Vec<HLine>,
    /// Values the y-axis must show besides the data.
    pub y_include: Vec<f64>,
    /// Extra legend lines (text only), e.g. a limit outside the view.
    pub notes: Vec<String>,
    /// Names of the y values 0, 1, 2 … (a coded state): the axis shows
    /// them at those values instead of numbers ([`Panel::categories`]).
    pub y_categories: Vec<String>,
}

impl<'a> Panel<'a> {
    /// An empty panel with its y-axis label (with unit).
    pub fn new(y_label: &str) -> Self {
        Self {
            y_label: y_label.to_string(),
            ..Self::default()
        }
    }

    /// Add a series.
    pub fn series(mut self, s: Series<'a>) -> Self {
        self.series.push(s);
        self
    }

    /// Name the y values 0, 1, 2 … (the codes of a state): the axis spans
    /// every name, labelled by name at its value.
    pub fn categories<'n>(mut self, names: impl IntoIterator<Item = &'n str>) -> Self {
        self.y_categories = names.into_iter().map(str::to_string).collect();
        self
    }

    fn y_bounds(&self) -> Option<(f64, f64)> {
        if !self.y_categories.is_empty() {
            // every name shown, the data or not
            self.series
                .iter()
                .flat_map(|s| s.points.iter())
                .any(|p| p.0.is_finite() && p.1.is_finite())
                .then_some((-0.5, self.y_categories.len() as f64 - 0.5))?;
            return Some((-0.5, self.y_categories.len() as f64 - 0.5));
        }
        let mut b = (f64::INFINITY, f64::NEG_INFINITY);
        let ys = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().filter(|p| p.0.is_finite()).map(|p| p.1))
            .chain(self.y_include.iter().copied())
            .filter(|y| y.is_finite());
        for y in ys {
            b = (b.0.min(y), b.1.max(y));
        }
        if !b.0.is_finite() {
            return None;
        }
        let span = b.1 - b.0;
        let pad = if span > 0.0 {
            0.06 * span
        } else {
            1.1 * (0.05 * b.0.abs()).max(1e-3)
        };
        Some((b.0 - pad, b.1 + pad))
    }
}

/// Stacked panels sharing one x-axis (drawn under the bottom panel), one
/// title, a legend at the right of each panel (never over the data).
#[derive(Debug, Clone)]
pub struct Figure<'a> {
    /// Title.
    pub title: String,
    /// X-axis label (with unit).
    pub x_label: String,
    /// Panels, top to bottom.
    pub panels: Vec<Panel<'a>>,
    /// Width in pixels (legends included).
    pub width_px: u32,
    /// Height of each panel in pixels.
    pub panel_height_px: u32,
    /// The x values are log10 of the quantity (a frequency response): the
    /// axis is marked at 1, 10, 100 … (and 2, 5 on less than two decades) in
    /// the quantity's own units, with a minor grid at 2 … 9 ([`Figure::log_x`]).
    pub log_x: bool,
}

const TITLE_H: u32 = 44;
const X_AXIS_H: u32 = 48;
const LEGEND_W: u32 = 190;
const X_LABELS: usize = 12;
const Y_LABELS: usize = 6;

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

impl<'a> Figure<'a> {
    /// An empty figure, 1200 px wide, 210 px per panel.
    pub fn new(title: &str, x_label: &str) -> Self {
        Self {
            title: title.to_string(),
            x_label: x_label.to_string(),
            panels: Vec::new(),
            width_px: 1200,
            panel_height_px: 210,
            log_x: false,
        }
    }

    /// Mark the x-axis logarithmically: the series' x values are log10 of
    /// the quantity named in the x label (e.g. `ω [rad/s]`).
    pub fn log_x(mut self) -> Self {
        self.log_x = true;
        self
    }

    /// Add a panel (below the others).
    pub fn panel(mut self, p: Panel<'a>) -> Self {
        self.panels.push(p);
        self
    }

    /// Total size in pixels.
    pub fn size_px(&self) -> (u32, u32) {
        let n = self.panels.len().max(1) as u32;
        (self.width_px, TITLE_H + n * self.panel_height_px + X_AXIS_H)
    }

    fn x_bounds(&self) -> Option<(f64, f64)> {
        let mut b = (f64::INFINITY, f64::NEG_INFINITY);
        for p in &self.panels {
            for s in &p.series {
                for &(x, y) in s.points {
                    if x.is_finite() && y.is_finite() {
                        b = (b.0.min(x), b.1.max(x));
                    }
                }
            }
        }
        if !b.0.is_finite() {
            return None;
        }
        if b.1 - b.0 <= 0.0 {
            b = (b.0 - 0.5, b.1 + 0.5);
        }
        Some(b)
    }

    /// Draw on `root`; `raster` for a bitmap backend.
    #[allow(clippy::too_many_lines)] // one figure's layout, panel by panel
    fn draw<DB: DrawingBackend>(
        &self,
        root: DrawingArea<DB, Shift>,
        path: &str,
        raster: bool,
    ) -> Result<(), PlotError> {
        let err = |e: &dyn std::fmt::Display| PlotError::Draw {
            path: path.to_string(),
            message: e.to_string(),
        };
        let empty = || PlotError::Empty {
            title: self.title.clone(),
        };
        let (x0, x1) = self.x_bounds().ok_or_else(empty)?;
        let mut ranges = Vec::with_capacity(self.panels.len());
        for p in &self.panels {
            ranges.push(p.y_bounds().ok_or_else(empty)?);
        }
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let body = root
            .titled(&self.title, ("sans-serif", 22))
            .map_err(|e| err(&e))?;
        let n = self.panels.len();
        let breaks: Vec<i32> = (1..n)
            .map(|i| i32::try_from(i as u64 * u64::from(self.panel_height_px)).unwrap_or(i32::MAX))
            .collect();
        let rows = body.split_by_breakpoints::<i32, i32, _, _>([], breaks);
        // the legend column beside all panels: a panel's legend starts level
        // with it, and a shared one runs on beside the panels that share it
        let (_, legend) = body.split_horizontally(self.width_px.saturating_sub(LEGEND_W));
        let xf = move |v: &f64| tick_label(*v, x0, x1, X_LABELS);
        // room for the names of a coded state's axis
        let y_area = if self.panels.iter().any(|p| !p.y_categories.is_empty()) {
            118
        } else {
            88
        };
        let blank = |_: &f64| String::new();
        for (i, ((panel, row), (y0, y1))) in self.panels.iter().zip(&rows).zip(ranges).enumerate() {
            let last = i + 1 == n;
            let legend_x = self.width_px.saturating_sub(LEGEND_W);
            let (left, _) = row.split_horizontally(legend_x);
            let categories = &panel.y_categories;
            let yf = move |v: &f64| {
                if categories.is_empty() {
                    return tick_label(*v, y0, y1, Y_LABELS);
                }
                let k = v.round();
                match categories.get(k as usize) {
                    Some(name) if (v - k).abs() < 1e-6 && k >= 0.0 => name.clone(),
                    _ => String::new(),
                }
            };
            let y_labels = if categories.is_empty() {
                Y_LABELS
            } else {
                // a tick at each code: plotters keeps a step of 1 for up
                // to this many labels on a span of n
                categories.len() + 1
            };
            let mut chart = ChartBuilder::on(&left)
                .margin_top(9)
                .margin_bottom(if last { 0 } else { 9 })
                .margin_right(12)
                .margin_left(6)
                .x_label_area_size(if last { X_AXIS_H } else { 0 })
                .y_label_area_size(y_area)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|e| err(&e))?;
            let mut mesh = chart.configure_mesh();
            mesh.y_desc(panel.y_label.as_str())
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 15))
                .max_light_lines(1)
                .light_line_style(RGBColor(240, 240, 240))
                .bold_line_style(RGBColor(212, 212, 212))
                .x_labels(X_LABELS)
                .y_labels(y_labels)
                .y_label_formatter(&yf);
            if self.log_x {
                mesh.disable_x_mesh().x_label_formatter(&blank);
                if last {
                    mesh.x_desc(self.x_label.as_str());
                }
            } else if last {
                mesh.x_desc(self.x_label.as_str()).x_label_formatter(&xf);
            } else {
                mesh.x_label_formatter(&blank);
            }
            mesh.draw().map_err(|e| err(&e))?;
            if self.log_x {
                let label_font = ("sans-serif", 14)
                    .into_font()
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Center, VPos::Top));
                for (v, major, label) in log_ticks(x0, x1) {
                    let c = if major {
                        RGBColor(212, 212, 212)
                    } else {
                        RGBColor(240, 240, 240)
                    };
                    chart
                        .draw_series(LineSeries::new([(v, y0), (v, y1)], c.stroke_width(1)))
                        .map_err(|e| err(&e))?;
                    if last && let Some(text) = label {
                        let (px, py) = chart.backend_coord(&(v, y0));
                        root.draw(&Text::new(text, (px, py + 6), label_font.clone()))
                            .map_err(|e| err(&e))?;
                    }
                }
            }
            // the limits inside the view, under the data
            for h in &panel.hlines {
                if h.y >= y0 && h.y <= y1 {
                    chart
                        .draw_series(DashedLineSeries::new(
                            [(x0, h.y), (x1, h.y)],
                            10,
                            6,
                            rgb(h.color).stroke_width(2),
                        ))
                        .map_err(|e| err(&e))?;
                }
            }
            let mut styles = Vec::with_capacity(panel.series.len());
            for (k, s) in panel.series.iter().enumerate() {
                let (color, dashed) = style_of(k, s);
                styles.push((color, dashed));
                if s.markers {
                    let points = s
                        .points
                        .iter()
                        .filter(|(x, y)| x.is_finite() && y.is_finite());
                    chart
                        .draw_series(points.map(|&p| Circle::new(p, 4, color.stroke_width(2))))
                        .map_err(|e| err(&e))?;
                    continue;
                }
                let mut run: Vec<(f64, f64)> = Vec::new();
                let mut flush = |run: &mut Vec<(f64, f64)>| {
                    draw_run(
                        &mut chart,
                        &root,
                        std::mem::take(run),
                        color,
                        dashed,
                        raster,
                    )
                    .map_err(|e| err(&e))
                };
                for &(x, y) in s.points {
                    if !(x.is_finite() && y.is_finite()) {
                        if s.gaps {
                            flush(&mut run)?;
                        }
                        continue;
                    }
                    if let (Some(jump), Some(&(_, yl))) = (s.break_jumps_over, run.last())
                        && (y - yl).abs() > jump
                    {
                        flush(&mut run)?;
                    }
                    run.push((x, y));
                }
                flush(&mut run)?;
            }
            // legend at the right of the panel; panels repeating the lines of
            // the one above share its legend (drawn once, down the column)
            let shared = i > 0
                && panel.hlines.is_empty()
                && panel.notes.is_empty()
                && self.panels[i - 1].series.len() == panel.series.len()
                && self.panels[i - 1]
                    .series
                    .iter()
                    .zip(&panel.series)
                    .all(|(a, b)| a.name == b.name);
            if shared {
                continue;
            }
            let font = ("sans-serif", 15).into_font().color(&BLACK);
            let note_font = ("sans-serif", 13).into_font().color(&RGBColor(90, 90, 90));
            let mut y = 18 + i32::try_from(i as u64 * u64::from(self.panel_height_px)).unwrap_or(0);
            for (s, (color, dashed)) in panel.series.iter().zip(&styles) {
                if s.markers {
                    legend
                        .draw(&Circle::new((20, y), 4, color.stroke_width(2)))
                        .and_then(|()| legend.draw(&Text::new(s.name, (40, y - 8), font.clone())))
                        .map_err(|e| err(&e))?;
                } else {
                    legend_entry(&legend, y, s.name, color.stroke_width(2), *dashed, &font)
                        .map_err(|e| err(&e))?;
                }
                y += 22;
            }
            for h in &panel.hlines {
                legend_entry(
                    &legend,
                    y,
                    &h.label,
                    rgb(h.color).stroke_width(2),
                    true,
                    &font,
                )
                .map_err(|e| err(&e))?;
                y += 22;
            }
            for note in &panel.notes {
                legend
                    .draw(&Text::new(note.as_str(), (6, y - 8), note_font.clone()))
                    .map_err(|e| err(&e))?;
                y += 18;
            }
        }
        root.present().map_err(|e| err(&e))?;
        Ok(())
    }

    /// Write the figure; the format follows the extension (`.png` or `.svg`).
    pub fn write(&self, path: &Path) -> Result<(), PlotError> {
        register_font()?;
        let name = path.display().to_string();
        let size = self.size_px();
        match path.extension().and_then(|e| e.to_str()) {
            Some("png") => self.draw(
                BitMapBackend::new(path, size).into_drawing_area(),
                &name,
                true,
            ),
            Some("svg") => self.draw(
                SVGBackend::new(path, size).into_drawing_area(),
                &name,
                false,
            ),
            _ => Err(PlotError::Format { path: name }),
        }
    }
}

/// A histogram in the theme of [`Figure`]: outlined bars, integer counts on
/// the y-axis, the x label with its unit, and the legend column beside the
/// plot holding the count of values and the notes (e.g. how many runs are
/// included, and why some are not).
#[derive(Debug, Clone)]
pub struct Histogram {
    /// Title.
    pub title: String,
    /// X-axis label (with unit).
    pub x_label: String,
    /// Y-axis label: what is counted (`count`, `runs`).
    pub y_label: String,
    /// The bins, left to right: `(left edge, width, count)`.
    pub bins: Vec<(f64, f64, usize)>,
    /// Notes beside the plot, one a line.
    pub notes: Vec<String>,
    /// Image size in pixels.
    pub size_px: (u32, u32),
}

/// The bins of `n` values over `[lo, hi]`: `(first edge, width, count)`;
/// √n of them (5 … 50), one of width 1 around a single value. The one
/// binning of every histogram (values at hand, [`Histogram::new`], or
/// streamed, counted by the caller, [`Histogram::of_bins`]).
pub fn bin_layout(n: u64, lo: f64, hi: f64) -> (f64, f64, usize) {
    if hi <= lo {
        return (lo - 0.5, 1.0, 1);
    }
    let bins = ((n as f64).sqrt().ceil() as usize).clamp(5, 50);
    (lo, (hi - lo) / bins as f64, bins)
}

/// The bin of `x` in a [`bin_layout`] `(first edge, width, count)`: the
/// last bin holds its right edge.
pub fn bin_of(x: f64, layout: (f64, f64, usize)) -> usize {
    let (lo, w, n) = layout;
    (((x - lo) / w).max(0.0) as usize).min(n.saturating_sub(1))
}

impl Histogram {
    /// A histogram of `values` ([`bin_layout`]; non-finite values are left
    /// out), 1000×500 px.
    pub fn new(title: &str, x_label: &str, values: &[f64]) -> Self {
        let finite = || values.iter().copied().filter(|x| x.is_finite());
        let (lo, hi) = finite().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
        let n = finite().count();
        let mut bins = Vec::new();
        if n > 0 {
            let layout = bin_layout(n as u64, lo, hi);
            let mut counts = vec![0usize; layout.2];
            for x in finite() {
                counts[bin_of(x, layout)] += 1;
            }
            bins = counts
                .into_iter()
                .enumerate()
                .map(|(b, c)| (layout.0 + b as f64 * layout.1, layout.1, c))
                .collect();
        }
        Self::of_bins(title, x_label, bins)
    }

    /// A histogram of bins counted by the caller (`(left edge, width,
    /// count)`, left to right), 1000×500 px.
    pub fn of_bins(title: &str, x_label: &str, bins: Vec<(f64, f64, usize)>) -> Self {
        Self {
            title: title.to_string(),
            x_label: x_label.to_string(),
            y_label: "count".to_string(),
            bins,
            notes: Vec::new(),
            size_px: (1000, 500),
        }
    }

    /// Add a note (a line beside the plot).
    pub fn note(mut self, line: impl Into<String>) -> Self {
        self.notes.push(line.into());
        self
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
        let bins = &self.bins;
        let (Some(first), Some(last)) = (bins.first(), bins.last()) else {
            return Err(PlotError::Empty {
                title: self.title.clone(),
            });
        };
        let (x0, x1) = (first.0, last.0 + last.1);
        let cmax = bins.iter().map(|b| b.2).max().unwrap_or(1).max(1);
        let (y0, y1) = (0.0, (cmax as f64 * 1.08).ceil().max(1.0));
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let body = root
            .titled(&self.title, ("sans-serif", 22))
            .map_err(|e| err(&e))?;
        let legend_x = self.size_px.0.saturating_sub(LEGEND_W);
        let (left, legend) = body.split_horizontally(legend_x);
        let mut chart = ChartBuilder::on(&left)
            .margin_top(9)
            .margin_right(12)
            .margin_left(6)
            .x_label_area_size(X_AXIS_H)
            .y_label_area_size(88)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| err(&e))?;
        let xf = move |v: &f64| tick_label(*v, x0, x1, X_LABELS);
        // counts are whole: a tick between two integers is not labelled
        let yf = |v: &f64| {
            if (v - v.round()).abs() < 1e-9 {
                format!("{:.0}", v.round())
            } else {
                String::new()
            }
        };
        chart
            .configure_mesh()
            .x_desc(self.x_label.as_str())
            .y_desc(self.y_label.as_str())
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .max_light_lines(1)
            .light_line_style(RGBColor(240, 240, 240))
            .bold_line_style(RGBColor(212, 212, 212))
            .x_labels(X_LABELS)
            .y_labels(Y_LABELS)
            .x_label_formatter(&xf)
            .y_label_formatter(&yf)
            .draw()
            .map_err(|e| err(&e))?;
        let fill = PALETTE[0].mix(0.45).filled();
        let edge = PALETTE[0].stroke_width(1);
        for &(l, w, c) in bins {
            if c == 0 {
                continue;
            }
            let r = [(l, 0.0), (l + w, c as f64)];
            chart
                .draw_series([Rectangle::new(r, fill), Rectangle::new(r, edge)])
                .map_err(|e| err(&e))?;
        }
        let font = ("sans-serif", 14).into_font().color(&BLACK);
        let mut y = 18;
        let n = bins.iter().map(|b| b.2).sum::<usize>();
        let mut lines = vec![
            format!("{n} values"),
            // the bin width in the axis' unit (`… [s]`)
            match self
                .x_label
                .rsplit_once('[')
                .and_then(|(_, u)| u.strip_suffix(']'))
                .filter(|u| !u.is_empty() && *u != "-")
            {
                Some(unit) => format!("bin width {} {unit}", significant(first.1, 3)),
                None => format!("bin width {}", significant(first.1, 3)),
            },
        ];
        lines.extend(self.notes.iter().cloned());
        for line in &lines {
            legend
                .draw(&Text::new(line.as_str(), (6, y - 8), font.clone()))
                .map_err(|e| err(&e))?;
            y += 20;
        }
        root.present().map_err(|e| err(&e))?;
        Ok(())
    }

    /// Write the histogram; the format follows the extension (`.png` or `.svg`).
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

/// `v` with `digits` significant digits (plain decimals, no exponent
/// between 1e-4 and 1e6).
fn significant(v: f64, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-4..6).contains(&mag) {
        return format!("{:.*e}", usize::try_from(digits - 1).unwrap_or(0), v);
    }
    let d = usize::try_from(digits - 1 - mag).unwrap_or(0);
    format!("{v:.d$}")
}

/// An estimate and its standard error as an engineer writes them: the
/// error to two significant digits, the value to the same decimal place
/// (`6.014 ± 0.019`, `246 ± 14`; with a shared exponent outside
/// 1e-4..1e6: `(3.21 ± 0.15)e-5`). An error that is zero, non-finite or
/// negative leaves the value at six significant digits and says so
/// (`± inf`, `± 0`).
pub fn value_pm(value: f64, std_error: f64) -> String {
    if !value.is_finite() {
        return format!("{value} ± {std_error}");
    }
    if !(std_error.is_finite() && std_error > 0.0) {
        let e = if std_error.is_nan() {
            "NaN".to_string()
        } else {
            format!("{std_error}")
        };
        return format!("{} ± {e}", significant(value, 6));
    }
    // the decimal place of the error's second significant digit
    let place = std_error.log10().floor() as i32 - 1;
    let big = value.abs().max(std_error);
    let mag = big.log10().floor() as i32;
    if (-4..6).contains(&mag) && place >= -12 {
        let d = usize::try_from(-place).unwrap_or(0);
        format!("{value:.d$} ± {std_error:.d$}")
    } else {
        let scale = 10f64.powi(mag);
        let d = usize::try_from(mag - place).unwrap_or(0);
        format!("({:.d$} ± {:.d$})e{mag}", value / scale, std_error / scale)
    }
}

/// One legend line: a 28 px sample of the line and its label.
fn legend_entry<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    y: i32,
    label: &str,
    style: ShapeStyle,
    dashed: bool,
    font: &TextStyle<'_>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    if dashed {
        area.draw(&plotters::element::DashedPathElement::new(
            [(6, y), (34, y)],
            8,
            5,
            style,
        ))?;
    } else {
        area.draw(&PathElement::new([(6, y), (34, y)], style))?;
    }
    area.draw(&Text::new(label, (40, y - 8), font.clone()))
}

/// Min/max decimation of time series sharing one time axis: at most
/// `2 * max_buckets + 2` points per series whatever the number of rows,
/// keeping each bucket's smallest and largest value (so spikes and the
/// envelope of noise survive) and the first and last rows. Memory is `O(max_buckets × series)`. A log with at most
/// `max_buckets` rows is kept exactly.
#[derive(Debug, Clone)]
pub struct Decimator {
    n_series: usize,
    max_buckets: usize,
    rows_per_bucket: usize,
    filled: usize,
    /// Per bucket and series (bucket-major): the (t, y) of the minimum.
    mins: Vec<(f64, f64)>,
    /// Per bucket and series: the (t, y) of the maximum.
    maxs: Vec<(f64, f64)>,
    rows: usize,
    /// The first and the last row pushed: (t, values).
    ends: [(f64, Vec<f64>); 2],
}

impl Decimator {
    /// For `n_series` series and at most `max_buckets` buckets (rounded up
    /// to an even number ≥ 2).
    pub fn new(n_series: usize, max_buckets: usize) -> Self {
        let max_buckets = max_buckets.max(2).next_multiple_of(2);
        Self {
            n_series,
            max_buckets,
            rows_per_bucket: 1,
            filled: 0,
            mins: Vec::with_capacity(max_buckets * n_series),
            maxs: Vec::with_capacity(max_buckets * n_series),
            rows: 0,
            ends: [(f64::NAN, Vec::new()), (f64::NAN, Vec::new())],
        }
    }

    /// Rows pushed.
    pub fn rows(&self) -> usize {
        self.rows
    }

    fn buckets(&self) -> usize {
        self.mins.len().checked_div(self.n_series).unwrap_or(0)
    }

    /// Add one row: time `t` and one value per series (extra values are
    /// ignored, missing ones taken as NaN, which no min/max picks).
    pub fn push(&mut self, t: f64, ys: &[f64]) {
        self.rows += 1;
        let n = self.n_series;
        let y = |s: usize| ys.get(s).copied().unwrap_or(f64::NAN);
        let end = usize::from(self.rows > 1);
        self.ends[end].0 = t;
        self.ends[end].1.clear();
        self.ends[end].1.extend((0..n).map(y));
        if self.buckets() == 0 || self.filled == self.rows_per_bucket {
            if self.buckets() == self.max_buckets {
                self.merge_pairs();
            }
            for s in 0..n {
                self.mins.push((t, y(s)));
                self.maxs.push((t, y(s)));
            }
            self.filled = 1;
            return;
        }
        let base = self.mins.len() - n;
        for s in 0..n {
            let v = y(s);
            let lo = &mut self.mins[base + s];
            if v < lo.1 || lo.1.is_nan() {
                *lo = (t, v);
            }
            let hi = &mut self.maxs[base + s];
            if v > hi.1 || hi.1.is_nan() {
                *hi = (t, v);
            }
        }
        self.filled += 1;
    }

    /// Halve the number of buckets (all full): bucket b takes 2b and 2b+1.
    fn merge_pairs(&mut self) {
        let n = self.n_series;
        let half = self.buckets() / 2;
        for b in 0..half {
            for s in 0..n {
                let (a, c) = ((2 * b) * n + s, (2 * b + 1) * n + s);
                let lo = if self.mins[c].1 < self.mins[a].1 || self.mins[a].1.is_nan() {
                    self.mins[c]
                } else {
                    self.mins[a]
                };
                let hi = if self.maxs[c].1 > self.maxs[a].1 || self.maxs[a].1.is_nan() {
                    self.maxs[c]
                } else {
                    self.maxs[a]
                };
                self.mins[b * n + s] = lo;
                self.maxs[b * n + s] = hi;
            }
        }
        self.mins.truncate(half * n);
        self.maxs.truncate(half * n);
        self.rows_per_bucket *= 2;
    }

    /// The decimated points of series `s`, in time order (non-finite values
    /// are left out).
    pub fn series(&self, s: usize) -> Vec<(f64, f64)> {
        let n = self.n_series;
        let mut out = Vec::with_capacity(2 * self.buckets());
        if s >= n {
            return out;
        }
        let end = |e: usize| {
            let (t, ref v) = self.ends[e];
            v.get(s).map(|y| (t, *y))
        };
        let mut push = |p: (f64, f64)| {
            let after = out.last().is_none_or(|q: &(f64, f64)| p.0 > q.0);
            if p.1.is_finite() && after {
                out.push(p);
            }
        };
        if let Some(p) = end(0) {
            push(p);
        }
        for b in 0..self.buckets() {
            let (lo, hi) = (self.mins[b * n + s], self.maxs[b * n + s]);
            let (first, second) = if lo.0 <= hi.0 { (lo, hi) } else { (hi, lo) };
            push(first);
            push(second);
        }
        if self.rows > 1
            && let Some(p) = end(1)
        {
            push(p);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn tick_labels_have_the_digits_the_step_needs() {
        // the step plotters takes (1-2-5 × 10^k, at most n ticks)
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b;
        assert!(close(tick_step(0.0, 1.0, 12), 0.1));
        assert!(close(tick_step(0.0, 20.0, 12), 2.0));
        assert!(close(tick_step(-0.05, 0.045, 6), 0.02));
        assert!(close(tick_step(0.0, 86400.0, 12), 10000.0));
        assert_eq!(tick_label(0.5, 0.0, 1.0, 12), "0.5");
        assert_eq!(tick_label(2.0, 0.0, 20.0, 12), "2");
        assert_eq!(tick_label(-0.04, -0.05, 0.045, 6), "-0.04");
        // a float-noise tick at zero reads as zero
        assert_eq!(tick_label(-1.08e-19, -4.2e-4, 2.4e-4, 6), "0");
        // tiny axis: one exponent per axis
        assert_eq!(tick_label(8e-5, -3.5e-5, 8.4e-5, 6), "8e-5");
        assert_eq!(tick_label(-2e-5, -3.5e-5, 8.4e-5, 6), "-2e-5");
        assert_eq!(tick_label(-2e-4, -4.2e-4, 2.4e-4, 6), "-2e-4");
        assert_eq!(tick_label(86400.0, 0.0, 86400.0, 12), "86400");
        assert_eq!(tick_label(2e7, 0.0, 5e7, 6), "2e7");
    }

    /// A 5 × 10^k step gets the digit it needs: the labels of an axis are
    /// all different (the envelope map's S_lat axis read `0.01, 0.01, 0`).
    #[test]
    fn tick_labels_are_distinct() {
        for (lo, hi, n) in [
            (-0.012, 0.016, 6),
            (0.1, 0.26, 6),
            (-0.0031, 0.0042, 6),
            (0.0, 0.9, 12),
            (-3.3, 3.3, 6),
        ] {
            let step = tick_step(lo, hi, n);
            let first = (lo / step).ceil() as i64;
            let last = (hi / step).floor() as i64;
            let labels: Vec<String> = (first..=last)
                .map(|k| tick_label(k as f64 * step, lo, hi, n))
                .collect();
            let mut unique = labels.clone();
            unique.dedup();
            assert_eq!(unique.len(), labels.len(), "{lo}..{hi}: {labels:?}");
            assert!(
                labels.iter().all(|l| l != "-0.00" && l != "-0"),
                "{labels:?}"
            );
        }
        assert_eq!(tick_label(0.005, -0.012, 0.016, 6), "0.005");
    }

    #[test]
    fn column_names_become_labels_with_units() {
        assert_eq!(column_label("thrust_n"), "thrust [N]");
        assert_eq!(column_label("torque_n_m"), "torque [N·m]");
        assert_eq!(column_label("omega_rad_s"), "omega [rad/s]");
        assert_eq!(
            column_label("touchdown_vertical_speed_m_s"),
            "touchdown_vertical_speed [m/s]"
        );
        assert_eq!(column_label("liftoff_time_s"), "liftoff_time [s]");
        assert_eq!(column_label("pitch_rad"), "pitch [rad]");
        assert_eq!(column_label("gain"), "gain [-]");
    }

    #[test]
    fn estimates_are_written_to_the_digits_their_error_allows() {
        assert_eq!(value_pm(6.014_124_273, 0.018_88), "6.014 ± 0.019");
        assert_eq!(value_pm(245.989_3, 13.7), "246 ± 14");
        assert_eq!(value_pm(0.70021, 0.000_35), "0.70021 ± 0.00035");
        assert_eq!(value_pm(-2.0, 0.5), "-2.00 ± 0.50");
        assert_eq!(value_pm(3.21e-5, 1.5e-6), "(3.21 ± 0.15)e-5");
        assert_eq!(value_pm(1.5e7, 2.0e5), "(1.500 ± 0.020)e7");
        assert_eq!(value_pm(5.0, f64::INFINITY), "5.00000 ± inf");
        assert_eq!(value_pm(5.0, 0.0), "5.00000 ± 0");
    }

    #[test]
    fn significant_digits() {
        assert_eq!(significant(0.021_63, 3), "0.0216");
        assert_eq!(significant(12.345, 3), "12.3");
        assert_eq!(significant(1234.5, 3), "1234");
        assert_eq!(significant(2.5e-7, 3), "2.50e-7");
    }

    #[test]
    fn log_axis_marks_decades_in_plain_numbers() {
        let t = log_ticks(0.0, 2.0);
        let labels: Vec<&str> = t.iter().filter_map(|m| m.2.as_deref()).collect();
        assert_eq!(labels, ["1", "10", "100"]);
        assert_eq!(t.len(), 19);
        // less than two decades: 2 and 5 labelled too
        let t = log_ticks(0.0, 1.8);
        let labels: Vec<&str> = t.iter().filter_map(|m| m.2.as_deref()).collect();
        assert_eq!(labels, ["1", "2", "5", "10", "20", "50"]);
        assert_eq!(t.iter().filter(|m| m.1).count(), 2);
        let t = log_ticks(-1.2, 2.5);
        let labels: Vec<&str> = t.iter().filter_map(|m| m.2.as_deref()).collect();
        assert_eq!(labels, ["0.1", "1", "10", "100"]);
        // a span inside one decade labels its marks
        let t = log_ticks(0.2, 0.8);
        assert!(t.iter().all(|m| m.2.is_some()) && !t.is_empty(), "{t:?}");
        assert!(log_ticks(1.0, 1.0).is_empty());
    }

    #[test]
    fn histogram_bins_count_every_finite_value() {
        let v: Vec<f64> = (0..100)
            .map(|i| f64::from(i) * 0.1)
            .chain([f64::NAN])
            .collect();
        let h = Histogram::new("t", "x [s]", &v);
        let b = &h.bins;
        assert_eq!(b.len(), 10);
        assert_eq!(b.iter().map(|x| x.2).sum::<usize>(), 100);
        // the largest value in the last bin
        assert_eq!(b[9].2, 10);
        assert_eq!(
            Histogram::new("t", "x", &[2.0, 2.0]).bins,
            vec![(1.5, 1.0, 2)]
        );
        assert!(Histogram::new("t", "x", &[]).bins.is_empty());
    }

    #[test]
    fn the_palette_does_not_repeat_a_style_within_twenty_series() {
        let pts = [(0.0, 0.0)];
        let styles: Vec<([u8; 3], bool)> = (0..20)
            .map(|k| {
                let (c, d) = style_of(k, &Series::new("s", &pts));
                ([c.0, c.1, c.2], d)
            })
            .collect();
        for i in 0..20 {
            for j in 0..i {
                assert_ne!(styles[i], styles[j], "{i} {j}");
            }
        }
    }

    #[test]
    fn decimator_bounds_the_points_and_keeps_the_extremes() {
        let rows = 1_000_003usize;
        let spike_row = 123_457usize;
        let mut d = Decimator::new(2, 500);
        for k in 0..rows {
            let t = k as f64 * 1e-3;
            let mut y = (t * 0.37).sin();
            if k == spike_row {
                y = 10.0;
            }
            let dip = if k == rows - 2 { -5.0 } else { 0.0 };
            d.push(t, &[y, dip]);
        }
        assert_eq!(d.rows(), rows);
        for s in 0..2 {
            let p = d.series(s);
            // between max/2 and max buckets, one or two points each, and the ends
            assert!(p.len() <= 1002, "{} points", p.len());
            assert!(p.len() >= 250, "{} points", p.len());
            assert!(p.windows(2).all(|w| w[0].0 < w[1].0), "time order");
        }
        let p0 = d.series(0);
        assert!(p0.contains(&(spike_row as f64 * 1e-3, 10.0)), "spike kept");
        let min = p0.iter().fold(f64::INFINITY, |m, q| m.min(q.1));
        assert!(min < -0.999_999, "{min}");
        let p1 = d.series(1);
        assert!(
            p1.contains(&((rows - 2) as f64 * 1e-3, -5.0)),
            "late dip kept"
        );
        // last sample present (a bucket's min or max holds the end)
        assert_eq!(p1.last().unwrap().0, (rows - 1) as f64 * 1e-3);
    }

    #[test]
    fn decimator_keeps_a_short_series_exactly() {
        let mut d = Decimator::new(1, 100);
        let pts: Vec<(f64, f64)> = (0..100).map(|k| (k as f64, (k as f64).cos())).collect();
        for (t, y) in &pts {
            d.push(*t, &[*y]);
        }
        assert_eq!(d.series(0), pts);
    }
}
