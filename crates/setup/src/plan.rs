//! The flight plan a scenario or a mission file flies: the trim it starts
//! from (`[trim]`: velocity and heading), `[[reference]]` steps and ramps on
//! `vn`, `ve`, `vd`, `psi`, or the jerk-limited `[trajectory]` (legs of
//! speed, yaw rate and down velocity on
//! [`helicon_core::trajectory::Mission`]), their limits and checks, and the
//! [`ReferenceSchedule`] the flight loop reads without allocating. The
//! simulator's scenarios and the on-board program's mission files share it.
//!
//! ```toml
//! [trim]
//! velocity_ned_m_s = [0.0, 0.0, 0.0]
//! yaw_rad = 0.0
//! [[reference]]                 # steps (ramp_s = 0) or ramps on vn, ve, vd, psi
//! t_s = 1.0
//! output = "vn"
//! value = 2.0
//! ```
//!
//! or, instead of `[[reference]]`:
//!
//! ```toml
//! [trajectory]
//! max_accel_m_s2 = 1.0          # speed channel: |dV/dt| and |d²V/dt²|
//! max_jerk_m_s3 = 0.5
//! [[trajectory.speed]]          # ground speed along the heading (m/s)
//! t_s = 5.0
//! value = 15.0
//! ```
//!
//! Each trajectory channel starts at the trim (speed: the trim's forward
//! speed; yaw rate 0; down: the trim's down velocity) and moves to each
//! leg's value along the time-optimal S-curve; a leg must start after the
//! previous one of its channel has arrived.

use helicon_config::ConfigError;
use helicon_core::schedule::heading_axes;
use helicon_core::trajectory::{Channel, MAX_LEGS, Mission};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// A number for a message (shortest round-trip text).
fn num(v: f64) -> String {
    helicon_config::format_number(v)
}

/// Output names of the metrics, in order.
pub const OUTPUTS: [&str; 4] = ["vn", "ve", "vd", "psi"];

/// Largest |velocity| of a trim or reference (m/s): a miniature helicopter
/// flies well below 50 m/s; 100 m/s leaves room for hostile-but-finite
/// studies while every metric (squared errors over a day) stays finite.
pub const MAX_SPEED_M_S: f64 = 100.0;

/// Largest |heading| of a trim or reference (rad): about 16 turns, room for
/// multi-turn heading ramps (the heading is unwrapped) while the yaw error
/// metrics stay finite.
pub const MAX_HEADING_RAD: f64 = 100.0;

const SPEED_RULE: &str = "must be finite and within +-100 m/s (MAX_SPEED_M_S)";
const HEADING_RULE: &str = "must be finite and within +-100 rad (about 16 turns)";

/// The trim the controller is designed at (and the initial condition's base).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrimSection {
    /// Inertial velocity NED (m/s).
    pub velocity_ned_m_s: [f64; 3],
    /// Heading (rad).
    pub yaw_rad: f64,
}

impl Default for TrimSection {
    fn default() -> Self {
        TrimSection {
            velocity_ned_m_s: [0.0; 3],
            yaw_rad: 0.0,
        }
    }
}

/// A reference change on one output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceChange {
    /// Start time (s).
    pub t_s: f64,
    /// Output: `vn`, `ve`, `vd` (NED velocity, m/s) or `psi` (rad).
    pub output: String,
    /// New value (absolute).
    pub value: f64,
    /// Ramp duration (s); 0 for a step.
    #[serde(default)]
    pub ramp_s: f64,
}

/// Largest |yaw rate| of a trajectory leg (rad/s): a standard-rate turn is
/// 0.05 rad/s; 2 rad/s is far beyond any coordinated turn.
pub const MAX_YAW_RATE_RAD_S: f64 = 2.0;

/// One leg of a channel: at `t_s` start moving to `value`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LegSection {
    /// Start time (s).
    pub t_s: f64,
    /// Target value (m/s or rad/s).
    pub value: f64,
}

/// The `[trajectory]` section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrajectorySection {
    /// Speed channel: largest |acceleration| (m/s²).
    pub max_accel_m_s2: f64,
    /// Speed channel: largest |jerk| (m/s³).
    pub max_jerk_m_s3: f64,
    /// Yaw-rate channel: largest |yaw acceleration| (rad/s²).
    pub max_yaw_accel_rad_s2: f64,
    /// Yaw-rate channel: largest |yaw jerk| (rad/s³).
    pub max_yaw_jerk_rad_s3: f64,
    /// Down channel: largest |vertical acceleration| (m/s²).
    pub max_vertical_accel_m_s2: f64,
    /// Down channel: largest |vertical jerk| (m/s³).
    pub max_vertical_jerk_m_s3: f64,
    /// Ground-speed legs.
    pub speed: Vec<LegSection>,
    /// Yaw-rate legs.
    pub yaw_rate: Vec<LegSection>,
    /// Down-velocity legs.
    pub down: Vec<LegSection>,
}

