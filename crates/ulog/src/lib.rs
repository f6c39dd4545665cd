//! # helicon-ulog
//!
//! The flight data log in PX4's ULog format (PX4 "ULog File Format",
//! version 1), the format pyulog, PlotJuggler and PX4 Flight Review read
//! (the tests read it with pyulog and px4-ulog).
//!
//! - [`format`](mod@format): message formats declared from Rust types
//!   ([`ulog_message!`], [`Record`]): name, fields with ULog types and
//!   arrays, `uint64_t timestamp` (µs) first, trailing padding to 8 bytes.
//! - [`writer`]: [`UlogWriter`]: header, flag bits, formats, info,
//!   parameters, subscriptions, data, text (LOGGING with levels), SYNC,
//!   DROPOUT. Records are encoded into the writer's buffer with no
//!   allocation; the buffer is written out whole at least every 0.1 s of
//!   log time and every 16 KiB ([`FlushPolicy`]), so a killed process
//!   leaves a file whose prefix is complete messages.
//! - [`messages`]: the on-board message set (`control`, `navigation`,
//!   `sensor_imu`, `helicon_mag`, `helicon_gps`, `servo_output`,
//!   `rc_input`, `timing`, `failsafe`, `mode`), the helpers that fill them
//!   from [`helicon_core`]'s `Telemetry` and `SensorFrame`, and
//!   [`FlightLog`], the writer with the whole set subscribed.
//! - [`px4`]: PX4's uORB topics (`vehicle_attitude`, `vehicle_local_position`,
//!   `sensor_gps`, `vehicle_status` …) in PX4's layout, and [`px4::Px4View`],
//!   which [`FlightLog`] uses to write them from helicon's records so that
//!   PX4's tools read the log as a PX4 log.
//! - [`reader`]: a streaming reader (typed errors; a truncated file gives
//!   every complete message, then [`ReadError::Truncated`]); [`flat`]:
//!   formats flattened to columns (nested types, arrays, padding);
//!   [`visit`]: one pass with the formats resolved; [`export`]: CSV and
//!   text export (`helicon log export`) and the summary (`helicon log info`);
//!   [`columns`]: a flight log as the simulator's `log.csv` columns on the
//!   control grid (what identification reads).
//! - [`synthetic`]: synthetic flight logs (stamps chosen, values a test
//!   recomputes), written by the project's writer, for tests and examples.
//!
//! ## Writing a flight log
//!
//! ```
//! use helicon_ulog::{FlightLog, FlushPolicy, LogInfo, LogRecord, messages::Timing};
//! # fn main() -> Result<(), helicon_ulog::WriteError> {
//! let mut log = FlightLog::new(Vec::new(), &LogInfo::default(), FlushPolicy::default())?;
//! // each control step (on the logger thread, records from the ring):
//! log.write(&LogRecord::Timing(Timing { timestamp: 2500, sample: 1, ..Default::default() }))?;
//! // log.log_telemetry(&telemetry)?; log.log_frame(&frame)?;
//! let bytes = log.finish()?;
//! assert_eq!(&bytes[..4], b"ULog");
//! # Ok(()) }
//! ```
//!
//! Call [`FlightLog::finish`] (or [`UlogWriter::finish`]) at the end: a
//! writer dropped without it loses its buffer (at most 0.1 s), as a crash
//! would.
//!
//! The writer is not thread-safe by itself: the runtime's logger thread
//! owns it and drains a ring of [`LogRecord`]s (all `Copy`, no heap).

pub mod columns;
pub mod error;
#[cfg(feature = "export")]
pub mod export;
pub mod flat;
pub mod format;
pub mod messages;
pub mod px4;
pub mod reader;
pub mod spec;
pub mod synthetic;
pub mod visit;
pub mod writer;

pub use error::{ReadError, WriteError};
pub use format::{FieldDef, Record, UlogType, UlogValue};
pub use messages::{FlightLog, LogInfo, LogRecord};
pub use spec::LogLevel;
pub use writer::{FlushPolicy, Topic, UlogWriter, WriterStats, timestamp_us};
