//! Export of a ULog file to CSV and text, for the tools that want CSV.
//!
//! In the output folder, for a log `NAME.ulg`:
//! - `NAME_<topic>_<multi_id>.csv` per topic instance (pyulog's `ulog2csv`
//!   naming): `timestamp` (µs) first, then the flattened fields in file
//!   order (`command[0]`, `esc[1].rpm`); integers as integers, bools as
//!   0/1, floats in shortest round-trip form, exponent notation outside
//!   [1e-4, 1e15) (`NaN`, `inf`, `-inf` for
//!   non-finite values, which are counted in the report);
//! - `NAME_info.txt`: the header timestamp and each INFO as `key: value`;
//! - `NAME_params.txt`: `name value` per parameter, changes during the log
//!   as `name value @ <timestamp µs>`;
//! - `NAME_messages.txt`: `<timestamp µs> <level> <text>` per LOGGING
//!   message, and `<timestamp µs> dropout <ms> ms` per DROPOUT.
//!
//! A truncated file (a writer killed mid-write) exports everything before
//! the cut; the report says where it was cut.

use crate::error::ReadError;
use crate::reader::{UlogReader, Value};
use crate::visit::{End, Event, PassSummary, Subscription, visit};
use helicon_config::{csv_cell, escape_control};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// An error exporting a log.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The log could not be read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// An output file could not be written.
    #[error("{file}: cannot {action}")]
    Io {
        /// The file.
        file: String,
        /// `create`, `write`.
        action: &'static str,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A CSV file could not be written.
    #[error("{file}: cannot write")]
    Csv {
        /// The file.
        file: String,
        /// The cause.
        #[source]
        source: csv::Error,
    },
}

/// Rows and time span of one topic instance.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TopicStats {
    /// Records.
    pub rows: u64,
    /// First and last timestamps (µs).
    pub first_last_us: Option<(u64, u64)>,
}

impl TopicStats {
    fn add(&mut self, timestamp_us: u64) {
        self.rows += 1;
        self.first_last_us = Some(match self.first_last_us {
            Some((first, _)) => (first, timestamp_us),
            None => (timestamp_us, timestamp_us),
        });
    }

    /// Mean record rate (Hz) over the span, `None` for fewer than two
    /// records or a zero span.
    pub fn rate_hz(&self) -> Option<f64> {
        let (a, b) = self.first_last_us?;
        if self.rows < 2 || b <= a {
            return None;
        }
        Some((self.rows - 1) as f64 / ((b - a) as f64 * 1e-6))
    }
}

/// One exported topic instance.
#[derive(Debug, Clone, PartialEq)]
pub struct TopicReport {
    /// The CSV file.
    pub file: PathBuf,
    /// Its rows and span.
    pub stats: TopicStats,
    /// Float values written as `NaN`: in PX4's topics, a field the vehicle
    /// does not have ("not available").
    pub nan_values: u64,
    /// Float values written as `inf` or `-inf`.
    pub infinite_values: u64,
}

/// What a log holds (`helicon log info`).
#[derive(Debug, Clone, PartialEq)]
pub struct LogSummary {
    /// Per `(topic, multi_id)`.
    pub topics: BTreeMap<(String, u8), TopicStats>,
    /// INFO messages as `(key, value)` text.
    pub info: Vec<(String, String)>,
    /// Parameters (initial values and changes).
    pub parameters: u64,
    /// Text messages.
    pub log_messages: u64,
    /// Total dropout duration (ms).
    pub dropout_ms: u64,
    /// The reading pass.
    pub pass: PassSummary,
}

/// Read a whole log and count what it holds.
pub fn summarize(input: &Path) -> Result<LogSummary, ReadError> {
    let reader = UlogReader::open(input)?;
    let mut s = LogSummary {
        topics: BTreeMap::new(),
        info: Vec::new(),
        parameters: 0,
        log_messages: 0,
        dropout_ms: 0,
        pass: PassSummary {
            end: End::Complete,
            start_us: 0,
            unknown_records: 0,
            non_monotonic: 0,
        },
    };
    s.pass = visit(reader, |ev| -> Result<(), ReadError> {
        match ev {
            Event::Info(kv) => s.info.push((kv.name.clone(), kv.value.to_string())),
            Event::InfoMultiple(kv) => {
                let len = kv.bytes.len();
                s.info
                    .push((kv.name.clone(), format!("({len} bytes in several parts)")));
            }
            Event::Parameter { .. } => s.parameters += 1,
            Event::Subscribed { topic, .. } => {
                s.topics
                    .entry((topic.name.clone(), topic.multi_id))
                    .or_default();
            }
            Event::Data {
                topic,
                timestamp_us,
                ..
            } => s
                .topics
                .entry((topic.name.clone(), topic.multi_id))
                .or_default()
                .add(timestamp_us),
            Event::Logging { .. } => s.log_messages += 1,
            Event::Dropout { duration_ms, .. } => s.dropout_ms += u64::from(duration_ms),
        }
        Ok(())
    })?;
    Ok(s)
}

