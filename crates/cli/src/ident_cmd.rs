//! `helicon ident frf` and `helicon ident tf`: frequency responses from any
//! CSV log with a time column, and transfer-function fits to them (see
//! docs/ident.md).

use anyhow::{Context, Result, anyhow, bail};
use clap::{Args, Subcommand};
use helicon_ident::Complex64;
use helicon_ident::fit::{CostOptions, TfFit, TfStructure, fit_tf};
use helicon_ident::frf::{
    Frf, WindowSpec, composite, conditioned, cross_spectra_grid, log_grid, unwrap_deg,
};
use helicon_model::config_error::escape_control as esc;
use helicon_model::config_error::format_seconds;
use helicon_sim::plot::{Figure, HLine, Panel, Series};
use std::io::Write;
use std::path::{Path, PathBuf};

/// `helicon ident`.
#[derive(Args, Debug)]
pub struct IdentArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: IdentCommand,
}

/// The `ident` subcommands.
#[derive(Subcommand, Debug)]
pub enum IdentCommand {
    /// Frequency responses (composite windows, coherence, random error) from a CSV log: DIR/frf.csv and Bode plots.
    Frf(FrfArgs),
    /// Fit a transfer function (CIFER cost) to one response of a frf.csv: DIR/tf_<output>.json and an overlay plot.
    Tf(TfArgs),
    /// Fit a linear state-space model with free entries (model TOML) to one or several responses: DIR/ss_fit.json and overlay plots.
    Ss(crate::ident_ss::SsArgs),
    /// Sample a flight-test input (sweep, multisine, doublet, 3211) from a TOML file to CSV `t_s,value`.
    Input(InputArgs),
    /// Identify a servo (K, ωn, ζ, rate limit, thesis (5.1)–(5.4)) from a log of its command and measured position: DIR/servo.json and an overlay plot.
    Servo(crate::ident_servo::ServoArgs),
    /// Write a simulated bench test of one of the model's servos (steps, a sweep, position noise) to CSV.
    ServoBench(crate::ident_servo::ServoBenchArgs),
    /// A ground experiment of thesis §11.1 (rotor drag, lift slopes, blade spring, Bell/Hiller gains, tail-fin loss): readings CSV in, parameter and standard error out.
    Ground(crate::ident_ground::GroundArgs),
    /// Identify the model's physical parameters from flight responses at several operating points (IDENT.toml; thesis ch. 11).
    Fit(crate::ident_fit::FitArgs),
    /// The identification programme end to end on a simulated helicopter with known parameters.
    Demo(crate::ident_fit::DemoArgs),
}

/// `helicon ident input`.
#[derive(Args, Debug)]
pub struct InputArgs {
    /// The input (TOML: `kind` = sweep | multisine | doublet | 3211 and its fields, see docs/ident.md).
    pub input: PathBuf,
    /// Sample time, s.
    #[arg(long, default_value_t = 0.0025, allow_negative_numbers = true)]
    pub dt: f64,
    /// Output CSV file.
    #[arg(long)]
    pub out: PathBuf,
}

/// `helicon ident input`.
pub fn run_input(a: &InputArgs) -> Result<()> {
    let file = a.input.display().to_string();
    let text = crate::files::read_text(&a.input)?;
    let mut input: helicon_ident::inputs::Input =
        toml::from_str(&text).map_err(|e| anyhow!("{file}: {}", e.to_string().trim_end()))?;
    input.prepare().with_context(|| file.clone())?;
    if !(a.dt.is_finite() && a.dt > 0.0) || input.duration_s() / a.dt > 1e8 {
        bail!(
            "--dt {}: must be finite, > 0 and give at most 1e8 samples over {} s",
            a.dt,
            input.duration_s()
        );
    }
    let mut w = std::io::BufWriter::new(
        std::fs::File::create(&a.out)
            .with_context(|| format!("{}: cannot create", a.out.display()))?,
    );
    writeln!(w, "t_s,value")?;
    let v = input.sample(a.dt);
    for (i, x) in v.iter().enumerate() {
        writeln!(w, "{},{x}", i as f64 * a.dt)?;
    }
    w.flush()?;
    println!(
        "{file}: {} samples over {} s -> {}",
        v.len(),
        input.duration_s(),
        a.out.display()
    );
    Ok(())
}

/// `helicon ident frf`.
#[derive(Args, Debug)]
pub struct FrfArgs {
    /// The log: a CSV with a header row (`#` lines are comments), or a flight log (ULog, e.g. flight.ulg) read under log.csv's column names.
    pub log: PathBuf,
    /// Input column.
    #[arg(long)]
    pub input: String,
    /// Output column(s), comma separated.
    #[arg(long, value_delimiter = ',', required = true)]
    pub output: Vec<String>,
    /// Time column, s.
    #[arg(long, default_value = "t_s")]
    pub time: String,
    /// Lowest frequency, rad/s (default: two periods in the longest window).
    #[arg(long, allow_negative_numbers = true)]
    pub omega_min: Option<f64>,
    /// Highest frequency, rad/s (default: 0.4 × the Nyquist frequency).
    #[arg(long, allow_negative_numbers = true)]
    pub omega_max: Option<f64>,
    /// Frequency points (log spaced).
    #[arg(long, default_value_t = 200)]
    pub points: usize,
    /// Window lengths composited: record/2, record/4, … (1 … 8).
    #[arg(long, default_value_t = 5)]
    pub windows: usize,
    /// Other input columns to condition on (correlated inputs: other servos, closed loop).
    #[arg(long, value_delimiter = ',')]
    pub conditioned_on: Vec<String>,
    /// Longest window used, s: longer ones among record/2, record/4, … are left out.
    #[arg(long, allow_negative_numbers = true)]
    pub max_window_s: Option<f64>,
    /// The part of the log used.
    #[command(flatten)]
    pub span: TimeSpan,
    /// The logged excitation added to the input from outside the loop (default: log.csv's `exc_lon`, `exc_lat`, `exc_col`, `exc_tr` for S_lon, S_lat, S_col, S_tr, when the log has it): checked to have excited the input.
    #[arg(long)]
    pub excitation: Option<String>,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// The excitation column log.csv writes for a servo input.
fn default_excitation(input: &str) -> Option<&'static str> {
    match input {
        "S_col" => Some("exc_col"),
        "S_lat" => Some("exc_lat"),
        "S_lon" => Some("exc_lon"),
        "S_tr" => Some("exc_tr"),
        _ => None,
    }
}

