//! `helicon attitude`, `helicon sensors simulate` and `helicon fuse`:
//! thesis chapter 13 on the command line.
//!
//! # Sensor log CSV (written by `sensors simulate`, read by `fuse`)
//!
//! One row per IMU sample, SI units, body axes FRD, NED earth axes. Lines
//! starting with `#` are comments. Columns (header names exactly):
//!
//! | column | meaning | required by `fuse` |
//! |---|---|---|
//! | `t_s` | time (s), strictly increasing, uniform | yes |
//! | `fx_m_s2, fy_m_s2, fz_m_s2` | accelerometer specific force `f = a − g`, body | yes |
//! | `p_rad_s, q_rad_s, r_rad_s` | gyro rates, body | yes |
//! | `mx, my, mz` | magnetometer, body (same unit as the field); empty when not sampled | yes (may be empty) |
//! | `gps_n_m, gps_e_m, gps_d_m` | GPS position NED; empty when no fix this row | yes (may be empty) |
//! | `true_n_m … true_d_m`, `true_vn_m_s … true_vd_m_s`, `true_an_m_s2 … true_ad_m_s2`, `true_phi_rad, true_theta_rad, true_psi_rad` | truth (simulation only) | no |
//!
//! `fuse` rules for bad rows: missing required columns, time not strictly
//! increasing or a step deviating more than 10% from the mean step → error
//! naming the row. A row whose IMU cells are not finite numbers is skipped
//! (the filter predicts through it with the last good IMU sample); a
//! non-finite or partial GPS or magnetometer triple is treated as absent.
//! Both are counted and reported.

use anyhow::{Context, Result, anyhow, bail};
use clap::{Args, Subcommand, ValueEnum};
use helicon_gnc::attitude::{VectorObservation, gravity_observation, q_method};
use helicon_gnc::fusion::{FusionConfig, FusionFilter, FusionInput, Matrix9, Vector9, wrap_pi};
use helicon_model::frames::body_from_ned;
use helicon_sim::plot::{LinePlot, Series};
use helicon_sim::sensors::{SensorConfig, SensorSuite};
use helicon_sim::trajectory::ScriptedTrajectory;
use nalgebra::Vector3;
use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};

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
        .from_path(&args.input)
        .with_context(|| format!("cannot read {file}"))?;
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
    /// trajectory (a model-driven trajectory comes with the closed loop).
    Simulate(SimulateArgs),
    /// Print the default sensor configuration as TOML (edit and pass with
    /// `simulate --config`).
    Config,
}

/// Print the default sensor configuration (TOML) to stdout.
pub fn run_sensors_config() -> Result<()> {
    print!("{}", SensorConfig::default().to_toml()?);
    Ok(())
}

/// Arguments of `helicon sensors simulate`.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Sensor configuration TOML (defaults: hobby IMU/GPS, see docs/sensors.md).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Duration (s).
    #[arg(long, default_value_t = 60.0)]
    pub duration_s: f64,
    /// Seed (overrides the config's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Output CSV (default: stdout).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

const LOG_HEADER: &str = "t_s,fx_m_s2,fy_m_s2,fz_m_s2,p_rad_s,q_rad_s,r_rad_s,mx,my,mz,gps_n_m,gps_e_m,gps_d_m,true_n_m,true_e_m,true_d_m,true_vn_m_s,true_ve_m_s,true_vd_m_s,true_an_m_s2,true_ae_m_s2,true_ad_m_s2,true_phi_rad,true_theta_rad,true_psi_rad";

