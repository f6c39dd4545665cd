//! A flight log as the simulator's `log.csv` columns: the on-board ULog read
//! onto the control task's sample grid, under the names `helicon sim` writes
//! (`t_s`, `S_col` … `S_tr`, `exc_*`, `meas_*`, `est_*`, `ref_*`, the IMU
//! health), so that identification takes a real flight's log where it takes
//! a simulated one.
//!
//! # The rule
//!
//! - **Time base**: the `control` topic (one record per control step,
//!   stamped with the time of the measurement the step used). The nominal
//!   period T is the one given (the parameters' `control.sample_time_s`) or,
//!   without one, the median step of the `control` timestamps; a median step
//!   further than the jitter tolerance from the period given is refused (a
//!   log decimated, or flown at another rate).
//! - **Jitter**: each step between consecutive `control` records must lie
//!   within ±[`JITTER_FRACTION`]·T of a whole number m ≥ 1 of periods;
//!   sample k is then placed at t₀ + n_k·T (n advancing by m), so the record
//!   handed on is uniform. A step further from the grid, or one that goes
//!   back in time, is refused naming its time; two records with the same
//!   time (a sample written twice) are refused as such.
//! - **Dropped samples**: m − 1 samples are missing after a step of m
//!   periods. Up to [`MAX_MISSING`] in a row are filled by linear
//!   interpolation between their neighbours (as `helicon ident frf` does for
//!   an irregular CSV); more are refused naming the time and the count (the
//!   spectra cannot bridge a drop-out: cut the log there).
//! - **Other topics**: sample and hold. A record of a topic stamped on the
//!   step's clock ([`STEP_CLOCK_TOPICS`]: `excitation`, `servo_output`)
//!   takes the time of the `control` record before it in the file (the
//!   runtime writes a step's records together, `control` first); the others
//!   (`imu_health`, `estimator_bias`) keep their own timestamps, on the
//!   measurement's clock. At each control sample a column takes its topic's
//!   latest record so timed at or before the sample's time plus T/2
//!   ([`ALIGN_FRACTION`]). A held record older than ([`MAX_MISSING`] + 1)·T is
//!   refused (the topic stopped being logged), naming the topic and the time.
//!   The record starts at the first control sample at which every topic
//!   asked for has a record ([`UlogColumns::skipped_start`] says how many
//!   control samples came before).
//!
//! Every value must be finite: a NaN or an infinity is refused naming the
//! file, the topic, the field and the time. A log cut short (a flight
//! computer that lost power) gives everything before the cut
//! ([`UlogColumns::truncated_at`]).

use crate::error::ReadError;
use crate::reader::{UlogReader, Value};
use crate::visit::{End, Event, visit};
use std::collections::BTreeSet;
use std::path::Path;

/// A step between control samples may differ from a whole number of periods
/// by this fraction of the period.
pub const JITTER_FRACTION: f64 = 0.1;

/// At most this many control samples in a row may be missing (filled by
/// linear interpolation); a longer drop-out is refused.
pub const MAX_MISSING: usize = 4;

/// A record of another topic belongs to a control sample when stamped at or
/// before the sample's time plus this fraction of the period.
pub const ALIGN_FRACTION: f64 = 0.5;

/// The topic whose records are the time base.
pub const TIME_BASE_TOPIC: &str = "control";

/// Topics the runtime writes in the control step after its `control` record
/// and stamps with the step's own clock (the wake-up time), not the
/// measurement's: they belong to the `control` record before them in the
/// file. (Under real time the two clocks differ: 4.7 ms measured in a
/// real-time SITL flight, nearly two periods.)
pub const STEP_CLOCK_TOPICS: [&str; 2] = ["excitation", "servo_output"];

/// One `log.csv` column and where it comes from in the flight log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UlogColumn {
    /// The `log.csv` column name.
    pub name: &'static str,
    /// The ULog topic (instance 0).
    pub topic: &'static str,
    /// The flattened field (`command[0]`).
    pub field: &'static str,
}

