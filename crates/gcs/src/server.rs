//! The ground-station server: MAVLink 2 (common dialect) over UDP on its own
//! thread. It reads the vehicle's status and events from the downlink ring
//! and writes commands to the uplink ring; the control task never waits for
//! it.
//!
//! Streams are scheduled in on-board time (the status's `t_s`), so a
//! lock-step SITL flight that runs faster than the wall clock still sends
//! every stream at its rate per simulated second, and the rates are exact
//! multiples of the status period.

// ground stations still send the superseded REQUEST_DATA_STREAM, SET_MODE
// and the *_INT mission frames: they are understood
#![allow(deprecated)]

use crate::geo::{MissionError, plan_of};
use crate::link::{Downlink, ServerEnd, Uplink, VehicleEvent, VehicleStatus};
use crate::navigator::{GuidedTarget, NavEvent, NavMode, NavigatorConfig};
use crate::params::{PARAMS, ParamError, ParamTable};
use helicon_devices::{Geodetic, LocalNed};
use mavlink::dialects::common::*;
use mavlink::{
    ConnectionAddress, MAVLinkMessageRaw, MavConnection, MavHeader, MavlinkVersion, Message,
    MessageData, SigningConfig, SigningData,
};
use nalgebra::Vector3;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

/// The default address: where ground stations listen.
pub const DEFAULT_ADDRESS: &str = "udpout:127.0.0.1:14550";

/// The messages the server streams, with their default rates (Hz; 0: off
/// until asked for).
pub const STREAMS: [(u32, &str, f64); 9] = [
    (HEARTBEAT_DATA::ID, "HEARTBEAT", 1.0),
    (SYS_STATUS_DATA::ID, "SYS_STATUS", 1.0),
    (ATTITUDE_DATA::ID, "ATTITUDE", 10.0),
    (GLOBAL_POSITION_INT_DATA::ID, "GLOBAL_POSITION_INT", 5.0),
    (LOCAL_POSITION_NED_DATA::ID, "LOCAL_POSITION_NED", 5.0),
    (GPS_RAW_INT_DATA::ID, "GPS_RAW_INT", 1.0),
    (VFR_HUD_DATA::ID, "VFR_HUD", 4.0),
    (SERVO_OUTPUT_RAW_DATA::ID, "SERVO_OUTPUT_RAW", 2.0),
    (RC_CHANNELS_DATA::ID, "RC_CHANNELS", 0.0),
];

/// The server's settings.
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// `udpout:HOST:PORT` (send to a ground station) or `udpin:HOST:PORT`
    /// (listen; answer whoever spoke last).
    pub address: String,
    /// The vehicle's MAVLink system id.
    pub system_id: u8,
    /// The origin of the local NED frame (the GPS receiver's home).
    pub home: Geodetic,
    /// The navigator's tuning at start (the parameter table's values).
    pub navigator: NavigatorConfig,
    /// MAVLink 2 signing key: when set, commands (COMMAND_LONG/INT, SET_MODE,
    /// PARAM_SET, mission upload, guided targets) must be signed with it.
    pub signing_key: Option<[u8; 32]>,
    /// Start-up rate of each of [`STREAMS`] (Hz, 0: off, at most 100);
    /// the ground station changes them.
    pub rates_hz: [f64; STREAMS.len()],
}

/// The default rates of [`STREAMS`].
pub fn default_rates_hz() -> [f64; STREAMS.len()] {
    STREAMS.map(|(_, _, r)| r)
}

/// Errors starting the server.
#[derive(Debug, thiserror::Error)]
pub enum GcsError {
    /// The address is not `udpin:`/`udpout:` HOST:PORT, or cannot be bound.
    #[error("ground-station address `{address}`: {message}")]
    Address {
        /// The address given.
        address: String,
        /// What failed.
        message: String,
    },
    /// The thread could not be started.
    #[error("ground-station thread: {0}")]
    Thread(String),
}

/// What the server counted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ServerReport {
    /// Messages sent.
    pub sent: u64,
    /// Messages received (parsed).
    pub received: u64,
    /// Commands refused for a missing or wrong signature.
    pub refused_unsigned: u64,
    /// Send errors (the ground station not listening is one per message).
    pub send_errors: u64,
}

/// The running server.
pub struct ServerHandle {
    stop: Arc<AtomicBool>,
    processed: Arc<AtomicU64>,
    thread: JoinHandle<ServerReport>,
}

impl ServerHandle {
    /// Statuses and events the server has handled (sent on) so far.
    pub fn processed(&self) -> u64 {
        self.processed.load(Ordering::Acquire)
    }

