//! Errors of the identification.

use helicon_model::ConfigError;

/// An identification failure. Configuration problems name the file and
/// the field ([`ConfigError`]); the others name the operating point, the
/// response or the log.
#[derive(Debug, thiserror::Error)]
pub enum ParamIdError {
    /// The IDENT.toml (or a file it names) is wrong.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// A log could not be read (one not named by an IDENT.toml field).
    #[error(transparent)]
    Log(#[from] LogError),
    /// A log named by a field of the IDENT.toml could not be read: the
    /// IDENT.toml and the field, then the reader's own error (which names
    /// the log and the column and line, or the topic, field and time).
    #[error("{file}: `{field}`: {source}")]
    LogOf {
        /// The IDENT.toml.
        file: String,
        /// Its field naming the log (`operating_point[1].log`).
        field: String,
        /// The reader's error (boxed: the error stays small on the happy
        /// path).
        #[source]
        source: Box<LogError>,
    },
    /// The part of a log used has samples in which the control law did not
    /// drive the servos (`servo_source` ≠ 0: the pilot, a failsafe), so the
    /// logged law commands and excitation are not what the helicopter got.
    #[error(
        "{file}: `{field}`: {log}: the control law did not drive the servos (servo_source ≠ 0) at {}: identification needs the law and its excitation driving them; set `{}.t_start_s`/`t_end_s` to leave {} out",
        crate::source::describe_spans(.spans),
        .field.strip_suffix(".log").unwrap_or(.field),
        if .spans.len() == 1 { "it" } else { "them" }
    )]
    NotLawDriven {
        /// The IDENT.toml.
        file: String,
        /// Its field naming the log.
        field: String,
        /// The log.
        log: String,
        /// The spans, in time order.
        spans: Vec<crate::source::ServoSpan>,
    },
    /// The frequency-response estimate failed.
    #[error("{file}: {what}: {source}")]
    Frf {
        /// The log.
        file: String,
        /// Which response.
        what: String,
        /// The cause (boxed: the error stays small on the happy path).
        source: Box<helicon_ident::IdentError>,
    },
    /// The model could not be trimmed or linearised at an operating point
    /// with the given parameters.
    #[error("operating point `{point}`: {reason}")]
    Model {
        /// Operating point name.
        point: String,
        /// What failed.
        reason: String,
    },
    /// The optimisation failed.
    #[error("fit: {0}")]
    Fit(String),
}

/// Why a log could not be read: the `log.csv` reader's or the flight-log
/// reader's own error, kept whole.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// A CSV log.
    #[error(transparent)]
    Csv(#[from] helicon_sim::log_csv::LogCsvError),
    /// A flight log (ULog) read as columns.
    #[error(transparent)]
    Ulog(#[from] helicon_ulog::columns::ColumnsError),
}

/// Result with [`ParamIdError`].
pub type Result<T> = std::result::Result<T, ParamIdError>;
