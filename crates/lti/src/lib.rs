//! # helicon-lti
//!
//! Generic linear time-invariant systems for helicon: discretization, Riccati
//! equations, LQR and Kalman design, and structural analysis.
//!
//! All matrices are `nalgebra::DMatrix<f64>` (design-time code, not a per-step hot path).
//! Bad input is reported through [`LtiError`]; nothing here panics on it.
//!
//! * [`expm()`] / [`c2d`]: matrix exponential (Higham 2005) and ZOH discretization.
//! * [`analysis`]: poles, damping, PBH and staircase controllability/observability.

pub mod analysis;
mod check;
pub mod error;
pub mod expm;

pub use analysis::{
    Pole, damp, damp_discrete, eigenvalues, observable_dimension, pbh_controllability,
    pbh_observability, reachable_dimension, spectral_radius,
};
pub use error::{LtiError, Result};
pub use expm::{c2d, expm};