const fn c(name: &'static str, topic: &'static str, field: &'static str) -> UlogColumn {
    UlogColumn { name, topic, field }
}

/// The `log.csv` columns a flight log provides (besides `t_s`, the control
/// grid), each with its topic and field. The names are those of
/// `helicon_sim::log_csv::LOG_SCHEMA` with the same units and meaning.
pub static ULOG_COLUMNS: [UlogColumn; 38] = [
    // servo commands after saturation, as the law sent them
    c("S_col", "control", "command[0]"),
    c("S_lat", "control", "command[1]"),
    c("S_lon", "control", "command[2]"),
    c("S_tr", "control", "command[3]"),
    // references
    c("ref_vn", "control", "ref_vel_ned_m_s[0]"),
    c("ref_ve", "control", "ref_vel_ned_m_s[1]"),
    c("ref_vd", "control", "ref_vel_ned_m_s[2]"),
    c("ref_psi", "control", "ref_yaw_rad"),
    // the estimate of the nine measured states (15.2)
    c("est_phi", "control", "estimate[0]"),
    c("est_theta", "control", "estimate[1]"),
    c("est_psi", "control", "estimate[2]"),
    c("est_u", "control", "estimate[3]"),
    c("est_v", "control", "estimate[4]"),
    c("est_w", "control", "estimate[5]"),
    c("est_p", "control", "estimate[6]"),
    c("est_q", "control", "estimate[7]"),
    c("est_r", "control", "estimate[8]"),
    // the measurements the estimator was given
    c("meas_phi", "control", "measured[0]"),
    c("meas_theta", "control", "measured[1]"),
    c("meas_psi", "control", "measured[2]"),
    c("meas_u", "control", "measured[3]"),
    c("meas_v", "control", "measured[4]"),
    c("meas_w", "control", "measured[5]"),
    c("meas_p", "control", "measured[6]"),
    c("meas_q", "control", "measured[7]"),
    c("meas_r", "control", "measured[8]"),
    // the IMU health monitor
    c("imu_vib_rms_m_s2", "imu_health", "vibration_rms_m_s2"),
    c(
        "imu_gravity_residual_m_s2",
        "imu_health",
        "gravity_residual_m_s2",
    ),
    c("imu_health_flags", "imu_health", "flags"),
    // the servo excitation added before saturation ([[excitation]])
    c("exc_col", "excitation", "offset[0]"),
    c("exc_lat", "excitation", "offset[1]"),
    c("exc_lon", "excitation", "offset[2]"),
    c("exc_tr", "excitation", "offset[3]"),
    // estimated IMU biases (the ESKF), body axes; not in a simulator's log.csv
    c("bias_gyro_x_rad_s", "estimator_bias", "gyro_rad_s[0]"),
    c("bias_gyro_y_rad_s", "estimator_bias", "gyro_rad_s[1]"),
    c("bias_gyro_z_rad_s", "estimator_bias", "gyro_rad_s[2]"),
    // the command the servos got and who decided it (0 law, 1 pilot, 2 failsafe)
    c("servo_source", "servo_output", "source"),
    // the excitation runs (1) or not (0)
    c("exc_active", "excitation", "active"),
];

/// The column `name` of [`ULOG_COLUMNS`].
pub fn ulog_column(name: &str) -> Option<&'static UlogColumn> {
    ULOG_COLUMNS.iter().find(|c| c.name == name)
}

