//! PX4's uORB topics, written beside helicon's own so that PX4's tools
//! (Flight Review, PlotJuggler's PX4 layouts, pyulog's `ulog2kml`) read a
//! helicon log as a PX4 log.
//!
//! Each record is the uORB definition (`msg/*.msg` of PX4-Autopilot) as
//! PX4's message generator lays it out in a log: every field of the
//! definition under its name and type, sorted by the size of its base type
//! (largest first, the definition's order kept among equals, so `timestamp`
//! comes first), and a trailing `_padding0` to a multiple of 8 bytes that is
//! declared in the format and not logged. `tools/ulog-check/px4_fields.json`
//! holds the names and types the definitions give (its generator,
//! `tools/ulog-check/gen_px4_fields.py`, reads a PX4-Autopilot checkout);
//! the Python check compares every topic of a helicon log with it.
//!
//! The topics are a view of helicon's records, made on the logger's side by
//! [`Px4View`] (allocation-free, decimated to PX4's logging rates: the full
//! rate stays in helicon's topics). A field helicon does not know is NaN for
//! a float (uORB's "not available"), zero for an integer, false for a flag.
//! The mapping, field by field, is in `docs/ulog.md`.

use crate::format::Record;
use crate::messages::{
    Control, HeliconGps, HeliconMag, Navigation, RcInput, SensorImu, ServoOutput, Timing,
};
use crate::ulog_message;
use helicon_devices::geodetic::{Geodetic, LocalNed};
use nalgebra::{UnitQuaternion, Vector3};

ulog_message! {
    /// `vehicle_attitude` (VehicleAttitude.msg): the estimated attitude.
    pub struct VehicleAttitude: "vehicle_attitude" {
        /// Time since system start (µs).
        timestamp: u64,
        /// Time of the raw data (µs).
        timestamp_sample: u64,
        /// Quaternion (w, x, y, z, Hamilton) rotating FRD body to NED.
        q: [f32; 4],
        /// Change of the quaternion at the last reset.
        delta_q_reset: [f32; 4],
        /// Quaternion reset counter.
        quat_reset_counter: u8,
    }
}

ulog_message! {
    /// `vehicle_angular_velocity` (VehicleAngularVelocity.msg).
    pub struct VehicleAngularVelocity: "vehicle_angular_velocity" {
        /// Time since system start (µs).
        timestamp: u64,
        /// Time of the data sample (µs).
        timestamp_sample: u64,
        /// Bias-corrected angular velocity about FRD x, y, z (rad/s).
        xyz: [f32; 3],
        /// Angular acceleration about FRD x, y, z (rad/s²).
        xyz_derivative: [f32; 3],
    }
}

ulog_message! {
    /// `vehicle_local_position` (VehicleLocalPosition.msg): the fused
    /// position and velocity in the local NED frame.
    pub struct VehicleLocalPosition: "vehicle_local_position" {
        /// Time since system start (µs).
        timestamp: u64,
        /// Time of the raw data (µs).
        timestamp_sample: u64,
        /// Time the reference position was set (µs).
        ref_timestamp: u64,
        /// Reference point latitude (deg).
        ref_lat: f64,
        /// Reference point longitude (deg).
        ref_lon: f64,
        /// North position (m).
        x: f32,
        /// East position (m).
        y: f32,
        /// Down position (m).
        z: f32,
        /// Lateral shift at the last reset (m).
        delta_xy: [f32; 2],
        /// Vertical shift at the last reset (m).
        delta_z: f32,
        /// North velocity (m/s).
        vx: f32,
        /// East velocity (m/s).
        vy: f32,
        /// Down velocity (m/s).
        vz: f32,
        /// Down position time derivative (m/s).
        z_deriv: f32,
        /// Lateral velocity shift at the last reset (m/s).
        delta_vxy: [f32; 2],
        /// Vertical velocity shift at the last reset (m/s).
        delta_vz: f32,
        /// North acceleration (m/s²).
        ax: f32,
        /// East acceleration (m/s²).
        ay: f32,
        /// Down acceleration (m/s²).
        az: f32,
        /// Yaw (rad, −π..π).
        heading: f32,
        /// Variance of the heading (rad²).
        heading_var: f32,
        /// Heading integrated from the gyro only (rad).
        unaided_heading: f32,
        /// Heading change at the last reset (rad).
        delta_heading: f32,
        /// Variance of the tilt (rad²).
        tilt_var: f32,
        /// Reference altitude AMSL (m).
        ref_alt: f32,
        /// Distance to the ground (m).
        dist_bottom: f32,
        /// Variance of the distance to the ground (m²).
        dist_bottom_var: f32,
        /// Shift of the distance to the ground at the last reset (m).
        delta_dist_bottom: f32,
        /// Standard deviation of the horizontal position (m).
        eph: f32,
        /// Standard deviation of the vertical position (m).
        epv: f32,
        /// Standard deviation of the horizontal velocity (m/s).
        evh: f32,
        /// Standard deviation of the vertical velocity (m/s).
        evv: f32,
        /// Largest horizontal speed (m/s; infinite: no limit).
        vxy_max: f32,
        /// Largest vertical speed (m/s; infinite: no limit).
        vz_max: f32,
        /// Smallest height above ground (m; infinite: no limit).
        hagl_min: f32,
        /// Largest height above ground for z control (m; infinite: no limit).
        hagl_max_z: f32,
        /// Largest height above ground for xy control (m; infinite: no limit).
        hagl_max_xy: f32,
        /// x and y are valid.
        xy_valid: bool,
        /// z is valid.
        z_valid: bool,
        /// vx and vy are valid.
        v_xy_valid: bool,
        /// vz is valid.
        v_z_valid: bool,
        /// Lateral position reset counter.
        xy_reset_counter: u8,
        /// Vertical position reset counter.
        z_reset_counter: u8,
        /// Lateral velocity reset counter.
        vxy_reset_counter: u8,
        /// Vertical velocity reset counter.
        vz_reset_counter: u8,
        /// Heading reset counter.
        heading_reset_counter: u8,
        /// The heading is good enough for control.
        heading_good_for_control: bool,
        /// x, y have a global reference (ref_lat, ref_lon).
        xy_global: bool,
        /// z has a global reference (ref_alt).
        z_global: bool,
        /// dist_bottom is valid.
        dist_bottom_valid: bool,
        /// Distance-to-ground reset counter.
        dist_bottom_reset_counter: u8,
        /// Sensors used for dist_bottom (bit field).
        dist_bottom_sensor_bitfield: u8,
        /// The position is dead-reckoned.
        dead_reckoning: bool,
    }
}

