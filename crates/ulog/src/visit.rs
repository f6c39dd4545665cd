//! One pass over a ULog file with the formats resolved: subscriptions,
//! data records with their timestamps, information, parameters, text
//! messages and dropouts, handed to a callback as [`Event`]s.
//!
//! # Cost
//!
//! A pass costs time and memory linear in the file with a small factor,
//! whatever the file holds:
//!
//! - a format is flattened once, when a topic of it is first subscribed,
//!   and shared by every subscription of it (a format declared again with
//!   other fields drops the flattened formats; the columns flattened over a
//!   pass are bounded, [`Limits::flattened_columns`]);
//! - an INFO_MULTIPLE sequence is joined as bytes ([`MultiInfo`]), one
//!   sequence at a time, of at most [`Limits::info_multiple_bytes`];
//! - subscriptions, formats and the fields of a format are bounded
//!   ([`Limits`]); beyond a limit the pass stops with
//!   [`ReadError::Limit`], naming the file, the offset and what was
//!   exceeded.
//!
//! Every other message is read, handled and dropped (the reader holds one
//! message of at most 64 KiB).

use crate::error::ReadError;
use crate::flat::{FlatFormat, FlattenError, MAX_COLUMNS, flatten_limited};
use crate::reader::{Format, InfoPart, KeyValue, Message, MultiInfo, UlogReader, Value};
use crate::spec::LogLevel;
use helicon_config::escape_control;
use std::collections::HashMap;
use std::io::Read;
use std::sync::Arc;

/// The bounds of a pass: each well above what a PX4 or helicon flight log
/// needs (PX4's logger subscribes a few hundred topic instances of a few
/// hundred formats, none of more than a few hundred fields; its longest
/// multi-part information, the boot console, is tens of kilobytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Subscriptions (ADD_LOGGED messages) in a file.
    pub subscriptions: usize,
    /// Distinct formats (FORMAT messages of distinct names).
    pub formats: usize,
    /// Fields written in one FORMAT message.
    pub format_fields: usize,
    /// Columns of one flattened format (at most [`MAX_COLUMNS`]).
    pub columns: usize,
    /// Columns flattened over the whole pass (each format once, again only
    /// after a format was declared anew).
    pub flattened_columns: usize,
    /// Bytes of one joined INFO_MULTIPLE sequence.
    pub info_multiple_bytes: usize,
}

impl Limits {
    /// The limits of [`visit`].
    pub const DEFAULT: Limits = Limits {
        subscriptions: 4096,
        formats: 4096,
        format_fields: 4096,
        columns: MAX_COLUMNS,
        flattened_columns: 1 << 20,
        info_multiple_bytes: 16 << 20,
    };
}

impl Default for Limits {
    fn default() -> Self {
        Limits::DEFAULT
    }
}

/// A subscribed topic instance.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Subscription {
    /// Topic (format) name.
    pub name: String,
    /// Instance.
    pub multi_id: u8,
    /// Its columns (shared by every subscription of the format).
    pub format: Arc<FlatFormat>,
    /// Index of the `timestamp` column.
    pub timestamp_column: usize,
}

