//! The control task's work for one sample, independent of how it is paced
//! (a 400 Hz clock on board, sensor arrival in lock-step SITL): the safety
//! supervisor decides the mode, the flight computer (the very
//! `SensorComputer` `helicon sim` flies) computes the law, the mode
//! picks what goes to the servos. Allocation-free.

use crate::landing::{Landing, LandingInput, LandingStep};
use crate::plausibility::{GpsQuality, Rejection, SensorGate};
use crate::safety::{Health, Mode, RcInput, RcLink, SafetyEvent, Supervisor};
use helicon_core::ServoLimits;
use helicon_core::imu_health::{ImuHealth, ImuHealthMonitor};
use helicon_core::state::Input;
use helicon_core::{Reference, SensorComputer, SensorFrame, Telemetry};
use helicon_setup::excitation::Excitations;

/// What the control task is given for one sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tick {
    /// On-board time now (s).
    pub now_s: f64,
    /// The fresh sensor frame of this sample (`None`: no new IMU sample
    /// arrived by the deadline).
    pub frame: Option<SensorFrame>,
    /// The previous sample missed its deadline.
    pub deadline_missed: bool,
    /// The receiver's latest frame, when a new one arrived.
    pub rc: Option<RcInput>,
    /// The mission's reference now.
    pub reference: Reference,
    /// The GPS receiver's own report of the frame's fix (satellites,
    /// accuracies), when it gives one.
    pub gps_quality: Option<GpsQuality>,
}

/// What the control task decided.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlOutput {
    /// The servo commands to send.
    pub servo: Input,
    /// Who decided them: the law, the pilot, or the trim.
    pub mode: Mode,
    /// The flight computer's record of the sample (when it ran).
    pub telemetry: Option<Telemetry>,
    /// A change of mode this sample.
    pub event: Option<SafetyEvent>,
    /// The flight-test excitation of the sample, when the mission has one
    /// and the flight computer ran: the offset added to the law's command
    /// (zeros when not applied) and whether it runs.
    pub excitation: Option<(Input, bool)>,
    /// The IMU health monitor after this sample's IMU sample (when it runs
    /// and a sample came).
    pub imu_health: Option<ImuHealth>,
    /// The IMU health's flags changed this sample (settling aside).
    pub imu_health_change: Option<ImuHealthChange>,
    /// The pilot's link was lost or came back this sample: its new state
    /// ([`RcLink::Failsafe`] or [`RcLink::Silent`]: lost, and how;
    /// [`RcLink::Ok`]: back).
    pub rc_link_change: Option<RcLink>,
    /// A sample refused this step, with the count of its kind so far, when
    /// that count is 1 or a power of two (the log's and the operator's
    /// text: the first and each doubling, never one per sample).
    pub rejection: Option<(Rejection, u64)>,
    /// A receiver frame refused this step (a channel outside the
    /// receiver's range: its sticks and switches are not used), with the
    /// frames refused so far, when that count is 1 or a power of two (as
    /// [`ControlOutput::rejection`]: the first and each doubling).
    pub rc_refusal: Option<u64>,
    /// The receiver's arm switch moved to off in flight this step and was
    /// refused (only the kill channel disarms in flight), with the refusals
    /// so far: the log's and the operator's [`DISARM_REFUSED_TEXT`].
    pub disarm_refusal: Option<u64>,
    /// The engine is cut (the servo frame's throttle hold): on the ground
    /// disarmed, with the ground logic ([`ControlTask::with_landing`]);
    /// never without it.
    pub throttle_hold: bool,
    /// The ground logic's step, when the task has it.
    pub landing: Option<LandingStep>,
}

/// The operator's text of refused receiver frames (at most 50 bytes: one
/// MAVLink STATUSTEXT).
pub const RC_REFUSED_TEXT: &str = "RC: channel out of range, frame refused";

/// The operator's text of an arm switch moved to off in flight (at most 50
/// bytes: one MAVLink STATUSTEXT): refused, the helicopter flies on.
pub const DISARM_REFUSED_TEXT: &str = "RC: disarm refused in flight (kill channel only)";

