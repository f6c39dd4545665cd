//! From the ground to the ground on board: the rotor's run-up (the spool
//! state), the land detector, the take-off and the landing.
//!
//! ```text
//!  disarmed ─arm─► spooling up ─runup_s─► ready ─climb asked─► taking off ─lift-off─► flying
//!      ▲                                    ▲  ◄─climb withdrawn / no lift-off─┘          │
//!      └─spooldown_s── spooling down ◄─disarm (any state)    landed ◄─land detector─────┘
//!                            ▲                                 │ (climb asked: taking off)
//!                            └──────── disarm_after_s ─────────┘
//! ```
//!
//! - **The engine** runs from arming to disarming: the servo frame's
//!   throttle hold is released when armed ([`LandingStep::throttle_hold`]).
//!   The rotor is taken as at speed `runup_s` after the engine started (the
//!   governor's soft start, as a helicopter speed controller's run-up
//!   timer: there is no rotor-speed sensor on this airframe).
//! - **On the ground** (disarmed, spooling up, ready, landed, spooling
//!   down) the servos get ground idle — zero collective, centred cyclic and
//!   tail — whatever the mode; the law runs (its estimator too) with its
//!   integrators held at zero.
//! - **Take-off**: ready, in `auto`, with a reference that climbs (the
//!   navigator's take-off, a mission's first leg, a scenario's `vd < 0`),
//!   the servo command blends from ground idle into the law's over
//!   `takeoff_ramp_s`, the integrators held until the ramp is complete
//!   and running from then (PX4's take-off: without them, the law's
//!   command can hover in ground effect below the lift-off test). Lift-off:
//!   the estimated height `liftoff_height_m` above where it stood, or a
//!   climb faster than `liftoff_climb_m_s`. A climb
//!   withdrawn before lift-off, or no lift-off `takeoff_timeout_s` after the
//!   ramp, blends back to ground idle (ready).
//! - **The land detector** (PX4's three stages): *ground contact* — no
//!   vertical movement (|vd| < `z_vel_max_m_s`), no horizontal movement
//!   (< `xy_vel_max_m_s`), and a low collective (below `low_collective` of
//!   the way from ground idle to the hover trim) or a descent asked for
//!   that does not happen; held a third of `trigger_s`, the command starts
//!   blending down to ground idle. *Maybe landed* — ground contact, the
//!   collective sent within a tenth of the way and no rotation (every body
//!   rate below `rot_max_deg_s`), a third of `trigger_s`. *Landed* — maybe
//!   landed a third of `trigger_s` more. Losing a condition goes back to
//!   flying (and the command back to the law).
//! - **Landed**: ground idle; `disarm_after_s` on the ground disarms (the
//!   reason `landed`); a climb asked for before takes off again.
//!
//! The detector reads the navigation's velocity (GPS/IMU fusion: not the
//! model-based predictor, which knows no ground), the IMU's rates and the
//! collective actually sent. Allocation-free; every field checked by
//! [`LandingConfig::validate`].

use helicon_config::ConfigError;
use helicon_core::Reference;
use helicon_core::state::Input;
use helicon_gcs::link::{GroundState, LandedState, RotorRunup};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// The ground logic's settings (`[landing]` in `onboard.toml`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LandingConfig {
    /// The ground logic runs (the on-board program starts on the ground;
    /// off only for a start in the air, as scripted test hardware has).
    pub enabled: bool,
    /// From engine start to the rotor at speed (s): longer than the
    /// governor's soft start (the Bergen Twin's spools up in 5 s).
    pub runup_s: f64,
    /// From engine cut to the rotor taken as stopped (s).
    pub spooldown_s: f64,
    /// The blend from ground idle into the law at take-off, and back down
    /// at touchdown (s).
    pub takeoff_ramp_s: f64,
    /// No lift-off this long after the take-off ramp ends: the take-off is
    /// given up (s).
    pub takeoff_timeout_s: f64,
    /// Lift-off: the estimated height above the standing point (m).
    pub liftoff_height_m: f64,
    /// Lift-off: an estimated climb faster than this (m/s).
    pub liftoff_climb_m_s: f64,
    /// No vertical movement: |vd| below this (m/s; PX4's `LNDMC_Z_VEL_MAX`).
    pub z_vel_max_m_s: f64,
    /// No horizontal movement: the ground speed below this (m/s; PX4's
    /// `LNDMC_XY_VEL_MAX`).
    pub xy_vel_max_m_s: f64,
    /// No rotation: every body rate below this (deg/s; PX4's `LNDMC_ROT_MAX`).
    pub rot_max_deg_s: f64,
    /// The three stages together take this long with every condition met
    /// (s; PX4's `LNDMC_TRIG_TIME`).
    pub trigger_s: f64,
    /// A low collective: below this fraction of the way from ground idle
    /// to the hover trim (0..1).
    pub low_collective: f64,
    /// Disarm this long after landing (s; PX4's `COM_DISARM_LAND`; negative:
    /// never).
    pub disarm_after_s: f64,
}