/// What the pass found, in file order.
#[derive(Debug)]
pub enum Event<'a> {
    /// An INFO message.
    Info(&'a KeyValue),
    /// An INFO_MULTIPLE sequence, its parts' bytes joined; reported when
    /// the next message is not its continuation. A key may have several
    /// sequences.
    InfoMultiple(&'a MultiInfo),
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
/// record shorter than its format, a [`Limits::DEFAULT`] exceeded, or an
/// error of `f` stops it.
pub fn visit<R: Read, E: From<ReadError>>(
    reader: UlogReader<R>,
    f: impl FnMut(Event<'_>) -> Result<(), E>,
) -> Result<PassSummary, E> {
    visit_with(reader, &Limits::DEFAULT, f)
}

/// The flattened formats of a pass and what they cost.
struct Flattened<'l> {
    formats: HashMap<String, Format>,
    cache: HashMap<String, Arc<FlatFormat>>,
    columns_so_far: usize,
    limits: &'l Limits,
}

impl Flattened<'_> {
    /// Declare `fmt`: the same declaration again changes nothing; another
    /// one drops the flattened formats (any may nest it).
    fn declare(&mut self, fmt: Format) -> Result<(), (String, usize)> {
        if fmt.fields.len() > self.limits.format_fields {
            return Err((
                format!("fields in format `{}`", escape_control(&fmt.name)),
                self.limits.format_fields,
            ));
        }
        match self.formats.get(&fmt.name) {
            Some(old) if *old == fmt => return Ok(()),
            Some(_) => self.cache.clear(),
            None if self.formats.len() >= self.limits.formats => {
                return Err(("formats".to_string(), self.limits.formats));
            }
            None => {}
        }
        self.formats.insert(fmt.name.clone(), fmt);
        Ok(())
    }

    /// The flattened format `name` (flattened at its first use).
    fn get(&mut self, name: &str) -> Result<Arc<FlatFormat>, Broken> {
        if let Some(f) = self.cache.get(name) {
            return Ok(Arc::clone(f));
        }
        let left = self
            .limits
            .flattened_columns
            .saturating_sub(self.columns_so_far);
        let max = self.limits.columns.min(left);
        let flat = flatten_limited(name, &self.formats, max).map_err(|e| match e {
            FlattenError::Rule(rule) => Broken::Rule(rule),
            FlattenError::TooManyColumns { topic, .. } if max < self.limits.columns => {
                Broken::Limit(
                    format!("columns flattened in all (at topic `{topic}`)"),
                    self.limits.flattened_columns,
                )
            }
            FlattenError::TooManyColumns { topic, limit } => {
                Broken::Limit(format!("columns in topic `{topic}`"), limit)
            }
        })?;
        self.columns_so_far += flat.columns.len();
        let flat = Arc::new(flat);
        self.cache.insert(name.to_string(), Arc::clone(&flat));
        Ok(flat)
    }
}

/// A subscription refused: a rule of the format, or a limit.
enum Broken {
    Rule(String),
    Limit(String, usize),
}

fn limit(file: &str, offset: u64, what: String, limit: usize) -> ReadError {
    ReadError::Limit {
        file: file.to_string(),
        offset,
        what,
        limit: limit as u64,
    }
}

/// [`visit`] within `limits`.
#[allow(clippy::too_many_lines)] // one pass: each message kind to its event
pub fn visit_with<R: Read, E: From<ReadError>>(
    mut reader: UlogReader<R>,
    limits: &Limits,
    mut f: impl FnMut(Event<'_>) -> Result<(), E>,
) -> Result<PassSummary, E> {
    let file = reader.file_name().to_string();
    let mut flat = Flattened {
        formats: HashMap::new(),
        cache: HashMap::new(),
        columns_so_far: 0,
        limits,
    };
    let mut subscriptions = 0usize;
    let mut subs: HashMap<u16, (Subscription, Option<u64>)> = HashMap::new();
    let mut in_data = false;
    let mut pending: Option<MultiInfo> = None;
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
                flat.declare(fmt)
                    .map_err(|(what, n)| limit(&file, at, what, n))?;
            }
            Message::Info(kv) => f(Event::Info(&kv))?,
            Message::InfoMultiple { is_continued, part } => {
                match pending.as_mut() {
                    Some(p) if is_continued && p.name == part.name => join(p, &part),
                    _ => {
                        if let Some(p) = pending.take() {
                            f(Event::InfoMultiple(&p))?;
                        }
                        pending = Some(MultiInfo {
                            element_type: part.element_type,
                            name: part.name,
                            bytes: part.bytes.to_vec(),
                        });
                    }
                }
                if let Some(p) = &pending
                    && p.bytes.len() > limits.info_multiple_bytes
                {
                    return Err(limit(
                        &file,
                        at,
                        format!(
                            "bytes in information `{}` (parts joined)",
                            escape_control(&p.name)
                        ),
                        limits.info_multiple_bytes,
                    )
                    .into());
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
                subscriptions += 1;
                if subscriptions > limits.subscriptions {
                    return Err(limit(
                        &file,
                        at,
                        "subscriptions".to_string(),
                        limits.subscriptions,
                    )
                    .into());
                }
                let sub = subscription(name, multi_id, &mut flat).map_err(|b| match b {
                    Broken::Rule(rule) => malformed(&file, at, "'A'", rule),
                    Broken::Limit(what, n) => limit(&file, at, what, n),
                })?;
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

/// The subscription of topic `name`, its format flattened (once a pass).
fn subscription(
    name: String,
    multi_id: u8,
    flat: &mut Flattened<'_>,
) -> Result<Subscription, Broken> {
    let format = flat.get(&name)?;
    let Some(timestamp_column) = format.timestamp_column() else {
        return Err(Broken::Rule(format!(
            "topic `{}` has no `uint64_t timestamp` field",
            escape_control(&name)
        )));
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
            escape_control(&topic.name),
            payload.len(),
            topic.format.min_len
        ));
    }
    match topic.format.value(payload, topic.timestamp_column) {
        Some(Value::UInt(t)) => Ok(t),
        _ => Err(format!(
            "`{}` record without its timestamp",
            escape_control(&topic.name)
        )),
    }
}

/// Append a continuation part to an INFO_MULTIPLE sequence: its bytes, when
/// of the sequence's element type (parts of another type are left out, as
/// the specification gives no meaning to the mix).
fn join(to: &mut MultiInfo, part: &InfoPart<'_>) {
    if to.element_type == part.element_type {
        to.bytes.extend_from_slice(part.bytes);
    }
}
