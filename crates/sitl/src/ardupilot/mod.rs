//! ArduPilot's JSON physics backend: `helicon sitl SCENARIO
//! --ardupilot-json [ADDR]`. ArduPilot's SITL (`--model JSON:HOST`) sends a
//! servo packet per frame over UDP ([`protocol`]); helicon decodes the
//! swashplate, tail and throttle outputs back into the Bergen Twin's inputs
//! ([`mapping`], the inverse of ArduPilot's heli mixer), steps the
//! simulator's hardware — the nonlinear model with its wind, landing gear,
//! drivetrain and ground effect, `helicon_sim::closed_loop::Hardware` — by
//! one frame period, and answers the state as ArduPilot reads it.
//!
//! Lock-step, frame by frame:
//! - a new `frame_count` (above the last): one step of `1/frame_rate`, then
//!   the state after it;
//! - the same `frame_count` again (ArduPilot re-sends a frame it got no
//!   answer to): the last state, no step;
//! - a `frame_count` below the last: ArduPilot restarted; the simulation
//!   starts again from its initial state (on the ground) and steps this frame;
//! - a malformed packet (size, magic, frame rate, PWM): counted, ignored;
//! - no packet: nothing happens, no time passes (the wait ends on the stop
//!   flag or after [`ArduPilotOptions::silence_timeout`]).
//!
//! The simulation runs at the frame rate of its first frame (of its last
//! restart); a frame asking another rate is stepped at that one and counted
//! ([`Counts::rate_mismatches`]).
//!
//! The reply is the truth, as ArduPilot's SITL wants it (it adds its own
//! sensor noise and faults from its `SIM_*` parameters): the body rates, the
//! specific force at the centre of mass (from the derivative of the step
//! just flown, the hardware's IMU truth), the position from the ground
//! point below the simulator's origin (home on the ground), the NED
//! velocity and the 3-2-1 Euler angles.

pub mod mapping;
pub mod protocol;

pub use mapping::{
    ArduPilotMap, ArduPilotSection, AutopilotOutputs, BERGEN_TWIN_TOML, Decoded, ServoOutput,
    SwashType,
};
pub use protocol::{PacketError, PhysicsState, ServoPacket, parse_servo_packet};

pub use crate::lockstep::Ending;

use crate::lockstep::{Session, SessionError};
use helicon_sim::closed_loop::{ClosedLoopError, Prepared, Summary};
use helicon_sim::log_csv::LogCsvError;
use helicon_sim::scenario::Scenario;
use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// The address ArduPilot's SITL sends its servo packets to.
pub const DEFAULT_ADDRESS: &str = "127.0.0.1:9002";

/// How long one wait for a packet lasts before the stop flag and the
/// silence are checked again.
const POLL: Duration = Duration::from_millis(50);

/// Settings of an ArduPilot JSON run.
#[derive(Debug, Clone, Default)]
pub struct ArduPilotOptions {
    /// Write the truth `log.csv` here (a restart of the autopilot starts it
    /// afresh); `None`: no log.
    pub out_dir: Option<PathBuf>,
    /// Write every n-th row of `log.csv` (and the last); 0 counts as 1.
    pub log_stride: usize,
    /// Checked between packets: once set, the run ends.
    pub stop: Option<Arc<AtomicBool>>,
    /// End the run when no valid packet came for this long (`None`: wait
    /// for ever — until the stop flag).
    pub silence_timeout: Option<Duration>,
    /// End the run after this many stepped frames.
    pub max_frames: Option<u64>,
}

/// What the run counted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct Counts {
    /// Frames stepped (new frame counts), all sessions.
    pub frames: u64,
    /// Repeated frame counts answered without a step.
    pub repeats: u64,
    /// Frame counts going back: the autopilot restarted.
    pub restarts: u64,
    /// New frame counts that skipped numbers (lost frames; each still one step).
    pub gaps: u64,
    /// Frames asking another rate than the session's.
    pub rate_mismatches: u64,
    /// Replies sent.
    pub replies: u64,
    /// Packets of a wrong size.
    pub bad_size: u64,
    /// Packets with a wrong magic number.
    pub bad_magic: u64,
    /// Packets with a frame rate of 0 or beyond 8 kHz.
    pub bad_frame_rate: u64,
    /// Packets with a PWM beyond 3000 µs.
    pub bad_pwm: u64,
}

