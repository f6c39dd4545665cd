//! The sensor log: one CSV row per IMU sample, the core's
//! [`SensorFrame`] plus, for simulated logs, the truth it was sampled from.
//! Written by `helicon sensors simulate` and by `helicon sim` (`[log]
//! sensors = true`), read by `helicon fuse` and by identification.
//!
//! One column specification ([`GROUPS`]) drives the header, the writer and
//! the reader. SI units, body axes FRD, NED earth axes; lines starting with
//! `#` are comments. Format version [`SENSOR_LOG_VERSION`] (see CHANGELOG.md).
//!
//! | columns | meaning | column required | cells may be empty |
//! |---|---|---|---|
//! | `t_s` | time (s), ≥ 0, strictly increasing | yes | no |
//! | `fx_m_s2 fy_m_s2 fz_m_s2` | accelerometer specific force `f = a − g`, body | yes | no |
//! | `p_rad_s q_rad_s r_rad_s` | gyro rates, body | yes | no |
//! | `mx my mz` | magnetometer, body (unit of the local field) | yes | yes: not sampled |
//! | `gps_epoch_s` | time of validity of the GPS fix (s) | no | yes |
//! | `gps_n_m gps_e_m gps_d_m` | GPS position NED | yes | yes: no fix this row |
//! | `gps_vn_m_s gps_ve_m_s gps_vd_m_s` | GPS (Doppler) velocity NED | no | yes |
//! | `true_n_m …`, `true_vn_m_s …`, `true_an_m_s2 …`, `true_phi_rad …`, `true_p_rad_s …` | truth (simulation only) | no | yes |
//!
//! Reading is strict: a cell that is not a finite number in plain decimal or
//! exponent notation (`0.` — a truncated number — `NaN`, `inf` or text), a
//! partly filled triple, a duplicated or missing column, or a value beyond
//! the physical bounds of [`bound_of`] is an error naming the file, the line
//! and the column.

use crate::trajectory::TruthSample;
use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample, SensorFrame};
use nalgebra::Vector3;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Version of the sensor-log format written here.
pub const SENSOR_LOG_VERSION: u32 = 2;

/// A group of columns: a scalar or a triple sharing a unit and a meaning.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Group {
    /// What the group holds.
    pub kind: GroupKind,
    /// Column names, in order.
    pub columns: &'static [&'static str],
    /// Unit of every column.
    pub unit: &'static str,
    /// The columns must be in the header.
    pub required: bool,
    /// Cells may be left empty (the quantity was not sampled that row).
    pub may_be_empty: bool,
}

/// The quantities of a sensor log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum GroupKind {
    /// Sample time.
    Time,
    /// Accelerometer.
    Accel,
    /// Gyro.
    Gyro,
    /// Magnetometer.
    Mag,
    /// GPS time of validity.
    GpsEpoch,
    /// GPS position.
    GpsPosition,
    /// GPS velocity.
    GpsVelocity,
    /// True position.
    TruePosition,
    /// True velocity.
    TrueVelocity,
    /// True acceleration.
    TrueAcceleration,
    /// True attitude.
    TrueEuler,
    /// True body rates.
    TrueRates,
}

