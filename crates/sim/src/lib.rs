//! # helicon-sim
//!
//! The world around the helicopter of the thesis *Nonlinear Modeling and
//! Optimal Control of a Miniature Autonomous Helicopter* (Aalborg 2006):
//!
//! - [`wind`]: steady wind, 1-cosine gust, the thesis wind model
//!   (14.38)–(14.42) and Dryden turbulence;
//! - [`sensors`]: IMU, magnetometer and GPS models with a seeded RNG;
//! - [`trajectory`]: a scripted smooth trajectory to drive the sensors;
//! - [`plot`]: time-series line plots to PNG and SVG.

pub mod closed_loop;
pub mod mc;
pub mod metrics;
pub mod navigation;
pub mod output;
pub mod plot;
pub mod scenario;
pub mod sensor_log;
pub mod sensors;
pub mod spectral;
pub mod trajectory;
pub mod wind;
