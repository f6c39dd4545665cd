//! The on-board message set: the topics the flight runtime logs, defined
//! once here so the writer on board and the readers on the ground agree,
//! and the allocation-free helpers that fill them from the core's types.
//!
//! | topic | per | from |
//! |---|---|---|
//! | `control` | control step | [`Telemetry`] |
//! | `navigation` | control step with a navigation solution | [`Telemetry::navigation`] |
//! | `sensor_imu` | sensor frame | [`SensorFrame::imu`] |
//! | `helicon_mag` | frame with a magnetometer sample | [`SensorFrame::mag_body`] |
//! | `helicon_gps` | frame with a GPS solution | [`SensorFrame::gps`] |
//! | `servo_output` | servo update | the runtime (what was sent, and who decided) |
//! | `rc_input` | RC frame | the runtime (pulse widths, manual switch) |
//! | `timing` | control step | the runtime (wake-up jitter, compute time, misses) |
//! | `failsafe` | event | the runtime; also a LOGGING message |
//! | `mode` | event | the runtime; also a LOGGING message |
//! | `excitation` | control step of a mission with `[[excitation]]` | the servo offset added to the law's command |
//! | `imu_health` | control step with an IMU sample | `helicon_core::imu_health::ImuHealth` |
//! | `estimator_bias` | control step of a navigation that estimates IMU biases (the ESKF) | [`NavigationSolution::imu_bias`] |
//!
//! Units are SI, frames NED (navigation) and FRD (body); times on the
//! on-board clock, `timestamp` in µs. Physical quantities are `double` so a
//! log replays bit for bit (the navigation can be re-run from
//! `sensor_*`). At 400 Hz (magnetometer 100 Hz, RC 50 Hz, GPS 5 Hz) the
//! whole set comes to about 231 kB/s; the IMU health adds 15.2 kB/s, the
//! ESKF's biases 43.6 kB/s and an identification flight's excitation
//! 18.4 kB/s.

use crate::error::WriteError;
use crate::format::Record;
use crate::px4::{self, Px4Record, Px4View};
use crate::spec::LogLevel;
use crate::ulog_message;
use crate::writer::{FlushPolicy, Topic, UlogWriter, timestamp_us};
use helicon_core::computer::Telemetry;
use helicon_core::navigation::{ImuBiasEstimate, NavigationSolution};
use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample, SensorFrame};
use helicon_core::state::NM;
use helicon_devices::geodetic::Geodetic;
use std::fs::File;
use std::io::Write;
use std::path::Path;

ulog_message! {
    /// One control step: what the flight software decided and knew
    /// ([`Telemetry`]).
    pub struct Control: "control" {
        /// Time of the measurement the step was computed from (µs).
        timestamp: u64,
        /// Sample counter since the flight computer was built.
        sample: u64,
        /// The same time in seconds, exact (s).
        t_s: f64,
        /// Reference heading ψ (rad).
        ref_yaw_rad: f64,
        /// Reference velocity NED (m/s).
        ref_vel_ned_m_s: [f64; 3],
        /// Servo commands sent, after saturation [S_col S_lat S_lon S_tr].
        command: [f64; 4],
        /// Output errors [ψ (rad), vn, ve, vd (m/s)], reference − estimate.
        tracking_error: [f64; 4],
        /// Integral states after this step [ψ (rad·samples), vn, ve, vd (m/s·samples)].
        integral: [f64; 4],
        /// The estimate of the nine measured states [φ θ ψ (rad), u v w (m/s), p q r (rad/s)].
        estimate: [f64; 9],
        /// The nine measured states the estimator was given (same units).
        measured: [f64; 9],
        /// Which commands were saturated.
        saturated: [bool; 4],
    }
}

ulog_message! {
    /// The navigation solution of a control step.
    pub struct Navigation: "navigation" {
        /// Time (µs).
        timestamp: u64,
        /// Fused position NED (m).
        position_ned_m: [f64; 3],
        /// Fused velocity NED (m/s).
        velocity_ned_m_s: [f64; 3],
        /// Fused attitude [φ θ ψ] (rad).
        attitude_rad: [f64; 3],
        /// 1σ of the fused position per NED axis (m).
        position_sigma_m: [f64; 3],
        /// A q-method attitude was fused this step.
        attitude_fix: bool,
        /// A GPS fix was fused this step.
        gps_fused: bool,
    }
}

ulog_message! {
    /// A raw IMU sample.
    pub struct SensorImu: "sensor_imu" {
        /// Time of the sample (µs).
        timestamp: u64,
        /// Specific force f = a − g in body axes (m/s²).
        specific_force_body_m_s2: [f64; 3],
        /// Body rates (rad/s).
        gyro_body_rad_s: [f64; 3],
    }
}

ulog_message! {
    /// A raw magnetometer sample.
    pub struct HeliconMag: "helicon_mag" {
        /// Time of the frame (µs).
        timestamp: u64,
        /// Field in body axes, in the units of the configured local field.
        field_body: [f64; 3],
    }
}

