//! # helicon-paramid
//!
//! Identification of the nonlinear model's physical parameters from flight
//! frequency responses, as thesis chapter 11 plans it after MOSCA: the
//! parameters are tuned so that the model's linearisations at several
//! operating points match the conditioned frequency responses measured at
//! those points, all operating points in one cost, (11.1)–(11.2).
//!
//! - [`config`]: the `IDENT.toml` file (operating points, logs, responses,
//!   parameters with bounds, weights, cost form, optimiser);
//! - [`data`]: the measured responses, conditioned composites from a log;
//! - [`linear`]: the model's responses C(zI − Φ)⁻¹Γ at the trim of each
//!   operating point for candidate parameters;
//! - [`cost`]: the residuals of (11.1) or of the CIFER cost;
//! - [`fit`]: bounded Levenberg–Marquardt or Nelder–Mead, Cramér–Rao bounds,
//!   insensitivities, correlations and the automatic fixing of parameters the
//!   data cannot determine;
//! - [`report`]: `identified.toml`, `report.json`, `report.md`;
//! - [`verify`]: time-domain verification on doublet logs (Theil coefficient);
//! - [`demo`]: the programme end to end on a simulated helicopter;
//! - [`ground_sim`]: the §11.1 ground experiments simulated on the demo's truth;
//! - [`keys`]: parameters by their `helicon params` key;
//! - [`source`]: a log's columns from `log.csv` or the flight computer's
//!   ULog (`flight.ulg`);
//! - [`calibration`]: the random errors' calibration against the scatter
//!   of the same responses over several flights.

pub mod calibration;
pub mod config;
pub mod cost;
pub mod data;
pub mod demo;
pub mod error;
pub mod fit;
pub mod ground_sim;
pub mod keys;
pub mod linear;
pub mod report;
pub mod source;
pub mod verify;

pub use error::{ParamIdError, Result};
