//! # helicon-config
//!
//! One error shape for the files and configurations the toolkit reads
//! (sensor, wind, scenario and on-board configurations; the parameter file
//! has its own `helicon_model::ParamError` with the same content plus the
//! file line): the file, the field, what was wrong and the allowed range,
//! and the `io::Error` source kept when a file could not be read. The
//! lowest crate that reads files: the model, the simulator and the on-board
//! program all report through it, and it depends on nothing of theirs.
//!
//! It also holds what every reader of user files shares: [`files`] (only
//! regular files, and bounded reads: [`read_text_bounded`],
//! [`open_bounded`], [`open_lines_bounded`]) and [`text`] (text from files escaped for a terminal,
//! [`escape_control`], and made safe as a CSV cell, [`csv_cell`]).

pub mod files;
pub mod suggest;
pub mod text;

pub use files::{
    Bounded, FileRefusal, LineBounded, MAX_DATA_BYTES, MAX_LINE_BYTES, MAX_TEXT_BYTES,
    open_bounded, open_lines_bounded, open_regular, read_text_bounded,
};
pub use suggest::{nearest, with_suggestion};
pub use text::{csv_cell, escape_control};

/// An error reading or checking a configuration.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read (or written).
    #[error("{file}: cannot {action}")]
    Io {
        /// File.
        file: String,
        /// What was being done: `read`, `write`, `create`.
        action: &'static str,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// Not valid TOML, an unknown field or a field of the wrong type (the
    /// parser's message names the field and its position; an unknown field
    /// is shown with the nearest valid one, [`with_suggestion`]).
    #[error("{file}: {}", with_suggestion(.message))]
    Parse {
        /// File.
        file: String,
        /// What was wrong.
        message: String,
    },
    /// A field out of its allowed range.
    #[error("{file}: `{field}` = {value}: {rule}")]
    Invalid {
        /// File.
        file: String,
        /// Dotted field name, e.g. `gps.rate_hz`.
        field: String,
        /// The value given, as text.
        value: String,
        /// The rule broken: the allowed range.
        rule: String,
    },
}

impl ConfigError {
    /// Read a configuration file whole: its name as errors print it, and its
    /// text; a file that cannot be read, is not a regular file or is longer
    /// than [`MAX_TEXT_BYTES`] is [`ConfigError::Io`] naming it
    /// ([`read_text_bounded`]).
    pub fn read_file(path: &std::path::Path) -> Result<(String, String), Self> {
        let text = read_text_bounded(path, MAX_TEXT_BYTES)?;
        Ok((path.display().to_string(), text))
    }

    /// The I/O error of a file that could not be read (the cause of
    /// [`ConfigError::Io`], a [`FileRefusal`] among them), for a reader with
    /// its own error type; any other error as an `io::Error` of its text.
    pub fn into_io(self) -> std::io::Error {
        match self {
            ConfigError::Io { source, .. } => source,
            other => std::io::Error::other(other.to_string()),
        }
    }

    /// An out-of-range number (`value` printed in its shortest round-trip
    /// form, so 1e-300 stays 1e-300).
    pub fn invalid(
        file: &str,
        field: impl Into<String>,
        value: f64,
        rule: impl Into<String>,
    ) -> Self {
        ConfigError::Invalid {
            file: file.to_string(),
            field: field.into(),
            value: format_number(value),
            rule: rule.into(),
        }
    }

    /// The same error attributed to another file, its field under `prefix`
    /// (a section checked on its own, then reported as part of the file that
    /// holds it).
    #[must_use]
    pub fn within(self, file: &str, prefix: &str) -> Self {
        let join = |f: String| {
            if prefix.is_empty() {
                f
            } else {
                format!("{prefix}.{f}")
            }
        };
        match self {
            ConfigError::Io { .. } => self,
            ConfigError::Parse { message, .. } => ConfigError::Parse {
                file: file.to_string(),
                message: format!("[{prefix}]: {message}"),
            },
            ConfigError::Invalid {
                field, value, rule, ..
            } => ConfigError::Invalid {
                file: file.to_string(),
                field: join(field),
                value,
                rule,
            },
        }
    }
}

/// A number for an error message: Rust's shortest round-trip form, which
/// switches to exponent notation for very large or small magnitudes.
pub fn format_number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e15).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A time or a time step for a message, rounded to the nanosecond (finer
/// than any log's resolution — a ULog stamps microseconds — and coarser
/// than the round-off of a difference of times), in its shortest form: a
/// step of 0.0024999999999999467 s computed from a log prints as 0.0025. A
/// value too large to round so (beyond 2⁵³ ns, 104 days) or not finite is
/// printed as it is.
pub fn format_seconds(v: f64) -> String {
    let ns = v * 1e9;
    if v.is_finite() && ns.abs() < 9.007_199_254_740_992e15 {
        // an integer count of ns over 1e9: correctly rounded, so the shortest
        // form has at most nine decimals
        format_number(ns.round() / 1e9)
    } else {
        format_number(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_file_field_value_and_rule_once() {
        let e = ConfigError::invalid("s.toml", "gps.rate_hz", 1e-300, "in (0, 100]");
        assert_eq!(e.to_string(), "s.toml: `gps.rate_hz` = 1e-300: in (0, 100]");
        let e = e.within("scenario.toml", "sensors");
        assert_eq!(
            e.to_string(),
            "scenario.toml: `sensors.gps.rate_hz` = 1e-300: in (0, 100]"
        );
        assert_eq!(format_number(2.5), "2.5");
        assert_eq!(format_number(1e308), "1e308");
        assert_eq!(format_number(86400.0), "86400");
        assert_eq!(format_seconds(0.0024999999999999467), "0.0025");
        assert_eq!(format_seconds(1.0 + 0.6), "1.6");
        assert_eq!(format_seconds(1.0 / 3000.0), "0.000333333");
        assert_eq!(format_seconds(1234.5678910000001), "1234.567891");
        assert_eq!(format_seconds(-0.5), "-0.5");
        assert_eq!(format_seconds(f64::NAN), "NaN");
        assert_eq!(format_seconds(1e300), "1e300");
    }
}
