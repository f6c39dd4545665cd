//! One pass over a ULog file with the formats resolved: subscriptions,
//! data records with their timestamps, information, parameters, text
//! messages and dropouts, handed to a callback as [`Event`]s.

use crate::error::ReadError;
use crate::flat::{FlatFormat, flatten};
use crate::reader::{Format, KeyValue, Message, UlogReader, Value};
use crate::spec::LogLevel;
use std::collections::HashMap;
use std::io::Read;

/// A subscribed topic instance.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Subscription {
    /// Topic (format) name.
    pub name: String,
    /// Instance.
    pub multi_id: u8,
    /// Its columns.
    pub format: FlatFormat,
    /// Index of the `timestamp` column.
    pub timestamp_column: usize,
}

/// What the pass found, in file order.
#[derive(Debug)]
pub enum Event<'a> {
    /// An INFO message.
    Info(&'a KeyValue),
    /// An INFO_MULTIPLE sequence, its parts joined (strings and arrays
    /// concatenated); reported when the next message is not its
    /// continuation. A key may have several sequences.
    InfoMultiple(&'a KeyValue),
    /// A parameter; `in_data` for a change during the log, at the newest
    /// timestamp seen so far.
    Parameter {
        /// Key and value.
        kv: &'a KeyValue,
        /// Written in the data section.
        in_data: bool,
        /// The newest data timestamp before it (µs).
        timestamp_us: u64,
    },
    /// A new subscription (message id `msg_id`).
    Subscribed {
        /// Message id.
        msg_id: u16,
        /// The topic.
        topic: &'a Subscription,
    },
    /// A data record.
    Data {
        /// Message id.
        msg_id: u16,
        /// The topic.
        topic: &'a Subscription,
        /// The record's bytes (at least `topic.format.min_len`).
        payload: &'a [u8],
        /// Its timestamp (µs).
        timestamp_us: u64,
    },
    /// A text message.
    Logging {
        /// Level.
        level: Option<LogLevel>,
        /// Tag, for tagged messages.
        tag: Option<u16>,
        /// Time (µs).
        timestamp_us: u64,
        /// Text.
        text: &'a str,
    },
    /// Data was lost.
    Dropout {
        /// Duration (ms).
        duration_ms: u16,
        /// The newest data timestamp before it (µs).
        timestamp_us: u64,
    },
}

/// How the file ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum End {
    /// On a message boundary.
    Complete,
    /// Inside a message at `offset` (a writer killed mid-write): everything
    /// before was read.
    Truncated {
        /// Byte offset of the incomplete message.
        offset: u64,
    },
}

/// Counters of one pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PassSummary {
    /// How the file ended.
    pub end: End,
    /// Header timestamp (µs).
    pub start_us: u64,
    /// Data records of message ids never subscribed (skipped).
    pub unknown_records: u64,
    /// Data records whose timestamp is below the previous record's of the
    /// same subscription.
    pub non_monotonic: u64,
}

fn malformed(file: &str, at: u64, kind: &str, rule: String) -> ReadError {
    ReadError::Malformed {
        file: file.to_string(),
        offset: at,
        kind: kind.to_string(),
        rule,
    }
}