ulog_message! {
    /// `vehicle_local_position_setpoint` (VehicleLocalPositionSetpoint.msg):
    /// NaN where the state is not controlled.
    pub struct VehicleLocalPositionSetpoint: "vehicle_local_position_setpoint" {
        /// Time since system start (µs).
        timestamp: u64,
        /// North (m).
        x: f32,
        /// East (m).
        y: f32,
        /// Down (m).
        z: f32,
        /// Yaw (rad).
        yaw: f32,
        /// Yaw rate (rad/s).
        yawspeed: f32,
        /// North velocity (m/s).
        vx: f32,
        /// East velocity (m/s).
        vy: f32,
        /// Down velocity (m/s).
        vz: f32,
        /// Acceleration NED (m/s²).
        acceleration: [f32; 3],
        /// Jerk NED (m/s³).
        jerk: [f32; 3],
        /// Normalised thrust vector NED.
        thrust: [f32; 3],
    }
}

ulog_message! {
    /// `vehicle_global_position` (VehicleGlobalPosition.msg): the fused
    /// position in WGS-84.
    pub struct VehicleGlobalPosition: "vehicle_global_position" {
        /// Time since system start (µs).
        timestamp: u64,
        /// Time of the raw data (µs).
        timestamp_sample: u64,
        /// Latitude (deg).
        lat: f64,
        /// Longitude (deg).
        lon: f64,
        /// Altitude AMSL (m).
        alt: f32,
        /// Altitude above the ellipsoid (m).
        alt_ellipsoid: f32,
        /// Altitude shift at the last reset (m).
        delta_alt: f32,
        /// Terrain shift at the last reset (m).
        delta_terrain: f32,
        /// Standard deviation of the horizontal position (m).
        eph: f32,
        /// Standard deviation of the vertical position (m).
        epv: f32,
        /// Terrain altitude (m).
        terrain_alt: f32,
        /// lat and lon are valid.
        lat_lon_valid: bool,
        /// alt is valid.
        alt_valid: bool,
        /// Horizontal reset counter.
        lat_lon_reset_counter: u8,
        /// Altitude reset counter.
        alt_reset_counter: u8,
        /// Terrain reset counter.
        terrain_reset_counter: u8,
        /// terrain_alt is valid.
        terrain_alt_valid: bool,
        /// The position is dead-reckoned.
        dead_reckoning: bool,
    }
}

ulog_message! {
    /// `sensor_combined` (SensorCombined.msg): gyro and accelerometer.
    pub struct SensorCombined: "sensor_combined" {
        /// Time since system start (µs), the gyro's time.
        timestamp: u64,
        /// Angular rate about FRD x, y, z (rad/s).
        gyro_rad: [f32; 3],
        /// Gyro sampling period (µs).
        gyro_integral_dt: u32,
        /// Accelerometer time − timestamp (µs).
        accelerometer_timestamp_relative: i32,
        /// Specific force along FRD x, y, z (m/s²).
        accelerometer_m_s2: [f32; 3],
        /// Accelerometer sampling period (µs).
        accelerometer_integral_dt: u32,
        /// Accelerometer clipping per axis (bits 1 x, 2 y, 4 z).
        accelerometer_clipping: u8,
        /// Gyro clipping per axis (bits 1 x, 2 y, 4 z).
        gyro_clipping: u8,
        /// Accelerometer calibration counter.
        accel_calibration_count: u8,
        /// Gyro calibration counter.
        gyro_calibration_count: u8,
    }
}