impl Default for LandingConfig {
    fn default() -> Self {
        LandingConfig {
            enabled: true,
            runup_s: 8.0,
            spooldown_s: 10.0,
            takeoff_ramp_s: 2.0,
            takeoff_timeout_s: 10.0,
            liftoff_height_m: 0.3,
            liftoff_climb_m_s: 0.3,
            z_vel_max_m_s: 0.25,
            xy_vel_max_m_s: 1.5,
            rot_max_deg_s: 20.0,
            trigger_s: 1.0,
            low_collective: 0.6,
            disarm_after_s: 2.0,
        }
    }
}

impl LandingConfig {
    /// Check every field (`file` names the configuration in errors).
    pub fn validate(&self, file: &str) -> Result<(), ConfigError> {
        let ranges = [
            ("landing.runup_s", self.runup_s, 0.0, 120.0),
            ("landing.spooldown_s", self.spooldown_s, 0.0, 300.0),
            ("landing.takeoff_ramp_s", self.takeoff_ramp_s, 0.1, 30.0),
            (
                "landing.takeoff_timeout_s",
                self.takeoff_timeout_s,
                0.5,
                120.0,
            ),
            ("landing.liftoff_height_m", self.liftoff_height_m, 0.05, 5.0),
            (
                "landing.liftoff_climb_m_s",
                self.liftoff_climb_m_s,
                0.05,
                5.0,
            ),
            ("landing.z_vel_max_m_s", self.z_vel_max_m_s, 0.01, 3.0),
            ("landing.xy_vel_max_m_s", self.xy_vel_max_m_s, 0.01, 10.0),
            ("landing.rot_max_deg_s", self.rot_max_deg_s, 1.0, 360.0),
            ("landing.trigger_s", self.trigger_s, 0.1, 10.0),
            ("landing.low_collective", self.low_collective, 0.05, 0.95),
            ("landing.disarm_after_s", self.disarm_after_s, -1.0, 600.0),
        ];
        for (field, v, lo, hi) in ranges {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                return Err(ConfigError::invalid(
                    file,
                    field,
                    v,
                    format!("must be within {lo}..={hi}"),
                ));
            }
        }
        Ok(())
    }
}

/// Where the helicopter is between the ground and the air.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SpoolState {
    /// On the ground, engine off.
    Disarmed,
    /// Armed on the ground, the rotor coming up to speed.
    SpoolingUp,
    /// On the ground, the rotor at speed, waiting for a climb.
    Ready,
    /// The command blending into the law, not yet lifted off.
    TakingOff,
    /// In the air.
    Flying,
    /// Landed, the rotor at speed (disarms after `disarm_after_s`).
    Landed,
    /// Disarmed, the engine cut, the rotor running down.
    SpoolingDown,
}

impl SpoolState {
    /// Every state, in declaration order ([`SpoolState::code`] is the index).
    pub const ALL: [SpoolState; 7] = [
        SpoolState::Disarmed,
        SpoolState::SpoolingUp,
        SpoolState::Ready,
        SpoolState::TakingOff,
        SpoolState::Flying,
        SpoolState::Landed,
        SpoolState::SpoolingDown,
    ];

    /// The name in logs and status texts.
    pub fn as_str(self) -> &'static str {
        match self {
            SpoolState::Disarmed => "disarmed",
            SpoolState::SpoolingUp => "spooling up",
            SpoolState::Ready => "ready",
            SpoolState::TakingOff => "taking off",
            SpoolState::Flying => "flying",
            SpoolState::Landed => "landed",
            SpoolState::SpoolingDown => "spooling down",
        }
    }

    /// A code for the log (0 … 6 in declaration order).
    pub fn code(self) -> u8 {
        self as u8
    }

    /// The operator's text on entering the state (one MAVLink STATUSTEXT).
    pub fn text(self) -> &'static str {
        match self {
            SpoolState::Disarmed => "rotor stopped",
            SpoolState::SpoolingUp => "engine on: rotor spooling up",
            SpoolState::Ready => "rotor at speed: ready for take-off",
            SpoolState::TakingOff => "taking off",
            SpoolState::Flying => "lift-off",
            SpoolState::Landed => "touchdown: on the ground",
            SpoolState::SpoolingDown => "engine cut: rotor spooling down",
        }
    }
}

/// The land detector's stage (PX4's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LandStage {
    /// In the air (or on the ground and not yet known landed).
    Air,
    /// Touching the ground: the command blends down.
    GroundContact,
    /// Maybe landed: minimal collective, no rotation.
    MaybeLanded,
    /// Landed.
    Landed,
}

impl LandStage {
    /// Every stage, in declaration order ([`LandStage::code`] is the index).
    pub const ALL: [LandStage; 4] = [
        LandStage::Air,
        LandStage::GroundContact,
        LandStage::MaybeLanded,
        LandStage::Landed,
    ];

    /// The name in logs and plots (PX4's).
    pub fn as_str(self) -> &'static str {
        match self {
            LandStage::Air => "air",
            LandStage::GroundContact => "ground contact",
            LandStage::MaybeLanded => "maybe landed",
            LandStage::Landed => "landed",
        }
    }

    /// A code for the log (0 … 3 in declaration order).
    pub fn code(self) -> u8 {
        self as u8
    }
}

