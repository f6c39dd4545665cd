//! # helicon-sim
//!
//! The world around the helicopter of the thesis *Nonlinear Modeling and
//! Optimal Control of a Miniature Autonomous Helicopter* (Aalborg 2006):
//!
//! - [`wind`]: steady wind, 1-cosine gust, the thesis wind model
//!   (14.38)–(14.42) and Dryden turbulence;
//! - [`sensors`]: IMU, magnetometer and GPS models with a seeded RNG;
//! - [`vibration`]: vibration at the IMU and the sensors' internal stages
//!   (mechanical range and bandwidth, internal low-pass; thesis Appendix A);
//! - [`ground`]: starting on the ground, the take-off and landing plan, the ground metrics;
//! - [`shaker`]: the shaker experiment of Appendix A (hidden saturation);
//! - [`trajectory`]: a scripted smooth trajectory to drive the sensors;
//! - [`envelope`]: jerk-limited mission references and the gain schedule a scenario flies;
//! - [`log_csv`]: the `log.csv` column table, streaming writer and typed reader;
//! - [`output`]: the run folder (log, summary, gains, scenario, figures, report);
//! - [`plot`]: time-series line plots and multi-panel figures to PNG and SVG.

pub mod closed_loop;
pub mod envelope;
pub mod excitation;
pub mod ground;
pub mod log_csv;
pub mod mc;
pub mod metrics;
pub mod navigation;
pub mod output;
pub mod plot;
pub mod resources;
pub mod scenario;
pub mod sensor_log;
pub mod sensors;
pub mod shaker;
pub use helicon_ident::spectral;
pub mod trajectory;
pub mod vibration;
pub mod wind;
