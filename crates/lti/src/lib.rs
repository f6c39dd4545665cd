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
//! * [`riccati`]: DARE by the structured doubling algorithm (Chu et al. 2004).
//! * [`lqr`]: `dlqr`, Bryson's rule, pincer α, integral action (thesis ch. 14).
//! * [`kalman`]: steady-state Kalman predictor/filter gains (thesis ch. 15).

pub mod analysis;
mod check;
pub mod error;
pub mod expm;
pub mod kalman;
pub mod lqr;
pub mod riccati;

pub use analysis::{
    Pole, damp, damp_discrete, eigenvalues, observable_dimension, pbh_controllability,
    pbh_observability, reachable_dimension, spectral_radius,
};
pub use error::{LtiError, Result};
pub use expm::{c2d, expm};
pub use kalman::{Kalman, dlqe};
pub use lqr::{
    IntegralAugmented, IntegralLqr, Lqr, alpha_from_settling_time, augment_integral, bryson,
    bryson_weights, dlqr, dlqr_integral, dlqr_pincer,
};
pub use riccati::{DareOptions, DareSolution, dare, dare_with};
