//! The one error type of the crate.

/// An error of an identification step: a parameter out of its range, data
/// that cannot give an answer, or a fit that failed.
#[derive(Debug, thiserror::Error)]
pub enum IdentError {
    /// A parameter out of its allowed range.
    #[error("`{field}` = {value}: {rule}")]
    Invalid {
        /// Parameter name, e.g. `sweep.omega_max_rad_s`.
        field: String,
        /// The value given, as text.
        value: String,
        /// The rule broken.
        rule: String,
    },
    /// The data cannot give the answer asked for (too short, not finite, no
    /// excitation), with the reason.
    #[error("{what}: {reason}")]
    Data {
        /// The data concerned, e.g. `channel 2` or `frequency response`.
        what: String,
        /// Why.
        reason: String,
    },
    /// A model file that cannot be read, parsed or used: the file, the
    /// field (dotted, e.g. `A.q[1]`, `parameter[2].max`) and the rule broken.
    #[error("{file}: `{field}`: {rule}")]
    File {
        /// The file.
        file: String,
        /// The field.
        field: String,
        /// What was wrong.
        rule: String,
    },
    /// A file that cannot be read or is not valid TOML (the parser's
    /// message names the key and the line), or holds an unknown key.
    #[error("{file}: {message}")]
    Parse {
        /// The file.
        file: String,
        /// What was wrong.
        message: String,
    },
    /// A fit failed (no usable point, no convergence, singular information matrix).
    #[error("fit: {0}")]
    Fit(String),
    /// A flight-test input program out of its range (`helicon_setup::inputs`).
    #[error(transparent)]
    Input(#[from] helicon_setup::inputs::InputError),
}

impl IdentError {
    /// A number out of range.
    pub fn invalid(field: impl Into<String>, value: f64, rule: impl Into<String>) -> Self {
        IdentError::Invalid {
            field: field.into(),
            value: format!("{value}"),
            rule: rule.into(),
        }
    }

    /// Data that cannot give an answer.
    pub fn data(what: impl Into<String>, reason: impl Into<String>) -> Self {
        IdentError::Data {
            what: what.into(),
            reason: reason.into(),
        }
    }
}

impl IdentError {
    /// A field of a file that breaks a rule.
    pub fn file(file: &str, field: impl Into<String>, rule: impl Into<String>) -> Self {
        IdentError::File {
            file: file.to_string(),
            field: field.into(),
            rule: rule.into(),
        }
    }
}

/// Result with [`IdentError`].
pub type Result<T> = std::result::Result<T, IdentError>;

/// `Ok(v)` when `v` is finite and inside `[lo, hi]`, else [`IdentError::Invalid`].
pub(crate) fn check_range(field: &str, v: f64, lo: f64, hi: f64) -> Result<f64> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(v)
    } else {
        Err(IdentError::invalid(
            field,
            v,
            format!("must be finite and in [{lo}, {hi}]"),
        ))
    }
}
