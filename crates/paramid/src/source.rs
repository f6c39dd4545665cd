//! Where a log's columns come from: the simulator's `log.csv` (or any CSV
//! with `t_s` and the columns named), or the flight computer's ULog
//! (`flight.ulg`), read onto the control grid by
//! [`helicon_ulog::columns`] under the same names. A file is taken as ULog
//! when it starts with the ULog magic bytes, whatever its name.
//!
//! Who drove the servos: a log with a [`SERVO_SOURCE`] column (a flight
//! log's `servo_output.source`, or a CSV that has the column) gives it with
//! the columns asked for, and [`servo_spans`] finds the samples in which the
//! control law did not (the one check, for the identification and the
//! `helicon ident` commands alike). A log without the column (the
//! simulator's `log.csv`, older flight logs) is taken as flown by the law.

use crate::error::LogError;
use helicon_model::config_error::format_seconds;
use helicon_sim::log_csv::{LogReader, read_log_csv_with};
use helicon_ulog::columns::{available_columns, read_ulog_columns_with};
use std::io::Read;
use std::path::Path;

/// The ULog file magic (PX4 "ULog File Format": `ULog` then 0x01 0x12 0x35).
const ULOG_MAGIC: [u8; 7] = [0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35];

/// Whether the file at `path` is a ULog file (its first bytes). A file that
/// cannot be opened, or is no regular file (a FIFO, which would block the
/// open, or a device), is not: the CSV reader then names the problem.
pub fn is_ulog(path: &Path) -> bool {
    let mut head = [0u8; 7];
    helicon_model::config_error::open_regular(path)
        .is_ok_and(|mut f| f.read_exact(&mut head).is_ok() && head == ULOG_MAGIC)
}

/// The columns of a log, by name.
#[derive(Debug, Clone, PartialEq)]
pub struct LogColumns {
    /// Names, `t_s` first.
    pub names: Vec<String>,
    /// Values, in the order of `names`.
    pub columns: Vec<Vec<f64>>,
    /// What a user should know about the reading (a ULog's filled samples,
    /// a cut); empty for a CSV.
    pub notes: Vec<String>,
    /// Who drove the servos at each sample ([`SERVO_SOURCE`]), when the log
    /// says.
    pub servo_source: Option<Vec<f64>>,
}

impl LogColumns {
    /// The column `name` (present: the readers refuse a missing one).
    pub fn column(&self, name: &str) -> &[f64] {
        self.names
            .iter()
            .position(|n| n == name)
            .map_or(&[], |j| self.columns[j].as_slice())
    }
}

/// Read `t_s` and the columns `names` of the log at `path`: a ULog onto the
/// control grid of period `period_s` (one pass over the file), a CSV as it
/// is; with the [`SERVO_SOURCE`] column when the log has it.
pub fn read_log(path: &Path, names: &[&str], period_s: f64) -> Result<LogColumns, LogError> {
    let asked = names.contains(&SERVO_SOURCE);
    let mut out = if is_ulog(path) {
        let optional: &[&str] = if asked { &[] } else { &[SERVO_SOURCE] };
        let u = read_ulog_columns_with(path, names, optional, Some(period_s))?;
        let notes = u.notes();
        LogColumns {
            names: u.names,
            columns: u.columns,
            notes,
            servo_source: None,
        }
    } else {
        let mut ask: Vec<&str> = names.to_vec();
        if !asked
            && LogReader::open(path, &[])?
                .names()
                .iter()
                .any(|n| n == SERVO_SOURCE)
        {
            ask.push(SERVO_SOURCE);
        }
        let table = read_log_csv_with(path, &ask)?;
        let mut out = LogColumns {
            names: vec!["t_s".into()],
            columns: vec![table.time_s().to_vec()],
            notes: Vec::new(),
            servo_source: None,
        };
        for n in ask.iter().filter(|n| **n != "t_s") {
            out.names.push((*n).to_string());
            out.columns.push(table.column(n)?.to_vec());
        }
        out
    };
    if asked {
        out.servo_source = Some(out.column(SERVO_SOURCE).to_vec());
    } else if out.names.last().is_some_and(|n| n == SERVO_SOURCE) {
        // read here, not asked for by the caller: the last column
        out.names.pop();
        out.servo_source = out.columns.pop();
    }
    Ok(out)
}

/// The column names the log at `path` offers.
pub fn log_names(path: &Path) -> Result<Vec<String>, LogError> {
    if is_ulog(path) {
        return Ok(available_columns(path)?
            .into_iter()
            .map(String::from)
            .collect());
    }
    Ok(LogReader::open(path, &[])?.names().to_vec())
}

/// The column saying who drove the servos at each sample: 0 the control
/// law, 1 the pilot (manual), 2 a failsafe (a flight log's
/// `servo_output.source`).
pub const SERVO_SOURCE: &str = "servo_source";

/// A run of consecutive samples in which the control law did not drive the
/// servos.
#[derive(Debug, Clone, PartialEq)]
pub struct ServoSpan {
    /// Time of its first sample, s.
    pub first_s: f64,
    /// Time of its last sample, s.
    pub last_s: f64,
    /// Its samples.
    pub samples: usize,
    /// The [`SERVO_SOURCE`] values in it, ascending, each once (a value
    /// between two, next to a drop-out a flight log's reading filled, is
    /// kept as it is).
    pub sources: Vec<f64>,
}

/// The runs of samples of `servo_source` (at times `t_s`) that are not 0,
/// in time order: the law drove the servos everywhere else.
pub fn servo_spans(t_s: &[f64], servo_source: &[f64]) -> Vec<ServoSpan> {
    let mut out: Vec<ServoSpan> = Vec::new();
    let mut open = false;
    for (&t, &s) in t_s.iter().zip(servo_source) {
        if s == 0.0 {
            open = false;
            continue;
        }
        match out.last_mut() {
            Some(span) if open => {
                span.last_s = t;
                span.samples += 1;
                if !span.sources.contains(&s) {
                    span.sources.push(s);
                    span.sources.sort_by(f64::total_cmp);
                }
            }
            _ => out.push(ServoSpan {
                first_s: t,
                last_s: t,
                samples: 1,
                sources: vec![s],
            }),
        }
        open = true;
    }
    out
}

/// The spans for a message: `t = 1.5 … 1.6975 s (pilot, 80 samples)`, the
/// first five and how many more.
pub fn describe_spans(spans: &[ServoSpan]) -> String {
    const LISTED: usize = 5;
    let who = |v: &f64| {
        if *v == 1.0 {
            "pilot".to_string()
        } else if *v == 2.0 {
            "failsafe".to_string()
        } else {
            format!("source {v}")
        }
    };
    let mut parts: Vec<String> = spans
        .iter()
        .take(LISTED)
        .map(|s| {
            format!(
                "t = {} … {} s ({}, {} sample{})",
                format_seconds(s.first_s),
                format_seconds(s.last_s),
                s.sources.iter().map(who).collect::<Vec<_>>().join("/"),
                s.samples,
                if s.samples == 1 { "" } else { "s" }
            )
        })
        .collect();
    if spans.len() > LISTED {
        parts.push(format!("and {} more spans", spans.len() - LISTED));
    }
    parts.join(", ")
}