/// The column specification, in file order.
pub const GROUPS: [Group; 12] = [
    Group {
        kind: GroupKind::Time,
        columns: &["t_s"],
        unit: "s",
        required: true,
        may_be_empty: false,
    },
    Group {
        kind: GroupKind::Accel,
        columns: &["fx_m_s2", "fy_m_s2", "fz_m_s2"],
        unit: "m/s^2",
        required: true,
        may_be_empty: false,
    },
    Group {
        kind: GroupKind::Gyro,
        columns: &["p_rad_s", "q_rad_s", "r_rad_s"],
        unit: "rad/s",
        required: true,
        may_be_empty: false,
    },
    Group {
        kind: GroupKind::Mag,
        columns: &["mx", "my", "mz"],
        unit: "field unit",
        required: true,
        may_be_empty: true,
    },
    Group {
        kind: GroupKind::GpsEpoch,
        columns: &["gps_epoch_s"],
        unit: "s",
        required: false,
        may_be_empty: true,
    },
    Group {
        kind: GroupKind::GpsPosition,
        columns: &["gps_n_m", "gps_e_m", "gps_d_m"],
        unit: "m",
        required: true,
        may_be_empty: true,
    },
    Group {
        kind: GroupKind::GpsVelocity,
        columns: &["gps_vn_m_s", "gps_ve_m_s", "gps_vd_m_s"],
        unit: "m/s",
        required: false,
        may_be_empty: true,
    },
    Group {
        kind: GroupKind::TruePosition,
        columns: &["true_n_m", "true_e_m", "true_d_m"],
        unit: "m",
        required: false,
        may_be_empty: true,
    },
    Group {
        kind: GroupKind::TrueVelocity,
        columns: &["true_vn_m_s", "true_ve_m_s", "true_vd_m_s"],
        unit: "m/s",
        required: false,
        may_be_empty: true,
    },
    Group {
        kind: GroupKind::TrueAcceleration,
        columns: &["true_an_m_s2", "true_ae_m_s2", "true_ad_m_s2"],
        unit: "m/s^2",
        required: false,
        may_be_empty: true,
    },
    Group {
        kind: GroupKind::TrueEuler,
        columns: &["true_phi_rad", "true_theta_rad", "true_psi_rad"],
        unit: "rad",
        required: false,
        may_be_empty: true,
    },
    Group {
        kind: GroupKind::TrueRates,
        columns: &["true_p_rad_s", "true_q_rad_s", "true_r_rad_s"],
        unit: "rad/s",
        required: false,
        may_be_empty: true,
    },
];

/// The largest magnitude accepted in a group's cells, and why.
///
/// - accelerometer 1e4 m/s² (≈ 1000 g): beyond the range of any MEMS
///   accelerometer (the widest common parts are ±400 g);
/// - gyro 100 rad/s (≈ 5700 °/s): beyond every MEMS gyro range (±4000 °/s);
/// - positions 1e7 m: a local NED frame larger than the Earth is a unit error;
/// - velocities 1e3 m/s, accelerations 1e4 m/s²: far beyond any rotorcraft;
/// - magnetometer 1e6 field units: covers gauss, µT and nT;
/// - angles 1e3 rad (unwrapped headings), times 1e9 s (31 years).
pub fn bound_of(kind: GroupKind) -> f64 {
    match kind {
        GroupKind::Time | GroupKind::GpsEpoch => 1e9,
        GroupKind::Accel | GroupKind::TrueAcceleration => 1e4,
        GroupKind::Gyro | GroupKind::TrueRates => 100.0,
        GroupKind::Mag => 1e6,
        GroupKind::GpsPosition | GroupKind::TruePosition => 1e7,
        GroupKind::GpsVelocity | GroupKind::TrueVelocity => 1e3,
        GroupKind::TrueEuler => 1e3,
    }
}

/// The truth a simulated log carries (each group when present).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LoggedTruth {
    /// Position NED (m).
    pub position_ned_m: Option<Vector3<f64>>,
    /// Velocity NED (m/s).
    pub velocity_ned_m_s: Option<Vector3<f64>>,
    /// Acceleration NED (m/s²).
    pub acceleration_ned_m_s2: Option<Vector3<f64>>,
    /// 3-2-1 Euler angles (rad).
    pub euler_rad: Option<Vector3<f64>>,
    /// Body rates (rad/s).
    pub rates_body_rad_s: Option<Vector3<f64>>,
}

impl From<&TruthSample> for LoggedTruth {
    fn from(t: &TruthSample) -> Self {
        LoggedTruth {
            position_ned_m: Some(t.pos_ned_m),
            velocity_ned_m_s: Some(t.vel_ned_m_s),
            acceleration_ned_m_s2: Some(t.acc_ned_m_s2),
            euler_rad: Some(t.euler_rad),
            rates_body_rad_s: Some(t.omega_body_rad_s),
        }
    }
}

/// One row: the frame the flight software sees and the truth, if logged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorLogRow {
    /// The sensor frame.
    pub frame: SensorFrame,
    /// The truth (simulated logs).
    pub truth: LoggedTruth,
}

