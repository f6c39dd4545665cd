//! Run outputs: one folder per closed-loop run.
//!
//! | file | content |
//! |---|---|
//! | `log.csv` | the time series, [`LOG_SCHEMA`] (see [`crate::log_csv`]), every `log.decimation`-th sample from t = 0 |
//! | `summary.json` | the [`Summary`]: outcome, reason, end time, metrics per output, effort, saturation, estimator RMS, seeds, parameter hash, version |
//! | `gains.json` | the flown gains ([`helicon_gnc::design::Gains::save`]); a scenario flies them again with `[controller] gains_file` |
//! | `scenario.toml` | the scenario as flown (relative `params` / `gains_file` paths made absolute) |
//! | `outputs.png/svg` | vn, ve, vd, ψ each with its reference, stacked (thesis Figs 14.3, 14.5, 14.8) |
//! | `servos.png/svg` | the four servo commands, saturation limits dashed |
//! | `estimator.png/svg` | truth − estimate of the nine measured states: attitude, velocity, rates (thesis Fig. 15.4) |
//! | `wind.png/svg` | air-mass velocity north, east, down (only when there is wind) |
//! | `inflow.png/svg` | main- and tail-rotor inflow ratios |
//! | `report.md` | a short human report with the tables and the figures |
//!
//! Two ways to write a run folder:
//!
//! - [`write_run`] from a [`Flight`] held in memory;
//! - streaming: [`start_run`] before flying (creates the folder and
//!   `log.csv`, so an unwritable folder fails before the flight), one
//!   [`LogWriter::write`] per kept sample, then [`finish_run`] with the
//!   summary. The figures are drawn from `log.csv` read back
//!   ([`write_figures`]), decimated to a bounded number of points, so neither
//!   flying nor plotting needs memory proportional to the duration.
//!
//! `summary.json` never holds a silent `null` or `inf`: its only nulls are
//! `reason` (the run completed) and `metrics.<output>.settling_time_s` (not
//! settled); any other number that is not finite is an error naming the
//! field ([`OutputError::NonFinite`]) and nothing is written.

pub use crate::log_csv::{
    LOG_COLUMNS, LOG_FORMAT_VERSION, LOG_SCHEMA, LogCsvError, LogWriter, MEASURED_NAMES,
    log_header, read_log_csv, write_log,
};