ulog_message! {
    /// `sensor_gps` (SensorGps.msg): a GPS solution in WGS-84. The same
    /// layout is logged as `vehicle_gps_position` ([`VehicleGpsPosition`]).
    pub struct SensorGps: "sensor_gps" {
        /// Time since system start (µs).
        timestamp: u64,
        /// Time of validity of the solution (µs).
        timestamp_sample: u64,
        /// Latitude (deg).
        latitude_deg: f64,
        /// Longitude (deg).
        longitude_deg: f64,
        /// Altitude above MSL (m).
        altitude_msl_m: f64,
        /// Altitude above the ellipsoid (m).
        altitude_ellipsoid_m: f64,
        /// UTC time of the solution (µs; 0 unknown).
        time_utc_usec: u64,
        /// Device id.
        device_id: u32,
        /// Speed accuracy (m/s).
        s_variance_m_s: f32,
        /// Course accuracy (rad).
        c_variance_rad: f32,
        /// Horizontal position accuracy (m).
        eph: f32,
        /// Vertical position accuracy (m).
        epv: f32,
        /// Horizontal dilution of precision.
        hdop: f32,
        /// Vertical dilution of precision.
        vdop: f32,
        /// Noise per millisecond.
        noise_per_ms: i32,
        /// Jamming indicator.
        jamming_indicator: i32,
        /// Ground speed (m/s).
        vel_m_s: f32,
        /// North velocity (m/s).
        vel_n_m_s: f32,
        /// East velocity (m/s).
        vel_e_m_s: f32,
        /// Down velocity (m/s).
        vel_d_m_s: f32,
        /// Course over ground (rad, −π..π).
        cog_rad: f32,
        /// UTC time − timestamp (µs).
        timestamp_time_relative: i32,
        /// Receiver error flags.
        system_error: u32,
        /// Dual-antenna heading (rad; NaN not available).
        heading: f32,
        /// Dual-antenna heading offset (rad; NaN not applicable).
        heading_offset: f32,
        /// Heading accuracy (rad).
        heading_accuracy: f32,
        /// RTCM injection rate (Hz).
        rtcm_injection_rate: f32,
        /// Automatic gain control monitor.
        automatic_gain_control: u16,
        /// Fix type: 0/1 none, 2 2-D, 3 3-D.
        fix_type: u8,
        /// Jamming state (0 unknown).
        jamming_state: u8,
        /// Spoofing state (0 unknown).
        spoofing_state: u8,
        /// Authentication state (0 unknown).
        authentication_state: u8,
        /// The NED velocity is valid.
        vel_ned_valid: bool,
        /// Satellites used.
        satellites_used: u8,
        /// RTCM instance used.
        selected_rtcm_instance: u8,
        /// An RTCM CRC failed.
        rtcm_crc_failed: bool,
        /// RTCM message used (0 unknown).
        rtcm_msg_used: u8,
        /// Corrections quality (0 not available).
        quality_corrections: u8,
        /// Receiver quality (0 not available).
        quality_receiver: u8,
        /// GNSS signal quality (0 not available).
        quality_gnss_signals: u8,
        /// Post-processing quality (0 not available).
        quality_post_processing: u8,
    }
}

/// `vehicle_gps_position`: PX4's selected GPS, the [`SensorGps`] layout
/// under its second topic name (`# TOPICS sensor_gps vehicle_gps_position`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VehicleGpsPosition(pub SensorGps);

impl Record for VehicleGpsPosition {
    const NAME: &'static str = "vehicle_gps_position";
    const FIELDS: &'static [crate::format::FieldDef] = SensorGps::FIELDS;
    const SIZE: usize = SensorGps::SIZE;
    fn timestamp_us(&self) -> u64 {
        self.0.timestamp
    }
    fn encode(&self, out: &mut [u8]) -> Option<usize> {
        self.0.encode(out)
    }
    fn decode(bytes: &[u8]) -> Option<Self> {
        SensorGps::decode(bytes).map(VehicleGpsPosition)
    }
}

ulog_message! {
    /// `vehicle_magnetometer` (VehicleMagnetometer.msg).
    pub struct VehicleMagnetometer: "vehicle_magnetometer" {
        /// Time since system start (µs).
        timestamp: u64,
        /// Time of the raw data (µs).
        timestamp_sample: u64,
        /// Device id.
        device_id: u32,
        /// Field along FRD x, y, z (PX4: Gauss; helicon: the unit of the
        /// configured local field).
        magnetometer_ga: [f32; 3],
        /// Calibration counter.
        calibration_count: u8,
    }
}

ulog_message! {
    /// `actuator_outputs` (ActuatorOutputs.msg): the servo commands.
    pub struct ActuatorOutputs: "actuator_outputs" {
        /// Time since system start (µs).
        timestamp: u64,
        /// Valid outputs.
        noutputs: u32,
        /// Outputs in natural units (helicon: S_col S_lat S_lon S_tr).
        output: [f32; 16],
    }
}

ulog_message! {
    /// `input_rc` (InputRc.msg): the receiver's frame.
    pub struct InputRc: "input_rc" {
        /// Time since system start (µs).
        timestamp: u64,
        /// Last valid reception (µs).
        timestamp_last_signal: u64,
        /// RSSI (< 0 undefined, 0..100).
        rssi: i32,
        /// RSSI (dBm; NaN invalid).
        rssi_dbm: f32,
        /// Lost frames.
        rc_lost_frame_count: u16,
        /// Total frames.
        rc_total_frame_count: u16,
        /// PPM frame length (0 not PPM).
        rc_ppm_frame_length: u16,
        /// Frame rate (Hz; 0 invalid).
        rc_frame_rate: u16,
        /// Pulse widths (µs).
        values: [u16; 18],
        /// Channels seen.
        channel_count: u8,
        /// The receiver's failsafe flag.
        rc_failsafe: bool,
        /// No frame in the expected time.
        rc_lost: bool,
        /// Input source (0 unknown).
        input_source: u8,
        /// Link quality (% ; −1 invalid).
        link_quality: i8,
        /// Link SNR (dB; −1 invalid).
        link_snr: i8,
    }
}

