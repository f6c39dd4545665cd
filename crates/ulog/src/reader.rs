//! A streaming ULog reader: one message at a time from any `Read`, with
//! bounded memory (one message of at most 64 KiB), typed errors and no
//! panics on any input.
//!
//! A file cut short (a writer killed mid-write) yields every complete
//! message and then [`ReadError::Truncated`]. Message sizes are 16-bit, so
//! each step reads at most 65 538 bytes and always advances: no input can
//! make the reader hang or allocate without bound.

use crate::error::ReadError;
use crate::format::UlogType;
use crate::spec::{self, LogLevel, msg};
use helicon_config::escape_control;
use std::io::{ErrorKind, Read};

/// The file header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileHeader {
    /// Format version (1).
    pub version: u8,
    /// Timestamp of the log start (µs).
    pub timestamp_us: u64,
}

/// One field of a FORMAT message as written in the file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FormatField {
    /// The type name: a base type (`float`) or another format's name.
    pub type_name: String,
    /// Array length, if an array.
    pub array_len: Option<usize>,
    /// Field name.
    pub name: String,
}

impl FormatField {
    /// The base type, when the field is not a nested format.
    pub fn base_type(&self) -> Option<UlogType> {
        UlogType::from_name(&self.type_name)
    }
}

/// A FORMAT message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Format {
    /// Message (type) name.
    pub name: String,
    /// Fields in order.
    pub fields: Vec<FormatField>,
}

/// A value of an INFO or PARAMETER message.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A signed integer.
    Int(i64),
    /// An unsigned integer.
    UInt(u64),
    /// A `float`.
    Float32(f32),
    /// A `double`.
    Float(f64),
    /// A bool.
    Bool(bool),
    /// A `char[n]` string (invalid UTF-8 replaced).
    Str(String),
    /// An array of numbers.
    Array(Vec<Value>),
    /// A type this reader does not decode (raw bytes).
    Raw(Vec<u8>),
}

/// Floats print in their shortest round-trip form, in plain notation for
/// ordinary magnitudes and in exponent notation outside [1e-4, 1e15) (the
/// rule of the toolkit's other number printing: 1e-300 stays `1e-300`).
fn plain(v: f64) -> bool {
    v == 0.0 || !v.is_finite() || (1e-4..1e15).contains(&v.abs())
}

impl std::fmt::Display for Value {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::Int(v) => write!(f, "{v}"),
            Value::UInt(v) => write!(f, "{v}"),
            Value::Float32(v) => {
                if plain(f64::from(*v)) {
                    write!(f, "{v}")
                } else {
                    write!(f, "{v:e}")
                }
            }
            Value::Float(v) => {
                if plain(*v) {
                    write!(f, "{v}")
                } else {
                    write!(f, "{v:e}")
                }
            }
            Value::Bool(v) => write!(f, "{}", u8::from(*v)),
            Value::Str(s) => f.write_str(s),
            Value::Array(a) => {
                f.write_str("[")?;
                for (i, v) in a.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{v}")?;
                }
                f.write_str("]")
            }
            Value::Raw(b) => write!(f, "<{} bytes>", b.len()),
        }
    }
}

/// A key-value message (INFO, INFO_MULTIPLE, PARAMETER, PARAMETER_DEFAULT).
#[derive(Debug, Clone, PartialEq)]
pub struct KeyValue {
    /// The key's type as written (`char[7]`, `float`, `int32_t`).
    pub type_name: String,
    /// The key's name.
    pub name: String,
    /// The decoded value.
    pub value: Value,
}

/// One part of an INFO_MULTIPLE sequence as written: its key and the bytes
/// of its value, undecoded (the parts of a long text or blob are joined as
/// bytes, [`MultiInfo`], and decoded when asked).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InfoPart<'a> {
    /// The element type as written (`char`, `uint8_t`): the key's type
    /// without its array length.
    pub element_type: String,
    /// The key's name.
    pub name: String,
    /// The value's bytes (of a `char[n]` part, all that follow the key; of
    /// an array of numbers, its `n` elements).
    pub bytes: &'a [u8],
}

/// An INFO_MULTIPLE sequence, its parts' bytes joined: one allocation the
/// size of the value, decoded by [`MultiInfo::value`] or printed by its
/// `Display` (which decodes element by element, allocating nothing per
/// element).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MultiInfo {
    /// The element type as written (`char`, `uint8_t`).
    pub element_type: String,
    /// The key's name.
    pub name: String,
    /// The joined bytes of the parts.
    pub bytes: Vec<u8>,
}