impl SensorLogRow {
    fn get(&self, kind: GroupKind) -> Option<[f64; 3]> {
        let f = &self.frame;
        let v3 = |v: Option<Vector3<f64>>| v.map(|v| [v.x, v.y, v.z]);
        match kind {
            GroupKind::Time => Some([f.t_s, 0.0, 0.0]),
            GroupKind::Accel => v3(Some(f.imu.specific_force_body_m_s2)),
            GroupKind::Gyro => v3(Some(f.imu.gyro_body_rad_s)),
            GroupKind::Mag => v3(f.mag_body),
            GroupKind::GpsEpoch => f.gps.map(|g| [g.epoch_s, 0.0, 0.0]),
            GroupKind::GpsPosition => v3(f.gps.map(|g| g.position_ned_m)),
            GroupKind::GpsVelocity => v3(f.gps.and_then(|g| g.velocity_ned_m_s)),
            GroupKind::TruePosition => v3(self.truth.position_ned_m),
            GroupKind::TrueVelocity => v3(self.truth.velocity_ned_m_s),
            GroupKind::TrueAcceleration => v3(self.truth.acceleration_ned_m_s2),
            GroupKind::TrueEuler => v3(self.truth.euler_rad),
            GroupKind::TrueRates => v3(self.truth.rates_body_rad_s),
        }
    }
}

/// Errors reading or writing a sensor log: the file, the line (1-based,
/// counting the header and comments) and the column when known.
#[derive(Debug, thiserror::Error)]
pub enum SensorLogError {
    /// The file could not be opened, read or written.
    #[error("{file}: {what}")]
    Io {
        /// File.
        file: String,
        /// What was being done.
        what: &'static str,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The content is wrong.
    #[error("{file}:{line}: {message}")]
    Content {
        /// File.
        file: String,
        /// Line (1-based; 0 when the whole file is concerned).
        line: u64,
        /// What was wrong, naming the column.
        message: String,
    },
}

/// Writes a sensor log row by row (buffered).
pub struct SensorLogWriter<W: Write> {
    out: W,
    file: String,
    cells: String,
}

impl<W: Write> SensorLogWriter<W> {
    /// Start a log on `out` (named `file` in errors) with a `#` comment line
    /// describing its origin, then the header.
    pub fn new(mut out: W, file: &str, comment: &str) -> Result<Self, SensorLogError> {
        let io = |source| SensorLogError::Io {
            file: file.to_string(),
            what: "cannot write",
            source,
        };
        let header: Vec<&str> = GROUPS
            .iter()
            .flat_map(|g| g.columns.iter().copied())
            .collect();
        writeln!(
            out,
            "# helicon sensor log v{SENSOR_LOG_VERSION}: {}",
            comment.replace('\n', " ")
        )
        .map_err(io)?;
        writeln!(out, "{}", header.join(",")).map_err(io)?;
        Ok(SensorLogWriter {
            out,
            file: file.to_string(),
            cells: String::with_capacity(512),
        })
    }

    /// Append one row. Floats are written in Rust's shortest round-trip
    /// form, so reading the log back gives the same numbers bit for bit.
    pub fn write(&mut self, row: &SensorLogRow) -> Result<(), SensorLogError> {
        use std::fmt::Write as _;
        self.cells.clear();
        for (gi, g) in GROUPS.iter().enumerate() {
            let v = row.get(g.kind);
            for j in 0..g.columns.len() {
                if gi + j > 0 {
                    self.cells.push(',');
                }
                if let Some(v) = v {
                    if !v[j].is_finite() {
                        return Err(SensorLogError::Content {
                            file: self.file.clone(),
                            line: 0,
                            message: format!(
                                "refusing to write non-finite `{}` = {} at t = {} s",
                                g.columns[j], v[j], row.frame.t_s
                            ),
                        });
                    }
                    let _ = write!(self.cells, "{}", v[j]);
                }
            }
        }
        self.cells.push('\n');
        self.out
            .write_all(self.cells.as_bytes())
            .map_err(|source| SensorLogError::Io {
                file: self.file.clone(),
                what: "cannot write",
                source,
            })
    }

    /// Flush and return the writer.
    pub fn finish(mut self) -> Result<W, SensorLogError> {
        self.out.flush().map_err(|source| SensorLogError::Io {
            file: self.file.clone(),
            what: "cannot write",
            source,
        })?;
        Ok(self.out)
    }
}

/// A sensor log read back.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorLog {
    /// The file it was read from.
    pub file: PathBuf,
    /// The rows, in time order.
    pub rows: Vec<SensorLogRow>,
    /// Which optional groups the header had.
    pub has: Vec<GroupKind>,
}

impl SensorLog {
    /// The mean sample period (s).
    pub fn mean_dt_s(&self) -> f64 {
        match (self.rows.first(), self.rows.last()) {
            (Some(a), Some(b)) if self.rows.len() > 1 => {
                (b.frame.t_s - a.frame.t_s) / (self.rows.len() - 1) as f64
            }
            _ => f64::NAN,
        }
    }