    /// Stop the server and wait for its thread.
    pub fn stop(self) -> ServerReport {
        self.stop.store(true, Ordering::SeqCst);
        self.thread.join().unwrap_or_default()
    }
}

/// Parse and check an address (only UDP is offered).
pub fn parse_address(address: &str) -> Result<ConnectionAddress, GcsError> {
    let bad = |message: String| GcsError::Address {
        address: address.to_string(),
        message,
    };
    if !(address.starts_with("udpin:") || address.starts_with("udpout:")) {
        return Err(bad("expected udpin:HOST:PORT or udpout:HOST:PORT".into()));
    }
    ConnectionAddress::parse_address(address).map_err(|e| bad(e.to_string()))
}

/// Start the server on its own thread.
pub fn spawn(config: ServerConfig, end: ServerEnd) -> Result<ServerHandle, GcsError> {
    let addr = parse_address(&config.address)?;
    let ConnectionAddress::Udp(udp) = addr else {
        return Err(GcsError::Address {
            address: config.address.clone(),
            message: "only UDP is offered".into(),
        });
    };
    let conn =
        mavlink::Connectable::connect::<MavMessage>(&udp.read_timeout(Duration::from_millis(2)))
            .map_err(|e| GcsError::Address {
                address: config.address.clone(),
                message: e.to_string(),
            })?;
    let stop = Arc::new(AtomicBool::new(false));
    let stop2 = stop.clone();
    let processed = Arc::new(AtomicU64::new(0));
    let processed2 = processed.clone();
    let thread = std::thread::Builder::new()
        .name("gcs".into())
        .spawn(move || {
            let mut s = Server::new(config, end, conn);
            while !stop2.load(Ordering::Relaxed) {
                let n = s.poll();
                processed2.fetch_add(n, Ordering::Release);
            }
            s.report
        })
        .map_err(|e| GcsError::Thread(e.to_string()))?;
    Ok(ServerHandle {
        stop,
        processed,
        thread,
    })
}

enum Upload {
    Idle,
    Receiving {
        count: u16,
        items: Vec<MISSION_ITEM_INT_DATA>,
    },
}

struct Server {
    config: ServerConfig,
    end: ServerEnd,
    conn: mavlink::Connection<MavMessage>,
    home: LocalNed,
    params: ParamTable,
    signing: Option<SigningData>,
    intervals_s: [Option<f64>; STREAMS.len()],
    next_due_s: [f64; STREAMS.len()],
    status: Option<VehicleStatus>,
    mission: Vec<MISSION_ITEM_INT_DATA>,
    upload: Upload,
    last_flight_mode: &'static str,
    /// An arm/disarm sent on and not yet seen in a status: the commands
    /// that follow it in the ring find the vehicle in that state.
    arm_requested: Option<bool>,
    report: ServerReport,
}

fn interval_of(rate_hz: f64) -> Option<f64> {
    (rate_hz.is_finite() && rate_hz > 0.0).then(|| 1.0 / rate_hz)
}

impl Server {
    fn new(config: ServerConfig, end: ServerEnd, conn: mavlink::Connection<MavMessage>) -> Self {
        let signing = config
            .signing_key
            .map(|k| SigningData::from_config(SigningConfig::new(k, 0, false, false)));
        Server {
            home: LocalNed::new(config.home),
            params: ParamTable::new(config.navigator),
            signing,
            intervals_s: config.rates_hz.map(|r| interval_of(r.min(100.0))),
            next_due_s: [0.0; STREAMS.len()],
            status: None,
            mission: Vec::new(),
            upload: Upload::Idle,
            last_flight_mode: "",
            arm_requested: None,
            report: ServerReport::default(),
            config,
            end,
            conn,
        }
    }

    fn header(&self) -> MavHeader {
        MavHeader {
            system_id: self.config.system_id,
            component_id: MavComponent::MAV_COMP_ID_AUTOPILOT1 as u8,
            sequence: 0,
        }
    }

    fn send(&mut self, msg: &MavMessage) {
        match self.conn.send(&self.header(), msg) {
            Ok(_) => self.report.sent += 1,
            Err(_) => self.report.send_errors += 1,
        }
    }

    fn text(&mut self, severity: MavSeverity, text: &str) {
        let mut bytes = [0u8; 50];
        let n = text.len().min(50);
        bytes[..n].copy_from_slice(&text.as_bytes()[..n]);
        self.send(&MavMessage::STATUSTEXT(STATUSTEXT_DATA {
            severity,
            text: bytes.into(),
            ..STATUSTEXT_DATA::DEFAULT
        }));
    }