impl MultiInfo {
    /// The element type, when it is a base type.
    pub fn base_type(&self) -> Option<UlogType> {
        UlogType::from_name(&self.element_type)
    }

    /// The key's type of the joined value (`char[1234]`).
    pub fn type_name(&self) -> String {
        let n = self
            .base_type()
            .map_or(self.bytes.len(), |t| self.bytes.len() / t.size());
        format!("{}[{n}]", self.element_type)
    }

    /// The joined value decoded: text for `char` (invalid UTF-8 replaced),
    /// an array for another base type, raw bytes for an unknown type.
    pub fn value(&self) -> Value {
        match self.base_type() {
            Some(UlogType::Char) => Value::Str(text(&self.bytes)),
            Some(t) => Value::Array(
                self.bytes
                    .chunks_exact(t.size())
                    .map(|c| decode_value(t, c))
                    .collect(),
            ),
            None => Value::Raw(self.bytes.clone()),
        }
    }
}

impl std::fmt::Display for MultiInfo {
    /// As [`Value`]'s `Display` of [`MultiInfo::value`].
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.base_type() {
            Some(UlogType::Char) => {
                for chunk in self.bytes.utf8_chunks() {
                    f.write_str(chunk.valid())?;
                    if !chunk.invalid().is_empty() {
                        f.write_str("\u{FFFD}")?;
                    }
                }
                Ok(())
            }
            Some(t) => {
                f.write_str("[")?;
                for (i, c) in self.bytes.chunks_exact(t.size()).enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{}", decode_value(t, c))?;
                }
                f.write_str("]")
            }
            None => write!(f, "<{} bytes>", self.bytes.len()),
        }
    }
}

/// One message of a ULog file.
#[derive(Debug, Clone, PartialEq)]
pub enum Message<'a> {
    /// Flag bits.
    FlagBits {
        /// Compatible flags.
        compat: [u8; 8],
        /// Incompatible flags.
        incompat: [u8; 8],
        /// Offsets of appended data sections.
        appended_offsets: [u64; 3],
    },
    /// A format definition.
    Format(Format),
    /// An information.
    Info(KeyValue),
    /// Part of a multi-message information.
    InfoMultiple {
        /// This continues the previous message of the same key.
        is_continued: bool,
        /// Key and this part's bytes.
        part: InfoPart<'a>,
    },
    /// A parameter (value or change).
    Parameter(KeyValue),
    /// A parameter default.
    ParameterDefault {
        /// Which defaults (bit 0 system, bit 1 current configuration).
        default_types: u8,
        /// Key and value.
        kv: KeyValue,
    },
    /// A subscription.
    AddLogged {
        /// Instance.
        multi_id: u8,
        /// Message id used by the data messages.
        msg_id: u16,
        /// Format name.
        name: String,
    },
    /// An unsubscription.
    RemoveLogged {
        /// Message id.
        msg_id: u16,
    },
    /// A data record (payload without the message id).
    Data {
        /// Message id.
        msg_id: u16,
        /// The record's bytes.
        payload: &'a [u8],
    },
    /// A text message.
    Logging {
        /// Level (`None` for a byte that is no level).
        level: Option<LogLevel>,
        /// Tag (tagged messages only).
        tag: Option<u16>,
        /// Time (µs).
        timestamp_us: u64,
        /// Text (invalid UTF-8 replaced).
        text: String,
    },
    /// A sync marker.
    Sync,
    /// Data lost for `duration_ms`.
    Dropout {
        /// Duration (ms).
        duration_ms: u16,
    },
    /// A message type this reader does not know (skipped by the spec's rule).
    Unknown {
        /// Type byte.
        kind: u8,
    },
}

/// Reads the messages of a ULog file one by one.
#[derive(Debug)]
pub struct UlogReader<R: Read> {
    src: R,
    file: String,
    offset: u64,
    buf: Vec<u8>,
    header: FileHeader,
    done: bool,
}

