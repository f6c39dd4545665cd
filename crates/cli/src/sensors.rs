//! `helicon attitude`, `helicon sensors simulate` and `helicon fuse`
//! (`helicon sensors shaker` is in `shaker_cmd`):
//! thesis chapter 13 on the command line.
//!
//! The sensor log format (written by `sensors simulate` and by `helicon sim`
//! with `[log] sensors = true`, read by `fuse`) is specified once, in
//! `helicon_sim::sensor_log`; `fuse` replays it through the navigation that
//! flies (`helicon_core::NavigationFilter`, via
//! `helicon_sim::navigation::replay_navigation`).

use anyhow::{Context, Result, anyhow, bail};
use clap::{Args, Subcommand, ValueEnum};
use helicon_core::attitude::{VectorObservation, q_method};
use helicon_core::frames::wrap_pi;
use helicon_model::Params;
use helicon_sim::navigation::{
    NavigationConfig, ReplayInit, ReplayNavigation, imu_noise, replay_navigation, sensor_noise,
};
use helicon_sim::plot::{Figure, Panel, Series};
use helicon_sim::scenario::{EstimatorKind, EstimatorSection, Scenario};
use helicon_sim::sensor_log::{
    GroupKind, LoggedTruth, SensorLogRow, SensorLogWriter, read_sensor_log,
};
use helicon_sim::sensors::{SensorConfig, SensorSuite};
use helicon_sim::trajectory::ScriptedTrajectory;
use nalgebra::Vector3;
use std::collections::HashMap;
use std::io::Write;
use std::path::PathBuf;

// ------------------------------------------------------------------ attitude

/// Arguments of `helicon attitude`.
#[derive(Args, Debug)]
pub struct AttitudeArgs {
    /// Input CSV: per observation k = 1, 2, …: `wk, bkx, bky, bkz` (body) and
    /// `rkx, rky, rkz` (NED reference); empty cells where a row has fewer
    /// observations.
    #[arg(long)]
    pub input: PathBuf,
    /// Output CSV (default: stdout): `qw,qx,qy,qz` (Hamilton, scalar first,
    /// body_from_ned), `phi,theta,psi` (3-2-1 Euler, rad), `loss`.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

fn out_writer(out: &Option<PathBuf>) -> Result<Box<dyn Write>> {
    Ok(match out {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout())),
    })
}

/// Batch Wahba solver over a CSV of vector observations.
pub fn run_attitude(args: &AttitudeArgs) -> Result<()> {
    let file = args.input.display().to_string();
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(crate::files::open_lines(&args.input)?);
    let headers = rdr
        .headers()
        .with_context(|| format!("{file}: no header"))?
        .clone();
    let idx: HashMap<String, usize> = headers
        .iter()
        .enumerate()
        .map(|(i, h)| (h.to_string(), i))
        .collect();
    let names = |k: usize| {
        [
            format!("w{k}"),
            format!("b{k}x"),
            format!("b{k}y"),
            format!("b{k}z"),
            format!("r{k}x"),
            format!("r{k}y"),
            format!("r{k}z"),
        ]
    };
    let mut cols: Vec<[usize; 7]> = Vec::new();
    for k in 1.. {
        let n = names(k);
        let found: Vec<Option<usize>> = n.iter().map(|c| idx.get(c).copied()).collect();
        if found.iter().all(Option::is_none) {
            break;
        }
        let mut c = [0; 7];
        for (j, f) in found.iter().enumerate() {
            c[j] = f.ok_or_else(|| {
                anyhow!(
                    "{file}: column `{}` missing (observation {k} is incomplete)",
                    n[j]
                )
            })?;
        }
        cols.push(c);
    }
    if cols.is_empty() {
        bail!("{file}: no observation columns (expected w1,b1x,b1y,b1z,r1x,r1y,r1z,...)");
    }
    let mut w = out_writer(&args.out)?;
    writeln!(w, "qw,qx,qy,qz,phi,theta,psi,loss")?;
    let mut obs: Vec<VectorObservation> = Vec::with_capacity(cols.len());
    for (i, rec) in rdr.records().enumerate() {
        let row = i + 1;
        let rec = rec.with_context(|| format!("{file}: row {row}: malformed CSV"))?;
        obs.clear();
        for (k, c) in cols.iter().enumerate() {
            let cells: Vec<&str> = c.iter().map(|&j| rec.get(j).unwrap_or("")).collect();
            if cells.iter().all(|s| s.is_empty()) {
                continue;
            }
            let mut v = [0.0; 7];
            for (j, s) in cells.iter().enumerate() {
                v[j] = s.parse::<f64>().map_err(|_| {
                    anyhow!(
                        "{file}: row {row}: observation {}: `{s}` is not a number",
                        k + 1
                    )
                })?;
            }
            obs.push(VectorObservation::new(
                v[0],
                Vector3::new(v[1], v[2], v[3]),
                Vector3::new(v[4], v[5], v[6]),
            ));
        }
        let sol = q_method(&obs).map_err(|e| anyhow!("{file}: row {row}: {e}"))?;
        let q = sol.body_from_ned.quaternion();
        let e = sol.euler();
        writeln!(
            w,
            "{},{},{},{},{},{},{},{}",
            q.w, q.i, q.j, q.k, e.x, e.y, e.z, sol.loss
        )?;
    }
    w.flush()?;
    Ok(())
}

