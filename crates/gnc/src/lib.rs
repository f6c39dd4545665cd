//! # helicon-gnc
//!
//! Off-board design of the flight software (thesis chapters 14 and 15): the
//! LQR with integral action and the steady-state Kalman predictor designed on
//! the linearised model, producing the fixed-size [`helicon_core::GainSet`]
//! the flight computer flies, and the `gains.json` file that carries it.
//!
//! The on-board algorithms themselves (navigation, estimators, the control
//! law, the flight computer) live in `helicon-core`, which depends on
//! nalgebra only.

pub mod design;
pub mod schedule;

pub use design::{ControllerConfig, DesignError, Gains, design};
pub use schedule::{EnvelopeConfig, Schedule, ScheduleError, design_schedule, frozen_point_check};