/// The part of a log to use, on its time column (`--t-start`, `--t-end`).
#[derive(Args, Debug, Clone, Copy, Default)]
pub struct TimeSpan {
    /// Use the log from this time on (the time column's value), s.
    #[arg(long, allow_negative_numbers = true)]
    pub t_start: Option<f64>,
    /// Use the log up to this time (the time column's value), s.
    #[arg(long, allow_negative_numbers = true)]
    pub t_end: Option<f64>,
}

impl TimeSpan {
    /// Whether time `t` is inside; a bound must be finite and the start
    /// before the end (refused naming the options `flags`, e.g.
    /// `--t-start/--t-end`).
    fn check(&self, flags: &str) -> Result<()> {
        for v in [self.t_start, self.t_end].into_iter().flatten() {
            if !v.is_finite() {
                bail!("{flags} {v}: must be a finite time, s");
            }
        }
        if let (Some(a), Some(b)) = (self.t_start, self.t_end)
            && a >= b
        {
            bail!("{flags} {a} … {b}: the start must be before the end");
        }
        Ok(())
    }

    fn contains(&self, t: f64) -> bool {
        self.t_start.is_none_or(|a| t >= a) && self.t_end.is_none_or(|b| t <= b)
    }
}

/// `helicon ident tf`.
#[derive(Args, Debug)]
pub struct TfArgs {
    /// A frf.csv written by `helicon ident frf`.
    pub frf: PathBuf,
    /// The response to fit (its `output` column value).
    #[arg(long)]
    pub output: String,
    /// Numerator order.
    #[arg(long)]
    pub num: usize,
    /// Denominator order (monic).
    #[arg(long)]
    pub den: usize,
    /// Fit a time delay.
    #[arg(long)]
    pub delay: bool,
    /// Points with a coherence γ² at or below this are left out.
    #[arg(long, default_value_t = 0.6, allow_negative_numbers = true)]
    pub min_coherence: f64,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Time-domain verification on another log (a doublet, a 3211): the fit
    /// is simulated on `--verify-input` and compared with `--verify-output`
    /// (both taken as perturbations from their first sample), Theil coefficient.
    #[arg(long, requires_all = ["verify_input", "verify_output"])]
    pub verify: Option<PathBuf>,
    /// Input column of the verification log.
    #[arg(long)]
    pub verify_input: Option<String>,
    /// Output column of the verification log.
    #[arg(long)]
    pub verify_output: Option<String>,
    /// Time column of the verification log.
    #[arg(long, default_value = "t_s")]
    pub verify_time: String,
    /// Use the verification log from this time on, s.
    #[arg(long, allow_negative_numbers = true)]
    pub verify_t_start: Option<f64>,
    /// Use the verification log up to this time, s.
    #[arg(long, allow_negative_numbers = true)]
    pub verify_t_end: Option<f64>,
}

/// Run `helicon ident`.
pub fn run(args: &IdentArgs) -> Result<()> {
    match &args.command {
        IdentCommand::Frf(a) => run_frf(a),
        IdentCommand::Tf(a) => run_tf(a),
        IdentCommand::Input(a) => run_input(a),
        IdentCommand::Ss(a) => crate::ident_ss::run_ss(a),
        IdentCommand::Servo(a) => crate::ident_servo::run_servo(a),
        IdentCommand::ServoBench(a) => crate::ident_servo::run_bench(a),
        IdentCommand::Ground(a) => crate::ident_ground::run(a),
        IdentCommand::Fit(a) => crate::ident_fit::run_fit(a),
        IdentCommand::Demo(a) => crate::ident_fit::run_demo_cmd(a),
    }
}

/// Columns read from a CSV by name: their values, row by row.
pub(crate) struct Table {
    pub(crate) columns: Vec<Vec<f64>>,
}

/// Read the named columns of `path` (the time column first) and keep the
/// rows whose time is inside `span` (its options are `flags`, for the
/// messages); every value must be a finite number (errors name the file,
/// the column and the line). A flight log (ULog) is read onto its control
/// grid under log.csv's names ([`helicon_ulog::columns`]); its time column
/// is `t_s`. A log that says who drove the servos (a `servo_source` column)
/// is refused when the control law did not drive them throughout the span
/// ([`helicon_paramid::source::servo_spans`], naming the spans).
pub(crate) fn read_columns(
    path: &Path,
    names: &[&str],
    span: TimeSpan,
    flags: &str,
) -> Result<Table> {
    Ok(read_columns_with(path, names, &[], span, flags)?.0)
}