// ------------------------------------------------------------------ simulate

/// Arguments of `helicon sensors`.
#[derive(Args, Debug)]
pub struct SensorsArgs {
    /// Subcommand.
    #[command(subcommand)]
    pub command: SensorsCommand,
}

/// `helicon sensors` subcommands.
#[derive(Subcommand, Debug)]
pub enum SensorsCommand {
    /// Write a sensor log (CSV, see `helicon fuse --help`) from the scripted
    /// trajectory (`helicon sim` with `[log] sensors = true` writes one from
    /// a closed-loop flight).
    Simulate(SimulateArgs),
    /// Print the default sensor configuration as TOML (edit and pass with
    /// `simulate --config`).
    Config,
    /// The shaker experiment of thesis Appendix A: the accelerometer on a
    /// one-axis exciter; its output and moving average (Figures A.1–A.3) and
    /// a sweep over frequency and amplitude mapping the mean shift (hidden
    /// saturation). See docs/vibration.md.
    Shaker(crate::shaker_cmd::ShakerArgs),
}

/// Print the default sensor configuration (TOML) to stdout.
pub fn run_sensors_config() -> Result<()> {
    let mut con = crate::console::Console::stdout();
    con.write_str(&SensorConfig::default().to_toml()?);
    con.finish().context("writing to stdout")
}

/// Arguments of `helicon sensors simulate`.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Sensor configuration TOML (defaults: hobby IMU/GPS, see docs/sensors.md).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Helicopter parameters TOML: local gravity `environment.g_m_s2`
    /// (default: the Bergen Twin's).
    #[arg(long)]
    pub params: Option<PathBuf>,
    /// Duration (s); `--duration-s` is the old spelling.
    #[arg(
        long = "duration",
        alias = "duration-s",
        value_name = "S",
        default_value_t = 60.0,
        allow_negative_numbers = true
    )]
    pub duration_s: f64,
    /// Seed (overrides the config's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Output CSV (default: stdout).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub(crate) fn params_from(path: &Option<PathBuf>) -> Result<Params> {
    Ok(match path {
        Some(p) => Params::from_file(p)?,
        None => Params::bergen_twin(),
    })
}