fn opt3(v: Option<Vector3<f64>>) -> String {
    match v {
        Some(v) => format!("{},{},{}", v.x, v.y, v.z),
        None => ",,".to_string(),
    }
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
            "--duration-s {} is invalid (allowed: 0 < d <= 86400)",
            args.duration_s
        );
    }
    let traj = ScriptedTrajectory::default();
    let mut suite = SensorSuite::new(cfg)?;
    let n = (args.duration_s * cfg.imu.rate_hz).round() as usize;
    let mut w = out_writer(&args.out)?;
    writeln!(
        w,
        "# helicon sensors simulate: scripted trajectory (helicon_sim::trajectory::ScriptedTrajectory default), seed {}, IMU {} Hz, GPS {} Hz, latency {} s",
        cfg.seed, cfg.imu.rate_hz, cfg.gps.rate_hz, cfg.gps.latency_s
    )?;
    writeln!(w, "{LOG_HEADER}")?;
    for k in 0..=n {
        let t = k as f64 / cfg.imu.rate_hz;
        let truth = traj.truth(t);
        let s = suite.sample(&truth);
        let e = truth.euler_rad;
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            t,
            s.specific_force_body_m_s2.x,
            s.specific_force_body_m_s2.y,
            s.specific_force_body_m_s2.z,
            s.gyro_body_rad_s.x,
            s.gyro_body_rad_s.y,
            s.gyro_body_rad_s.z,
            opt3(s.mag_body),
            opt3(s.gps_ned_m),
            opt3(Some(truth.pos_ned_m)),
            opt3(Some(truth.vel_ned_m_s)),
            opt3(Some(truth.acc_ned_m_s2)),
            e.x,
            e.y,
            wrap_pi(e.z),
        )?;
    }
    w.flush()?;
    Ok(())
}

// ------------------------------------------------------------------ fuse

/// Source of the helicopter's own acceleration subtracted from the
/// accelerometer to obtain gravity for attitude determination, (13.2).
///
/// The fusion filter's own velocity cannot serve: its derivative is
/// `R̂ f + g`, and subtracting it from `f` returns `R̂ᵀ g`, the predicted
/// attitude itself (no tilt information; tried, it diverged). The
/// acceleration must come from the model or state estimator (closed loop).
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum OwnAccel {
    /// Assume zero (the thesis implementation; valid only when not accelerating).
    None,
    /// The log's truth columns `true_an_m_s2…` (simulated logs only).
    Truth,
}

/// Arguments of `helicon fuse`.
#[derive(Args, Debug)]
pub struct FuseArgs {
    /// Sensor log CSV (format: see the module docs / docs/sensors.md).
    pub log: PathBuf,
    /// Output directory (created): fused.csv, summary.json, plots.
    #[arg(long)]
    pub out: PathBuf,
    /// Magnetic field in NED (same unit as mx,my,mz), default thesis (13.14).
    #[arg(long, num_args = 3, value_names = ["N", "E", "D"], allow_hyphen_values = true, default_values_t = [0.153, 0.008, -0.438])]
    pub mag_field_ned: Vec<f64>,
    /// Gravity used by the filter (m/s²); match the log's (`helicon sensors
    /// simulate` uses the sensor config's `gravity_m_s2`, default 9.82, (13.13)).
    #[arg(long, default_value_t = 9.82)]
    pub gravity_m_s2: f64,
    /// Own-acceleration source for the gravity observation.
    #[arg(long, value_enum, default_value_t = OwnAccel::None)]
    pub own_accel: OwnAccel,
    /// GPS σ horizontal (m) for the filter's R.
    #[arg(long, default_value_t = 1.5)]
    pub gps_sigma_h_m: f64,
    /// GPS σ vertical (m) for the filter's R.
    #[arg(long, default_value_t = 3.0)]
    pub gps_sigma_v_m: f64,
    /// Accelerometer input σ (m/s²) for the filter's Q, per IMU sample. The
    /// filter has no bias states, so this must also cover slowly varying
    /// errors (bias, scale factor, g × attitude error): 3 m/s² at 400 Hz gave
    /// the lowest position error on the default simulated log (docs/sensors.md).
    #[arg(long, default_value_t = 3.0)]
    pub accel_sigma_m_s2: f64,
    /// Euler-rate input σ (rad/s) for the filter's Q, per IMU sample. Large
    /// enough that the q-method attitude pulls out the gyro bias quickly (the
    /// filter has no bias states; docs/sensors.md).
    #[arg(long, default_value_t = 0.2)]
    pub rate_sigma_rad_s: f64,
    /// Attitude-measurement σ (rad) for the filter's R.
    #[arg(long, default_value_t = 0.05)]
    pub attitude_sigma_rad: f64,
}

