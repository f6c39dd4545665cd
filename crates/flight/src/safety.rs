//! The safety supervisor: arming, the pilot's switch, sensor stale limits
//! and control overruns decide each sample what flies.
//!
//! | mode | servos | references |
//! |---|---|---|
//! | `Disarmed` | the trim (the hover equilibrium), nothing beyond | — |
//! | `Auto` | the control law | the mission's |
//! | `Hold` | the control law | zero velocity, the heading at entry |
//! | `Descent` | the control law | `failsafe.descent_m_s` down, heading held |
//! | `ImuLost` | the trim, open loop | — (no attitude to close a loop on) |
//! | `Manual` | the RC receiver's, at once | — (the estimator keeps running) |
//!
//! Priority, highest first: the pilot's switch (manual), disarmed, IMU lost
//! or a navigation failure, the failsafes (GPS, magnetometer, overruns),
//! auto. A failsafe latches: GPS coming back does not resume the mission;
//! the pilot takes over (manual) and hands back (auto) to clear it. After
//! `failsafe.hold_s` in `Hold` the helicopter descends at
//! `failsafe.descent_m_s` until the pilot takes over or disarms. Every
//! change of mode is one [`SafetyEvent`] with its reason, for the log.
//!
//! The receiver's failsafe (it lost the pilot's transmitter) is the pilot's
//! link lost: its frames' switches and sticks are ignored (a failsafe
//! frame never disarms nor hands the servos to the receiver); a pilot
//! flying in manual hands over to the law's hold, latched (reason
//! `rc_lost`), then the descent, until the link is back and the pilot
//! takes over and hands back; in auto the mission flies on. A receiver
//! that goes silent (no frame for `stale.rc_s` after its last one: a cut
//! cable, the avionics board resetting) is the same loss, handled the same
//! way, until its frames come back ([`RcLink::Silent`]).
//!
//! Arming: the receiver's arm switch arms or disarms when it moves (and at
//! its first frame) and stays there for `rc.arm_hold_s` (default 0.5 s: a
//! glitching or toggling channel does nothing); the ground station's arm or
//! disarm ([`Supervisor::arm`], [`Supervisor::disarm`]) holds until the
//! switch moves again. Once the supervisor is told where the helicopter is
//! ([`Supervisor::set_landed`]: the land detector of
//! [`crate::landing`]), arming off the ground is refused. The arm switch
//! disarms only on the ground: moved to off in flight, or while nothing
//! has told the supervisor where the helicopter is (no ground logic), it is
//! refused and said ([`Supervisor::take_disarm_refused`]); the helicopter
//! flies on. Disarming in flight is the kill channel's alone
//! (`rc.kill_channel`, held `rc.kill_hold_s`: reason `kill`) or the ground
//! station's forced disarm; the ground logic disarms after its time on the
//! ground (reason `landed`). A receiver frame with a channel outside the receiver's range is
//! refused: not a frame of the pilot's.
//!
//! Sensor faults: a sample refused by the plausibility gate
//! ([`crate::plausibility`]) counts as missing; when a sensor goes stale
//! while its last samples were refused, the reason is `imu_rejected`,
//! `gps_rejected` or `mag_rejected` instead of the silence's `*_stale`.

use crate::config::{FailsafeConfig, RcConfig, StaleLimits};
use helicon_core::Reference;
use helicon_core::state::Input;
use nalgebra::Vector3;

/// What flies this sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Not armed: servos at the trim.
    Disarmed,
    /// The control law tracks the mission's references.
    Auto,
    /// Failsafe: hover (zero velocity), heading held.
    Hold,
    /// Failsafe after the hold: descend at the configured rate.
    Descent,
    /// No IMU (or the navigation failed): servos at the trim, open loop.
    ImuLost,
    /// The pilot flies: the receiver's commands go to the servos.
    Manual,
}

impl Mode {
    /// The name written in logs.
    pub fn as_str(self) -> &'static str {
        match self {
            Mode::Disarmed => "disarmed",
            Mode::Auto => "auto",
            Mode::Hold => "hold",
            Mode::Descent => "descent",
            Mode::ImuLost => "imu_lost",
            Mode::Manual => "manual",
        }
    }

    /// A small code for binary logs (0..=5, in declaration order).
    pub fn code(self) -> u8 {
        self as u8
    }
}

/// Why the mode changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Reason {
    /// The arm switch was set.
    Armed,
    /// The arm switch was cleared.
    Disarmed,
    /// The pilot's switch went to manual.
    PilotManual,
    /// The pilot's switch went back to auto.
    PilotAuto,
    /// No fresh IMU sample within `stale.imu_s`.
    ImuStale,
    /// The navigation or estimator refused a sample.
    NavigationFailure,
    /// No GPS fix within `stale.gps_s`.
    GpsStale,
    /// No magnetometer sample within `stale.mag_s`.
    MagStale,
    /// `failsafe.overrun_limit` consecutive deadline misses.
    Overrun,
    /// `failsafe.hold_s` in hold elapsed: descending.
    HoldElapsed,
    /// The IMU delivers again (or the navigation recovered): auto.
    ImuRecovered,
    /// The receiver reports its failsafe, or went silent for `stale.rc_s`
    /// (the pilot's link lost), while the pilot flew: the law takes over.
    RcLost,
    /// The IMU's samples were refused as implausible until `stale.imu_s`
    /// passed (a sensor fault, not a silence).
    ImuRejected,
    /// The GPS fixes were refused (no 3-D fix, poor quality, impossible,
    /// a jump) until `stale.gps_s` passed.
    GpsRejected,
    /// The magnetometer's samples were refused until `stale.mag_s` passed.
    MagRejected,
    /// The receiver's kill channel was held (`rc.kill_hold_s`): disarmed.
    Kill,
    /// Disarmed on the ground after a landing (`landing.disarm_after_s`).
    Landed,
}