ulog_message! {
    /// `vehicle_status` (VehicleStatus.msg): arming, mode, failsafe.
    pub struct VehicleStatus: "vehicle_status" {
        /// Time since system start (µs).
        timestamp: u64,
        /// Arming time (µs).
        armed_time: u64,
        /// Takeoff time (µs).
        takeoff_time: u64,
        /// Time the current nav_state began (µs).
        nav_state_timestamp: u64,
        /// Valid nav_state values (bit mask).
        valid_nav_states_mask: u32,
        /// Modes a user can select (bit mask).
        can_set_nav_states_mask: u32,
        /// Detected failures (bit mask).
        failure_detector_status: u16,
        /// 1 disarmed, 2 armed.
        arming_state: u8,
        /// Latest arming reason.
        latest_arming_reason: u8,
        /// Latest disarming reason.
        latest_disarming_reason: u8,
        /// The mode the user selected.
        nav_state_user_intention: u8,
        /// The active mode (`NAVIGATION_STATE_*`).
        nav_state: u8,
        /// Mode executor in charge (0 autopilot).
        executor_in_charge: u8,
        /// Hardware in the loop (0 off).
        hil_state: u8,
        /// 1 rotary wing.
        vehicle_type: u8,
        /// In a failsafe.
        failsafe: bool,
        /// In a failsafe the user took over.
        failsafe_and_user_took_over: bool,
        /// Failsafe defer state.
        failsafe_defer_state: u8,
        /// Ground-station link lost.
        gcs_connection_lost: bool,
        /// Ground-station link losses.
        gcs_connection_lost_counter: u8,
        /// High-latency link lost.
        high_latency_data_link_lost: bool,
        /// VTOL capable.
        is_vtol: bool,
        /// VTOL tailsitter.
        is_vtol_tailsitter: bool,
        /// In a VTOL transition.
        in_transition_mode: bool,
        /// In a transition to fixed wing.
        in_transition_to_fw: bool,
        /// MAVLink MAV_TYPE.
        system_type: u8,
        /// MAVLink system id.
        system_id: u8,
        /// MAVLink component id.
        component_id: u8,
        /// A safety button is connected.
        safety_button_available: bool,
        /// Safety is off.
        safety_off: bool,
        /// Input power valid.
        power_input_valid: bool,
        /// USB connected.
        usb_connected: bool,
        /// Open Drone ID present.
        open_drone_id_system_present: bool,
        /// Open Drone ID healthy.
        open_drone_id_system_healthy: bool,
        /// Parachute present.
        parachute_system_present: bool,
        /// Parachute healthy.
        parachute_system_healthy: bool,
        /// RC calibration in progress.
        rc_calibration_in_progress: bool,
        /// Calibration enabled.
        calibration_enabled: bool,
        /// All pre-flight checks pass.
        pre_flight_checks_pass: bool,
    }
}

ulog_message! {
    /// `vehicle_land_detected` (VehicleLandDetected.msg): written by
    /// [`crate::FlightLog::write`] for [`crate::LogRecord::LandDetected`],
    /// which a land detector fills; helicon logs none of its own.
    pub struct VehicleLandDetected: "vehicle_land_detected" {
        /// Time since system start (µs).
        timestamp: u64,
        /// In free fall.
        freefall: bool,
        /// Ground contact, not landed (stage 1).
        ground_contact: bool,
        /// Maybe landed (stage 2).
        maybe_landed: bool,
        /// Landed (stage 3).
        landed: bool,
        /// Maybe in ground effect.
        in_ground_effect: bool,
        /// Descending.
        in_descend: bool,
        /// Low throttle.
        has_low_throttle: bool,
        /// Moving vertically.
        vertical_movement: bool,
        /// Moving horizontally.
        horizontal_movement: bool,
        /// Rotating.
        rotational_movement: bool,
        /// Close to the ground or the check skipped.
        close_to_ground_or_skipped_check: bool,
        /// At rest.
        at_rest: bool,
    }
}

ulog_message! {
    /// `cpuload` (Cpuload.msg as Flight Review reads it: `load`,
    /// `ram_usage`).
    pub struct Cpuload: "cpuload" {
        /// Time since system start (µs).
        timestamp: u64,
        /// Processor load (0..1): helicon's control task's compute time over
        /// the window.
        load: f32,
        /// RAM usage (0..1; NaN: not measured).
        ram_usage: f32,
    }
}

/// `vehicle_status.arming_state`: disarmed.
pub const ARMING_STATE_DISARMED: u8 = 1;
/// `vehicle_status.arming_state`: armed.
pub const ARMING_STATE_ARMED: u8 = 2;
/// `vehicle_status.nav_state`: manual.
pub const NAV_STATE_MANUAL: u8 = 0;
/// `vehicle_status.nav_state`: auto mission.
pub const NAV_STATE_AUTO_MISSION: u8 = 3;
/// `vehicle_status.nav_state`: auto loiter (hold).
pub const NAV_STATE_AUTO_LOITER: u8 = 4;
/// `vehicle_status.nav_state`: return to launch.
pub const NAV_STATE_AUTO_RTL: u8 = 5;
/// `vehicle_status.nav_state`: descend (no position control).
pub const NAV_STATE_DESCEND: u8 = 12;
/// `vehicle_status.nav_state`: termination.
pub const NAV_STATE_TERMINATION: u8 = 13;
/// `vehicle_status.nav_state`: offboard (a ground station's targets).
pub const NAV_STATE_OFFBOARD: u8 = 14;
/// `vehicle_status.nav_state`: auto takeoff.
pub const NAV_STATE_AUTO_TAKEOFF: u8 = 17;
/// `vehicle_status.nav_state`: auto land.
pub const NAV_STATE_AUTO_LAND: u8 = 18;
/// `vehicle_status.vehicle_type`: rotary wing.
pub const VEHICLE_TYPE_ROTARY_WING: u8 = 1;
/// MAVLink `MAV_TYPE_HELICOPTER`.
pub const MAV_TYPE_HELICOPTER: u8 = 4;

