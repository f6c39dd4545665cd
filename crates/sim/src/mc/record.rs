//! What one run produces: its `runs.csv` row (with its typed outcome and
//! termination) and its trace.

use super::campaign::dispersion_key_known;
use crate::closed_loop::{Outcome, Termination};
use serde::{Deserialize, Serialize};

/// Metric columns of `runs.csv` (after the fixed columns and the dispersed values).
pub const METRIC_NAMES: [&str; 20] = [
    "vn_settling_s",
    "vn_overshoot_pct",
    "vn_rms",
    "vn_max_abs",
    "ve_settling_s",
    "ve_overshoot_pct",
    "ve_rms",
    "ve_max_abs",
    "vd_settling_s",
    "vd_overshoot_pct",
    "vd_rms",
    "vd_max_abs",
    "psi_settling_s",
    "psi_overshoot_pct",
    "psi_rms",
    "psi_max_abs",
    "effort_rms_S_col",
    "effort_rms_S_lat",
    "effort_rms_S_lon",
    "effort_rms_S_tr",
];

/// The ground metrics of a campaign whose scenario has `[ground]`: more
/// columns of `runs.csv` after [`METRIC_NAMES`], and more values of a
/// record's `metrics`, in this order (the fields of
/// [`GroundMetrics`](crate::ground::GroundMetrics); empty when the flight
/// had none, e.g. no touchdown).
pub const GROUND_METRIC_NAMES: [&str; 14] = [
    "liftoff_time_s",
    "liftoff_drift_m",
    "liftoff_omega_rad_s",
    "touchdown_time_s",
    "touchdown_vertical_speed_m_s",
    "touchdown_horizontal_speed_m_s",
    "touchdown_offset_m",
    "touchdown_drift_m",
    "touchdown_peak_normal_n",
    "max_tilt_on_ground_rad",
    "final_omega_rad_s",
    "takeoff_start_s",
    "arm_to_liftoff_s",
    "liftoff_detected_s",
];

/// The metric names of a record: [`METRIC_NAMES`], then
/// [`GROUND_METRIC_NAMES`] for a campaign with `[ground]`.
pub fn metric_names(ground: bool) -> impl Iterator<Item = &'static str> {
    let g = if ground { GROUND_METRIC_NAMES.len() } else { 0 };
    METRIC_NAMES
        .iter()
        .chain(GROUND_METRIC_NAMES.iter().take(g))
        .copied()
}

/// The number of metrics of a record ([`metric_names`]).
pub fn metric_count(ground: bool) -> usize {
    METRIC_NAMES.len() + if ground { GROUND_METRIC_NAMES.len() } else { 0 }
}

/// The ground metrics of a flight as record values, in
/// [`GROUND_METRIC_NAMES`] order.
pub fn ground_values(m: &crate::ground::GroundMetrics) -> [Option<f64>; 14] {
    [
        m.liftoff_time_s,
        m.liftoff_drift_m,
        m.liftoff_omega_rad_s,
        m.touchdown_time_s,
        m.touchdown_vertical_speed_m_s,
        m.touchdown_horizontal_speed_m_s,
        m.touchdown_offset_m,
        m.touchdown_drift_m,
        m.touchdown_peak_normal_n,
        Some(m.max_tilt_on_ground_rad),
        Some(m.final_omega_rad_s),
        m.takeoff_start_s,
        m.arm_to_liftoff_s,
        m.liftoff_detected_s,
    ]
}

/// How a run ended, in one word (the `outcome` column of `runs.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RunOutcome {
    /// Flew the whole duration.
    Completed,
    /// The flight stopped early (attitude, rate, heading, non-finite state,
    /// model or navigation failure).
    Diverged,
    /// A drawn parameter broke a parameter rule (the run was not flown).
    Invalid,
    /// Trim, design or flight setup failed (the run was not flown), or a
    /// completed flight gave a non-finite metric.
    Error,
}

impl RunOutcome {
    /// Every outcome, in declaration order.
    pub const ALL: [RunOutcome; 4] = [
        RunOutcome::Completed,
        RunOutcome::Diverged,
        RunOutcome::Invalid,
        RunOutcome::Error,
    ];

    /// The word written in `runs.csv` and `stats.json`.
    pub fn as_str(self) -> &'static str {
        match self {
            RunOutcome::Completed => "completed",
            RunOutcome::Diverged => "diverged",
            RunOutcome::Invalid => "invalid",
            RunOutcome::Error => "error",
        }
    }
}

impl std::fmt::Display for RunOutcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for RunOutcome {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        RunOutcome::ALL
            .into_iter()
            .find(|o| o.as_str() == s)
            .ok_or_else(|| {
                format!("unknown outcome `{s}` (one of completed, diverged, invalid, error)")
            })
    }
}

impl From<Outcome> for RunOutcome {
    fn from(o: Outcome) -> Self {
        match o {
            Outcome::Completed => RunOutcome::Completed,
            // a campaign's flights are not stopped one by one (an
            // interrupted campaign resumes); were one, it ended early
            Outcome::Diverged | Outcome::Stopped => RunOutcome::Diverged,
        }
    }
}