struct LogRow {
    t: f64,
    f: Option<Vector3<f64>>,
    w: Option<Vector3<f64>>,
    mag: Option<Vector3<f64>>,
    gps: Option<Vector3<f64>>,
    true_pos: Option<Vector3<f64>>,
    true_acc: Option<Vector3<f64>>,
    true_euler: Option<Vector3<f64>>,
}

fn triple(rec: &csv::StringRecord, c: Option<[usize; 3]>) -> (Option<Vector3<f64>>, bool) {
    let Some(c) = c else { return (None, false) };
    let cells: Vec<&str> = c.iter().map(|&i| rec.get(i).unwrap_or("")).collect();
    if cells.iter().all(|s| s.is_empty()) {
        return (None, false);
    }
    let v: Vec<f64> = cells
        .iter()
        .map(|s| s.parse::<f64>().unwrap_or(f64::NAN))
        .collect();
    if v.iter().all(|x| x.is_finite()) {
        (Some(Vector3::new(v[0], v[1], v[2])), false)
    } else {
        (None, true)
    }
}

struct Log {
    rows: Vec<LogRow>,
    skipped_imu: usize,
    bad_aux: usize,
}

fn read_log(path: &Path) -> Result<Log> {
    let file = path.display().to_string();
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_path(path)
        .with_context(|| format!("cannot read {file}"))?;
    let headers = rdr
        .headers()
        .with_context(|| format!("{file}: no header"))?
        .clone();
    let idx: HashMap<&str, usize> = headers.iter().enumerate().map(|(i, h)| (h, i)).collect();
    let required = [
        "t_s", "fx_m_s2", "fy_m_s2", "fz_m_s2", "p_rad_s", "q_rad_s", "r_rad_s", "mx", "my", "mz",
        "gps_n_m", "gps_e_m", "gps_d_m",
    ];
    let missing: Vec<&str> = required
        .iter()
        .copied()
        .filter(|c| !idx.contains_key(c))
        .collect();
    if !missing.is_empty() {
        bail!("{file}: missing required column(s): {}", missing.join(", "));
    }
    let c3 = |a: &str, b: &str, c: &str| match (idx.get(a), idx.get(b), idx.get(c)) {
        (Some(&x), Some(&y), Some(&z)) => Some([x, y, z]),
        _ => None,
    };
    let cf = c3("fx_m_s2", "fy_m_s2", "fz_m_s2");
    let cw = c3("p_rad_s", "q_rad_s", "r_rad_s");
    let cm = c3("mx", "my", "mz");
    let cg = c3("gps_n_m", "gps_e_m", "gps_d_m");
    let ctp = c3("true_n_m", "true_e_m", "true_d_m");
    let cta = c3("true_an_m_s2", "true_ae_m_s2", "true_ad_m_s2");
    let cte = c3("true_phi_rad", "true_theta_rad", "true_psi_rad");
    let ct = idx["t_s"];
    let mut rows = Vec::new();
    let (mut skipped_imu, mut bad_aux) = (0, 0);
    let mut last_t = f64::NEG_INFINITY;
    for (i, rec) in rdr.records().enumerate() {
        let row = i + 1;
        let rec = rec.with_context(|| format!("{file}: row {row}: malformed CSV"))?;
        let ts = rec.get(ct).unwrap_or("");
        let t: f64 = ts
            .parse()
            .map_err(|_| anyhow!("{file}: row {row}: t_s `{ts}` is not a number"))?;
        if !t.is_finite() {
            bail!("{file}: row {row}: t_s is not finite");
        }
        if t <= last_t {
            bail!("{file}: row {row}: time goes backwards or repeats ({t} s after {last_t} s)");
        }
        last_t = t;
        let (f, bf) = triple(&rec, cf);
        let (w, bw) = triple(&rec, cw);
        let imu_ok = f.is_some() && w.is_some() && !bf && !bw;
        if !imu_ok {
            skipped_imu += 1;
        }
        let (mag, bm) = triple(&rec, cm);
        let (gps, bg) = triple(&rec, cg);
        bad_aux += usize::from(bm) + usize::from(bg);
        rows.push(LogRow {
            t,
            f: if imu_ok { f } else { None },
            w: if imu_ok { w } else { None },
            mag,
            gps,
            true_pos: triple(&rec, ctp).0,
            true_acc: triple(&rec, cta).0,
            true_euler: triple(&rec, cte).0,
        });
    }
    if rows.len() < 2 {
        bail!("{file}: fewer than two data rows");
    }
    let mean_dt = (rows[rows.len() - 1].t - rows[0].t) / (rows.len() - 1) as f64;
    for (i, pair) in rows.windows(2).enumerate() {
        let dt = pair[1].t - pair[0].t;
        if (dt / mean_dt - 1.0).abs() > 0.1 {
            bail!(
                "{file}: row {}: time step {dt} s deviates more than 10% from the mean step {mean_dt} s (the fusion filter needs uniform sampling)",
                i + 2
            );
        }
    }
    Ok(Log {
        rows,
        skipped_imu,
        bad_aux,
    })
}