/// One sample's view of the flight for the ground logic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandingInput<'a> {
    /// On-board time (s).
    pub now_s: f64,
    /// The supervisor has the helicopter armed.
    pub armed: bool,
    /// The mode flies the mission's reference (`auto`).
    pub auto: bool,
    /// The reference flown this sample.
    pub reference: &'a Reference,
    /// The navigation's position and velocity NED (m, m/s), when it runs.
    pub position_velocity_ned: Option<(Vector3<f64>, Vector3<f64>)>,
    /// The IMU's body rates of the sample (rad/s), when one came.
    pub gyro_body_rad_s: Option<Vector3<f64>>,
}

/// What the ground logic decided for a sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandingStep {
    /// The state changed this sample: (from, to).
    pub change: Option<(SpoolState, SpoolState)>,
    /// Disarm now: `disarm_after_s` on the ground after landing.
    pub disarm: bool,
    /// The engine is cut (the servo frame's throttle hold).
    pub throttle_hold: bool,
    /// A take-off was given up (no lift-off): told to the operator.
    pub takeoff_aborted: bool,
    /// The land detector's stage after the sample.
    pub stage: LandStage,
    /// The state or the stage changed this sample, or it is the first:
    /// the log's `vehicle_land_detected` is written.
    pub report: bool,
    /// The detector's view of this sample: a low collective, moving
    /// vertically, moving horizontally, rotating (all false when it does
    /// not run: on the ground, taking off).
    pub flags: DetectorFlags,
}

/// The land detector's conditions of a sample (PX4's names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DetectorFlags {
    /// The collective below `low_collective` of the way to the hover trim.
    pub low_collective: bool,
    /// |vd| at or above `z_vel_max_m_s`.
    pub vertical_movement: bool,
    /// The ground speed at or above `xy_vel_max_m_s`.
    pub horizontal_movement: bool,
    /// A body rate at or above `rot_max_deg_s`.
    pub rotating: bool,
    /// A descent asked for (faster than 1.1 × `z_vel_max_m_s`).
    pub descending: bool,
}

/// The spool state machine and the land detector.
#[derive(Debug, Clone)]
pub struct Landing {
    config: LandingConfig,
    ts_s: f64,
    idle: Input,
    hover_collective: f64,
    state: SpoolState,
    since_s: f64,
    stage: LandStage,
    stage_since_s: f64,
    blend: f64,
    /// The estimated position where it stood (NED, m).
    ground_ned_m: Option<Vector3<f64>>,
    /// When the take-off ramp reached the law.
    ramp_done_s: Option<f64>,
    /// The collective sent last sample.
    last_collective: f64,
    /// Since when a descent has been asked for without a break (s).
    descent_since_s: Option<f64>,
    /// A take-off was given up: a climb must be withdrawn and asked again.
    climb_refused: bool,
    /// The detector's conditions of the last sample it ran.
    flags: DetectorFlags,
    /// Samples updated so far.
    updates: u64,
}

impl Landing {
    /// The ground logic of `config` at control period `ts_s`, with the hover
    /// trim `u_trim` (its collective sets what a low collective is);
    /// starting on the ground, disarmed, at `t0_s`.
    pub fn new(config: LandingConfig, ts_s: f64, u_trim: &Input, t0_s: f64) -> Self {
        Landing {
            config,
            ts_s,
            idle: Input::zeros(),
            hover_collective: u_trim[0],
            state: SpoolState::Disarmed,
            since_s: t0_s,
            stage: LandStage::Landed,
            stage_since_s: t0_s,
            blend: 0.0,
            ground_ned_m: None,
            ramp_done_s: None,
            last_collective: 0.0,
            descent_since_s: None,
            climb_refused: false,
            flags: DetectorFlags::default(),
            updates: 0,
        }
    }

    /// The same ground logic for a flight that starts in the air at `t0_s`:
    /// armed, flying, the land detector in the air, the command the law's
    /// (a simulation's start at its design point).
    pub fn in_flight(config: LandingConfig, ts_s: f64, u_trim: &Input, t0_s: f64) -> Self {
        let mut l = Landing::new(config, ts_s, u_trim, t0_s);
        l.state = SpoolState::Flying;
        l.stage = LandStage::Air;
        l.blend = 1.0;
        l.last_collective = u_trim[0];
        l
    }

    /// The state now.
    pub fn state(&self) -> SpoolState {
        self.state
    }

    /// The land detector's stage now.
    pub fn stage(&self) -> LandStage {
        self.stage
    }

    /// The blend from ground idle (0) to the command of the mode (1).
    pub fn blend(&self) -> f64 {
        self.blend
    }

    /// Ground idle: the servo commands on the ground.
    pub fn idle(&self) -> &Input {
        &self.idle
    }

    /// On the ground (not taking off, not flying).
    pub fn on_ground(&self) -> bool {
        !matches!(self.state, SpoolState::TakingOff | SpoolState::Flying)
            && self.stage == LandStage::Landed
    }