/// As [`read_columns`], and also the columns `optional` that the log has
/// (`None` for one it has not), cut to the same span.
pub(crate) fn read_columns_with(
    path: &Path,
    names: &[&str],
    optional: &[&str],
    span: TimeSpan,
    flags: &str,
) -> Result<(Table, Vec<Option<Vec<f64>>>)> {
    use helicon_paramid::source::{SERVO_SOURCE, describe_spans, servo_spans};
    let file = path.display().to_string();
    span.check(flags)?;
    let (mut table, extra) = if helicon_paramid::source::is_ulog(path) {
        read_ulog(path, names, optional)?
    } else {
        read_csv(path, names, optional)?
    };
    if span.t_start.is_some() || span.t_end.is_some() {
        let keep: Vec<bool> = table.columns[0].iter().map(|t| span.contains(*t)).collect();
        for c in &mut table.columns {
            let mut k = keep.iter();
            c.retain(|_| k.next().copied().unwrap_or(false));
        }
    }
    if table.columns[0].len() < 16 {
        bail!(
            "{file}: {} data rows{}; at least 16 are needed",
            table.columns[0].len(),
            if span.t_start.is_some() || span.t_end.is_some() {
                format!(" between {flags}")
            } else {
                String::new()
            }
        );
    }
    let column_of = |name: &str| {
        names.iter().position(|n| *n == name).or_else(|| {
            extra
                .iter()
                .position(|n| n == name)
                .map(|j| names.len() + j)
        })
    };
    if let Some(source) = column_of(SERVO_SOURCE).and_then(|j| table.columns.get(j)) {
        let spans = servo_spans(&table.columns[0], source);
        if !spans.is_empty() {
            bail!(
                "{file}: the control law did not drive the servos (servo_source ≠ 0) at {}: the logged law commands are not what the servos got and the law's excitation did not drive them; use {flags} to leave {} out",
                describe_spans(&spans),
                if spans.len() == 1 { "it" } else { "them" }
            );
        }
    }
    let found: Vec<Option<Vec<f64>>> = optional
        .iter()
        .map(|o| column_of(o).and_then(|j| table.columns.get(j).cloned()))
        .collect();
    table.columns.truncate(names.len());
    Ok((table, found))
}

/// [`read_columns`] of a CSV: the columns `names`, then those of
/// `optional` the header has and `servo_source` when the header has it and
/// `names` does not (their names returned, in order).
fn read_csv(path: &Path, names: &[&str], optional: &[&str]) -> Result<(Table, Vec<String>)> {
    use helicon_paramid::source::SERVO_SOURCE;
    let file = path.display().to_string();
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(crate::files::open_lines(path)?);
    let header = rdr
        .headers()
        .with_context(|| format!("{file}: no header row"))?
        .clone();
    let mut ask = names.to_vec();
    for o in optional.iter().chain([&SERVO_SOURCE]) {
        if header.iter().any(|h| h == *o) && !ask.contains(o) {
            ask.push(o);
        }
    }
    let extra: Vec<String> = ask[names.len()..].iter().map(|n| n.to_string()).collect();
    let names = ask.as_slice();
    let mut idx = Vec::with_capacity(names.len());
    for n in names {
        let found: Vec<usize> = header
            .iter()
            .enumerate()
            .filter(|(_, h)| h == n)
            .map(|(i, _)| i)
            .collect();
        match found.as_slice() {
            [i] => idx.push(*i),
            [] => bail!(
                "{file}: no column `{}` (columns: {}){}",
                esc(n),
                esc(&header.iter().collect::<Vec<_>>().join(", ")),
                helicon_config::nearest(n, header.iter())
                    .map(|c| format!("; did you mean `{}`?", esc(c)))
                    .unwrap_or_default()
            ),
            _ => bail!("{file}: column `{n}` appears {} times", found.len()),
        }
    }
    let mut columns = vec![Vec::new(); names.len()];
    for rec in rdr.records() {
        let rec = rec.with_context(|| format!("{file}: malformed CSV"))?;
        let line = rec.position().map_or(0, |p| p.line());
        for (c, &i) in idx.iter().enumerate() {
            let text = rec.get(i).unwrap_or("");
            let v: f64 = text.parse().map_err(|_| {
                anyhow!(
                    "{file}: line {line}, column `{}`: `{}` is not a number",
                    esc(names[c]),
                    esc(text)
                )
            })?;
            if !v.is_finite() {
                bail!(
                    "{file}: line {line}, column `{}`: {text} is not finite",
                    esc(names[c])
                );
            }
            columns[c].push(v);
        }
    }
    Ok((Table { columns }, extra))
}

/// [`read_columns`] of a flight log: the first name is the time column,
/// which must be `t_s` (the control grid), and `servo_source` last when the
/// log has servo records and `names` does not ask for it (one pass); what
/// the reading did (samples filled, a cut) is said on stderr.
fn read_ulog(path: &Path, names: &[&str], optional: &[&str]) -> Result<(Table, Vec<String>)> {
    use helicon_paramid::source::SERVO_SOURCE;
    let file = path.display().to_string();
    if names.first().is_some_and(|t| *t != "t_s") {
        bail!(
            "{file}: a flight log's time column is `t_s` (the control samples), not `{}`",
            names[0]
        );
    }
    let mut optional: Vec<&str> = optional
        .iter()
        .copied()
        .filter(|o| !names.contains(o))
        .collect();
    if !names.contains(&SERVO_SOURCE) && !optional.contains(&SERVO_SOURCE) {
        optional.push(SERVO_SOURCE);
    }
    let u = helicon_ulog::columns::read_ulog_columns_with(path, names, &optional, None)?;
    for n in u.notes() {
        eprintln!("{n}");
    }
    eprintln!(
        "{file}: flight log read on its control grid: {} samples every {} s (the median step; largest distance of a sample from the grid {:.1} µs)",
        u.columns[0].len(),
        format_seconds(u.period_s),
        u.max_jitter_s * 1e6
    );
    // the reader gives `t_s` first and each column once
    if u.names.len() < names.len() || u.names.iter().zip(names).any(|(a, b)| a != b) {
        bail!("{file}: a column is named twice (or `t_s` not first)");
    }
    let extra = u.names[names.len()..].to_vec();
    Ok((Table { columns: u.columns }, extra))
}