fn rms(v: &[f64]) -> Option<f64> {
    if v.is_empty() {
        None
    } else {
        Some((v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt())
    }
}

/// Replay a sensor log through attitude determination and the fusion filter.
pub fn run_fuse(args: &FuseArgs) -> Result<()> {
    let log = read_log(&args.log)?;
    let rows = &log.rows;
    let dt = (rows[rows.len() - 1].t - rows[0].t) / (rows.len() - 1) as f64;
    let g = args.gravity_m_s2;
    if !(g.is_finite() && g > 0.0) {
        bail!("--gravity-m-s2 must be finite and > 0, got {g}");
    }
    let mag_ned = Vector3::new(
        args.mag_field_ned[0],
        args.mag_field_ned[1],
        args.mag_field_ned[2],
    );
    let config = FusionConfig {
        dt_s: dt,
        gravity_m_s2: g,
        accel_sigma_m_s2: args.accel_sigma_m_s2,
        euler_rate_sigma_rad_s: args.rate_sigma_rad_s,
        gps_sigma_m: Vector3::new(args.gps_sigma_h_m, args.gps_sigma_h_m, args.gps_sigma_v_m),
        gps_vel_sigma_m_s: Vector3::new(0.1, 0.1, 0.2),
        attitude_sigma_rad: Vector3::repeat(args.attitude_sigma_rad),
    };
    if args.own_accel == OwnAccel::Truth && rows.iter().all(|r| r.true_acc.is_none()) {
        bail!("--own-accel truth needs the true_an_m_s2,true_ae_m_s2,true_ad_m_s2 columns");
    }
    // Attitude measurement (q-method, §13.2) for a row.
    let attitude = |r: &LogRow,
                    acc_ned: Option<Vector3<f64>>,
                    euler_prior: &Vector3<f64>|
     -> Option<Vector3<f64>> {
        let (f, m) = (r.f?, r.mag?);
        let a_body =
            acc_ned.map(|a| body_from_ned(euler_prior.x, euler_prior.y, euler_prior.z) * a);
        let obs = [
            gravity_observation(1.0, &f, a_body.as_ref()),
            VectorObservation::new(1.0, m, mag_ned),
        ];
        q_method(&obs).ok().map(|s| s.euler())
    };
    // Initial state: first GPS fix, zero velocity, first attitude solution.
    let first_gps = rows
        .iter()
        .find_map(|r| r.gps)
        .unwrap_or_else(Vector3::zeros);
    let first_att = rows
        .iter()
        .find_map(|r| attitude(r, None, &Vector3::zeros()))
        .unwrap_or_else(Vector3::zeros);
    let mut x0 = Vector9::zeros();
    x0.fixed_rows_mut::<3>(0).copy_from(&first_gps);
    x0.fixed_rows_mut::<3>(6).copy_from(&first_att);
    let p0 = Matrix9::from_diagonal(&Vector9::from_row_slice(&[
        25.0, 25.0, 25.0, 4.0, 4.0, 4.0, 0.04, 0.04, 0.1,
    ]));
    let mut filter = FusionFilter::new(config, x0, p0)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let fused_path = args.out.join("fused.csv");
    let mut w = std::io::BufWriter::new(
        std::fs::File::create(&fused_path)
            .with_context(|| format!("cannot create {}", fused_path.display()))?,
    );
    writeln!(
        w,
        "t_s,n_m,e_m,d_m,vn_m_s,ve_m_s,vd_m_s,phi_rad,theta_rad,psi_rad,sigma_n_m,sigma_e_m,sigma_d_m,sigma_phi_rad,sigma_theta_rad,sigma_psi_rad,qm_phi_rad,qm_theta_rad,qm_psi_rad,err_n_m,err_e_m,err_d_m,err_phi_rad,err_theta_rad,err_psi_rad"
    )?;
    let (mut last_f, mut last_w) = (Vector3::new(0.0, 0.0, -g), Vector3::zeros());
    let (mut n_att, mut n_att_fail, mut n_gps) = (0usize, 0usize, 0usize);
    let (mut e_pos_h, mut e_pos_v, mut e_att, mut e_gps_h) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut series: [Vec<(f64, f64)>; 15] = Default::default();
    for (k, r) in rows.iter().enumerate() {
        let euler_now = filter.state().fixed_rows::<3>(6).into_owned();
        let own_acc = match args.own_accel {
            OwnAccel::None => None,
            OwnAccel::Truth => r.true_acc,
        };
        let att = if r.f.is_some() && r.mag.is_some() {
            let a = attitude(r, own_acc, &euler_now);
            if a.is_some() {
                n_att += 1;
            } else {
                n_att_fail += 1;
            }
            a
        } else {
            None
        };
        n_gps += usize::from(r.gps.is_some());
        if k > 0 {
            filter
                .step(&FusionInput {
                    specific_force_body_m_s2: last_f,
                    gyro_body_rad_s: last_w,
                    gps_ned_m: r.gps,
                    gps_vel_ned_m_s: None,
                    attitude_rad: att,
                })
                .with_context(|| format!("{}: row {}: fusion filter", args.log.display(), k + 1))?;
        }
        if let (Some(f), Some(wg)) = (r.f, r.w) {
            last_f = f;
            last_w = wg;
        }
        let x = *filter.state();
        let p = filter.covariance();
        let sd: Vec<f64> = [0, 1, 2, 6, 7, 8]
            .iter()
            .map(|&i| p[(i, i)].sqrt())
            .collect();
        let mut err = [f64::NAN; 6];
        if let Some(tp) = r.true_pos {
            for i in 0..3 {
                err[i] = x[i] - tp[i];
            }
            e_pos_h.push((err[0] * err[0] + err[1] * err[1]).sqrt());
            e_pos_v.push(err[2]);
            if let Some(gz) = r.gps {
                e_gps_h.push(((gz.x - tp.x).powi(2) + (gz.y - tp.y).powi(2)).sqrt());
            }
        }
        if let Some(te) = r.true_euler {
            for i in 0..3 {
                err[3 + i] = wrap_pi(x[6 + i] - te[i]);
            }
            e_att.extend_from_slice(&err[3..6]);
        }
        let qm = att.map(|a| [a.x, a.y, a.z]);
        let cell = |v: f64| {
            if v.is_finite() {
                v.to_string()
            } else {
                String::new()
            }
        };
        let qm_s = match qm {
            Some(a) => format!("{},{},{}", a[0], a[1], a[2]),
            None => ",,".into(),
        };
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.t,
            x[0],
            x[1],
            x[2],
            x[3],
            x[4],
            x[5],
            x[6],
            x[7],
            x[8],
            sd[0],
            sd[1],
            sd[2],
            sd[3],
            sd[4],
            sd[5],
            qm_s,
            cell(err[0]),
            cell(err[1]),
            cell(err[2]),
            cell(err[3]),
            cell(err[4]),
            cell(err[5]),
        )?;
        // Plot series (decimated to ≤ ~4000 points).
        let every = (rows.len() / 4000).max(1);
        if k % every == 0 || r.gps.is_some() {
            series[0].push((r.t, x[0]));
            series[1].push((r.t, x[1]));
            series[2].push((r.t, x[2]));
            if let Some(tp) = r.true_pos {
                series[3].push((r.t, tp.x));
                series[4].push((r.t, tp.y));
                series[5].push((r.t, tp.z));
            }
            if let Some(gz) = r.gps {
                series[6].push((r.t, gz.x));
                series[7].push((r.t, gz.y));
            }
            series[8].push((r.t, x[6]));
            series[9].push((r.t, x[7]));
            series[10].push((r.t, x[8]));
            if let Some(te) = r.true_euler {
                series[11].push((r.t, te.x));
                series[12].push((r.t, te.y));
                series[13].push((r.t, te.z));
            }
            if let Some(a) = qm {
                series[14].push((r.t, a[0]));
            }
        }
    }
    w.flush()?;
    let summary = serde_json::json!({
        "log": args.log.display().to_string(),
        "rows": rows.len(),
        "dt_s": dt,
        "skipped_imu_rows": log.skipped_imu,
        "invalid_gps_or_mag_cells_ignored": log.bad_aux,
        "gps_fixes": n_gps,
        "attitude_solutions": n_att,
        "attitude_failures_degenerate": n_att_fail,
        "own_accel": format!("{:?}", args.own_accel),
        "rms_horizontal_position_error_m": rms(&e_pos_h),
        "rms_vertical_position_error_m": rms(&e_pos_v),
        "rms_gps_horizontal_error_m": rms(&e_gps_h),
        "rms_attitude_error_rad": rms(&e_att),
    });
    std::fs::write(
        args.out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?,
    )?;
    for ext in ["png", "svg"] {
        let mut pos = LinePlot::new("Fused position (NED)", "time [s]", "position [m]")
            .series(Series::new("north fused", &series[0]))
            .series(Series::new("east fused", &series[1]))
            .series(Series::new("down fused", &series[2]))
            .series(Series::new("GPS north", &series[6]))
            .series(Series::new("GPS east", &series[7]));
        if !series[3].is_empty() {
            pos = pos
                .series(Series::new("north true", &series[3]))
                .series(Series::new("east true", &series[4]))
                .series(Series::new("down true", &series[5]));
        }
        pos.write(&args.out.join(format!("position.{ext}")))?;
        let mut att = LinePlot::new("Fused attitude (3-2-1 Euler)", "time [s]", "angle [rad]")
            .series(Series::new("phi fused", &series[8]))
            .series(Series::new("theta fused", &series[9]))
            .series(Series::new("psi fused", &series[10]))
            .series(Series::new("phi q-method", &series[14]));
        if !series[11].is_empty() {
            att = att
                .series(Series::new("phi true", &series[11]))
                .series(Series::new("theta true", &series[12]))
                .series(Series::new("psi true", &series[13]));
        }
        att.write(&args.out.join(format!("attitude.{ext}")))?;
    }
    eprintln!(
        "fused {} rows ({} IMU rows skipped, {} bad GPS/mag cells ignored, {} GPS fixes, {} attitude solutions, {} degenerate); wrote {}",
        rows.len(),
        log.skipped_imu,
        log.bad_aux,
        n_gps,
        n_att,
        n_att_fail,
        args.out.display()
    );
    Ok(())
}
