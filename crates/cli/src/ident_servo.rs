//! `helicon ident servo` and `helicon ident servo-bench`: identify a servo
//! (thesis (5.1)–(5.4)) from a log of its command and measured position, and
//! write a simulated bench test of the model's own servo block (see
//! docs/ground-and-servo.md).

use crate::ident_cmd::{TimeSpan, read_columns, uniform};
use anyhow::{Context, Result, bail};
use clap::Args;
use helicon_ident::Complex64;
use helicon_ident::frf::{WindowSpec, cross_spectra_grid, log_grid, siso};
use helicon_ident::servo::{BenchInput, RateLimit, ServoFit, ServoFitOptions, fit_servo};
use helicon_model::Params;
use helicon_sim::plot::{Figure, Panel, Series};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::io::Write;
use std::path::PathBuf;

/// The servo channels of the parameter file, in input order.
const CHANNELS: [&str; 4] = ["collective", "lateral", "longitudinal", "tail"];

fn channel_index(name: &str) -> Result<usize> {
    CHANNELS
        .iter()
        .position(|c| *c == name)
        .with_context(|| format!("--channel {name}: must be one of {}", CHANNELS.join(", ")))
}

/// `helicon ident servo`.
#[derive(Args, Debug)]
pub struct ServoArgs {
    /// The log (CSV with a header row; `#` lines are comments): the servo's
    /// command and its measured position (rad), from rest at the first command.
    pub log: PathBuf,
    /// Command column (the servo input S, dimensionless).
    #[arg(long)]
    pub command: String,
    /// Measured position column, rad.
    #[arg(long)]
    pub position: String,
    /// Time column, s.
    #[arg(long, default_value = "t_s")]
    pub time: String,
    /// The channel the servo drives (collective, lateral, longitudinal,
    /// tail): names the parameter keys in servo.json.
    #[arg(long, default_value = "collective")]
    pub channel: String,
    /// Known command saturation, lower end (default: none).
    #[arg(long, allow_negative_numbers = true)]
    pub s_min: Option<f64>,
    /// Known command saturation, upper end (default: none).
    #[arg(long, allow_negative_numbers = true)]
    pub s_max: Option<f64>,
    /// RK4 steps per log sample (1 matches the model at the log's sample time).
    #[arg(long, default_value_t = 1)]
    pub substeps: usize,
    /// The part of the log used (the servo from rest at its first command).
    #[command(flatten)]
    pub span: TimeSpan,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// `helicon ident servo-bench`.
#[derive(Args, Debug)]
pub struct ServoBenchArgs {
    /// Parameter file (TOML) overriding any subset of the embedded Bergen Twin.
    #[arg(long)]
    pub params: Option<PathBuf>,
    /// The servo channel to drive (collective, lateral, longitudinal, tail).
    #[arg(long, default_value = "collective")]
    pub channel: String,
    /// Sample time, s (the model's step 1/400 s by default).
    #[arg(long, default_value_t = helicon_model::integrate::DEFAULT_STEP_S, allow_negative_numbers = true)]
    pub dt: f64,
    /// Position measurement noise, rad RMS (white, Gaussian).
    #[arg(long, default_value_t = 0.002, allow_negative_numbers = true)]
    pub noise_rad: f64,
    /// Noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Time each step level is held, s (longer for slow or strongly rate-limited servos).
    #[arg(long, default_value_t = 0.3, allow_negative_numbers = true)]
    pub hold_s: f64,
    /// Leave out the sweep (steps only).
    #[arg(long)]
    pub no_sweep: bool,
    /// Output CSV file: `t_s,command,position_rad,position_true_rad`.
    #[arg(long)]
    pub out: PathBuf,
}

/// `helicon ident servo-bench`.
pub fn run_bench(a: &ServoBenchArgs) -> Result<()> {
    let params = match &a.params {
        Some(p) => Params::from_file(p)?,
        None => Params::bergen_twin(),
    };
    let ch = channel_index(&a.channel)?;
    let servo = params.servos[ch];
    if !(a.noise_rad.is_finite() && (0.0..=1.0).contains(&a.noise_rad)) {
        bail!(
            "--noise-rad {}: must be finite and in [0, 1] rad",
            a.noise_rad
        );
    }
    if !(a.dt.is_finite() && a.dt > 0.0 && a.dt <= 0.1) {
        bail!("--dt {}: must be finite and in (0, 0.1] s", a.dt);
    }
    let mut input = BenchInput::new(servo.s_min, servo.s_max)
        .with_context(|| format!("servo.{} command range", a.channel))?;
    input.hold_s = a.hold_s;
    if a.no_sweep {
        input.sweep = None;
    }
    let cmd = input.sample(a.dt).context("--hold-s")?;
    let x0 = [servo.gain_rad * cmd[0], 0.0];
    let truth = helicon_model::actuators::servo_response(&servo, &cmd, a.dt, x0);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(a.seed);
    let normal = Normal::new(0.0, 1.0)?;
    let mut w = std::io::BufWriter::new(
        std::fs::File::create(&a.out)
            .with_context(|| format!("{}: cannot create", a.out.display()))?,
    );
    writeln!(
        w,
        "# helicon servo bench: servo.{} K = {} rad, wn = {} rad/s, zeta = {}, rate limit {} rad/s, S in [{}, {}]; position noise {} rad RMS, seed {}",
        a.channel,
        servo.gain_rad,
        servo.omega_n_rad_s,
        servo.zeta,
        servo.rate_max_rad_s,
        servo.s_min,
        servo.s_max,
        a.noise_rad,
        a.seed
    )?;
    writeln!(w, "t_s,command,position_rad,position_true_rad")?;
    for (k, (s, x)) in cmd.iter().zip(&truth).enumerate() {
        let y = x[0] + a.noise_rad * normal.sample(&mut rng);
        writeln!(w, "{},{s},{y},{}", k as f64 * a.dt, x[0])?;
    }
    w.flush()?;
    let mut con = crate::console::Console::stdout();
    writeln!(
        con,
        "servo.{}: {} samples over {:.2} s (steps of {:?} of the half range, full-range steps{}) -> {}",
        a.channel,
        cmd.len(),
        cmd.len() as f64 * a.dt,
        input.step_fractions,
        if input.sweep.is_some() {
            ", a 5-300 rad/s sweep"
        } else {
            ""
        },
        a.out.display()
    );
    con.finish().context("writing to stdout")
}

/// `helicon ident servo`.
pub fn run_servo(a: &ServoArgs) -> Result<()> {
    let file = a.log.display().to_string();
    let ch = channel_index(&a.channel)?;
    let names = [a.time.as_str(), a.command.as_str(), a.position.as_str()];
    for (i, n) in names.iter().enumerate() {
        if names[..i].contains(n) {
            bail!("column `{n}` is named twice among --time, --command and --position");
        }
    }
    let table = read_columns(&a.log, &names, a.span, "--t-start/--t-end")?;
    let mut cols = table.columns;
    let t = cols.remove(0);
    let dt = uniform(&file, &a.time, &t, &mut cols)?;
    let opts = ServoFitOptions {
        substeps: a.substeps,
        s_min: a.s_min.unwrap_or(f64::NEG_INFINITY),
        s_max: a.s_max.unwrap_or(f64::INFINITY),
        ..ServoFitOptions::default()
    };
    let (cmd, pos) = (&cols[0], &cols[1]);
    let fit = fit_servo(cmd, pos, dt, &opts).with_context(|| format!("{file}: servo fit"))?;
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("{}: cannot create", a.out.display()))?;
    let check = frequency_check(cmd, pos, dt, &fit);
    let json_path = a.out.join("servo.json");
    let doc = servo_json(a, &file, ch, &fit, &opts, check)?;
    std::fs::write(&json_path, serde_json::to_string_pretty(&doc)? + "\n")
        .with_context(|| format!("{}: cannot write", json_path.display()))?;
    let png = a.out.join("servo.png");
    overlay(&png, &file, cmd, pos, dt, &fit, a.substeps)?;
    let pm = |e: helicon_ident::servo::Estimate| helicon_sim::plot::value_pm(e.value, e.std_error);
    let mut con = crate::console::Console::stdout();
    writeln!(
        con,
        "{file}: {} samples every {} s; residual RMS {:.3e} rad",
        fit.n_samples,
        helicon_model::config_error::format_seconds(dt),
        fit.residual_rms_rad
    );
    writeln!(con, "  K  = {} rad", pm(fit.gain_rad));
    writeln!(con, "  ωn = {} rad/s", pm(fit.omega_n_rad_s));
    writeln!(con, "  ζ  = {}", pm(fit.zeta));
    match &fit.rate_limit {
        RateLimit::Identified {
            rate_max_rad_s,
            samples_on_limit,
        } => writeln!(
            con,
            "  rate limit = {} rad/s ({samples_on_limit} samples on the limit, likelihood ratio {:.1})",
            pm(*rate_max_rad_s),
            fit.lr_statistic
        ),
        RateLimit::NotReached {
            lower_bound_rad_s, ..
        } => writeln!(
            con,
            "  rate limit: not reached in this log (at least {lower_bound_rad_s:.3} rad/s); not identified"
        ),
    }
    writeln!(con, "  {}\n  {}", json_path.display(), png.display());
    con.finish().context("writing to stdout")
}