/// Whether the `count`-th refusal of a kind is told (logged, sent to the
/// ground station): the first and each doubling, never one per sample.
fn worth_a_text(count: u64) -> bool {
    count.is_power_of_two()
}

/// A change of the IMU health monitor's flags (the settling flag aside):
/// the supervisor logs it (a warning when a flag is raised) and tells the
/// ground station; the mode does not change.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImuHealthChange {
    /// The flags before.
    pub previous: u8,
    /// The flags now ([`ImuHealth::VIBRATION`], …).
    pub flags: u8,
}

impl ImuHealthChange {
    /// The operator's text for the change: the most severe flag raised,
    /// or that the IMU is healthy again (at most 50 bytes: one MAVLink
    /// STATUSTEXT).
    pub fn text(&self) -> &'static str {
        if self.flags & ImuHealth::GRAVITY_DEFICIT != 0 {
            "IMU: gravity deficit, accelerometer saturating?"
        } else if self.flags & ImuHealth::NEAR_RANGE != 0 {
            "IMU: accelerometer near its range"
        } else if self.flags & ImuHealth::VIBRATION != 0 {
            "IMU: vibration above threshold"
        } else {
            "IMU: healthy again"
        }
    }
}

/// What the control task reports of a step it computed (the ground link's
/// item; SITL fills `log.csv`'s estimate, excitation and IMU-health
/// columns from it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// The flight computer's record.
    pub telemetry: Telemetry,
    /// The excitation added to the law's command (zeros without).
    pub excitation: Input,
    /// The IMU health after the step's sample (when the monitor runs).
    pub imu_health: Option<ImuHealth>,
}

impl ControlOutput {
    /// The step's report, when the flight computer ran.
    pub fn report(&self) -> Option<StepReport> {
        self.telemetry.map(|telemetry| StepReport {
            telemetry,
            excitation: self.excitation.map_or_else(Input::zeros, |e| e.0),
            imu_health: self.imu_health,
        })
    }
}

/// The excitation's clock: started at the first entry into auto, ended
/// for good when auto is left.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct ExcitationClock {
    start_s: Option<f64>,
    ended: bool,
}

impl ExcitationClock {
    /// The time into the excitation at `now_s` in `mode` (`None`: not
    /// applied).
    fn at(&mut self, now_s: f64, mode: Mode) -> Option<f64> {
        if self.ended {
            return None;
        }
        if mode != Mode::Auto {
            self.ended = self.start_s.is_some();
            return None;
        }
        Some(now_s - *self.start_s.get_or_insert(now_s))
    }
}

/// The control task: the flight computer under the safety supervisor.
#[derive(Debug, Clone)]
pub struct ControlTask {
    computer: SensorComputer,
    supervisor: Supervisor,
    u_trim: Input,
    law: Input,
    rc: Option<RcInput>,
    heading_rad: f64,
    nav_failed: bool,
    excitation: ExcitationClock,
    health: Option<ImuHealthMonitor>,
    health_flags: u8,
    rc_lost: bool,
    gate: Option<SensorGate>,
    servo_limits: Option<ServoLimits>,
    rc_refused: u64,
    landing: Option<Landing>,
}

impl ControlTask {
    /// A control task flying `computer` (disarmed until the receiver arms
    /// it), holding `u_trim` when the law is not flying.
    pub fn new(computer: SensorComputer, supervisor: Supervisor, u_trim: Input) -> Self {
        ControlTask {
            computer,
            supervisor,
            u_trim,
            law: u_trim,
            rc: None,
            heading_rad: 0.0,
            nav_failed: false,
            excitation: ExcitationClock::default(),
            health: None,
            health_flags: 0,
            rc_lost: false,
            gate: None,
            servo_limits: None,
            rc_refused: 0,
            landing: None,
        }
    }