/// The sample time of the time column; an irregular column is resampled by
/// linear interpolation onto a uniform grid at its median step (said on
/// stderr), and refused when it goes backwards or has a gap over 5 steps.
pub(crate) fn uniform(file: &str, time: &str, t: &[f64], cols: &mut [Vec<f64>]) -> Result<f64> {
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    if let Some(i) = steps.iter().position(|d| d.is_nan() || *d <= 0.0) {
        bail!(
            "{file}: column `{time}` does not increase at data row {} ({} then {})",
            i + 2,
            format_seconds(t[i]),
            format_seconds(t[i + 1])
        );
    }
    steps.sort_by(f64::total_cmp);
    let dt = steps[steps.len() / 2];
    let (lo, hi) = (steps[0], steps[steps.len() - 1]);
    if hi > 5.0 * dt {
        bail!(
            "{file}: column `{time}` has a gap of {} s (the median step is {} s): a drop-out the spectra cannot bridge; cut the log",
            format_seconds(hi),
            format_seconds(dt)
        );
    }
    if hi - lo <= 1e-6 * dt {
        return Ok(dt);
    }
    let n = ((t[t.len() - 1] - t[0]) / dt).floor() as usize + 1;
    for c in cols.iter_mut() {
        let old = std::mem::take(c);
        let mut j = 0;
        for k in 0..n {
            let tk = t[0] + k as f64 * dt;
            while j + 2 < t.len() && t[j + 1] < tk {
                j += 1;
            }
            let f = ((tk - t[j]) / (t[j + 1] - t[j])).clamp(0.0, 1.0);
            c.push(old[j] + f * (old[j + 1] - old[j]));
        }
    }
    eprintln!(
        "{file}: `{time}` steps range {} … {} s: resampled by linear interpolation to {n} samples every {} s (the median step)",
        format_seconds(lo),
        format_seconds(hi),
        format_seconds(dt)
    );
    Ok(dt)
}

pub(crate) fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The window lengths of `ident frf`, samples: record/2, record/4, …
/// (`--windows` of them, at least 32 samples each), leaving out those over
/// `--max-window-s` and those whose effective number of averages n_d is
/// below the number of inputs `nin` (conditioning on q inputs needs
/// n_d ≥ q), each named on stderr. Refused when none is left.
fn window_lengths(a: &FrfArgs, file: &str, n: usize, dt: f64, nin: usize) -> Result<Vec<usize>> {
    if let Some(m) = a.max_window_s
        && !(m.is_finite() && m > 0.0)
    {
        bail!("--max-window-s {m}: must be finite and > 0");
    }
    let mut lens = Vec::new();
    let mut left_out = Vec::new();
    for l in (1..=a.windows).map(|k| n >> k).filter(|l| *l >= 32) {
        let secs = l as f64 * dt;
        if let Some(m) = a.max_window_s
            && secs > m
        {
            eprintln!("{file}: the {secs:.3} s window is longer than --max-window-s {m}: left out");
            left_out.push(format!("{secs:.3} s (over --max-window-s)"));
            continue;
        }
        let nd = WindowSpec::half_overlap(l)
            .effective_averages(n)
            .unwrap_or(0.0);
        if nd < nin as f64 {
            eprintln!(
                "{file}: the {secs:.3} s window holds {nd:.2} effective averages, fewer than the {nin} inputs need: left out"
            );
            left_out.push(format!("{secs:.3} s ({nd:.2} averages)"));
            continue;
        }
        lens.push(l);
    }
    if lens.is_empty() {
        if left_out.is_empty() {
            bail!("{file}: {n} samples: too short for a 32-sample window");
        }
        bail!(
            "{file}: no window qualifies: {} ({nin} input(s) need at least {nin} effective averages per window); raise --windows for shorter windows{}, or condition on fewer inputs",
            left_out.join(", "),
            if a.max_window_s.is_some() {
                ", raise --max-window-s"
            } else {
                ""
            }
        );
    }
    Ok(lens)
}