impl Default for TrajectorySection {
    fn default() -> Self {
        TrajectorySection {
            max_accel_m_s2: 1.0,
            max_jerk_m_s3: 0.5,
            max_yaw_accel_rad_s2: 0.05,
            max_yaw_jerk_rad_s3: 0.05,
            max_vertical_accel_m_s2: 0.5,
            max_vertical_jerk_m_s3: 0.5,
            speed: Vec::new(),
            yaw_rate: Vec::new(),
            down: Vec::new(),
        }
    }
}

impl TrajectorySection {
    /// The mission starting from the trim; errors name the file and the
    /// field.
    pub fn mission(&self, trim: &TrimSection, file: &str) -> Result<Mission, ConfigError> {
        let t = trim;
        let v = heading_axes(t.yaw_rad, &Vector3::from(t.velocity_ned_m_s));
        if v.y.abs() > 1e-9 {
            return Err(ConfigError::invalid(
                file,
                "trim.velocity_ned_m_s",
                v.y,
                "with [trajectory] the trim velocity must point along the heading \
                 (the trajectory starts from the trim's forward speed)",
            ));
        }
        let channel = |field: &'static str,
                       initial: f64,
                       legs: &[LegSection],
                       limit: f64,
                       rate: f64,
                       jerk: f64|
         -> Result<Channel, ConfigError> {
            for (i, l) in legs.iter().enumerate() {
                if !(l.t_s.is_finite() && l.t_s >= 0.0) {
                    return Err(ConfigError::invalid(
                        file,
                        format!("trajectory.{field}[{i}].t_s"),
                        l.t_s,
                        "must be finite and >= 0 s",
                    ));
                }
                if !(l.value.is_finite() && l.value.abs() <= limit) {
                    return Err(ConfigError::invalid(
                        file,
                        format!("trajectory.{field}[{i}].value"),
                        l.value,
                        format!("must be finite and within +-{}", num(limit)),
                    ));
                }
            }
            if legs.len() > MAX_LEGS {
                return Err(ConfigError::invalid(
                    file,
                    format!("trajectory.{field}"),
                    legs.len() as f64,
                    "at most 32 legs",
                ));
            }
            let pairs: Vec<(f64, f64)> = legs.iter().map(|l| (l.t_s, l.value)).collect();
            Channel::new(field, initial, &pairs, rate, jerk).map_err(|e| ConfigError::Invalid {
                file: file.to_string(),
                field: format!("trajectory.{field}"),
                value: format!("{} legs", legs.len()),
                rule: e.to_string(),
            })
        };
        for (f, v) in [
            ("trajectory.max_accel_m_s2", self.max_accel_m_s2),
            ("trajectory.max_jerk_m_s3", self.max_jerk_m_s3),
            ("trajectory.max_yaw_accel_rad_s2", self.max_yaw_accel_rad_s2),
            ("trajectory.max_yaw_jerk_rad_s3", self.max_yaw_jerk_rad_s3),
            (
                "trajectory.max_vertical_accel_m_s2",
                self.max_vertical_accel_m_s2,
            ),
            (
                "trajectory.max_vertical_jerk_m_s3",
                self.max_vertical_jerk_m_s3,
            ),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= 100.0) {
                return Err(ConfigError::invalid(
                    file,
                    f,
                    v,
                    "must be finite, > 0 and <= 100",
                ));
            }
        }
        Ok(Mission {
            speed_m_s: channel(
                "speed",
                v.x,
                &self.speed,
                MAX_SPEED_M_S,
                self.max_accel_m_s2,
                self.max_jerk_m_s3,
            )?,
            yaw_rate_rad_s: channel(
                "yaw_rate",
                0.0,
                &self.yaw_rate,
                MAX_YAW_RATE_RAD_S,
                self.max_yaw_accel_rad_s2,
                self.max_yaw_jerk_rad_s3,
            )?,
            down_m_s: channel(
                "down",
                v.z,
                &self.down,
                MAX_SPEED_M_S,
                self.max_vertical_accel_m_s2,
                self.max_vertical_jerk_m_s3,
            )?,
            yaw0_rad: t.yaw_rad,
        })
    }
}

/// Reference changes sorted by time (a scenario's or a mission file's).
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceSchedule {
    start: [f64; 4],
    /// (t_s, output index, value, ramp_s), sorted by time.
    changes: Vec<(f64, usize, f64, f64)>,
    /// The `[trajectory]` mission, which replaces the changes.
    mission: Option<helicon_core::trajectory::Mission>,
}