    /// The law's integrators are held at zero this sample: on the ground,
    /// and taking off until the ramp has reached the law's command (as
    /// PX4's take-off releases its integrators once the throttle ramp is
    /// done). From there they run, so a climb the law without its
    /// integrators would not make (a hover in ground effect below the
    /// lift-off test) lifts off or meets the take-off's timeout.
    pub fn holds_law(&self) -> bool {
        match self.state {
            SpoolState::Flying => false,
            SpoolState::TakingOff => self.ramp_done_s.is_none(),
            _ => true,
        }
    }

    /// The rotor is at speed (ready, taking off, flying, landed).
    pub fn rotor_at_speed(&self) -> bool {
        matches!(
            self.state,
            SpoolState::Ready | SpoolState::TakingOff | SpoolState::Flying | SpoolState::Landed
        )
    }

    /// The ground station's view.
    pub fn ground_state(&self) -> GroundState {
        let landed = match (self.state, self.stage) {
            (SpoolState::TakingOff, _) => LandedState::Takeoff,
            (SpoolState::Flying, LandStage::Air) => LandedState::InAir,
            (SpoolState::Flying, _) => LandedState::Landing,
            // disarmed in the air (the kill), until still on the ground
            (SpoolState::SpoolingDown | SpoolState::Disarmed, LandStage::Air) => LandedState::InAir,
            _ => LandedState::OnGround,
        };
        let rotor = match self.state {
            SpoolState::Disarmed => RotorRunup::Stopped,
            SpoolState::SpoolingUp => RotorRunup::SpoolingUp,
            SpoolState::SpoolingDown => RotorRunup::SpoolingDown,
            _ => RotorRunup::AtSpeed,
        };
        GroundState { landed, rotor }
    }

    /// The servo command sent: `mode_command` (the law's, the pilot's, the
    /// trim) blended from ground idle; the pilot's sticks (`manual`) pass
    /// unchanged. Remembers the collective for the detector.
    pub fn servo(&mut self, mode_command: &Input, manual: bool) -> Input {
        let out = if manual || self.blend >= 1.0 {
            *mode_command
        } else {
            self.idle + (mode_command - self.idle) * self.blend
        };
        self.last_collective = out[0];
        out
    }

    fn enter(&mut self, to: SpoolState, now_s: f64, change: &mut Option<(SpoolState, SpoolState)>) {
        if to != self.state {
            *change = Some((change.map_or(self.state, |c| c.0), to));
            self.state = to;
            self.since_s = now_s;
        }
    }

    fn set_stage(&mut self, stage: LandStage, now_s: f64) {
        if stage != self.stage {
            self.stage = stage;
            self.stage_since_s = now_s;
        }
    }

    /// One sample, after the law: the state's transitions and the blend of
    /// the next command. Call [`Landing::servo`] for this sample's command
    /// before. No allocation.
    pub fn update(&mut self, i: &LandingInput<'_>) -> LandingStep {
        let c = self.config;
        let now = i.now_s;
        let stage_before = self.stage;
        self.flags = DetectorFlags::default();
        let mut change = None;
        let mut disarm = false;
        let mut takeoff_aborted = false;
        let ramp = self.ts_s / c.takeoff_ramp_s;
        let (pos, vel) = match i.position_velocity_ned {
            Some((p, v)) if p.iter().chain(v.iter()).all(|x| x.is_finite()) => (Some(p), Some(v)),
            _ => (None, None),
        };
        let mut climb_asked = i.armed && i.auto && i.reference.velocity_ned_m_s.z < -0.1;
        if !climb_asked {
            self.climb_refused = false;
        }
        climb_asked &= !self.climb_refused;
        if !i.armed {
            self.settle_disarmed(i, vel, now);
            match self.state {
                SpoolState::Disarmed => {}
                SpoolState::SpoolingDown => {
                    if now - self.since_s >= c.spooldown_s {
                        self.enter(SpoolState::Disarmed, now, &mut change);
                    }
                }
                _ => self.enter(SpoolState::SpoolingDown, now, &mut change),
            }
            self.blend = 0.0;
        } else {
            match self.state {
                SpoolState::Disarmed | SpoolState::SpoolingDown => {
                    self.enter(SpoolState::SpoolingUp, now, &mut change);
                }
                SpoolState::SpoolingUp => {
                    if now - self.since_s >= c.runup_s - 1e-9 {
                        self.enter(SpoolState::Ready, now, &mut change);
                    }
                }
                SpoolState::Ready | SpoolState::Landed => {
                    self.blend = (self.blend - ramp).max(0.0);
                    if climb_asked {
                        self.ground_ned_m = pos;
                        self.ramp_done_s = None;
                        self.enter(SpoolState::TakingOff, now, &mut change);
                    } else if self.state == SpoolState::Landed
                        && c.disarm_after_s >= 0.0
                        && now - self.since_s >= c.disarm_after_s - 1e-9
                    {
                        disarm = true;
                    }
                }
                SpoolState::TakingOff => {
                    self.blend = (self.blend + ramp).min(1.0);
                    if self.blend >= 1.0 && self.ramp_done_s.is_none() {
                        self.ramp_done_s = Some(now);
                    }
                    let lifted = match (pos, vel, self.ground_ned_m) {
                        (Some(p), Some(v), Some(g)) => {
                            g.z - p.z >= c.liftoff_height_m || -v.z >= c.liftoff_climb_m_s
                        }
                        (Some(_), Some(v), None) => -v.z >= c.liftoff_climb_m_s,
                        _ => false,
                    };
                    if lifted {
                        self.set_stage(LandStage::Air, now);
                        self.enter(SpoolState::Flying, now, &mut change);
                    } else if !climb_asked {
                        self.enter(SpoolState::Ready, now, &mut change);
                    } else if self
                        .ramp_done_s
                        .is_some_and(|t| now - t >= c.takeoff_timeout_s)
                    {
                        takeoff_aborted = true;
                        self.climb_refused = true;
                        self.enter(SpoolState::Ready, now, &mut change);
                    }
                }
                SpoolState::Flying => self.detect(i, vel, now, ramp, &mut change),
            }
        }
        self.updates += 1;
        LandingStep {
            change,
            disarm,
            throttle_hold: matches!(self.state, SpoolState::Disarmed | SpoolState::SpoolingDown),
            takeoff_aborted,
            stage: self.stage,
            report: change.is_some() || self.stage != stage_before || self.updates == 1,
            flags: self.flags,
        }
    }