/// `helicon ident frf`.
#[allow(clippy::too_many_lines)] // the steps of one command in order: read, check the excitation, estimate, write
pub fn run_frf(a: &FrfArgs) -> Result<()> {
    let file = a.log.display().to_string();
    if a.windows == 0 || a.windows > 8 {
        bail!("--windows {}: must be 1 … 8", a.windows);
    }
    if a.points < 2 || a.points > 10_000 {
        bail!("--points {}: must be 2 … 10000", a.points);
    }
    let mut names: Vec<&str> = vec![a.time.as_str(), a.input.as_str()];
    names.extend(a.conditioned_on.iter().map(String::as_str));
    names.extend(a.output.iter().map(String::as_str));
    for (i, n) in names.iter().enumerate() {
        if names[..i].contains(n) {
            bail!(
                "column `{n}` is named twice among --time, --input, --conditioned-on and --output"
            );
        }
    }
    // an excitation named with --excitation must be there; the default one may not be
    let exc_name = a
        .excitation
        .as_deref()
        .or_else(|| default_excitation(&a.input));
    if let Some(e) = a.excitation.as_deref() {
        if names.contains(&e) {
            bail!(
                "--excitation {e}: also named among --time, --input, --conditioned-on and --output"
            );
        }
        names.push(e);
    }
    let optional: Vec<&str> = match (a.excitation.as_deref(), exc_name) {
        (None, Some(e)) if !names.contains(&e) => vec![e],
        _ => Vec::new(),
    };
    let (table, found) = read_columns_with(&a.log, &names, &optional, a.span, "--t-start/--t-end")?;
    let mut cols = table.columns;
    let mut exc: Option<Vec<f64>> = match found.into_iter().next() {
        Some(col) => col,
        None if a.excitation.is_some() => cols.pop(),
        None => None,
    };
    let t = cols.remove(0);
    if let Some(e) = exc.as_mut() {
        // resampled with the others (appended last, taken back after)
        cols.push(std::mem::take(e));
    }
    let dt = uniform(&file, &a.time, &t, &mut cols)?;
    if let Some(e) = exc.as_mut() {
        *e = cols.pop().unwrap_or_default();
    }
    let n = cols[0].len();
    let record_s = n as f64 * dt;
    let nin = 1 + a.conditioned_on.len();
    let lens = window_lengths(a, &file, n, dt, nin)?;
    let omega_min = a
        .omega_min
        .unwrap_or(4.0 * std::f64::consts::PI / (lens[0] as f64 * dt));
    let omega_max = a.omega_max.unwrap_or(0.4 * std::f64::consts::PI / dt);
    let nyquist = std::f64::consts::PI / dt;
    if omega_max > nyquist {
        bail!(
            "--omega-max {omega_max}: above the Nyquist frequency π/dt = {nyquist} rad/s of {file} (sample time {} s)",
            format_seconds(dt)
        );
    }
    let grid = log_grid(omega_min, omega_max, a.points)
        .with_context(|| format!("--omega-min {omega_min} and --omega-max {omega_max}"))?;
    let check =
        helicon_ident::excitation::check_excitation(&cols[0], exc.as_deref(), dt, lens[0], &grid)
            .with_context(|| format!("{file}: checking the excitation of `{}`", a.input))?;
    let chans: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    let inputs: Vec<usize> = (0..nin).collect();
    let mut per_output: Vec<Vec<Frf>> = vec![Vec::new(); a.output.len()];
    for &l in &lens {
        let cs = cross_spectra_grid(&chans, dt, WindowSpec::half_overlap(l), &grid)
            .with_context(|| format!("{file}: window of {l} samples"))?;
        for (o, parts) in per_output.iter_mut().enumerate() {
            let (mut f, _) = conditioned(&cs, &inputs, nin + o)
                .with_context(|| format!("{file}: `{}`", a.output[o]))?;
            parts.push(f.swap_remove(0));
        }
    }
    let secs: Vec<f64> = lens.iter().map(|l| *l as f64 * dt).collect();
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("{}: cannot create", a.out.display()))?;
    let csv_path = a.out.join("frf.csv");
    let mut w = std::io::BufWriter::new(
        std::fs::File::create(&csv_path)
            .with_context(|| format!("{}: cannot create", csv_path.display()))?,
    );
    writeln!(
        w,
        "output,omega_rad_s,mag_db,phase_deg,coherence,random_error"
    )?;
    println!(
        "{file}: {n} samples every {} s ({record_s:.3} s), windows {} s, input `{}`{}",
        format_seconds(dt),
        secs.iter()
            .map(|s| format!("{s:.3}"))
            .collect::<Vec<_>>()
            .join("/"),
        a.input,
        if a.conditioned_on.is_empty() {
            String::new()
        } else {
            format!(" conditioned on {}", a.conditioned_on.join(","))
        }
    );
    for (o, parts) in per_output.iter().enumerate() {
        let name = &a.output[o];
        let f = composite(parts, &secs).with_context(|| format!("{file}: `{name}`"))?;
        let (mag, ph) = (f.mag_db(), f.phase_deg());
        for k in 0..f.len() {
            let row = [
                f.omega_rad_s[k],
                mag[k],
                ph[k],
                f.coherence[k],
                f.random_error[k],
            ];
            if row.iter().any(|v| !v.is_finite()) {
                bail!(
                    "`{name}` at {} rad/s: a non-finite value (zero response?)",
                    f.omega_rad_s[k]
                );
            }
            writeln!(
                w,
                "{name},{},{},{},{},{}",
                row[0], row[1], row[2], row[3], row[4]
            )?;
        }
        let good = f.coherence.iter().filter(|c| **c > 0.6).count();
        let png = a.out.join(format!("bode_{}.png", file_stem(name)));
        write_bode(&png, &format!("{name} / {}", a.input), &f, None, None)?;
        println!(
            "  {name}: {} points, {good} with γ² > 0.6; {}",
            f.len(),
            png.display()
        );
    }
    w.flush()?;
    println!("  {}", csv_path.display());
    report_excitation(&a.input, exc_name.filter(|_| exc.is_some()), &check);
    Ok(())
}

/// Say what the excitation check found: one line on stdout, and a warning
/// on stderr for each problem (the response is written all the same).
fn report_excitation(
    input: &str,
    exc_name: Option<&str>,
    check: &helicon_ident::excitation::ExcitationCheck,
) {
    let share = check
        .coherent_share
        .map(|s| format!(", {:.0} % of its band power coherent with it", 100.0 * s))
        .unwrap_or_default();
    match (exc_name, check.excitation_rms) {
        (Some(e), Some(rms)) => println!(
            "  excitation: `{e}` RMS {rms:.3e}{share}; `{input}` RMS {:.3e}, {:.0} % of the band's points more than 40 dB below its peak",
            check.input_rms,
            100.0 * check.weak_share
        ),
        _ => println!(
            "  excitation: no excitation column for `{input}` (--excitation names one): the input's feedback share is not checked; `{input}` RMS {:.3e}, {:.0} % of the band's points more than 40 dB below its peak",
            check.input_rms,
            100.0 * check.weak_share
        ),
    }
    for p in &check.problems {
        eprintln!("warning: `{input}`: {p}");
    }
}