/// What an export wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportReport {
    /// Per `(topic, multi_id)`.
    pub topics: BTreeMap<(String, u8), TopicReport>,
    /// The text files written (info, parameters, messages).
    pub text_files: Vec<PathBuf>,
    /// Text messages.
    pub log_messages: u64,
    /// Total dropout duration (ms).
    pub dropout_ms: u64,
    /// The reading pass.
    pub pass: PassSummary,
}

/// Keep a topic name usable in a file name (`[A-Za-z0-9_]`, others → `_`).
fn safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

struct Outputs {
    dir: PathBuf,
    stem: String,
    files: Vec<PathBuf>,
}

impl Outputs {
    fn path(&mut self, suffix: &str) -> PathBuf {
        let path = self.dir.join(format!("{}_{suffix}", self.stem));
        self.files.push(path.clone());
        path
    }

    fn create(&mut self, suffix: &str) -> Result<(PathBuf, BufWriter<File>), ExportError> {
        let path = self.path(suffix);
        let f = File::create(&path).map_err(|source| ExportError::Io {
            file: path.display().to_string(),
            action: "create",
            source,
        })?;
        Ok((path, BufWriter::new(f)))
    }
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> ExportError + '_ {
    move |source| ExportError::Io {
        file: path.display().to_string(),
        action: "write",
        source,
    }
}

fn non_finite_text(x: f64) -> &'static str {
    if x.is_nan() {
        "NaN"
    } else if x > 0.0 {
        "inf"
    } else {
        "-inf"
    }
}

/// Format one value as a CSV field into `s`; the value when non-finite.
fn format_value(v: &Value, s: &mut String) -> Option<f64> {
    s.clear();
    let x = match v {
        Value::Float(x) if !x.is_finite() => *x,
        Value::Float32(x) if !x.is_finite() => f64::from(*x),
        _ => {
            let _ = write!(s, "{v}");
            return None;
        }
    };
    s.push_str(non_finite_text(x));
    Some(x)
}

type TopicCsv = (csv::Writer<File>, (String, u8), TopicReport);

/// The CSV of a topic instance, its header written: `timestamp` first.
fn new_csv(
    out: &mut Outputs,
    topic: &Subscription,
    key: (String, u8),
) -> Result<TopicCsv, ExportError> {
    let suffix = format!("{}_{}.csv", safe(&topic.name), topic.multi_id);
    let path = out.path(&suffix);
    let err = |source| ExportError::Csv {
        file: path.display().to_string(),
        source,
    };
    let mut w = csv::Writer::from_path(&path).map_err(err)?;
    let cols = &topic.format.columns;
    let ts = topic.timestamp_column;
    let order = std::iter::once(ts).chain((0..cols.len()).filter(|i| *i != ts));
    // the names come from the file: no cell may start a formula
    w.write_record(order.map(|i| csv_cell(&cols[i].name).into_owned()))
        .map_err(err)?;
    let report = TopicReport {
        file: path,
        stats: TopicStats::default(),
        nan_values: 0,
        infinite_values: 0,
    };
    Ok((w, key, report))
}