    /// Disarmed off the ground (a kill in the air): on the ground again
    /// once still and not rotating for the whole trigger time.
    fn settle_disarmed(&mut self, i: &LandingInput<'_>, vel: Option<Vector3<f64>>, now: f64) {
        if self.stage == LandStage::Landed {
            return;
        }
        let c = self.config;
        // a sample without its evidence tells nothing (as in flight)
        if !Self::evidence(i, vel) {
            return;
        }
        let still = self.not_moving(vel) && !self.rotating(i.gyro_body_rad_s);
        if !still {
            self.set_stage(LandStage::Air, now);
        } else if self.stage == LandStage::Air {
            self.set_stage(LandStage::MaybeLanded, now);
        } else if now - self.stage_since_s >= c.trigger_s - 1e-9 {
            self.set_stage(LandStage::Landed, now);
        }
    }

    /// The sample carries the detector's evidence: the IMU's rates and the
    /// navigation's velocity (a step without a fresh sample has neither).
    fn evidence(i: &LandingInput<'_>, vel: Option<Vector3<f64>>) -> bool {
        vel.is_some() && i.gyro_body_rad_s.is_some()
    }

    /// No vertical and no horizontal movement (an unknown velocity moves).
    fn not_moving(&self, vel: Option<Vector3<f64>>) -> bool {
        let c = &self.config;
        vel.is_some_and(|v| v.z.abs() < c.z_vel_max_m_s && v.xy().norm() < c.xy_vel_max_m_s)
    }

    /// A body rate at or above `rot_max_deg_s` (unknown rates rotate).
    fn rotating(&self, gyro_body_rad_s: Option<Vector3<f64>>) -> bool {
        let max = self.config.rot_max_deg_s;
        gyro_body_rad_s.is_none_or(|w| w.iter().any(|r| r.abs().to_degrees() >= max))
    }

    /// The land detector in flight, and the blend it drives.
    fn detect(
        &mut self,
        i: &LandingInput<'_>,
        vel: Option<Vector3<f64>>,
        now: f64,
        ramp: f64,
        change: &mut Option<(SpoolState, SpoolState)>,
    ) {
        let c = self.config;
        let way = |col: f64| {
            let span = self.hover_collective - self.idle[0];
            if span.abs() < 1e-9 {
                1.0
            } else {
                (col - self.idle[0]) / span
            }
        };
        let still = self.not_moving(vel);
        // a descent asked for (faster than "no vertical movement", PX4's
        // 1.1·LNDMC_Z_VEL_MAX) for the whole trigger time that does not
        // happen: the ground stops it (a descent just begun has not yet
        // moved)
        if i.reference.velocity_ned_m_s.z >= 1.1 * c.z_vel_max_m_s {
            self.descent_since_s.get_or_insert(now);
        } else {
            self.descent_since_s = None;
        }
        let descent_asked = self
            .descent_since_s
            .is_some_and(|t| now - t >= c.trigger_s - 1e-9);
        let low = way(self.last_collective) < c.low_collective;
        let contact = still && (low || descent_asked);
        let rotating = self.rotating(i.gyro_body_rad_s);
        let minimal = way(self.last_collective) <= 0.1;
        self.flags = DetectorFlags {
            low_collective: low,
            vertical_movement: vel.is_none_or(|v| v.z.abs() >= c.z_vel_max_m_s),
            horizontal_movement: vel.is_none_or(|v| v.xy().norm() >= c.xy_vel_max_m_s),
            rotating,
            descending: self.descent_since_s.is_some(),
        };
        // a sample without the IMU's rates or the navigation's velocity (a
        // reader that fell behind, a sample refused) tells nothing: the
        // stage and its clock stay, the blend goes on as the stage has it.
        // Taken as moving, every such sample would send a touchdown back to
        // the air, and a real-time board that misses one sample in ten
        // would never land. A sensor silent for its stale limit is the
        // supervisor's failsafe.
        let evidence = Self::evidence(i, vel);
        let third = c.trigger_s / 3.0 - 1e-9;
        let held = now - self.stage_since_s >= third;
        let next = match self.stage {
            s if !evidence => s,
            _ if !contact => LandStage::Air,
            LandStage::Air => LandStage::GroundContact,
            LandStage::GroundContact if held && minimal && !rotating => LandStage::MaybeLanded,
            LandStage::GroundContact => LandStage::GroundContact,
            LandStage::MaybeLanded if !minimal || rotating => LandStage::GroundContact,
            LandStage::MaybeLanded if held => LandStage::Landed,
            s => s,
        };
        // a new stage restarts its clock; the command blends down once
        // ground contact has held a third of the trigger time
        self.set_stage(next, now);
        let contact_held = now - self.stage_since_s >= third;
        match self.stage {
            LandStage::Air => self.blend = (self.blend + ramp).min(1.0),
            LandStage::GroundContact if !contact_held => {}
            _ => self.blend = (self.blend - ramp).max(0.0),
        }
        if self.stage == LandStage::Landed {
            self.enter(SpoolState::Landed, now, change);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TS: f64 = 0.0025;

    fn trim() -> Input {
        Input::new(0.1, 0.0, 0.0, 0.05)
    }

    fn input<'a>(
        now_s: f64,
        armed: bool,
        reference: &'a Reference,
        pv: (Vector3<f64>, Vector3<f64>),
        gyro: Vector3<f64>,
    ) -> LandingInput<'a> {
        LandingInput {
            now_s,
            armed,
            auto: true,
            reference,
            position_velocity_ned: Some(pv),
            gyro_body_rad_s: Some(gyro),
        }
    }