ulog_message! {
    /// A GPS solution as delivered.
    pub struct HeliconGps: "helicon_gps" {
        /// Time of the frame that delivered it (µs).
        timestamp: u64,
        /// Time of validity of the solution (s, on-board clock).
        epoch_s: f64,
        /// Position NED (m).
        position_ned_m: [f64; 3],
        /// Doppler velocity NED (m/s); zeros when not given.
        velocity_ned_m_s: [f64; 3],
        /// Fix type: 0 none, 2 2-D, 3 3-D (PX4's `fix_type` codes).
        fix_type: u8,
        /// The receiver gave a velocity.
        velocity_valid: bool,
    }
}

ulog_message! {
    /// The commands sent to the servos and who decided them.
    pub struct ServoOutput: "servo_output" {
        /// Time (µs).
        timestamp: u64,
        /// Commands [S_col S_lat S_lon S_tr] in the model's input units.
        command: [f64; 4],
        /// Source: 0 the control law, 1 the pilot (manual), 2 failsafe.
        source: u8,
    }
}

ulog_message! {
    /// One RC receiver frame.
    pub struct RcInput: "rc_input" {
        /// Time (µs).
        timestamp: u64,
        /// Channel pulse widths (µs); unused channels 0.
        channels_us: [u16; 16],
        /// Number of channels received.
        channel_count: u8,
        /// The pilot's manual/automatic switch is at manual.
        manual_switch: bool,
        /// No valid RC signal.
        signal_lost: bool,
    }
}

ulog_message! {
    /// Real-time behaviour of one control step.
    pub struct Timing: "timing" {
        /// Time (µs).
        timestamp: u64,
        /// The control step's sample counter.
        sample: u64,
        /// Wake-up time minus the scheduled time (µs).
        wakeup_jitter_us: i32,
        /// Time from wake-up to commands out (µs).
        compute_time_us: u32,
        /// Deadline misses since start.
        deadline_misses: u32,
        /// Log records dropped since start (logger ring full).
        log_dropped: u32,
    }
}

ulog_message! {
    /// A failsafe raised or cleared (also written as a LOGGING message).
    pub struct Failsafe: "failsafe" {
        /// Time (µs).
        timestamp: u64,
        /// Reason code ([`FailsafeReason`]).
        reason: u8,
        /// Raised (true) or cleared (false).
        active: bool,
    }
}

ulog_message! {
    /// A flight mode change (also written as a LOGGING message).
    pub struct Mode: "mode" {
        /// Time (µs).
        timestamp: u64,
        /// New mode ([`FlightMode`] code).
        mode: u8,
        /// Previous mode.
        previous: u8,
    }
}

ulog_message! {
    /// The flight-test excitation of a control step (`[[excitation]]`):
    /// the servo offset added to the law's command before saturation.
    pub struct Excitation: "excitation" {
        /// Time of the control step (µs).
        timestamp: u64,
        /// Offset [S_col S_lat S_lon S_tr] in the model's input units
        /// (zeros when not applied).
        offset: [f64; 4],
        /// The excitation runs (auto, its clock started and not ended).
        active: bool,
    }
}

ulog_message! {
    /// The IMU health monitor after a sample (vibration, hidden
    /// accelerometer saturation; `helicon_core::imu_health`).
    pub struct ImuHealth: "imu_health" {
        /// Time of the IMU sample (µs).
        timestamp: u64,
        /// RMS of the in-band residue (m/s²).
        vibration_rms_m_s2: f64,
        /// |running mean of the specific force| − g (m/s²).
        gravity_residual_m_s2: f64,
        /// Decaying peak of the largest axis over the output range (0..1).
        peak_fraction: f64,
        /// Flags: 1 vibration, 2 near range, 4 gravity deficit, 8 settling.
        flags: u8,
    }
}

ulog_message! {
    /// The IMU biases a navigation estimates (the ESKF), body axes.
    pub struct EstimatorBias: "estimator_bias" {
        /// Time of the control step (µs).
        timestamp: u64,
        /// Gyro bias (rad/s).
        gyro_rad_s: [f64; 3],
        /// Accelerometer bias (m/s²).
        accel_m_s2: [f64; 3],
        /// 1σ of the gyro bias (rad/s).
        gyro_sigma_rad_s: [f64; 3],
        /// 1σ of the accelerometer bias (m/s²).
        accel_sigma_m_s2: [f64; 3],
    }
}

impl EstimatorBias {
    /// The record of a navigation's bias estimate at time `t_s`.
    pub fn from_estimate(t_s: f64, b: &ImuBiasEstimate) -> Result<Self, WriteError> {
        Ok(EstimatorBias {
            timestamp: timestamp_us(t_s, "estimator_bias")?,
            gyro_rad_s: vec3(&b.gyro_rad_s),
            accel_m_s2: vec3(&b.accel_m_s2),
            gyro_sigma_rad_s: vec3(&b.gyro_sigma_rad_s),
            accel_sigma_m_s2: vec3(&b.accel_sigma_m_s2),
        })
    }
}

/// Why a failsafe was raised (the `failsafe.reason` codes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum FailsafeReason {
    /// The navigation failed (no attitude, diverged filter).
    NavigationFailure = 1,
    /// A non-finite measurement or estimate.
    NonFinite = 2,
    /// A sensor stopped delivering.
    SensorTimeout = 3,
    /// The control step missed its deadline.
    DeadlineMiss = 4,
    /// The RC link was lost.
    RcLoss = 5,
    /// The pilot commanded it.
    Pilot = 6,
    /// A sensor's samples were refused as implausible (out of its range,
    /// beyond what the airframe can do, no fix) until its stale limit.
    SensorImplausible = 7,
    /// Anything else.
    Other = 255,
}