/// Read until `buf` is full or the input ends; returns the bytes read.
fn read_full<R: Read>(src: &mut R, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match src.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

fn kind_name(kind: u8) -> String {
    if kind.is_ascii_graphic() {
        format!("'{}'", kind as char)
    } else {
        format!("0x{kind:02x}")
    }
}

/// The reader of a ULog file opened by [`UlogReader::open`].
pub type FileReader = UlogReader<std::io::BufReader<helicon_config::Bounded<std::fs::File>>>;

impl FileReader {
    /// Open the ULog file at `path` and read its header. Only a regular file
    /// is opened (a FIFO or a device such as `/dev/zero` is refused before
    /// any read, [`helicon_config::open_bounded`]); the errors name it.
    pub fn open(path: &std::path::Path) -> Result<FileReader, ReadError> {
        let name = path.display().to_string();
        let src = helicon_config::open_bounded(path, u64::MAX).map_err(|e| match e {
            helicon_config::ConfigError::Io { source, .. } => ReadError::Io {
                file: name.clone(),
                source,
            },
            other => ReadError::Io {
                file: name.clone(),
                source: std::io::Error::other(other.to_string()),
            },
        })?;
        UlogReader::new(std::io::BufReader::new(src), &name)
    }
}

impl<R: Read> UlogReader<R> {
    /// Read the header of `src`; `file` names it in errors.
    pub fn new(mut src: R, file: &str) -> Result<Self, ReadError> {
        let mut h = [0u8; spec::HEADER_LEN];
        let n = read_full(&mut src, &mut h).map_err(|source| ReadError::Io {
            file: file.to_string(),
            source,
        })?;
        if n >= spec::MAGIC.len() && h[..spec::MAGIC.len()] != spec::MAGIC
            || n < spec::MAGIC.len() && h[..n] != spec::MAGIC[..n]
        {
            return Err(ReadError::BadMagic {
                file: file.to_string(),
            });
        }
        if n < spec::HEADER_LEN {
            return Err(ReadError::Truncated {
                file: file.to_string(),
                offset: 0,
                kind: "header".to_string(),
            });
        }
        let mut ts = [0u8; 8];
        ts.copy_from_slice(&h[8..16]);
        Ok(UlogReader {
            src,
            file: file.to_string(),
            offset: spec::HEADER_LEN as u64,
            buf: Vec::with_capacity(1024),
            header: FileHeader {
                version: h[7],
                timestamp_us: u64::from_le_bytes(ts),
            },
            done: false,
        })
    }

    /// The file header.
    pub fn header(&self) -> FileHeader {
        self.header
    }

    /// Byte offset of the next message (the end of the last one read).
    pub fn offset(&self) -> u64 {
        self.offset
    }

    /// The file name used in errors.
    pub fn file_name(&self) -> &str {
        &self.file
    }

    fn malformed(&self, at: u64, kind: u8, rule: impl Into<String>) -> ReadError {
        ReadError::Malformed {
            file: self.file.clone(),
            offset: at,
            kind: kind_name(kind),
            rule: rule.into(),
        }
    }

    /// The next message, `Ok(None)` at a clean end of file. After an error
    /// the reader returns `Ok(None)`.
    pub fn next_message(&mut self) -> Result<Option<Message<'_>>, ReadError> {
        if self.done {
            return Ok(None);
        }
        let at = self.offset;
        let io = |file: &str, source| ReadError::Io {
            file: file.to_string(),
            source,
        };
        let mut h = [0u8; spec::MSG_HEADER_LEN];
        let n = read_full(&mut self.src, &mut h).map_err(|e| io(&self.file, e))?;
        if n == 0 {
            self.done = true;
            return Ok(None);
        }
        let truncated = |file: &str, kind: String| ReadError::Truncated {
            file: file.to_string(),
            offset: at,
            kind,
        };
        if n < spec::MSG_HEADER_LEN {
            self.done = true;
            return Err(truncated(&self.file, "message header".to_string()));
        }
        let size = usize::from(u16::from_le_bytes([h[0], h[1]]));
        let kind = h[2];
        self.buf.resize(size, 0);
        let got = read_full(&mut self.src, &mut self.buf).map_err(|e| io(&self.file, e))?;
        if got < size {
            self.done = true;
            return Err(truncated(&self.file, kind_name(kind)));
        }
        self.offset += (spec::MSG_HEADER_LEN + size) as u64;
        match parse_message(kind, &self.buf) {
            Ok(m) => Ok(Some(m)),
            Err(rule) => {
                self.done = true;
                Err(self.malformed(at, kind, rule))
            }
        }
    }
}

fn u16_at(b: &[u8], i: usize) -> Option<u16> {
    Some(u16::from_le_bytes([*b.get(i)?, *b.get(i + 1)?]))
}