    fn uplink(&mut self, u: Uplink) -> bool {
        self.end.uplink.push(u).is_ok()
    }

    /// One turn: messages in (up to the read timeout), then the vehicle's
    /// statuses and events out.
    /// Returns the statuses and events handled.
    fn poll(&mut self) -> u64 {
        for _ in 0..32 {
            match self.conn.recv_raw() {
                Ok(raw) => self.receive(&raw),
                Err(_) => break,
            }
        }
        let mut n = 0;
        while let Ok(d) = self.end.downlink.pop() {
            match d {
                Downlink::Status(s) => self.on_status(&s),
                Downlink::Event(t, e) => self.on_event(t, e),
            }
            n += 1;
        }
        n
    }

    fn on_status(&mut self, s: &VehicleStatus) {
        self.status = Some(*s);
        if self.arm_requested == Some(s.armed) {
            self.arm_requested = None;
        }
        if s.flight_mode.name != self.last_flight_mode {
            if !self.last_flight_mode.is_empty() {
                let text = format!("flight mode {}", s.flight_mode.name);
                let sev = if s.flight_mode.name == "auto" || s.flight_mode.name == "disarmed" {
                    MavSeverity::MAV_SEVERITY_INFO
                } else {
                    MavSeverity::MAV_SEVERITY_WARNING
                };
                self.text(sev, &text);
            }
            self.last_flight_mode = s.flight_mode.name;
        }
        for i in 0..STREAMS.len() {
            let Some(iv) = self.intervals_s[i] else {
                continue;
            };
            if s.t_s + 1e-9 >= self.next_due_s[i] {
                self.send_stream(STREAMS[i].0, s);
                // stay on the grid; resynchronise after a gap
                self.next_due_s[i] = if s.t_s - self.next_due_s[i] > iv {
                    s.t_s + iv
                } else {
                    self.next_due_s[i] + iv
                };
            }
        }
    }

    fn on_event(&mut self, t_s: f64, e: VehicleEvent) {
        match e {
            VehicleEvent::Armed(a) => {
                self.text(
                    MavSeverity::MAV_SEVERITY_INFO,
                    if a { "armed" } else { "disarmed" },
                );
            }
            VehicleEvent::Warning(text) => {
                self.text(MavSeverity::MAV_SEVERITY_WARNING, text);
            }
            VehicleEvent::FlightMode(name, reason) => {
                self.text(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    &format!("{name}: {reason}"),
                );
            }
            VehicleEvent::Nav(n) => match n {
                NavEvent::Mode(m) => {
                    self.text(
                        MavSeverity::MAV_SEVERITY_INFO,
                        &format!("mode {}", m.as_str()),
                    );
                }
                NavEvent::Current(seq) => {
                    let total = self.mission.len() as u16;
                    self.send(&MavMessage::MISSION_CURRENT(MISSION_CURRENT_DATA {
                        seq,
                        total,
                        mission_state: MissionState::MISSION_STATE_ACTIVE,
                        ..MISSION_CURRENT_DATA::DEFAULT
                    }));
                }
                NavEvent::Reached(seq) => {
                    self.send(&MavMessage::MISSION_ITEM_REACHED(
                        MISSION_ITEM_REACHED_DATA { seq },
                    ));
                }
                NavEvent::Landed => self.text(MavSeverity::MAV_SEVERITY_INFO, "landed"),
                NavEvent::LinkLost => self.text(
                    MavSeverity::MAV_SEVERITY_CRITICAL,
                    &format!("failsafe: ground-station link lost at {t_s:.1} s"),
                ),
                NavEvent::LinkRegained => {
                    self.text(
                        MavSeverity::MAV_SEVERITY_NOTICE,
                        "ground-station link regained",
                    );
                }
            },
        }
    }

    fn heartbeat(&self, s: &VehicleStatus) -> HEARTBEAT_DATA {
        let mut base = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
        if s.armed {
            base |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
        }
        if s.flight_mode.law_flies {
            base |= MavModeFlag::MAV_MODE_FLAG_STABILIZE_ENABLED
                | MavModeFlag::MAV_MODE_FLAG_GUIDED_ENABLED
                | MavModeFlag::MAV_MODE_FLAG_AUTO_ENABLED;
        } else if s.flight_mode.name == "manual" {
            base |= MavModeFlag::MAV_MODE_FLAG_MANUAL_INPUT_ENABLED;
        }
        let system_status = if s.link_lost || !matches!(s.flight_mode.name, "auto" | "disarmed") {
            MavState::MAV_STATE_CRITICAL
        } else if s.armed {
            MavState::MAV_STATE_ACTIVE
        } else {
            MavState::MAV_STATE_STANDBY
        };
        HEARTBEAT_DATA {
            custom_mode: s.nav_mode.code(),
            mavtype: MavType::MAV_TYPE_HELICOPTER,
            autopilot: MavAutopilot::MAV_AUTOPILOT_GENERIC,
            base_mode: base,
            system_status,
            mavlink_version: 3,
        }
    }

