//! # helicon-model
//!
//! The first-principles nonlinear model of a miniature helicopter from the thesis
//! *Nonlinear Modeling and Optimal Control of a Miniature Autonomous Helicopter*
//! (Aalborg University, 2006), chapters 4–10 and appendices B–D, with the
//! corrections documented in `shared/spec/MODEL.md`.

pub mod frames;
pub mod state;