use crate::closed_loop::{Flight, Prepared, Summary};
use crate::log_csv::LogReader;
use crate::plot::{Decimator, Figure, HLine, Panel, PlotError, Series};
use crate::scenario::{OUTPUTS, Scenario};
use helicon_gnc::design::DesignError;
use helicon_model::state::INPUT_NAMES;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Errors writing the run outputs; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Creating or writing a file failed (the one configuration/file error
    /// shape: file, action, the `io::Error` kept as source).
    #[error(transparent)]
    Io(#[from] helicon_model::ConfigError),
    /// Serialising the summary or the scenario failed.
    #[error("{path}: cannot serialise: {message}")]
    Serialize {
        /// File.
        path: String,
        /// Message.
        message: String,
    },
    /// A summary number is NaN or infinite (it would be written as `null`).
    #[error("{path}: `{field}` is not a finite number: nothing written")]
    NonFinite {
        /// File.
        path: String,
        /// The JSON path of the field (`metrics.vn.rms_error`).
        field: String,
    },
    /// Writing or reading `log.csv`.
    #[error(transparent)]
    Log(#[from] LogCsvError),
    /// Writing the gains failed.
    #[error(transparent)]
    Gains(#[from] DesignError),
    /// Drawing a figure failed.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// Writing the sensor log failed.
    #[error(transparent)]
    SensorLog(#[from] crate::sensor_log::SensorLogError),
}

/// The files written for one run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunFiles {
    /// The run folder.
    pub dir: PathBuf,
    /// `log.csv`.
    pub log: PathBuf,
    /// `summary.json`.
    pub summary: PathBuf,
    /// `gains.json`.
    pub gains: PathBuf,
    /// `scenario.toml`.
    pub scenario: PathBuf,
    /// `report.md`.
    pub report: PathBuf,
    /// Figures (PNG and SVG), in the order written.
    pub plots: Vec<PathBuf>,
    /// Number of data rows in `log.csv`.
    pub log_rows: usize,
}

fn io_err(path: &Path, source: std::io::Error) -> OutputError {
    OutputError::Io(helicon_model::ConfigError::Io {
        file: path.display().to_string(),
        action: "write",
        source,
    })
}

/// Check that every number of a summary is finite. serde_json writes NaN
/// and ±inf as `null`, so any `null` other than `reason` and
/// `metrics.*.settling_time_s` names a non-finite field; a `Some(NaN)`
/// settling time is caught directly. `path` names the file in the error.
pub fn check_summary(path: &Path, summary: &Summary) -> Result<(), OutputError> {
    let non_finite = |field: String| OutputError::NonFinite {
        path: path.display().to_string(),
        field,
    };
    for (name, m) in &summary.metrics {
        if m.settling_time_s.is_some_and(|v| !v.is_finite()) {
            return Err(non_finite(format!("metrics.{name}.settling_time_s")));
        }
    }
    let v = serde_json::to_value(summary).map_err(|e| OutputError::Serialize {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    fn walk(v: &serde_json::Value, at: &str, bad: &mut Option<String>) {
        if bad.is_some() {
            return;
        }
        match v {
            serde_json::Value::Null => {
                let allowed = at == "reason"
                    || (at.starts_with("metrics.") && at.ends_with(".settling_time_s"));
                if !allowed {
                    *bad = Some(at.to_string());
                }
            }
            serde_json::Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    walk(x, &format!("{at}[{i}]"), bad);
                }
            }
            serde_json::Value::Object(o) => {
                for (k, x) in o {
                    let p = if at.is_empty() {
                        k.clone()
                    } else {
                        format!("{at}.{k}")
                    };
                    walk(x, &p, bad);
                }
            }
            _ => {}
        }
    }
    let mut bad = None;
    walk(&v, "", &mut bad);
    match bad {
        Some(field) => Err(non_finite(field)),
        None => Ok(()),
    }
}

/// Write `summary.json` (checked with [`check_summary`] first).
pub fn write_summary(path: &Path, summary: &Summary) -> Result<(), OutputError> {
    check_summary(path, summary)?;
    let text = serde_json::to_string_pretty(summary).map_err(|e| OutputError::Serialize {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    std::fs::write(path, text + "\n").map_err(|e| io_err(path, e))
}

/// The scenario as flown, with relative file references made absolute so the
/// copy in the run folder still points at the same files.
fn scenario_as_flown(scenario: &Scenario) -> Result<Scenario, std::io::Error> {
    let cwd = std::env::current_dir()?;
    let abs = |p: &Path| {
        let r = scenario.resolve(p);
        if r.is_relative() { cwd.join(&r) } else { r }
    };
    let mut s = scenario.clone();
    s.params = s.params.as_deref().map(abs);
    s.controller.gains_file = s.controller.gains_file.as_deref().map(abs);
    Ok(s)
}

/// Write `scenario.toml`.
pub fn write_scenario(path: &Path, scenario: &Scenario) -> Result<(), OutputError> {
    let s = scenario_as_flown(scenario).map_err(|source| {
        OutputError::Io(helicon_model::ConfigError::Io {
            file: path.display().to_string(),
            action: "resolve its paths against the current folder",
            source,
        })
    })?;
    let body = toml::to_string(&s).map_err(|e| OutputError::Serialize {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    let text = format!(
        "# The scenario as flown by helicon {}. Fly the same gains again with\n\
         # [controller] gains_file = \"gains.json\" (next to this file).\n{body}",
        env!("CARGO_PKG_VERSION")
    );
    std::fs::write(path, text).map_err(|e| io_err(path, e))
}

// ---------------------------------------------------------------- figures

/// What the run figures are drawn with.
#[derive(Debug, Clone, PartialEq)]
pub struct FigureOptions {
    /// Title prefix (the scenario name).
    pub name: String,
    /// Appended to every title, e.g. `diverged at t = 0.53 s`.
    pub note: Option<String>,
    /// Servo command limits `[min, max]` per input (dashed on the servo figure).
    pub servo_limits: Option<[[f64; 2]; 4]>,
    /// Buckets of the min/max decimation: at most twice this many points
    /// per line, whatever the duration.
    pub max_buckets: usize,
}

impl FigureOptions {
    /// The options for a run: its name, the divergence (if any) and the
    /// servo limits of the model flown.
    pub fn for_run(prepared: &Prepared, summary: &Summary) -> Self {
        let servos = &prepared.model.params().servos;
        Self {
            name: summary.scenario.clone(),
            note: summary
                .reason
                .as_ref()
                .map(|_| format!("diverged at t = {:.3} s", summary.t_end_s)),
            servo_limits: Some(std::array::from_fn(|i| [servos[i].s_min, servos[i].s_max])),
            max_buckets: DEFAULT_MAX_BUCKETS,
        }
    }

    fn title(&self, what: &str) -> String {
        match &self.note {
            Some(n) => format!("{}: {what} ({n})", self.name),
            None => format!("{}: {what}", self.name),
        }
    }
}

/// Default decimation buckets: ≤ 4000 points per line.
pub const DEFAULT_MAX_BUCKETS: usize = 2000;

/// One figure of the run folder.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunFigure {
    /// File stem (`outputs` for `outputs.png` and `outputs.svg`).
    pub stem: &'static str,
    /// Its title.
    pub title: String,
    /// What it shows, for the report.
    pub caption: &'static str,
}

/// The `log.csv` columns the figures use, in this order (the positions below).
const FIG_COLUMNS: [&str; 27] = [
    "t_s",
    "ref_vn",
    "ref_ve",
    "ref_vd",
    "ref_psi",
    "vn",
    "ve",
    "vd",
    "psi",
    "S_col",
    "S_lat",
    "S_lon",
    "S_tr",
    "err_phi",
    "err_theta",
    "err_psi",
    "err_u",
    "err_v",
    "err_w",
    "err_p",
    "err_q",
    "err_r",
    "wind_n",
    "wind_e",
    "wind_d",
    "lambda_mr",
    "lambda_tr",
];
// positions in FIG_COLUMNS (checked by a unit test)
const REF0: usize = 1;
const OUT0: usize = 5;
const SERVO0: usize = 9;
const ERR0: usize = 13;
const WIND0: usize = 22;
const LAMBDA0: usize = 25;

const BLACK: [u8; 3] = [0, 0, 0];
const BLUE: [u8; 3] = [31, 119, 180];
const RED: [u8; 3] = [214, 39, 40];

/// How far past ±π of its reference a drawn ψ may stay to keep its line
/// whole (rad): an error of about π is either branch.
const PSI_WRAP_SLACK_RAD: f64 = 0.05;

/// ψ (rad) as drawn against its reference `psi_ref_rad`: within ±π of it
/// (−π against a +π reference is the same heading, and would read as a 2π
/// error); an error within [`PSI_WRAP_SLACK_RAD`] of ±π takes the branch
/// nearest the last ψ drawn, so a heading step of π does not leave a lone
/// point a turn away.
fn psi_against_reference(psi_rad: f64, psi_ref_rad: f64, last_rad: Option<f64>) -> f64 {
    let pi = std::f64::consts::PI;
    let e = helicon_core::frames::wrap_pi(psi_rad - psi_ref_rad);
    let w = psi_ref_rad + e;
    match last_rad {
        Some(last) if e.abs() > pi - PSI_WRAP_SLACK_RAD => {
            let other = w - 2.0 * pi * e.signum();
            if (other - last).abs() < (w - last).abs() {
                other
            } else {
                w
            }
        }
        _ => w,
    }
}

/// Draw the run figures (PNG and SVG) into `dir` from the log file `log_csv`
/// (read back with [`LogReader`], min/max-decimated to at most
/// `2 × max_buckets` points per line, so the time and memory are bounded by
/// the file length and the bucket count, not the number of points drawn).
/// Returns the figures written (none for a log without rows) and their files.
#[allow(clippy::too_many_lines)] // the run report, one section after another
pub fn write_figures(
    dir: &Path,
    log_csv: &Path,
    opts: &FigureOptions,
) -> Result<(Vec<RunFigure>, Vec<PathBuf>), OutputError> {
    let mut reader = LogReader::open(log_csv, &FIG_COLUMNS)?;
    let mut dec = Decimator::new(FIG_COLUMNS.len() - 1, opts.max_buckets);
    let mut wind = false;
    let mut last_psi: Option<f64> = None;
    while let Some(row) = reader.next_row()? {
        wind |= row[WIND0..WIND0 + 3].iter().any(|v| *v != 0.0);
        let mut row = row.to_vec();
        let (psi, psi_ref) = (OUT0 + 3, REF0 + 3);
        row[psi] = psi_against_reference(row[psi], row[psi_ref], last_psi);
        last_psi = Some(row[psi]);
        dec.push(row[0], &row[1..]);
    }
    if dec.rows() == 0 {
        return Ok((Vec::new(), Vec::new()));
    }
    // decimated series by FIG_COLUMNS position
    let pts: Vec<Vec<(f64, f64)>> = (1..FIG_COLUMNS.len()).map(|c| dec.series(c - 1)).collect();
    let col = |c: usize| pts[c - 1].as_slice();
    let pi = std::f64::consts::PI;

    let mut figures: Vec<(RunFigure, Figure<'_>)> = Vec::new();

    // outputs and references (thesis Fig. 14.5 layout)
    let out_labels = ["vn [m/s]", "ve [m/s]", "vd [m/s]", "ψ [rad]"];
    let out_names = ["vn", "ve", "vd", "ψ"];
    let ref_names = [
        "vn reference",
        "ve reference",
        "vd reference",
        "ψ reference",
    ];
    let title = opts.title("outputs and references (NED velocity, heading)");
    let mut fig = Figure::new(&title, "time [s]");
    for j in 0..4 {
        let mut y = Series::new(out_names[j], col(OUT0 + j)).color(BLUE);
        let mut r = Series::new(ref_names[j], col(REF0 + j))
            .color(BLACK)
            .dashed();
        if j == 3 {
            y = y.break_jumps_over(pi);
            r = r.break_jumps_over(pi);
        }
        fig = fig.panel(Panel::new(out_labels[j]).series(y).series(r));
    }
    figures.push((
        RunFigure {
            stem: "outputs",
            title,
            caption: "each controlled output (solid) with its reference (dashed)",
        },
        fig,
    ));

    // servos with their saturation limits
    let title = opts.title("servo commands (after saturation)");
    let mut fig = Figure::new(&title, "time [s]");
    for i in 0..4 {
        let data = col(SERVO0 + i);
        let mut panel = Panel::new(&format!("{} [-]", INPUT_NAMES[i]))
            .series(Series::new(INPUT_NAMES[i], data).color(BLUE));
        if let Some(lim) = opts.servo_limits.map(|l| l[i]) {
            let (lo, hi) = data
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |b, p| {
                    (b.0.min(p.1), b.1.max(p.1))
                });
            // a limit is shown when it is within one data span (at least 5 %
            // of the servo range) of the data; otherwise it is named in the
            // legend, so a small signal is not flattened by a far limit
            let reach = (hi - lo).max(0.05 * (lim[1] - lim[0]));
            for (which, l) in [("max", lim[1]), ("min", lim[0])] {
                if l >= lo - reach && l <= hi + reach {
                    panel.y_include.push(l);
                    panel.hlines.push(HLine {
                        y: l,
                        label: format!("{which} {l}"),
                        color: RED,
                    });
                } else {
                    panel.notes.push(format!("{which} {l} (off scale)"));
                }
            }
        }
        fig = fig.panel(panel);
    }
    figures.push((
        RunFigure {
            stem: "servos",
            title,
            caption: "the four servo commands sent to the plant, saturation limits dashed",
        },
        fig,
    ));

    // estimator errors of the nine measured states
    let title = opts.title("estimator error (truth − estimate)");
    let mut fig = Figure::new(&title, "time [s]");
    let groups = [
        ("attitude error [rad]", ["φ", "θ", "ψ"]),
        ("velocity error [m/s]", ["u", "v", "w"]),
        ("rate error [rad/s]", ["p", "q", "r"]),
    ];
    for (g, (label, names)) in groups.iter().enumerate() {
        let mut panel = Panel::new(label);
        for (k, name) in names.iter().enumerate() {
            panel = panel.series(Series::new(name, col(ERR0 + 3 * g + k)));
        }
        fig = fig.panel(panel);
    }
    figures.push((
        RunFigure {
            stem: "estimator",
            title,
            caption: "truth − estimate of the nine measured states: attitude, body velocity, body rates",
        },
        fig,
    ));

    if wind {
        let title = opts.title("wind (air-mass velocity, NED)");
        let mut fig = Figure::new(&title, "time [s]");
        for (i, (label, name)) in [
            ("north [m/s]", "wind north"),
            ("east [m/s]", "wind east"),
            ("down [m/s]", "wind down"),
        ]
        .iter()
        .enumerate()
        {
            fig =
                fig.panel(Panel::new(label).series(Series::new(name, col(WIND0 + i)).color(BLUE)));
        }
        figures.push((
            RunFigure {
                stem: "wind",
                title,
                caption: "the air-mass velocity in NED axes",
            },
            fig,
        ));
    }

    let title = opts.title("rotor inflow ratios");
    let mut fig = Figure::new(&title, "time [s]");
    fig.panel_height_px = 190;
    for (i, (label, name)) in [("λ main rotor [-]", "λ_mr"), ("λ tail rotor [-]", "λ_tr")]
        .iter()
        .enumerate()
    {
        fig = fig.panel(Panel::new(label).series(Series::new(name, col(LAMBDA0 + i)).color(BLUE)));
    }
    figures.push((
        RunFigure {
            stem: "inflow",
            title,
            caption: "main- and tail-rotor inflow ratios",
        },
        fig,
    ));

    let mut files = Vec::with_capacity(2 * figures.len());
    let mut written = Vec::with_capacity(figures.len());
    for (info, fig) in figures {
        for ext in ["png", "svg"] {
            let path = dir.join(format!("{}.{ext}", info.stem));
            fig.write(&path)?;
            files.push(path);
        }
        written.push(info);
    }
    Ok((written, files))
}

// ---------------------------------------------------------------- report

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or_else(|| "not settled".to_string(), |s| format!("{s:.2}"))
}

/// The text of `report.md`: the run, its outcome, tables of the metrics and
/// the `figures` written (the summary is assumed checked, [`check_summary`]).
pub fn report_markdown(
    scenario: &Scenario,
    prepared: &Prepared,
    summary: &Summary,
    figures: &[RunFigure],
) -> String {
    let s = summary;
    let mut r = String::new();
    let _ = writeln!(r, "# helicon run: {}\n", s.scenario);
    let _ = writeln!(
        r,
        "- preset `{}`, {} s planned at {} Hz, design trim {:?} m/s NED, yaw {} rad",
        s.preset,
        scenario.duration_s,
        1.0 / s.sample_time_s,
        scenario.trim.velocity_ned_m_s,
        scenario.trim.yaw_rad
    );
    let _ = writeln!(
        r,
        "- controller: feedback {}, estimator {}, fusion {}, integral action {}, pincer alpha {:.5}, closed-loop spectral radius {:.6}",
        on(scenario.controller.feedback),
        on(scenario.controller.estimator),
        on(scenario.controller.fusion),
        on(scenario.controller.design.integral_action),
        s.design_alpha,
        s.design_spectral_radius
    );
    let _ = writeln!(
        r,
        "- hover/design trim: S = [{:.5}, {:.5}, {:.5}, {:.5}], lambda_mr = {:.5}",
        prepared.trim.u[0],
        prepared.trim.u[1],
        prepared.trim.u[2],
        prepared.trim.u[3],
        prepared.trim.aux.lambda_mr
    );
    let gyro = &prepared.model.params().yaw_gyro;
    let _ = writeln!(
        r,
        "- parameters: {}; stock yaw gyro {}",
        scenario.params.as_ref().map_or_else(
            || "the Bergen Industrial Twin (embedded)".to_string(),
            |p| format!("`{}` over the Bergen Twin", p.display())
        ),
        if gyro.enabled != 0.0 {
            format!(
                "on (Kp {} s/rad, Ki {}, {} rad/s at full tail input)",
                gyro.kp_s, gyro.ki, gyro.max_rate_rad_s
            )
        } else {
            "off".to_string()
        }
    );
    let _ = writeln!(
        r,
        "- seeds: wind {}, sensors {}; parameter hash `{}`; helicon {}\n",
        s.wind_seed, s.sensor_seed, s.parameter_hash, s.version
    );
    match &s.reason {
        Some(why) => {
            let _ = writeln!(
                r,
                "**Outcome: diverged** at t = {:.3} s: {why}\n",
                s.t_end_s
            );
        }
        None => {
            let _ = writeln!(r, "**Outcome: completed** ({:.2} s flown)\n", s.t_end_s);
        }
    }
    let _ = writeln!(r, "## Tracking\n");
    let _ = writeln!(
        r,
        "| output | step size | at (s) | 1 % settling (s) | overshoot (%) | RMS error | max abs error |"
    );
    let _ = writeln!(r, "|---|---|---|---|---|---|---|");
    for name in OUTPUTS {
        if let Some(m) = s.metrics.get(name) {
            let _ = writeln!(
                r,
                "| {name} | {:.3} | {:.2} | {} | {:.1} | {:.4} | {:.4} |",
                m.excitation,
                m.excitation_time_s,
                fmt_opt(m.settling_time_s),
                m.overshoot_pct,
                m.rms_error,
                m.max_abs_error
            );
        }
    }
    let _ = writeln!(
        r,
        "\nUnits: m/s for the velocities, rad for psi. Settling from the last reference change (or the initial error).\n"
    );
    let _ = writeln!(r, "## Inputs\n");
    let _ = writeln!(r, "| input | RMS of u - u_trim | time saturated (s) |");
    let _ = writeln!(r, "|---|---|---|");
    for i in 0..4 {
        let _ = writeln!(
            r,
            "| {} | {:.5} | {:.3} |",
            INPUT_NAMES[i], s.control_effort_rms[i], s.saturation_time_s[i]
        );
    }
    let _ = writeln!(r, "\n## Estimator error RMS (truth - estimate)\n");
    let _ = writeln!(r, "| {} |", MEASURED_NAMES.join(" | "));
    let _ = writeln!(r, "|{}", "---|".repeat(9));
    let cells: Vec<String> = s
        .estimator_error_rms
        .iter()
        .map(|v| format!("{v:.2e}"))
        .collect();
    let _ = writeln!(r, "| {} |", cells.join(" | "));
    let _ = writeln!(r, "\n## Figures\n");
    if figures.is_empty() {
        let _ = writeln!(r, "None: the log has no rows.\n");
    }
    for f in figures {
        let _ = writeln!(
            r,
            "![{t}]({s}.png)  \n{c}: [PNG]({s}.png) · [SVG]({s}.svg)\n",
            t = f.title,
            c = f.caption,
            s = f.stem
        );
    }
    let _ = writeln!(
        r,
        "## Files\n\n`log.csv` (time series, format version {LOG_FORMAT_VERSION}, columns in docs/closed-loop.md), `summary.json`, `gains.json` (the flown gains), `scenario.toml` (the scenario as flown)."
    );
    r
}

fn on(b: bool) -> &'static str {
    if b { "on" } else { "off" }
}

/// Start a run folder before flying: create `dir` and `log.csv` (its
/// header written), so a folder that cannot be written fails before the
/// flight. Write each kept sample with [`LogWriter::write`], then call
/// [`finish_run`] with `LogWriter::finish`'s row count.
pub fn start_run(dir: &Path) -> Result<LogWriter, OutputError> {
    std::fs::create_dir_all(dir).map_err(|e| io_err(dir, e))?;
    Ok(LogWriter::create(&dir.join("log.csv"))?)
}

/// Finish a run folder whose `log.csv` is written ([`start_run`]):
/// `summary.json`, `gains.json`, `scenario.toml`, the figures (drawn from
/// `log.csv`) and `report.md`. The summary is checked first.
pub fn finish_run(
    dir: &Path,
    scenario: &Scenario,
    prepared: &Prepared,
    summary: &Summary,
    log_rows: usize,
) -> Result<RunFiles, OutputError> {
    let summary_path = dir.join("summary.json");
    check_summary(&summary_path, summary)?;
    let log = dir.join("log.csv");
    let mut opts = FigureOptions::for_run(prepared, summary);
    if let Some(name) = scenario.params.as_deref().and_then(Path::file_name) {
        // another helicopter (or the same with other switches): said on
        // every figure, as the report says it
        opts.name = format!("{} [{}]", opts.name, name.to_string_lossy());
    }
    let (figures, plots) = write_figures(dir, &log, &opts)?;
    write_summary(&summary_path, summary)?;
    let gains = dir.join("gains.json");
    prepared.gains.save(&gains)?;
    let scenario_path = dir.join("scenario.toml");
    write_scenario(&scenario_path, scenario)?;
    let report = dir.join("report.md");
    std::fs::write(
        &report,
        report_markdown(scenario, prepared, summary, &figures),
    )
    .map_err(|e| io_err(&report, e))?;
    Ok(RunFiles {
        dir: dir.to_path_buf(),
        log,
        summary: summary_path,
        gains,
        scenario: scenario_path,
        report,
        plots,
        log_rows,
    })
}

/// Write the run folder `dir` (created if needed) of a flight held in
/// memory: `log.csv` (its rows as flown; the flight applied `[log]
/// decimation`), then as [`finish_run`].
pub fn write_run(
    dir: &Path,
    scenario: &Scenario,
    prepared: &Prepared,
    flight: &Flight,
) -> Result<RunFiles, OutputError> {
    check_summary(&dir.join("summary.json"), &flight.summary)?;
    let mut log = start_run(dir)?;
    for r in &flight.log {
        log.write(r)?;
    }
    let rows = log.finish()?;
    finish_run(dir, scenario, prepared, &flight.summary, rows)
}

/// One flown case of a multi-case scenario (`[[case]]`), for
/// [`write_cases_index`].
#[derive(Debug, Clone, Copy)]
pub struct CaseRun<'a> {
    /// Case name (the `[[case]] name`, without the scenario's prefix).
    pub case: &'a str,
    /// Its summary.
    pub summary: &'a Summary,
}

/// For a scenario with `[[case]]` entries flown into `dir/<case>/`: write
/// `dir/summary.json` (`{"scenario": name, "cases": {<case>: summary, ...}}`)
/// and `dir/report.md` (one table row per case, linking each case's
/// report). Returns the two paths.
pub fn write_cases_index(
    dir: &Path,
    scenario_name: &str,
    cases: &[CaseRun<'_>],
) -> Result<(PathBuf, PathBuf), OutputError> {
    std::fs::create_dir_all(dir).map_err(|e| io_err(dir, e))?;
    let summary = dir.join("summary.json");
    for c in cases {
        check_summary(&summary, c.summary)?;
    }
    let mut map = serde_json::Map::new();
    for c in cases {
        let v = serde_json::to_value(c.summary).map_err(|e| OutputError::Serialize {
            path: summary.display().to_string(),
            message: e.to_string(),
        })?;
        map.insert(c.case.to_string(), v);
    }
    let doc = serde_json::json!({ "scenario": scenario_name, "cases": map });
    let text = serde_json::to_string_pretty(&doc).map_err(|e| OutputError::Serialize {
        path: summary.display().to_string(),
        message: e.to_string(),
    })?;
    std::fs::write(&summary, text + "\n").map_err(|e| io_err(&summary, e))?;

    let mut r = String::new();
    let _ = writeln!(
        r,
        "# helicon run: {scenario_name} ({} cases)\n",
        cases.len()
    );
    let _ = writeln!(
        r,
        "1 % settling time (s) / overshoot (%) / RMS error per output; velocities in m/s, psi in rad.\n"
    );
    let _ = writeln!(r, "| case | outcome | vn | ve | vd | psi | report |");
    let _ = writeln!(r, "|---|---|---|---|---|---|---|");
    for c in cases {
        let s = c.summary;
        let outcome = match &s.reason {
            Some(why) => format!("diverged at {:.3} s: {why}", s.t_end_s),
            None => "completed".to_string(),
        };
        let cells: Vec<String> = OUTPUTS
            .iter()
            .map(|o| {
                s.metrics.get(*o).map_or_else(String::new, |m| {
                    format!(
                        "{} / {:.1} / {:.4}",
                        fmt_opt(m.settling_time_s),
                        m.overshoot_pct,
                        m.rms_error
                    )
                })
            })
            .collect();
        let _ = writeln!(
            r,
            "| {} | {outcome} | {} | [{}/report.md]({}/report.md) |",
            c.case,
            cells.join(" | "),
            c.case,
            c.case
        );
    }
    let report = dir.join("report.md");
    std::fs::write(&report, r).map_err(|e| io_err(&report, e))?;
    Ok((summary, report))
}

/// The columns of `ground.csv`, in order (SI units in the names).
pub const GROUND_COLUMNS: [&str; 15] = [
    "t_s",
    "height_m",
    "clearance_m",
    "omega_rad_s",
    "throttle",
    "normal_front_left_n",
    "normal_front_right_n",
    "normal_rear_left_n",
    "normal_rear_right_n",
    "normal_total_n",
    "friction_total_n",
    "ground_effect_factor",
    "spool_state",
    "land_stage",
    "blend",
];

/// `sensors.csv` in `dir`, the sensor log of a flight with `[log] sensors =
/// true` (the frames its flight software was given, with their truth), its
/// comment line naming the scenario and the sensor seed; nothing (`None`)
/// without recorded frames. Returns the file written.
pub fn write_sensor_log(
    dir: &Path,
    scenario: &Scenario,
    rows: &[crate::sensor_log::SensorLogRow],
) -> Result<Option<PathBuf>, OutputError> {
    if rows.is_empty() {
        return Ok(None);
    }
    let path = dir.join("sensors.csv");
    let file = std::fs::File::create(&path).map_err(|e| io_err(&path, e))?;
    let mut w = crate::sensor_log::SensorLogWriter::new(
        std::io::BufWriter::new(file),
        &path.display().to_string(),
        &format!(
            "helicon sim: scenario `{}`, sensor seed {}",
            scenario.name, scenario.sensors.seed
        ),
    )?;
    for r in rows {
        w.write(r)?;
    }
    let mut file = w.finish()?;
    std::io::Write::flush(&mut file).map_err(|e| io_err(&path, e))?;
    Ok(Some(path))
}

/// The ground files of a flight with the ground blocks on (nothing when
/// `rows` is empty): `ground.csv` ([`GROUND_COLUMNS`]: the CM's height
/// above the ground, the skids' clearance (empty without the landing gear),
/// rotor speed, throttle, the contact points' normal forces, friction, the
/// ground-effect factor, the on-board spool state after the sample
/// (`helicon_flight::landing::SpoolState::code`: 0 disarmed, 1 spooling up,
/// 2 ready, 3 taking off, 4 flying, 5 landed, 6 spooling down), the land
/// detector's stage (`LandStage::code`: 0 air, 1 ground contact, 2 maybe
/// landed, 3 landed; both empty without `[ground]`) and the blend of the
/// sample's command from ground idle to the flight law) and
/// `ground.png`/`ground.svg` (height and clearance, rotor speed, contact
/// forces, throttle and blend, and the spool state and land-detector stage
/// as step lines named on their axes). Returns the files written.
pub fn write_ground(
    dir: &Path,
    rows: &[crate::closed_loop::GroundRow],
    title: &str,
) -> Result<Vec<PathBuf>, OutputError> {
    if rows.is_empty() {
        return Ok(Vec::new());
    }
    let csv_path = dir.join("ground.csv");
    let mut text = GROUND_COLUMNS.join(",");
    text.push('\n');
    for r in rows {
        let g = &r.sample;
        let cells = [
            r.t_s,
            r.height_m,
            g.clearance_m,
            g.omega_rad_s,
            g.throttle,
            g.normal_n[0],
            g.normal_n[1],
            g.normal_n[2],
            g.normal_n[3],
            g.normal_n.iter().sum(),
            g.friction_n,
            g.ground_effect_factor,
            g.spool_state,
            g.land_stage,
            g.blend,
        ];
        for (i, v) in cells.iter().enumerate() {
            if i > 0 {
                text.push(',');
            }
            if v.is_finite() {
                let _ = write!(text, "{v:?}");
            }
        }
        text.push('\n');
    }
    std::fs::write(&csv_path, text).map_err(|e| io_err(&csv_path, e))?;
    let pts = |f: &dyn Fn(&crate::closed_loop::GroundRow) -> f64| -> Vec<(f64, f64)> {
        rows.iter().map(|r| (r.t_s, f(r))).collect()
    };
    let height = pts(&|r| r.height_m);
    let clearance = pts(&|r| r.sample.clearance_m);
    let omega = pts(&|r| r.sample.omega_rad_s);
    let total = pts(&|r| r.sample.normal_n.iter().sum());
    let per: Vec<Vec<(f64, f64)>> = (0..4).map(|i| pts(&|r| r.sample.normal_n[i])).collect();
    let friction = pts(&|r| r.sample.friction_n);
    let throttle = pts(&|r| r.sample.throttle);
    let blend = pts(&|r| r.sample.blend);
    let names = helicon_model::landing_gear::CONTACT_NAMES;
    let mut forces = Panel::new("contact force [N]").series(Series::new("normal, total", &total));
    for (i, p) in per.iter().enumerate() {
        forces = forces.series(Series::new(names[i], p));
    }
    forces = forces.series(Series::new("friction, total", &friction).dashed());
    let spool = steps(rows, |r| r.sample.spool_state);
    let stage = steps(rows, |r| r.sample.land_stage);
    let mut fig = Figure::new(&format!("{title}: ground"), "time [s]")
        .panel(
            Panel::new("height [m]")
                .series(Series::new("CM above ground", &height))
                .series(Series::new("skid clearance", &clearance)),
        )
        .panel(Panel::new("rotor speed [rad/s]").series(Series::new("Ω", &omega)))
        .panel(forces)
        .panel(
            Panel::new("[0 … 1]")
                .series(Series::new("throttle", &throttle))
                .series(Series::new("blend idle → law", &blend).dashed()),
        );
    // the on-board ground logic's states, when it flew ([ground])
    if !spool.is_empty() {
        use helicon_flight::landing::{LandStage, SpoolState};
        fig = fig
            .panel(
                Panel::new("on-board spool state")
                    .series(Series::new("spool state", &spool))
                    .categories(SpoolState::ALL.iter().map(|s| s.as_str())),
            )
            .panel(
                Panel::new("land detector")
                    .series(Series::new("land detector stage", &stage).color([200, 60, 40]))
                    .categories(LandStage::ALL.iter().map(|s| s.as_str())),
            );
    }
    let mut files = vec![csv_path];
    for ext in ["png", "svg"] {
        let path = dir.join(format!("ground.{ext}"));
        fig.write(&path)?;
        files.push(path);
    }
    Ok(files)
}

/// A coded state of the ground rows as a step line: each change drawn
/// vertically at the sample it happened (empty when the rows have none).
fn steps(
    rows: &[crate::closed_loop::GroundRow],
    code: impl Fn(&crate::closed_loop::GroundRow) -> f64,
) -> Vec<(f64, f64)> {
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for r in rows {
        let v = code(r);
        if !v.is_finite() {
            continue;
        }
        if let Some(&(_, last)) = pts.last()
            && last != v
        {
            pts.push((r.t_s, last));
        }
        pts.push((r.t_s, v));
    }
    pts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psi_is_drawn_against_its_reference_without_a_lone_point() {
        let pi = std::f64::consts::PI;
        // −π against +π: the same heading, drawn at +π
        assert!((psi_against_reference(-pi + 0.2, pi, None) - (pi + 0.2)).abs() < 1e-12);
        // a step of the reference from 0 to π while ψ is still at 0 (a hair
        // below): the branch of the last ψ drawn, not 2π
        let a = psi_against_reference(-1e-5, pi, Some(0.0));
        assert!((a + 1e-5).abs() < 1e-12, "{a}");
        let b = psi_against_reference(2e-5, pi, Some(a));
        assert!((b - 2e-5).abs() < 1e-12, "{b}");
        // past the slack the error is wrapped again
        let c = psi_against_reference(-0.2, pi, Some(-0.04));
        assert!((c - (2.0 * pi - 0.2)).abs() < 1e-12, "{c}");
    }

    #[test]
    fn figure_column_positions_match_the_names() {
        for j in 0..4 {
            assert_eq!(FIG_COLUMNS[REF0 + j], format!("ref_{}", OUTPUTS[j]));
            assert_eq!(FIG_COLUMNS[OUT0 + j], OUTPUTS[j]);
            assert_eq!(FIG_COLUMNS[SERVO0 + j], INPUT_NAMES[j]);
        }
        for (i, m) in MEASURED_NAMES.iter().enumerate() {
            assert_eq!(FIG_COLUMNS[ERR0 + i], format!("err_{m}"));
        }
        assert_eq!(
            &FIG_COLUMNS[WIND0..WIND0 + 3],
            &["wind_n", "wind_e", "wind_d"]
        );
        assert_eq!(&FIG_COLUMNS[LAMBDA0..], &["lambda_mr", "lambda_tr"]);
        for c in FIG_COLUMNS {
            assert!(crate::log_csv::log_column(c).is_some(), "{c}");
        }
    }
}