/// The decimation of each PX4 topic: the least time between two records
/// (µs; 0 every record), PX4's logger's default intervals (helicon's own
/// topics keep the full rate).
pub const INTERVALS_US: [(&str, u64); 14] = [
    (VehicleAttitude::NAME, 20_000),
    (VehicleAngularVelocity::NAME, 20_000),
    (VehicleLocalPosition::NAME, 100_000),
    (VehicleLocalPositionSetpoint::NAME, 100_000),
    (VehicleGlobalPosition::NAME, 200_000),
    (SensorCombined::NAME, 10_000),
    (SensorGps::NAME, 0),
    (VehicleGpsPosition::NAME, 0),
    (VehicleMagnetometer::NAME, 100_000),
    (ActuatorOutputs::NAME, 20_000),
    (InputRc::NAME, 100_000),
    (VehicleStatus::NAME, 1_000_000),
    (VehicleLandDetected::NAME, 0),
    (Cpuload::NAME, 500_000),
];

const fn interval_us(i: usize) -> u64 {
    INTERVALS_US[i].1
}

/// Indexes into [`INTERVALS_US`] and the view's last-write times.
const ATT: usize = 0;
const RATES: usize = 1;
const LPOS: usize = 2;
const LPOS_SP: usize = 3;
const GPOS: usize = 4;
const IMU: usize = 5;
const MAG: usize = 8;
const OUT: usize = 9;
const RC: usize = 10;
const STATUS: usize = 11;
const LOAD: usize = 13;

/// The PX4 records of one helicon record (at most three).
#[derive(Debug, Clone, Copy, PartialEq)]
#[allow(clippy::large_enum_variant)] // on the stack of the logger, never stored
pub enum Px4Record {
    /// `vehicle_attitude`
    Attitude(VehicleAttitude),
    /// `vehicle_angular_velocity`
    AngularVelocity(VehicleAngularVelocity),
    /// `vehicle_local_position`
    LocalPosition(VehicleLocalPosition),
    /// `vehicle_local_position_setpoint`
    LocalPositionSetpoint(VehicleLocalPositionSetpoint),
    /// `vehicle_global_position`
    GlobalPosition(VehicleGlobalPosition),
    /// `sensor_combined`
    SensorCombined(SensorCombined),
    /// `sensor_gps` and `vehicle_gps_position` (one GPS)
    Gps(SensorGps),
    /// `vehicle_magnetometer`
    Magnetometer(VehicleMagnetometer),
    /// `actuator_outputs`
    ActuatorOutputs(ActuatorOutputs),
    /// `input_rc`
    InputRc(InputRc),
    /// `vehicle_status`
    Status(VehicleStatus),
    /// `cpuload`
    Cpuload(Cpuload),
}

/// What PX4's `vehicle_status` says of a helicon flight mode: arming,
/// `nav_state`, failsafe.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StatusMode {
    /// [`ARMING_STATE_ARMED`] or [`ARMING_STATE_DISARMED`].
    pub arming_state: u8,
    /// `NAVIGATION_STATE_*` (`NAV_STATE_*` here).
    pub nav_state: u8,
    /// A failsafe acts.
    pub failsafe: bool,
}

/// The state that turns helicon's records into PX4's topics: the home
/// position (for the geodetic topics), the decimation clocks, the previous
/// rates and IMU time (derivatives and sampling periods), the CPU load's
/// window and the vehicle status. No allocation.
#[derive(Debug, Clone)]
pub struct Px4View {
    home: Option<LocalNed>,
    start_utc_us: Option<u64>,
    next_us: [Option<u64>; INTERVALS_US.len()],
    prev_rates: Option<(u64, [f64; 3])>,
    prev_imu_us: Option<u64>,
    load_window: Option<(u64, u64)>,
    status: VehicleStatus,
    status_started: bool,
    navigator: Option<u8>,
}

fn f(v: f64) -> f32 {
    v as f32
}

fn f3(v: [f64; 3]) -> [f32; 3] {
    [f(v[0]), f(v[1]), f(v[2])]
}

const NAN3: [f32; 3] = [f32::NAN; 3];

impl Px4View {
    /// A view for a flight whose local NED frame is at `home` (`None`: the
    /// geodetic topics are not written), and whose on-board clock's zero
    /// was `start_utc_us` UTC (µs since 1970; `None`: unknown, the GPS's
    /// `time_utc_usec` is 0).
    pub fn new(home: Option<Geodetic>, start_utc_us: Option<u64>) -> Self {
        Px4View {
            home: home.map(LocalNed::new),
            start_utc_us,
            next_us: [None; INTERVALS_US.len()],
            prev_rates: None,
            prev_imu_us: None,
            load_window: None,
            status: VehicleStatus {
                arming_state: ARMING_STATE_DISARMED,
                nav_state: NAV_STATE_AUTO_MISSION,
                nav_state_user_intention: NAV_STATE_AUTO_MISSION,
                vehicle_type: VEHICLE_TYPE_ROTARY_WING,
                system_type: MAV_TYPE_HELICOPTER,
                system_id: 1,
                component_id: 1,
                valid_nav_states_mask: (1 << NAV_STATE_MANUAL)
                    | (1 << NAV_STATE_AUTO_MISSION)
                    | (1 << NAV_STATE_AUTO_LOITER)
                    | (1 << NAV_STATE_AUTO_RTL)
                    | (1 << NAV_STATE_DESCEND)
                    | (1 << NAV_STATE_TERMINATION)
                    | (1 << NAV_STATE_OFFBOARD)
                    | (1 << NAV_STATE_AUTO_TAKEOFF)
                    | (1 << NAV_STATE_AUTO_LAND),
                power_input_valid: true,
                pre_flight_checks_pass: true,
                ..VehicleStatus::default()
            },
            status_started: false,
            navigator: None,
        }
    }