impl FailsafeReason {
    /// Every reason.
    pub const ALL: [FailsafeReason; 8] = [
        FailsafeReason::NavigationFailure,
        FailsafeReason::NonFinite,
        FailsafeReason::SensorTimeout,
        FailsafeReason::DeadlineMiss,
        FailsafeReason::RcLoss,
        FailsafeReason::Pilot,
        FailsafeReason::SensorImplausible,
        FailsafeReason::Other,
    ];

    /// Text for logs.
    pub const fn name(self) -> &'static str {
        match self {
            FailsafeReason::NavigationFailure => "navigation failure",
            FailsafeReason::NonFinite => "non-finite measurement or estimate",
            FailsafeReason::SensorTimeout => "sensor timeout",
            FailsafeReason::DeadlineMiss => "deadline miss",
            FailsafeReason::RcLoss => "RC signal lost",
            FailsafeReason::Pilot => "pilot",
            FailsafeReason::SensorImplausible => "sensor implausible",
            FailsafeReason::Other => "other",
        }
    }

    /// The reason of a code read from a log.
    pub fn from_code(code: u8) -> Option<FailsafeReason> {
        FailsafeReason::ALL.into_iter().find(|r| *r as u8 == code)
    }
}

/// The flight modes (the `mode.mode` codes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum FlightMode {
    /// On the ground, servos held.
    Standby = 0,
    /// The pilot flies (RC passthrough).
    Manual = 1,
    /// The control law flies.
    Automatic = 2,
    /// Failsafe commands.
    Failsafe = 3,
}

impl FlightMode {
    /// Every mode.
    pub const ALL: [FlightMode; 4] = [
        FlightMode::Standby,
        FlightMode::Manual,
        FlightMode::Automatic,
        FlightMode::Failsafe,
    ];

    /// Text for logs.
    pub const fn name(self) -> &'static str {
        match self {
            FlightMode::Standby => "standby",
            FlightMode::Manual => "manual",
            FlightMode::Automatic => "automatic",
            FlightMode::Failsafe => "failsafe",
        }
    }

    /// The mode of a code read from a log.
    pub fn from_code(code: u8) -> Option<FlightMode> {
        FlightMode::ALL.into_iter().find(|m| *m as u8 == code)
    }
}

fn vec3(v: &nalgebra::Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

impl Control {
    /// The record of one control step. Errors only for a time that cannot
    /// be a timestamp.
    pub fn from_telemetry(t: &Telemetry) -> Result<Self, WriteError> {
        let mut estimate = [0.0; NM];
        estimate.copy_from_slice(&t.estimate.as_slice()[..NM]);
        let v = &t.reference.velocity_ned_m_s;
        Ok(Control {
            timestamp: timestamp_us(t.t_s, "control")?,
            sample: t.sample,
            t_s: t.t_s,
            ref_yaw_rad: t.reference.yaw_rad,
            ref_vel_ned_m_s: [v.x, v.y, v.z],
            command: t.command.into(),
            tracking_error: t.tracking_error.into(),
            integral: t.integral.into(),
            estimate,
            measured: t.measured.into(),
            saturated: t.saturated,
        })
    }
}

impl Navigation {
    /// The record of a navigation solution at time `t_s`.
    pub fn from_solution(t_s: f64, n: &NavigationSolution) -> Result<Self, WriteError> {
        Ok(Navigation {
            timestamp: timestamp_us(t_s, "navigation")?,
            position_ned_m: vec3(&n.position_ned_m),
            velocity_ned_m_s: vec3(&n.velocity_ned_m_s),
            attitude_rad: vec3(&n.attitude_rad),
            position_sigma_m: vec3(&n.position_sigma_m),
            attitude_fix: n.attitude_fix,
            gps_fused: n.gps_fused,
        })
    }
}

impl SensorImu {
    /// The record of an IMU sample at time `t_s`.
    pub fn from_sample(t_s: f64, imu: &ImuSample) -> Result<Self, WriteError> {
        Ok(SensorImu {
            timestamp: timestamp_us(t_s, "sensor_imu")?,
            specific_force_body_m_s2: vec3(&imu.specific_force_body_m_s2),
            gyro_body_rad_s: vec3(&imu.gyro_body_rad_s),
        })
    }
}

impl HeliconGps {
    /// The record of a GPS solution delivered at time `t_s`.
    pub fn from_fix(t_s: f64, g: &GpsFix) -> Result<Self, WriteError> {
        Ok(HeliconGps {
            timestamp: timestamp_us(t_s, "helicon_gps")?,
            epoch_s: g.epoch_s,
            position_ned_m: vec3(&g.position_ned_m),
            velocity_ned_m_s: g.velocity_ned_m_s.as_ref().map_or([0.0; 3], vec3),
            fix_type: match g.fix {
                GpsFixType::NoFix => 0,
                GpsFixType::Fix2d => 2,
                GpsFixType::Fix3d => 3,
            },
            velocity_valid: g.velocity_ned_m_s.is_some(),
        })
    }

    /// The core's GPS solution back (`None` for an unknown fix code).
    pub fn to_fix(&self) -> Option<GpsFix> {
        let [vn, ve, vd] = self.velocity_ned_m_s;
        let [n, e, d] = self.position_ned_m;
        Some(GpsFix {
            epoch_s: self.epoch_s,
            fix: match self.fix_type {
                0 | 1 => GpsFixType::NoFix,
                2 => GpsFixType::Fix2d,
                3 => GpsFixType::Fix3d,
                _ => return None,
            },
            position_ned_m: nalgebra::Vector3::new(n, e, d),
            velocity_ned_m_s: self
                .velocity_valid
                .then(|| nalgebra::Vector3::new(vn, ve, vd)),
        })
    }
}

/// The records of one sensor frame: IMU always, magnetometer and GPS when
/// present in the frame.
pub fn frame_records(
    f: &SensorFrame,
) -> Result<(SensorImu, Option<HeliconMag>, Option<HeliconGps>), WriteError> {
    let imu = SensorImu::from_sample(f.t_s, &f.imu)?;
    let mag = f.mag_body.as_ref().map(|m| HeliconMag {
        timestamp: imu.timestamp,
        field_body: vec3(m),
    });
    let gps = match &f.gps {
        Some(g) => Some(HeliconGps::from_fix(f.t_s, g)?),
        None => None,
    };
    Ok((imu, mag, gps))
}

/// One record of any topic: what a logger ring carries (all `Copy`, no
/// heap).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LogRecord {
    /// `control`
    Control(Control),
    /// `navigation`
    Navigation(Navigation),
    /// `sensor_imu`
    Imu(SensorImu),
    /// `helicon_mag`
    Mag(HeliconMag),
    /// `helicon_gps`
    Gps(HeliconGps),
    /// `servo_output`
    Servo(ServoOutput),
    /// `rc_input`
    Rc(RcInput),
    /// `timing`
    Timing(Timing),
    /// `failsafe` (also logged as text)
    Failsafe(Failsafe),
    /// `mode` (also logged as text)
    Mode(Mode),
    /// `excitation`
    Excitation(Excitation),
    /// `imu_health`
    ImuHealth(ImuHealth),
    /// `estimator_bias`
    EstimatorBias(EstimatorBias),
    /// `vehicle_land_detected` (PX4's topic; a land detector's verdict)
    LandDetected(px4::VehicleLandDetected),
}

