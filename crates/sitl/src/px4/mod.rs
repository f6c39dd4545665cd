//! PX4's simulator backend: `helicon sitl SCENARIO --px4 [ADDR]`. PX4's
//! SITL (`simulator_mavlink`, started by `make px4_sitl none` or by its
//! `rcS` with no simulator of its own) connects as a TCP client to the
//! simulator, port 4560; helicon listens, sends the sensors, and steps the
//! simulator's hardware — the nonlinear model with its wind, landing gear,
//! drivetrain and ground effect, `helicon_sim::closed_loop::Hardware` — one
//! sensor period per actuator message PX4 answers.
//!
//! The protocol, as read in PX4's `SimulatorMavlink.cpp` (lock-step build):
//! - on connecting, PX4 sends a `HEARTBEAT` and a `COMMAND_LONG` asking for
//!   `HIL_STATE_QUATERNION`; its clock does not run until the first
//!   `HIL_SENSOR` (`id` 0) sets it to `time_usec`;
//! - first contact: helicon's first valid frame from PX4 makes it send the
//!   sensors at t = 0 (`HIL_SENSOR`, `HIL_GPS`, `HIL_STATE_QUATERNION`,
//!   `HEARTBEAT`);
//! - until the connection's first `HIL_ACTUATOR_CONTROLS`, the model
//!   free-runs on the wall clock: one step (disarmed, controls 0) and its
//!   sensors per sensor period, as PX4's other simulators do before the
//!   first actuator message ([`Px4Options::free_run_until_first_actuator`]);
//! - PX4 runs its modules up to that time and answers
//!   `HIL_ACTUATOR_CONTROLS` (`controls[n-1]` the output `PWM_MAIN_FUNCn`,
//!   motors 0 … 1, servos −1 … 1, all 0 while disarmed; `mode` with
//!   `MAV_MODE_FLAG_SAFETY_ARMED`, `flags` bit 0 lock-step);
//! - each `HIL_ACTUATOR_CONTROLS`: one step of the sensor period (default
//!   4000 µs, PX4's 250 Hz), then the sensors at the new time: `time_usec`
//!   advances by the step, exactly;
//! - no message: no time passes (the wait ends on the stop flag or after
//!   [`Px4Options::silence_timeout`]);
//! - a new connection (PX4 restarted): the simulation starts again from its
//!   initial state (on the ground, rotor stopped) and the handshake again;
//! - bytes that are not a valid frame (junk, checksum, unknown id, bad
//!   payload): counted by kind, ignored; other valid messages (`HEARTBEAT`,
//!   `COMMAND_LONG`): counted, ignored.
//!
//! The sensors are the truth (PX4's SITL adds no noise of its own; its
//! `SENS_*`/`SIH_*` noise does not apply to `simulator_mavlink`):
//! `HIL_SENSOR` every step with the specific force at the centre of mass
//! (body FRD, m/s²), the body rates (rad/s), the Earth field of
//! [`mapping::Px4Section::mag_field_ned_gauss`] rotated into the body
//! (gauss), the ISA pressure (hPa), pressure altitude (m) and temperature
//! (°C) of the altitude above sea level (home altitude plus the height
//! above the ground start); `HIL_GPS` at [`Px4Options::gps_rate_hz`] (3-D
//! fix, 10 satellites, eph 0.3 m, epv 0.4 m, the position as latitude and
//! longitude about home on a sphere of 6 378 137 m); `HIL_STATE_QUATERNION`
//! (ground truth) every step unless turned off; a `HEARTBEAT` each second
//! of model time.

pub mod mapping;
pub mod protocol;

pub use crate::lockstep::Ending;
pub use mapping::{BERGEN_TWIN_TOML, CHANNELS, Px4Decoded, Px4Map, Px4Outputs, Px4Section};
pub use protocol::{FrameError, Framer, Outbox};