    /// Whether a topic at index `i` is due at `t_us` (and if so, taken as
    /// written): its records keep to a schedule one interval apart, each
    /// slot taken by the first record at or after its time less a tenth of
    /// the interval, at most 1 ms (the jitter of the control task's clock),
    /// so that the topic's mean rate is its interval's; after a gap in the
    /// source the schedule starts again.
    fn due(&mut self, i: usize, t_us: u64) -> bool {
        let every = interval_us(i);
        let early = (every / 10).min(1000);
        match self.next_us[i] {
            Some(next) if t_us + early < next => false,
            Some(next) if t_us <= next + every => {
                self.next_us[i] = Some(next + every);
                true
            }
            _ => {
                self.next_us[i] = Some(t_us + every);
                true
            }
        }
    }

    /// The current `vehicle_status`.
    pub fn status(&self) -> &VehicleStatus {
        &self.status
    }

    /// The ground station's navigator changed its mode at `t_us` to
    /// `nav_state` (`NAV_STATE_*`): the `vehicle_status` to write. It is
    /// the active mode while the flight software is armed and not in a
    /// failsafe; the intention always.
    pub fn set_navigator(&mut self, t_us: u64, nav_state: u8) -> VehicleStatus {
        self.navigator = Some(nav_state);
        let s = &mut self.status;
        s.nav_state_user_intention = nav_state;
        if !s.failsafe && s.arming_state == ARMING_STATE_ARMED && s.nav_state != nav_state {
            s.nav_state = nav_state;
            s.nav_state_timestamp = t_us;
        }
        s.timestamp = t_us;
        self.next_us[STATUS] = Some(t_us + interval_us(STATUS));
        self.status_started = true;
        self.status
    }

    /// The mode changed at `t_us`: the `vehicle_status` to write. Under a
    /// ground station the automatic mode is its navigator's.
    pub fn set_mode(&mut self, t_us: u64, mut mode: StatusMode) -> VehicleStatus {
        if let Some(nav) = self.navigator
            && !mode.failsafe
            && mode.nav_state == NAV_STATE_AUTO_MISSION
        {
            mode.nav_state = nav;
        }
        let s = &mut self.status;
        if mode.arming_state == ARMING_STATE_ARMED && s.arming_state != ARMING_STATE_ARMED {
            s.armed_time = t_us;
        }
        if mode.nav_state != s.nav_state {
            s.nav_state_timestamp = t_us;
        }
        s.arming_state = mode.arming_state;
        s.nav_state = mode.nav_state;
        if !mode.failsafe {
            s.nav_state_user_intention = mode.nav_state;
        }
        s.failsafe = mode.failsafe;
        s.timestamp = t_us;
        self.next_us[STATUS] = Some(t_us + interval_us(STATUS));
        self.status_started = true;
        self.status
    }

    /// The PX4 records of `control`: attitude, rates, the velocity and
    /// heading setpoint, and the vehicle status (first and each second).
    pub fn from_control(&mut self, c: &Control, out: &mut impl FnMut(Px4Record)) {
        let t = c.timestamp;
        let [phi, theta, psi, .., p, q, r] = c.estimate;
        if !self.status_started {
            self.status_started = true;
            self.next_us[STATUS] = Some(t + interval_us(STATUS));
            self.status.timestamp = t;
            out(Px4Record::Status(self.status));
        } else if self.due(STATUS, t) {
            self.status.timestamp = t;
            out(Px4Record::Status(self.status));
        }
        if self.due(ATT, t) {
            let qn = UnitQuaternion::from_euler_angles(phi, theta, psi);
            out(Px4Record::Attitude(VehicleAttitude {
                timestamp: t,
                timestamp_sample: t,
                q: [f(qn.w), f(qn.i), f(qn.j), f(qn.k)],
                delta_q_reset: [0.0; 4],
                quat_reset_counter: 0,
            }));
        }
        let rates = [p, q, r];
        let derivative = match self.prev_rates {
            Some((t0, r0)) if t > t0 => {
                let dt = (t - t0) as f64 * 1e-6;
                [
                    f((p - r0[0]) / dt),
                    f((q - r0[1]) / dt),
                    f((r - r0[2]) / dt),
                ]
            }
            _ => NAN3,
        };
        self.prev_rates = Some((t, rates));
        if self.due(RATES, t) {
            out(Px4Record::AngularVelocity(VehicleAngularVelocity {
                timestamp: t,
                timestamp_sample: t,
                xyz: f3(rates),
                xyz_derivative: derivative,
            }));
        }
        if self.due(LPOS_SP, t) {
            let [vn, ve, vd] = c.ref_vel_ned_m_s;
            out(Px4Record::LocalPositionSetpoint(
                VehicleLocalPositionSetpoint {
                    timestamp: t,
                    x: f32::NAN,
                    y: f32::NAN,
                    z: f32::NAN,
                    yaw: f(c.ref_yaw_rad),
                    yawspeed: f32::NAN,
                    vx: f(vn),
                    vy: f(ve),
                    vz: f(vd),
                    acceleration: NAN3,
                    jerk: NAN3,
                    thrust: NAN3,
                },
            ));
        }
    }

