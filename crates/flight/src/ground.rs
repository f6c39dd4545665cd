//! The ground station in the on-board program (thesis Figure 3.5's Ground
//! Station Server and Navigator, `helicon-gcs`): the MAVLink 2 server on its
//! own thread and the navigator as the control task's [`Mission`]. The two
//! meet through `helicon-gcs`' lock-free rings only: the control task never
//! waits for the server (a full ring drops a status and counts it).

use crate::mission::{Mission, References};
use helicon_config::ConfigError;
use helicon_devices::Geodetic;
use helicon_gcs::config::GcsSection;
use helicon_gcs::link::{Vehicle, channel};
use helicon_gcs::navigator::Navigator;
use helicon_gcs::server::{self, GcsError, ServerHandle};

/// The rings' capacity between the control task and the server (at 400 Hz
/// with statuses at 100 Hz: tens of seconds of a stalled server).
const RING: usize = 8192;

/// The fastest status stream the ground station can ask for (Hz).
const STATUS_HZ: f64 = 100.0;

/// Why the ground station did not start.
#[derive(Debug, thiserror::Error)]
pub enum GroundError {
    /// The `[gcs]` section (file, field, rule).
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The server (its address, its thread).
    #[error(transparent)]
    Server(#[from] GcsError),
}

/// The ground station's parameter table as the flight starts (PX4's
/// names, `helicon_gcs::params`): the flight log's initial parameters.
/// A value the operator sets in flight reaches the navigator, not the log
/// (docs/ulog.md, "Parameters").
pub fn initial_parameters(
    section: &GcsSection,
    home: Geodetic,
    file: &str,
) -> Result<Vec<(&'static str, f32)>, GroundError> {
    let config = section.server_config(home, file)?;
    let table = helicon_gcs::params::ParamTable::new(config.navigator);
    Ok((0..table.len()).filter_map(|i| table.get(i)).collect())
}

/// Start the ground station of `section` (`file` names it in errors):
/// the server thread is running when this returns, and the mission is the
/// navigator the control task flies, disarmed until the operator arms.
/// `home` is the origin of the local NED frame; `sample_time_s` the control
/// period (the vehicle's status goes out at up to 100 Hz).
pub fn start(
    section: &GcsSection,
    home: Geodetic,
    file: &str,
    sample_time_s: f64,
) -> Result<(Mission, ServerHandle), GroundError> {
    let config = section.server_config(home, file)?;
    let nav = Navigator::new(config.navigator).map_err(|e| {
        ConfigError::invalid(file, format!("gcs.navigator.{}", e.field), e.value, e.rule)
    })?;
    let status_every = if sample_time_s.is_finite() && sample_time_s > 0.0 {
        ((1.0 / STATUS_HZ) / sample_time_s).round().max(1.0) as u64
    } else {
        1
    };
    let (vehicle_end, server_end) = channel(RING);
    let vehicle = Vehicle::new(nav, vehicle_end, status_every);
    let handle = server::spawn(config, server_end)?;
    Ok((Mission::new(References::Ground(Box::new(vehicle))), handle))
}
