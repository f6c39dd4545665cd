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
    /// A log could not be read.
    #[error(transparent)]
    Log(#[from] helicon_sim::log_csv::LogCsvError),
    /// A flight log (ULog) could not be read as columns.
    #[error(transparent)]
    Ulog(#[from] helicon_ulog::columns::ColumnsError),
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

/// Result with [`ParamIdError`].
pub type Result<T> = std::result::Result<T, ParamIdError>;
