//! # helicon-flight
//!
//! The on-board program of the thesis's helicopter (chapter 3, Figure 3.5)
//! around the very flight software `helicon sim` flies
//! (`helicon_core::SensorComputer`: the thesis's navigation or the ESKF,
//! one design or a gain schedule, built by `helicon_setup::flight_computer`,
//! the one builder the simulator calls too). It stands on its own: it
//! depends on the core, `helicon-setup`, the device protocols, the log and
//! the ground station, never on the simulator (SITL, the simulator playing
//! the hardware, is `helicon-sitl`, above both):
//!
//! - [`config`]: `onboard.toml` (devices, parameter and gains files, stale
//!   limits, failsafes, log folder, real-time options), checked field by field;
//! - [`safety`]: arming, the pilot's switch, sensor stale limits and overruns;
//!   hold, then a descent;
//! - [`control`]: the control task's work for one sample;
//! - [`mission`]: the references (schedule, hold, the ground station's
//!   navigator) and the flight-test excitation;
//! - [`ground`]: the ground station (MAVLink server and navigator) started
//!   from the on-board program;
//! - [`runtime`]: the threads (sensor server, receiver, control task,
//!   avionics-out with its watchdog, logger) and the lock-free rings between them;
//! - [`realtime`]: absolute-deadline sleeps, SCHED_FIFO, `mlockall`, latency statistics;
//! - [`records`]: what is logged (ULog through `helicon-ulog`).

pub mod config;
pub mod control;
pub mod ground;
pub mod landing;
pub mod mission;
pub mod onboard;
pub mod plausibility;
pub mod ports;
pub mod realtime;
pub mod records;
pub mod runtime;
pub mod safety;