/// Why a flight log cannot be read as columns. Each names the file; those
/// about data name the topic, the field and the time.
#[derive(Debug, thiserror::Error)]
pub enum ColumnsError {
    /// The log could not be read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// A column name this reader does not provide.
    #[error("{file}: no column `{name}` in a flight log (it provides: {known})")]
    UnknownColumn {
        /// The log.
        file: String,
        /// The name asked for.
        name: String,
        /// The names provided.
        known: String,
    },
    /// The log has no records of a topic a column needs.
    #[error("{file}: no `{topic}` records (column `{column}` comes from `{topic}.{field}`){hint}")]
    MissingTopic {
        /// The log.
        file: String,
        /// The topic.
        topic: String,
        /// Its field.
        field: String,
        /// The column asked for.
        column: String,
        /// What logs it.
        hint: &'static str,
    },
    /// The topic's format lacks a field.
    #[error("{file}: topic `{topic}` has no field `{field}` (column `{column}`)")]
    MissingField {
        /// The log.
        file: String,
        /// The topic.
        topic: String,
        /// The field.
        field: String,
        /// The column asked for.
        column: String,
    },
    /// A value that is not a finite number.
    #[error("{file}: `{topic}.{field}` at t = {time_s} s is {value}: not a finite number")]
    NotFinite {
        /// The log.
        file: String,
        /// The topic.
        topic: String,
        /// The field.
        field: String,
        /// Time of the record, s.
        time_s: f64,
        /// The value as text.
        value: String,
    },
    /// The records of a topic go back in time.
    #[error("{file}: `{topic}` goes back in time at t = {time_s} s (after {previous_s} s)")]
    Backwards {
        /// The log.
        file: String,
        /// The topic.
        topic: String,
        /// Time of the record, s.
        time_s: f64,
        /// Time of the record before, s.
        previous_s: f64,
    },
    /// Two records of a topic with the same timestamp where each must
    /// have its own (`control`: one record per control step): a logger
    /// that wrote a sample twice.
    #[error(
        "{file}: `{topic}` has two records stamped t = {time_s} s: a sample written twice (a logger fault), not a step of the control task"
    )]
    Duplicate {
        /// The log.
        file: String,
        /// The topic.
        topic: String,
        /// The time both records carry, s.
        time_s: f64,
    },
    /// A control step off the sample grid.
    #[error(
        "{file}: `control` step of {step_s} s at t = {time_s} s is not a whole number of control periods {period_s} s within ±{tolerance} of a period (the control task's clock is off)"
    )]
    Jitter {
        /// The log.
        file: String,
        /// Time of the record ending the step, s.
        time_s: f64,
        /// The step, s.
        step_s: f64,
        /// The period, s.
        period_s: f64,
        /// The tolerance (fraction of the period).
        tolerance: f64,
    },
    /// Too many control samples missing in a row.
    #[error(
        "{file}: {missing} control samples missing before t = {time_s} s (after {previous_s} s; at most {max} are bridged): a drop-out the spectra cannot bridge; use the part before or after it"
    )]
    Gap {
        /// The log.
        file: String,
        /// Time of the record after the gap, s.
        time_s: f64,
        /// Time of the record before the gap, s.
        previous_s: f64,
        /// Samples missing.
        missing: usize,
        /// The most bridged.
        max: usize,
    },
    /// A topic that stopped being logged.
    #[error(
        "{file}: `{topic}` has no record in the {age_s} s before the control sample at t = {time_s} s (at most {max_s} s): the topic stopped being logged"
    )]
    Stale {
        /// The log.
        file: String,
        /// The topic.
        topic: String,
        /// Time of the control sample, s.
        time_s: f64,
        /// Age of the newest record, s.
        age_s: f64,
        /// The most accepted, s.
        max_s: f64,
    },
    /// Not enough samples, or a nominal period that is not a time.
    #[error("{file}: {rule}")]
    Record {
        /// The log.
        file: String,
        /// What is wrong.
        rule: String,
    },
}

/// A flight log read onto the control grid.
#[derive(Debug, Clone, PartialEq)]
pub struct UlogColumns {
    /// The log.
    pub file: String,
    /// The control period used, s.
    pub period_s: f64,
    /// Column names: `t_s` first, then those asked for.
    pub names: Vec<String>,
    /// The columns, one value per grid sample, in the order of `names`.
    pub columns: Vec<Vec<f64>>,
    /// Control samples before the first at which every topic asked for had
    /// a record (left out).
    pub skipped_start: usize,
    /// Dropped samples filled: (time of the first missing sample, count).
    pub filled: Vec<(f64, usize)>,
    /// The largest distance of a control record from its grid time, s.
    pub max_jitter_s: f64,
    /// The byte offset where a log cut short ends.
    pub truncated_at: Option<u64>,
}

