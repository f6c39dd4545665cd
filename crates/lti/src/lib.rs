//! # helicon-lti
//!
//! Generic linear time-invariant systems for helicon: discretization, Riccati
//! equations, LQR and Kalman design, and structural analysis.
