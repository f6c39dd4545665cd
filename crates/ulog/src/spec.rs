//! Constants of the ULog file format (PX4 "ULog File Format", version 1).

/// The 7 magic bytes that open every ULog file: `ULog` 0x01 0x12 0x35.
pub const MAGIC: [u8; 7] = [0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35];
/// The file format version written after the magic.
pub const VERSION: u8 = 1;
/// Size of the file header: magic, version, timestamp (µs).
pub const HEADER_LEN: usize = 16;
/// Size of every message header: `uint16_t msg_size` + `uint8_t msg_type`.
pub const MSG_HEADER_LEN: usize = 3;
/// The largest message payload (`msg_size` is a `uint16_t`).
pub const MAX_PAYLOAD: usize = u16::MAX as usize;
/// The payload of a SYNC message.
pub const SYNC_MAGIC: [u8; 8] = [0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12];
/// Size of the flag bits message payload: compat\[8\], incompat\[8\],
/// appended offsets\[3\] (u64).
pub const FLAG_BITS_LEN: usize = 40;

/// Message type bytes.
pub mod msg {
    /// Flag bits (first message after the header).
    pub const FLAG_BITS: u8 = b'B';
    /// Format definition.
    pub const FORMAT: u8 = b'F';
    /// Information (key, value).
    pub const INFO: u8 = b'I';
    /// Information split over several messages.
    pub const INFO_MULTIPLE: u8 = b'M';
    /// Parameter (`int32_t` or `float`).
    pub const PARAMETER: u8 = b'P';
    /// Parameter default.
    pub const PARAMETER_DEFAULT: u8 = b'Q';
    /// Subscription of a topic instance to a message id.
    pub const ADD_LOGGED: u8 = b'A';
    /// Unsubscription.
    pub const REMOVE_LOGGED: u8 = b'R';
    /// Data of a subscribed topic.
    pub const DATA: u8 = b'D';
    /// Text log message.
    pub const LOGGING: u8 = b'L';
    /// Tagged text log message.
    pub const LOGGING_TAGGED: u8 = b'C';
    /// Synchronisation marker.
    pub const SYNC: u8 = b'S';
    /// Dropout: data lost for a duration (ms).
    pub const DROPOUT: u8 = b'O';
}

/// The log level of a LOGGING message (syslog levels, written as the ASCII
/// digits `'0'`…`'7'` as PX4 does).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum LogLevel {
    /// System is unusable.
    Emergency,
    /// Action must be taken immediately.
    Alert,
    /// Critical conditions.
    Critical,
    /// Error conditions.
    Error,
    /// Warning conditions.
    Warning,
    /// Normal but significant condition.
    Notice,
    /// Informational.
    Info,
    /// Debug-level messages.
    Debug,
}

impl LogLevel {
    /// The byte written in the file (`'0'` = emergency … `'7'` = debug).
    pub const fn byte(self) -> u8 {
        b'0' + self as u8
    }

    /// The level of a byte read from a file: the ASCII digits PX4 writes,
    /// and the raw values 0…7 some writers use.
    pub const fn from_byte(b: u8) -> Option<LogLevel> {
        let v = match b {
            b'0'..=b'7' => b - b'0',
            0..=7 => b,
            _ => return None,
        };
        Some(match v {
            0 => LogLevel::Emergency,
            1 => LogLevel::Alert,
            2 => LogLevel::Critical,
            3 => LogLevel::Error,
            4 => LogLevel::Warning,
            5 => LogLevel::Notice,
            6 => LogLevel::Info,
            _ => LogLevel::Debug,
        })
    }

    /// Lower-case name (`error`, `warning`, …), as pyulog prints it.
    pub const fn name(self) -> &'static str {
        match self {
            LogLevel::Emergency => "emergency",
            LogLevel::Alert => "alert",
            LogLevel::Critical => "critical",
            LogLevel::Error => "error",
            LogLevel::Warning => "warning",
            LogLevel::Notice => "notice",
            LogLevel::Info => "info",
            LogLevel::Debug => "debug",
        }
    }
}