fn u64_at(b: &[u8], i: usize) -> Option<u64> {
    let s = b.get(i..i + 8)?;
    let mut a = [0u8; 8];
    a.copy_from_slice(s);
    Some(u64::from_le_bytes(a))
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Parse one message payload; `Err` is the rule broken.
fn parse_message(kind: u8, b: &[u8]) -> Result<Message<'_>, String> {
    let short = || format!("{} bytes is too short", b.len());
    Ok(match kind {
        msg::FLAG_BITS => {
            if b.len() < spec::FLAG_BITS_LEN {
                return Err(short());
            }
            let mut compat = [0u8; 8];
            let mut incompat = [0u8; 8];
            compat.copy_from_slice(&b[..8]);
            incompat.copy_from_slice(&b[8..16]);
            let mut appended_offsets = [0u64; 3];
            for (i, o) in appended_offsets.iter_mut().enumerate() {
                *o = u64_at(b, 16 + 8 * i).ok_or_else(short)?;
            }
            Message::FlagBits {
                compat,
                incompat,
                appended_offsets,
            }
        }
        msg::FORMAT => Message::Format(parse_format(b)?),
        msg::INFO => Message::Info(parse_key_value(b)?),
        msg::INFO_MULTIPLE => {
            let (&cont, rest) = b.split_first().ok_or_else(short)?;
            Message::InfoMultiple {
                is_continued: cont != 0,
                part: parse_info_part(rest)?,
            }
        }
        msg::PARAMETER => Message::Parameter(parse_key_value(b)?),
        msg::PARAMETER_DEFAULT => {
            let (&default_types, rest) = b.split_first().ok_or_else(short)?;
            Message::ParameterDefault {
                default_types,
                kv: parse_key_value(rest)?,
            }
        }
        msg::ADD_LOGGED => {
            if b.len() < 4 {
                return Err(short());
            }
            Message::AddLogged {
                multi_id: b[0],
                msg_id: u16_at(b, 1).ok_or_else(short)?,
                name: text(&b[3..]),
            }
        }
        msg::REMOVE_LOGGED => Message::RemoveLogged {
            msg_id: u16_at(b, 0).ok_or_else(short)?,
        },
        msg::DATA => Message::Data {
            msg_id: u16_at(b, 0).ok_or_else(short)?,
            payload: &b[2..],
        },
        msg::LOGGING => Message::Logging {
            level: LogLevel::from_byte(*b.first().ok_or_else(short)?),
            tag: None,
            timestamp_us: u64_at(b, 1).ok_or_else(short)?,
            text: text(&b[9..]),
        },
        msg::LOGGING_TAGGED => Message::Logging {
            level: LogLevel::from_byte(*b.first().ok_or_else(short)?),
            tag: Some(u16_at(b, 1).ok_or_else(short)?),
            timestamp_us: u64_at(b, 3).ok_or_else(short)?,
            text: text(b.get(11..).ok_or_else(short)?),
        },
        msg::SYNC => {
            if b.get(..8) != Some(&spec::SYNC_MAGIC[..]) {
                return Err("SYNC magic bytes wrong".to_string());
            }
            Message::Sync
        }
        msg::DROPOUT => Message::Dropout {
            duration_ms: u16_at(b, 0).ok_or_else(short)?,
        },
        other => Message::Unknown { kind: other },
    })
}

/// `type name` or `type[n] name` → (type, array length, name).
fn parse_typed_name(s: &str) -> Result<(String, Option<usize>, String), String> {
    let s = s.trim();
    let (ty, name) = s
        .split_once(' ')
        .ok_or_else(|| format!("`{}` is not `type name`", escape_control(s)))?;
    let name = name.trim();
    if name.is_empty() || ty.is_empty() {
        return Err(format!("`{}` is not `type name`", escape_control(s)));
    }
    let (ty, len) = match ty.split_once('[') {
        Some((t, rest)) => {
            let n = rest
                .strip_suffix(']')
                .and_then(|n| n.parse::<usize>().ok())
                .filter(|n| *n <= spec::MAX_PAYLOAD)
                .ok_or_else(|| format!("`{}`: bad array length", escape_control(s)))?;
            (t, Some(n))
        }
        None => (ty, None),
    };
    Ok((ty.to_string(), len, name.to_string()))
}

fn parse_format(b: &[u8]) -> Result<Format, String> {
    let s = std::str::from_utf8(b).map_err(|_| "format is not UTF-8".to_string())?;
    let (name, fields) = s
        .split_once(':')
        .ok_or_else(|| "format has no `name:`".to_string())?;
    if name.is_empty() {
        return Err("format has an empty name".to_string());
    }
    let mut out = Vec::new();
    for f in fields.split(';').filter(|f| !f.trim().is_empty()) {
        let (type_name, array_len, name) = parse_typed_name(f)?;
        out.push(FormatField {
            type_name,
            array_len,
            name,
        });
    }
    Ok(Format {
        name: name.to_string(),
        fields: out,
    })
}

/// A key: its type, array length and name, and the value's bytes after it.
type SplitKey<'a> = (String, Option<usize>, String, &'a [u8]);