    #[test]
    fn the_defaults_are_valid_and_each_field_is_checked() {
        LandingConfig::default().validate("onboard.toml").unwrap();
        let c = LandingConfig {
            trigger_s: f64::NAN,
            ..LandingConfig::default()
        };
        let e = c.validate("onboard.toml").unwrap_err().to_string();
        assert!(e.contains("landing.trigger_s"), "{e}");
        let c = LandingConfig {
            runup_s: -1.0,
            ..LandingConfig::default()
        };
        assert!(c.validate("x").is_err());
    }

    /// Arm, run-up, a climb asked, the ramp, lift-off, a landing detected
    /// in its three stages, the disarm after the time on the ground, the
    /// spool-down: every transition at its time.
    #[test]
    fn from_the_ground_to_the_ground() {
        let c = LandingConfig::default();
        let mut l = Landing::new(c, TS, &trim(), 0.0);
        let hover = Reference::default();
        let climb = Reference {
            velocity_ned_m_s: Vector3::new(0.0, 0.0, -1.0),
            yaw_rad: 0.0,
        };
        let still = (Vector3::new(0.0, 0.0, -0.3), Vector3::zeros());
        let mut t = 0.0;
        let mut log = Vec::new();
        let step = |l: &mut Landing, t: f64, armed: bool, r: &Reference, pv, law: &Input| {
            let u = l.servo(law, false);
            let s = l.update(&input(t, armed, r, pv, Vector3::zeros()));
            (u, s)
        };
        // disarmed: ground idle, engine cut
        let (u, s) = step(&mut l, t, false, &hover, still, &trim());
        assert_eq!(u, Input::zeros());
        assert!(s.throttle_hold && l.on_ground());
        // armed: spooling up for runup_s, ready after
        while t < c.runup_s + 0.01 {
            t += TS;
            let (u, s) = step(&mut l, t, true, &hover, still, &trim());
            assert_eq!(u, Input::zeros());
            assert!(!s.throttle_hold);
            if let Some(ch) = s.change {
                log.push((t, ch));
            }
        }
        assert_eq!(l.state(), SpoolState::Ready);
        assert!((log[1].0 - c.runup_s).abs() < 2.0 * TS, "{log:?}");
        // a climb: the ramp with the integrators held, the integrators
        // released once it is complete (the skids still down), then
        // lift-off at 0.3 m
        let law = Input::new(0.12, 0.0, 0.0, 0.05);
        let t_climb = t;
        let mut z = -0.3;
        let mut released = false;
        while l.state() != SpoolState::Flying {
            t += TS;
            if t - t_climb > c.takeoff_ramp_s + 0.5 {
                z -= 0.5 * TS;
            }
            let (u, _) = step(
                &mut l,
                t,
                true,
                &climb,
                (Vector3::new(0.0, 0.0, z), Vector3::new(0.0, 0.0, -0.1)),
                &law,
            );
            assert!(u[0] <= law[0] + 1e-12);
            if l.state() == SpoolState::TakingOff {
                assert_eq!(l.holds_law(), l.blend() < 1.0, "t = {t}");
                released |= !l.holds_law();
            }
            assert!(t - t_climb < 5.0, "no lift-off");
        }
        assert!(released, "the integrators ran before lift-off");
        assert!(!l.holds_law());
        assert!((-0.3 - z - c.liftoff_height_m).abs() < 0.01, "{z}");
        assert_eq!(l.ground_state().landed, LandedState::InAir);
        // the landing: still, a descent asked, the collective falling with
        // the blend: contact, maybe landed, landed within the trigger time
        // plus the ramp down
        let down = Reference {
            velocity_ned_m_s: Vector3::new(0.0, 0.0, 0.3),
            yaw_rad: 0.0,
        };
        let t_touch = t;
        while l.state() != SpoolState::Landed {
            t += TS;
            step(&mut l, t, true, &down, still, &law);
            assert!(t - t_touch < 5.0, "not landed");
        }
        let took = t - t_touch;
        // the descent asked for a trigger time, contact a third of it, the
        // ramp to a tenth of hover, two thirds more
        assert!(
            took > 2.0 * c.trigger_s && took < 2.0 * c.trigger_s + c.takeoff_ramp_s,
            "{took}"
        );
        assert!(l.on_ground());
        // disarm after disarm_after_s, then spool down
        let t_landed = t;
        loop {
            t += TS;
            let (_, s) = step(&mut l, t, true, &down, still, &law);
            if s.disarm {
                break;
            }
        }
        assert!((t - t_landed - c.disarm_after_s).abs() < 2.0 * TS);
        let (_, s) = step(&mut l, t + TS, false, &down, still, &law);
        assert_eq!(
            s.change,
            Some((SpoolState::Landed, SpoolState::SpoolingDown))
        );
        assert!(s.throttle_hold);
    }

