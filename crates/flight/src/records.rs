//! What the runtime logs: the ULog records of `helicon-ulog`'s on-board
//! message set, plus the supervisor's events with their precise reason,
//! carried to the logger thread through lock-free rings (all `Copy`).

use crate::control::{ControlOutput, ImuHealthChange, Tick};
use crate::plausibility::Rejection;
use crate::ports::DeviceEvent;
use crate::safety::{Mode, RcInput, RcLink, Reason, SafetyEvent};
use helicon_core::imu_health::ImuHealth;
use helicon_ulog::messages::{
    Control, EstimatorBias, Excitation, Failsafe, FailsafeReason, FlightMode,
    ImuHealth as ImuHealthRecord, Mode as ModeRecord, Navigation, RcInput as RcRecord, ServoOutput,
    Timing,
};
use helicon_ulog::{FlightLog, LogLevel, LogRecord, WriteError, px4, timestamp_us};
use std::io::Write;

/// One item of a logger ring.
#[derive(Debug, Clone, Copy, PartialEq)]
#[allow(clippy::large_enum_variant)] // ring items stay inline: boxing would allocate per record
pub enum FlightRecord {
    /// A record of the message set.
    Log(LogRecord),
    /// A change of mode (written as `mode`, `failsafe` when it raises or
    /// clears one, and one text message naming the precise reason).
    Event(SafetyEvent),
    /// The IMU health's flags changed (written as a text message: a
    /// warning when a flag is raised).
    ImuHealth {
        /// On-board time (s).
        t_s: f64,
        /// The change.
        change: ImuHealthChange,
    },
    /// The pilot's link lost (the receiver's failsafe flag, or its
    /// silence) or back (written as a text message).
    RcLink {
        /// On-board time (s).
        t_s: f64,
        /// The new state: lost (the receiver's failsafe or its silence) or
        /// back.
        link: RcLink,
    },
    /// The watchdog commanded the trim: the control task was silent for
    /// this long (s).
    Watchdog {
        /// On-board time (s).
        t_s: f64,
        /// Silence (s).
        silent_s: f64,
    },
    /// Sensor samples refused by the plausibility gate (or the navigation's
    /// innovation gate): the count of the kind so far, logged at the first
    /// and at each doubling.
    SensorRejected {
        /// On-board time (s).
        t_s: f64,
        /// What was refused.
        kind: Rejection,
        /// Refusals of the kind so far.
        count: u64,
    },
    /// A device's port failed (read error, end of file, hang-up) or came
    /// back: `lost` names the error's kind.
    Device {
        /// On-board time (s).
        t_s: f64,
        /// The device and what happened.
        event: DeviceEvent,
    },
    /// The avionics port dropped servo frames, its output buffer full (the
    /// line slower than the frames, the board not reading): the count so
    /// far, logged at the first drop and at each doubling.
    ServoDropped {
        /// On-board time (s).
        t_s: f64,
        /// Frames dropped so far.
        dropped: u64,
    },
}

