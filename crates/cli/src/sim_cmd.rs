//! `helicon sim SCENARIO.toml [--out DIR]`: fly a closed-loop scenario and
//! write its run folder (log, summary, gains, scenario, plots, report).
//!
//! A divergence is a result, not an error: it is printed clearly and the exit
//! status is 0. Only bad input (scenario, parameter or gains files) or a
//! failure to write the outputs exits non-zero.

use crate::console::Console;
use crate::signals::{Stop, mark_stopped};
use anyhow::{Context, Result, bail};
use clap::Args;
use helicon_model::Params;
use helicon_sim::closed_loop::{
    Flight, Outcome, Prepared, estimate_log_csv, fly_to_until, prepare, prepare_with_params,
};
use helicon_sim::output::{CaseRun, RunFiles, finish_run, start_run, write_cases_index};
use helicon_sim::scenario::{OUTPUTS, Scenario, ScenarioOverrides, num};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// `helicon sim`.
#[derive(Args, Debug)]
pub struct SimArgs {
    /// Scenario file (TOML; see docs/closed-loop.md and scenarios/).
    pub scenario: PathBuf,
    /// Output folder (default `out/<scenario name>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Plant parameters: a TOML file of `helicon params` keys over the
    /// Bergen Twin (overrides the scenario's `params`; a relative path is
    /// relative to the working directory).
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// Seed of both the wind and the sensor random streams (overrides the
    /// scenario's `wind.seed` and `sensors.seed`, in every case).
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Flight duration in seconds (overrides the scenario's `duration_s`;
    /// finite, > 0 and <= 86400).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Replace a run of other inputs (another scenario, parameter file, seed
    /// or duration) already in the output folder.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub log: LogArgs,
}

/// The default of `--max-log-bytes`: 1 GB.
pub const DEFAULT_MAX_LOG_BYTES: u64 = 1_000_000_000;

/// How much of the flight `log.csv` keeps (`helicon sim`, `helicon sitl`).
#[derive(Args, Debug, Clone, Default)]
pub struct LogArgs {
    /// Rows per second of `log.csv`: the log at a lower rate (every n-th
    /// sample, n = the log's full rate / HZ rounded; the full rate is the
    /// control rate over `[log] decimation`). The summary's metrics still
    /// use every sample.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub log_rate: Option<f64>,
    /// The largest `log.csv` to write (bytes; default the scenario's
    /// `[log] max_bytes`, else 1000000000). Its size is estimated before
    /// the flight; a larger one is written at the highest rate that fits
    /// (said on stderr), or refused with --no-log-decimation or --log-rate.
    #[arg(long, value_name = "BYTES")]
    pub max_log_bytes: Option<u64>,
    /// Refuse a flight whose `log.csv` would be larger than
    /// --max-log-bytes instead of lowering its rate.
    #[arg(long)]
    pub no_log_decimation: bool,
}

impl LogArgs {
    /// The log limit (bytes) for `scenario` and how messages name it:
    /// `--max-log-bytes` when given, else the scenario's `[log] max_bytes`,
    /// else [`DEFAULT_MAX_LOG_BYTES`] (named as the option's default).
    pub fn limit(&self, scenario: &Scenario) -> (u64, String) {
        match (self.max_log_bytes, scenario.log.max_bytes) {
            (Some(b), _) => (b, format!("--max-log-bytes {b}")),
            (None, Some(b)) => (
                b,
                format!("[log] max_bytes = {b} of scenario `{}`", scenario.name),
            ),
            (None, None) => (
                DEFAULT_MAX_LOG_BYTES,
                format!("--max-log-bytes {DEFAULT_MAX_LOG_BYTES}"),
            ),
        }
    }
}

/// A byte count for people: `13.3 GB`, `950 kB`.
pub fn human_bytes(b: u64) -> String {
    let v = b as f64;
    if v >= 1e9 {
        format!("{:.1} GB", v / 1e9)
    } else if v >= 1e6 {
        format!("{:.1} MB", v / 1e6)
    } else if v >= 1e3 {
        format!("{:.0} kB", v / 1e3)
    } else {
        format!("{b} bytes")
    }
}

/// The stride of `log.csv` (write every n-th kept sample) for `scenario`
/// under `args`: from `--log-rate`, else 1; then the size estimated before
/// flying ([`estimate_log_csv`]) against `--max-log-bytes`: above it the
/// stride grows to fit (a warning on stderr), or the flight is refused
/// (`--no-log-decimation`, or a `--log-rate` given). `what` names the log in
/// messages.
pub fn plan_log(scenario: &Scenario, prepared: &Prepared, args: &LogArgs) -> Result<usize> {
    let ts = prepared.gains.set.sample_time_s;
    let full_hz = 1.0 / (ts * f64::from(scenario.log.decimation.max(1)));
    let mut stride = 1u64;
    if let Some(hz) = args.log_rate {
        if !(hz.is_finite() && hz > 0.0) {
            bail!("--log-rate {hz}: must be a finite rate > 0 Hz");
        }
        if hz > full_hz * (1.0 + 1e-9) {
            bail!(
                "--log-rate {hz}: above the log's full rate, {} Hz (the control rate over [log] decimation = {})",
                num(full_hz),
                scenario.log.decimation
            );
        }
        stride = (full_hz / hz).round().max(1.0) as u64;
    }
    let est = estimate_log_csv(scenario, prepared, stride)
        .with_context(|| format!("scenario `{}`: estimating the log's size", scenario.name))?;
    let (max, named) = args.limit(scenario);
    if est.bytes <= max {
        return Ok(usize::try_from(stride).unwrap_or(usize::MAX));
    }
    let rate = full_hz / stride as f64;
    let header = helicon_sim::log_csv::header_bytes();
    // the stride that fits: the rows the limit holds, at the measured width
    // aim 2 % under the limit: the estimate's error is smaller
    let target = max - max / 50;
    let fits_rows = (target.saturating_sub(header) as f64 / est.bytes_per_row).floor();
    let fits_hz = (fits_rows - 1.0).max(0.0) / scenario.duration_s.max(1e-9);
    let said = format!(
        "log.csv of this flight would be about {} ({} rows at {} Hz), over {named}",
        human_bytes(est.bytes),
        est.rows,
        num(rate)
    );
    if args.no_log_decimation || args.log_rate.is_some() || fits_rows < 2.0 {
        bail!(
            "{said}: give --log-rate HZ (about {} Hz fits), a larger --max-log-bytes, or a shorter --duration",
            num((fits_hz * 1000.0).floor() / 1000.0)
        );
    }
    let mut s = stride.saturating_mul((est.bytes as f64 / target as f64).ceil() as u64);
    let mut est2 = estimate_log_csv(scenario, prepared, s)?;
    while est2.bytes > target {
        s = s.saturating_add((s / 16).max(1));
        est2 = estimate_log_csv(scenario, prepared, s)?;
    }
    eprintln!(
        "warning: {said}: writing one sample in {s} ({} Hz, about {}); the summary's metrics use every sample. \
         For another rate give --log-rate HZ, for the full rate --max-log-bytes {} or more",
        num((full_hz / s as f64 * 1000.0).round() / 1000.0),
        human_bytes(est2.bytes),
        est.bytes + est.bytes / 50
    );
    Ok(usize::try_from(s).unwrap_or(usize::MAX))
}

/// The file of a run folder naming the inputs flown into it.
pub const RUN_STAMP: &str = ".helicon-run";

/// What was flown, as the run stamp says it: the scenario file and the
/// parameter file by their absolute paths, the overrides.
fn run_inputs(args: &SimArgs) -> String {
    let abs = |p: &Path| {
        std::fs::canonicalize(p)
            .unwrap_or_else(|_| p.to_path_buf())
            .display()
            .to_string()
    };
    let mut text = format!("scenario {}", abs(&args.scenario));
    if let Some(p) = &args.params {
        text.push_str(&format!(" --params {}", abs(p)));
    }
    if let Some(s) = args.seed {
        text.push_str(&format!(" --seed {s}"));
    }
    if let Some(d) = args.duration {
        text.push_str(&format!(" --duration {}", num(d)));
    }
    text
}

/// Refuse an output folder that holds a run of other inputs (unless
/// `force`); [`stamp_out_folder`] marks it once a run was written there (a
/// run refused before flying leaves the folder as it was).
fn claim_out_folder(out: &Path, inputs: &str, force: bool) -> Result<()> {
    let stamp = out.join(RUN_STAMP);
    if let Some(prev) = crate::files::read_text_if_present(&stamp)? {
        let prev = prev.trim();
        if prev != inputs && !force {
            bail!(
                "{} holds a run of other inputs ({prev}; this run: {inputs}): give another --out, or --force to replace it",
                out.display()
            );
        }
    }
    Ok(())
}

/// Mark `out` as holding the run of `inputs`.
fn stamp_out_folder(out: &Path, inputs: &str) -> Result<()> {
    let stamp = out.join(RUN_STAMP);
    std::fs::create_dir_all(out).with_context(|| format!("{}: cannot create", out.display()))?;
    std::fs::write(&stamp, format!("{inputs}\n"))
        .with_context(|| format!("{}: cannot write", stamp.display()))
}

/// What a run did and how long each part took.
pub struct RunReport {
    /// The flight.
    pub flight: Flight,
    /// The files written.
    pub files: RunFiles,
    /// Wall time of trim + linearization + design (s).
    pub prepare_s: f64,
    /// Wall time of the flight (s).
    pub fly_s: f64,
    /// Wall time of writing the outputs (s).
    pub write_s: f64,
}

/// Trim, linearize and design (or load the gains), with a spinner on
/// stderr; returns the prepared scenario and the wall time (s).
pub fn prepare_step(scenario: &Scenario) -> Result<(Prepared, f64)> {
    // the parameter file first: its errors name it (file:line: key)
    let params = match &scenario.params {
        Some(p) => Some((
            Params::from_file(&scenario.resolve(p))?,
            scenario.resolve(p),
        )),
        None => None,
    };
    let spinner = crate::console::spinner("trim, linearize, design");
    let t0 = Instant::now();
    let (prepared, with) = match params {
        Some((p, path)) => (
            prepare_with_params(scenario, p),
            format!(" with the parameters of {}", path.display()),
        ),
        None => (prepare(scenario), String::new()),
    };
    spinner.finish_and_clear();
    let prepared = prepared.with_context(|| {
        format!(
            "scenario `{}`{with}: preparing the design point and gains",
            scenario.name
        )
    })?;
    Ok((prepared, t0.elapsed().as_secs_f64()))
}

/// The scenario overrides of `--params`, `--seed`, `--duration` (the
/// parameter path made absolute: the scenario resolves paths against its
/// own folder).
pub fn overrides_from(
    params: Option<&Path>,
    seed: Option<u64>,
    duration_s: Option<f64>,
) -> Result<ScenarioOverrides> {
    let params = match params {
        Some(p) => Some(
            std::path::absolute(p)
                .with_context(|| format!("--params {}: cannot resolve the path", p.display()))?,
        ),
        None => None,
    };
    Ok(ScenarioOverrides {
        params,
        seed,
        duration_s,
    })
}

/// How command-line overrides are named in errors: ` (with --duration 0)`.
pub fn overrides_label(o: &ScenarioOverrides) -> String {
    let mut given = Vec::new();
    if let Some(p) = &o.params {
        given.push(format!("--params {}", p.display()));
    }
    if let Some(s) = o.seed {
        given.push(format!("--seed {s}"));
    }
    if let Some(d) = o.duration_s {
        given.push(format!("--duration {}", num(d)));
    }
    if given.is_empty() {
        String::new()
    } else {
        format!(" (with {})", given.join(" "))
    }
}

/// Fly with a progress bar on stderr, streaming `log.csv` into the run
/// folder `out` (created first, so an unwritable folder fails before the
/// flight), then write the rest of the folder. Returns the flight (its
/// in-memory log empty), the files, and the flying and writing wall times (s).
/// `source` names the scenario's origin in an error (its file).
pub fn fly_and_write_step(
    out: &Path,
    scenario: &Scenario,
    prepared: &Prepared,
    source: &str,
) -> Result<(Flight, RunFiles, f64, f64)> {
    fly_and_write_with(out, scenario, prepared, source, &LogArgs::default(), None)
}

/// As [`fly_and_write_step`], the log planned by `log` ([`plan_log`]) and
/// the flight ended early when `stop`'s flag is set (a signal): the run
/// folder is then written for what was flown, its summary `stopped`.
pub fn fly_and_write_with(
    out: &Path,
    scenario: &Scenario,
    prepared: &Prepared,
    source: &str,
    log: &LogArgs,
    stop: Option<&Stop>,
) -> Result<(Flight, RunFiles, f64, f64)> {
    scenario.check_work(source, prepared.gains.set.sample_time_s)?;
    let stride = plan_log(scenario, prepared, log)?;
    let mut log = start_run(out)
        .with_context(|| format!("writing the run outputs to {}", out.display()))?
        .with_stride(stride);
    let bar = crate::console::bar(1000, format!("flying {} s", num(scenario.duration_s)));
    let t1 = Instant::now();
    let mut cb = |f: f64| bar.set_position((f.clamp(0.0, 1.0) * 1000.0).round() as u64);
    let never = AtomicBool::new(false);
    let flag = stop.map_or(&never, |s| s.flag().as_ref());
    let flight = fly_to_until(scenario, prepared, &mut log, Some(&mut cb), flag);
    bar.finish_and_clear();
    let mut flight =
        flight.with_context(|| format!("scenario `{}`: setting up the flight", scenario.name))?;
    if let Some(stop) = stop {
        mark_stopped(stop, &mut flight.summary);
    }
    let fly_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let rows = log
        .finish()
        .with_context(|| format!("writing the run outputs to {}", out.display()))?;
    let files = finish_run(out, scenario, prepared, &flight.summary, rows)
        .with_context(|| format!("writing the run outputs to {}", out.display()))?;
    helicon_sim::output::write_ground(out, &flight.ground, &scenario.name)
        .with_context(|| format!("writing the ground files to {}", out.display()))?;
    helicon_sim::output::write_sensor_log(out, scenario, &flight.sensors)
        .with_context(|| format!("writing the sensor log to {}", out.display()))?;
    Ok((flight, files, fly_s, t2.elapsed().as_secs_f64()))
}

/// Prepare, fly (with a progress bar on stderr) and write a scenario;
/// `source` names its origin (file) in errors.
pub fn run_scenario(
    scenario: &Scenario,
    out: &Path,
    source: &str,
    log: &LogArgs,
    stop: Option<&Stop>,
) -> Result<RunReport> {
    let (prepared, prepare_s) = prepare_step(scenario)?;
    let (flight, files, fly_s, write_s) =
        fly_and_write_with(out, scenario, &prepared, source, log, stop)?;
    Ok(RunReport {
        flight,
        files,
        prepare_s,
        fly_s,
        write_s,
    })
}

/// A folder name from a scenario name (anything but letters, digits, `-`,
/// `_` and `.` becomes `_`, so a name cannot escape `out/`).
pub fn folder_name(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() || s.chars().all(|c| c == '.') {
        "run".to_string()
    } else {
        s
    }
}

/// Print the outcome, the key metrics and where the files are.
pub fn print_run(con: &mut Console, report: &RunReport) {
    let s = &report.flight.summary;
    match s.outcome {
        Outcome::Completed => writeln!(
            con,
            "outcome: COMPLETED, {:.2} s flown (preset {}, wind seed {}, sensor seed {})",
            s.t_end_s, s.preset, s.wind_seed, s.sensor_seed
        ),
        Outcome::Diverged => writeln!(
            con,
            "outcome: DIVERGED at t = {:.3} s: {}",
            s.t_end_s,
            s.reason.as_deref().unwrap_or("unknown reason")
        ),
        Outcome::Stopped => writeln!(
            con,
            "outcome: STOPPED at t = {:.3} s: {}",
            s.t_end_s,
            s.reason.as_deref().unwrap_or("on request")
        ),
    }
    writeln!(
        con,
        "  {:<4} {:>10} {:>8} {:>13} {:>10} {:>10} {:>10}",
        "out", "step size", "at [s]", "settle 1% [s]", "overshoot", "RMS err", "max err"
    );
    for name in OUTPUTS {
        if let Some(m) = s.metrics.get(name) {
            let settle = m
                .settling_time_s
                .map_or_else(|| "not settled".to_string(), |v| format!("{v:.2}"));
            writeln!(
                con,
                "  {:<4} {:>10.3} {:>8.2} {:>13} {:>9.1}% {:>10.4} {:>10.4}",
                name,
                m.excitation,
                m.excitation_time_s,
                settle,
                m.overshoot_pct,
                m.rms_error,
                m.max_abs_error
            );
        }
    }
    writeln!(
        con,
        "  (velocities in m/s, psi in rad; RMS of u - u_trim [{:.4}, {:.4}, {:.4}, {:.4}], saturated [{:.2}, {:.2}, {:.2}, {:.2}] s)",
        s.control_effort_rms[0],
        s.control_effort_rms[1],
        s.control_effort_rms[2],
        s.control_effort_rms[3],
        s.saturation_time_s[0],
        s.saturation_time_s[1],
        s.saturation_time_s[2],
        s.saturation_time_s[3]
    );
    let f = &report.files;
    writeln!(
        con,
        "wrote {} ({} rows, {}), summary.json, gains.json, scenario.toml, report.md and {} plots to {}",
        f.log
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        f.log_rows,
        std::fs::metadata(&f.log)
            .map_or_else(|_| "size unknown".to_string(), |m| human_bytes(m.len())),
        f.plots.len(),
        f.dir.display()
    );
    writeln!(
        con,
        "  times: prepare {:.3} s, flight {:.3} s ({:.0}x real time), outputs {:.3} s",
        report.prepare_s,
        report.fly_s,
        s.t_end_s / report.fly_s.max(1e-9),
        report.write_s
    );
}

/// Run `helicon sim`: one run folder, or for a scenario with `[[case]]`
/// entries one sub-folder per case plus a `summary.json`/`report.md` index.
pub fn run(args: &SimArgs) -> Result<()> {
    let overrides = overrides_from(args.params.as_deref(), args.seed, args.duration)?;
    let source = format!("{}{}", args.scenario.display(), overrides_label(&overrides));
    let scenario = Scenario::from_file(&args.scenario)?.with_overrides(&overrides, &source)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(folder_name(&scenario.name)));
    claim_out_folder(&out, &run_inputs(args), args.force)?;
    let cases = scenario.cases();
    // stdout may close at any time (`| head -1`): every case is still flown
    // and written, the write error is returned at the end.
    let mut con = Console::stdout();
    writeln!(
        con,
        "helicon sim: scenario `{}` ({}), preset {}, {} s{}",
        scenario.name,
        args.scenario.display(),
        scenario.preset.name(),
        num(scenario.duration_s),
        if scenario.variants.is_empty() {
            String::new()
        } else {
            format!(", {} cases", cases.len())
        }
    );
    let stop = Stop::install()?;
    if scenario.variants.is_empty() {
        let report = run_scenario(&scenario, &out, &source, &args.log, Some(&stop))?;
        stamp_out_folder(&out, &run_inputs(args))?;
        print_run(&mut con, &report);
        if let Some(e) = stop.stopped(format!("the run folder {} is complete", out.display())) {
            let _ = con.finish();
            return Err(e.into());
        }
        return con.finish().context("writing to stdout");
    }
    let prefix = format!("{}-", scenario.name);
    let mut flown = Vec::with_capacity(cases.len());
    for case in &cases {
        let label = case
            .name
            .strip_prefix(&prefix)
            .unwrap_or(&case.name)
            .to_string();
        let dir = out.join(folder_name(&label));
        writeln!(con, "\ncase `{label}` ({})", case.name);
        let report = run_scenario(
            case,
            &dir,
            &format!("{source}, case `{label}`"),
            &args.log,
            Some(&stop),
        )?;
        print_run(&mut con, &report);
        flown.push((label, report.flight.summary));
        if stop.received().is_some() {
            // the cases not flown are left out of the index
            break;
        }
    }
    let index: Vec<CaseRun<'_>> = flown
        .iter()
        .map(|(label, summary)| CaseRun {
            case: label,
            summary,
        })
        .collect();
    let (summary, report) = write_cases_index(&out, &scenario.name, &index)
        .with_context(|| format!("writing the case index to {}", out.display()))?;
    stamp_out_folder(&out, &run_inputs(args))?;
    if let Some(e) = stop.stopped(format!(
        "{} of {} cases flown, the index {} lists them",
        flown.len(),
        cases.len(),
        summary.display()
    )) {
        let _ = con.finish();
        return Err(e.into());
    }
    let diverged = flown.iter().filter(|(_, s)| s.reason.is_some()).count();
    writeln!(
        con,
        "\n{} cases flown, {} completed, {diverged} diverged; index: {} and {}",
        flown.len(),
        flown.len() - diverged,
        summary.display(),
        report.display()
    );
    con.finish().context("writing to stdout")
}