/// Export `input` (a `.ulg` file) into the folder `dir` (created if
/// needed). See the module documentation for the files.
#[allow(clippy::too_many_lines)] // one pass: each event kind to its file
pub fn export_csv(input: &Path, dir: &Path) -> Result<ExportReport, ExportError> {
    let reader = UlogReader::open(input)?;
    std::fs::create_dir_all(dir).map_err(|source| ExportError::Io {
        file: dir.display().to_string(),
        action: "create",
        source,
    })?;
    let stem = input
        .file_stem()
        .map_or_else(|| "log".to_string(), |s| s.to_string_lossy().into_owned());
    let mut out = Outputs {
        dir: dir.to_path_buf(),
        stem,
        files: Vec::new(),
    };
    let (info_path, mut info) = out.create("info.txt")?;
    let (params_path, mut params) = out.create("params.txt")?;
    let (msgs_path, mut msgs) = out.create("messages.txt")?;
    writeln!(info, "start_timestamp_us: {}", reader.header().timestamp_us)
        .map_err(io_err(&info_path))?;

    // per message id: index into `csvs`
    let mut by_msg_id: BTreeMap<u16, usize> = BTreeMap::new();
    let mut csvs: Vec<TopicCsv> = Vec::new();
    let mut field = String::new();
    let mut log_messages = 0u64;
    let mut dropout_ms = 0u64;
    let csv_err = |p: &Path| {
        let file = p.display().to_string();
        move |source| ExportError::Csv {
            file: file.clone(),
            source,
        }
    };

    let pass = visit(reader, |ev| -> Result<(), ExportError> {
        match ev {
            Event::Info(kv) => {
                let (k, v) = (escape_control(&kv.name), kv.value.to_string());
                writeln!(info, "{k}: {}", escape_control(&v)).map_err(io_err(&info_path))?;
            }
            Event::InfoMultiple(kv) => {
                let k = escape_control(&kv.name);
                match kv.base_type() {
                    // text: escaped, decoded once (its bytes are bounded)
                    Some(crate::UlogType::Char) => {
                        let v = String::from_utf8_lossy(&kv.bytes);
                        writeln!(info, "{k}: {}", escape_control(&v))
                    }
                    // numbers: printed element by element
                    _ => writeln!(info, "{k}: {kv}"),
                }
                .map_err(io_err(&info_path))?;
            }
            Event::Parameter {
                kv,
                in_data,
                timestamp_us,
            } => {
                let k = escape_control(&kv.name);
                let v = kv.value.to_string();
                let v = escape_control(&v);
                if in_data {
                    writeln!(params, "{k} {v} @ {timestamp_us}")
                } else {
                    writeln!(params, "{k} {v}")
                }
                .map_err(io_err(&params_path))?;
            }
            Event::Subscribed { msg_id, .. } => {
                // a message id subscribed again may be another topic
                by_msg_id.remove(&msg_id);
            }
            Event::Data {
                msg_id,
                topic,
                payload,
                timestamp_us,
            } => {
                // the CSV of a topic instance is created at its first record
                // (as pyulog does: no file for a topic that logged nothing)
                let idx = match by_msg_id.get(&msg_id) {
                    Some(i) => *i,
                    None => {
                        let key = (topic.name.clone(), topic.multi_id);
                        let i = match csvs.iter().position(|(_, k, _)| *k == key) {
                            Some(i) => i,
                            None => {
                                csvs.push(new_csv(&mut out, topic, key)?);
                                csvs.len() - 1
                            }
                        };
                        by_msg_id.insert(msg_id, i);
                        i
                    }
                };
                let Some((w, _, report)) = csvs.get_mut(idx) else {
                    return Ok(());
                };
                let ts = topic.timestamp_column;
                let n = topic.format.columns.len();
                for i in std::iter::once(ts).chain((0..n).filter(|i| *i != ts)) {
                    if let Some(v) = topic.format.value(payload, i) {
                        match format_value(&v, &mut field) {
                            Some(x) if x.is_nan() => report.nan_values += 1,
                            Some(_) => report.infinite_values += 1,
                            None => {}
                        }
                    }
                    w.write_field(&field).map_err(csv_err(&report.file))?;
                }
                w.write_record(None::<&[u8]>)
                    .map_err(csv_err(&report.file))?;
                report.stats.add(timestamp_us);
            }
            Event::Logging {
                level,
                timestamp_us,
                text,
                ..
            } => {
                let level = level.map_or("unknown", |l| l.name());
                let text = escape_control(text);
                writeln!(msgs, "{timestamp_us} {level} {text}").map_err(io_err(&msgs_path))?;
                log_messages += 1;
            }
            Event::Dropout {
                duration_ms,
                timestamp_us,
            } => {
                writeln!(msgs, "{timestamp_us} dropout {duration_ms} ms")
                    .map_err(io_err(&msgs_path))?;
                dropout_ms += u64::from(duration_ms);
            }
        }
        Ok(())
    })?;

    info.flush().map_err(io_err(&info_path))?;
    params.flush().map_err(io_err(&params_path))?;
    msgs.flush().map_err(io_err(&msgs_path))?;
    let mut topics = BTreeMap::new();
    for (mut w, key, report) in csvs {
        w.flush().map_err(io_err(&report.file))?;
        topics.insert(key, report);
    }
    Ok(ExportReport {
        topics,
        text_files: vec![info_path, params_path, msgs_path],
        log_messages,
        dropout_ms,
        pass,
    })
}

/// True when the pass ended inside a message.
pub fn was_truncated(r: &ExportReport) -> bool {
    matches!(r.pass.end, End::Truncated { .. })
}