impl Counts {
    /// Malformed packets, all kinds.
    pub fn malformed(&self) -> u64 {
        self.bad_size + self.bad_magic + self.bad_frame_rate + self.bad_pwm
    }

    fn count(&mut self, e: &PacketError) {
        match e {
            PacketError::Size(_) => self.bad_size += 1,
            PacketError::Magic { .. } => self.bad_magic += 1,
            PacketError::FrameRate(_) => self.bad_frame_rate += 1,
            PacketError::Pwm { .. } => self.bad_pwm += 1,
        }
    }
}

/// What an ArduPilot JSON run did.
#[derive(Debug, Clone)]
pub struct ArduPilotReport {
    /// The counters.
    pub counts: Counts,
    /// Why it ended.
    pub ending: Ending,
    /// The frame rate of the last session (Hz).
    pub frame_rate_hz: Option<u16>,
    /// Frames stepped in the last session.
    pub session_frames: u64,
    /// Model time of the last session (s): its frames over its rate.
    pub model_time_s: f64,
    /// Wall time from the first valid packet to the last reply (s).
    pub wall_s: f64,
    /// Frames stepped per wall second, lock-step (the autopilot's side included).
    pub frames_per_s: f64,
    /// Model time per wall time (all sessions).
    pub speed_x: f64,
    /// The last state answered.
    pub last_state: Option<PhysicsState>,
    /// The last session's true state at the end.
    pub final_state: Option<helicon_model::State>,
    /// The last session's rotor speed at the end (rad/s).
    pub rotor_speed_rad_s: Option<f64>,
    /// The last session's flight summary (as `helicon sim` writes it).
    pub summary: Option<Summary>,
    /// The truth log, when written.
    pub log_csv: Option<PathBuf>,
    /// Its rows.
    pub log_rows: usize,
    /// The autopilot's address (the last packet's sender).
    pub peer: Option<SocketAddr>,
}