/// Simulate the sensors along the scripted trajectory and write the log.
pub fn run_simulate(args: &SimulateArgs) -> Result<()> {
    let mut cfg = match &args.config {
        Some(p) => SensorConfig::from_file(p)?,
        None => SensorConfig::default(),
    };
    if let Some(s) = args.seed {
        cfg.seed = s;
    }
    if !(args.duration_s.is_finite() && args.duration_s > 0.0 && args.duration_s <= 86_400.0) {
        bail!(
            "--duration {} is invalid (allowed: 0 < d <= 86400)",
            helicon_sim::scenario::num(args.duration_s)
        );
    }
    let g = params_from(&args.params)?.environment.g_m_s2;
    let traj = ScriptedTrajectory::default();
    let mut suite = SensorSuite::new(cfg, g)?;
    let n = (args.duration_s * cfg.imu.rate_hz).round() as usize;
    let name = args
        .out
        .as_ref()
        .map_or_else(|| "<stdout>".to_string(), |p| p.display().to_string());
    let mut w = SensorLogWriter::new(
        out_writer(&args.out)?,
        &name,
        &format!(
            "helicon sensors simulate: scripted trajectory, seed {}, IMU {} Hz, GPS {} Hz, latency {} s, g {g} m/s^2",
            cfg.seed, cfg.imu.rate_hz, cfg.gps.rate_hz, cfg.gps.latency_s
        ),
    )?;
    let bar = crate::console::bar(
        n as u64 + 1,
        format!(
            "simulating {} s of sensors",
            helicon_sim::scenario::num(args.duration_s)
        ),
    );
    for k in 0..=n {
        let t = k as f64 / cfg.imu.rate_hz;
        let mut truth = traj.truth(t);
        truth.euler_rad.z = wrap_pi(truth.euler_rad.z);
        let frame = suite.sample(&truth);
        w.write(&SensorLogRow {
            frame,
            truth: LoggedTruth::from(&truth),
        })?;
        if k % 1024 == 0 {
            bar.set_position(k as u64);
        }
    }
    bar.finish_and_clear();
    w.finish()?;
    // a one-line summary (none when the log itself is on stdout)
    if let Some(path) = &args.out {
        println!(
            "wrote {} ({} rows, {} s at {} Hz, seed {})",
            path.display(),
            n + 1,
            helicon_sim::scenario::num(args.duration_s),
            cfg.imu.rate_hz,
            cfg.seed
        );
    }
    Ok(())
}

// ------------------------------------------------------------------ fuse

/// How `fuse` initialises the navigation.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum InitArg {
    /// From the truth columns (simulated logs): the closed loop's alignment.
    Truth,
    /// From the first GPS fix and q-method attitude.
    Sensors,
}

/// Which navigation `fuse` replays.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum EstimatorArg {
    /// The thesis's q-method + fusion filter.
    Thesis,
    /// The error-state Kalman filter with IMU bias states.
    Eskf,
}

/// Arguments of `helicon fuse`.
#[derive(Args, Debug)]
pub struct FuseArgs {
    /// Sensor log CSV (format: docs/sensors.md; written by `helicon sensors
    /// simulate` or by `helicon sim` with `[log] sensors = true`).
    pub log: PathBuf,
    /// Output directory (created): fused.csv, summary.json, plots.
    #[arg(long)]
    pub out: PathBuf,
    /// Take the sensor noise figures, magnetic field, navigation tuning and
    /// gravity from a scenario (to replay the navigation of its flight).
    #[arg(long, conflicts_with_all = ["sensors", "params"])]
    pub scenario: Option<PathBuf>,
    /// Sensor configuration TOML (noise figures and magnetic field); default
    /// `helicon sensors config`.
    #[arg(long)]
    pub sensors: Option<PathBuf>,
    /// Helicopter parameters TOML: local gravity `environment.g_m_s2`.
    #[arg(long)]
    pub params: Option<PathBuf>,
    /// Magnetic field in NED (same unit as mx,my,mz); overrides the sensor
    /// configuration's `mag.field_ned`.
    #[arg(long, num_args = 3, value_names = ["N", "E", "D"], allow_hyphen_values = true)]
    pub mag_field_ned: Option<Vec<f64>>,
    /// Initialisation (default: truth when the log has truth columns, else sensors).
    #[arg(long, value_enum)]
    pub init: Option<InitArg>,
    /// Navigation: accelerometer input σ per sample (m/s²); overrides the tuning.
    #[arg(long)]
    pub accel_sigma_m_s2: Option<f64>,
    /// Navigation: Euler-rate input σ per sample (rad/s); overrides the tuning.
    #[arg(long)]
    pub rate_sigma_rad_s: Option<f64>,
    /// Navigation: q-method attitude σ (rad); overrides the tuning.
    #[arg(long)]
    pub attitude_sigma_rad: Option<f64>,
    /// The navigation replayed (default: the scenario's `[estimator] kind`,
    /// else the thesis's). The ESKF takes its tuning from the scenario.
    #[arg(long, value_enum)]
    pub estimator: Option<EstimatorArg>,
}