impl Reason {
    /// The name written in logs.
    pub fn as_str(self) -> &'static str {
        match self {
            Reason::Armed => "armed",
            Reason::Disarmed => "disarmed",
            Reason::PilotManual => "pilot_manual",
            Reason::PilotAuto => "pilot_auto",
            Reason::ImuStale => "imu_stale",
            Reason::NavigationFailure => "navigation_failure",
            Reason::GpsStale => "gps_stale",
            Reason::MagStale => "mag_stale",
            Reason::Overrun => "overrun",
            Reason::HoldElapsed => "hold_elapsed",
            Reason::ImuRecovered => "imu_recovered",
            Reason::RcLost => "rc_lost",
            Reason::ImuRejected => "imu_rejected",
            Reason::GpsRejected => "gps_rejected",
            Reason::MagRejected => "mag_rejected",
            Reason::Kill => "kill",
            Reason::Landed => "landed",
        }
    }

    /// A small code for binary logs (0..=15, in declaration order).
    pub fn code(self) -> u8 {
        self as u8
    }
}

/// One change of mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SafetyEvent {
    /// On-board time (s).
    pub t_s: f64,
    /// Mode before.
    pub from: Mode,
    /// Mode after.
    pub to: Mode,
    /// Why.
    pub reason: Reason,
}

/// The RC receiver's frame as the avionics board reports it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RcInput {
    /// The sticks, mapped to servo commands (the servos' units).
    pub servo: Input,
    /// The pilot's switch: true hands the servos to the receiver.
    pub manual: bool,
    /// The arm switch.
    pub armed: bool,
    /// The receiver's failsafe: it lost the pilot's transmitter and
    /// outputs its failsafe values (its sticks and switches are not the
    /// pilot's and are ignored).
    pub failsafe: bool,
    /// The kill channel (`rc.kill_channel`) is set: held for
    /// `rc.kill_hold_s` it disarms, in flight too.
    pub kill: bool,
    /// A channel the frame's mapping reads was outside the receiver's range
    /// (`rc.min_us`..`rc.max_us`): the frame is refused (counted, logged)
    /// and taken as not received.
    pub out_of_range: bool,
}

/// The state of the pilot's link, as the receiver's frames tell it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum RcLink {
    /// No receiver frame yet (a flight without a receiver is flown from
    /// the ground station: not a loss).
    #[default]
    Unknown,
    /// The last frame was the pilot's.
    Ok,
    /// The last frame carried the receiver's failsafe flag.
    Failsafe,
    /// No frame for longer than `stale.rc_s` after the last one: handled
    /// as the failsafe flag until the frames come back.
    Silent,
}

impl RcLink {
    /// The pilot's link is lost (the receiver's failsafe or its silence).
    pub fn is_lost(self) -> bool {
        matches!(self, RcLink::Failsafe | RcLink::Silent)
    }

    /// The log's text of a change to this state: the pilot's link lost,
    /// and how, or back.
    pub fn text(self) -> &'static str {
        self.rc_text().trim_start_matches("RC: ")
    }

    /// The operator's text of a change to this state (one MAVLink
    /// STATUSTEXT): [`RcLink::text`] after `RC: `.
    pub fn rc_text(self) -> &'static str {
        match self {
            RcLink::Silent => "RC: receiver silent, the pilot's link lost",
            RcLink::Failsafe => "RC: receiver failsafe, the pilot's link lost",
            RcLink::Ok | RcLink::Unknown => "RC: the pilot's link back",
        }
    }
}

/// What the supervisor is told each sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Health {
    /// On-board time now (s).
    pub now_s: f64,
    /// A fresh IMU sample arrived for this sample.
    pub imu_fresh: bool,
    /// A GPS fix arrived this sample.
    pub gps_fresh: bool,
    /// A magnetometer sample arrived this sample.
    pub mag_fresh: bool,
    /// The control task missed its previous deadline.
    pub deadline_missed: bool,
    /// The navigation or estimator refused this sample.
    pub navigation_failed: bool,
    /// This sample's IMU sample was refused as implausible.
    pub imu_rejected: bool,
    /// This sample's GPS fix was refused.
    pub gps_rejected: bool,
    /// This sample's magnetometer sample was refused.
    pub mag_rejected: bool,
}

