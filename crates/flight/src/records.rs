//! What the runtime logs: the ULog records of `helicon-ulog`'s on-board
//! message set, plus the supervisor's events with their precise reason,
//! carried to the logger thread through lock-free rings (all `Copy`).

use crate::control::{ControlOutput, DISARM_REFUSED_TEXT, ImuHealthChange, RC_REFUSED_TEXT, Tick};
use crate::landing::{LandStage, LandingStep, SpoolState};
use crate::mission::NavigatorNews;
use crate::plausibility::Rejection;
use crate::ports::DeviceEvent;
use crate::safety::{Mode, RcInput, RcLink, Reason, SafetyEvent};
use helicon_core::imu_health::ImuHealth;
use helicon_gcs::navigator::{NavEvent, NavMode};
use helicon_gcs::params::ParamTable;
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
    /// Receiver frames refused (a channel outside the receiver's range):
    /// the count so far, logged at the first and at each doubling.
    RcRefused {
        /// On-board time (s).
        t_s: f64,
        /// Frames refused so far.
        count: u64,
    },
    /// The receiver's arm switch moved to off in flight: refused (only the
    /// kill channel disarms in flight), the helicopter flies on.
    DisarmRefused {
        /// On-board time (s).
        t_s: f64,
        /// Refusals so far.
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
    /// What the ground station's navigator did (its mode changes and
    /// events as text and PX4's `vehicle_status`; a tuning the operator set
    /// as parameter changes).
    Navigator {
        /// On-board time (s).
        t_s: f64,
        /// The events and the tuning.
        news: NavigatorNews,
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
    /// The ground logic's state changed (written as a text message).
    Spool {
        /// On-board time (s).
        t_s: f64,
        /// The state before.
        from: SpoolState,
        /// The state now.
        to: SpoolState,
        /// A take-off given up (no lift-off).
        aborted: bool,
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
        Reason::Armed | Reason::Disarmed | Reason::HoldElapsed | Reason::Kill | Reason::Landed => {
            None
        }
    }
}

/// A change of the ground logic's state, as a log text (a warning when a
/// take-off was given up).
fn write_spool<W: Write>(
    log: &mut FlightLog<W>,
    t_s: f64,
    from: SpoolState,
    to: SpoolState,
    aborted: bool,
) -> Result<(), WriteError> {
    let ts = timestamp_us(t_s, "ground state")?;
    let (level, why) = if aborted {
        (LogLevel::Warning, ": no lift-off, take-off given up")
    } else {
        (LogLevel::Info, "")
    };
    log_fmt(
        log,
        level,
        ts,
        format_args!("ground: {} -> {}{why}", from.as_str(), to.as_str()),
        "ground: state changed",
    )
}

/// PX4's `vehicle_land_detected` of the ground logic's step.
fn land_detected(ts: u64, l: &LandingStep) -> px4::VehicleLandDetected {
    let f = l.flags;
    px4::VehicleLandDetected {
        timestamp: ts,
        ground_contact: l.stage == LandStage::GroundContact,
        maybe_landed: l.stage == LandStage::MaybeLanded,
        landed: l.stage == LandStage::Landed,
        in_descend: f.descending,
        has_low_throttle: f.low_collective,
        vertical_movement: f.vertical_movement,
        horizontal_movement: f.horizontal_movement,
        rotational_movement: f.rotating,
        close_to_ground_or_skipped_check: true,
        at_rest: l.stage == LandStage::Landed,
        ..px4::VehicleLandDetected::default()
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

/// A supervisor event: `mode` and PX4's `vehicle_status`, `failsafe` when
/// it raises or clears one, and one text naming the precise reason.
fn write_event<W: Write>(log: &mut FlightLog<W>, ev: &SafetyEvent) -> Result<(), WriteError> {
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

/// Write one ring item to the flight log (no allocation).
#[allow(clippy::too_many_lines)] // one arm per record kind
pub fn write_record<W: Write>(log: &mut FlightLog<W>, r: &FlightRecord) -> Result<(), WriteError> {
    match r {
        FlightRecord::Log(x) => log.write(x),
        FlightRecord::Event(ev) => write_event(log, ev),
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
        FlightRecord::RcRefused { t_s, count } => {
            let ts = timestamp_us(*t_s, "rc refused")?;
            log_fmt(
                log,
                LogLevel::Warning,
                ts,
                format_args!("rc_input: {RC_REFUSED_TEXT} ({count} so far) at t = {t_s:.4} s"),
                "rc_input: frame refused",
            )
        }
        FlightRecord::DisarmRefused { t_s, count } => {
            let ts = timestamp_us(*t_s, "disarm refused")?;
            log_fmt(
                log,
                LogLevel::Warning,
                ts,
                format_args!("rc_input: {DISARM_REFUSED_TEXT} ({count} so far) at t = {t_s:.4} s"),
                "rc_input: disarm refused",
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
        FlightRecord::Spool {
            t_s,
            from,
            to,
            aborted,
        } => write_spool(log, *t_s, *from, *to, *aborted),
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
        FlightRecord::Navigator { t_s, news } => write_navigator(log, *t_s, news),
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

/// ULog's level of a MAVLink `MAV_SEVERITY` (the same syslog scale,
/// 0 emergency … 7 debug).
fn level_of_severity(severity: u8) -> LogLevel {
    LogLevel::from_byte(severity.min(7)).unwrap_or(LogLevel::Info)
}

/// PX4's navigation state of a navigator mode.
pub fn nav_state(m: NavMode) -> u8 {
    match m {
        NavMode::Idle | NavMode::Hold => px4::NAV_STATE_AUTO_LOITER,
        NavMode::Takeoff => px4::NAV_STATE_AUTO_TAKEOFF,
        NavMode::Mission => px4::NAV_STATE_AUTO_MISSION,
        NavMode::Return => px4::NAV_STATE_AUTO_RTL,
        NavMode::Land => px4::NAV_STATE_AUTO_LAND,
        NavMode::Guided => px4::NAV_STATE_OFFBOARD,
    }
}

/// The navigator's events as texts (and its mode as PX4's
/// `vehicle_status`), the operator's tuning as parameter changes (each
/// value of the parameter table that changed). No allocation.
fn write_navigator<W: Write>(
    log: &mut FlightLog<W>,
    t_s: f64,
    news: &NavigatorNews,
) -> Result<(), WriteError> {
    let ts = timestamp_us(t_s, "navigator")?;
    for e in news.events.iter() {
        let (level, what) = match e {
            NavEvent::Mode(m) => {
                log.write_navigator_state(ts, nav_state(m))?;
                (LogLevel::Info, m.as_str())
            }
            NavEvent::Current(_) => (LogLevel::Info, "next mission item"),
            NavEvent::Reached(_) => (LogLevel::Info, "mission item reached"),
            NavEvent::Landed => (LogLevel::Notice, "landed"),
            NavEvent::LinkLost => (LogLevel::Critical, "ground station link lost"),
            NavEvent::LinkRegained => (LogLevel::Notice, "ground station link back"),
            NavEvent::FenceBreach(true) => (LogLevel::Critical, "fence breached (horizontal)"),
            NavEvent::FenceBreach(false) => (LogLevel::Critical, "fence breached (height)"),
        };
        match e {
            NavEvent::Current(seq) | NavEvent::Reached(seq) => log_fmt(
                log,
                level,
                ts,
                format_args!("navigator: {what}: {seq} at t = {t_s:.4} s"),
                "navigator",
            )?,
            NavEvent::Mode(_) => log_fmt(
                log,
                level,
                ts,
                format_args!("navigator: mode {what} at t = {t_s:.4} s"),
                "navigator",
            )?,
            _ => log_fmt(
                log,
                level,
                ts,
                format_args!("navigator: {what} at t = {t_s:.4} s"),
                "navigator",
            )?,
        }
    }
    for t in news.texts.iter() {
        log_fmt(
            log,
            level_of_severity(t.severity),
            ts,
            format_args!("gcs: {}", t.as_str()),
            "gcs",
        )?;
    }
    if news.texts.dropped > 0 {
        log_fmt(
            log,
            LogLevel::Warning,
            ts,
            format_args!(
                "gcs: {} more texts at t = {t_s:.4} s not logged",
                news.texts.dropped
            ),
            "gcs",
        )?;
    }
    if let Some((before, after)) = &news.config_change {
        let (old, new) = (ParamTable::new(*before), ParamTable::new(*after));
        for i in 0..new.len() {
            if let (Some((_, a)), Some((name, b))) = (old.get(i), new.get(i))
                && a.to_bits() != b.to_bits()
            {
                log.parameter_changed(name, b, ts)?;
            }
        }
    }
    Ok(())
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
    if let Some(l) = &out.landing {
        if let Some((from, to)) = l.change {
            push(FlightRecord::Spool {
                t_s: tick.now_s,
                from,
                to,
                aborted: l.takeoff_aborted,
            });
        }
        if l.report {
            push(FlightRecord::Log(LogRecord::LandDetected(land_detected(
                ts, l,
            ))));
        }
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
    if let Some(count) = out.rc_refusal {
        push(FlightRecord::RcRefused {
            t_s: tick.now_s,
            count,
        });
    }
    if let Some(count) = out.disarm_refusal {
        push(FlightRecord::DisarmRefused {
            t_s: tick.now_s,
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

#[cfg(test)]
mod tests {
    use super::*;
    use helicon_gcs::navigator::{Events, NavigatorConfig};
    use helicon_ulog::px4::{NAV_STATE_AUTO_RTL, VehicleStatus};
    use helicon_ulog::reader::{Message, UlogReader};
    use helicon_ulog::{FlushPolicy, LogInfo, Record};

    /// The navigator's mode, events and the operator's tuning reach the
    /// log: texts at their levels, `vehicle_status.nav_state`, and a
    /// parameter change for the one value set.
    #[test]
    fn navigator_news_is_logged() {
        let mut log =
            FlightLog::new(Vec::new(), &LogInfo::default(), FlushPolicy::default()).expect("log");
        let armed = SafetyEvent {
            t_s: 0.5,
            from: Mode::Disarmed,
            to: Mode::Auto,
            reason: Reason::Armed,
        };
        write_record(&mut log, &FlightRecord::Event(armed)).expect("event");
        let mut events = Events::default();
        events.push(NavEvent::Mode(NavMode::Return));
        events.push(NavEvent::Reached(2));
        events.push(NavEvent::LinkLost);
        let before = NavigatorConfig::default();
        let mut table = ParamTable::new(before);
        table.set("NAV_CRUISE_SPD", 1.25).expect("a valid speed");
        let mut texts = helicon_gcs::link::OperatorTexts::default();
        texts.push(helicon_gcs::link::OperatorText::new(
            4,
            "refused: not armed",
        ));
        let news = NavigatorNews {
            events,
            config_change: Some((before, *table.config())),
            texts,
        };
        write_record(&mut log, &FlightRecord::Navigator { t_s: 1.0, news }).expect("news");
        let bytes = log.finish().expect("finish");
        let mut r = UlogReader::new(&bytes[..], "t").expect("reader");
        let (mut texts, mut params, mut status) = (Vec::new(), Vec::new(), None);
        let mut status_id = None;
        while let Some(m) = r.next_message().expect("message") {
            match m {
                Message::AddLogged { msg_id, name, .. } if name == VehicleStatus::NAME => {
                    status_id = Some(msg_id);
                }
                Message::Data { msg_id, payload } if Some(msg_id) == status_id => {
                    status = VehicleStatus::decode(payload);
                }
                Message::Logging { level, text, .. } => texts.push((level, text)),
                Message::Parameter(kv) => params.push((kv.name.clone(), kv.value.to_string())),
                _ => {}
            }
        }
        let status = status.expect("a vehicle_status");
        assert_eq!(status.nav_state, NAV_STATE_AUTO_RTL);
        assert_eq!(status.nav_state_user_intention, NAV_STATE_AUTO_RTL);
        assert_eq!(status.arming_state, px4::ARMING_STATE_ARMED);
        let has = |level: LogLevel, s: &str| {
            texts
                .iter()
                .any(|(l, t)| *l == Some(level) && t.starts_with(s))
        };
        assert!(
            has(LogLevel::Info, "navigator: mode RETURN at t = 1.0000 s"),
            "{texts:?}"
        );
        // the server's own text, at its severity (MAV_SEVERITY_WARNING)
        assert!(
            has(LogLevel::Warning, "gcs: refused: not armed"),
            "{texts:?}"
        );
        assert!(
            has(LogLevel::Info, "navigator: mission item reached: 2"),
            "{texts:?}"
        );
        assert!(
            has(LogLevel::Critical, "navigator: ground station link lost"),
            "{texts:?}"
        );
        assert!(
            has(LogLevel::Info, "parameter NAV_CRUISE_SPD = 1.25"),
            "{texts:?}"
        );
        assert_eq!(
            params,
            vec![("NAV_CRUISE_SPD".to_string(), "1.25".to_string())]
        );
    }
}