    /// The PX4 records of a navigation solution: the local position and,
    /// with a home, the global position.
    pub fn from_navigation(&mut self, n: &Navigation, out: &mut impl FnMut(Px4Record)) {
        let t = n.timestamp;
        let [x, y, z] = n.position_ned_m;
        let [vx, vy, vz] = n.velocity_ned_m_s;
        let [sn, se, sd] = n.position_sigma_m;
        let finite = |a: &[f64; 3]| a.iter().all(|v| v.is_finite());
        let home = self.home.as_ref().map(LocalNed::home);
        if self.due(LPOS, t) {
            let pos_ok = finite(&n.position_ned_m);
            let vel_ok = finite(&n.velocity_ned_m_s);
            out(Px4Record::LocalPosition(VehicleLocalPosition {
                timestamp: t,
                timestamp_sample: t,
                ref_timestamp: 0,
                ref_lat: home.map_or(f64::NAN, |h| h.latitude_deg),
                ref_lon: home.map_or(f64::NAN, |h| h.longitude_deg),
                x: f(x),
                y: f(y),
                z: f(z),
                vx: f(vx),
                vy: f(vy),
                vz: f(vz),
                z_deriv: f(vz),
                ax: f32::NAN,
                ay: f32::NAN,
                az: f32::NAN,
                heading: f(n.attitude_rad[2]),
                heading_var: f32::NAN,
                unaided_heading: f32::NAN,
                tilt_var: f32::NAN,
                ref_alt: home.map_or(f32::NAN, |h| f(h.height_m)),
                dist_bottom: f32::NAN,
                dist_bottom_var: f32::NAN,
                eph: f(sn.hypot(se)),
                epv: f(sd),
                evh: f32::NAN,
                evv: f32::NAN,
                vxy_max: f32::INFINITY,
                vz_max: f32::INFINITY,
                hagl_min: f32::INFINITY,
                hagl_max_z: f32::INFINITY,
                hagl_max_xy: f32::INFINITY,
                xy_valid: pos_ok,
                z_valid: pos_ok,
                v_xy_valid: vel_ok,
                v_z_valid: vel_ok,
                heading_good_for_control: n.attitude_rad[2].is_finite(),
                xy_global: home.is_some(),
                z_global: home.is_some(),
                ..VehicleLocalPosition::default()
            }));
        }
        let due = self.home.is_some() && self.due(GPOS, t);
        if let (true, Some(ned)) = (due, &self.home) {
            let g = ned.to_geodetic(&Vector3::new(x, y, z));
            out(Px4Record::GlobalPosition(VehicleGlobalPosition {
                timestamp: t,
                timestamp_sample: t,
                lat: g.latitude_deg,
                lon: g.longitude_deg,
                alt: f(g.height_m),
                alt_ellipsoid: f(g.height_m),
                eph: f(sn.hypot(se)),
                epv: f(sd),
                terrain_alt: f32::NAN,
                lat_lon_valid: g.latitude_deg.is_finite() && g.longitude_deg.is_finite(),
                alt_valid: g.height_m.is_finite(),
                ..VehicleGlobalPosition::default()
            }));
        }
    }

    /// The PX4 record of an IMU sample: `sensor_combined`.
    pub fn from_imu(&mut self, s: &SensorImu, out: &mut impl FnMut(Px4Record)) {
        let t = s.timestamp;
        let dt = self
            .prev_imu_us
            .filter(|p| t > *p)
            .map_or(0, |p| u32::try_from(t - p).unwrap_or(u32::MAX));
        self.prev_imu_us = Some(t);
        if self.due(IMU, t) {
            out(Px4Record::SensorCombined(SensorCombined {
                timestamp: t,
                gyro_rad: f3(s.gyro_body_rad_s),
                gyro_integral_dt: dt,
                accelerometer_timestamp_relative: 0,
                accelerometer_m_s2: f3(s.specific_force_body_m_s2),
                accelerometer_integral_dt: dt,
                ..SensorCombined::default()
            }));
        }
    }

    /// The PX4 record of a magnetometer sample: `vehicle_magnetometer`.
    pub fn from_mag(&mut self, m: &HeliconMag, out: &mut impl FnMut(Px4Record)) {
        if self.due(MAG, m.timestamp) {
            out(Px4Record::Magnetometer(VehicleMagnetometer {
                timestamp: m.timestamp,
                timestamp_sample: m.timestamp,
                device_id: 0,
                magnetometer_ga: f3(m.field_body),
                calibration_count: 0,
            }));
        }
    }