/// The supervisor's state.
#[derive(Debug, Clone)]
pub struct Supervisor {
    stale: StaleLimits,
    failsafe: FailsafeConfig,
    mode: Mode,
    since_s: f64,
    /// The latched failsafe (mode and reason) to resume after an IMU
    /// recovery; `None` when the mission flies.
    latched: Option<Reason>,
    hold_heading_rad: f64,
    last_imu_s: f64,
    last_gps_s: f64,
    last_mag_s: f64,
    misses: u32,
    armed: bool,
    /// The receiver's arm switch at its last frame.
    rc_armed: Option<bool>,
    /// When the receiver's last frame came (s; `None`: never).
    last_rc_s: Option<f64>,
    rc_link: RcLink,
    manual: bool,
    nav_failed: bool,
    rc_config: RcConfig,
    /// The arm switch's new position and since when it was seen (s).
    arm_pending: Option<(bool, f64)>,
    /// Since when the kill channel is seen set (s).
    kill_since: Option<f64>,
    /// The last sample of each sensor was refused (IMU, GPS, magnetometer).
    rejecting: [bool; 3],
    /// `last_gps_s` before this sample's fix (restored when the navigation
    /// refuses the fix).
    prev_gps_s: f64,
    landed: bool,
    /// Told where it is at least once: arming off the ground is refused,
    /// and the arm switch disarms only on the ground.
    ground_known: bool,
    /// The last disarm was the one after a landing.
    landed_disarm: bool,
    /// The arm switch moved to off in flight and was refused, not yet
    /// taken ([`Supervisor::take_disarm_refused`]).
    disarm_refused: bool,
    /// Arm-switch disarms refused so far.
    disarms_refused: u64,
    /// The arm switch has been off since a refused disarm: it disarms once
    /// on the ground.
    disarm_held_in_flight: bool,
}

impl Supervisor {
    /// Disarmed at `t0_s`, every sensor taken as fresh then.
    pub fn new(stale: StaleLimits, failsafe: FailsafeConfig, t0_s: f64) -> Self {
        Supervisor {
            stale,
            failsafe,
            mode: Mode::Disarmed,
            since_s: t0_s,
            latched: None,
            hold_heading_rad: 0.0,
            last_imu_s: t0_s,
            last_gps_s: t0_s,
            last_mag_s: t0_s,
            misses: 0,
            armed: false,
            rc_armed: None,
            last_rc_s: None,
            rc_link: RcLink::Unknown,
            manual: false,
            nav_failed: false,
            rc_config: RcConfig::default(),
            arm_pending: None,
            kill_since: None,
            rejecting: [false; 3],
            prev_gps_s: t0_s,
            landed: false,
            ground_known: false,
            landed_disarm: false,
            disarm_refused: false,
            disarms_refused: 0,
            disarm_held_in_flight: false,
        }
    }

    /// The same supervisor with the receiver's settings `rc` (arm hold time,
    /// kill channel).
    #[must_use]
    pub fn with_rc(mut self, rc: RcConfig) -> Self {
        self.rc_config = rc;
        self
    }

    /// Tell the supervisor whether the helicopter is on the ground (the land
    /// detector's or the navigator's word; until told, it is taken as
    /// flying). The arm switch disarms only on the ground.
    pub fn set_landed(&mut self, landed: bool) {
        self.landed = landed;
        self.ground_known = true;
    }

    /// The navigation refused this sample's GPS fix (its innovation gate):
    /// the fix counts as missing for the stale limit, as a refused one.
    pub fn gps_refused(&mut self) {
        self.last_gps_s = self.prev_gps_s;
        self.rejecting[1] = true;
    }

    /// Arm (as the arm switch would): the first update enters auto. SITL
    /// starts armed, as a pilot arms on the ground before the flight.
    /// Refused (`false`) off the ground, once told where it is
    /// ([`Supervisor::set_landed`]).
    pub fn arm(&mut self) -> bool {
        if self.ground_known && !self.landed && !self.armed {
            return false;
        }
        self.armed = true;
        self.landed_disarm = false;
        true
    }

    /// Disarm (as the arm switch would; the ground station's disarm).
    pub fn disarm(&mut self) {
        self.armed = false;
    }

    /// Disarm after the time on the ground that follows a landing (the
    /// reason `landed`).
    pub fn disarm_landed(&mut self) {
        if self.armed {
            self.armed = false;
            self.landed_disarm = true;
        }
    }

    /// Whether the arm switch moved to off in flight since the last call
    /// and was refused (the helicopter flies on): what the operator is told.
    pub fn take_disarm_refused(&mut self) -> bool {
        std::mem::take(&mut self.disarm_refused)
    }

    /// Arm-switch disarms refused so far (the switch moved to off in flight).
    pub fn disarms_refused(&self) -> u64 {
        self.disarms_refused
    }

    /// Armed (the flag: the mode follows at the next update).
    pub fn armed(&self) -> bool {
        self.armed
    }

    /// The mode now.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The pilot's link after the last update.
    pub fn rc_link(&self) -> RcLink {
        self.rc_link
    }

    /// The latched failsafe reason, if any.
    pub fn latched(&self) -> Option<Reason> {
        self.latched
    }

