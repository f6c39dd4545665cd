//! A ULog flight log read whole into columns: one table per topic instance,
//! one column per flattened field (`outer.inner`, `name[i]`, as `helicon
//! log export` and pyulog name them), in file order with `timestamp` (µs)
//! first, plus the log's information and parameters.
//!
//! Column types: `float`/`double` as f64, `uint64_t` as u64, `bool` as
//! bool, every other integer (and `char`) as i64. A truncated file (a
//! writer killed mid-message) gives every complete message and says so.

use crate::error::{Error, Result};
use helicon_ulog::UlogType;
use helicon_ulog::reader::{UlogReader, Value};
use helicon_ulog::visit::{End, Event, visit};
use std::collections::BTreeMap;
use std::path::Path;

/// One column's values.
#[derive(Debug, Clone, PartialEq)]
pub enum Column {
    /// `float`, `double`.
    F64(Vec<f64>),
    /// `uint64_t`.
    U64(Vec<u64>),
    /// The other integers and `char`.
    I64(Vec<i64>),
    /// `bool`.
    Bool(Vec<bool>),
}

impl Column {
    fn new(t: UlogType) -> Column {
        match t {
            UlogType::Float | UlogType::Double => Column::F64(Vec::new()),
            UlogType::UInt64 => Column::U64(Vec::new()),
            UlogType::Bool => Column::Bool(Vec::new()),
            _ => Column::I64(Vec::new()),
        }
    }

    fn push(&mut self, v: &Value) {
        match (self, v) {
            (Column::F64(c), Value::Float(x)) => c.push(*x),
            (Column::F64(c), Value::Float32(x)) => c.push(f64::from(*x)),
            (Column::U64(c), Value::UInt(x)) => c.push(*x),
            (Column::Bool(c), Value::Bool(x)) => c.push(*x),
            (Column::I64(c), Value::Int(x)) => c.push(*x),
            (Column::I64(c), Value::UInt(x)) => c.push(i64::try_from(*x).unwrap_or(i64::MAX)),
            (Column::I64(c), Value::Str(s)) => c.push(s.bytes().next().map_or(0, i64::from)),
            // a value of another kind cannot come from the column's type;
            // keep the columns aligned all the same
            (Column::F64(c), _) => c.push(f64::NAN),
            (Column::U64(c), _) => c.push(0),
            (Column::Bool(c), _) => c.push(false),
            (Column::I64(c), _) => c.push(0),
        }
    }

    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            Column::F64(c) => c.len(),
            Column::U64(c) => c.len(),
            Column::I64(c) => c.len(),
            Column::Bool(c) => c.len(),
        }
    }

    /// No values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One topic instance: its columns in order, `timestamp` first.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Topic {
    /// (field name, values).
    pub columns: Vec<(String, Column)>,
}

/// A whole log.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Log {
    /// Per topic instance, keyed `topic` for instance 0 and
    /// `topic_<multi_id>` for the others; topics that logged nothing are
    /// left out (as `helicon log export` leaves out their files).
    pub topics: BTreeMap<String, Topic>,
    /// INFO and INFO_MULTIPLE messages as text.
    pub info: BTreeMap<String, String>,
    /// Parameters (initial values; a change during the log replaces it).
    pub parameters: BTreeMap<String, f64>,
    /// Header timestamp (µs).
    pub start_timestamp_us: u64,
    /// Whether the file ended inside a message.
    pub truncated: bool,
}

fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Int(x) => Some(*x as f64),
        Value::UInt(x) => Some(*x as f64),
        Value::Float32(x) => Some(f64::from(*x)),
        Value::Float(x) => Some(*x),
        Value::Bool(b) => Some(f64::from(u8::from(*b))),
        _ => None,
    }
}

/// Read the ULog file at `path`.
pub fn read(path: &Path) -> Result<Log> {
    let name = path.display().to_string();
    let file =
        std::fs::File::open(path).map_err(|e| Error::new(format!("{name}: cannot read: {e}")))?;
    let reader = UlogReader::new(std::io::BufReader::new(file), &name)?;
    let mut log = Log {
        start_timestamp_us: reader.header().timestamp_us,
        ..Log::default()
    };
    // per (topic, multi_id): key into `log.topics`
    let mut keys: BTreeMap<(String, u8), String> = BTreeMap::new();
    let pass = visit(
        reader,
        |ev| -> std::result::Result<(), helicon_ulog::ReadError> {
            match ev {
                Event::Info(kv) => {
                    log.info.insert(kv.name.clone(), kv.value.to_string());
                }
                Event::InfoMultiple(m) => {
                    log.info.insert(m.name.clone(), m.value().to_string());
                }
                Event::Parameter { kv, .. } => {
                    if let Some(v) = number(&kv.value) {
                        log.parameters.insert(kv.name.clone(), v);
                    }
                }
                Event::Data { topic, payload, .. } => {
                    let id = (topic.name.clone(), topic.multi_id);
                    let key = keys
                        .entry(id)
                        .or_insert_with(|| {
                            if topic.multi_id == 0 {
                                topic.name.clone()
                            } else {
                                format!("{}_{}", topic.name, topic.multi_id)
                            }
                        })
                        .clone();
                    let cols = &topic.format.columns;
                    let ts = topic.timestamp_column;
                    let order: Vec<usize> = std::iter::once(ts)
                        .chain((0..cols.len()).filter(|i| *i != ts))
                        .collect();
                    let t = log.topics.entry(key).or_insert_with(|| Topic {
                        columns: order
                            .iter()
                            .map(|&i| (cols[i].name.clone(), Column::new(cols[i].ty)))
                            .collect(),
                    });
                    // a topic re-subscribed with another format keeps its first
                    // columns; values are matched by position only when they agree
                    if t.columns.len() == order.len() {
                        for (slot, &i) in t.columns.iter_mut().zip(&order) {
                            if let Some(v) = topic.format.value(payload, i) {
                                slot.1.push(&v);
                            }
                        }
                    }
                }
                Event::Subscribed { .. } | Event::Logging { .. } | Event::Dropout { .. } => {}
            }
            Ok(())
        },
    )?;
    log.truncated = matches!(pass.end, End::Truncated { .. });
    Ok(log)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixture(name: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../crates/ulog/tests/fixtures")
            .join(name)
    }

    #[test]
    fn the_sample_log_reads_into_aligned_columns() {
        let log = read(&fixture("helicon_sample.ulg")).unwrap();
        assert!(!log.topics.is_empty());
        for (name, t) in &log.topics {
            assert_eq!(t.columns[0].0, "timestamp", "{name}");
            assert!(matches!(t.columns[0].1, Column::U64(_)), "{name}");
            let n = t.columns[0].1.len();
            assert!(n > 0);
            assert!(t.columns.iter().all(|(_, c)| c.len() == n), "{name}");
        }
    }

    #[test]
    fn a_missing_or_foreign_file_is_an_error() {
        let e = read(Path::new("/nonexistent/x.ulg")).unwrap_err();
        assert!(e.message().contains("/nonexistent/x.ulg"), "{e}");
        let e = read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml")).unwrap_err();
        assert!(e.message().contains("Cargo.toml"), "{e}");
    }
}