    #[allow(clippy::too_many_lines)] // one message per arm
    fn send_stream(&mut self, id: u32, s: &VehicleStatus) {
        let ms = (s.t_s * 1000.0).clamp(0.0, f64::from(u32::MAX)) as u32;
        let geo = self.home.to_geodetic(&s.position_ned_m);
        let lat = (geo.latitude_deg * 1e7) as i32;
        let lon = (geo.longitude_deg * 1e7) as i32;
        let alt_mm = (geo.height_m * 1000.0) as i32;
        let rel_mm = (-s.position_ned_m.z * 1000.0) as i32;
        let v = s.velocity_ned_m_s;
        let cm = |x: f64| (x * 100.0).clamp(-32767.0, 32767.0) as i16;
        let heading_deg = s.attitude_rad.z.to_degrees().rem_euclid(360.0);
        let servo_us =
            |u: f64| (1500.0 + u.to_degrees() * 500.0 / 30.0).clamp(800.0, 2200.0) as u16;
        let msg = match id {
            HEARTBEAT_DATA::ID => MavMessage::HEARTBEAT(self.heartbeat(s)),
            SYS_STATUS_DATA::ID => {
                let present = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_GYRO
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_ACCEL
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_MAG
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_GPS
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
                    | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL;
                let mut health = present;
                if !s.gps_ok {
                    health &= !MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_GPS;
                }
                if !s.navigation_ok {
                    health &= !(MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_GYRO
                        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_ACCEL
                        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_MAG);
                }
                MavMessage::SYS_STATUS(SYS_STATUS_DATA {
                    onboard_control_sensors_present: present,
                    onboard_control_sensors_enabled: present,
                    onboard_control_sensors_health: health,
                    load: (s.load * 1000.0).clamp(0.0, 1000.0) as u16,
                    voltage_battery: u16::MAX,
                    current_battery: -1,
                    battery_remaining: -1,
                    ..SYS_STATUS_DATA::DEFAULT
                })
            }
            ATTITUDE_DATA::ID => MavMessage::ATTITUDE(ATTITUDE_DATA {
                time_boot_ms: ms,
                roll: s.attitude_rad.x as f32,
                pitch: s.attitude_rad.y as f32,
                yaw: s.attitude_rad.z as f32,
                rollspeed: s.rates_rad_s.x as f32,
                pitchspeed: s.rates_rad_s.y as f32,
                yawspeed: s.rates_rad_s.z as f32,
            }),
            GLOBAL_POSITION_INT_DATA::ID => {
                MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
                    time_boot_ms: ms,
                    lat,
                    lon,
                    alt: alt_mm,
                    relative_alt: rel_mm,
                    vx: cm(v.x),
                    vy: cm(v.y),
                    vz: cm(v.z),
                    hdg: (heading_deg * 100.0) as u16,
                })
            }
            LOCAL_POSITION_NED_DATA::ID => {
                MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                    time_boot_ms: ms,
                    x: s.position_ned_m.x as f32,
                    y: s.position_ned_m.y as f32,
                    z: s.position_ned_m.z as f32,
                    vx: v.x as f32,
                    vy: v.y as f32,
                    vz: v.z as f32,
                })
            }
            GPS_RAW_INT_DATA::ID => MavMessage::GPS_RAW_INT(GPS_RAW_INT_DATA {
                time_usec: (s.t_s * 1e6).max(0.0) as u64,
                lat,
                lon,
                alt: alt_mm,
                eph: (s.position_sigma_m.xy().norm() * 100.0).clamp(0.0, 65534.0) as u16,
                epv: (s.position_sigma_m.z * 100.0).clamp(0.0, 65534.0) as u16,
                vel: (v.xy().norm() * 100.0).clamp(0.0, 65534.0) as u16,
                cog: (v.y.atan2(v.x).to_degrees().rem_euclid(360.0) * 100.0) as u16,
                fix_type: if s.gps_ok {
                    GpsFixType::GPS_FIX_TYPE_3D_FIX
                } else {
                    GpsFixType::GPS_FIX_TYPE_NO_FIX
                },
                satellites_visible: u8::MAX,
                ..GPS_RAW_INT_DATA::DEFAULT
            }),
            VFR_HUD_DATA::ID => MavMessage::VFR_HUD(VFR_HUD_DATA {
                airspeed: v.norm() as f32,
                groundspeed: v.xy().norm() as f32,
                alt: geo.height_m as f32,
                climb: (-v.z) as f32,
                heading: heading_deg as i16,
                throttle: 0,
            }),
            SERVO_OUTPUT_RAW_DATA::ID => MavMessage::SERVO_OUTPUT_RAW(SERVO_OUTPUT_RAW_DATA {
                time_usec: ((s.t_s * 1e6) as u64 & u64::from(u32::MAX)) as u32,
                servo1_raw: servo_us(s.servo[0]),
                servo2_raw: servo_us(s.servo[1]),
                servo3_raw: servo_us(s.servo[2]),
                servo4_raw: servo_us(s.servo[3]),
                ..SERVO_OUTPUT_RAW_DATA::DEFAULT
            }),
            RC_CHANNELS_DATA::ID => MavMessage::RC_CHANNELS(RC_CHANNELS_DATA {
                time_boot_ms: ms,
                chan1_raw: servo_us(s.servo[0]),
                chan2_raw: servo_us(s.servo[1]),
                chan3_raw: servo_us(s.servo[2]),
                chan4_raw: servo_us(s.servo[3]),
                chancount: 4,
                rssi: u8::MAX,
                ..RC_CHANNELS_DATA::DEFAULT
            }),
            _ => return,
        };
        self.send(&msg);
    }

    /// Whether a message is a command that needs a signature.
    fn is_command(id: u32) -> bool {
        matches!(
            id,
            COMMAND_LONG_DATA::ID
                | COMMAND_INT_DATA::ID
                | SET_MODE_DATA::ID
                | PARAM_SET_DATA::ID
                | MISSION_COUNT_DATA::ID
                | MISSION_ITEM_INT_DATA::ID
                | MISSION_CLEAR_ALL_DATA::ID
                | SET_POSITION_TARGET_LOCAL_NED_DATA::ID
        )
    }

    fn receive(&mut self, raw: &MAVLinkMessageRaw) {
        let id = raw.message_id();
        let Ok(msg) = MavMessage::parse(raw.version(), id, raw.payload()) else {
            return;
        };
        if raw.system_id() == self.config.system_id {
            return; // our own echo
        }
        self.report.received += 1;
        if Self::is_command(id)
            && let Some(sig) = &self.signing
        {
            let ok = match raw {
                MAVLinkMessageRaw::V2(v2) => sig.verify_signature(v2),
                MAVLinkMessageRaw::V1(_) => false,
            };
            if !ok {
                self.report.refused_unsigned += 1;
                self.refuse_unsigned(&msg);
                return;
            }
        }
        self.dispatch(&msg);
    }

    fn refuse_unsigned(&mut self, msg: &MavMessage) {
        self.text(
            MavSeverity::MAV_SEVERITY_WARNING,
            "refused: command not signed with the vehicle's key",
        );
        let command = match msg {
            MavMessage::COMMAND_LONG(c) => Some(c.command),
            MavMessage::COMMAND_INT(c) => Some(c.command),
            _ => None,
        };
        if let Some(command) = command {
            self.ack(command, MavResult::MAV_RESULT_DENIED);
        }
    }

    fn dispatch(&mut self, msg: &MavMessage) {
        match msg {
            MavMessage::HEARTBEAT(h) if h.mavtype == MavType::MAV_TYPE_GCS => {
                self.uplink(Uplink::GcsHeartbeat);
            }
            MavMessage::COMMAND_LONG(c) => {
                let p = [
                    c.param1, c.param2, c.param3, c.param4, c.param5, c.param6, c.param7,
                ];
                let r = self.command(c.command, p);
                self.ack(c.command, r);
            }
            MavMessage::COMMAND_INT(c) => {
                let p = [c.param1, c.param2, c.param3, c.param4, 0.0, 0.0, c.z];
                let r = self.command(c.command, p);
                self.ack(c.command, r);
            }
            MavMessage::SET_MODE(m) => {
                let _ = self.set_mode(m.custom_mode);
            }
            MavMessage::REQUEST_DATA_STREAM(r) => self.request_stream(r),
            MavMessage::PARAM_REQUEST_LIST(_) => {
                for i in 0..self.params.len() {
                    self.param_value(i);
                }
            }
            MavMessage::PARAM_REQUEST_READ(r) => {
                let name = r.param_id.to_str().unwrap_or("").trim_end_matches('\0');
                let i = if r.param_index >= 0 {
                    Some(r.param_index as usize)
                } else {
                    self.params.index_of(name)
                };
                if let Some(i) = i.filter(|i| *i < self.params.len()) {
                    self.param_value(i);
                }
            }
            MavMessage::PARAM_SET(p) => self.param_set(p),
            MavMessage::MISSION_COUNT(c) => self.mission_count(c),
            MavMessage::MISSION_ITEM_INT(it) => self.mission_item(it),
            MavMessage::MISSION_REQUEST_LIST(_) => {
                let count = self.mission.len() as u16;
                self.send(&MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
                    count,
                    target_system: 255,
                    target_component: 0,
                    ..MISSION_COUNT_DATA::DEFAULT
                }));
            }
            MavMessage::MISSION_REQUEST_INT(r) => {
                if let Some(it) = self.mission.get(r.seq as usize).cloned() {
                    self.send(&MavMessage::MISSION_ITEM_INT(it));
                } else {
                    self.mission_ack(MavMissionResult::MAV_MISSION_INVALID_SEQUENCE);
                }
            }
            MavMessage::MISSION_CLEAR_ALL(_) => {
                self.mission.clear();
                self.uplink(Uplink::Plan(Box::default()));
                self.mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED);
            }
            MavMessage::SET_POSITION_TARGET_LOCAL_NED(t) => self.guided(t),
            _ => {}
        }
    }

    fn ack(&mut self, command: MavCmd, result: MavResult) {
        self.send(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
            command,
            result,
            ..COMMAND_ACK_DATA::DEFAULT
        }));
    }

    fn armed(&self) -> bool {
        self.arm_requested
            .unwrap_or(self.status.is_some_and(|s| s.armed))
    }

    fn accepted(&mut self, u: Uplink) -> MavResult {
        if self.uplink(u) {
            MavResult::MAV_RESULT_ACCEPTED
        } else {
            MavResult::MAV_RESULT_TEMPORARILY_REJECTED
        }
    }

    fn command(&mut self, command: MavCmd, p: [f32; 7]) -> MavResult {
        let needs_armed = matches!(
            command,
            MavCmd::MAV_CMD_NAV_TAKEOFF
                | MavCmd::MAV_CMD_NAV_LAND
                | MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH
                | MavCmd::MAV_CMD_NAV_LOITER_UNLIM
                | MavCmd::MAV_CMD_MISSION_START
        );
        if needs_armed && !self.armed() {
            self.text(MavSeverity::MAV_SEVERITY_WARNING, "refused: not armed");
            return MavResult::MAV_RESULT_DENIED;
        }
        match command {
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => self.arm(p[0], p[1]),
            MavCmd::MAV_CMD_NAV_TAKEOFF => {
                let h = f64::from(p[6]);
                let h = if h.is_finite() && h > 0.0 {
                    h
                } else {
                    self.params.config().takeoff_height_m
                };
                if h > 100.0 {
                    return MavResult::MAV_RESULT_DENIED;
                }
                self.accepted(Uplink::Takeoff(h))
            }
            MavCmd::MAV_CMD_NAV_LAND => self.accepted(Uplink::Land),
            MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH => self.accepted(Uplink::Return),
            MavCmd::MAV_CMD_NAV_LOITER_UNLIM => self.accepted(Uplink::Hold),
            MavCmd::MAV_CMD_MISSION_START => {
                if self.mission.is_empty() {
                    return MavResult::MAV_RESULT_DENIED;
                }
                self.accepted(Uplink::StartMission)
            }
            MavCmd::MAV_CMD_DO_SET_MODE => self.set_mode(p[1] as u32),
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL => self.set_interval(p[0], p[1]),
            MavCmd::MAV_CMD_REQUEST_MESSAGE => {
                let id = p[0] as u32;
                match (STREAMS.iter().any(|(i, _, _)| *i == id), self.status) {
                    (true, Some(s)) => {
                        self.send_stream(id, &s);
                        MavResult::MAV_RESULT_ACCEPTED
                    }
                    (true, None) => MavResult::MAV_RESULT_TEMPORARILY_REJECTED,
                    _ => MavResult::MAV_RESULT_UNSUPPORTED,
                }
            }
            _ => MavResult::MAV_RESULT_UNSUPPORTED,
        }
    }

    fn arm(&mut self, arm: f32, force: f32) -> MavResult {
        let Some(s) = self.status else {
            return MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
        };
        if arm == 1.0 {
            if !s.navigation_ok {
                self.text(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    "refused: no navigation solution",
                );
                return MavResult::MAV_RESULT_DENIED;
            }
            let r = self.accepted(Uplink::Arm(true));
            if r == MavResult::MAV_RESULT_ACCEPTED {
                self.arm_requested = Some(true);
            }
            r
        } else if arm == 0.0 {
            // disarming in the air stops the law: only on the ground, or forced
            let on_ground = s.nav_mode == NavMode::Idle;
            if !on_ground && force != 21196.0 {
                self.text(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    "refused: disarm in flight (force with 21196)",
                );
                return MavResult::MAV_RESULT_DENIED;
            }
            let r = self.accepted(Uplink::Arm(false));
            if r == MavResult::MAV_RESULT_ACCEPTED {
                self.arm_requested = Some(false);
            }
            r
        } else {
            MavResult::MAV_RESULT_DENIED
        }
    }

    fn set_mode(&mut self, custom: u32) -> MavResult {
        let Some(mode) = NavMode::from_code(custom) else {
            return MavResult::MAV_RESULT_DENIED;
        };
        if !self.armed() {
            return MavResult::MAV_RESULT_DENIED;
        }
        let u = match mode {
            NavMode::Mission if !self.mission.is_empty() => Uplink::StartMission,
            NavMode::Hold => Uplink::Hold,
            NavMode::Return => Uplink::Return,
            NavMode::Land => Uplink::Land,
            NavMode::Takeoff => Uplink::Takeoff(self.params.config().takeoff_height_m),
            _ => return MavResult::MAV_RESULT_DENIED,
        };
        self.accepted(u)
    }

    fn set_interval(&mut self, id: f32, interval_us: f32) -> MavResult {
        let id = id as u32;
        let Some(i) = STREAMS.iter().position(|(m, _, _)| *m == id) else {
            return MavResult::MAV_RESULT_UNSUPPORTED;
        };
        let us = f64::from(interval_us);
        self.intervals_s[i] = if us == -1.0 {
            None
        } else if us == 0.0 {
            interval_of(STREAMS[i].2)
        } else if us.is_finite() && us >= 10_000.0 {
            Some(us * 1e-6)
        } else {
            // faster than 100 Hz: the status period
            return MavResult::MAV_RESULT_DENIED;
        };
        self.next_due_s[i] = self.status.map_or(0.0, |s| s.t_s);
        MavResult::MAV_RESULT_ACCEPTED
    }

    fn request_stream(&mut self, r: &REQUEST_DATA_STREAM_DATA) {
        let ids: &[u32] = match r.req_stream_id {
            MavDataStream::MAV_DATA_STREAM_ALL => &[
                SYS_STATUS_DATA::ID,
                ATTITUDE_DATA::ID,
                GLOBAL_POSITION_INT_DATA::ID,
                LOCAL_POSITION_NED_DATA::ID,
                GPS_RAW_INT_DATA::ID,
                VFR_HUD_DATA::ID,
                SERVO_OUTPUT_RAW_DATA::ID,
                RC_CHANNELS_DATA::ID,
            ],
            MavDataStream::MAV_DATA_STREAM_RAW_SENSORS => &[GPS_RAW_INT_DATA::ID],
            MavDataStream::MAV_DATA_STREAM_EXTENDED_STATUS => &[SYS_STATUS_DATA::ID],
            MavDataStream::MAV_DATA_STREAM_RC_CHANNELS => {
                &[RC_CHANNELS_DATA::ID, SERVO_OUTPUT_RAW_DATA::ID]
            }
            MavDataStream::MAV_DATA_STREAM_POSITION => {
                &[GLOBAL_POSITION_INT_DATA::ID, LOCAL_POSITION_NED_DATA::ID]
            }
            MavDataStream::MAV_DATA_STREAM_EXTRA1 => &[ATTITUDE_DATA::ID],
            MavDataStream::MAV_DATA_STREAM_EXTRA2 => &[VFR_HUD_DATA::ID],
            _ => &[],
        };
        let interval = if r.start_stop == 0 || r.req_message_rate == 0 {
            -1.0
        } else {
            1e6 / f32::from(r.req_message_rate.min(100))
        };
        for id in ids {
            let _ = self.set_interval(*id as f32, interval);
        }
    }

    fn param_value(&mut self, i: usize) {
        let Some((name, value)) = self.params.get(i) else {
            return;
        };
        self.send(&MavMessage::PARAM_VALUE(PARAM_VALUE_DATA {
            param_value: value,
            param_count: PARAMS.len() as u16,
            param_index: i as u16,
            param_id: name.into(),
            param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
        }));
    }

    fn param_set(&mut self, p: &PARAM_SET_DATA) {
        let name = p
            .param_id
            .to_str()
            .unwrap_or("")
            .trim_end_matches('\0')
            .to_string();
        match self.params.set(&name, p.param_value) {
            Ok(i) => {
                self.uplink(Uplink::Config(*self.params.config()));
                self.param_value(i);
            }
            Err(ParamError::Unknown(_)) => {
                self.text(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    &format!("no parameter {name}"),
                );
            }
            Err(e @ ParamError::Rejected { .. }) => {
                self.text(MavSeverity::MAV_SEVERITY_WARNING, &format!("refused {e}"));
                // the answer is the unchanged value
                if let Some(i) = self.params.index_of(&name) {
                    self.param_value(i);
                }
            }
        }
    }

    fn mission_ack(&mut self, result: MavMissionResult) {
        self.send(&MavMessage::MISSION_ACK(MISSION_ACK_DATA {
            target_system: 255,
            target_component: 0,
            mavtype: result,
            ..MISSION_ACK_DATA::DEFAULT
        }));
    }

    fn request_item(&mut self, seq: u16) {
        self.send(&MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
            seq,
            target_system: 255,
            target_component: 0,
            ..MISSION_REQUEST_INT_DATA::DEFAULT
        }));
    }

    fn mission_count(&mut self, c: &MISSION_COUNT_DATA) {
        if c.mission_type != MavMissionType::MAV_MISSION_TYPE_MISSION {
            self.mission_ack(MavMissionResult::MAV_MISSION_UNSUPPORTED);
            return;
        }
        if usize::from(c.count) > crate::navigator::MAX_MISSION_ITEMS * 2 {
            self.mission_ack(MavMissionResult::MAV_MISSION_NO_SPACE);
            return;
        }
        if c.count == 0 {
            self.mission.clear();
            self.uplink(Uplink::Plan(Box::default()));
            self.mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED);
            return;
        }
        self.upload = Upload::Receiving {
            count: c.count,
            items: Vec::with_capacity(usize::from(c.count)),
        };
        self.request_item(0);
    }

    fn mission_item(&mut self, it: &MISSION_ITEM_INT_DATA) {
        let Upload::Receiving { count, items } = &mut self.upload else {
            return;
        };
        let expected = items.len() as u16;
        if it.seq != expected {
            // a repeat or a skip: ask again for the one expected
            self.request_item(expected);
            return;
        }
        items.push(it.clone());
        if items.len() < usize::from(*count) {
            self.request_item(expected + 1);
            return;
        }
        let items = std::mem::take(items);
        self.upload = Upload::Idle;
        match plan_of(&self.home, &items) {
            Ok(plan) => {
                self.mission = items;
                self.uplink(Uplink::Plan(Box::new(plan)));
                self.mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED);
            }
            Err(MissionError { seq, rule, result }) => {
                self.text(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    &format!("mission refused: item {seq}: {rule}"),
                );
                self.mission_ack(result);
            }
        }
    }

    fn guided(&mut self, t: &SET_POSITION_TARGET_LOCAL_NED_DATA) {
        if !self.armed() {
            return;
        }
        if t.coordinate_frame != MavFrame::MAV_FRAME_LOCAL_NED {
            self.text(
                MavSeverity::MAV_SEVERITY_WARNING,
                "guided: only MAV_FRAME_LOCAL_NED",
            );
            return;
        }
        let m = t.type_mask;
        let pos_ignored = m.contains(
            PositionTargetTypemask::POSITION_TARGET_TYPEMASK_X_IGNORE
                | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_Y_IGNORE
                | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_Z_IGNORE,
        );
        let vel_ignored = m.contains(
            PositionTargetTypemask::POSITION_TARGET_TYPEMASK_VX_IGNORE
                | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_VY_IGNORE
                | PositionTargetTypemask::POSITION_TARGET_TYPEMASK_VZ_IGNORE,
        );
        let yaw = (!m.contains(PositionTargetTypemask::POSITION_TARGET_TYPEMASK_YAW_IGNORE))
            .then_some(f64::from(t.yaw));
        let target = if !vel_ignored && pos_ignored {
            GuidedTarget::Velocity(
                Vector3::new(f64::from(t.vx), f64::from(t.vy), f64::from(t.vz)),
                yaw,
            )
        } else if !pos_ignored {
            GuidedTarget::Position(
                Vector3::new(f64::from(t.x), f64::from(t.y), f64::from(t.z)),
                yaw,
            )
        } else {
            return;
        };
        self.uplink(Uplink::Guided(target));
    }
}

/// The MAVLink 2 version the server speaks.
pub const VERSION: MavlinkVersion = MavlinkVersion::V2;