/// Errors of an ArduPilot JSON run (a divergence or a crash is an outcome:
/// [`Ending::Simulation`]).
#[derive(Debug, thiserror::Error)]
pub enum ArduPilotError {
    /// The UDP socket.
    #[error("ArduPilot JSON socket {address}: {source}")]
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
    /// Building the hardware.
    #[error(transparent)]
    Prepare(#[from] ClosedLoopError),
    /// The truth log.
    #[error(transparent)]
    Csv(#[from] LogCsvError),
    /// The `[ardupilot]` section.
    #[error(transparent)]
    Config(#[from] helicon_config::ConfigError),
}

impl From<SessionError> for ArduPilotError {
    fn from(e: SessionError) -> Self {
        match e {
            SessionError::Prepare(e) => ArduPilotError::Prepare(e),
            SessionError::Csv(e) => ArduPilotError::Csv(e),
        }
    }
}

/// The physics side's UDP socket, bound before the run so that its address
/// (an OS-chosen port) can be told to the autopilot.
#[derive(Debug)]
pub struct ArduPilotServer {
    socket: UdpSocket,
    address: SocketAddr,
}

impl ArduPilotServer {
    /// Bind `address` (`HOST:PORT`; port 0: the OS chooses).
    pub fn bind(address: &str) -> Result<Self, ArduPilotError> {
        let err = |source| ArduPilotError::Socket {
            address: address.to_string(),
            source,
        };
        let socket = UdpSocket::bind(address).map_err(err)?;
        socket.set_read_timeout(Some(POLL)).map_err(err)?;
        let address = socket.local_addr().map_err(err)?;
        Ok(ArduPilotServer { socket, address })
    }

    /// The bound address.
    pub fn local_addr(&self) -> SocketAddr {
        self.address
    }

    /// Serve ArduPilot's frames with `scenario` (prepared) as the physics,
    /// its servo outputs read through `map`, until the stop flag, the
    /// silence timeout, the frame limit or the simulation's end.
    #[allow(clippy::too_many_lines)] // one loop: receive, classify, step, answer
    pub fn run(
        &self,
        scenario: &Scenario,
        prepared: &Prepared,
        map: &ArduPilotMap,
        options: &ArduPilotOptions,
    ) -> Result<ArduPilotReport, ArduPilotError> {
        let sock_err = |source| ArduPilotError::Socket {
            address: self.address.to_string(),
            source,
        };
        let g = prepared.model.params().environment.g_m_s2;
        // home on the ground below the simulator's origin (the design point)
        let ground_down_m = crate::lockstep::ground_down_m(prepared);
        let log_csv = crate::lockstep::log_path(options.out_dir.as_deref()).map_err(|(d, e)| {
            ArduPilotError::Folder {
                path: d.display().to_string(),
                source: e,
            }
        })?;
        let mut counts = Counts::default();
        let mut session: Option<Session<'_>> = None;
        let mut rate_hz: u16 = 0;
        let mut last_count: Option<u32> = None;
        let mut last_state: Option<PhysicsState> = None;
        let mut reply = String::with_capacity(512);
        let mut buf = [0u8; 512];
        let mut peer = None;
        let mut first_packet: Option<Instant> = None;
        let mut last_reply_at: Option<Instant> = None;
        let mut last_valid = Instant::now();
        let mut model_time_all = 0.0;
        let stop = || crate::lockstep::stopped(options.stop.as_ref());
        let ending = loop {
            if stop() {
                break Ending::Stopped;
            }
            if options
                .silence_timeout
                .is_some_and(|t| last_valid.elapsed() >= t)
            {
                break Ending::Silent;
            }
            let (n, from) = match self.socket.recv_from(&mut buf) {
                Ok(x) => x,
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
                // a previous reply's peer gone (ICMP port unreachable): not ours to end on
                Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => continue,
                Err(e) => return Err(sock_err(e)),
            };
            let pkt = match parse_servo_packet(&buf[..n]) {
                Ok(p) => p,
                Err(e) => {
                    counts.count(&e);
                    continue;
                }
            };
            last_valid = Instant::now();
            first_packet.get_or_insert(last_valid);
            peer = Some(from);
            let c = pkt.frame_count;
            let repeat = last_count == Some(c);
            let restart = last_count.is_some_and(|l| c < l);
            if restart {
                counts.restarts += 1;
                if let Some(s) = session.take() {
                    // the log starts afresh with the new session
                    model_time_all += s.restart()?;
                }
            }
            if !repeat {
                if last_count.is_some_and(|l| c > l.wrapping_add(1)) && !restart {
                    counts.gaps += 1;
                }
                if session.is_none() {
                    rate_hz = pkt.frame_rate_hz;
                    session = Some(Session::new(
                        scenario,
                        prepared,
                        1.0 / f64::from(rate_hz),
                        log_csv.as_deref(),
                        options.log_stride,
                    )?);
                }
                let Some(s) = session.as_mut() else {
                    continue;
                };
                if pkt.frame_rate_hz != rate_hz {
                    counts.rate_mismatches += 1;
                }
                let d = map.decode(pkt.pwm());
                let end = s.step(&d.input, d.engine_on)?;
                counts.frames += 1;
                last_count = Some(c);
                let mut state = state_of(s, g, ground_down_m);
                if s.now.is_none() {
                    // the flight ended in this step: the last state answered is its end
                    let x = s.hw.state();
                    state.position_ned_m = [
                        x[helicon_model::state::ix::X],
                        x[helicon_model::state::ix::Y],
                        x[helicon_model::state::ix::Z] - ground_down_m,
                    ];
                    state.attitude_rad = [
                        x[helicon_model::state::ix::PHI],
                        x[helicon_model::state::ix::THETA],
                        x[helicon_model::state::ix::PSI],
                    ];
                }
                last_state = Some(state);
                if let Some((kind, why)) = end {
                    if state.is_finite() {
                        state.write_json(&mut reply);
                        let _ = self.socket.send_to(reply.as_bytes(), from);
                        counts.replies += 1;
                    }
                    last_reply_at = Some(Instant::now());
                    break Ending::Simulation(kind, why);
                }
                if options.max_frames.is_some_and(|m| counts.frames >= m) {
                    state.write_json(&mut reply);
                    self.socket
                        .send_to(reply.as_bytes(), from)
                        .map_err(sock_err)?;
                    counts.replies += 1;
                    last_reply_at = Some(Instant::now());
                    break Ending::FrameLimit;
                }
                state.write_json(&mut reply);
            } else {
                counts.repeats += 1;
                match &last_state {
                    Some(st) => st.write_json(&mut reply),
                    None => continue,
                }
            }
            match self.socket.send_to(reply.as_bytes(), from) {
                Ok(_) => counts.replies += 1,
                Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => {}
                Err(e) => return Err(sock_err(e)),
            }
            last_reply_at = Some(Instant::now());
        };
        let wall_s = match (first_packet, last_reply_at) {
            (Some(a), Some(b)) => b.duration_since(a).as_secs_f64(),
            _ => 0.0,
        };
        let (frame_rate_hz, session_frames, model_time_s, final_state, rotor, summary, rows) =
            match session {
                Some(s) => {
                    let c = s.close(ending.abort_reason())?;
                    (
                        Some(rate_hz),
                        c.frames,
                        c.model_time_s,
                        Some(c.final_state),
                        Some(c.rotor_speed_rad_s),
                        Some(c.summary),
                        c.rows,
                    )
                }
                None => (None, 0, 0.0, None, None, None, 0),
            };
        model_time_all += model_time_s;
        Ok(ArduPilotReport {
            counts,
            ending,
            frame_rate_hz,
            session_frames,
            model_time_s,
            wall_s,
            frames_per_s: if wall_s > 0.0 {
                counts.frames as f64 / wall_s
            } else {
                0.0
            },
            speed_x: if wall_s > 0.0 {
                model_time_all / wall_s
            } else {
                0.0
            },
            last_state,
            final_state,
            rotor_speed_rad_s: rotor,
            summary,
            log_csv: if rows > 0 { log_csv } else { None },
            log_rows: rows,
            peer,
        })
    }
}

/// `timing.json` of an ArduPilot JSON run.
pub fn timing_json(r: &ArduPilotReport) -> serde_json::Value {
    serde_json::json!({
        "backend": "ardupilot-json",
        "frame_rate_hz": r.frame_rate_hz,
        "frames": r.counts.frames,
        "session_frames": r.session_frames,
        "model_time_s": r.model_time_s,
        "wall_s": r.wall_s,
        "frames_per_s": r.frames_per_s,
        "speed_x_realtime": r.speed_x,
        "counts": r.counts,
        "malformed": r.counts.malformed(),
    })
}

/// The state ArduPilot reads of `s` now (`g` gravity, the home
/// `ground_down_m` below the simulator's origin).
fn state_of(s: &Session<'_>, g: f64, ground_down_m: f64) -> PhysicsState {
    let t = s.time_s();
    match &s.now {
        Some(now) => {
            let tr = &now.truth;
            let f = tr.specific_force_body(g);
            PhysicsState {
                timestamp_s: t,
                gyro_rad_s: tr.omega_body_rad_s.into(),
                accel_body_m_s2: f.into(),
                position_ned_m: [
                    tr.pos_ned_m.x,
                    tr.pos_ned_m.y,
                    tr.pos_ned_m.z - ground_down_m,
                ],
                velocity_ned_m_s: tr.vel_ned_m_s.into(),
                attitude_rad: tr.euler_rad.into(),
            }
        }
        None => PhysicsState {
            timestamp_s: t,
            ..PhysicsState::default()
        },
    }
}
