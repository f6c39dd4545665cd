//! Run outputs: one folder per closed-loop run.
//!
//! [`write_run`] writes
//!
//! | file | content |
//! |---|---|
//! | `log.csv` | the time series (columns below), every `log.decimation`-th sample from t = 0 |
//! | `summary.json` | the [`Summary`]: outcome, reason, end time, metrics per output, effort, saturation, estimator RMS, seeds, parameter hash, version |
//! | `gains.json` | the flown gains ([`helicon_gnc::design::Gains::save`]); a scenario flies them again with `[controller] gains_file` |
//! | `scenario.toml` | the scenario as flown (relative `params` / `gains_file` paths made absolute) |
//! | `*.png`, `*.svg` | plots: each output against its reference, servo inputs, wind (when there is any), estimator errors of the nine measured states, inflow ratios |
//! | `report.md` | a short human report linking the plots |
//!
//! # `log.csv` columns (SI units: m, rad, m/s, rad/s; servo commands dimensionless)
//!
//! 1. `t_s`: time (s);
//! 2. the 30 true states, named as [`STATE_NAMES`] (`x y z` NED position,
//!    `phi theta psi`, `u v w` body velocity, `p q r`, flapping, stabilizer
//!    bar, servo states and their rates);
//! 3. `S_col S_lat S_lon S_tr`: the servo commands sent to the plant (after
//!    saturation), [`INPUT_NAMES`];
//! 4. `ref_vn ref_ve ref_vd ref_psi`: the references (NED velocity, yaw);
//! 5. `vn ve vd`: the true NED velocity;
//! 6. `est_<m>` for the nine measured states `m` of (15.2), [`MEASURED_NAMES`]
//!    (`phi theta psi u v w p q r`): the estimator's value (absolute);
//! 7. `err_<m>`: truth − estimate (the yaw error wrapped to (−π, π]);
//! 8. `meas_<m>`: the measurement given to the controller (ideal states, or
//!    the output of attitude determination and fusion when `controller.fusion`);
//! 9. `wind_n wind_e wind_d`: air-mass velocity NED (m/s);
//! 10. `lambda_mr lambda_tr`: main- and tail-rotor inflow ratios;
//! 11. `thrust_mr_n force_tr_y_n`: main-rotor thrust −hFz (N) and tail-rotor
//!     side force tFy (N).
//!
//! Numbers are written with the shortest representation that reads back to
//! the same `f64`, so a log is an exact record of the run.

use crate::closed_loop::{Flight, LogRow, Prepared, Summary};
use crate::plot::{LinePlot, PlotError, Series};
use crate::scenario::{OUTPUTS, Scenario};
use helicon_core::frames::wrap_pi;
use helicon_gnc::design::DesignError;
use helicon_model::state::{INPUT_NAMES, REDUCED_OFFSET, STATE_NAMES};
use std::fmt::Write as _;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The nine measured states of the thesis (15.2), in order.
pub const MEASURED_NAMES: [&str; 9] = ["phi", "theta", "psi", "u", "v", "w", "p", "q", "r"];

/// Number of columns of `log.csv`.
pub const LOG_COLUMNS: usize = 1 + 30 + 4 + 4 + 3 + 3 * 9 + 3 + 2 + 2;