/// servo.json: the estimates with their standard errors, the parameter keys
/// they set (and a TOML snippet setting them), the fit's figures and the
/// frequency-domain cross-check.
fn servo_json(
    a: &ServoArgs,
    file: &str,
    ch: usize,
    fit: &ServoFit,
    opts: &ServoFitOptions,
    check: serde_json::Value,
) -> Result<serde_json::Value> {
    let section = format!("servo.{}", CHANNELS[ch]);
    let key = |k: &str| format!("{section}.{k}");
    let rate = serde_json::to_value(&fit.rate_limit)?;
    let finite_or_null = |v: f64| {
        if v.is_finite() {
            serde_json::json!(v)
        } else {
            serde_json::Value::Null
        }
    };
    let mut toml = format!(
        "[{section}]\ngain_rad = {}\nomega_n_rad_s = {}\nzeta = {}\n",
        fit.gain_rad.value, fit.omega_n_rad_s.value, fit.zeta.value
    );
    if let RateLimit::Identified { rate_max_rad_s, .. } = &fit.rate_limit {
        toml.push_str(&format!("rate_max_rad_s = {}\n", rate_max_rad_s.value));
    }
    Ok(serde_json::json!({
        "log": file,
        "command": a.command,
        "position": a.position,
        "time": a.time,
        "dt_s": fit.dt_s,
        "n_samples": fit.n_samples,
        "substeps": opts.substeps,
        "s_min": finite_or_null(opts.s_min),
        "s_max": finite_or_null(opts.s_max),
        "gain_rad": fit.gain_rad,
        "omega_n_rad_s": fit.omega_n_rad_s,
        "zeta": fit.zeta,
        "position_offset_rad": fit.position_offset_rad,
        "rate_limit": rate,
        "residual_rms_rad": fit.residual_rms_rad,
        "residual_rms_linear_rad": fit.residual_rms_linear_rad,
        "lr_statistic": fit.lr_statistic,
        "correlation_order": if matches!(fit.rate_limit, RateLimit::Identified { .. }) {
            vec!["gain_rad", "omega_n_rad_s", "zeta", "position_offset_rad", "rate_max_rad_s"]
        } else {
            vec!["gain_rad", "omega_n_rad_s", "zeta", "position_offset_rad"]
        },
        "correlation": fit.correlation,
        "evaluations": fit.evaluations,
        "params_keys": {
            "gain_rad": key("gain_rad"),
            "omega_n_rad_s": key("omega_n_rad_s"),
            "zeta": key("zeta"),
            "rate_max_rad_s": key("rate_max_rad_s"),
        },
        "frequency_check": check,
        "params_toml": toml,
    }))
}