impl UlogColumns {
    /// The column `name`, if read.
    pub fn get(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|j| self.columns[j].as_slice())
    }

    /// One line per thing a user should know about the reading (samples
    /// skipped, filled, a cut), for a tool to print (the period and
    /// [`max_jitter_s`](Self::max_jitter_s) are the tool's to word).
    pub fn notes(&self) -> Vec<String> {
        let mut out = Vec::new();
        let f = &self.file;
        if self.skipped_start > 0 {
            out.push(format!(
                "{f}: the first {} control samples left out (before every topic asked for had a record)",
                self.skipped_start
            ));
        }
        for (t, n) in self.filled.iter().take(10) {
            out.push(format!(
                "{f}: {n} control sample(s) missing from t = {t} s, filled by linear interpolation"
            ));
        }
        if self.filled.len() > 10 {
            let all: usize = self.filled.iter().map(|g| g.1).sum();
            out.push(format!(
                "{f}: … and {} more drop-outs ({all} samples filled in all, {:.2} % of the record)",
                self.filled.len() - 10,
                100.0 * all as f64 / self.columns.first().map_or(1, Vec::len).max(1) as f64
            ));
        }
        if let Some(at) = self.truncated_at {
            out.push(format!(
                "{f}: the log is cut short at byte {at}: read up to there"
            ));
        }
        out
    }
}

/// The names a log at `path` can give: `t_s` and the columns of
/// [`ULOG_COLUMNS`] whose topic has records (the runtime subscribes every
/// topic; a flight without `[[excitation]]` logs no `excitation` record).
/// The file is read until a record of every topic of [`ULOG_COLUMNS`] has
/// been seen (within the first control steps of a flight that logs them
/// all), else to its end; a fault after that point is left to the reading
/// of the columns to report.
pub fn available_columns(path: &Path) -> Result<Vec<&'static str>, ColumnsError> {
    /// Why the pass ended early: a read error, or every topic seen.
    enum Stop {
        Read(ReadError),
        AllSeen,
    }
    impl From<ReadError> for Stop {
        fn from(e: ReadError) -> Stop {
            Stop::Read(e)
        }
    }
    // every topic a column comes from, the time base among them
    let mut all: Vec<&'static str> = ULOG_COLUMNS.iter().map(|c| c.topic).collect();
    all.sort_unstable();
    all.dedup();
    let mut topics: BTreeSet<&'static str> = BTreeSet::new();
    let pass = visit::<_, Stop>(open(path)?, |e| {
        if let Event::Data { topic, .. } = e
            && topic.multi_id == 0
            && let Some(t) = all.iter().find(|t| **t == topic.name)
            && topics.insert(t)
            && topics.len() == all.len()
        {
            return Err(Stop::AllSeen);
        }
        Ok(())
    });
    match pass {
        Ok(_) | Err(Stop::AllSeen) => {}
        Err(Stop::Read(e)) => return Err(e.into()),
    }
    let mut out = Vec::new();
    if topics.contains(TIME_BASE_TOPIC) {
        out.push("t_s");
    }
    out.extend(
        ULOG_COLUMNS
            .iter()
            .filter(|c| topics.contains(c.topic))
            .map(|c| c.name),
    );
    Ok(out)
}

fn open(path: &Path) -> Result<crate::reader::FileReader, ReadError> {
    UlogReader::open(path)
}