    /// The same task flying from the ground to the ground with `landing`:
    /// it starts on the ground, disarmed, the engine cut; arming runs the
    /// rotor up, a climb takes off, the land detector lands and disarms
    /// ([`crate::landing`]); arming off the ground is refused, and the
    /// receiver's arm switch disarms only on the ground.
    #[must_use]
    pub fn with_landing(mut self, landing: Landing) -> Self {
        self.supervisor.set_landed(landing.on_ground());
        self.landing = Some(landing);
        self
    }

    /// The ground logic, when the task has it.
    pub fn landing(&self) -> Option<&Landing> {
        self.landing.as_ref()
    }

    /// The supervisor has the helicopter armed (its flag: it takes effect
    /// at the next step).
    pub fn armed(&self) -> bool {
        self.supervisor.armed()
    }

    /// The same task refusing implausible sensor samples by `gate` before
    /// the navigation sees them (`helicon onboard` and `helicon sitl` fly
    /// with it).
    #[must_use]
    pub fn with_gate(mut self, gate: SensorGate) -> Self {
        self.gate = Some(gate);
        self
    }

    /// The same task clamping every servo command it sends — the law's,
    /// the pilot's sticks, the trim — to `limits` (the servos' range), and
    /// sending the trim for a command that is not finite.
    #[must_use]
    pub fn with_servo_limits(mut self, limits: ServoLimits) -> Self {
        self.servo_limits = Some(limits);
        self
    }

    /// The plausibility gate, when the task has one (its counts).
    pub fn gate(&self) -> Option<&SensorGate> {
        self.gate.as_ref()
    }

    /// Receiver frames refused so far (a channel outside the receiver's range).
    pub fn rc_refused(&self) -> u64 {
        self.rc_refused
    }

    /// Tell the supervisor whether the helicopter is on the ground.
    pub fn set_landed(&mut self, landed: bool) {
        self.supervisor.set_landed(landed);
    }

    /// The same task running the IMU health monitor on each IMU sample
    /// (as `helicon sim` does; `helicon_setup::imu_health_at` builds it).
    #[must_use]
    pub fn with_imu_health(mut self, monitor: ImuHealthMonitor) -> Self {
        self.health = Some(monitor);
        self
    }

    /// Arm or disarm from the ground station (takes effect at the next
    /// step; holds until the receiver's arm switch moves). `false` when
    /// refused: arming off the ground, with the ground logic.
    pub fn set_armed(&mut self, armed: bool) -> bool {
        if armed {
            self.supervisor.arm()
        } else {
            self.supervisor.disarm();
            true
        }
    }

    /// The mode now.
    pub fn mode(&self) -> Mode {
        self.supervisor.mode()
    }

    /// One sample. The supervisor first takes this sample's health (IMU,
    /// GPS and magnetometer freshness, the last deadline, the last
    /// sample's navigation) and the receiver; the flight computer then runs
    /// on the fresh frame against the mode's reference; the mode picks the
    /// servo commands. Entering auto from any other mode resets the law's
    /// integrators (no wound-up integral from the ground or from manual
    /// flight). No excitation: [`ControlTask::step_with`].
    pub fn step(&mut self, tick: &Tick) -> ControlOutput {
        self.step_with(tick, &Excitations::default())
    }