/// The frequency-domain cross-check: the measured frequency response
/// (command → position, Hann windows of a quarter of the record, half
/// overlap) against the fitted second order with the zero-order hold's half
/// sample of delay, K ωn²/(s² + 2ζωn s + ωn²) e^{−s dt/2}, over the points
/// with γ² > 0.9 below 2 ωn: the median and largest magnitude (dB) and
/// phase (deg) differences. `null` when the log cannot give a response (too short, no
/// coherent point). Rate-limited parts of the log lower the coherence and
/// bias the response: the time-domain fit is the estimate, this is a check.
fn frequency_check(cmd: &[f64], pos: &[f64], dt: f64, fit: &ServoFit) -> serde_json::Value {
    let n = cmd.len();
    let len = n / 4;
    let wn = fit.omega_n_rad_s.value;
    let w_lo = 4.0 * std::f64::consts::PI / (len as f64 * dt);
    let w_hi = (2.0 * wn).min(0.4 * std::f64::consts::PI / dt);
    let Ok(grid) = log_grid(w_lo, w_hi, 60) else {
        return serde_json::Value::Null;
    };
    let Ok(cs) = cross_spectra_grid(&[cmd, pos], dt, WindowSpec::half_overlap(len), &grid) else {
        return serde_json::Value::Null;
    };
    let Ok(f) = siso(&cs, 0, 1) else {
        return serde_json::Value::Null;
    };
    let (k, z) = (fit.gain_rad.value, fit.zeta.value);
    let (mut dmag, mut dph) = (Vec::new(), Vec::new());
    for i in 0..f.len() {
        if f.coherence[i] <= 0.9 {
            continue;
        }
        let s = Complex64::new(0.0, f.omega_rad_s[i]);
        let model = k * wn * wn / (s * s + 2.0 * z * wn * s + wn * wn) * (-s * (0.5 * dt)).exp();
        let ratio = f.h[i] / model;
        if !(ratio.norm().is_finite() && ratio.norm() > 0.0) {
            continue;
        }
        dmag.push((20.0 * ratio.norm().log10()).abs());
        dph.push(ratio.arg().to_degrees().abs());
    }
    if dmag.is_empty() {
        return serde_json::Value::Null;
    }
    let median_max = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (v[v.len() / 2], v[v.len() - 1])
    };
    let (mag_med, mag_max) = median_max(&mut dmag);
    let (ph_med, ph_max) = median_max(&mut dph);
    serde_json::json!({
        "omega_min_rad_s": w_lo,
        "omega_max_rad_s": w_hi,
        "points": dmag.len(),
        "median_mag_error_db": mag_med,
        "max_mag_error_db": mag_max,
        "median_phase_error_deg": ph_med,
        "max_phase_error_deg": ph_max,
    })
}