/// Identification written into the log's INFO messages, the parameters
/// written into its definitions, and what the PX4 view of the log needs.
#[derive(Debug, Clone, PartialEq)]
pub struct LogInfo {
    /// `sys_name` (shown by the log viewers).
    pub sys_name: String,
    /// `ver_sw`: the software version (a git hash or version string).
    pub ver_sw: String,
    /// `ver_hw`: the hardware (Flight Review's board name).
    pub ver_hw: String,
    /// `sys_uuid`: the computer's unique id (empty: not written).
    pub sys_uuid: String,
    /// `time_ref_utc`: PX4's offset of the local time from UTC (s); the
    /// on-board clock and the GPS's `time_utc_usec` are UTC, so 0.
    pub time_ref_utc_s: Option<i32>,
    /// Header timestamp (µs on the on-board clock).
    pub start_us: u64,
    /// The UTC time of the on-board clock's zero (µs since 1970), when the
    /// computer's clock knows it: the GPS's `time_utc_usec` (Flight Review's
    /// start time). `None` writes 0, PX4's "unknown".
    pub start_utc_us: Option<u64>,
    /// The origin of the local NED frame: the geodetic PX4 topics
    /// (`vehicle_global_position`, `sensor_gps`, `vehicle_gps_position`,
    /// `vehicle_local_position.ref_lat` …) need it; `None` leaves them out.
    pub home: Option<Geodetic>,
    /// The control period (µs): a gap of more than 1.5 periods between two
    /// `timing` records (missed deadlines) is written as a DROPOUT of the
    /// time missed. `None`: no dropout is inferred.
    pub control_period_us: Option<u64>,
    /// The parameters at the start (`float`), as PX4 logs its own: written
    /// as PARAMETER messages in the definitions; a change in flight is
    /// [`FlightLog::parameter_changed`].
    pub parameters: Vec<(String, f32)>,
}

impl Default for LogInfo {
    fn default() -> Self {
        LogInfo {
            sys_name: "helicon".to_string(),
            ver_sw: env!("CARGO_PKG_VERSION").to_string(),
            ver_hw: default_ver_hw(),
            sys_uuid: String::new(),
            time_ref_utc_s: Some(0),
            start_us: 0,
            start_utc_us: None,
            home: None,
            control_period_us: None,
            parameters: Vec::new(),
        }
    }
}

/// `HELICON_<OS>_<ARCH>` of the computer this runs on, e.g.
/// `HELICON_LINUX_AARCH64`.
pub fn default_ver_hw() -> String {
    format!(
        "HELICON_{}_{}",
        std::env::consts::OS,
        std::env::consts::ARCH
    )
    .to_ascii_uppercase()
}

