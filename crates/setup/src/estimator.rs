//! Which navigation flies ahead of the Kalman predictor (`[estimator]` of a
//! scenario and of `onboard.toml`) and the error-state filter's tuning.

use serde::{Deserialize, Serialize};

/// Which navigation flies ahead of the Kalman predictor (TOML `[estimator]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum EstimatorKind {
    /// The thesis's chain: q-method attitude + the GPS/IMU fusion filter
    /// without bias states (chapter 13).
    #[default]
    Thesis,
    /// The error-state Kalman filter with gyro and accelerometer bias states,
    /// GPS latency and innovation gating (`helicon_core::eskf`).
    Eskf,
}

/// The estimator section: the kind and the ESKF's tuning (used when
/// `controller.estimator` and `controller.fusion` put sensors in the loop).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct EstimatorSection {
    /// `thesis` (default) or `eskf`.
    pub kind: EstimatorKind,
    /// ESKF tuning (`[estimator.eskf]`).
    pub eskf: helicon_core::eskf::EskfConfig,
}

impl EstimatorSection {
    /// True for the default section (the thesis chain, default tuning).
    pub fn is_default(&self) -> bool {
        *self == EstimatorSection::default()
    }
}
