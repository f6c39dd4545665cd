//! The ULog writer: header, definitions, then data, into one buffer that is
//! written out whole on a flush policy so a killed process leaves a file of
//! complete messages.
//!
//! Sequence: [`UlogWriter::new`] / [`UlogWriter::create`] (header and flag
//! bits) → [`UlogWriter::add_format`], [`UlogWriter::info_str`],
//! [`UlogWriter::parameter_f32`] … (definitions section) → the first
//! [`UlogWriter::add_logged`] opens the data section → [`UlogWriter::write`],
//! [`UlogWriter::log`], [`UlogWriter::dropout`] … → [`UlogWriter::finish`].
//!
//! Per record nothing is allocated: records are encoded straight into the
//! writer's buffer, whose capacity is reserved once (flush threshold plus
//! the largest message).

use crate::error::WriteError;
use crate::format::{Record, format_string};
use crate::spec::{self, LogLevel, msg};
use std::fs::File;
use std::io::Write;
use std::marker::PhantomData;
use std::path::Path;

/// The largest [`FlushPolicy::max_bytes`] accepted.
pub const MAX_FLUSH_BYTES: usize = 64 << 20;

/// When the buffer is written to the output. The defaults bound the loss of
/// a killed process to 0.1 s of log time (or 16 KiB, whichever comes first).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FlushPolicy {
    /// Write out when the newest timestamp is this far past the last
    /// flush (µs of log time).
    pub interval_us: u64,
    /// Write out when this many bytes are buffered.
    pub max_bytes: usize,
    /// Append a SYNC message before each flush (lets a reader resynchronise
    /// after corruption; 11 bytes per flush).
    pub sync_each_flush: bool,
}

impl Default for FlushPolicy {
    fn default() -> Self {
        FlushPolicy {
            interval_us: 100_000,
            max_bytes: 16 * 1024,
            sync_each_flush: true,
        }
    }
}

/// A subscription: the message id of one instance (`multi_id`) of a topic,
/// returned by [`UlogWriter::add_logged`]. Cheap to copy.
#[derive(Debug)]
pub struct Topic<R> {
    msg_id: u16,
    multi_id: u8,
    _record: PhantomData<fn() -> R>,
}

impl<R> Clone for Topic<R> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<R> Copy for Topic<R> {}

impl<R> Topic<R> {
    /// The ULog message id.
    pub fn msg_id(&self) -> u16 {
        self.msg_id
    }
    /// The instance number of the topic.
    pub fn multi_id(&self) -> u8 {
        self.multi_id
    }
}

/// Counters of what a writer wrote.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WriterStats {
    /// Data messages written.
    pub data_messages: u64,
    /// LOGGING messages written.
    pub log_messages: u64,
    /// Bytes handed to the output so far (header included).
    pub bytes_flushed: u64,
    /// Flushes done.
    pub flushes: u64,
}

