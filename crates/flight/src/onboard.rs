//! The on-board program: read the configuration, the parameters and the
//! gains, open the devices, align on the ground from the sensors, build the
//! flight computer exactly as the simulator does, and run the runtime on the
//! clock.

use crate::config::OnboardConfig;
use crate::control::ControlTask;
use crate::ground;
use crate::mission::{Mission, References};
use crate::plausibility::SensorGate;
use crate::ports::{DeviceSensors, avionics_ports, open_port};
use crate::runtime::{self, Next, Pacing, RunReport, RuntimeOptions, SensorPort};
use crate::safety::Supervisor;
use helicon_config::ConfigError;
use helicon_core::attitude::{VectorObservation, gravity_observation, q_method};
use helicon_core::frames::body_from_ned;
use helicon_core::state::{ReducedState, State, expand, ix};
use helicon_core::{Reference, SensorFrame};
use helicon_devices::{Geodetic, LocalNed};
use helicon_gnc::design::Gains;
use helicon_model::Params;
use helicon_setup::excitation::Excitations;
use helicon_setup::mission::MissionFile;
use helicon_setup::{OnBoardSetup, flight_computer, imu_health_at};
use helicon_ulog::{FlightLog, FlushPolicy, LogInfo};
use nalgebra::Vector3;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Errors of the on-board program before it flies.
#[derive(Debug, thiserror::Error)]
pub enum OnboardError {
    /// The configuration, the mission or a file they name.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The parameter file.
    #[error(transparent)]
    Params(#[from] helicon_model::ParamError),
    /// The gains file.
    #[error(transparent)]
    Gains(#[from] helicon_gnc::design::DesignError),
    /// Gains designed for another sample time than the parameters'.
    #[error(
        "{file}: the gains were designed for a sample time of {gains_s} s but the parameters' \
         `control.sample_time_s` is {params_s} s: redesign for this helicopter"
    )]
    SampleTime {
        /// The gains file.
        file: String,
        /// Its sample time (s).
        gains_s: f64,
        /// The parameters' (s).
        params_s: f64,
    },
    /// A device.
    #[error(transparent)]
    Port(#[from] runtime::PortError),
    /// No alignment within the time allowed.
    #[error("alignment: {0}")]
    Alignment(String),
    /// The ground station.
    #[error(transparent)]
    Ground(#[from] ground::GroundError),
    /// Building the flight software.
    #[error(transparent)]
    Build(#[from] helicon_setup::BuildError),
    /// Stopped on request before the flight log was opened (during the
    /// alignment): nothing was written.
    #[error("stopped before the alignment ended: no flight log was written")]
    Stopped,
    /// The flight log.
    #[error("{path}: {message}")]
    Log {
        /// The file.
        path: String,
        /// What failed.
        message: String,
    },
}

/// The ground alignment: the state the navigation and the predictor start
/// from, from the first frame with a magnetometer sample and a 3-D GPS fix
/// after the first IMU sample: attitude by the q-method (gravity from the
/// accelerometer, the magnetometer against the local field), position and
/// velocity from the fix, rates from the gyro; the rest of the state the
/// trim's.
pub fn align(
    frame: &SensorFrame,
    mag_field_ned: &Vector3<f64>,
    trim_x: &ReducedState,
) -> Option<State> {
    let mag = frame.mag_body?;
    let fix = frame.gps.filter(|g| g.is_valid())?;
    let obs = [
        gravity_observation(1.0, &frame.imu.specific_force_body_m_s2, None),
        VectorObservation::new(1.0, mag, *mag_field_ned),
    ];
    let euler = q_method(&obs).ok()?.euler();
    let mut x = expand(trim_x, fix.position_ned_m.into());
    x[ix::PHI] = euler.x;
    x[ix::THETA] = euler.y;
    x[ix::PSI] = euler.z;
    let v_body = body_from_ned(euler.x, euler.y, euler.z)
        * fix.velocity_ned_m_s.unwrap_or_else(Vector3::zeros);
    x[ix::U] = v_body.x;
    x[ix::V] = v_body.y;
    x[ix::W] = v_body.z;
    x[ix::P] = frame.imu.gyro_body_rad_s.x;
    x[ix::Q] = frame.imu.gyro_body_rad_s.y;
    x[ix::R] = frame.imu.gyro_body_rad_s.z;
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The flight-test excitation flown: `onboard.toml`'s `[[excitation]]`,
/// or the mission file's; both at once is refused (which one was meant?).
fn mission_excitation(
    cfg: &OnboardConfig,
    mission: Option<&MissionFile>,
) -> Result<Excitations, ConfigError> {
    match mission {
        Some(m) if !m.excitation.is_empty() => {
            let file = cfg
                .mission
                .as_ref()
                .map_or_else(|| m.name.clone(), |p| cfg.resolve(p).display().to_string());
            if !cfg.excitation.is_empty() {
                return Err(ConfigError::Invalid {
                    file: cfg.file.clone(),
                    field: "excitation".into(),
                    value: format!("{} entries", cfg.excitation.len()),
                    rule: format!(
                        "the mission file {file} has its own [[excitation]]: give them in one place"
                    ),
                });
            }
            Excitations::new(&m.excitation, &file)
        }
        _ => Excitations::new(&cfg.excitation, &cfg.file),
    }
}

/// Run the on-board program of `cfg` for `duration` (when `None`, until
/// stopped: a device lost is reopened, not the end); the log goes to the
/// configured folder. Returns the runtime's report (the caller writes it
/// beside the log) and the log's path.
pub fn run(
    cfg: &OnboardConfig,
    duration: Option<Duration>,
    sched_fifo: bool,
) -> Result<(RunReport, PathBuf), OnboardError> {
    run_until(cfg, duration, sched_fifo, &AtomicBool::new(false))
}

/// How often [`run_until`] looks at its stop flag while the runtime flies.
const STOP_POLL: Duration = Duration::from_millis(20);

/// As [`run`], ended early once `stop` is set (a signal handler's flag,
/// looked at every 20 ms): the runtime stops after its current step, the
/// logger writes what it was sent and closes the log, and the report is
/// returned as at a normal end. Set before the log exists (during the
/// alignment), the program ends with [`OnboardError::Stopped`].
#[allow(clippy::too_many_lines)] // the program's steps in order
pub fn run_until(
    cfg: &OnboardConfig,
    duration: Option<Duration>,
    sched_fifo: bool,
    stop: &AtomicBool,
) -> Result<(RunReport, PathBuf), OnboardError> {
    let params = match &cfg.params {
        Some(p) => Params::from_file(&cfg.resolve(p))?,
        None => Params::bergen_twin(),
    };
    let gains_path = cfg.resolve(&cfg.gains);
    let gains = Gains::load(&gains_path)?;
    let ts = params.control.sample_time_s;
    if gains.set.sample_time_s != ts {
        return Err(OnboardError::SampleTime {
            file: gains_path.display().to_string(),
            gains_s: gains.set.sample_time_s,
            params_s: ts,
        });
    }
    let mission_scenario = match &cfg.mission {
        Some(m) => Some(MissionFile::from_file(&cfg.resolve(m))?),
        None => None,
    };
    let excitation = mission_excitation(cfg, mission_scenario.as_ref())?;
    let d = &cfg.devices;
    let imu = open_port(&d.imu.path, d.imu.baud)?;
    let gps = open_port(&d.gps.path, d.gps.baud)?;
    let avionics = open_port(&d.avionics.path, d.avionics.baud)?;
    let (rc, servos) = avionics_ports(avionics, cfg.rc)?;
    let h = &cfg.home;
    let home = Geodetic::new(h.latitude_deg, h.longitude_deg, h.height_m)
        .map_err(|e| OnboardError::Alignment(format!("home: {e}")))?;
    let mut sensors = DeviceSensors::new(imu, gps, LocalNed::new(home), cfg.sensors.gps.latency_s);

    let mut gate = SensorGate::new(&cfg.plausibility, &cfg.sensors, &cfg.file)?;
    // ground alignment: wait for a frame with the magnetometer and a fix
    let field = Vector3::from(cfg.sensors.mag.field_ned);
    let start = Instant::now();
    let limit = Duration::from_secs(60);
    let mut mag = None;
    let x0 = loop {
        if stop.load(Ordering::SeqCst) {
            return Err(OnboardError::Stopped);
        }
        if start.elapsed() > limit {
            return Err(OnboardError::Alignment(format!(
                "no IMU sample with a plausible magnetometer sample and 3-D GPS fix within {} s \
                 (check {} and {})",
                limit.as_secs(),
                d.imu.path.display(),
                d.gps.path.display()
            )));
        }
        match sensors.next(Duration::from_millis(100))? {
            Next::Item(a) => {
                // only plausible samples align (a fix without 3-D, a field
                // of the wrong magnitude are refused as in flight)
                let gated = a
                    .frame
                    .and_then(|f| gate.check(&f, a.gps_quality.as_ref()).frame);
                if let Some(mut f) = gated {
                    mag = f.mag_body.or(mag);
                    f.mag_body = mag;
                    if let Some(x) = align(&f, &field, &gains.set.x_trim) {
                        break x;
                    }
                }
            }
            Next::Timeout => {}
            Next::Closed => {
                return Err(OnboardError::Alignment(format!(
                    "{} closed",
                    d.imu.path.display()
                )));
            }
        }
    };
    // on board the thesis chain gates its GPS updates (unless configured)
    let mut navigation = cfg.navigation;
    navigation
        .gps_gate_nis
        .get_or_insert(helicon_core::navigation::GPS_GATE_NIS);
    let computer = flight_computer(&OnBoardSetup {
        servo_limits: params.servo_limits(),
        gravity_m_s2: params.environment.g_m_s2,
        gains: &gains.set,
        schedule: None,
        trim_x: &gains.set.x_trim,
        sensors: &cfg.sensors,
        navigation: &navigation,
        estimator: &cfg.estimator,
        feedback: true,
        x0: &x0,
    })?;
    let u_trim = gains.set.u_trim;
    let mut task = ControlTask::new(
        computer,
        Supervisor::new(cfg.stale, cfg.failsafe, 0.0).with_rc(cfg.rc),
        u_trim,
    )
    .with_imu_health(imu_health_at(
        params.environment.g_m_s2,
        ts,
        &cfg.sensors,
        &cfg.file,
    )?)
    .with_gate(gate)
    .with_servo_limits(params.servo_limits());
    if cfg.landing.enabled {
        // on the ground, disarmed, the engine cut: the ground logic flies
        // the run-up, the take-off and the landing
        task = task.with_landing(crate::landing::Landing::new(cfg.landing, ts, &u_trim, 0.0));
    }
    let dir = cfg.resolve(&cfg.log.dir);
    std::fs::create_dir_all(&dir).map_err(|e| OnboardError::Log {
        path: dir.display().to_string(),
        message: format!("cannot create: {e}"),
    })?;
    // a new file, numbered after the folder's logs: two flights in one
    // second, or a board without a real-time clock, never share a name, and
    // an existing log is never overwritten
    let unix = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .ok();
    let unix_s = unix.map_or(0, |d| d.as_secs());
    let table = match &cfg.gcs {
        Some(g) => ground::initial_parameters(g, home, &cfg.file)?,
        None => Vec::new(),
    };
    let info = LogInfo {
        // the computer's id where the system keeps one (systemd's)
        sys_uuid: helicon_config::read_text_bounded(Path::new("/etc/machine-id"), 256)
            .map(|t| t.trim().to_string())
            .unwrap_or_default(),
        // the runtime's clock starts as the log is created (within
        // milliseconds); a computer without a set clock says 1970
        start_utc_us: unix
            .filter(|d| d.as_secs() > 1_000_000_000)
            .and_then(|d| u64::try_from(d.as_micros()).ok()),
        home: Some(home),
        control_period_us: Some((ts * 1e6).round() as u64),
        parameters: crate::records::log_parameters(ts, &table),
        ..LogInfo::default()
    };
    let (log, path) = FlightLog::create_numbered(&dir, unix_s, &info, FlushPolicy::default())
        .map_err(|e| OnboardError::Log {
            path: dir.display().to_string(),
            message: e.to_string(),
        })?;
    // the ground station last: its server thread runs from here on
    let (mission, server) = match (&mission_scenario, &cfg.gcs) {
        (_, Some(g)) => {
            let (m, server) = ground::start(g, home, &cfg.file, ts)?;
            (m, Some(server))
        }
        (Some(s), None) => (
            Mission::new(References::Schedule(Box::new(s.reference_schedule()))),
            None,
        ),
        (None, None) => (
            Mission::new(References::Hold(Reference {
                velocity_ned_m_s: Vector3::zeros(),
                yaw_rad: x0[ix::PSI],
            })),
            None,
        ),
    };
    let mission = mission.with_excitation(excitation);
    let mut realtime = cfg.realtime;
    realtime.sched_fifo &= sched_fifo;
    let handle = runtime::spawn(
        task,
        mission,
        sensors,
        Some(rc),
        servos,
        log,
        None,
        RuntimeOptions {
            sample_time_s: ts,
            pacing: Pacing::Clock,
            max_steps: duration.map(|d| (d.as_secs_f64() / ts).round() as u64),
            realtime,
            watchdog_s: 0.05,
            u_trim,
        },
    );
    for w in &handle.warnings() {
        eprintln!("warning: {w}");
    }
    if !cfg.landing.enabled && cfg.rc.kill_channel.is_none() {
        // the arm switch disarms only on the ground, which nothing tells
        eprintln!(
            "warning: {}: [landing] enabled = false and no rc.kill_channel: the receiver cannot \
             disarm (the arm switch disarms only on the ground); set rc.kill_channel for a kill \
             switch",
            cfg.file
        );
    }
    while !handle.is_finished() {
        if stop.load(Ordering::SeqCst) {
            handle.stop();
            break;
        }
        std::thread::sleep(STOP_POLL);
    }
    let report = handle.join();
    if let Some(server) = server {
        server.stop();
    }
    Ok((report, path))
}

#[cfg(test)]
mod tests {
    use super::*;

    const MIN: &str = "gains = \"g.json\"\n[devices.imu]\npath = \"/dev/ttyS1\"\nbaud = 921600\n\
        [devices.gps]\npath = \"/dev/ttyS2\"\nbaud = 115200\n\
        [devices.avionics]\npath = \"/dev/ttyS3\"\nbaud = 115200\n";
    const SWEEP: &str = "[[excitation]]\nservo = \"S_lon\"\nt_s = 1.0\ninput = { kind = \"sweep\", \
        amplitude = 0.02, omega_min_rad_s = 1.2, omega_max_rad_s = 30.0, duration_s = 27.0 }\n";

    /// The excitation flown: onboard.toml's or the mission's, not both.
    #[test]
    fn the_excitation_comes_from_one_place() {
        let plain = OnboardConfig::from_toml_str(MIN, "o.toml").unwrap();
        let mut with = OnboardConfig::from_toml_str(&format!("{MIN}{SWEEP}"), "o.toml").unwrap();
        with.mission = Some(PathBuf::from("m.toml"));
        let mission =
            MissionFile::from_toml_str(&format!("duration_s = 5.0\n{SWEEP}"), "m.toml").unwrap();
        let bare = MissionFile::from_toml_str("duration_s = 5.0\n", "m.toml").unwrap();
        assert!(mission_excitation(&plain, None).unwrap().is_empty());
        assert!(!mission_excitation(&with, Some(&bare)).unwrap().is_empty());
        assert!(
            !mission_excitation(&plain, Some(&mission))
                .unwrap()
                .is_empty()
        );
        let e = mission_excitation(&with, Some(&mission))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("o.toml") && e.contains("excitation") && e.contains("m.toml"),
            "{e}"
        );
    }
}