    /// Take in this sample's health and the receiver's latest frame;
    /// `heading_rad` is the estimated heading (held on entering a
    /// failsafe). Returns the change of mode, if any (at most one per sample).
    #[allow(clippy::too_many_lines)] // one sample's rules in priority order
    pub fn update(
        &mut self,
        h: &Health,
        rc: Option<&RcInput>,
        heading_rad: f64,
    ) -> Option<SafetyEvent> {
        for (i, (fresh, rejected)) in [
            (h.imu_fresh, h.imu_rejected),
            (h.gps_fresh, h.gps_rejected),
            (h.mag_fresh, h.mag_rejected),
        ]
        .into_iter()
        .enumerate()
        {
            if fresh {
                self.rejecting[i] = false;
            } else if rejected {
                self.rejecting[i] = true;
            }
        }
        if h.imu_fresh {
            self.last_imu_s = h.now_s;
        }
        self.prev_gps_s = self.last_gps_s;
        if h.gps_fresh {
            self.last_gps_s = h.now_s;
        }
        if h.mag_fresh {
            self.last_mag_s = h.now_s;
        }
        self.misses = if h.deadline_missed {
            self.misses + 1
        } else {
            0
        };
        self.nav_failed |= h.navigation_failed;
        // older than the limit by more than 1 ns: k·Ts sums do not flip a
        // sample early by rounding
        let stale = |last: f64, limit: f64| h.now_s - last > limit + 1e-9;
        // a frame with a channel out of the receiver's range is not a frame
        let rc = rc.filter(|r| !r.out_of_range);
        if let Some(r) = rc {
            self.last_rc_s = Some(h.now_s);
            self.rc_link = if r.failsafe {
                RcLink::Failsafe
            } else {
                RcLink::Ok
            };
        } else if self.rc_link == RcLink::Ok
            && self
                .last_rc_s
                .is_some_and(|last| stale(last, self.stale.rc_s))
        {
            // silent: the pilot's link lost, as with the failsafe flag
            self.rc_link = RcLink::Silent;
        }
        if self.rc_link.is_lost() {
            // the pilot's link is lost: the receiver's switches are not the
            // pilot's (no disarming, no manual); a pilot flying hands over
            // to the law's hold (latched, as the other failsafes); the
            // mission flies on in auto
            if self.manual {
                self.manual = false;
                if self.armed {
                    self.latched = Some(Reason::RcLost);
                }
            }
        } else if let Some(rc) = rc {
            self.arm_switch(rc, h.now_s);
            let was_manual = self.manual;
            self.manual = rc.manual;
            if was_manual && !rc.manual {
                // the pilot hands back: failsafes are cleared
                self.latched = None;
                self.nav_failed = false;
            }
        }
        let imu_lost = stale(self.last_imu_s, self.stale.imu_s) || self.nav_failed;
        let [imu_rejecting, gps_rejecting, mag_rejecting] = self.rejecting;
        if !self.armed {
            self.latched = None;
        } else if self.latched.is_none() && !self.manual {
            self.latched = if stale(self.last_gps_s, self.stale.gps_s) {
                Some(if gps_rejecting {
                    Reason::GpsRejected
                } else {
                    Reason::GpsStale
                })
            } else if stale(self.last_mag_s, self.stale.mag_s) {
                Some(if mag_rejecting {
                    Reason::MagRejected
                } else {
                    Reason::MagStale
                })
            } else if self.misses >= self.failsafe.overrun_limit {
                Some(Reason::Overrun)
            } else {
                None
            };
        }
        let (to, reason) = if self.manual {
            (Mode::Manual, Reason::PilotManual)
        } else if !self.armed {
            let r = if self.kill_since.is_some() {
                Reason::Kill
            } else if self.landed_disarm {
                Reason::Landed
            } else {
                Reason::Disarmed
            };
            (Mode::Disarmed, r)
        } else if imu_lost {
            let r = if self.nav_failed {
                Reason::NavigationFailure
            } else if imu_rejecting {
                Reason::ImuRejected
            } else {
                Reason::ImuStale
            };
            (Mode::ImuLost, r)
        } else if let Some(r) = self.latched {
            match self.mode {
                Mode::Hold if h.now_s - self.since_s >= self.failsafe.hold_s => {
                    (Mode::Descent, Reason::HoldElapsed)
                }
                Mode::Descent => (Mode::Descent, Reason::HoldElapsed),
                _ => (Mode::Hold, r),
            }
        } else {
            let r = match self.mode {
                Mode::Manual => Reason::PilotAuto,
                Mode::ImuLost => Reason::ImuRecovered,
                _ => Reason::Armed,
            };
            (Mode::Auto, r)
        };
        if to == self.mode {
            return None;
        }
        let ev = SafetyEvent {
            t_s: h.now_s,
            from: self.mode,
            to,
            reason,
        };
        if to == Mode::Hold {
            self.hold_heading_rad = heading_rad;
        }
        self.mode = to;
        self.since_s = h.now_s;
        Some(ev)
    }

