//! # helicon-lti
//!
//! Generic linear time-invariant systems for helicon: discretization, Riccati
//! equations, LQR and Kalman design, and structural analysis.
//!
//! All matrices are `nalgebra::DMatrix<f64>` (design-time code, not a per-step hot path).
//! Bad input is reported through [`LtiError`]; nothing here panics on it.
//!
//! Every entry point checks its matrix arguments for NaN/∞ and, where the algorithm
//! multiplies data matrices, for entries above [`MAX_ENTRY`] = 1e100 (the bound and its
//! reason are documented there); errors name the argument ([`LtiError::argument`]) and the
//! allowed range. Every returned number is finite (the one documented exception:
//! [`damp_discrete`] gives ω_n = ∞ for a pole at z = 0, as MATLAB does); a computation that
//! overflows ends in [`LtiError::Overflow`] instead of a NaN result.
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
pub use check::MAX_ENTRY;
pub use error::{LtiError, Result};
pub use expm::{c2d, c2d_fixed, expm};
pub use kalman::{Kalman, dlqe};
pub use lqr::{
    IntegralAugmented, IntegralLqr, Lqr, alpha_from_settling_time, augment_integral, bryson,
    bryson_weights, dlqr, dlqr_integral, dlqr_pincer,
};
pub use riccati::{DareOptions, DareSolution, dare, dare_with};
