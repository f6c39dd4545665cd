//! # helicon-setup
//!
//! What the simulator and the on-board program share above the
//! flight-software core (`helicon-core`): the configuration the flight
//! software is given and the one place it is assembled. The simulator
//! (`helicon-sim`), SITL and the on-board program (`helicon-flight`) all
//! read these types and call [`builder::flight_computer`], so a change in
//! the simulator cannot change what flies, and what flies is what was
//! simulated.
//!
//! - [`sensors`]: the IMU, magnetometer and GPS figures (`[sensors]`);
//! - [`vibration`]: the vibration environment and the sensors' internal
//!   stages (`[imu.vibration]`, thesis Appendix A);
//! - [`estimator`]: which navigation flies and the ESKF's tuning (`[estimator]`);
//! - [`plan`]: the flight plan (`[trim]`, `[[reference]]`, `[trajectory]`)
//!   and its allocation-free [`plan::ReferenceSchedule`];
//! - [`mission`]: an on-board mission file (the flight plan and the
//!   excitation of a scenario file, without the simulator's world);
//! - [`inputs`]: flight-test input programs (sweep, multisine, doublet, 3211);
//! - [`excitation`]: those programs on the servo channels (`[[excitation]]`);
//! - [`builder`]: gains or a schedule + sensors + estimator → the core's
//!   `SensorComputer`, the IMU health monitor.
//!
//! It depends on the core, `helicon-config` and serde/toml only.

pub mod builder;
pub mod estimator;
pub mod excitation;
pub mod inputs;
pub mod mission;
pub mod plan;
pub mod sensors;
pub mod vibration;

pub use builder::{BuildError, OnBoardSetup, flight_computer, imu_health_at};