#[derive(Debug, Clone, Copy)]
struct Topics {
    control: Topic<Control>,
    navigation: Topic<Navigation>,
    imu: Topic<SensorImu>,
    mag: Topic<HeliconMag>,
    gps: Topic<HeliconGps>,
    servo: Topic<ServoOutput>,
    rc: Topic<RcInput>,
    timing: Topic<Timing>,
    failsafe: Topic<Failsafe>,
    mode: Topic<Mode>,
    excitation: Topic<Excitation>,
    imu_health: Topic<ImuHealth>,
    estimator_bias: Topic<EstimatorBias>,
    attitude: Topic<px4::VehicleAttitude>,
    angular_velocity: Topic<px4::VehicleAngularVelocity>,
    local_position: Topic<px4::VehicleLocalPosition>,
    local_position_setpoint: Topic<px4::VehicleLocalPositionSetpoint>,
    global_position: Topic<px4::VehicleGlobalPosition>,
    sensor_combined: Topic<px4::SensorCombined>,
    sensor_gps: Topic<px4::SensorGps>,
    vehicle_gps: Topic<px4::VehicleGpsPosition>,
    magnetometer: Topic<px4::VehicleMagnetometer>,
    actuator_outputs: Topic<px4::ActuatorOutputs>,
    input_rc: Topic<px4::InputRc>,
    status: Topic<px4::VehicleStatus>,
    land_detected: Topic<px4::VehicleLandDetected>,
    cpuload: Topic<px4::Cpuload>,
}

/// The flight log: a [`UlogWriter`] with the whole message set declared
/// and subscribed (instance 0 of each topic).
#[derive(Debug)]
pub struct FlightLog<W: Write> {
    writer: UlogWriter<W>,
    topics: Topics,
    px4: Px4View,
    control_period_us: Option<u64>,
    last_timing_us: Option<u64>,
}

impl FlightLog<File> {
    /// Create the log file (a new one: an existing file is an error, see
    /// [`UlogWriter::create`]), write `info` and the definitions.
    pub fn create(path: &Path, info: &LogInfo, policy: FlushPolicy) -> Result<Self, WriteError> {
        let w = UlogWriter::create(path, info.start_us, policy)?;
        Self::with_info(w, info)
    }

    /// As [`Self::create`], replacing a file already at `path`
    /// ([`UlogWriter::create_replacing`]: a simulation run's own folder).
    pub fn create_replacing(
        path: &Path,
        info: &LogInfo,
        policy: FlushPolicy,
    ) -> Result<Self, WriteError> {
        let w = UlogWriter::create_replacing(path, info.start_us, policy)?;
        Self::with_info(w, info)
    }

    /// The next numbered flight log of the folder `dir`,
    /// `flight-<NNNN>-<UTC>.ulg` ([`UlogWriter::create_numbered`]); returns
    /// the log and its path.
    pub fn create_numbered(
        dir: &Path,
        unix_s: u64,
        info: &LogInfo,
        policy: FlushPolicy,
    ) -> Result<(Self, std::path::PathBuf), WriteError> {
        let (w, path) = UlogWriter::create_numbered(dir, "flight", unix_s, info.start_us, policy)?;
        Ok((Self::with_info(w, info)?, path))
    }
}

impl<W: Write> FlightLog<W> {
    /// A flight log into `out` with `info`.
    pub fn new(out: W, info: &LogInfo, policy: FlushPolicy) -> Result<Self, WriteError> {
        let w = UlogWriter::new(out, info.start_us, policy)?;
        Self::with_info(w, info)
    }

    fn with_info(mut w: UlogWriter<W>, info: &LogInfo) -> Result<Self, WriteError> {
        w.info_str("sys_name", &info.sys_name)?;
        w.info_str("ver_sw", &info.ver_sw)?;
        w.info_str("ver_hw", &info.ver_hw)?;
        w.info_str("sys_os_name", std::env::consts::OS)?;
        w.info_str("sys_toolchain", "rustc")?;
        if !info.sys_uuid.is_empty() {
            w.info_str("sys_uuid", &info.sys_uuid)?;
        }
        if let Some(t) = info.time_ref_utc_s {
            w.info_i32("time_ref_utc", t)?;
        }
        for (name, value) in &info.parameters {
            w.parameter_f32(name, *value)?;
        }
        let mut log = Self::from_writer(w)?;
        log.px4 = Px4View::new(info.home, info.start_utc_us);
        log.control_period_us = info.control_period_us;
        Ok(log)
    }