use crate::lockstep::{Session, SessionError};
use helicon_gcs::mavlink::dialects::common::{
    HEARTBEAT_DATA, HIL_GPS_DATA, HIL_SENSOR_DATA, HIL_STATE_QUATERNION_DATA,
    HilSensorUpdatedFlags, MavAutopilot, MavMessage, MavModeFlag, MavState, MavType,
};
use helicon_sim::closed_loop::{ClosedLoopError, Prepared, Summary};
use helicon_sim::log_csv::LogCsvError;
use helicon_sim::scenario::Scenario;
use nalgebra::{UnitQuaternion, Vector3};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// The address PX4's `simulator_mavlink` connects to.
pub const DEFAULT_ADDRESS: &str = "127.0.0.1:4560";

/// PX4's default sensor step (µs): 250 Hz.
pub const DEFAULT_STEP_US: u32 = 4000;

/// helicon's MAVLink system id as the simulator (PX4 does not check it).
pub const SIM_SYSTEM_ID: u8 = 1;
/// helicon's MAVLink component id as the simulator.
pub const SIM_COMPONENT_ID: u8 = 51;

/// How long one wait for bytes or a connection lasts before the stop flag
/// and the silence are checked again.
const POLL: Duration = Duration::from_millis(20);

/// The Earth's radius for the position about home (m).
const EARTH_RADIUS_M: f64 = 6_378_137.0;

/// Settings of a PX4 run.
#[derive(Debug, Clone)]
pub struct Px4Options {
    /// Write the truth `log.csv` here (a reconnection starts it afresh).
    pub out_dir: Option<PathBuf>,
    /// Write every n-th row of `log.csv` (and the last); 0 counts as 1.
    pub log_stride: usize,
    /// Checked between messages: once set, the run ends.
    pub stop: Option<Arc<AtomicBool>>,
    /// End the run when no valid message came for this long (`None`: wait
    /// for ever — until the stop flag).
    pub silence_timeout: Option<Duration>,
    /// End the run after this many steps (all connections).
    pub max_steps: Option<u64>,
    /// The sensor step (µs; PX4's default 4000, 250 Hz).
    pub step_us: u32,
    /// `HIL_GPS`' rate (Hz; sent on the steps nearest it).
    pub gps_rate_hz: f64,
    /// Send `HIL_STATE_QUATERNION` (PX4's ground truth) every step.
    pub ground_truth: bool,
    /// Before a connection's first `HIL_ACTUATOR_CONTROLS`, step (disarmed,
    /// controls 0) and send the sensors once per sensor period of wall
    /// time, as PX4's other simulators do until the first actuator message
    /// (PX4 sends none before its modules published outputs, and they run
    /// on the sensors' time); lock-step from the first actuator message on.
    pub free_run_until_first_actuator: bool,
}

impl Default for Px4Options {
    fn default() -> Self {
        Px4Options {
            out_dir: None,
            log_stride: 1,
            stop: None,
            silence_timeout: None,
            max_steps: None,
            step_us: DEFAULT_STEP_US,
            gps_rate_hz: 10.0,
            ground_truth: true,
            free_run_until_first_actuator: true,
        }
    }
}

/// What the run counted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct Counts {
    /// Steps flown (actuator messages answered, and free-running steps),
    /// all connections.
    pub steps: u64,
    /// Of those, free-running before a connection's first actuator message.
    pub free_steps: u64,
    /// Connections accepted (the first, then PX4's restarts).
    pub connections: u64,
    /// `HIL_ACTUATOR_CONTROLS` received.
    pub actuator_messages: u64,
    /// Of those, with the armed flag.
    pub armed_messages: u64,
    /// Other valid messages (`HEARTBEAT`, `COMMAND_LONG`, …), ignored.
    pub other_messages: u64,
    /// `HIL_SENSOR` sent.
    pub sensor_messages: u64,
    /// `HIL_GPS` sent.
    pub gps_messages: u64,
    /// `HIL_STATE_QUATERNION` sent.
    pub state_messages: u64,
    /// `HEARTBEAT` sent.
    pub heartbeats: u64,
    /// Bytes outside any frame.
    pub junk_bytes: u64,
    /// Frames with a wrong checksum.
    pub bad_crc: u64,
    /// Frames of message ids the common dialect does not have.
    pub unknown_id: u64,
    /// Frames whose payload did not parse.
    pub bad_payload: u64,
}

