//! The core's error type (hand-written `Display`: the core depends on
//! nalgebra only).

use crate::fusion::FusionError;

/// What can go wrong in the flight software core.
#[derive(Debug, Clone, PartialEq)]
pub enum CoreError {
    /// A gain set or servo limit cannot be flown.
    InvalidGains {
        /// Which part.
        what: &'static str,
        /// The rule broken.
        rule: &'static str,
    },
    /// The navigation (attitude determination + fusion) failed this sample.
    Navigation(FusionError),
    /// A measurement handed to an estimator was NaN or infinite.
    NonFiniteMeasurement {
        /// Which measurement.
        what: &'static str,
    },
    /// The estimate left the finite numbers (the estimator diverged).
    NonFiniteEstimate,
    /// A gain schedule cannot be flown (grid, sizes, mixed designs).
    InvalidSchedule {
        /// Which part.
        what: &'static str,
        /// The rule broken.
        rule: &'static str,
    },
    /// A reference trajectory is not valid.
    InvalidReference {
        /// Which channel.
        what: &'static str,
        /// The rule broken.
        rule: &'static str,
    },
}

impl std::fmt::Display for CoreError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CoreError::InvalidGains { what, rule } => write!(f, "gains: {what} {rule}"),
            CoreError::Navigation(e) => write!(f, "{e}"),
            CoreError::NonFiniteMeasurement { what } => {
                write!(f, "non-finite measurement: {what}")
            }
            CoreError::NonFiniteEstimate => write!(f, "the state estimate became non-finite"),
            CoreError::InvalidSchedule { what, rule } => write!(f, "gain schedule: {what} {rule}"),
            CoreError::InvalidReference { what, rule } => write!(f, "reference `{what}`: {rule}"),
        }
    }
}

/// `Navigation` is transparent: its message is the navigation error's own,
/// so the cause is said once (no `source`).
impl std::error::Error for CoreError {}

impl From<FusionError> for CoreError {
    fn from(e: FusionError) -> Self {
        CoreError::Navigation(e)
    }
}