    /// Declare and subscribe the message set on a writer whose own
    /// information and parameters are written (definitions still open).
    /// The PX4 view has no home (no geodetic topics) and infers no
    /// dropouts.
    pub fn from_writer(mut w: UlogWriter<W>) -> Result<Self, WriteError> {
        w.add_format::<Control>()?;
        w.add_format::<Navigation>()?;
        w.add_format::<SensorImu>()?;
        w.add_format::<HeliconMag>()?;
        w.add_format::<HeliconGps>()?;
        w.add_format::<ServoOutput>()?;
        w.add_format::<RcInput>()?;
        w.add_format::<Timing>()?;
        w.add_format::<Failsafe>()?;
        w.add_format::<Mode>()?;
        w.add_format::<Excitation>()?;
        w.add_format::<ImuHealth>()?;
        w.add_format::<EstimatorBias>()?;
        w.add_format::<px4::VehicleAttitude>()?;
        w.add_format::<px4::VehicleAngularVelocity>()?;
        w.add_format::<px4::VehicleLocalPosition>()?;
        w.add_format::<px4::VehicleLocalPositionSetpoint>()?;
        w.add_format::<px4::VehicleGlobalPosition>()?;
        w.add_format::<px4::SensorCombined>()?;
        w.add_format::<px4::SensorGps>()?;
        w.add_format::<px4::VehicleGpsPosition>()?;
        w.add_format::<px4::VehicleMagnetometer>()?;
        w.add_format::<px4::ActuatorOutputs>()?;
        w.add_format::<px4::InputRc>()?;
        w.add_format::<px4::VehicleStatus>()?;
        w.add_format::<px4::VehicleLandDetected>()?;
        w.add_format::<px4::Cpuload>()?;
        let topics = Topics {
            control: w.add_logged(0)?,
            navigation: w.add_logged(0)?,
            imu: w.add_logged(0)?,
            mag: w.add_logged(0)?,
            gps: w.add_logged(0)?,
            servo: w.add_logged(0)?,
            rc: w.add_logged(0)?,
            timing: w.add_logged(0)?,
            failsafe: w.add_logged(0)?,
            mode: w.add_logged(0)?,
            excitation: w.add_logged(0)?,
            imu_health: w.add_logged(0)?,
            estimator_bias: w.add_logged(0)?,
            attitude: w.add_logged(0)?,
            angular_velocity: w.add_logged(0)?,
            local_position: w.add_logged(0)?,
            local_position_setpoint: w.add_logged(0)?,
            global_position: w.add_logged(0)?,
            sensor_combined: w.add_logged(0)?,
            sensor_gps: w.add_logged(0)?,
            vehicle_gps: w.add_logged(0)?,
            magnetometer: w.add_logged(0)?,
            actuator_outputs: w.add_logged(0)?,
            input_rc: w.add_logged(0)?,
            status: w.add_logged(0)?,
            land_detected: w.add_logged(0)?,
            cpuload: w.add_logged(0)?,
        };
        Ok(FlightLog {
            writer: w,
            topics,
            px4: Px4View::new(None, None),
            control_period_us: None,
            last_timing_us: None,
        })
    }

    /// A parameter changed in flight at `t_us`: a PARAMETER message in the
    /// data section (PX4's way), preceded by a text naming the change.
    pub fn parameter_changed(
        &mut self,
        name: &str,
        value: f32,
        t_us: u64,
    ) -> Result<(), WriteError> {
        self.writer.parameter_f32(name, value)?;
        let mut text = StackText::new();
        let _ = write_fmt(&mut text, format_args!("parameter {name} = {value}"));
        self.writer.log(LogLevel::Info, t_us, text.as_str())
    }

    /// A mode change: the `mode` record and PX4's `vehicle_status` saying
    /// `status` (the runtime's precise mapping; [`Self::write_data`] maps
    /// a `mode` record by its [`FlightMode`] alone).
    pub fn write_mode(&mut self, m: &Mode, status: px4::StatusMode) -> Result<(), WriteError> {
        self.writer.write(self.topics.mode, m)?;
        let s = self.px4.set_mode(m.timestamp, status);
        self.writer.write(self.topics.status, &s)
    }

    /// The ground station's navigator changed its mode at `t_us`: PX4's
    /// `vehicle_status` with its `nav_state` (`px4::NAV_STATE_*`).
    pub fn write_navigator_state(&mut self, t_us: u64, nav_state: u8) -> Result<(), WriteError> {
        let s = self.px4.set_navigator(t_us, nav_state);
        self.writer.write(self.topics.status, &s)
    }

    /// Write a PX4 record of the view.
    fn write_px4(&mut self, r: &Px4Record) -> Result<(), WriteError> {
        let t = &self.topics;
        let w = &mut self.writer;
        match r {
            Px4Record::Attitude(x) => w.write(t.attitude, x),
            Px4Record::AngularVelocity(x) => w.write(t.angular_velocity, x),
            Px4Record::LocalPosition(x) => w.write(t.local_position, x),
            Px4Record::LocalPositionSetpoint(x) => w.write(t.local_position_setpoint, x),
            Px4Record::GlobalPosition(x) => w.write(t.global_position, x),
            Px4Record::SensorCombined(x) => w.write(t.sensor_combined, x),
            Px4Record::Gps(x) => {
                w.write(t.sensor_gps, x)?;
                w.write(t.vehicle_gps, &px4::VehicleGpsPosition(*x))
            }
            Px4Record::Magnetometer(x) => w.write(t.magnetometer, x),
            Px4Record::ActuatorOutputs(x) => w.write(t.actuator_outputs, x),
            Px4Record::InputRc(x) => w.write(t.input_rc, x),
            Px4Record::Status(x) => w.write(t.status, x),
            Px4Record::Cpuload(x) => w.write(t.cpuload, x),
        }
    }