    /// True when the header had every column of `kind`.
    pub fn has(&self, kind: GroupKind) -> bool {
        self.has.contains(&kind)
    }
}

/// Parse one cell strictly: plain decimal or exponent notation, finite, not
/// ending in a bare `.` (a truncated number).
pub fn parse_number(cell: &str) -> Result<f64, String> {
    let s = cell.trim();
    let plain = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_digit() || matches!(c, '+' | '-' | '.' | 'e' | 'E'))
        && s.chars().any(|c| c.is_ascii_digit());
    if !plain {
        return Err(format!("`{s}` is not a number"));
    }
    let mantissa = s.split(['e', 'E']).next().unwrap_or("");
    if mantissa.ends_with('.') || mantissa.starts_with('.') || mantissa.starts_with("-.") {
        return Err(format!(
            "`{s}` looks truncated (digits expected around the `.`)"
        ));
    }
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("`{s}` is out of the floating-point range")),
        Err(_) => Err(format!("`{s}` is not a number")),
    }
}

/// Read a sensor log (see the module docs for the rules).
#[allow(clippy::too_many_lines)] // one pass over the rows; the column rules live in GROUPS
pub fn read_sensor_log(path: &Path) -> Result<SensorLog, SensorLogError> {
    let file = path.display().to_string();
    let content = |line: u64, message: String| SensorLogError::Content {
        file: file.clone(),
        line,
        message,
    };
    let f = helicon_config::open_lines_bounded(
        path,
        helicon_config::MAX_DATA_BYTES,
        helicon_config::MAX_LINE_BYTES,
    )
    .map_err(|e| SensorLogError::Io {
        file: file.clone(),
        what: "cannot open",
        source: e.into_io(),
    })?;
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(false)
        .from_reader(std::io::BufReader::new(f));
    let headers = rdr
        .headers()
        .map_err(|e| content(e.position().map_or(1, |p| p.line()), format!("header: {e}")))?
        .clone();
    let header_line = rdr.position().line();
    let mut seen = std::collections::HashMap::new();
    for (i, h) in headers.iter().enumerate() {
        if let Some(first) = seen.insert(h.to_string(), i) {
            return Err(content(
                header_line,
                format!(
                    "column `{h}` appears twice (columns {} and {})",
                    first + 1,
                    i + 1
                ),
            ));
        }
    }
    // column indices per group (all or none of a group's columns)
    let mut index: Vec<Option<Vec<usize>>> = Vec::with_capacity(GROUPS.len());
    for g in &GROUPS {
        let found: Vec<Option<usize>> = g.columns.iter().map(|c| seen.get(*c).copied()).collect();
        if found.iter().all(Option::is_some) {
            index.push(Some(found.into_iter().flatten().collect()));
        } else if g.required || found.iter().any(Option::is_some) {
            let missing: Vec<&str> = g
                .columns
                .iter()
                .zip(&found)
                .filter(|(_, f)| f.is_none())
                .map(|(c, _)| *c)
                .collect();
            return Err(content(
                header_line,
                format!("missing column(s) {}", missing.join(", ")),
            ));
        } else {
            index.push(None);
        }
    }
    let has: Vec<GroupKind> = GROUPS
        .iter()
        .zip(&index)
        .filter(|(_, i)| i.is_some())
        .map(|(g, _)| g.kind)
        .collect();
    let mut rows: Vec<SensorLogRow> = Vec::new();
    let mut record = csv::StringRecord::new();
    let mut last_t = f64::NEG_INFINITY;
    loop {
        let more = rdr.read_record(&mut record).map_err(|e| {
            content(
                e.position().map_or(0, csv::Position::line),
                format!("malformed CSV: {e}"),
            )
        })?;
        if !more {
            break;
        }
        let line = record.position().map_or(0, csv::Position::line);
        let mut vals: [Option<[f64; 3]>; GROUPS.len()] = [None; GROUPS.len()];
        for (gi, (g, idx)) in GROUPS.iter().zip(&index).enumerate() {
            let Some(idx) = idx else { continue };
            let cells: Vec<&str> = idx.iter().map(|&i| record.get(i).unwrap_or("")).collect();
            let empty = cells.iter().filter(|c| c.is_empty()).count();
            if empty == cells.len() {
                if !g.may_be_empty {
                    return Err(content(
                        line,
                        format!("`{}` is empty (required every row)", g.columns[0]),
                    ));
                }
                continue;
            }
            if empty > 0 {
                return Err(content(
                    line,
                    format!("{} must be all filled or all empty", g.columns.join(", ")),
                ));
            }
            let mut v = [0.0; 3];
            for (j, c) in cells.iter().enumerate() {
                let x = parse_number(c)
                    .map_err(|m| content(line, format!("`{}`: {m}", g.columns[j])))?;
                let bound = bound_of(g.kind);
                if x.abs() > bound {
                    return Err(content(
                        line,
                        format!(
                            "`{}` = {}: beyond the physical bound ±{bound} {}",
                            g.columns[j],
                            crate::scenario::num(x),
                            g.unit
                        ),
                    ));
                }
                v[j] = x;
            }
            vals[gi] = Some(v);
        }
        let get = |k: GroupKind| {
            GROUPS
                .iter()
                .position(|g| g.kind == k)
                .and_then(|i| vals[i])
        };
        let v3 = |k| get(k).map(|v| Vector3::new(v[0], v[1], v[2]));
        let t = get(GroupKind::Time).map_or(f64::NAN, |v| v[0]);
        if t < 0.0 {
            return Err(content(line, format!("`t_s` = {t}: must be >= 0")));
        }
        if t <= last_t {
            return Err(content(
                line,
                format!("time goes backwards or repeats (`t_s` = {t} s after {last_t} s)"),
            ));
        }
        last_t = t;
        let gps = v3(GroupKind::GpsPosition).map(|p| GpsFix {
            epoch_s: get(GroupKind::GpsEpoch).map_or(t, |v| v[0]),
            fix: GpsFixType::Fix3d,
            position_ned_m: p,
            velocity_ned_m_s: v3(GroupKind::GpsVelocity),
        });
        if gps.is_none() && v3(GroupKind::GpsVelocity).is_some() {
            return Err(content(
                line,
                "GPS velocity given without a GPS position".to_string(),
            ));
        }
        let (Some(f), Some(w)) = (v3(GroupKind::Accel), v3(GroupKind::Gyro)) else {
            return Err(content(line, "IMU cells missing".to_string()));
        };
        rows.push(SensorLogRow {
            frame: SensorFrame {
                t_s: t,
                imu: ImuSample {
                    specific_force_body_m_s2: f,
                    gyro_body_rad_s: w,
                },
                mag_body: v3(GroupKind::Mag),
                gps,
            },
            truth: LoggedTruth {
                position_ned_m: v3(GroupKind::TruePosition),
                velocity_ned_m_s: v3(GroupKind::TrueVelocity),
                acceleration_ned_m_s2: v3(GroupKind::TrueAcceleration),
                euler_rad: v3(GroupKind::TrueEuler),
                rates_body_rad_s: v3(GroupKind::TrueRates),
            },
        });
    }
    if rows.len() < 2 {
        return Err(content(0, "fewer than two data rows".to_string()));
    }
    Ok(SensorLog {
        file: path.to_path_buf(),
        rows,
        has,
    })
}

/// Check the log is uniformly sampled (every step within 10 % of the mean,
/// as the navigation's fixed-step filter needs); returns the mean step (s).
pub fn uniform_step_s(log: &SensorLog) -> Result<f64, SensorLogError> {
    let mean = log.mean_dt_s();
    for (i, pair) in log.rows.windows(2).enumerate() {
        let dt = pair[1].frame.t_s - pair[0].frame.t_s;
        if (dt / mean - 1.0).abs() > 0.1 {
            return Err(SensorLogError::Content {
                file: log.file.display().to_string(),
                line: 0,
                message: format!(
                    "data row {}: time step {dt} s deviates more than 10% from the mean step \
                     {mean} s (the navigation filter needs uniform sampling)",
                    i + 2
                ),
            });
        }
    }
    Ok(mean)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strict_numbers() {
        assert_eq!(parse_number("1.5e-3"), Ok(1.5e-3));
        assert_eq!(parse_number("-2"), Ok(-2.0));
        for bad in ["0.", "1.e5", ".5", "NaN", "inf", "abc", "1e999", "", "0x10"] {
            assert!(parse_number(bad).is_err(), "{bad}");
        }
    }
}