/// Writes a ULog file into `W` (a `File` for a flight log).
#[derive(Debug)]
pub struct UlogWriter<W: Write> {
    out: W,
    file: String,
    buf: Vec<u8>,
    policy: FlushPolicy,
    formats: Vec<(&'static str, &'static [crate::format::FieldDef])>,
    subscriptions: Vec<(&'static str, u8)>,
    data_section: bool,
    last_flush_us: Option<u64>,
    newest_us: u64,
    stats: WriterStats,
}

/// The `action` of the [`WriteError::Io`] of a create refused because a
/// file is already at the path.
pub const EXISTS_ACTION: &str = "create it: a file is already there (a log is never overwritten)";

/// At most this many sequence numbers are tried by
/// [`UlogWriter::create_numbered`] after the one its scan found free (each
/// taken meanwhile by another process).
pub const MAX_NUMBER_TRIES: u32 = 1000;

/// The sequence number of a numbered log's file name
/// `<stem>-<NNNN>-<anything>.ulg` (see [`UlogWriter::create_numbered`]).
pub fn log_number(file_name: &str, stem: &str) -> Option<u32> {
    let rest = file_name.strip_prefix(stem)?.strip_prefix('-')?;
    let rest = rest.strip_suffix(".ulg")?;
    let (digits, _) = rest.split_once('-')?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// The UTC stamp of a log's file name, `YYYYMMDDTHHMMSSZ`, from seconds
/// since 1970 (a board without a real-time clock gives 1970: the sequence
/// number keeps its names apart).
pub fn utc_stamp(unix_s: u64) -> String {
    use chrono::{Datelike, Timelike};
    let t = i64::try_from(unix_s)
        .ok()
        .and_then(|s| chrono::DateTime::from_timestamp(s, 0))
        .unwrap_or_default();
    format!(
        "{:04}{:02}{:02}T{:02}{:02}{:02}Z",
        t.year(),
        t.month(),
        t.day(),
        t.hour(),
        t.minute(),
        t.second()
    )
}

impl UlogWriter<File> {
    /// Create a new file at `path` (never an existing one: a file already
    /// there is an error, [`EXISTS_ACTION`], and is left as it was) and write
    /// the header and flag bits; `start_us` is the header timestamp (µs on
    /// the log's clock).
    pub fn create(path: &Path, start_us: u64, policy: FlushPolicy) -> Result<Self, WriteError> {
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
            .map_err(|source| WriteError::Io {
                file: path.display().to_string(),
                action: if source.kind() == std::io::ErrorKind::AlreadyExists {
                    EXISTS_ACTION
                } else {
                    "create"
                },
                source,
            })?;
        Self::with_name(file, path.display().to_string(), start_us, policy)
    }

    /// As [`Self::create`], replacing (truncating) a file already at
    /// `path`: for outputs whose folder is a run's own (a simulation run
    /// flown again into its folder), never for a flight log.
    pub fn create_replacing(
        path: &Path,
        start_us: u64,
        policy: FlushPolicy,
    ) -> Result<Self, WriteError> {
        let file = File::create(path).map_err(|source| WriteError::Io {
            file: path.display().to_string(),
            action: "create",
            source,
        })?;
        Self::with_name(file, path.display().to_string(), start_us, policy)
    }

    /// Create the next numbered log in the folder `dir`:
    /// `<stem>-<NNNN>-<YYYYMMDDTHHMMSSZ>.ulg`, `NNNN` one more than the
    /// largest number of the folder's `<stem>-<NNNN>-….ulg` files (1 in an
    /// empty folder), the stamp [`utc_stamp`]`(unix_s)`. The file is created
    /// exclusively ([`Self::create`]); a name taken meanwhile (another
    /// process) moves on to the next number, at most [`MAX_NUMBER_TRIES`]
    /// times. Names stay distinct whatever the clock says: two logs in one
    /// second, a board without a real-time clock restarting at 1970. Returns
    /// the writer and the file's path.
    pub fn create_numbered(
        dir: &Path,
        stem: &str,
        unix_s: u64,
        start_us: u64,
        policy: FlushPolicy,
    ) -> Result<(Self, std::path::PathBuf), WriteError> {
        let dir_err = |source, action| WriteError::Io {
            file: dir.display().to_string(),
            action,
            source,
        };
        check_name(stem).map_err(|rule| WriteError::Invalid {
            file: dir.display().to_string(),
            what: format!("log name stem `{stem}`"),
            rule,
        })?;
        let mut largest = 0u32;
        for entry in std::fs::read_dir(dir).map_err(|e| dir_err(e, "list the folder"))? {
            let entry = entry.map_err(|e| dir_err(e, "list the folder"))?;
            if let Some(n) = entry.file_name().to_str().and_then(|n| log_number(n, stem)) {
                largest = largest.max(n);
            }
        }
        let stamp = utc_stamp(unix_s);
        let mut last = None;
        for i in 1..=MAX_NUMBER_TRIES {
            let Some(n) = largest.checked_add(i) else {
                break;
            };
            let path = dir.join(format!("{stem}-{n:04}-{stamp}.ulg"));
            match Self::create(&path, start_us, policy) {
                Ok(w) => return Ok((w, path)),
                Err(WriteError::Io { action, source, .. }) if action == EXISTS_ACTION => {
                    last = Some(source);
                }
                Err(e) => return Err(e),
            }
        }
        Err(WriteError::Io {
            file: dir.display().to_string(),
            action: "find a free log number (every one tried was taken)",
            source: last.unwrap_or_else(|| std::io::Error::other("log numbers exhausted")),
        })
    }

    /// Flush, then ask the OS to put the file's data on the storage
    /// (`fsync`): for power loss; a killed process needs only the flush.
    pub fn sync_to_storage(&mut self) -> Result<(), WriteError> {
        self.flush()?;
        self.out.sync_data().map_err(|source| WriteError::Io {
            file: self.file.clone(),
            action: "sync",
            source,
        })
    }
}

impl<W: Write> UlogWriter<W> {
    /// A writer into any byte sink; writes the header and flag bits.
    pub fn new(out: W, start_us: u64, policy: FlushPolicy) -> Result<Self, WriteError> {
        Self::with_name(out, "<stream>".to_string(), start_us, policy)
    }

    /// A writer into `out`, named `file` in errors.
    pub fn with_name(
        out: W,
        file: String,
        start_us: u64,
        policy: FlushPolicy,
    ) -> Result<Self, WriteError> {
        if policy.max_bytes > MAX_FLUSH_BYTES {
            return Err(WriteError::Invalid {
                file,
                what: format!("flush policy max_bytes = {}", policy.max_bytes),
                rule: "at most 64 MiB (the buffer is reserved once)",
            });
        }
        // room for the threshold plus the largest message that crosses it
        let cap = policy.max_bytes + 2 * (spec::MAX_PAYLOAD + spec::MSG_HEADER_LEN);
        let mut w = UlogWriter {
            out,
            file,
            buf: Vec::with_capacity(cap),
            policy,
            formats: Vec::new(),
            subscriptions: Vec::new(),
            data_section: false,
            last_flush_us: None,
            newest_us: start_us,
            stats: WriterStats::default(),
        };
        w.buf.extend_from_slice(&spec::MAGIC);
        w.buf.push(spec::VERSION);
        w.buf.extend_from_slice(&start_us.to_le_bytes());
        // Flag bits: no compat or incompat flags, no appended data.
        let flags = [0u8; spec::FLAG_BITS_LEN];
        w.push_message(msg::FLAG_BITS, &[&flags])?;
        Ok(w)
    }

    /// The file name used in errors.
    pub fn file_name(&self) -> &str {
        &self.file
    }

    /// What was written so far.
    pub fn stats(&self) -> WriterStats {
        self.stats
    }

    /// Bytes encoded but not yet written to the output (what a killed
    /// process would lose).
    pub fn buffered_bytes(&self) -> usize {
        self.buf.len()
    }

    /// The output (e.g. the `Vec<u8>` of a test); call [`Self::finish`]
    /// first to have everything in it.
    pub fn get_ref(&self) -> &W {
        &self.out
    }

    fn invalid(&self, what: impl Into<String>, rule: &'static str) -> WriteError {
        WriteError::Invalid {
            file: self.file.clone(),
            what: what.into(),
            rule,
        }
    }

    /// Append one message (header + payload parts) to the buffer.
    fn push_message(&mut self, kind: u8, parts: &[&[u8]]) -> Result<(), WriteError> {
        let len: usize = parts.iter().map(|p| p.len()).sum();
        let Ok(len16) = u16::try_from(len) else {
            return Err(self.invalid(
                format!("a `{}` message of {len} bytes", kind as char),
                "a ULog message holds at most 65535 bytes",
            ));
        };
        self.buf.extend_from_slice(&len16.to_le_bytes());
        self.buf.push(kind);
        for p in parts {
            self.buf.extend_from_slice(p);
        }
        Ok(())
    }

    fn close_check(&self, what: &str) -> Result<(), WriteError> {
        if self.data_section {
            return Err(WriteError::DefinitionsClosed {
                file: self.file.clone(),
                what: what.to_string(),
            });
        }
        Ok(())
    }

    /// Declare the format of record type `R` (definitions section only).
    /// Declaring the same type again is a no-op.
    pub fn add_format<R: Record>(&mut self) -> Result<(), WriteError> {
        if let Some((_, fields)) = self.formats.iter().find(|(n, _)| *n == R::NAME) {
            if *fields == R::FIELDS {
                return Ok(());
            }
            return Err(WriteError::Duplicate {
                file: self.file.clone(),
                what: format!("format `{}`", R::NAME),
            });
        }
        self.close_check(&format!("format `{}`", R::NAME))?;
        check_name(R::NAME).map_err(|rule| self.invalid(format!("topic `{}`", R::NAME), rule))?;
        let s = format_string::<R>();
        self.push_message(msg::FORMAT, &[s.as_bytes()])?;
        self.formats.push((R::NAME, R::FIELDS));
        Ok(())
    }

    /// An INFO message with key `"<c type> <name>"` and raw value bytes.
    fn info_raw(&mut self, kind: u8, key: &str, value: &[u8]) -> Result<(), WriteError> {
        let Ok(key_len) = u8::try_from(key.len()) else {
            return Err(self.invalid(format!("key `{key}`"), "a ULog key holds at most 255 bytes"));
        };
        self.push_message(kind, &[&[key_len], key.as_bytes(), value])
    }

    /// An information string (`char[len] name`), e.g. `sys_name`, `ver_sw`.
    /// Allowed in both sections.
    pub fn info_str(&mut self, name: &str, value: &str) -> Result<(), WriteError> {
        check_name(name).map_err(|rule| self.invalid(format!("info `{name}`"), rule))?;
        let key = format!("char[{}] {name}", value.len());
        self.info_raw(msg::INFO, &key, value.as_bytes())
    }

    /// An `int32_t` information, e.g. `time_ref_utc` (UTC offset, s).
    pub fn info_i32(&mut self, name: &str, value: i32) -> Result<(), WriteError> {
        check_name(name).map_err(|rule| self.invalid(format!("info `{name}`"), rule))?;
        self.info_raw(msg::INFO, &format!("int32_t {name}"), &value.to_le_bytes())
    }

    /// A `uint32_t` information, e.g. `ver_hw_subtype`.
    pub fn info_u32(&mut self, name: &str, value: u32) -> Result<(), WriteError> {
        check_name(name).map_err(|rule| self.invalid(format!("info `{name}`"), rule))?;
        self.info_raw(msg::INFO, &format!("uint32_t {name}"), &value.to_le_bytes())
    }

    /// A `uint64_t` information.
    pub fn info_u64(&mut self, name: &str, value: u64) -> Result<(), WriteError> {
        check_name(name).map_err(|rule| self.invalid(format!("info `{name}`"), rule))?;
        self.info_raw(msg::INFO, &format!("uint64_t {name}"), &value.to_le_bytes())
    }

    /// A `float` parameter (the only parameter types are `float` and
    /// `int32_t`). In the data section it records a parameter change.
    pub fn parameter_f32(&mut self, name: &str, value: f32) -> Result<(), WriteError> {
        check_name(name).map_err(|rule| self.invalid(format!("parameter `{name}`"), rule))?;
        self.info_raw(
            msg::PARAMETER,
            &format!("float {name}"),
            &value.to_le_bytes(),
        )
    }

    /// An `int32_t` parameter.
    pub fn parameter_i32(&mut self, name: &str, value: i32) -> Result<(), WriteError> {
        check_name(name).map_err(|rule| self.invalid(format!("parameter `{name}`"), rule))?;
        self.info_raw(
            msg::PARAMETER,
            &format!("int32_t {name}"),
            &value.to_le_bytes(),
        )
    }

    /// Subscribe instance `multi_id` of topic `R` (its format declared
    /// before); opens the data section. Returns the handle for
    /// [`Self::write`].
    pub fn add_logged<R: Record>(&mut self, multi_id: u8) -> Result<Topic<R>, WriteError> {
        if !self.formats.iter().any(|(n, _)| *n == R::NAME) {
            return Err(WriteError::UnknownFormat {
                file: self.file.clone(),
                topic: R::NAME.to_string(),
            });
        }
        if self.subscriptions.contains(&(R::NAME, multi_id)) {
            return Err(WriteError::Duplicate {
                file: self.file.clone(),
                what: format!("topic `{}` instance {multi_id}", R::NAME),
            });
        }
        let Ok(msg_id) = u16::try_from(self.subscriptions.len()) else {
            return Err(WriteError::TooManyTopics {
                file: self.file.clone(),
            });
        };
        if msg_id == u16::MAX {
            return Err(WriteError::TooManyTopics {
                file: self.file.clone(),
            });
        }
        self.data_section = true;
        self.push_message(
            msg::ADD_LOGGED,
            &[&[multi_id], &msg_id.to_le_bytes(), R::NAME.as_bytes()],
        )?;
        self.subscriptions.push((R::NAME, multi_id));
        Ok(Topic {
            msg_id,
            multi_id,
            _record: PhantomData,
        })
    }

    /// Write one data record. No allocation; flushes per the policy.
    pub fn write<R: Record>(&mut self, topic: Topic<R>, record: &R) -> Result<(), WriteError> {
        let known = self
            .subscriptions
            .get(usize::from(topic.msg_id))
            .is_some_and(|(n, m)| *n == R::NAME && *m == topic.multi_id);
        if !known {
            return Err(WriteError::UnknownTopic {
                file: self.file.clone(),
                msg_id: topic.msg_id,
            });
        }
        let size = R::SIZE + 2;
        let Ok(size16) = u16::try_from(size) else {
            return Err(self.invalid(
                format!("topic `{}`", R::NAME),
                "a ULog message holds at most 65535 bytes",
            ));
        };
        let start = self.buf.len();
        self.buf.extend_from_slice(&size16.to_le_bytes());
        self.buf.push(msg::DATA);
        self.buf.extend_from_slice(&topic.msg_id.to_le_bytes());
        self.buf.resize(start + spec::MSG_HEADER_LEN + size, 0);
        // The slice is exactly R::SIZE long: encode cannot fail.
        let _ = record.encode(&mut self.buf[start + spec::MSG_HEADER_LEN + 2..]);
        self.stats.data_messages += 1;
        self.after_record(record.timestamp_us())
    }

    /// A LOGGING message (text shown by the log viewers); texts longer than
    /// a message can hold are cut at a character boundary.
    pub fn log(
        &mut self,
        level: LogLevel,
        timestamp_us: u64,
        text: &str,
    ) -> Result<(), WriteError> {
        let max = spec::MAX_PAYLOAD - 9;
        let mut end = text.len().min(max);
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        self.push_message(
            msg::LOGGING,
            &[
                &[level.byte()],
                &timestamp_us.to_le_bytes(),
                &text.as_bytes()[..end],
            ],
        )?;
        self.stats.log_messages += 1;
        self.after_record(timestamp_us)
    }

    /// A DROPOUT message: data was lost for `duration_ms` (e.g. the logger's
    /// ring overflowed), written at log time `timestamp_us`.
    pub fn dropout(&mut self, duration_ms: u16, timestamp_us: u64) -> Result<(), WriteError> {
        self.push_message(msg::DROPOUT, &[&duration_ms.to_le_bytes()])?;
        self.after_record(timestamp_us)
    }

    /// A SYNC message.
    pub fn sync_marker(&mut self) -> Result<(), WriteError> {
        self.push_message(msg::SYNC, &[&spec::SYNC_MAGIC])
    }

    fn after_record(&mut self, timestamp_us: u64) -> Result<(), WriteError> {
        self.newest_us = self.newest_us.max(timestamp_us);
        let due_time = match self.last_flush_us {
            Some(t) => self.newest_us.saturating_sub(t) >= self.policy.interval_us,
            None => true,
        };
        if due_time || self.buf.len() >= self.policy.max_bytes {
            if self.policy.sync_each_flush && self.data_section {
                self.sync_marker()?;
            }
            self.flush()?;
        }
        Ok(())
    }

    /// Write the buffered messages to the output and flush it.
    pub fn flush(&mut self) -> Result<(), WriteError> {
        let io = |source, action| WriteError::Io {
            file: self.file.clone(),
            action,
            source,
        };
        if !self.buf.is_empty() {
            self.out.write_all(&self.buf).map_err(|e| io(e, "write"))?;
            self.stats.bytes_flushed += self.buf.len() as u64;
            self.buf.clear();
        }
        self.out.flush().map_err(|e| io(e, "flush"))?;
        self.stats.flushes += 1;
        self.last_flush_us = Some(self.newest_us);
        Ok(())
    }

    /// Flush and return the output.
    pub fn finish(mut self) -> Result<W, WriteError> {
        self.flush()?;
        Ok(self.out)
    }
}

/// A ULog key or topic name: non-empty ASCII letters, digits and `_`,
/// starting with a letter or `_` (so the key string parses unambiguously).
fn check_name(name: &str) -> Result<(), &'static str> {
    let ok_first = name
        .bytes()
        .next()
        .is_some_and(|b| b.is_ascii_alphabetic() || b == b'_');
    if !ok_first || !name.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_') {
        return Err("names are ASCII letters, digits and `_`, not starting with a digit");
    }
    if name.len() > 200 {
        return Err("names are at most 200 bytes");
    }
    Ok(())
}

/// The ULog timestamp (µs) of a time in seconds: rounded to the nearest µs;
/// an error for negative, non-finite or too large times.
pub fn timestamp_us(t_s: f64, what: &'static str) -> Result<u64, WriteError> {
    let us = (t_s * 1e6).round();
    // `u64::MAX as f64` rounds to 2^64 exactly: anything at or beyond is refused.
    if !us.is_finite() || !(0.0..u64::MAX as f64).contains(&us) {
        return Err(WriteError::BadTime { what, value_s: t_s });
    }
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)] // checked above
    Ok(us as u64)
}