impl ReferenceSchedule {
    /// The schedule of a flight plan: starting from the trim's velocity and
    /// heading, `reference` sorted by time, or the `[trajectory]` mission
    /// (checked beforehand with [`TrajectorySection::mission`]).
    pub fn new(
        trim: &TrimSection,
        reference: &[ReferenceChange],
        trajectory: Option<&TrajectorySection>,
    ) -> Self {
        let mut changes: Vec<(f64, usize, f64, f64)> = reference
            .iter()
            .map(|c| {
                (
                    c.t_s,
                    // `check_references` (every load and override) refuses an
                    // output not in OUTPUTS: the fallback is never taken on a file
                    OUTPUTS.iter().position(|o| *o == c.output).unwrap_or(0),
                    c.value,
                    c.ramp_s,
                )
            })
            .collect();
        changes.sort_by(|a, b| a.0.total_cmp(&b.0));
        let t = trim;
        ReferenceSchedule {
            start: [
                t.velocity_ned_m_s[0],
                t.velocity_ned_m_s[1],
                t.velocity_ned_m_s[2],
                t.yaw_rad,
            ],
            changes,
            // checked with the plan (`TrajectorySection::mission`)
            mission: trajectory.and_then(|tr| tr.mission(trim, "").ok()),
        }
    }

    /// The reference (vn, ve, vd, psi) at time `t_s`: each change ramps (or
    /// steps) from the value before it, or the `[trajectory]` mission's
    /// jerk-limited reference. Does not allocate.
    pub fn at(&self, t_s: f64) -> [f64; 4] {
        if let Some(m) = &self.mission {
            let r = m.at(t_s);
            let v = r.velocity_ned_m_s;
            return [v.x, v.y, v.z, r.yaw_rad];
        }
        let mut r = self.start;
        for &(t0, i, value, ramp) in &self.changes {
            if t_s < t0 {
                break;
            }
            let frac = if ramp > 0.0 {
                ((t_s - t0) / ramp).min(1.0)
            } else {
                1.0
            };
            r[i] += frac * (value - r[i]);
        }
        r
    }
}

/// Check the trim section (its velocity and heading within the limits);
/// errors name `file` and the field.
pub fn check_trim(trim: &TrimSection, file: &str) -> Result<(), ConfigError> {
    let bad = |field: &str, value: String, rule: &str| ConfigError::Invalid {
        file: file.to_string(),
        field: field.to_string(),
        value,
        rule: rule.to_string(),
    };
    for (i, v) in trim.velocity_ned_m_s.iter().enumerate() {
        if !(v.is_finite() && v.abs() <= MAX_SPEED_M_S) {
            return Err(bad(
                &format!("trim.velocity_ned_m_s[{i}]"),
                num(*v),
                SPEED_RULE,
            ));
        }
    }
    if !(trim.yaw_rad.is_finite() && trim.yaw_rad.abs() <= MAX_HEADING_RAD) {
        return Err(bad("trim.yaw_rad", num(trim.yaw_rad), HEADING_RULE));
    }
    Ok(())
}

/// Check `[[reference]]` changes (output name, times, values within the
/// limits); errors name `file` and the field.
pub fn check_references(reference: &[ReferenceChange], file: &str) -> Result<(), ConfigError> {
    let bad = |field: &str, value: String, rule: &str| ConfigError::Invalid {
        file: file.to_string(),
        field: field.to_string(),
        value,
        rule: rule.to_string(),
    };
    for (i, r) in reference.iter().enumerate() {
        let field = |f: &str| format!("reference[{i}].{f}");
        if !OUTPUTS.contains(&r.output.as_str()) {
            return Err(bad(
                &field("output"),
                format!("{:?}", r.output),
                "must be vn, ve, vd or psi",
            ));
        }
        if !(r.t_s.is_finite() && r.t_s >= 0.0) {
            return Err(bad(&field("t_s"), num(r.t_s), "must be finite and >= 0 s"));
        }
        if !(r.ramp_s.is_finite() && r.ramp_s >= 0.0) {
            return Err(bad(
                &field("ramp_s"),
                num(r.ramp_s),
                "must be finite and >= 0 s",
            ));
        }
        let (limit, rule) = if r.output == "psi" {
            (MAX_HEADING_RAD, HEADING_RULE)
        } else {
            (MAX_SPEED_M_S, SPEED_RULE)
        };
        if !(r.value.is_finite() && r.value.abs() <= limit) {
            return Err(bad(&field("value"), num(r.value), rule));
        }
    }
    Ok(())
}