/// The records of one topic: timestamps (µs) and the fields asked for.
struct TopicData {
    name: &'static str,
    fields: Vec<&'static str>,
    /// Column index of each field in the subscription's format.
    index: Option<Vec<usize>>,
    /// The format `index` was found in (a topic subscribed again with the
    /// same format is not searched again).
    indexed: Option<std::sync::Arc<crate::flat::FlatFormat>>,
    t_us: Vec<u64>,
    /// The fields of every record, record after record (`fields.len()` a
    /// record): one growing buffer, no allocation per record.
    values: Vec<f64>,
}

impl TopicData {
    fn new(name: &'static str) -> TopicData {
        TopicData {
            name,
            fields: Vec::new(),
            index: None,
            indexed: None,
            t_us: Vec::new(),
            values: Vec::new(),
        }
    }

    /// Field `f` of record `k`.
    fn value(&self, k: usize, f: usize) -> f64 {
        self.values[k * self.fields.len() + f]
    }
}

fn as_f64(v: &Value) -> Option<f64> {
    match v {
        Value::Int(x) => Some(*x as f64),
        Value::UInt(x) => Some(*x as f64),
        Value::Float32(x) => Some(f64::from(*x)),
        Value::Float(x) => Some(*x),
        Value::Bool(b) => Some(f64::from(u8::from(*b))),
        _ => None,
    }
}

/// Read the columns `names` (any of [`ULOG_COLUMNS`]; `t_s` is always
/// given first) of the flight log at `path` onto the control grid of period
/// `period_s` (the median control step when `None`), by the rule of the
/// [module documentation](self).
pub fn read_ulog_columns(
    path: &Path,
    names: &[&str],
    period_s: Option<f64>,
) -> Result<UlogColumns, ColumnsError> {
    read_ulog_columns_with(path, names, &[], period_s)
}