/// Errors writing the run outputs.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Creating or writing a file failed.
    #[error("{path}: {message}")]
    Io {
        /// File or folder.
        path: String,
        /// Message.
        message: String,
    },
    /// Serialising the summary or the scenario failed.
    #[error("{path}: cannot serialise: {message}")]
    Serialize {
        /// File.
        path: String,
        /// Message.
        message: String,
    },
    /// Writing the gains failed.
    #[error(transparent)]
    Gains(#[from] DesignError),
    /// Drawing a plot failed.
    #[error(transparent)]
    Plot(#[from] PlotError),
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
    /// Plots (PNG and SVG), in the order written.
    pub plots: Vec<PathBuf>,
    /// Number of data rows in `log.csv`.
    pub log_rows: usize,
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// The `log.csv` header, in column order (see the module documentation).
pub fn log_header() -> Vec<String> {
    let mut h = Vec::with_capacity(LOG_COLUMNS);
    h.push("t_s".to_string());
    h.extend(STATE_NAMES.iter().map(|s| (*s).to_string()));
    h.extend(INPUT_NAMES.iter().map(|s| (*s).to_string()));
    h.extend(OUTPUTS.iter().map(|s| format!("ref_{s}")));
    h.extend(["vn", "ve", "vd"].iter().map(|s| (*s).to_string()));
    for prefix in ["est", "err", "meas"] {
        h.extend(MEASURED_NAMES.iter().map(|s| format!("{prefix}_{s}")));
    }
    h.extend(
        [
            "wind_n",
            "wind_e",
            "wind_d",
            "lambda_mr",
            "lambda_tr",
            "thrust_mr_n",
            "force_tr_y_n",
        ]
        .iter()
        .map(|s| (*s).to_string()),
    );
    h
}

/// truth − estimate of measured state `i` (yaw wrapped).
fn estimator_error(r: &LogRow, i: usize) -> f64 {
    let d = r.x[i + REDUCED_OFFSET] - r.estimate9[i];
    if i == 2 { wrap_pi(d) } else { d }
}

/// Write one number: shortest round-trip text, plain notation for ordinary
/// magnitudes and exponent notation for very small or large ones.
fn put<W: Write>(w: &mut W, v: f64, first: bool) -> std::io::Result<()> {
    if !first {
        w.write_all(b",")?;
    }
    let a = v.abs();
    if a == 0.0 || !a.is_finite() || (1e-4..1e9).contains(&a) {
        write!(w, "{v}")
    } else {
        write!(w, "{v:e}")
    }
}

fn write_row<W: Write>(w: &mut W, r: &LogRow) -> std::io::Result<()> {
    put(w, r.t_s, true)?;
    for v in r.x.iter() {
        put(w, *v, false)?;
    }
    for v in r.u.iter() {
        put(w, *v, false)?;
    }
    for v in r.reference {
        put(w, v, false)?;
    }
    for v in &r.output[..3] {
        put(w, *v, false)?;
    }
    for v in r.estimate9 {
        put(w, v, false)?;
    }
    for i in 0..9 {
        put(w, estimator_error(r, i), false)?;
    }
    for v in r.measured9 {
        put(w, v, false)?;
    }
    for v in r.wind_ned.iter().chain(&r.lambda).chain(&r.thrust) {
        put(w, *v, false)?;
    }
    w.write_all(b"\n")
}

/// Write `log.csv` (every `decimation`-th row from the first); returns the
/// number of data rows.
pub fn write_log(path: &Path, log: &[LogRow], decimation: u32) -> Result<usize, OutputError> {
    let file = std::fs::File::create(path).map_err(|e| io_err(path, e))?;
    let mut w = BufWriter::with_capacity(1 << 16, file);
    let step = decimation.max(1) as usize;
    let mut rows = 0;
    let res = (|| -> std::io::Result<()> {
        w.write_all(log_header().join(",").as_bytes())?;
        w.write_all(b"\n")?;
        for r in log.iter().step_by(step) {
            write_row(&mut w, r)?;
            rows += 1;
        }
        w.flush()
    })();
    res.map_err(|e| io_err(path, e))?;
    Ok(rows)
}

/// Write `summary.json`.
pub fn write_summary(path: &Path, summary: &Summary) -> Result<(), OutputError> {
    let text = serde_json::to_string_pretty(summary).map_err(|e| OutputError::Serialize {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    std::fs::write(path, text + "\n").map_err(|e| io_err(path, e))
}

/// The scenario as flown, with relative file references made absolute so the
/// copy in the run folder still points at the same files.
fn scenario_as_flown(scenario: &Scenario) -> Scenario {
    let abs = |p: &Path| {
        let r = scenario.resolve(p);
        if r.is_relative() {
            std::env::current_dir().map_or(r.clone(), |d| d.join(&r))
        } else {
            r
        }
    };
    let mut s = scenario.clone();
    s.params = s.params.as_deref().map(abs);
    s.controller.gains_file = s.controller.gains_file.as_deref().map(abs);
    s
}

/// Write `scenario.toml`.
pub fn write_scenario(path: &Path, scenario: &Scenario) -> Result<(), OutputError> {
    let s = scenario_as_flown(scenario);
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

/// At most this many points per plotted line (a longer log is strided).
const MAX_PLOT_POINTS: usize = 4000;

struct PlotSpec {
    stem: &'static str,
    title: String,
    y_label: &'static str,
    lines: Vec<(String, Vec<(f64, f64)>)>,
}

fn column(log: &[LogRow], stride: usize, f: impl Fn(&LogRow) -> f64) -> Vec<(f64, f64)> {
    log.iter().step_by(stride).map(|r| (r.t_s, f(r))).collect()
}

fn plot_specs(log: &[LogRow]) -> Vec<PlotSpec> {
    let stride = log.len().div_ceil(MAX_PLOT_POINTS).max(1);
    let mut specs = Vec::new();
    let outputs: [(&str, &str, &str); 4] = [
        ("vn", "North velocity", "vn [m/s]"),
        ("ve", "East velocity", "ve [m/s]"),
        ("vd", "Down velocity", "vd [m/s]"),
        ("psi", "Heading", "psi [rad]"),
    ];
    for (j, (name, what, unit)) in outputs.into_iter().enumerate() {
        specs.push(PlotSpec {
            stem: match j {
                0 => "output_vn",
                1 => "output_ve",
                2 => "output_vd",
                _ => "output_psi",
            },
            title: format!("{what} {name} and its reference"),
            y_label: unit,
            lines: vec![
                (
                    format!("{name} reference"),
                    column(log, stride, |r| r.reference[j]),
                ),
                (name.to_string(), column(log, stride, |r| r.output[j])),
            ],
        });
    }
    specs.push(PlotSpec {
        stem: "servos",
        title: "Servo inputs (after saturation)".to_string(),
        y_label: "servo command [-]",
        lines: (0..4)
            .map(|i| (INPUT_NAMES[i].to_string(), column(log, stride, |r| r.u[i])))
            .collect(),
    });
    if log.iter().any(|r| r.wind_ned.iter().any(|w| *w != 0.0)) {
        specs.push(PlotSpec {
            stem: "wind",
            title: "Wind (air-mass velocity, NED)".to_string(),
            y_label: "wind [m/s]",
            lines: ["north", "east", "down"]
                .iter()
                .enumerate()
                .map(|(i, n)| ((*n).to_string(), column(log, stride, |r| r.wind_ned[i])))
                .collect(),
        });
    }
    for (stem, what, unit, first) in [
        ("estimator_error_attitude", "attitude", "error [rad]", 0),
        (
            "estimator_error_velocity",
            "body velocity",
            "error [m/s]",
            3,
        ),
        ("estimator_error_rates", "body rates", "error [rad/s]", 6),
    ] {
        specs.push(PlotSpec {
            stem,
            title: format!("Estimator error (truth - estimate): {what}"),
            y_label: unit,
            lines: (first..first + 3)
                .map(|i| {
                    (
                        MEASURED_NAMES[i].to_string(),
                        column(log, stride, |r| estimator_error(r, i)),
                    )
                })
                .collect(),
        });
    }
    specs.push(PlotSpec {
        stem: "inflow",
        title: "Inflow ratios".to_string(),
        y_label: "inflow ratio [-]",
        lines: vec![
            (
                "main rotor".to_string(),
                column(log, stride, |r| r.lambda[0]),
            ),
            (
                "tail rotor".to_string(),
                column(log, stride, |r| r.lambda[1]),
            ),
        ],
    });
    specs
}

/// Draw the plots as PNG and SVG into `dir`; returns the files written.
pub fn write_plots(dir: &Path, log: &[LogRow]) -> Result<Vec<PathBuf>, OutputError> {
    let mut files = Vec::new();
    if log.is_empty() {
        return Ok(files);
    }
    for spec in plot_specs(log) {
        let mut p = LinePlot::new(&spec.title, "time [s]", spec.y_label);
        for (name, pts) in &spec.lines {
            p = p.series(Series::new(name, pts));
        }
        for ext in ["png", "svg"] {
            let path = dir.join(format!("{}.{ext}", spec.stem));
            p.write(&path)?;
            files.push(path);
        }
    }
    Ok(files)
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or_else(|| "not settled".to_string(), |s| format!("{s:.2}"))
}

/// The text of `report.md`.
pub fn report_markdown(scenario: &Scenario, prepared: &Prepared, flight: &Flight) -> String {
    let s = &flight.summary;
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
        "| output | excitation | at (s) | 1 % settling (s) | overshoot (%) | RMS error | max abs error |"
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
    let _ = writeln!(r, "\n## Plots\n");
    for spec in plot_specs(&flight.log) {
        let _ = writeln!(
            r,
            "![{t}]({s}.png)  \n{t}: [PNG]({s}.png) · [SVG]({s}.svg)\n",
            t = spec.title,
            s = spec.stem
        );
    }
    let _ = writeln!(
        r,
        "## Files\n\n`log.csv` (time series, columns in docs/closed-loop.md), `summary.json`, `gains.json` (the flown gains), `scenario.toml` (the scenario as flown)."
    );
    r
}

fn on(b: bool) -> &'static str {
    if b { "on" } else { "off" }
}

/// Write the run folder `dir` (created if needed): `log.csv`,
/// `summary.json`, `gains.json`, `scenario.toml`, the plots and `report.md`.
pub fn write_run(
    dir: &Path,
    scenario: &Scenario,
    prepared: &Prepared,
    flight: &Flight,
) -> Result<RunFiles, OutputError> {
    std::fs::create_dir_all(dir).map_err(|e| io_err(dir, e))?;
    let log = dir.join("log.csv");
    // the flight log is already decimated (`[log] decimation`) as it is flown
    let log_rows = write_log(&log, &flight.log, 1)?;
    let summary = dir.join("summary.json");
    write_summary(&summary, &flight.summary)?;
    let gains = dir.join("gains.json");
    prepared.gains.save(&gains)?;
    let scenario_path = dir.join("scenario.toml");
    write_scenario(&scenario_path, scenario)?;
    let plots = write_plots(dir, &flight.log)?;
    let report = dir.join("report.md");
    std::fs::write(&report, report_markdown(scenario, prepared, flight))
        .map_err(|e| io_err(&report, e))?;
    Ok(RunFiles {
        dir: dir.to_path_buf(),
        log,
        summary,
        gains,
        scenario: scenario_path,
        report,
        plots,
        log_rows,
    })
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