    /// The PX4 records of one helicon record, written after it (at most
    /// three per record: no allocation).
    fn write_view(&mut self, r: &LogRecord) -> Result<(), WriteError> {
        let mut out: [Option<Px4Record>; 3] = [None; 3];
        let mut n = 0;
        let mut push = |p: Px4Record| {
            if let Some(slot) = out.get_mut(n) {
                *slot = Some(p);
                n += 1;
            }
        };
        let v = &mut self.px4;
        match r {
            LogRecord::Control(x) => v.from_control(x, &mut push),
            LogRecord::Navigation(x) => v.from_navigation(x, &mut push),
            LogRecord::Imu(x) => v.from_imu(x, &mut push),
            LogRecord::Mag(x) => v.from_mag(x, &mut push),
            LogRecord::Gps(x) => v.from_gps(x, &mut push),
            LogRecord::Servo(x) => v.from_servo(x, &mut push),
            LogRecord::Rc(x) => v.from_rc(x, &mut push),
            LogRecord::Timing(x) => v.from_timing(x, &mut push),
            LogRecord::Mode(x) => {
                let mode = FlightMode::from_code(x.mode).unwrap_or(FlightMode::Failsafe);
                let s = v.set_mode(x.timestamp, status_mode(mode, v.status().nav_state));
                push(Px4Record::Status(s));
            }
            LogRecord::Failsafe(_)
            | LogRecord::Excitation(_)
            | LogRecord::ImuHealth(_)
            | LogRecord::EstimatorBias(_)
            | LogRecord::LandDetected(_) => {}
        }
        for p in out.iter().flatten() {
            self.write_px4(p)?;
        }
        Ok(())
    }

    /// A DROPOUT for the control steps missed before the `timing` record at
    /// `t_us` (more than 1.5 control periods since the last one).
    fn timing_gap(&mut self, t_us: u64) -> Result<(), WriteError> {
        let last = self.last_timing_us.replace(t_us);
        if let (Some(period), Some(last)) = (self.control_period_us, last)
            && t_us > last
            && 2 * (t_us - last) > 3 * period
        {
            let lost_ms = (t_us - last - period).div_ceil(1000).max(1);
            let ms = u16::try_from(lost_ms).unwrap_or(u16::MAX);
            self.writer.dropout(ms, t_us)?;
        }
        Ok(())
    }

    /// The underlying writer (parameters changes, text messages, dropouts,
    /// flushing).
    pub fn writer_mut(&mut self) -> &mut UlogWriter<W> {
        &mut self.writer
    }

    /// Write one record's data only: no LOGGING text for failsafe and mode
    /// events (for a runtime that writes its own, more precise text with
    /// [`UlogWriter::log`]), then its PX4 view (`vehicle_attitude` of a
    /// `control` record …, decimated) and, for a `timing` record after a
    /// gap, a DROPOUT. No allocation.
    pub fn write_data(&mut self, r: &LogRecord) -> Result<(), WriteError> {
        let t = &self.topics;
        let w = &mut self.writer;
        match r {
            LogRecord::Control(x) => w.write(t.control, x),
            LogRecord::Navigation(x) => w.write(t.navigation, x),
            LogRecord::Imu(x) => w.write(t.imu, x),
            LogRecord::Mag(x) => w.write(t.mag, x),
            LogRecord::Gps(x) => w.write(t.gps, x),
            LogRecord::Servo(x) => w.write(t.servo, x),
            LogRecord::Rc(x) => w.write(t.rc, x),
            LogRecord::Timing(x) => w.write(t.timing, x),
            LogRecord::Failsafe(x) => w.write(t.failsafe, x),
            LogRecord::Mode(x) => w.write(t.mode, x),
            LogRecord::Excitation(x) => w.write(t.excitation, x),
            LogRecord::ImuHealth(x) => w.write(t.imu_health, x),
            LogRecord::EstimatorBias(x) => w.write(t.estimator_bias, x),
            LogRecord::LandDetected(x) => w.write(t.land_detected, x),
        }?;
        if let LogRecord::Timing(x) = r {
            self.timing_gap(x.timestamp)?;
        }
        self.write_view(r)
    }

    /// Write one record (failsafe and mode events also as LOGGING text).
    /// No allocation.
    pub fn write(&mut self, r: &LogRecord) -> Result<(), WriteError> {
        self.write_data(r)?;
        let w = &mut self.writer;
        match r {
            LogRecord::Failsafe(x) => {
                let name = FailsafeReason::from_code(x.reason).map_or("unknown", |r| r.name());
                let mut text = StackText::new();
                let _ = if x.active {
                    write_fmt(&mut text, format_args!("failsafe raised: {name}"))
                } else {
                    write_fmt(&mut text, format_args!("failsafe cleared: {name}"))
                };
                let level = if x.active {
                    LogLevel::Critical
                } else {
                    LogLevel::Notice
                };
                w.log(level, x.timestamp, text.as_str())
            }
            LogRecord::Mode(x) => {
                let name = |c| FlightMode::from_code(c).map_or("unknown", |m| m.name());
                let mut text = StackText::new();
                let _ = write_fmt(
                    &mut text,
                    format_args!("mode: {} -> {}", name(x.previous), name(x.mode)),
                );
                w.log(LogLevel::Info, x.timestamp, text.as_str())
            }
            _ => Ok(()),
        }
    }