    /// [`ControlTask::step`] with the mission's flight-test excitation:
    /// its clock starts at the first entry into auto, it is added to the
    /// law's command only in auto, and leaving auto (the pilot's switch, a
    /// failsafe, disarming) ends it for the rest of the flight. No
    /// allocation.
    #[allow(clippy::too_many_lines)] // one sample in order: gate, supervise, compute, pick
    pub fn step_with(&mut self, tick: &Tick, excitation: &Excitations) -> ControlOutput {
        let mut rejection = None;
        let mut note = |kind: Rejection, count: u64| {
            if worth_a_text(count) && rejection.is_none() {
                rejection = Some((kind, count));
            }
        };
        let mut rc_refusal = None;
        if let Some(rc) = tick.rc
            && rc.out_of_range
        {
            self.rc_refused += 1;
            rc_refusal = worth_a_text(self.rc_refused).then_some(self.rc_refused);
        }
        if let Some(rc) = tick.rc
            && !rc.failsafe
            && !rc.out_of_range
        {
            // a receiver in failsafe does not give the pilot's sticks
            self.rc = Some(rc);
        }
        // plausibility before fusion: refused parts of the frame are missing
        let gated = match (&tick.frame, self.gate.as_mut()) {
            (Some(f), Some(g)) => {
                let out = g.check(f, tick.gps_quality.as_ref());
                for r in [out.imu, out.mag, out.gps].into_iter().flatten() {
                    note(r, g.count(r));
                }
                Some(out)
            }
            _ => None,
        };
        let frame = gated.map_or(tick.frame, |g| g.frame);
        let health = Health {
            now_s: tick.now_s,
            imu_fresh: frame.is_some(),
            gps_fresh: frame.is_some_and(|f| f.gps.is_some_and(|g| g.is_valid())),
            mag_fresh: frame.is_some_and(|f| f.mag_body.is_some()),
            deadline_missed: tick.deadline_missed,
            navigation_failed: self.nav_failed,
            imu_rejected: gated.is_some_and(|g| g.imu.is_some()),
            gps_rejected: gated.is_some_and(|g| g.gps.is_some()),
            mag_rejected: gated.is_some_and(|g| g.mag.is_some()),
        };
        let event = self
            .supervisor
            .update(&health, tick.rc.as_ref(), self.heading_rad);
        // the pilot's link: lost by the receiver's failsafe flag or its
        // silence (the supervisor's stale.rc_s), told once per change
        let rc_link = self.supervisor.rc_link();
        let mut rc_link_change = None;
        if rc_link.is_lost() != self.rc_lost {
            self.rc_lost = rc_link.is_lost();
            rc_link_change = Some(rc_link);
        }
        if let Some(ev) = &event
            && ev.to == Mode::Auto
        {
            self.computer.reset_feedback();
        }
        self.nav_failed = false;
        let offset = if excitation.is_empty() {
            None
        } else {
            Some(
                match self.excitation.at(tick.now_s, self.supervisor.mode()) {
                    Some(t) => (excitation.at(t), true),
                    None => (Input::zeros(), false),
                },
            )
        };
        let mut imu_health = None;
        let mut imu_health_change = None;
        if let (Some(frame), Some(m)) = (&frame, self.health.as_mut()) {
            let h = m.update(&frame.imu);
            let flags = h.flags & !ImuHealth::SETTLING;
            if flags != self.health_flags {
                imu_health_change = Some(ImuHealthChange {
                    previous: self.health_flags,
                    flags,
                });
                self.health_flags = flags;
            }
            imu_health = Some(h);
        }
        let mut telemetry = None;
        let reference = self.supervisor.reference(&tick.reference);
        if let Some(frame) = &frame {
            let u_exc = offset.map_or_else(Input::zeros, |o| o.0);
            // outside the law's modes the predictor is told what the
            // servos get (the pilot's sticks, the trim), not the idle law's
            let applied = match self.supervisor.mode() {
                Mode::Auto | Mode::Hold | Mode::Descent => None,
                Mode::Manual | Mode::Disarmed | Mode::ImuLost => Some(self.supervisor.servo(
                    &self.u_trim,
                    &self.u_trim,
                    self.rc.as_ref(),
                )),
            };
            // on the ground: the law's integrators held, the predictor told
            // this sample's command blended from ground idle (the servos
            // blend the same below; `self.law` stays the law's own)
            let mut blend = None;
            if let Some(l) = &self.landing {
                if l.holds_law() {
                    self.computer.reset_feedback();
                }
                if self.supervisor.mode() != Mode::Manual && l.blend() < 1.0 {
                    blend = Some((*l.idle(), l.blend()));
                }
            }
            let mut law = None;
            let stepped = self.computer.step_servo(frame, &reference, &u_exc, |u| {
                law = Some(*u);
                let sent = applied.unwrap_or(*u);
                blend.map_or(applied, |(idle, b)| Some(idle + (sent - idle) * b))
            });
            match stepped {
                Ok(t) => {
                    self.law = law.unwrap_or(t.command);
                    self.heading_rad = t.estimate[2];
                    // a valid fix the navigation's innovation gate refused
                    // (a jump) counts as missing, as a refused one
                    if frame.gps.is_some_and(|g| g.is_valid())
                        && t.navigation.is_some_and(|n| !n.gps_fused)
                    {
                        self.supervisor.gps_refused();
                        if let Some(g) = self.gate.as_mut() {
                            let n = g.count_rejection(Rejection::GpsJump);
                            note(Rejection::GpsJump, n);
                        }
                    }
                    telemetry = Some(t);
                }
                Err(_) => self.nav_failed = true,
            }
        }
        let mut servo = self
            .supervisor
            .servo(&self.law, &self.u_trim, self.rc.as_ref());
        if !servo.iter().all(|v| v.is_finite()) {
            servo = self.u_trim;
        }
        let mut landing = None;
        if let Some(l) = self.landing.as_mut() {
            let mode = self.supervisor.mode();
            servo = l.servo(&servo, mode == Mode::Manual);
            let nav = telemetry.and_then(|t: Telemetry| t.navigation);
            let step = l.update(&LandingInput {
                now_s: tick.now_s,
                armed: self.supervisor.armed(),
                auto: mode == Mode::Auto,
                reference: &reference,
                position_velocity_ned: nav.map(|n| (n.position_ned_m, n.velocity_ned_m_s)),
                gyro_body_rad_s: frame.map(|f| f.imu.gyro_body_rad_s),
            });
            if step.disarm {
                self.supervisor.disarm_landed();
            }
            self.supervisor.set_landed(l.on_ground());
            landing = Some(step);
        }
        if let Some(l) = &self.servo_limits {
            for i in 0..servo.len() {
                servo[i] = servo[i].clamp(l.min[i], l.max[i]);
            }
        }
        ControlOutput {
            servo,
            mode: self.supervisor.mode(),
            telemetry,
            event,
            excitation: offset.filter(|_| telemetry.is_some()),
            imu_health,
            imu_health_change,
            rc_link_change,
            rejection,
            rc_refusal,
            disarm_refusal: self
                .supervisor
                .take_disarm_refused()
                .then(|| self.supervisor.disarms_refused()),
            throttle_hold: landing.is_some_and(|l| l.throttle_hold),
            landing,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The excitation's clock starts at the first entry into auto, runs in
    /// auto only, and leaving auto ends it for good.
    /// The operator's texts fit one MAVLink STATUSTEXT (50 bytes).
    #[test]
    fn imu_health_texts_fit_a_status_text() {
        for flags in 0..8 {
            let c = ImuHealthChange { previous: 8, flags };
            assert!(c.text().len() <= 50, "{}", c.text());
        }
        let c = ImuHealthChange {
            previous: 0,
            flags: ImuHealth::GRAVITY_DEFICIT | ImuHealth::VIBRATION,
        };
        assert!(c.text().contains("gravity deficit"));
    }

    #[test]
    fn the_excitation_runs_from_the_first_auto_until_auto_is_left() {
        let mut c = ExcitationClock::default();
        assert_eq!(c.at(0.0, Mode::Disarmed), None);
        assert_eq!(c.at(0.5, Mode::Manual), None);
        assert_eq!(c.at(1.0, Mode::Auto), Some(0.0));
        assert_eq!(c.at(1.25, Mode::Auto), Some(0.25));
        assert_eq!(c.at(1.5, Mode::Manual), None);
        assert_eq!(c.at(2.0, Mode::Auto), None);
        let mut c = ExcitationClock::default();
        assert_eq!(c.at(0.0, Mode::Auto), Some(0.0));
        assert_eq!(c.at(0.1, Mode::Hold), None);
        assert_eq!(c.at(0.2, Mode::Auto), None);
    }
}