/// The coherence above which a Bode plot draws the estimate's confidence
/// band (γ² ≥ 0.6, the usual threshold for a usable frequency response).
const COHERENT_GAMMA2: f64 = 0.6;

/// Write magnitude, phase and coherence against ω on a logarithmic axis,
/// with the estimate's 95 % band (±2ε over the coherent points) and an
/// optional fit (magnitude and phase curves, x = log10 ω) overlaid, to
/// `path`. A fit made over a narrower band than the estimate's, `fit_band`
/// `(ω_min, ω_max)` in rad/s, is drawn in the theme's colour inside the band
/// and pale outside it, so a model is judged where it was fitted.
pub(crate) fn write_bode(
    path: &Path,
    title: &str,
    f: &Frf,
    fit: Option<&[Vec<(f64, f64)>; 2]>,
    fit_band: Option<(f64, f64)>,
) -> Result<()> {
    let lw = |v: &[f64]| -> Vec<(f64, f64)> {
        f.omega_rad_s
            .iter()
            .zip(v)
            .map(|(w, y)| (w.log10(), *y))
            .collect()
    };
    let (mag_db, phase_deg) = (f.mag_db(), f.phase_deg());
    let (mag, ph, coh) = (lw(&mag_db), lw(&phase_deg), lw(&f.coherence));
    // the estimate's 95 % band, ±2ε (ε its normalised random error, of |H|
    // and of ∠H in rad), drawn over the coherent points only: where γ² is
    // low ε grows without bound and says nothing
    let band = |k: usize, sign: f64| -> (f64, f64) {
        let e = f.random_error.get(k).copied().unwrap_or(f64::NAN);
        if f.coherence.get(k).is_none_or(|c| *c < COHERENT_GAMMA2) || !e.is_finite() {
            return (f64::NAN, f64::NAN);
        }
        let ratio = (1.0 + sign * 2.0 * e).max(1e-3);
        (
            mag_db[k] + 20.0 * ratio.log10(),
            phase_deg[k] + sign * (2.0 * e).to_degrees(),
        )
    };
    let at = |sign: f64, which: usize| -> Vec<(f64, f64)> {
        (0..f.omega_rad_s.len())
            .map(|k| {
                let b = band(k, sign);
                (f.omega_rad_s[k].log10(), if which == 0 { b.0 } else { b.1 })
            })
            .collect()
    };
    let (mag_hi, mag_lo, ph_hi, ph_lo) = (at(1.0, 0), at(-1.0, 0), at(1.0, 1), at(-1.0, 1));
    const GREY: [u8; 3] = [150, 150, 150];
    let mut pm = Panel::new("magnitude [dB]").series(Series::new("estimate", &mag));
    let mut pp = Panel::new("phase [deg]").series(Series::new("estimate", &ph));
    // the fit inside its band, and outside it (NaN where the other is)
    let (lo, hi) = fit_band.map_or((f64::NEG_INFINITY, f64::INFINITY), |(a, b)| {
        (a.log10() - 1e-9, b.log10() + 1e-9)
    });
    let part = |c: &[(f64, f64)], inside: bool| -> Vec<(f64, f64)> {
        c.iter()
            .map(|&(x, y)| {
                if ((lo..=hi).contains(&x)) == inside {
                    (x, y)
                } else {
                    (x, f64::NAN)
                }
            })
            .collect()
    };
    let fits = fit.map(|c| {
        [
            part(&c[0], true),
            part(&c[1], true),
            part(&c[0], false),
            part(&c[1], false),
        ]
    });
    let band_label = fit_band.map(|(a, b)| match (a > 0.0, b.is_finite()) {
        (true, true) => format!("fit ({}–{} rad/s)", fmt_omega(a), fmt_omega(b)),
        (true, false) => format!("fit (ω ≥ {} rad/s)", fmt_omega(a)),
        (false, true) => format!("fit (ω ≤ {} rad/s)", fmt_omega(b)),
        (false, false) => "fit".to_string(),
    });
    if let Some([m_in, p_in, m_out, p_out]) = &fits {
        let label = band_label.as_deref().unwrap_or("fit");
        pm = pm.series(Series::new(label, m_in).dashed().with_gaps());
        pp = pp.series(Series::new(label, p_in).dashed().with_gaps());
        if m_out.iter().any(|p| p.1.is_finite()) {
            const PALE: [u8; 3] = [253, 198, 150];
            pm = pm.series(
                Series::new("fit, outside", m_out)
                    .dashed()
                    .color(PALE)
                    .with_gaps(),
            );
            pp = pp.series(
                Series::new("fit, outside", p_out)
                    .dashed()
                    .color(PALE)
                    .with_gaps(),
            );
        }
    }
    for (name, m, p) in [
        ("+2ε (γ² ≥ 0.6)", &mag_hi, &ph_hi),
        ("−2ε", &mag_lo, &ph_lo),
    ] {
        pm = pm.series(Series::new(name, m).color(GREY).with_gaps());
        pp = pp.series(Series::new(name, p).color(GREY).with_gaps());
    }
    let mut pc = Panel::new("coherence γ² [-]").series(Series::new("γ²", &coh));
    pc.hlines.push(HLine {
        y: COHERENT_GAMMA2,
        label: "0.6".into(),
        color: [127, 127, 127],
    });
    pc.y_include = vec![0.0, 1.0];
    Figure::new(title, "ω [rad/s]")
        .log_x()
        .panel(pm)
        .panel(pp)
        .panel(pc)
        .write(path)
        .with_context(|| path.display().to_string())
}