    /// A touchdown whose samples now and then come without the IMU's rates
    /// or the navigation's velocity (a real-time reader that fell behind:
    /// one sample in three here) lands, in the time a touchdown without
    /// gaps takes (to a sample a stage): a missing sample holds the detector, it
    /// does not send it back to the air. Disarmed in the air (a kill), the
    /// settling on the ground holds the same way.
    #[test]
    fn samples_without_their_evidence_hold_the_land_detector() {
        let c = LandingConfig::default();
        let down = Reference {
            velocity_ned_m_s: Vector3::new(0.0, 0.0, 0.3),
            yaw_rad: 0.0,
        };
        let still = (Vector3::new(0.0, 0.0, -0.3), Vector3::zeros());
        let law = Input::new(0.12, 0.0, 0.0, 0.05);
        // from flying to landed, each `gap`-th sample without evidence
        let land = |gap: Option<usize>, armed: bool| {
            let mut l = Landing::in_flight(c, TS, &trim(), 0.0);
            let mut t = 0.0;
            for k in 1.. {
                t += TS;
                let missing = gap.is_some_and(|g| k % g == 0);
                l.servo(&law, false);
                let mut i = input(t, armed, &down, still, Vector3::zeros());
                if missing {
                    i.position_velocity_ned = if k % 2 == 0 { None } else { Some(still) };
                    i.gyro_body_rad_s = if k % 2 == 0 {
                        Some(Vector3::zeros())
                    } else {
                        None
                    };
                }
                l.update(&i);
                if l.stage() == LandStage::Landed {
                    break;
                }
                assert!(
                    t < 10.0,
                    "gap {gap:?}, armed {armed}: not landed: {:?}",
                    l.stage()
                );
            }
            t
        };
        for armed in [true, false] {
            let (whole, gappy) = (land(None, armed), land(Some(3), armed));
            // each of the three stages' changes waits at most one sample
            // for one with its evidence
            assert!(
                (whole - gappy).abs() <= 3.0 * TS + 1e-9,
                "armed {armed}: landed at {whole} s, with gaps at {gappy} s"
            );
        }
    }

    /// In the air, hovering at the trim collective, or descending: no
    /// ground contact, ever.
    #[test]
    fn no_landing_in_a_hover_or_a_descent() {
        let mut l = Landing::new(LandingConfig::default(), TS, &trim(), 0.0);
        l.state = SpoolState::Flying;
        l.stage = LandStage::Air;
        l.blend = 1.0;
        let hover = Reference::default();
        let down = Reference {
            velocity_ned_m_s: Vector3::new(0.0, 0.0, 0.5),
            yaw_rad: 0.0,
        };
        for k in 0..4000 {
            let t = f64::from(k) * TS;
            // a hover: still, the trim collective
            let (r, v) = if k < 2000 {
                (&hover, Vector3::new(0.2, 0.0, 0.05))
            } else {
                (&down, Vector3::new(0.0, 0.0, 0.45))
            };
            l.servo(&trim(), false);
            l.update(&input(
                t,
                true,
                r,
                (Vector3::new(0.0, 0.0, -5.0), v),
                Vector3::zeros(),
            ));
            assert_eq!(l.state(), SpoolState::Flying, "t = {t}");
        }
        assert_eq!(l.blend(), 1.0);
    }