    /// The receiver's arm switch and kill channel of a frame of the pilot's:
    /// the switch's new position is taken once held `rc.arm_hold_s` (a
    /// glitching or toggling channel does nothing); it disarms only on the
    /// ground (refused in flight, counted), the kill channel held
    /// `rc.kill_hold_s` disarms at any time.
    fn arm_switch(&mut self, rc: &RcInput, now_s: f64) {
        let held = |since: f64, hold: f64| now_s - since >= hold - 1e-9;
        if rc.kill && self.rc_config.kill_channel.is_some() {
            let since = *self.kill_since.get_or_insert(now_s);
            if held(since, self.rc_config.kill_hold_s) {
                self.armed = false;
            }
        } else if self.kill_since.is_some() && !self.armed {
            // released after it disarmed: the arm switch must move to arm
            self.kill_since = None;
            self.rc_armed = Some(rc.armed);
        } else {
            self.kill_since = None;
        }
        if self.rc_armed == Some(rc.armed) {
            self.arm_pending = None;
            if !rc.armed
                && self.armed
                && self.disarm_held_in_flight
                && self.ground_known
                && self.landed
            {
                // held off since it was refused in flight: on the ground it acts
                self.armed = false;
                self.disarm_held_in_flight = false;
            }
            return;
        }
        let since = match self.arm_pending {
            Some((pos, since)) if pos == rc.armed => since,
            _ => {
                self.arm_pending = Some((rc.armed, now_s));
                now_s
            }
        };
        if !held(since, self.rc_config.arm_hold_s) {
            return;
        }
        // the switch moved (or its first position) and held: it acts
        self.arm_pending = None;
        self.rc_armed = Some(rc.armed);
        self.disarm_held_in_flight = false;
        if rc.armed {
            if self.kill_since.is_none() && (self.landed || !self.ground_known) {
                self.armed = true;
                self.landed_disarm = false;
            }
        } else if self.ground_known && self.landed {
            self.armed = false;
        } else if self.armed {
            // in flight (or nothing says it is on the ground): only the
            // kill channel disarms there
            self.disarm_refused = true;
            self.disarms_refused += 1;
            self.disarm_held_in_flight = true;
        }
    }

    /// The reference flown in this mode: the mission's in auto, hover and
    /// the held heading in hold, the descent in descent.
    pub fn reference(&self, mission: &Reference) -> Reference {
        match self.mode {
            Mode::Hold => Reference {
                velocity_ned_m_s: Vector3::zeros(),
                yaw_rad: self.hold_heading_rad,
            },
            Mode::Descent => Reference {
                velocity_ned_m_s: Vector3::new(0.0, 0.0, self.failsafe.descent_m_s),
                yaw_rad: self.hold_heading_rad,
            },
            _ => *mission,
        }
    }

    /// The servo commands sent in this mode.
    pub fn servo(&self, law: &Input, trim: &Input, rc: Option<&RcInput>) -> Input {
        match self.mode {
            Mode::Auto | Mode::Hold | Mode::Descent => *law,
            Mode::Manual => rc.map_or(*trim, |r| r.servo),
            Mode::Disarmed | Mode::ImuLost => *trim,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn health(now_s: f64, gps: bool) -> Health {
        Health {
            now_s,
            imu_fresh: true,
            gps_fresh: gps,
            mag_fresh: true,
            deadline_missed: false,
            navigation_failed: false,
            imu_rejected: false,
            gps_rejected: false,
            mag_rejected: false,
        }
    }

    fn rc(manual: bool, armed: bool) -> RcInput {
        RcInput {
            servo: Input::repeat(0.1),
            manual,
            armed,
            failsafe: false,
            kill: false,
            out_of_range: false,
        }
    }

    /// The arm switch acting at once (the tests of other rules).
    fn instant() -> RcConfig {
        RcConfig {
            arm_hold_s: 0.0,
            ..RcConfig::default()
        }
    }

    #[test]
    fn a_receiver_failsafe_hands_the_pilots_flight_to_the_hold() {
        let fs = FailsafeConfig::default();
        let mut s = Supervisor::new(StaleLimits::default(), fs, 0.0).with_rc(instant());
        s.update(&health(0.0, true), Some(&rc(false, true)), 0.0);
        // in auto: the mission flies on, the failsafe frame's switches
        // (disarmed, manual) ignored
        let lost = RcInput {
            failsafe: true,
            ..rc(true, false)
        };
        assert!(s.update(&health(0.1, true), Some(&lost), 0.0).is_none());
        assert_eq!(s.mode(), Mode::Auto);
        // the link back, the pilot takes over; then it is lost again
        let ev = s
            .update(&health(0.2, true), Some(&rc(true, true)), 0.4)
            .unwrap();
        assert_eq!(ev.to, Mode::Manual);
        let ev = s.update(&health(0.3, true), Some(&lost), 0.4).unwrap();
        assert_eq!(
            (ev.from, ev.to, ev.reason),
            (Mode::Manual, Mode::Hold, Reason::RcLost)
        );
        assert_eq!(s.reference(&Reference::default()).yaw_rad, 0.4);
        assert_eq!(s.latched(), Some(Reason::RcLost));
        // latched: a failsafe frame at auto does not resume the mission
        let lost_auto = RcInput {
            failsafe: true,
            ..rc(false, true)
        };
        assert!(
            s.update(&health(0.4, true), Some(&lost_auto), 0.4)
                .is_none()
        );
        // the link back at manual: the pilot's; handed back: auto
        assert_eq!(
            s.update(&health(0.5, true), Some(&rc(true, true)), 0.4)
                .unwrap()
                .to,
            Mode::Manual
        );
        let ev = s
            .update(&health(0.6, true), Some(&rc(false, true)), 0.4)
            .unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Auto, Reason::PilotAuto));
    }

