//! The typed errors of writing and reading ULog files.

/// An error writing a ULog file.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The output could not be written (or created).
    #[error("{file}: cannot {action}")]
    Io {
        /// The file (or `<stream>` for a writer not made from a path).
        file: String,
        /// What was being done: `create`, `write`, `flush`, `sync`.
        action: &'static str,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A format, or an info/parameter that must precede the data, was added
    /// after the first `add_logged` (the definitions section is closed).
    #[error("{file}: `{what}` must be declared before the first logged topic")]
    DefinitionsClosed {
        /// The file.
        file: String,
        /// What was declared too late.
        what: String,
    },
    /// `add_logged` of a topic whose format was not declared.
    #[error("{file}: topic `{topic}` has no declared format")]
    UnknownFormat {
        /// The file.
        file: String,
        /// The topic.
        topic: String,
    },
    /// The same topic and multi id subscribed twice, or a format declared
    /// twice with different fields.
    #[error("{file}: `{what}` declared twice")]
    Duplicate {
        /// The file.
        file: String,
        /// The topic (and multi id).
        what: String,
    },
    /// More topics than ULog message ids (65535).
    #[error("{file}: too many logged topics (ULog allows 65535 message ids)")]
    TooManyTopics {
        /// The file.
        file: String,
    },
    /// A key, name or value longer than a ULog message can hold, or with
    /// characters a ULog key cannot have.
    #[error("{file}: {what}: {rule}")]
    Invalid {
        /// The file.
        file: String,
        /// Which key or name.
        what: String,
        /// The rule broken.
        rule: &'static str,
    },
    /// A data record of a topic handle from another writer.
    #[error("{file}: message id {msg_id} was not subscribed by this writer")]
    UnknownTopic {
        /// The file.
        file: String,
        /// The message id.
        msg_id: u16,
    },
    /// A time that cannot be a ULog timestamp (negative, non-finite or
    /// beyond 2⁶⁴ µs).
    #[error("{what}: time {value_s} s is not a valid timestamp (finite, ≥ 0)")]
    BadTime {
        /// Which record.
        what: &'static str,
        /// The time given (s).
        value_s: f64,
    },
}

/// An error reading a ULog file. A truncated file is
/// [`ReadError::Truncated`]: every complete message before the cut has been
/// returned.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The input could not be read.
    #[error("{file}: cannot read")]
    Io {
        /// The file.
        file: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The file does not start with the ULog magic bytes.
    #[error("{file}: not a ULog file (bad magic bytes)")]
    BadMagic {
        /// The file.
        file: String,
    },
    /// The file ends inside a message (a writer killed mid-write): all
    /// complete messages before `offset` were read.
    #[error("{file}: truncated at byte {offset} (inside a {kind} message)")]
    Truncated {
        /// The file.
        file: String,
        /// Byte offset of the incomplete message.
        offset: u64,
        /// Its type (`header` when the file header itself is cut).
        kind: String,
    },
    /// A message whose content contradicts the specification.
    #[error("{file}: byte {offset}: {kind} message: {rule}")]
    Malformed {
        /// The file.
        file: String,
        /// Byte offset of the message.
        offset: u64,
        /// Its type.
        kind: String,
        /// What was wrong.
        rule: String,
    },
    /// The file exceeds one of the reader's limits (subscriptions, fields
    /// of a format, columns, joined information): refused before it can cost
    /// more time or memory than its size warrants. See
    /// [`crate::visit::Limits`].
    #[error("{file}: byte {offset}: more than {limit} {what} (a limit of this reader)")]
    Limit {
        /// The file.
        file: String,
        /// Byte offset of the message that went beyond the limit.
        offset: u64,
        /// What was counted (`subscriptions`, `fields in format \`x\``).
        what: String,
        /// The limit.
        limit: u64,
    },
    /// Incompatible flags this reader does not know.
    #[error("{file}: incompatible ULog flags {flags:#x} (this reader knows bit 0: appended data)")]
    Incompatible {
        /// The file.
        file: String,
        /// The first incompatible-flags byte.
        flags: u8,
    },
}