fn rms(v: &[f64]) -> Option<f64> {
    if v.is_empty() {
        None
    } else {
        Some((v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt())
    }
}

/// Columns of `fused.csv`.
const FUSED_COLUMNS: [&str; 30] = [
    "t_s",
    "n_m",
    "e_m",
    "d_m",
    "vn_m_s",
    "ve_m_s",
    "vd_m_s",
    "phi_rad",
    "theta_rad",
    "psi_rad",
    "sigma_n_m",
    "sigma_e_m",
    "sigma_d_m",
    "sigma_phi_rad",
    "sigma_theta_rad",
    "sigma_psi_rad",
    "u_m_s",
    "v_m_s",
    "w_m_s",
    "p_rad_s",
    "q_rad_s",
    "r_rad_s",
    "attitude_fix",
    "gps_fused",
    "err_n_m",
    "err_e_m",
    "err_d_m",
    "err_phi_rad",
    "err_theta_rad",
    "err_psi_rad",
];

/// Replay a sensor log through the navigation that flies.
#[allow(clippy::too_many_lines)] // the replay, its CSV row and its plots in one pass over the log
pub fn run_fuse(args: &FuseArgs) -> Result<()> {
    let (sensors, mut nav, params, estimator) = match &args.scenario {
        Some(p) => {
            let sc = Scenario::from_file(p)?;
            let params = match &sc.params {
                Some(pp) => Params::from_file(&sc.resolve(pp))?,
                None => Params::bergen_twin(),
            };
            (sc.sensors, sc.navigation, params, sc.estimator)
        }
        None => (
            match &args.sensors {
                Some(p) => SensorConfig::from_file(p)?,
                None => SensorConfig::default(),
            },
            NavigationConfig::default(),
            params_from(&args.params)?,
            EstimatorSection::default(),
        ),
    };
    let eskf = match args.estimator {
        Some(EstimatorArg::Eskf) => true,
        Some(EstimatorArg::Thesis) => false,
        None => estimator.kind == EstimatorKind::Eskf,
    };
    if let Some(v) = args.accel_sigma_m_s2 {
        nav.accel_sigma_m_s2 = v;
    }
    if let Some(v) = args.rate_sigma_rad_s {
        nav.euler_rate_sigma_rad_s = v;
    }
    if let Some(v) = args.attitude_sigma_rad {
        nav.attitude_sigma_rad = v;
    }
    nav.validate()?;
    let mut noise = sensor_noise(&sensors, params.environment.g_m_s2);
    if let Some(m) = &args.mag_field_ned {
        let m = Vector3::new(m[0], m[1], m[2]);
        if !(m.iter().all(|v| v.is_finite()) && m.norm() > 0.0) {
            bail!(
                "--mag-field-ned {} {} {}: must be finite and not zero",
                m.x,
                m.y,
                m.z
            );
        }
        noise.mag_field_ned = m;
    }
    let log = read_sensor_log(&args.log)?;
    let has_truth = [
        GroupKind::TruePosition,
        GroupKind::TrueVelocity,
        GroupKind::TrueEuler,
        GroupKind::TrueRates,
    ]
    .iter()
    .all(|k| log.has(*k));
    let init = match args.init {
        Some(InitArg::Truth) => ReplayInit::Truth,
        Some(InitArg::Sensors) => ReplayInit::Sensors,
        None if has_truth => ReplayInit::Truth,
        None => ReplayInit::Sensors,
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let fused_path = args.out.join("fused.csv");
    let mut w = std::io::BufWriter::new(
        std::fs::File::create(&fused_path)
            .with_context(|| format!("cannot create {}", fused_path.display()))?,
    );
    writeln!(w, "{}", FUSED_COLUMNS.join(","))?;
    let (mut n_att, mut n_gps) = (0usize, 0usize);
    let (mut e_pos_h, mut e_pos_v, mut e_att, mut e_gps_h) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut series: [Vec<(f64, f64)>; 14] = Default::default();
    let every = (log.rows.len() / 4000).max(1);
    let mut line = String::new();
    let mut k = 0usize;
    let which = if eskf {
        ReplayNavigation::Eskf(&estimator.eskf, imu_noise(&sensors))
    } else {
        ReplayNavigation::Thesis(&nav)
    };
    let mut last = None;
    let replay = replay_navigation(&log, which, &noise, init, |row, y, filter| {
        use std::fmt::Write as _;
        let sol = filter.solution();
        last = Some(sol);
        let att_sigma = filter.attitude_sigma_rad();
        let t = row.frame.t_s;
        n_att += usize::from(sol.attitude_fix);
        n_gps += usize::from(sol.gps_fused);
        let mut err = [None; 6];
        if let Some(tp) = row.truth.position_ned_m {
            for i in 0..3 {
                err[i] = Some(sol.position_ned_m[i] - tp[i]);
            }
            e_pos_h.push((sol.position_ned_m.xy() - tp.xy()).norm());
            e_pos_v.push(sol.position_ned_m.z - tp.z);
            if let Some(g) = row.frame.gps {
                e_gps_h.push((g.position_ned_m.xy() - tp.xy()).norm());
            }
        }
        if let Some(te) = row.truth.euler_rad {
            for i in 0..3 {
                let d = wrap_pi(sol.attitude_rad[i] - te[i]);
                err[3 + i] = Some(d);
                e_att.push(d);
            }
        }
        line.clear();
        let _ = write!(line, "{t}");
        for v in sol
            .position_ned_m
            .iter()
            .chain(sol.velocity_ned_m_s.iter())
            .chain(sol.attitude_rad.iter())
        {
            let _ = write!(line, ",{v}");
        }
        for v in sol.position_sigma_m.iter().chain(att_sigma.iter()) {
            let _ = write!(line, ",{v}");
        }
        for v in y.iter() {
            let _ = write!(line, ",{v}");
        }
        let _ = write!(
            line,
            ",{},{}",
            u8::from(sol.attitude_fix),
            u8::from(sol.gps_fused)
        );
        for e in err {
            match e {
                Some(v) => {
                    let _ = write!(line, ",{v}");
                }
                None => line.push(','),
            }
        }
        writeln!(w, "{line}")?;
        if k % every == 0 || sol.gps_fused {
            for i in 0..3 {
                series[i].push((t, sol.position_ned_m[i]));
                series[8 + i].push((t, sol.attitude_rad[i]));
            }
            if let Some(tp) = row.truth.position_ned_m {
                for i in 0..3 {
                    series[3 + i].push((t, tp[i]));
                }
            }
            if let Some(g) = row.frame.gps {
                series[6].push((t, g.position_ned_m.x));
                series[7].push((t, g.position_ned_m.y));
            }
            if let Some(te) = row.truth.euler_rad {
                for i in 0..3 {
                    series[11 + i].push((t, te[i]));
                }
            }
        }
        k += 1;
        Ok::<(), std::io::Error>(())
    })?;
    replay.with_context(|| format!("cannot write {}", fused_path.display()))?;
    w.flush()?;
    let mut summary = serde_json::json!({
        "log": args.log.display().to_string(),
        "rows": log.rows.len(),
        "dt_s": log.mean_dt_s(),
        "init": format!("{init:?}").to_lowercase(),
        "gps_fixes_fused": n_gps,
        "attitude_solutions_fused": n_att,
        "estimator": if eskf { "eskf" } else { "thesis" },
        "navigation": {
            "accel_sigma_m_s2": nav.accel_sigma_m_s2,
            "euler_rate_sigma_rad_s": nav.euler_rate_sigma_rad_s,
            "attitude_sigma_rad": nav.attitude_sigma_rad,
            "gravity_weight": nav.gravity_weight,
            "gravity_m_s2": noise.gravity_m_s2,
        },
        // null: the log has no truth columns to compare with
        "rms_horizontal_position_error_m": rms(&e_pos_h),
        "rms_vertical_position_error_m": rms(&e_pos_v),
        "rms_gps_horizontal_error_m": rms(&e_gps_h),
        "rms_attitude_error_rad": rms(&e_att),
    });
    // the ESKF's: updates rejected by its gate, the final bias estimates
    if let (Some(sol), Some(b), Some(obj)) =
        (last, last.and_then(|s| s.imu_bias), summary.as_object_mut())
    {
        obj.insert("rejected_updates".into(), sol.rejected_updates.into());
        obj.insert(
            "gyro_bias_rad_s".into(),
            b.gyro_rad_s.as_slice().to_vec().into(),
        );
        obj.insert(
            "accel_bias_m_s2".into(),
            b.accel_m_s2.as_slice().to_vec().into(),
        );
    }
    let summary_path = args.out.join("summary.json");
    std::fs::write(&summary_path, serde_json::to_string_pretty(&summary)?)
        .with_context(|| format!("cannot write {}", summary_path.display()))?;
    // ψ fused wrapped against the true ψ (one branch, no ±π seam between
    // them); both drawn unconnected across a wrap
    if series[13].len() == series[10].len() {
        let truth = series[13].clone();
        for (f, t) in series[10].iter_mut().zip(&truth) {
            f.1 = t.1 + helicon_core::frames::wrap_pi(f.1 - t.1);
        }
    }
    let pi = std::f64::consts::PI;
    let has_truth = !series[3].is_empty();
    let has_att_truth = !series[11].is_empty();
    for ext in ["png", "svg"] {
        // one panel per axis: the fused estimate, the GPS fixes, the truth
        // (dashed) of that axis only
        let mut pos = Figure::new("Fused position (NED)", "time [s]");
        for (i, axis) in ["north", "east", "down"].into_iter().enumerate() {
            let mut p = Panel::new(&format!("{axis} [m]")).series(Series::new("fused", &series[i]));
            if i < 2 {
                p = p.series(Series::new("GPS", &series[6 + i]));
            }
            if has_truth {
                p = p.series(
                    Series::new("true", &series[3 + i])
                        .color([0, 0, 0])
                        .dashed(),
                );
            }
            pos = pos.panel(p);
        }
        pos.write(&args.out.join(format!("position.{ext}")))?;
        let mut att = Figure::new("Fused attitude (3-2-1 Euler)", "time [s]");
        for (i, axis) in ["φ", "θ", "ψ"].into_iter().enumerate() {
            let mut fused = Series::new("fused", &series[8 + i]);
            let mut truth = Series::new("true", &series[11 + i])
                .color([0, 0, 0])
                .dashed();
            if i == 2 {
                fused = fused.break_jumps_over(pi);
                truth = truth.break_jumps_over(pi);
            }
            let mut p = Panel::new(&format!("{axis} [rad]")).series(fused);
            if has_att_truth {
                p = p.series(truth);
            }
            att = att.panel(p);
        }
        att.write(&args.out.join(format!("attitude.{ext}")))?;
    }
    crate::console::note!(
        "fused {} rows ({} GPS fixes, {} attitude solutions, initialised from the {}); wrote {}",
        log.rows.len(),
        n_gps,
        n_att,
        if init == ReplayInit::Truth {
            "truth"
        } else {
            "sensors"
        },
        args.out.display()
    );
    Ok(())
}