/// As [`read_ulog_columns`], and also the columns `optional` whose topic
/// the log has records of (after those of `names`, in their order); one
/// whose topic has none is left out rather than refused. One pass over the
/// file: a caller need not list the log's topics first
/// ([`available_columns`]) to know what it may ask for.
pub fn read_ulog_columns_with(
    path: &Path,
    names: &[&str],
    optional: &[&str],
    period_s: Option<f64>,
) -> Result<UlogColumns, ColumnsError> {
    let file = path.display().to_string();
    let mut wanted: Vec<&'static UlogColumn> = Vec::new();
    // whether each of `wanted` was asked for in `names` (else `optional`)
    let mut required: Vec<bool> = Vec::new();
    for (n, req) in names
        .iter()
        .map(|n| (n, true))
        .chain(optional.iter().map(|n| (n, false)))
    {
        if *n == "t_s" {
            continue;
        }
        let Some(col) = ulog_column(n) else {
            return Err(ColumnsError::UnknownColumn {
                file,
                name: (*n).to_string(),
                known: std::iter::once("t_s")
                    .chain(ULOG_COLUMNS.iter().map(|c| c.name))
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        };
        if !wanted.iter().any(|w| w.name == col.name) {
            wanted.push(col);
            required.push(req);
        }
    }
    let mut topics: Vec<TopicData> = vec![TopicData::new(TIME_BASE_TOPIC)];
    let mut slot = Vec::with_capacity(wanted.len());
    for w in &wanted {
        let ti = match topics.iter().position(|t| t.name == w.topic) {
            Some(i) => i,
            None => {
                topics.push(TopicData::new(w.topic));
                topics.len() - 1
            }
        };
        topics[ti].fields.push(w.field);
        slot.push((ti, topics[ti].fields.len() - 1));
    }
    let summary = collect(path, &file, &wanted, &mut topics)?;
    for ((w, &(ti, _)), &req) in wanted.iter().zip(&slot).zip(&required) {
        if req && topics[ti].t_us.is_empty() {
            return Err(missing_topic(&file, w.topic, w.field, w.name));
        }
    }
    // what the log gives: every column asked for, the optional ones whose
    // topic has records (`align` passes over a topic without)
    let given: Vec<(&'static UlogColumn, (usize, usize))> = wanted
        .iter()
        .zip(&slot)
        .filter(|(_, (ti, _))| !topics[*ti].t_us.is_empty())
        .map(|(w, s)| (*w, *s))
        .collect();
    if topics[0].t_us.is_empty() {
        return Err(missing_topic(&file, TIME_BASE_TOPIC, "timestamp", "t_s"));
    }
    let grid = Grid::build(&file, &topics[0].t_us, period_s)?;
    let (start, held) = align(&file, &topics, &grid)?;
    let mut out = UlogColumns {
        file,
        period_s: grid.period_s,
        names: std::iter::once("t_s")
            .chain(given.iter().map(|(w, _)| w.name))
            .map(String::from)
            .collect(),
        columns: Vec::new(),
        skipped_start: start,
        filled: Vec::new(),
        max_jitter_s: grid.max_jitter_s,
        truncated_at: match summary.end {
            End::Complete => None,
            End::Truncated { offset } => Some(offset),
        },
    };
    let n0 = grid.slot[start];
    let t0 = topics[0].t_us[0] as f64 / 1e6;
    let t: Vec<f64> = (n0..=grid.slot[grid.slot.len() - 1])
        .map(|n| t0 + n as f64 * grid.period_s)
        .collect();
    if t.len() < 16 {
        return Err(ColumnsError::Record {
            file: out.file,
            rule: format!("{} control samples: at least 16 are needed", t.len()),
        });
    }
    for w in grid.slot[start..].windows(2) {
        if w[1] > w[0] + 1 {
            // to the µs, the log's resolution
            let t = ((t0 + (w[0] + 1) as f64 * grid.period_s) * 1e6).round() / 1e6;
            out.filled.push((t, w[1] - w[0] - 1));
        }
    }
    out.columns.push(t);
    for &(_, (ti, fi)) in &given {
        let at = |k: usize| -> f64 {
            if ti == 0 {
                topics[0].value(k, fi)
            } else {
                topics[ti].value(held[ti - 1][k], fi)
            }
        };
        out.columns.push(fill(&grid.slot, start, at));
    }
    Ok(out)
}

fn missing_topic(file: &str, topic: &str, field: &str, column: &str) -> ColumnsError {
    ColumnsError::MissingTopic {
        file: file.to_string(),
        topic: topic.to_string(),
        field: field.to_string(),
        column: column.to_string(),
        hint: match topic {
            "excitation" => ": logged by a flight with [[excitation]]",
            "estimator_bias" => ": logged by a navigation that estimates the IMU biases (the ESKF)",
            "imu_health" => ": logged by the on-board runtime's IMU health monitor",
            "control" => ": is this a helicon flight log?",
            _ => "",
        },
    }
}

/// One pass: the records of every topic in `topics` (instance 0), checked
/// for finiteness and order.
fn collect(
    path: &Path,
    file: &str,
    wanted: &[&'static UlogColumn],
    topics: &mut [TopicData],
) -> Result<crate::visit::PassSummary, ColumnsError> {
    // the newest `control` timestamp so far (the step of step-clock records)
    let mut step_us: Option<u64> = None;
    visit::<_, ColumnsError>(open(path)?, |e| {
        if let Event::Data {
            topic,
            timestamp_us,
            ..
        } = &e
            && topic.multi_id == 0
            && topic.name == TIME_BASE_TOPIC
        {
            step_us = Some(*timestamp_us);
        }
        match e {
            Event::Subscribed { topic, .. } if topic.multi_id == 0 => {
                let Some(td) = topics.iter_mut().find(|t| t.name == topic.name) else {
                    return Ok(());
                };
                if td
                    .indexed
                    .as_ref()
                    .is_some_and(|f| std::sync::Arc::ptr_eq(f, &topic.format))
                {
                    return Ok(());
                }
                let mut index = Vec::with_capacity(td.fields.len());
                for f in &td.fields {
                    let Some(i) = topic.format.columns.iter().position(|c| c.name == *f) else {
                        let column = wanted
                            .iter()
                            .find(|w| w.topic == td.name && w.field == *f)
                            .map_or("", |w| w.name);
                        return Err(ColumnsError::MissingField {
                            file: file.to_string(),
                            topic: td.name.to_string(),
                            field: (*f).to_string(),
                            column: column.to_string(),
                        });
                    };
                    index.push(i);
                }
                td.index = Some(index);
                td.indexed = Some(std::sync::Arc::clone(&topic.format));
            }
            Event::Data {
                topic,
                payload,
                timestamp_us,
                ..
            } if topic.multi_id == 0 => {
                let Some(td) = topics.iter_mut().find(|t| t.name == topic.name) else {
                    return Ok(());
                };
                let Some(index) = &td.index else {
                    return Ok(());
                };
                let timestamp_us = if STEP_CLOCK_TOPICS.contains(&td.name) {
                    // before the first control step: no sample to belong to
                    let Some(step) = step_us else { return Ok(()) };
                    step
                } else {
                    timestamp_us
                };
                let time_s = timestamp_us as f64 / 1e6;
                if let Some(&prev) = td.t_us.last()
                    && timestamp_us < prev
                {
                    return Err(ColumnsError::Backwards {
                        file: file.to_string(),
                        topic: td.name.to_string(),
                        time_s,
                        previous_s: prev as f64 / 1e6,
                    });
                }
                for (f, &i) in td.fields.iter().zip(index) {
                    let v = topic.format.value(payload, i);
                    match v.as_ref().and_then(as_f64) {
                        Some(x) if x.is_finite() => td.values.push(x),
                        _ => {
                            return Err(ColumnsError::NotFinite {
                                file: file.to_string(),
                                topic: td.name.to_string(),
                                field: (*f).to_string(),
                                time_s,
                                value: v.map_or_else(|| "absent".into(), |v| v.to_string()),
                            });
                        }
                    }
                }
                td.t_us.push(timestamp_us);
            }
            _ => {}
        }
        Ok(())
    })
}

/// The control records on the sample grid.
struct Grid {
    period_s: f64,
    /// Grid index of each control record.
    slot: Vec<usize>,
    max_jitter_s: f64,
    /// Control timestamps, s.
    t_s: Vec<f64>,
}

impl Grid {
    fn build(file: &str, t_us: &[u64], period_s: Option<f64>) -> Result<Grid, ColumnsError> {
        let t_s: Vec<f64> = t_us.iter().map(|t| *t as f64 / 1e6).collect();
        if t_s.len() < 2 {
            return Err(ColumnsError::Record {
                file: file.to_string(),
                rule: format!("{} `control` record(s): at least 16 are needed", t_s.len()),
            });
        }
        // `collect` refused a stamp going back; one repeated is refused here
        if let Some(w) = t_us.windows(2).find(|w| w[1] == w[0]) {
            return Err(ColumnsError::Duplicate {
                file: file.to_string(),
                topic: TIME_BASE_TOPIC.into(),
                time_s: w[1] as f64 / 1e6,
            });
        }
        // steps in whole µs, so the times printed are the log's
        let mut steps: Vec<u64> = t_us.windows(2).map(|w| w[1].saturating_sub(w[0])).collect();
        steps.sort_unstable();
        let median = steps[steps.len() / 2] as f64 / 1e6;
        let ts = period_s.unwrap_or(median);
        if !(ts.is_finite() && ts > 0.0) {
            return Err(ColumnsError::Record {
                file: file.to_string(),
                rule: format!("the control period {ts} s must be finite and > 0"),
            });
        }
        if (median - ts).abs() > JITTER_FRACTION * ts {
            return Err(ColumnsError::Record {
                file: file.to_string(),
                rule: format!(
                    "the `control` records' median step is {median} s, not the control period {ts} s: log every control sample (and check control.sample_time_s)"
                ),
            });
        }
        let mut slot = Vec::with_capacity(t_s.len());
        slot.push(0usize);
        let mut max_jitter_s: f64 = 0.0;
        for k in 1..t_s.len() {
            // a step back (refused by `collect`) would be 0: refused as jitter
            let step = t_us[k].saturating_sub(t_us[k - 1]) as f64 / 1e6;
            let m = (step / ts).round();
            if m < 1.0 || (step - m * ts).abs() > JITTER_FRACTION * ts {
                return Err(ColumnsError::Jitter {
                    file: file.to_string(),
                    time_s: t_s[k],
                    step_s: step,
                    period_s: ts,
                    tolerance: JITTER_FRACTION,
                });
            }
            let missing = m as usize - 1;
            if missing > MAX_MISSING {
                return Err(ColumnsError::Gap {
                    file: file.to_string(),
                    time_s: t_s[k],
                    previous_s: t_s[k - 1],
                    missing,
                    max: MAX_MISSING,
                });
            }
            slot.push(slot[k - 1] + missing + 1);
            max_jitter_s = max_jitter_s.max((t_s[k] - t_s[0] - slot[k] as f64 * ts).abs());
        }
        Ok(Grid {
            period_s: ts,
            slot,
            max_jitter_s,
            t_s,
        })
    }
}

/// For each topic after the first, the record held at each control record;
/// and the first control record at which every topic has one.
#[allow(clippy::type_complexity)]
fn align(
    file: &str,
    topics: &[TopicData],
    grid: &Grid,
) -> Result<(usize, Vec<Vec<usize>>), ColumnsError> {
    let ts = grid.period_s;
    let max_age = (MAX_MISSING + 1) as f64 * ts;
    let mut start = 0;
    let mut held = Vec::with_capacity(topics.len().saturating_sub(1));
    for td in &topics[1..] {
        if td.t_us.is_empty() {
            // an optional column's topic without records: nothing read from it
            held.push(Vec::new());
            continue;
        }
        let rec: Vec<f64> = td.t_us.iter().map(|t| *t as f64 / 1e6).collect();
        let mut idx = Vec::with_capacity(grid.t_s.len());
        let mut j: Option<usize> = None;
        for (k, &t) in grid.t_s.iter().enumerate() {
            let limit = t + ALIGN_FRACTION * ts;
            let mut next = j.map_or(0, |j| j + 1);
            while next < rec.len() && rec[next] <= limit {
                j = Some(next);
                next += 1;
            }
            match j {
                None => {
                    start = start.max(k + 1);
                    idx.push(0);
                }
                Some(j) => idx.push(j),
            }
        }
        held.push(idx);
    }
    if start >= grid.t_s.len() {
        return Err(ColumnsError::Record {
            file: file.to_string(),
            rule: "no control sample has a record of every topic asked for".into(),
        });
    }
    for (td, idx) in topics[1..].iter().zip(&held) {
        if td.t_us.is_empty() {
            continue;
        }
        for k in start..grid.t_s.len() {
            let age = grid.t_s[k] - td.t_us[idx[k]] as f64 / 1e6;
            if age > max_age + 1e-9 {
                // to the µs, the log's resolution (a difference of times
                // carries round-off digits)
                let us = |v: f64| (v * 1e6).round() / 1e6;
                return Err(ColumnsError::Stale {
                    file: file.to_string(),
                    topic: td.name.to_string(),
                    time_s: grid.t_s[k],
                    age_s: us(age),
                    max_s: us(max_age),
                });
            }
        }
    }
    Ok((start, held))
}

/// The values `at(k)` of the control records from `start` on, on the grid
/// `slot`, missing samples linearly interpolated.
fn fill(slot: &[usize], start: usize, at: impl Fn(usize) -> f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(slot[slot.len() - 1] - slot[start] + 1);
    out.push(at(start));
    for k in start + 1..slot.len() {
        let (a, b) = (at(k - 1), at(k));
        let m = slot[k] - slot[k - 1];
        for i in 1..m {
            let f = i as f64 / m as f64;
            out.push(a + f * (b - a));
        }
        out.push(b);
    }
    out
}