/// Read all of `reader`, calling `f` for each event. A truncated file ends
/// the pass normally with [`End::Truncated`]; any other read error, a
/// record shorter than its format, or an error of `f` stops it.
pub fn visit<R: Read, E: From<ReadError>>(
    mut reader: UlogReader<R>,
    mut f: impl FnMut(Event<'_>) -> Result<(), E>,
) -> Result<PassSummary, E> {
    let file = reader.file_name().to_string();
    let mut formats: HashMap<String, Format> = HashMap::new();
    let mut subs: HashMap<u16, (Subscription, Option<u64>)> = HashMap::new();
    let mut in_data = false;
    let mut pending: Option<KeyValue> = None;
    let mut newest_us = 0u64;
    let mut summary = PassSummary {
        end: End::Complete,
        start_us: reader.header().timestamp_us,
        unknown_records: 0,
        non_monotonic: 0,
    };
    loop {
        let at = reader.offset();
        let m = match reader.next_message() {
            Ok(Some(m)) => m,
            Ok(None) => break,
            Err(ReadError::Truncated { offset, .. }) => {
                summary.end = End::Truncated { offset };
                break;
            }
            Err(e) => return Err(e.into()),
        };
        if !matches!(m, Message::InfoMultiple { .. })
            && let Some(p) = pending.take()
        {
            f(Event::InfoMultiple(&p))?;
        }
        match m {
            Message::Format(fmt) => {
                formats.insert(fmt.name.clone(), fmt);
            }
            Message::Info(kv) => f(Event::Info(&kv))?,
            Message::InfoMultiple { is_continued, kv } => {
                match pending.as_mut() {
                    Some(p) if is_continued && p.name == kv.name => join(p, kv),
                    _ => {
                        if let Some(p) = pending.take() {
                            f(Event::InfoMultiple(&p))?;
                        }
                        pending = Some(kv);
                    }
                }
                continue;
            }
            Message::Parameter(kv) => f(Event::Parameter {
                kv: &kv,
                in_data,
                timestamp_us: newest_us,
            })?,
            Message::AddLogged {
                multi_id,
                msg_id,
                name,
            } => {
                in_data = true;
                let sub = subscription(name, multi_id, &formats)
                    .map_err(|rule| malformed(&file, at, "'A'", rule))?;
                subs.insert(msg_id, (sub, None));
                if let Some((topic, _)) = subs.get(&msg_id) {
                    f(Event::Subscribed { msg_id, topic })?;
                }
            }
            Message::RemoveLogged { msg_id } => {
                subs.remove(&msg_id);
            }
            Message::Data { msg_id, payload } => {
                let Some((topic, last)) = subs.get_mut(&msg_id) else {
                    summary.unknown_records += 1;
                    continue;
                };
                let timestamp_us = record_timestamp(topic, payload)
                    .map_err(|rule| malformed(&file, at, "'D'", rule))?;
                if last.is_some_and(|l| timestamp_us < l) {
                    summary.non_monotonic += 1;
                }
                *last = Some(timestamp_us);
                newest_us = newest_us.max(timestamp_us);
                f(Event::Data {
                    msg_id,
                    topic,
                    payload,
                    timestamp_us,
                })?;
            }
            Message::Logging {
                level,
                tag,
                timestamp_us,
                text,
            } => f(Event::Logging {
                level,
                tag,
                timestamp_us,
                text: &text,
            })?,
            Message::Dropout { duration_ms } => f(Event::Dropout {
                duration_ms,
                timestamp_us: newest_us,
            })?,
            Message::FlagBits { incompat, .. } => {
                // bit 0 of the first byte (appended data) is the only one defined
                if incompat[0] & !1 != 0 || incompat[1..].iter().any(|b| *b != 0) {
                    return Err(ReadError::Incompatible {
                        file: file.clone(),
                        flags: incompat[0],
                    }
                    .into());
                }
            }
            Message::ParameterDefault { .. } | Message::Sync | Message::Unknown { .. } => {}
        }
    }
    if let Some(p) = pending.take() {
        f(Event::InfoMultiple(&p))?;
    }
    Ok(summary)
}

/// The subscription of topic `name`, its format flattened.
fn subscription(
    name: String,
    multi_id: u8,
    formats: &HashMap<String, Format>,
) -> Result<Subscription, String> {
    let format = flatten(&name, formats)?;
    let Some(timestamp_column) = format.timestamp_column() else {
        return Err(format!("topic `{name}` has no `uint64_t timestamp` field"));
    };
    Ok(Subscription {
        name,
        multi_id,
        format,
        timestamp_column,
    })
}

/// The timestamp of a record, after checking its length against its format.
fn record_timestamp(topic: &Subscription, payload: &[u8]) -> Result<u64, String> {
    if payload.len() < topic.format.min_len {
        return Err(format!(
            "`{}` record of {} bytes, its format needs {}",
            topic.name,
            payload.len(),
            topic.format.min_len
        ));
    }
    match topic.format.value(payload, topic.timestamp_column) {
        Some(Value::UInt(t)) => Ok(t),
        _ => Err(format!("`{}` record without its timestamp", topic.name)),
    }
}

/// Append a continuation part to an INFO_MULTIPLE sequence.
fn join(to: &mut KeyValue, part: KeyValue) {
    match (&mut to.value, part.value) {
        (Value::Str(a), Value::Str(b)) => a.push_str(&b),
        (Value::Array(a), Value::Array(b)) => a.extend(b),
        (Value::Raw(a), Value::Raw(b)) => a.extend(b),
        // parts of different types: keep the first, as the specification
        // gives no meaning to the mix
        _ => {}
    }
}