/// The overlay plot: measured and fitted position, the residual, the command.
fn overlay(
    png: &std::path::Path,
    file: &str,
    cmd: &[f64],
    pos: &[f64],
    dt: f64,
    fit: &ServoFit,
    substeps: usize,
) -> Result<()> {
    let model = fit.predict(cmd, substeps);
    let ts = |v: &[f64]| -> Vec<(f64, f64)> {
        v.iter()
            .enumerate()
            .map(|(k, y)| (k as f64 * dt, *y))
            .collect()
    };
    let res: Vec<f64> = model.iter().zip(pos).map(|(a, b)| b - a).collect();
    let (m, f, r, c) = (ts(pos), ts(&model), ts(&res), ts(cmd));
    let rate = match &fit.rate_limit {
        RateLimit::Identified { rate_max_rad_s, .. } => {
            format!("rate limit {:.3} rad/s", rate_max_rad_s.value)
        }
        RateLimit::NotReached { .. } => "rate limit not reached".into(),
    };
    Figure::new(
        &format!(
            "{file}: K {:.4}, ωn {:.2} rad/s, ζ {:.4}, {rate}",
            fit.gain_rad.value, fit.omega_n_rad_s.value, fit.zeta.value
        ),
        "time [s]",
    )
    .panel(
        Panel::new("position [rad]")
            .series(Series::new("measured", &m))
            .series(Series::new("fit", &f).dashed()),
    )
    .panel(Panel::new("measured − fit [rad]").series(Series::new("residual", &r)))
    .panel(Panel::new("command [-]").series(Series::new("command", &c)))
    .write(png)
    .with_context(|| png.display().to_string())
}