    /// A receiver that goes silent is its failsafe flag: the pilot's
    /// flight handed to the hold once the last frame is older than
    /// `stale.rc_s` (latched), the mission flown on in auto, and the
    /// frames back give the pilot's switch again. Never before a first
    /// frame.
    #[test]
    fn a_silent_receiver_is_the_receivers_failsafe() {
        let stale = StaleLimits {
            rc_s: 0.5,
            ..StaleLimits::default()
        };
        let mut s = Supervisor::new(stale, FailsafeConfig::default(), 0.0);
        // no receiver at all (a ground-station flight): never lost
        s.arm();
        s.update(&health(0.0, true), None, 0.0);
        assert!(s.update(&health(2.0, true), None, 0.0).is_none());
        assert_eq!(s.rc_link(), RcLink::Unknown);
        // the pilot flies, the last frame at 2.1 s
        let ev = s
            .update(&health(2.1, true), Some(&rc(true, true)), 0.3)
            .unwrap();
        assert_eq!(ev.to, Mode::Manual);
        assert!(s.update(&health(2.6, true), None, 0.3).is_none());
        assert_eq!(s.rc_link(), RcLink::Ok);
        let ev = s.update(&health(2.6025, true), None, 0.3).unwrap();
        assert_eq!(
            (ev.from, ev.to, ev.reason),
            (Mode::Manual, Mode::Hold, Reason::RcLost)
        );
        assert_eq!(s.rc_link(), RcLink::Silent);
        assert_eq!(s.latched(), Some(Reason::RcLost));
        assert_eq!(s.reference(&Reference::default()).yaw_rad, 0.3);
        // frames back at auto: latched (the hold flies on)
        assert!(
            s.update(&health(3.0, true), Some(&rc(false, true)), 0.3)
                .is_none()
        );
        assert_eq!(s.rc_link(), RcLink::Ok);
        // the pilot takes over and hands back: auto
        s.update(&health(3.1, true), Some(&rc(true, true)), 0.3);
        let ev = s
            .update(&health(3.2, true), Some(&rc(false, true)), 0.3)
            .unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Auto, Reason::PilotAuto));
        // silent in auto: the mission flies on, never disarmed
        assert!(s.update(&health(4.0, true), None, 0.3).is_none());
        assert_eq!(s.rc_link(), RcLink::Silent);
        assert_eq!(s.mode(), Mode::Auto);
    }

    /// The texts of the link's changes: the log's is the operator's after
    /// `RC: `, and the operator's fits one MAVLink STATUSTEXT (50 bytes).
    #[test]
    fn the_link_texts_name_how_it_was_lost() {
        for (link, text) in [
            (RcLink::Silent, "receiver silent, the pilot's link lost"),
            (RcLink::Failsafe, "receiver failsafe, the pilot's link lost"),
            (RcLink::Ok, "the pilot's link back"),
        ] {
            assert_eq!(link.text(), text);
            assert_eq!(link.rc_text(), format!("RC: {text}"));
            assert!(link.rc_text().len() <= 50, "{}", link.rc_text());
        }
    }

    #[test]
    fn gps_loss_holds_then_descends_and_latches() {
        let fs = FailsafeConfig {
            hold_s: 1.0,
            descent_m_s: 0.5,
            overrun_limit: 3,
        };
        let mut s = Supervisor::new(StaleLimits::default(), fs, 0.0).with_rc(instant());
        let armed = rc(false, true);
        let ev = s.update(&health(0.0, true), Some(&armed), 0.3).unwrap();
        assert_eq!(
            (ev.from, ev.to, ev.reason),
            (Mode::Disarmed, Mode::Auto, Reason::Armed)
        );
        // GPS last seen at 0.5 s; stale after 1.0 s more
        assert!(s.update(&health(0.5, true), None, 0.3).is_none());
        assert!(s.update(&health(1.5, false), None, 0.3).is_none());
        let ev = s.update(&health(1.5025, false), None, 0.7).unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Hold, Reason::GpsStale));
        let mission = Reference {
            velocity_ned_m_s: Vector3::new(2.0, 0.0, 0.0),
            yaw_rad: 1.0,
        };
        let r = s.reference(&mission);
        assert_eq!(r.velocity_ned_m_s, Vector3::zeros());
        assert_eq!(r.yaw_rad, 0.7);
        // the fix comes back: still holding (latched)
        assert!(s.update(&health(2.0, true), None, 0.7).is_none());
        let ev = s.update(&health(2.5025, true), None, 0.7).unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Descent, Reason::HoldElapsed));
        assert_eq!(s.reference(&mission).velocity_ned_m_s.z, 0.5);
        // the pilot takes over and hands back: the mission resumes
        let ev = s
            .update(&health(3.0, true), Some(&rc(true, true)), 0.7)
            .unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Manual, Reason::PilotManual));
        assert_eq!(
            s.servo(&Input::zeros(), &Input::zeros(), Some(&rc(true, true)))[0],
            0.1
        );
        let ev = s.update(&health(3.1, true), Some(&armed), 0.7).unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Auto, Reason::PilotAuto));
        assert_eq!(s.reference(&mission), mission);
    }

    #[test]
    fn imu_loss_and_overruns() {
        let fs = FailsafeConfig {
            hold_s: 1.0,
            descent_m_s: 0.5,
            overrun_limit: 3,
        };
        let mut s = Supervisor::new(StaleLimits::default(), fs, 0.0).with_rc(instant());
        s.update(&health(0.0, true), Some(&rc(false, true)), 0.0);
        let mut h = health(0.01, true);
        h.imu_fresh = false;
        assert!(s.update(&h, None, 0.0).is_none());
        h.now_s = 0.0201;
        let ev = s.update(&h, None, 0.0).unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::ImuLost, Reason::ImuStale));
        let trim = Input::repeat(0.05);
        assert_eq!(s.servo(&Input::zeros(), &trim, None), trim);
        // the IMU comes back: auto again (the IMU loss is not latched)
        let ev = s.update(&health(0.03, true), None, 0.0).unwrap();
        assert_eq!(ev.to, Mode::Auto);
        let mut h = health(0.04, true);
        h.deadline_missed = true;
        assert!(s.update(&h, None, 0.0).is_none());
        assert!(s.update(&h, None, 0.0).is_none());
        let ev = s.update(&h, None, 0.0).unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Hold, Reason::Overrun));
        // disarmed (on the ground): trim, nothing beyond
        s.set_landed(true);
        let ev = s
            .update(&health(0.05, true), Some(&rc(false, false)), 0.0)
            .unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Disarmed, Reason::Disarmed));
        assert_eq!(s.servo(&Input::repeat(9.0), &trim, None), trim);
    }

    #[test]
    fn magnetometer_loss_holds_and_disarming_clears_the_latch() {
        let fs = FailsafeConfig::default();
        let mut s = Supervisor::new(StaleLimits::default(), fs, 0.0).with_rc(instant());
        s.update(&health(0.0, true), Some(&rc(false, true)), 0.2);
        let mut h = health(0.5, true);
        h.mag_fresh = false;
        assert!(s.update(&h, None, 0.2).is_none()); // 0.5 s old: not yet
        h.now_s = 0.5025;
        let ev = s.update(&h, None, 0.2).unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Hold, Reason::MagStale));
        assert_eq!(s.latched(), Some(Reason::MagStale));
        // disarm (on the ground), then arm again with a healthy
        // magnetometer: auto, latch cleared
        s.set_landed(true);
        s.update(&health(0.6, true), Some(&rc(false, false)), 0.2);
        assert_eq!(s.latched(), None);
        let ev = s
            .update(&health(0.7, true), Some(&rc(false, true)), 0.2)
            .unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Auto, Reason::Armed));
    }

    #[test]
    fn the_ground_station_arms_until_the_switch_moves() {
        let mut s = Supervisor::new(StaleLimits::default(), FailsafeConfig::default(), 0.0)
            .with_rc(instant());
        let off = rc(false, false);
        let on = rc(false, true);
        s.set_landed(true);
        // the switch off at its first frame: disarmed
        assert!(s.update(&health(0.0, true), Some(&off), 0.0).is_none());
        // the ground station arms: the switch, still off, does not undo it
        s.arm();
        let ev = s.update(&health(0.01, true), Some(&off), 0.0).unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Auto, Reason::Armed));
        assert!(s.update(&health(0.02, true), Some(&off), 0.0).is_none());
        // the switch moves on, then off: disarmed
        assert!(s.update(&health(0.03, true), Some(&on), 0.0).is_none());
        let ev = s.update(&health(0.04, true), Some(&off), 0.0).unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Disarmed, Reason::Disarmed));
        // the switch on: armed; the ground station disarms and it holds
        s.update(&health(0.05, true), Some(&on), 0.0).unwrap();
        s.disarm();
        let ev = s.update(&health(0.06, true), Some(&on), 0.0).unwrap();
        assert_eq!(ev.to, Mode::Disarmed);
        assert!(s.update(&health(0.07, true), Some(&on), 0.0).is_none());
    }

    /// One 20 ms frame with the arm channel low, or a channel toggling every
    /// frame, does not disarm; the switch held 0.5 s does.
    #[test]
    fn the_arm_switch_acts_only_when_held() {
        let mut s = Supervisor::new(StaleLimits::default(), FailsafeConfig::default(), 0.0);
        let (on, off) = (rc(false, true), rc(false, false));
        let mut t = 0.0;
        let mut step = |s: &mut Supervisor, r: &RcInput| {
            let ev = s.update(&health(t, true), Some(r), 0.0);
            t += 0.02;
            ev
        };
        // armed only once the switch was on for 0.5 s
        for _ in 0..25 {
            assert!(step(&mut s, &on).is_none());
        }
        assert_eq!(step(&mut s, &on).map(|e| e.to), Some(Mode::Auto));
        // one frame low: nothing; toggling every frame for 2 s: nothing
        assert!(step(&mut s, &off).is_none());
        for k in 0..100 {
            assert!(step(&mut s, if k % 2 == 0 { &on } else { &off }).is_none());
        }
        assert_eq!(s.mode(), Mode::Auto);
        assert!(!s.take_disarm_refused());
        // held low 0.5 s: nothing says it is on the ground, so it flies on,
        // the refusal said once (no kill channel configured)
        let mut refused = 0;
        for _ in 0..60 {
            assert!(step(&mut s, &off).is_none());
            refused += usize::from(s.take_disarm_refused());
        }
        assert_eq!((s.mode(), refused, s.disarms_refused()), (Mode::Auto, 1, 1));
        // still held low when the land detector says it is down: disarmed
        s.set_landed(true);
        assert_eq!(
            step(&mut s, &off).map(|e| (e.to, e.reason)),
            Some((Mode::Disarmed, Reason::Disarmed))
        );
    }

    /// Told where it is (the land detector): arming off the ground is
    /// refused, by the ground station and by the arm switch; in the air the
    /// arm switch does not disarm (no kill channel configured); on the
    /// ground it does; the disarm after a landing has its own reason.
    #[test]
    fn off_the_ground_no_arming_and_no_disarm_by_the_switch() {
        let mut s = Supervisor::new(StaleLimits::default(), FailsafeConfig::default(), 0.0)
            .with_rc(instant());
        let (on, off) = (rc(false, true), rc(false, false));
        s.set_landed(false);
        assert!(!s.arm());
        assert!(s.update(&health(0.0, true), Some(&on), 0.0).is_none());
        assert_eq!(s.mode(), Mode::Disarmed);
        // on the ground: the switch (moved again) arms
        s.set_landed(true);
        s.update(&health(0.02, true), Some(&off), 0.0);
        let ev = s.update(&health(0.04, true), Some(&on), 0.0).unwrap();
        assert_eq!(ev.to, Mode::Auto);
        // in the air the switch low does nothing
        s.set_landed(false);
        for k in 3..60 {
            assert!(
                s.update(&health(f64::from(k) * 0.02, true), Some(&off), 0.0)
                    .is_none()
            );
        }
        assert_eq!(s.mode(), Mode::Auto);
        // landed: the switch low disarms
        s.set_landed(true);
        s.update(&health(1.3, true), Some(&on), 0.0);
        let ev = s.update(&health(1.32, true), Some(&off), 0.0).unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Disarmed, Reason::Disarmed));
        // armed again by the ground station; the ground logic's disarm
        assert!(s.arm());
        s.update(&health(1.34, true), None, 0.0).unwrap();
        s.disarm_landed();
        let ev = s.update(&health(1.36, true), None, 0.0).unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Disarmed, Reason::Landed));
    }

    /// With a kill channel the arm switch does not disarm in flight; the
    /// kill channel held 0.1 s does, and the arm switch must move to arm
    /// again. A frame with a channel out of range is not the pilot's.
    #[test]
    fn the_kill_channel_disarms_in_flight_and_out_of_range_frames_are_refused() {
        let cfg = RcConfig {
            kill_channel: Some(6),
            ..instant()
        };
        let mut s =
            Supervisor::new(StaleLimits::default(), FailsafeConfig::default(), 0.0).with_rc(cfg);
        let (on, off) = (rc(false, true), rc(false, false));
        s.update(&health(0.0, true), Some(&on), 0.0).unwrap();
        assert_eq!(s.mode(), Mode::Auto);
        for k in 1..50 {
            assert!(
                s.update(&health(f64::from(k) * 0.02, true), Some(&off), 0.0)
                    .is_none()
            );
        }
        assert_eq!(s.mode(), Mode::Auto);
        // an out-of-range frame in manual does not take the servos
        let mut wild = rc(true, false);
        wild.out_of_range = true;
        assert!(s.update(&health(1.0, true), Some(&wild), 0.0).is_none());
        // the kill held: one frame does not disarm, 0.1 s does
        let mut kill = on;
        kill.kill = true;
        assert!(s.update(&health(1.02, true), Some(&kill), 0.0).is_none());
        assert!(s.update(&health(1.06, true), Some(&kill), 0.0).is_none());
        let ev = s.update(&health(1.12, true), Some(&kill), 0.0).unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Disarmed, Reason::Kill));
        // released with the arm switch on: still disarmed until it moves
        assert!(s.update(&health(1.14, true), Some(&on), 0.0).is_none());
        assert!(s.update(&health(1.16, true), Some(&off), 0.0).is_none());
        let ev = s.update(&health(1.18, true), Some(&on), 0.0).unwrap();
        assert_eq!(ev.to, Mode::Auto);
        // on the ground the arm switch disarms
        s.set_landed(true);
        let ev = s.update(&health(1.2, true), Some(&off), 0.0).unwrap();
        assert_eq!(ev.to, Mode::Disarmed);
    }

    /// A GPS whose fixes are refused goes stale as `gps_rejected`; one the
    /// navigation refused counts as missing too.
    #[test]
    fn refused_samples_go_stale_with_their_own_reason() {
        let mut s = Supervisor::new(StaleLimits::default(), FailsafeConfig::default(), 0.0)
            .with_rc(instant());
        s.update(&health(0.0, true), Some(&rc(false, true)), 0.0)
            .unwrap();
        let mut h = health(0.5, false);
        h.gps_rejected = true;
        assert!(s.update(&h, None, 0.0).is_none());
        // a fix taken fresh, then refused by the navigation's gate
        s.update(&health(0.6, true), None, 0.0);
        s.gps_refused();
        h.now_s = 1.0025;
        h.gps_rejected = false;
        let ev = s.update(&h, None, 0.0).unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::Hold, Reason::GpsRejected));
        // the IMU refused until stale: imu_rejected
        let mut s = Supervisor::new(StaleLimits::default(), FailsafeConfig::default(), 0.0)
            .with_rc(instant());
        s.update(&health(0.0, true), Some(&rc(false, true)), 0.0)
            .unwrap();
        let mut h = health(0.0, true);
        h.imu_fresh = false;
        h.imu_rejected = true;
        let mut ev = None;
        for k in 1..=10 {
            h.now_s = f64::from(k) * 0.0025;
            ev = ev.or(s.update(&h, None, 0.0));
        }
        let ev = ev.unwrap();
        assert_eq!((ev.to, ev.reason), (Mode::ImuLost, Reason::ImuRejected));
    }
}