impl Counts {
    /// Malformed frames (checksum, unknown id, payload; junk bytes apart).
    pub fn malformed(&self) -> u64 {
        self.bad_crc + self.unknown_id + self.bad_payload
    }

    fn count(&mut self, e: FrameError) {
        match e {
            FrameError::Junk(n) => self.junk_bytes += n as u64,
            FrameError::Crc => self.bad_crc += 1,
            FrameError::UnknownId(_) => self.unknown_id += 1,
            FrameError::Payload(_) => self.bad_payload += 1,
        }
    }
}

/// What a PX4 run did.
#[derive(Debug, Clone)]
pub struct Px4Report {
    /// The counters.
    pub counts: Counts,
    /// Why it ended.
    pub ending: Ending,
    /// The sensor step (µs).
    pub step_us: u32,
    /// Steps flown in the last connection.
    pub session_steps: u64,
    /// Model time of the last connection (s).
    pub model_time_s: f64,
    /// Wall time from the first valid message to the last sensors sent (s).
    pub wall_s: f64,
    /// Steps per wall second, lock-step (the autopilot's side included).
    pub steps_per_s: f64,
    /// Model time per wall time (all connections).
    pub speed_x: f64,
    /// The last `HIL_SENSOR` sent.
    pub last_sensor: Option<HIL_SENSOR_DATA>,
    /// The last connection's true state at the end.
    pub final_state: Option<helicon_model::State>,
    /// The last connection's rotor speed at the end (rad/s).
    pub rotor_speed_rad_s: Option<f64>,
    /// The last connection's flight summary (as `helicon sim` writes it).
    pub summary: Option<Summary>,
    /// The truth log, when written.
    pub log_csv: Option<PathBuf>,
    /// Its rows.
    pub log_rows: usize,
    /// PX4's address (the last connection's).
    pub peer: Option<SocketAddr>,
}