    /// Log one control step: `control`, and `navigation` when the
    /// estimator runs one.
    pub fn log_telemetry(&mut self, t: &Telemetry) -> Result<(), WriteError> {
        self.write(&LogRecord::Control(Control::from_telemetry(t)?))?;
        if let Some(n) = &t.navigation {
            self.write(&LogRecord::Navigation(Navigation::from_solution(t.t_s, n)?))?;
        }
        Ok(())
    }

    /// Log one sensor frame: `sensor_imu`, and `helicon_mag`/`helicon_gps`
    /// when sampled.
    pub fn log_frame(&mut self, f: &SensorFrame) -> Result<(), WriteError> {
        let (imu, mag, gps) = frame_records(f)?;
        self.write(&LogRecord::Imu(imu))?;
        if let Some(m) = mag {
            self.write(&LogRecord::Mag(m))?;
        }
        if let Some(g) = gps {
            self.write(&LogRecord::Gps(g))?;
        }
        Ok(())
    }

    /// Flush and return the output.
    pub fn finish(self) -> Result<W, WriteError> {
        self.writer.finish()
    }
}

/// PX4's `vehicle_status` of a helicon flight mode; standby keeps the
/// navigation state `current`.
pub fn status_mode(m: FlightMode, current: u8) -> px4::StatusMode {
    let (arming_state, nav_state, failsafe) = match m {
        FlightMode::Standby => (px4::ARMING_STATE_DISARMED, current, false),
        FlightMode::Manual => (px4::ARMING_STATE_ARMED, px4::NAV_STATE_MANUAL, false),
        FlightMode::Automatic => (px4::ARMING_STATE_ARMED, px4::NAV_STATE_AUTO_MISSION, false),
        FlightMode::Failsafe => (px4::ARMING_STATE_ARMED, px4::NAV_STATE_AUTO_LOITER, true),
    };
    px4::StatusMode {
        arming_state,
        nav_state,
        failsafe,
    }
}

fn write_fmt(text: &mut StackText, args: std::fmt::Arguments<'_>) -> std::fmt::Result {
    std::fmt::Write::write_fmt(text, args)
}

/// A short text formatted on the stack (no allocation); longer text is cut.
struct StackText {
    buf: [u8; 128],
    len: usize,
}

impl StackText {
    fn new() -> Self {
        StackText {
            buf: [0; 128],
            len: 0,
        }
    }
    fn as_str(&self) -> &str {
        std::str::from_utf8(&self.buf[..self.len]).unwrap_or("")
    }
}

impl std::fmt::Write for StackText {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        let room = self.buf.len() - self.len;
        let mut n = s.len().min(room);
        while !s.is_char_boundary(n) {
            n -= 1;
        }
        self.buf[self.len..self.len + n].copy_from_slice(&s.as_bytes()[..n]);
        self.len += n;
        Ok(())
    }
}

/// The sizes of the message set's records (bytes logged per message,
/// without the 5-byte header and id).
pub fn record_sizes() -> [(&'static str, usize); 13] {
    [
        (Control::NAME, Control::SIZE),
        (Navigation::NAME, Navigation::SIZE),
        (SensorImu::NAME, SensorImu::SIZE),
        (HeliconMag::NAME, HeliconMag::SIZE),
        (HeliconGps::NAME, HeliconGps::SIZE),
        (ServoOutput::NAME, ServoOutput::SIZE),
        (RcInput::NAME, RcInput::SIZE),
        (Timing::NAME, Timing::SIZE),
        (Failsafe::NAME, Failsafe::SIZE),
        (Mode::NAME, Mode::SIZE),
        (Excitation::NAME, Excitation::SIZE),
        (ImuHealth::NAME, ImuHealth::SIZE),
        (EstimatorBias::NAME, EstimatorBias::SIZE),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sizes docs/ulog.md quotes, and the data rate they give.
    #[test]
    fn record_sizes_and_data_rate() {
        let size = |name| {
            record_sizes()
                .into_iter()
                .find(|(n, _)| *n == name)
                .map(|(_, s)| s + 5)
                .unwrap_or(0)
        };
        assert_eq!(size("control"), 305);
        assert_eq!(size("navigation"), 111);
        assert_eq!(size("sensor_imu"), 61);
        assert_eq!(size("servo_output"), 46);
        assert_eq!(size("timing"), 37);
        let per_s = 400 * (size("control") + size("navigation") + size("sensor_imu"))
            + 400 * (size("servo_output") + size("timing"))
            + 100 * size("helicon_mag")
            + 50 * size("rc_input")
            + 5 * size("helicon_gps")
            + 10 * 11; // a SYNC per flush
        assert_eq!(per_s.div_ceil(1000), 231); // kB/s
        // the on-board runtime's additions, each per control step
        assert_eq!(size("imu_health"), 5 + 8 + 3 * 8 + 1);
        assert_eq!(400 * size("imu_health"), 15_200);
        assert_eq!(400 * size("estimator_bias"), 400 * (5 + 8 + 12 * 8));
        assert_eq!(400 * size("excitation"), 400 * (5 + 8 + 4 * 8 + 1));
    }
}