/// The flight log's initial parameters: the control period
/// (`HC_CTRL_DT_S`, s) and the ground station's table (`table`, empty
/// without one; [`crate::ground::initial_parameters`]).
pub fn log_parameters(sample_time_s: f64, table: &[(&'static str, f32)]) -> Vec<(String, f32)> {
    std::iter::once(("HC_CTRL_DT_S", sample_time_s as f32))
        .chain(table.iter().copied())
        .map(|(n, v)| (n.to_string(), v))
        .collect()
}

/// PX4's `vehicle_status` of a supervisor mode: armed or not, the
/// navigation state (hold: loiter, descent: descend, IMU lost: termination,
/// the servos at the trim in open loop) and whether a failsafe acts.
pub fn status_mode(m: Mode) -> px4::StatusMode {
    let (nav_state, failsafe) = match m {
        Mode::Disarmed | Mode::Auto => (px4::NAV_STATE_AUTO_MISSION, false),
        Mode::Manual => (px4::NAV_STATE_MANUAL, false),
        Mode::Hold => (px4::NAV_STATE_AUTO_LOITER, true),
        Mode::Descent => (px4::NAV_STATE_DESCEND, true),
        Mode::ImuLost => (px4::NAV_STATE_TERMINATION, true),
    };
    px4::StatusMode {
        arming_state: if m == Mode::Disarmed {
            px4::ARMING_STATE_DISARMED
        } else {
            px4::ARMING_STATE_ARMED
        },
        nav_state,
        failsafe,
    }
}

/// The log's flight mode of a supervisor mode.
pub fn flight_mode(m: Mode) -> FlightMode {
    match m {
        Mode::Disarmed => FlightMode::Standby,
        Mode::Auto => FlightMode::Automatic,
        Mode::Manual => FlightMode::Manual,
        Mode::Hold | Mode::Descent | Mode::ImuLost => FlightMode::Failsafe,
    }
}

/// The log's failsafe reason code of a supervisor reason (`None`: not a
/// failsafe).
pub fn failsafe_reason(r: Reason) -> Option<FailsafeReason> {
    match r {
        Reason::ImuStale | Reason::GpsStale | Reason::MagStale | Reason::ImuRecovered => {
            Some(FailsafeReason::SensorTimeout)
        }
        Reason::Overrun => Some(FailsafeReason::DeadlineMiss),
        Reason::NavigationFailure => Some(FailsafeReason::NavigationFailure),
        Reason::PilotManual | Reason::PilotAuto => Some(FailsafeReason::Pilot),
        Reason::RcLost => Some(FailsafeReason::RcLoss),
        Reason::ImuRejected | Reason::GpsRejected | Reason::MagRejected => {
            Some(FailsafeReason::SensorImplausible)
        }
        Reason::Armed | Reason::Disarmed | Reason::HoldElapsed | Reason::Kill => None,
    }
}

fn is_failsafe(m: Mode) -> bool {
    matches!(m, Mode::Hold | Mode::Descent | Mode::ImuLost)
}

/// A short text on the stack (no allocation).
struct Text {
    buf: [u8; 160],
    len: usize,
}

impl std::fmt::Write for Text {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        let n = s.len().min(self.buf.len() - self.len);
        self.buf[self.len..self.len + n].copy_from_slice(&s.as_bytes()[..n]);
        self.len += n;
        Ok(())
    }
}

/// Format a text on the stack and write it to the log at `level` (no
/// allocation; `fallback` if the formatted text is cut inside a character).
fn log_fmt<W: Write>(
    log: &mut FlightLog<W>,
    level: LogLevel,
    ts: u64,
    args: std::fmt::Arguments<'_>,
    fallback: &str,
) -> Result<(), WriteError> {
    let mut text = Text {
        buf: [0; 160],
        len: 0,
    };
    let _ = std::fmt::Write::write_fmt(&mut text, args);
    let s = std::str::from_utf8(&text.buf[..text.len]).unwrap_or(fallback);
    log.writer_mut().log(level, ts, s)
}

/// Write one ring item to the flight log (no allocation).
pub fn write_record<W: Write>(log: &mut FlightLog<W>, r: &FlightRecord) -> Result<(), WriteError> {
    match r {
        FlightRecord::Log(x) => log.write(x),
        FlightRecord::Event(ev) => {
            let ts = timestamp_us(ev.t_s, "mode change")?;
            // the records' data only (and PX4's vehicle_status): the text
            // below is the event's one text (FlightLog::write would add a
            // generic one of its own)
            log.write_mode(
                &ModeRecord {
                    timestamp: ts,
                    mode: flight_mode(ev.to) as u8,
                    previous: flight_mode(ev.from) as u8,
                },
                status_mode(ev.to),
            )?;
            let raised = is_failsafe(ev.to) && !is_failsafe(ev.from);
            let cleared = is_failsafe(ev.from) && !is_failsafe(ev.to);
            if let Some(code) = failsafe_reason(ev.reason)
                && (raised || cleared)
            {
                log.write_data(&LogRecord::Failsafe(Failsafe {
                    timestamp: ts,
                    reason: code as u8,
                    active: raised,
                }))?;
            }
            let level = if is_failsafe(ev.to) {
                LogLevel::Critical
            } else {
                LogLevel::Notice
            };
            log_fmt(
                log,
                level,
                ts,
                format_args!(
                    "{}: {} -> {} at t = {:.4} s",
                    ev.reason.as_str(),
                    ev.from.as_str(),
                    ev.to.as_str(),
                    ev.t_s
                ),
                "mode change",
            )
        }
        FlightRecord::ImuHealth { t_s, change } => {
            let ts = timestamp_us(*t_s, "imu health")?;
            let level = if change.flags & ImuHealth::GRAVITY_DEFICIT != 0 {
                LogLevel::Critical
            } else if change.flags & !change.previous != 0 {
                LogLevel::Warning
            } else {
                LogLevel::Notice
            };
            log_fmt(
                log,
                level,
                ts,
                format_args!(
                    "imu_health: flags {} -> {} at t = {t_s:.4} s: {}",
                    change.previous,
                    change.flags,
                    change.text()
                ),
                "imu health",
            )
        }
        FlightRecord::RcLink { t_s, link } => {
            let ts = timestamp_us(*t_s, "rc link")?;
            let level = if link.is_lost() {
                LogLevel::Critical
            } else {
                LogLevel::Notice
            };
            log_fmt(
                log,
                level,
                ts,
                format_args!("rc_link: {}", link.text()),
                "rc_link",
            )
        }
        FlightRecord::SensorRejected { t_s, kind, count } => {
            let ts = timestamp_us(*t_s, "sensor rejected")?;
            log_fmt(
                log,
                LogLevel::Warning,
                ts,
                format_args!(
                    "plausibility: {} ({count} so far) at t = {t_s:.4} s",
                    kind.text()
                ),
                "plausibility: sample refused",
            )
        }
        FlightRecord::Device { t_s, event } => {
            let ts = timestamp_us(*t_s, "device")?;
            let level = if event.lost {
                LogLevel::Critical
            } else {
                LogLevel::Notice
            };
            log_fmt(
                log,
                level,
                ts,
                format_args!("device: {} at t = {t_s:.4} s", event.text()),
                "device",
            )
        }
        FlightRecord::ServoDropped { t_s, dropped } => {
            let ts = timestamp_us(*t_s, "servo drop")?;
            log_fmt(
                log,
                LogLevel::Warning,
                ts,
                format_args!(
                    "avionics: {dropped} servo frame(s) dropped so far: the port's output buffer is full"
                ),
                "avionics: servo frames dropped",
            )
        }
        FlightRecord::Watchdog { t_s, silent_s } => {
            let ts = timestamp_us(*t_s, "watchdog")?;
            log_fmt(
                log,
                LogLevel::Emergency,
                ts,
                format_args!("watchdog: control task silent for {silent_s:.4} s: servos at trim"),
                "watchdog",
            )
        }
    }
}

/// Everything one control step logs, handed to `push` in order: the frame
/// (`sensor_imu`, `helicon_mag`, `helicon_gps`), the receiver's frame, the
/// change of mode, the IMU health (`imu_health`, and its change of flags),
/// the control step (`control`, `navigation`, `estimator_bias` when the
/// navigation estimates the IMU biases, `excitation` when the mission has
/// one), the servo command and the
/// timing. No allocation.
pub fn step_records(
    tick: &Tick,
    out: &ControlOutput,
    timing: Timing,
    push: &mut impl FnMut(FlightRecord),
) -> Result<(), WriteError> {
    let ts = timestamp_us(tick.now_s, "control step")?;
    if let Some(f) = &tick.frame {
        let (imu, mag, gps) = helicon_ulog::messages::frame_records(f)?;
        push(FlightRecord::Log(LogRecord::Imu(imu)));
        if let Some(m) = mag {
            push(FlightRecord::Log(LogRecord::Mag(m)));
        }
        if let Some(g) = gps {
            push(FlightRecord::Log(LogRecord::Gps(g)));
        }
    }
    if let Some(rc) = &tick.rc {
        push(FlightRecord::Log(LogRecord::Rc(rc_record(ts, rc))));
    }
    if let Some(link) = out.rc_link_change {
        push(FlightRecord::RcLink {
            t_s: tick.now_s,
            link,
        });
    }
    if let Some(ev) = out.event {
        push(FlightRecord::Event(ev));
    }
    if let (Some(f), Some(h)) = (&tick.frame, &out.imu_health) {
        push(FlightRecord::Log(LogRecord::ImuHealth(ImuHealthRecord {
            timestamp: timestamp_us(f.t_s, "imu_health")?,
            vibration_rms_m_s2: h.vibration_rms_m_s2,
            gravity_residual_m_s2: h.gravity_residual_m_s2,
            peak_fraction: h.peak_fraction,
            flags: h.flags,
        })));
    }
    if let Some((kind, count)) = out.rejection {
        push(FlightRecord::SensorRejected {
            t_s: tick.now_s,
            kind,
            count,
        });
    }
    if let Some(change) = out.imu_health_change {
        push(FlightRecord::ImuHealth {
            t_s: tick.now_s,
            change,
        });
    }
    if let Some(t) = &out.telemetry {
        push(FlightRecord::Log(LogRecord::Control(
            Control::from_telemetry(t)?,
        )));
        if let Some(n) = &t.navigation {
            push(FlightRecord::Log(LogRecord::Navigation(
                Navigation::from_solution(t.t_s, n)?,
            )));
            if let Some(b) = &n.imu_bias {
                push(FlightRecord::Log(LogRecord::EstimatorBias(
                    EstimatorBias::from_estimate(t.t_s, b)?,
                )));
            }
        }
        if let Some((offset, active)) = out.excitation {
            push(FlightRecord::Log(LogRecord::Excitation(Excitation {
                timestamp: ts,
                offset: offset.into(),
                active,
            })));
        }
    }
    push(FlightRecord::Log(LogRecord::Servo(ServoOutput {
        timestamp: ts,
        command: out.servo.into(),
        source: match out.mode {
            Mode::Auto => 0,
            Mode::Manual => 1,
            _ => 2,
        },
    })));
    push(FlightRecord::Log(LogRecord::Timing(timing)));
    Ok(())
}

/// The receiver's frame as a log record: the sticks in the first four
/// channels as pulse widths (the receiver's mapping,
/// [`crate::ports::stick_us`]).
fn rc_record(ts: u64, rc: &RcInput) -> RcRecord {
    let mut channels_us = [0u16; 16];
    for i in 0..4 {
        channels_us[i] = crate::ports::stick_us(rc.servo[i]);
    }
    RcRecord {
        timestamp: ts,
        channels_us,
        channel_count: 4,
        manual_switch: rc.manual,
        signal_lost: rc.failsafe,
    }
}