/// A frequency as a legend prints it: up to 3 significant digits, no
/// trailing zeros (`1.5`, `12`, `0.25`).
fn fmt_omega(w: f64) -> String {
    let t = format!("{w:.3}");
    let t = t.trim_end_matches('0').trim_end_matches('.');
    t.to_string()
}

/// Read the rows of `output` from a frf.csv.
pub(crate) fn read_frf(path: &Path, output: &str) -> Result<Frf> {
    let file = path.display().to_string();
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(crate::files::open_lines(path)?);
    let header: Vec<String> = rdr
        .headers()
        .with_context(|| format!("{file}: no header row"))?
        .iter()
        .map(str::to_string)
        .collect();
    let want = [
        "output",
        "omega_rad_s",
        "mag_db",
        "phase_deg",
        "coherence",
        "random_error",
    ];
    if header != want {
        bail!(
            "{file}: header `{}` is not a frf.csv header `{}`",
            esc(&header.join(",")),
            want.join(",")
        );
    }
    let mut f = Frf::default();
    let mut seen = Vec::<String>::new();
    for rec in rdr.records() {
        let rec = rec.with_context(|| format!("{file}: malformed CSV"))?;
        let line = rec.position().map_or(0, |p| p.line());
        let name = rec.get(0).unwrap_or("");
        if !seen.iter().any(|s| s == name) {
            seen.push(name.to_string());
        }
        if name != output {
            continue;
        }
        let mut v = [0.0; 5];
        for (c, slot) in v.iter_mut().enumerate() {
            let text = rec.get(c + 1).unwrap_or("");
            *slot = text
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    anyhow!(
                        "{file}: line {line}, column `{}`: `{}` is not a finite number",
                        want[c + 1],
                        esc(text)
                    )
                })?;
        }
        if v[0] <= 0.0 || f.omega_rad_s.last().is_some_and(|w| *w >= v[0]) {
            bail!(
                "{file}: line {line}, column `omega_rad_s`: {} must be > 0 and increasing",
                v[0]
            );
        }
        if !(0.0..=1.0).contains(&v[3]) || v[4] < 0.0 {
            bail!(
                "{file}: line {line}: coherence {} must be in [0, 1] and random_error {} ≥ 0",
                v[3],
                v[4]
            );
        }
        f.omega_rad_s.push(v[0]);
        f.h.push(Complex64::from_polar(
            10f64.powf(v[1] / 20.0),
            v[2].to_radians(),
        ));
        f.coherence.push(v[3]);
        f.random_error.push(v[4]);
    }
    if f.is_empty() {
        bail!(
            "{file}: no rows for output `{output}` (outputs: {})",
            esc(&seen.join(", "))
        );
    }
    Ok(f)
}

/// `helicon ident tf`.
pub fn run_tf(a: &TfArgs) -> Result<()> {
    if !(0.0..1.0).contains(&a.min_coherence) {
        bail!("--min-coherence {}: must be in [0, 1)", a.min_coherence);
    }
    let f = read_frf(&a.frf, &a.output)?;
    let st = TfStructure {
        num_order: a.num,
        den_order: a.den,
        delay: a.delay,
    };
    let opts = CostOptions {
        min_coherence: a.min_coherence,
        ..CostOptions::default()
    };
    let fit = fit_tf(&f, st, &opts, None)
        .with_context(|| format!("{}: `{}`", a.frf.display(), a.output))?;
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("{}: cannot create", a.out.display()))?;
    let stem = file_stem(&a.output);
    let json_path = a.out.join(format!("tf_{stem}.json"));
    let params: Vec<serde_json::Value> = (0..fit.params.len())
        .map(|i| {
            // a bound the data do not give is JSON null, never a number
            let fin = |v: f64| {
                if v.is_finite() {
                    serde_json::json!(v)
                } else {
                    serde_json::Value::Null
                }
            };
            serde_json::json!({
                "name": fit.names[i],
                "value": fit.params[i],
                "cramer_rao": fin(fit.cramer_rao[i]),
                "cramer_rao_pct": fin(fit.cramer_rao_pct[i]),
                "insensitivity_pct": fin(fit.insensitivity_pct[i]),
                "identifiable": fit.identifiable(i),
            })
        })
        .collect();
    let doc = serde_json::json!({
        "output": a.output,
        "num": fit.num,
        "den": fit.den,
        "delay_s": fit.delay_s,
        "cost": fit.cost,
        "n_points": fit.n_points,
        "min_coherence": a.min_coherence,
        "parameters": params,
        "verification": verify(a, &fit, &stem)?,
    });
    std::fs::write(&json_path, serde_json::to_string_pretty(&doc)? + "\n")
        .with_context(|| format!("{}: cannot write", json_path.display()))?;
    let overlay = fit_curves(&f, |w| fit.eval(w));
    let png = a.out.join(format!("tf_{stem}.png"));
    let title = format!(
        "{}: fit num {} den {}{}",
        a.output,
        a.num,
        a.den,
        if a.delay { " + delay" } else { "" }
    );
    write_bode(&png, &title, &f, Some(&overlay), None)?;
    println!(
        "{}: J = {:.3} over {} points",
        a.output, fit.cost, fit.n_points
    );
    let mut unknown = Vec::new();
    for i in 0..fit.params.len() {
        println!(
            "  {:>6} = {:<14.6e} CR {}  I {}{}",
            fit.names[i],
            fit.params[i],
            percent_cell(fit.cramer_rao_pct[i]),
            percent_cell(fit.insensitivity_pct[i]),
            if fit.identifiable(i) {
                ""
            } else {
                unknown.push(fit.names[i].as_str());
                "  NOT IDENTIFIABLE"
            }
        );
    }
    if !unknown.is_empty() {
        eprintln!(
            "warning: {} not identifiable from these data (Cramér–Rao bound infinite or ≥ {} % of the value): fit a lower order, or fix {}",
            unknown.join(", "),
            helicon_ident::cost::NOT_IDENTIFIABLE_PCT,
            if unknown.len() == 1 { "it" } else { "them" }
        );
    }
    println!("  {}\n  {}", json_path.display(), png.display());
    Ok(())
}

