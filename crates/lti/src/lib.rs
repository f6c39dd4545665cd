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
//!
//! ```
//! use nalgebra::DMatrix;
//! # fn main() -> Result<(), helicon_lti::LtiError> {
//! // Double integrator sampled at 10 Hz, LQR with a pincer α = 1.05.
//! let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
//! let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
//! let (phi, gamma) = helicon_lti::c2d(&a, &b, 0.1)?;
//! let q = DMatrix::identity(2, 2);
//! let r = DMatrix::from_element(1, 1, 0.1);
//! let lqr = helicon_lti::dlqr_pincer(&phi, &gamma, &q, &r, None, 1.05)?;
//! assert!(lqr.poles.iter().all(|z| z.norm() < 1.0 / 1.05));
//! let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
//! let kf = helicon_lti::dlqe(&phi, None, &c, &(q * 0.01), &DMatrix::from_element(1, 1, 1.0))?;
//! assert_eq!(kf.l.shape(), (2, 1));
//! # Ok(())
//! # }
//! ```

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
pub use expm::{c2d, c2d_fixed, expm};
pub use kalman::{Kalman, dlqe};
pub use lqr::{
    IntegralAugmented, IntegralLqr, Lqr, alpha_from_settling_time, augment_integral, bryson,
    bryson_weights, dlqr, dlqr_integral, dlqr_pincer,
};
pub use riccati::{DareOptions, DareSolution, dare, dare_with};
