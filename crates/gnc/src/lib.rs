//! # helicon-gnc
//!
//! On-board guidance, navigation and control algorithms for the helicopter of
//! the thesis *Nonlinear Modeling and Optimal Control of a Miniature Autonomous
//! Helicopter* (Aalborg 2006):
//!
//! - [`attitude`]: attitude determination by Davenport's q-method (§13.2);
//! - [`fusion`]: GPS + IMU + attitude fusion Kalman filter (§13.3).
//!
//! Rotations and Euler kinematics come from `helicon_model::frames` (chapter 9).

pub mod attitude;
pub mod controller;
pub mod design;
pub mod fusion;
pub mod navigation;

pub use attitude::{AttitudeError, AttitudeSolution, VectorObservation, q_method};
pub use fusion::{FusionConfig, FusionError, FusionFilter, FusionInput};