/// A bound in % for a parameter table, 9 characters: `—` with the reason
/// when the data give none (infinite), `>1e6 %` past a million.
pub(crate) fn percent_cell(pct: f64) -> String {
    if !pct.is_finite() {
        "     none".to_string()
    } else if pct >= 1e6 {
        format!("{:>7.0e} %", pct)
    } else {
        format!("{pct:>7.2} %")
    }
}

/// The phase (deg) of a model's response `h` on the grid of the estimate
/// `f`, unwrapped and shifted by the whole turns that bring it nearest the
/// estimate on average over the coherent points (γ² > 0.6; all points when
/// none is): the one way every Bode overlay puts a model's phase against
/// the data's.
pub(crate) fn phase_near_estimate(f: &Frf, h: &[Complex64]) -> Vec<f64> {
    let mut ph = unwrap_deg(&h.iter().map(|v| v.arg().to_degrees()).collect::<Vec<_>>());
    let est = f.phase_deg();
    let n = est.len().min(ph.len());
    let good: Vec<usize> = (0..n).filter(|&k| f.coherence[k] > 0.6).collect();
    let idx: Vec<usize> = if good.is_empty() {
        (0..n).collect()
    } else {
        good
    };
    if !idx.is_empty() {
        let mean = idx.iter().map(|&k| est[k] - ph[k]).sum::<f64>() / idx.len() as f64;
        let turns = (mean / 360.0).round() * 360.0;
        ph.iter_mut().for_each(|p| *p += turns);
    }
    ph
}

/// A fitted model's magnitude and phase (`eval` gives T(jω)) on the
/// response's grid, the phase placed against the estimate
/// ([`phase_near_estimate`]).
pub(crate) fn fit_curves(f: &Frf, eval: impl Fn(f64) -> Complex64) -> [Vec<(f64, f64)>; 2] {
    let h: Vec<Complex64> = f.omega_rad_s.iter().map(|w| eval(*w)).collect();
    let ph = phase_near_estimate(f, &h);
    let x: Vec<f64> = f.omega_rad_s.iter().map(|w| w.log10()).collect();
    [
        x.iter()
            .zip(&h)
            .map(|(x, v)| (*x, 20.0 * v.norm().log10()))
            .collect(),
        x.iter().zip(ph).map(|(x, p)| (*x, p)).collect(),
    ]
}

/// The time-domain verification of `--verify`: the Theil coefficient and a
/// plot `DIR/verify_<output>.png`; JSON `null` without `--verify`.
fn verify(a: &TfArgs, fit: &TfFit, stem: &str) -> Result<serde_json::Value> {
    let (Some(log), Some(inp), Some(out)) = (&a.verify, &a.verify_input, &a.verify_output) else {
        return Ok(serde_json::Value::Null);
    };
    let file = log.display().to_string();
    let span = TimeSpan {
        t_start: a.verify_t_start,
        t_end: a.verify_t_end,
    };
    let table = read_columns(
        log,
        &[a.verify_time.as_str(), inp.as_str(), out.as_str()],
        span,
        "--verify-t-start/--verify-t-end",
    )?;
    let mut cols = table.columns;
    let t = cols.remove(0);
    let dt = uniform(&file, &a.verify_time, &t, &mut cols)?;
    let perturb = |v: &[f64]| -> Vec<f64> { v.iter().map(|x| x - v[0]).collect() };
    let (u, y) = (perturb(&cols[0]), perturb(&cols[1]));
    let sim = helicon_ident::fit::simulate(fit, &u, dt)
        .with_context(|| format!("{file}: simulating the fit"))?;
    let tic = helicon_ident::fit::theil(&y, &sim).with_context(|| format!("{file}: `{out}`"))?;
    let tt: Vec<(f64, f64)> = (0..y.len()).map(|k| (k as f64 * dt, y[k])).collect();
    let ts: Vec<(f64, f64)> = (0..sim.len()).map(|k| (k as f64 * dt, sim[k])).collect();
    let png = a.out.join(format!("verify_{stem}.png"));
    Figure::new(
        &format!("{out}: fit on {file}, Theil {tic:.4}"),
        "time from the first sample [s]",
    )
    .panel(
        Panel::new(&format!("{out} − initial"))
            .series(Series::new("measured", &tt))
            .series(Series::new("fit", &ts).dashed()),
    )
    .write(&png)
    .with_context(|| png.display().to_string())?;
    println!(
        "  verification on {file}: Theil inequality coefficient {tic:.4}; {}",
        png.display()
    );
    Ok(serde_json::json!({ "log": file, "input": inp, "output": out, "theil": tic }))
}