    /// The PX4 record of a GPS solution (`sensor_gps`, also written as
    /// `vehicle_gps_position`); none without a home (the solution is NED).
    pub fn from_gps(&mut self, g: &HeliconGps, out: &mut impl FnMut(Px4Record)) {
        let Some(ned) = &self.home else { return };
        let [n, e, d] = g.position_ned_m;
        let geo = ned.to_geodetic(&Vector3::new(n, e, d));
        let [vn, ve, vd] = g.velocity_ned_m_s;
        let v = |x: f64| if g.velocity_valid { f(x) } else { f32::NAN };
        let sample_us = crate::writer::timestamp_us(g.epoch_s, "sensor_gps").unwrap_or(g.timestamp);
        let (time_utc_usec, relative) = match self.start_utc_us {
            Some(u) => (
                u.saturating_add(sample_us),
                i32::try_from(i128::from(sample_us) - i128::from(g.timestamp)).unwrap_or(0),
            ),
            None => (0, 0),
        };
        out(Px4Record::Gps(SensorGps {
            timestamp: g.timestamp,
            timestamp_sample: sample_us,
            latitude_deg: geo.latitude_deg,
            longitude_deg: geo.longitude_deg,
            altitude_msl_m: geo.height_m,
            altitude_ellipsoid_m: geo.height_m,
            time_utc_usec,
            s_variance_m_s: f32::NAN,
            c_variance_rad: f32::NAN,
            eph: f32::NAN,
            epv: f32::NAN,
            hdop: f32::NAN,
            vdop: f32::NAN,
            vel_m_s: v(vn.hypot(ve)),
            vel_n_m_s: v(vn),
            vel_e_m_s: v(ve),
            vel_d_m_s: v(vd),
            cog_rad: v(ve.atan2(vn)),
            timestamp_time_relative: relative,
            heading: f32::NAN,
            heading_offset: f32::NAN,
            heading_accuracy: f32::NAN,
            rtcm_injection_rate: f32::NAN,
            fix_type: g.fix_type,
            vel_ned_valid: g.velocity_valid,
            ..SensorGps::default()
        }));
    }

    /// The PX4 record of a servo command: `actuator_outputs`.
    pub fn from_servo(&mut self, s: &ServoOutput, out: &mut impl FnMut(Px4Record)) {
        if self.due(OUT, s.timestamp) {
            let mut output = [0.0; 16];
            for (o, c) in output.iter_mut().zip(s.command) {
                *o = f(c);
            }
            out(Px4Record::ActuatorOutputs(ActuatorOutputs {
                timestamp: s.timestamp,
                noutputs: 4,
                output,
            }));
        }
    }

    /// The PX4 record of a receiver frame: `input_rc`.
    pub fn from_rc(&mut self, r: &RcInput, out: &mut impl FnMut(Px4Record)) {
        if self.due(RC, r.timestamp) {
            let mut values = [0u16; 18];
            values[..16].copy_from_slice(&r.channels_us);
            out(Px4Record::InputRc(InputRc {
                timestamp: r.timestamp,
                timestamp_last_signal: r.timestamp,
                rssi: -1,
                rssi_dbm: f32::NAN,
                values,
                channel_count: r.channel_count,
                rc_failsafe: r.signal_lost,
                rc_lost: false,
                link_quality: -1,
                link_snr: -1,
                ..InputRc::default()
            }));
        }
    }

    /// The PX4 record of the timing of a control step: `cpuload` every
    /// half second, the control task's compute time over the window.
    pub fn from_timing(&mut self, t: &Timing, out: &mut impl FnMut(Px4Record)) {
        // the window opens at a step and holds the compute times of the
        // steps after it (each step's time belongs to the period it ends)
        let (start, busy) = match self.load_window {
            Some((start, busy)) if t.timestamp >= start => {
                (start, busy + u64::from(t.compute_time_us))
            }
            _ => (t.timestamp, 0),
        };
        self.load_window = Some((start, busy));
        let elapsed = t.timestamp - start;
        if elapsed >= interval_us(LOAD) {
            let load = (busy as f64 / elapsed as f64) as f32;
            self.load_window = Some((t.timestamp, 0));
            out(Px4Record::Cpuload(Cpuload {
                timestamp: t.timestamp,
                load,
                ram_usage: f32::NAN,
            }));
        }
    }
}

/// The message bytes per second the PX4 view adds to a flight of
/// `control_hz` control steps, with a magnetometer at `mag_hz`, GPS at
/// `gps_hz`, and a receiver at `rc_hz` (0 without one), and a home (the
/// geodetic topics): each topic at the lesser of its source's rate and its
/// decimation, plus the 3-byte header and 2-byte id of each message.
pub fn bytes_per_s(control_hz: f64, mag_hz: f64, gps_hz: f64, rc_hz: f64) -> f64 {
    let rate = |i: usize, source_hz: f64| {
        let every = interval_us(i);
        if every == 0 {
            source_hz
        } else {
            source_hz.min(1e6 / every as f64)
        }
    };
    let msg = |size: usize| (size + 5) as f64;
    msg(VehicleAttitude::SIZE) * rate(ATT, control_hz)
        + msg(VehicleAngularVelocity::SIZE) * rate(RATES, control_hz)
        + msg(VehicleLocalPosition::SIZE) * rate(LPOS, control_hz)
        + msg(VehicleLocalPositionSetpoint::SIZE) * rate(LPOS_SP, control_hz)
        + msg(VehicleGlobalPosition::SIZE) * rate(GPOS, control_hz)
        + msg(SensorCombined::SIZE) * rate(IMU, control_hz)
        + 2.0 * msg(SensorGps::SIZE) * gps_hz
        + msg(VehicleMagnetometer::SIZE) * rate(MAG, mag_hz)
        + msg(ActuatorOutputs::SIZE) * rate(OUT, control_hz)
        + msg(InputRc::SIZE) * rate(RC, rc_hz)
        + msg(VehicleStatus::SIZE) * rate(STATUS, control_hz)
        + msg(Cpuload::SIZE) * rate(LOAD, control_hz)
}