/// The stage of a run that failed with an error (outcome `error`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorStage {
    /// Checking the drawn parameters failed other than by a broken rule.
    Parameters,
    /// Trimming the dispersed plant at the design point.
    Trim,
    /// Linearization, discretization or controller design (`design = "per-run"`).
    Design,
    /// Setting up the flight (wind, sensors, navigation filter, log size).
    FlightSetup,
    /// A completed flight whose metrics were not all finite.
    Metrics,
}

impl ErrorStage {
    /// Every stage, in declaration order.
    pub const ALL: [ErrorStage; 5] = [
        ErrorStage::Parameters,
        ErrorStage::Trim,
        ErrorStage::Design,
        ErrorStage::FlightSetup,
        ErrorStage::Metrics,
    ];

    /// The word written in the `termination` column.
    pub fn as_str(self) -> &'static str {
        match self {
            ErrorStage::Parameters => "parameters",
            ErrorStage::Trim => "trim",
            ErrorStage::Design => "design",
            ErrorStage::FlightSetup => "flight_setup",
            ErrorStage::Metrics => "metrics",
        }
    }
}

impl std::str::FromStr for ErrorStage {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        ErrorStage::ALL
            .into_iter()
            .find(|o| o.as_str() == s)
            .ok_or_else(|| {
                format!("unknown error stage `{s}` (one of parameters, trim, design, flight_setup, metrics)")
            })
    }
}

/// Why a run ended, typed: its outcome and its class (what the statistics
/// group failures by). Written as the `outcome` and `termination` columns.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RunTermination {
    /// A flight: how it ended (`completed`, or a divergence such as
    /// `rate_limit`); the outcome follows from it.
    Flight(Termination),
    /// A draw broke a parameter rule: the parameter key (`section.key`).
    InvalidDraw(String),
    /// An error: the stage that failed.
    Error(ErrorStage),
}

impl RunTermination {
    /// The run's outcome.
    pub fn outcome(&self) -> RunOutcome {
        match self {
            RunTermination::Flight(t) => t.outcome().into(),
            RunTermination::InvalidDraw(_) => RunOutcome::Invalid,
            RunTermination::Error(_) => RunOutcome::Error,
        }
    }

    /// The word written in the `termination` column: the flight's
    /// termination, the parameter key or the stage.
    pub fn as_str(&self) -> &str {
        match self {
            RunTermination::Flight(t) => t.as_str(),
            RunTermination::InvalidDraw(key) => key,
            RunTermination::Error(s) => s.as_str(),
        }
    }

    /// Read back the `termination` column of a run with `outcome`.
    pub fn parse(outcome: RunOutcome, word: &str) -> Result<RunTermination, String> {
        let t = match outcome {
            RunOutcome::Completed | RunOutcome::Diverged => {
                RunTermination::Flight(word.parse::<Termination>()?)
            }
            RunOutcome::Invalid => {
                if !dispersion_key_known(word) {
                    return Err(format!(
                        "`{word}` is not a parameter key (an invalid run names the key that broke its rule)"
                    ));
                }
                RunTermination::InvalidDraw(word.to_string())
            }
            RunOutcome::Error => RunTermination::Error(word.parse()?),
        };
        if t.outcome() != outcome {
            return Err(format!(
                "termination `{word}` is not one of a `{outcome}` run"
            ));
        }
        Ok(t)
    }
}

impl std::fmt::Display for RunTermination {
    /// `completed`, or `<outcome>: <termination>` (e.g. `diverged: rate_limit`,
    /// `invalid: body.mass_kg`, `error: trim`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunTermination::Flight(Termination::Completed) => f.write_str("completed"),
            _ => write!(f, "{}: {}", self.outcome(), self.as_str()),
        }
    }
}

/// One row of `runs.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct RunRecord {
    /// Run index.
    pub index: usize,
    /// Wind seed.
    pub wind_seed: u64,
    /// Sensor seed.
    pub sensor_seed: u64,
    /// Dispersed values.
    pub values: Vec<f64>,
    /// How it ended (its outcome is [`RunRecord::outcome`]).
    pub termination: RunTermination,
    /// Why it failed, as a sentence with times and values (empty when completed).
    pub reason: String,
    /// Time reached (s).
    pub t_end_s: f64,
    /// Metrics in [`METRIC_NAMES`] order, then, for a campaign with
    /// `[ground]`, [`GROUND_METRIC_NAMES`] (`None`: not settled / not flown
    /// / no such event; never a non-finite number).
    pub metrics: Vec<Option<f64>>,
}

impl RunRecord {
    /// The run's outcome.
    pub fn outcome(&self) -> RunOutcome {
        self.termination.outcome()
    }

    /// Did it fly the whole duration?
    pub fn completed(&self) -> bool {
        self.outcome() == RunOutcome::Completed
    }
}

/// One kept sample of a run's outputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TracePoint {
    /// Time (s).
    pub t_s: f64,
    /// vn, ve, vd (m/s), ψ (rad).
    pub output: [f64; 4],
}

/// What a run produces.
#[derive(Debug, Clone)]
pub struct RunOutput {
    /// Its row.
    pub record: RunRecord,
    /// Its outputs at the trace rate.
    pub trace: Vec<TracePoint>,
}

impl Serialize for RunTermination {
    /// As its `termination` word (the outcome is written next to it).
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}