/// A key-value payload → (type, array length, name, value bytes).
fn split_key(b: &[u8]) -> Result<SplitKey<'_>, String> {
    let (&key_len, rest) = b.split_first().ok_or_else(|| "no key length".to_string())?;
    let key_len = usize::from(key_len);
    let key = rest
        .get(..key_len)
        .ok_or_else(|| format!("key of {key_len} bytes beyond the message"))?;
    let key = std::str::from_utf8(key).map_err(|_| "key is not UTF-8".to_string())?;
    let (type_name, array_len, name) = parse_typed_name(key)?;
    Ok((type_name, array_len, name, &rest[key_len..]))
}

fn parse_info_part(b: &[u8]) -> Result<InfoPart<'_>, String> {
    let (element_type, array_len, name, raw) = split_key(b)?;
    let bytes = match UlogType::from_name(&element_type) {
        Some(UlogType::Char) | None => raw,
        Some(t) => {
            let n = t.size() * array_len.unwrap_or(1);
            raw.get(..n).ok_or_else(|| {
                format!("value of `{}` shorter than its type", escape_control(&name))
            })?
        }
    };
    Ok(InfoPart {
        element_type,
        name,
        bytes,
    })
}

fn parse_key_value(b: &[u8]) -> Result<KeyValue, String> {
    let (type_name, array_len, name, raw) = split_key(b)?;
    let value = match (UlogType::from_name(&type_name), array_len) {
        (Some(UlogType::Char), _) => Value::Str(text(raw)),
        (Some(t), None) => {
            if raw.len() < t.size() {
                return Err(format!(
                    "value of `{}` shorter than its type",
                    escape_control(&name)
                ));
            }
            decode_value(t, raw)
        }
        (Some(t), Some(n)) => {
            if raw.len() < t.size() * n {
                return Err(format!(
                    "value of `{}` shorter than its type",
                    escape_control(&name)
                ));
            }
            Value::Array(
                raw.chunks_exact(t.size())
                    .take(n)
                    .map(|c| decode_value(t, c))
                    .collect(),
            )
        }
        (None, _) => Value::Raw(raw.to_vec()),
    };
    Ok(KeyValue {
        type_name: match array_len {
            Some(n) => format!("{type_name}[{n}]"),
            None => type_name,
        },
        name,
        value,
    })
}

/// Decode one base value from `b[..t.size()]` (the caller checks length;
/// a short slice decodes as zero bytes).
pub fn decode_value(t: UlogType, b: &[u8]) -> Value {
    let mut a = [0u8; 8];
    let n = t.size().min(b.len());
    a[..n].copy_from_slice(&b[..n]);
    match t {
        UlogType::Int8 => Value::Int(i64::from(i8::from_le_bytes([a[0]]))),
        UlogType::UInt8 | UlogType::Char => Value::UInt(u64::from(a[0])),
        UlogType::Int16 => Value::Int(i64::from(i16::from_le_bytes([a[0], a[1]]))),
        UlogType::UInt16 => Value::UInt(u64::from(u16::from_le_bytes([a[0], a[1]]))),
        UlogType::Int32 => Value::Int(i64::from(i32::from_le_bytes([a[0], a[1], a[2], a[3]]))),
        UlogType::UInt32 => Value::UInt(u64::from(u32::from_le_bytes([a[0], a[1], a[2], a[3]]))),
        UlogType::Int64 => Value::Int(i64::from_le_bytes(a)),
        UlogType::UInt64 => Value::UInt(u64::from_le_bytes(a)),
        UlogType::Float => Value::Float32(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
        UlogType::Double => Value::Float(f64::from_le_bytes(a)),
        UlogType::Bool => Value::Bool(a[0] != 0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_print_shortest_and_readable() {
        assert_eq!(Value::Float(2.5).to_string(), "2.5");
        assert_eq!(Value::Float(-1e-300).to_string(), "-1e-300");
        assert_eq!(Value::Float(2.5e16).to_string(), "2.5e16");
        assert_eq!(Value::Float(86400.0).to_string(), "86400");
        assert_eq!(Value::Float32(0.0025).to_string(), "0.0025");
        assert_eq!(Value::Float32(3e-7).to_string(), "3e-7");
        assert_eq!(Value::Float(0.1 + 0.2).to_string(), "0.30000000000000004");
        assert_eq!(Value::Bool(true).to_string(), "1");
        assert_eq!(
            Value::Array(vec![Value::Int(-3), Value::UInt(4)]).to_string(),
            "[-3, 4]"
        );
    }
}