/// Errors of a PX4 run (a divergence or a crash is an outcome:
/// [`Ending::Simulation`]).
#[derive(Debug, thiserror::Error)]
pub enum Px4Error {
    /// The TCP socket.
    #[error("PX4 simulator socket {address}: {source}")]
    Socket {
        /// The address.
        address: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The output folder could not be created.
    #[error("{path}: cannot create: {source}")]
    Folder {
        /// The folder.
        path: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The options.
    #[error("PX4 options: {0}")]
    Options(String),
    /// Building the hardware.
    #[error(transparent)]
    Prepare(#[from] ClosedLoopError),
    /// The truth log.
    #[error(transparent)]
    Csv(#[from] LogCsvError),
    /// The `[px4]` section.
    #[error(transparent)]
    Config(#[from] helicon_config::ConfigError),
}

impl From<SessionError> for Px4Error {
    fn from(e: SessionError) -> Self {
        match e {
            SessionError::Prepare(e) => Px4Error::Prepare(e),
            SessionError::Csv(e) => Px4Error::Csv(e),
        }
    }
}

/// The simulator's listening socket, bound before the run so that its
/// address (an OS-chosen port) can be told to PX4.
#[derive(Debug)]
pub struct Px4Server {
    listener: TcpListener,
    address: SocketAddr,
}

/// How the sensors are made: home, the field, gravity.
struct Sensing {
    g: f64,
    ground_down_m: f64,
    home_lat_deg: f64,
    home_lon_deg: f64,
    home_alt_m: f64,
    mag_ned_gauss: Vector3<f64>,
    step_us: u64,
    gps_every: u64,
    heartbeat_every: u64,
    ground_truth: bool,
}

/// One connection's state.
struct Link {
    stream: TcpStream,
    framer: Framer,
    out: Outbox,
    contact: bool,
    /// The first actuator message came: lock-step.
    lockstep: bool,
    last_send: Instant,
}

impl Px4Server {
    /// Bind `address` (`HOST:PORT`; port 0: the OS chooses).
    pub fn bind(address: &str) -> Result<Self, Px4Error> {
        let err = |source| Px4Error::Socket {
            address: address.to_string(),
            source,
        };
        let listener = TcpListener::bind(address).map_err(err)?;
        listener.set_nonblocking(true).map_err(err)?;
        let address = listener.local_addr().map_err(err)?;
        Ok(Px4Server { listener, address })
    }

    /// The bound address.
    pub fn local_addr(&self) -> SocketAddr {
        self.address
    }

    /// Serve PX4 with `scenario` (prepared) as the physics, its actuator
    /// controls read through `map`, until the stop flag, the silence
    /// timeout, the step limit or the simulation's end.
    #[allow(clippy::too_many_lines)] // one loop: accept, receive, step, send
    pub fn run(
        &self,
        scenario: &Scenario,
        prepared: &Prepared,
        map: &Px4Map,
        options: &Px4Options,
    ) -> Result<Px4Report, Px4Error> {
        let sock_err = |source| Px4Error::Socket {
            address: self.address.to_string(),
            source,
        };
        if !(1000..=100_000).contains(&options.step_us) {
            return Err(Px4Error::Options(format!(
                "step_us {} not in 1000 ..= 100000 µs",
                options.step_us
            )));
        }
        if !(options.gps_rate_hz.is_finite() && options.gps_rate_hz > 0.0) {
            return Err(Px4Error::Options(format!(
                "gps_rate_hz {} not a positive rate",
                options.gps_rate_hz
            )));
        }
        let step_us = u64::from(options.step_us);
        let steps_per_s = 1e6 / step_us as f64;
        // the hardware's own sensor models (not sent: PX4 gets the truth)
        // sample at the step: the magnetometer's rate a divisor of it
        let mut adjusted = scenario.clone();
        let mag = &mut adjusted.sensors.mag.rate_hz;
        *mag = steps_per_s / (steps_per_s / *mag).ceil().max(1.0);
        let scenario = &adjusted;
        let sec = &map.section;
        let sensing = Sensing {
            g: prepared.model.params().environment.g_m_s2,
            ground_down_m: crate::lockstep::ground_down_m(prepared),
            home_lat_deg: sec.home_lat_deg,
            home_lon_deg: sec.home_lon_deg,
            home_alt_m: sec.home_alt_m,
            mag_ned_gauss: Vector3::from(sec.mag_field_ned_gauss),
            step_us,
            gps_every: ((steps_per_s / options.gps_rate_hz).round() as u64).max(1),
            heartbeat_every: (steps_per_s.round() as u64).max(1),
            ground_truth: options.ground_truth,
        };
        let log_csv = crate::lockstep::log_path(options.out_dir.as_deref()).map_err(|(d, e)| {
            Px4Error::Folder {
                path: d.display().to_string(),
                source: e,
            }
        })?;
        let mut counts = Counts::default();
        let mut session: Option<Session<'_>> = None;
        let mut link: Option<Link> = None;
        let mut last_sensor = None;
        let mut peer = None;
        let mut first_message: Option<Instant> = None;
        let mut last_sent_at: Option<Instant> = None;
        let mut last_valid = Instant::now();
        let mut model_time_all = 0.0;
        let step_s = step_us as f64 * 1e-6;
        let period = Duration::from_micros(step_us);
        // the wait for bytes: short enough to free-run at the sensor period
        let wait = if options.free_run_until_first_actuator {
            period.clamp(Duration::from_millis(1), POLL)
        } else {
            POLL
        };
        let idle = [0f32; CHANNELS];
        let stop = || crate::lockstep::stopped(options.stop.as_ref());
        let ending = 'run: loop {
            if stop() {
                break Ending::Stopped;
            }
            if options
                .silence_timeout
                .is_some_and(|t| last_valid.elapsed() >= t)
            {
                break Ending::Silent;
            }
            // a new connection: PX4 (re)started
            match self.listener.accept() {
                Ok((stream, from)) => {
                    stream.set_nonblocking(false).map_err(sock_err)?;
                    stream.set_nodelay(true).map_err(sock_err)?;
                    stream.set_read_timeout(Some(wait)).map_err(sock_err)?;
                    counts.connections += 1;
                    peer = Some(from);
                    if let Some(s) = session.take() {
                        model_time_all += s.restart()?;
                    }
                    link = Some(Link {
                        stream,
                        framer: Framer::new(),
                        out: Outbox::new(SIM_SYSTEM_ID, SIM_COMPONENT_ID),
                        contact: false,
                        lockstep: false,
                        last_send: Instant::now(),
                    });
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::Interrupted
                    ) => {}
                Err(e) => return Err(sock_err(e)),
            }
            let Some(l) = link.as_mut() else {
                std::thread::sleep(POLL);
                continue;
            };
            if options.free_run_until_first_actuator
                && l.contact
                && !l.lockstep
                && l.last_send.elapsed() >= period
                && let Some(s) = session.as_mut()
            {
                // PX4 has not answered yet: the clock runs on the wall's
                let d = map.decode(&idle, false);
                let end = s.step(&d.input, d.engine_on)?;
                counts.steps += 1;
                counts.free_steps += 1;
                l.out.clear();
                if let Some(h) = push_sensors(&mut l.out, s, &sensing, &mut counts) {
                    last_sensor = Some(h);
                }
                let sent = send(&mut l.stream, &mut l.out);
                l.last_send = Instant::now();
                last_sent_at = Some(l.last_send);
                if let Some((kind, why)) = end {
                    break 'run Ending::Simulation(kind, why);
                }
                if options.max_steps.is_some_and(|m| counts.steps >= m) {
                    break 'run Ending::FrameLimit;
                }
                if sent.is_err() {
                    link = None;
                    continue;
                }
            }
            let n = match l.stream.read(l.framer.spare()) {
                Ok(0) => {
                    // PX4 closed: wait for it to come back
                    link = None;
                    continue;
                }
                Ok(n) => n,
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock
                            | std::io::ErrorKind::TimedOut
                            | std::io::ErrorKind::Interrupted
                    ) =>
                {
                    continue;
                }
                Err(_) => {
                    // reset by the peer and the like: the connection is over
                    link = None;
                    continue;
                }
            };
            l.framer.commit(n);
            while let Some(m) = l.framer.next_message() {
                let msg = match m {
                    Ok(msg) => msg,
                    Err(e) => {
                        counts.count(e);
                        continue;
                    }
                };
                last_valid = Instant::now();
                first_message.get_or_insert(last_valid);
                if !l.contact {
                    // first contact: a fresh simulation, its sensors at t = 0
                    l.contact = true;
                    let s = session.insert(Session::new(
                        scenario,
                        prepared,
                        step_s,
                        log_csv.as_deref(),
                        options.log_stride,
                    )?);
                    l.out.clear();
                    if let Some(h) = push_sensors(&mut l.out, s, &sensing, &mut counts) {
                        last_sensor = Some(h);
                    }
                    if send(&mut l.stream, &mut l.out).is_err() {
                        link = None;
                        continue 'run;
                    }
                    l.last_send = Instant::now();
                    last_sent_at = Some(l.last_send);
                }
                let MavMessage::HIL_ACTUATOR_CONTROLS(c) = &msg else {
                    counts.other_messages += 1;
                    continue;
                };
                counts.actuator_messages += 1;
                l.lockstep = true;
                let armed = c.mode.contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
                if armed {
                    counts.armed_messages += 1;
                }
                let Some(s) = session.as_mut() else {
                    continue;
                };
                let d = map.decode(&c.controls, armed);
                let end = s.step(&d.input, d.engine_on)?;
                counts.steps += 1;
                l.out.clear();
                if let Some(h) = push_sensors(&mut l.out, s, &sensing, &mut counts) {
                    last_sensor = Some(h);
                }
                let sent = send(&mut l.stream, &mut l.out);
                l.last_send = Instant::now();
                last_sent_at = Some(l.last_send);
                if let Some((kind, why)) = end {
                    break 'run Ending::Simulation(kind, why);
                }
                if options.max_steps.is_some_and(|m| counts.steps >= m) {
                    break 'run Ending::FrameLimit;
                }
                if sent.is_err() {
                    link = None;
                    continue 'run;
                }
            }
        };
        let wall_s = match (first_message, last_sent_at) {
            (Some(a), Some(b)) => b.duration_since(a).as_secs_f64(),
            _ => 0.0,
        };
        let (session_steps, model_time_s, final_state, rotor, summary, rows) = match session {
            Some(s) => {
                let c = s.close(ending.abort_reason())?;
                (
                    c.frames,
                    c.model_time_s,
                    Some(c.final_state),
                    Some(c.rotor_speed_rad_s),
                    Some(c.summary),
                    c.rows,
                )
            }
            None => (0, 0.0, None, None, None, 0),
        };
        model_time_all += model_time_s;
        Ok(Px4Report {
            counts,
            ending,
            step_us: options.step_us,
            session_steps,
            model_time_s,
            wall_s,
            steps_per_s: if wall_s > 0.0 {
                counts.steps as f64 / wall_s
            } else {
                0.0
            },
            speed_x: if wall_s > 0.0 {
                model_time_all / wall_s
            } else {
                0.0
            },
            last_sensor,
            final_state,
            rotor_speed_rad_s: rotor,
            summary,
            log_csv: if rows > 0 { log_csv } else { None },
            log_rows: rows,
            peer,
        })
    }
}

/// Write the outbox to PX4, then empty it.
fn send(stream: &mut TcpStream, out: &mut Outbox) -> std::io::Result<()> {
    let r = stream.write_all(out.bytes());
    out.clear();
    r
}

/// ISA pressure (Pa) and temperature (°C) at `alt_m` above sea level.
fn isa(alt_m: f64) -> (f64, f64) {
    let t_k = 288.15 - 0.0065 * alt_m;
    let p = 101_325.0 * (t_k / 288.15).powf(5.255_877);
    (p, t_k - 273.15)
}

/// Saturate to an `i16` (cm/s, mG).
fn sat_i16(v: f64) -> i16 {
    if v.is_finite() {
        v.round().clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16
    } else {
        0
    }
}

/// The sensors of `s` now into `out` (and the GPS, ground truth and
/// heartbeat on their steps); the `HIL_SENSOR` sent, if the state is.
fn push_sensors(
    out: &mut Outbox,
    s: &Session<'_>,
    k: &Sensing,
    counts: &mut Counts,
) -> Option<HIL_SENSOR_DATA> {
    let now = s.now.as_ref()?;
    let tr = &now.truth;
    let time_usec = s.frames * k.step_us;
    let f = tr.specific_force_body(k.g);
    let w = tr.omega_body_rad_s;
    let m = tr.to_body(&k.mag_ned_gauss);
    let n_m = tr.pos_ned_m.x;
    let e_m = tr.pos_ned_m.y;
    let height_m = -(tr.pos_ned_m.z - k.ground_down_m);
    let alt_m = k.home_alt_m + height_m;
    let (p_pa, temp_c) = isa(alt_m);
    let sensor = HIL_SENSOR_DATA {
        time_usec,
        xacc: f.x as f32,
        yacc: f.y as f32,
        zacc: f.z as f32,
        xgyro: w.x as f32,
        ygyro: w.y as f32,
        zgyro: w.z as f32,
        xmag: m.x as f32,
        ymag: m.y as f32,
        zmag: m.z as f32,
        abs_pressure: (p_pa / 100.0) as f32,
        diff_pressure: 0.0,
        pressure_alt: alt_m as f32,
        temperature: temp_c as f32,
        fields_updated: HilSensorUpdatedFlags::from_bits_truncate(0x1FFF & !0x400),
        id: 0,
    };
    out.push(&MavMessage::HIL_SENSOR(sensor.clone()));
    counts.sensor_messages += 1;
    let lat_deg = k.home_lat_deg + (n_m / EARTH_RADIUS_M).to_degrees();
    let lon_deg =
        k.home_lon_deg + (e_m / (EARTH_RADIUS_M * k.home_lat_deg.to_radians().cos())).to_degrees();
    let lat = (lat_deg * 1e7).round() as i32;
    let lon = (lon_deg * 1e7).round() as i32;
    let alt_mm = (alt_m * 1000.0).round() as i32;
    let v = tr.vel_ned_m_s;
    if s.frames % k.gps_every == 0 {
        let ground_m_s = v.x.hypot(v.y);
        let cog = if ground_m_s > 0.1 {
            let c = v.y.atan2(v.x).to_degrees().rem_euclid(360.0);
            ((c * 100.0).round() as u16) % 36000
        } else {
            u16::MAX
        };
        out.push(&MavMessage::HIL_GPS(HIL_GPS_DATA {
            time_usec,
            lat,
            lon,
            alt: alt_mm,
            eph: 30,
            epv: 40,
            vel: (ground_m_s * 100.0).round().clamp(0.0, 65534.0) as u16,
            vn: sat_i16(v.x * 100.0),
            ve: sat_i16(v.y * 100.0),
            vd: sat_i16(v.z * 100.0),
            cog,
            fix_type: 3,
            satellites_visible: 10,
            id: 0,
            yaw: 0,
        }));
        counts.gps_messages += 1;
    }
    if k.ground_truth {
        let e = tr.euler_rad;
        let q = UnitQuaternion::from_euler_angles(e.x, e.y, e.z);
        let speed_cm_s = (v.norm() * 100.0).round().clamp(0.0, 65535.0) as u16;
        out.push(&MavMessage::HIL_STATE_QUATERNION(
            HIL_STATE_QUATERNION_DATA {
                time_usec,
                attitude_quaternion: [q.w as f32, q.i as f32, q.j as f32, q.k as f32],
                rollspeed: w.x as f32,
                pitchspeed: w.y as f32,
                yawspeed: w.z as f32,
                lat,
                lon,
                alt: alt_mm,
                vx: sat_i16(v.x * 100.0),
                vy: sat_i16(v.y * 100.0),
                vz: sat_i16(v.z * 100.0),
                ind_airspeed: speed_cm_s,
                true_airspeed: speed_cm_s,
                xacc: sat_i16(f.x / k.g * 1000.0),
                yacc: sat_i16(f.y / k.g * 1000.0),
                zacc: sat_i16(f.z / k.g * 1000.0),
            },
        ));
        counts.state_messages += 1;
    }
    if s.frames % k.heartbeat_every == 0 {
        out.push(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: MavType::MAV_TYPE_GENERIC,
            autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
            base_mode: MavModeFlag::empty(),
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }));
        counts.heartbeats += 1;
    }
    Some(sensor)
}

/// `timing.json` of a PX4 run.
pub fn timing_json(r: &Px4Report) -> serde_json::Value {
    serde_json::json!({
        "backend": "px4",
        "step_us": r.step_us,
        "frame_rate_hz": 1e6 / f64::from(r.step_us),
        "frames": r.counts.steps,
        "session_frames": r.session_steps,
        "model_time_s": r.model_time_s,
        "wall_s": r.wall_s,
        "frames_per_s": r.steps_per_s,
        "speed_x_realtime": r.speed_x,
        "counts": r.counts,
        "malformed": r.counts.malformed(),
    })
}