    /// Ground contact holds a third of the trigger time before the command
    /// blends down (a touch that does not last leaves the law flying); a
    /// kill in the air is reported in the air until still on the ground.
    #[test]
    fn contact_holds_before_the_blend_and_a_kill_in_the_air_is_in_the_air() {
        let c = LandingConfig::default();
        let mut l = Landing::new(c, TS, &trim(), 0.0);
        l.state = SpoolState::Flying;
        l.stage = LandStage::Air;
        l.blend = 1.0;
        let hover = Reference::default();
        let still = (Vector3::zeros(), Vector3::zeros());
        let low = Input::new(0.02, 0.0, 0.0, 0.05);
        let sinking = (Vector3::zeros(), Vector3::new(0.0, 0.0, 0.5));
        let mut t = 0.0;
        let mut first_drop = None;
        // a second in the air, then still with a low collective
        for k in 0..800 {
            t += TS;
            l.servo(&low, false);
            let pv = if k < 400 { sinking } else { still };
            l.update(&input(t, true, &hover, pv, Vector3::zeros()));
            if l.blend() < 1.0 && first_drop.is_none() {
                first_drop = Some(t);
            }
        }
        let t0 = 401.0 * TS; // the first still sample
        let drop = first_drop.expect("the blend went down") - t0;
        assert!((drop - c.trigger_s / 3.0).abs() < 2.0 * TS, "{drop}");
        // a kill in the air: in the air, then on the ground once still
        let mut l = Landing::new(c, TS, &trim(), 0.0);
        l.state = SpoolState::Flying;
        l.stage = LandStage::Air;
        let falling = (Vector3::zeros(), Vector3::new(0.0, 0.0, 3.0));
        l.update(&input(1.0, false, &hover, falling, Vector3::zeros()));
        assert_eq!(l.ground_state().landed, LandedState::InAir);
        assert!(!l.on_ground());
        let mut t = 1.0;
        while t < 1.0 + c.trigger_s + 0.1 {
            t += TS;
            l.update(&input(t, false, &hover, still, Vector3::zeros()));
        }
        assert!(l.on_ground());
        assert_eq!(l.ground_state().landed, LandedState::OnGround);
    }

    /// The codes are the indices of `ALL` (the logs' and plots' axes);
    /// a ground logic started in the air flies the law and lands by its
    /// detector, as one that took off.
    #[test]
    fn codes_index_all_and_a_start_in_the_air_flies_then_lands() {
        for (i, s) in SpoolState::ALL.iter().enumerate() {
            assert_eq!(usize::from(s.code()), i);
        }
        for (i, s) in LandStage::ALL.iter().enumerate() {
            assert_eq!(usize::from(s.code()), i);
        }
        let c = LandingConfig::default();
        let mut l = Landing::in_flight(c, TS, &trim(), 0.0);
        assert_eq!((l.state(), l.stage()), (SpoolState::Flying, LandStage::Air));
        assert!(!l.holds_law() && !l.on_ground());
        let law = Input::new(0.12, 0.01, -0.02, 0.05);
        assert_eq!(l.servo(&law, false), law);
        let s = l.update(&input(
            0.0,
            true,
            &Reference::default(),
            (Vector3::new(0.0, 0.0, -5.0), Vector3::new(0.0, 0.0, 0.4)),
            Vector3::zeros(),
        ));
        assert!(!s.throttle_hold && s.change.is_none());
        // still on the ground with a descent asked: landed within the
        // trigger time and the ramp down (as `from_the_ground_to_the_ground`)
        let down = Reference {
            velocity_ned_m_s: Vector3::new(0.0, 0.0, 0.3),
            yaw_rad: 0.0,
        };
        let still = (Vector3::zeros(), Vector3::zeros());
        let mut t = 0.0;
        while l.state() != SpoolState::Landed {
            t += TS;
            l.servo(&law, false);
            l.update(&input(t, true, &down, still, Vector3::zeros()));
            assert!(t < 2.0 * c.trigger_s + c.takeoff_ramp_s, "not landed");
        }
    }

    /// A climb withdrawn before lift-off goes back to ready; no lift-off
    /// within the timeout is given up.
    #[test]
    fn a_takeoff_without_liftoff_is_given_up() {
        let c = LandingConfig::default();
        let mut l = Landing::new(c, TS, &trim(), 0.0);
        l.state = SpoolState::Ready;
        let climb = Reference {
            velocity_ned_m_s: Vector3::new(0.0, 0.0, -1.0),
            yaw_rad: 0.0,
        };
        let still = (Vector3::zeros(), Vector3::zeros());
        let mut t = 0.0;
        let mut aborted = false;
        while t < c.takeoff_ramp_s + c.takeoff_timeout_s + 1.0 {
            t += TS;
            l.servo(&trim(), false);
            let s = l.update(&input(t, true, &climb, still, Vector3::zeros()));
            if s.takeoff_aborted {
                aborted = true;
                assert!(
                    (t - c.takeoff_ramp_s - c.takeoff_timeout_s).abs() < 0.01,
                    "{t}"
                );
                break;
            }
        }
        assert!(aborted);
        assert_eq!(l.state(), SpoolState::Ready);
        // armed, ready: the arm refusal aside, the run-up is not redone
        assert!(l.rotor_at_speed());
    }
}
