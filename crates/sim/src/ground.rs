//! From the ground to the ground: the scenario's `[ground]` section, the
//! on-board ground logic flown in the simulator, and the flight's ground
//! metrics.
//!
//! ```toml
//! [ground]
//! on_ground = true      # start resting on the skids (needs landing_gear.enabled)
//! spool_up_s = 0.0      # the operator arms: the engine starts (drivetrain.enabled: the rotor starts at rest)
//! takeoff_s = 7.0       # the operator switches to auto: a climb asked for from then takes off
//! ramp_s = 2.0          # the on-board take-off and touchdown blend (landing.takeoff_ramp_s)
//! land_after_s = 20.0   # the first touchdown after this time is the landing measured
//! shutdown_delay_s = 2.0 # on-board disarm this long after landing (landing.disarm_after_s)
//! ```
//!
//! The take-off and the landing are the on-board program's
//! ([`helicon_flight::landing`], the same code `helicon sitl` and the
//! helicopter fly): its spool state (disarmed → spooling up → ready →
//! taking off → flying → landed → spooling down), its land detector, the
//! take-off held (the law's integrators at zero, the command blended from
//! ground idle) until it detects lift-off, the landing blended down to
//! ground idle once it detects ground contact, and the disarm after
//! `shutdown_delay_s` on the ground, which cuts the engine. The simulator
//! only plays the operator: it arms at `spool_up_s` (and never re-arms
//! after the on-board disarm), switches to auto at `takeoff_s`; the
//! scenario's references ask for the climb and the descent. The on-board
//! settings are [`LandingConfig::default`] (as `helicon sitl` flies) with
//! `ramp_s` and `shutdown_delay_s`. The metrics come from the truth: the
//! skids' contact, the true position and velocity.

use crate::scenario::ScenarioError;
use helicon_core::Reference;
use helicon_flight::landing::{
    LandStage, Landing, LandingConfig, LandingInput, LandingStep, SpoolState,
};
use helicon_model::drivetrain::Spool;
use helicon_model::landing_gear::N_CONTACT;
use helicon_model::{Input, Params, State, state::ix};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// The scenario's `[ground]` section.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GroundSection {
    /// Start resting on the skids, rotor stopped (with the drivetrain) and
    /// the on-board ground logic disarmed; needs `landing_gear.enabled`.
    /// Off: the flight starts in the air at the design point, armed and
    /// flying, the land detector running.
    pub on_ground: bool,
    /// The operator arms at this time (s): the engine starts; with the
    /// drivetrain on, the rotor spools up from rest in
    /// `drivetrain.spool_up_s`, and the on-board run-up timer
    /// (`landing.runup_s`) runs.
    pub spool_up_s: f64,
    /// The operator switches to auto at this time (s): from then on, the
    /// rotor at speed, a climb of the references takes off.
    pub takeoff_s: f64,
    /// The on-board blend from ground idle into the law at take-off, and
    /// back at touchdown (s; `landing.takeoff_ramp_s`).
    pub ramp_s: f64,
    /// The first touchdown after this time (s) is the landing measured.
    pub land_after_s: f64,
    /// The on-board disarm this long after landing (s;
    /// `landing.disarm_after_s`): the engine cut.
    pub shutdown_delay_s: f64,
}

impl Default for GroundSection {
    fn default() -> Self {
        GroundSection {
            on_ground: true,
            spool_up_s: 0.0,
            takeoff_s: 7.0,
            ramp_s: 2.0,
            land_after_s: 20.0,
            shutdown_delay_s: 2.0,
        }
    }
}

impl GroundSection {
    /// Check the times and that the parameters have the blocks it needs.
    pub fn validate(&self, file: &str, duration_s: f64) -> Result<(), ScenarioError> {
        let bad = |field: &str, v: f64, rule: &str| {
            ScenarioError::invalid(file, format!("ground.{field}"), v, rule)
        };
        for (field, v) in [
            ("spool_up_s", self.spool_up_s),
            ("takeoff_s", self.takeoff_s),
            ("land_after_s", self.land_after_s),
            ("shutdown_delay_s", self.shutdown_delay_s),
        ] {
            if !(v.is_finite() && (0.0..=duration_s).contains(&v)) {
                return Err(bad(field, v, "must be finite, >= 0 and <= duration_s"));
            }
        }
        if !(self.ramp_s.is_finite() && self.ramp_s > 0.0 && self.ramp_s <= duration_s) {
            return Err(bad(
                "ramp_s",
                self.ramp_s,
                "must be finite, > 0 and <= duration_s",
            ));
        }
        // the on-board ground logic's own ranges (landing.takeoff_ramp_s,
        // landing.disarm_after_s), named by the scenario's fields
        if !(0.1..=30.0).contains(&self.ramp_s) {
            return Err(bad(
                "ramp_s",
                self.ramp_s,
                "must be within 0.1..=30 (the on-board landing.takeoff_ramp_s)",
            ));
        }
        if self.shutdown_delay_s > 600.0 {
            return Err(bad(
                "shutdown_delay_s",
                self.shutdown_delay_s,
                "must be <= 600 (the on-board landing.disarm_after_s)",
            ));
        }
        if self.takeoff_s < self.spool_up_s {
            return Err(bad(
                "takeoff_s",
                self.takeoff_s,
                "must be >= ground.spool_up_s (the engine starts first)",
            ));
        }
        if self.land_after_s < self.takeoff_s {
            return Err(bad(
                "land_after_s",
                self.land_after_s,
                "must be >= ground.takeoff_s",
            ));
        }
        Ok(())
    }

    /// The on-board ground logic's settings this section flies: the
    /// on-board defaults (as `helicon sitl` flies them) with `ramp_s` and
    /// `shutdown_delay_s`.
    pub fn landing_config(&self) -> LandingConfig {
        LandingConfig {
            takeoff_ramp_s: self.ramp_s,
            disarm_after_s: self.shutdown_delay_s,
            ..LandingConfig::default()
        }
    }

    /// Check the parameters flown: `on_ground` needs the landing gear.
    pub fn check_params(&self, params: &Params, file: &str) -> Result<(), ScenarioError> {
        if self.on_ground && !params.landing_gear.is_enabled() {
            return Err(ScenarioError::invalid(
                file,
                "ground.on_ground",
                1.0,
                "needs landing_gear.enabled = true in the parameters (the ground to stand on)",
            ));
        }
        Ok(())
    }
}

/// What the ground log keeps of one sample.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GroundSample {
    /// Lowest skid point's height above the ground (m; ≤ 0 in contact; NaN without the landing gear).
    pub clearance_m: f64,
    /// Rotor speed Ω (rad/s).
    pub omega_rad_s: f64,
    /// Throttle (0 … 1; 0 without the drivetrain).
    pub throttle: f64,
    /// Normal force of each contact point (N).
    pub normal_n: [f64; N_CONTACT],
    /// Total friction force (N, the sum of the points' magnitudes).
    pub friction_n: f64,
    /// Ground-effect factor k_G (0 when off).
    pub ground_effect_factor: f64,
    /// The on-board spool state after the sample ([`SpoolState::code`]:
    /// 0 disarmed … 6 spooling down; NaN without `[ground]`).
    pub spool_state: f64,
    /// The on-board land detector's stage after the sample
    /// ([`LandStage::code`]: 0 air … 3 landed; NaN without `[ground]`).
    pub land_stage: f64,
    /// The on-board blend from ground idle (0) to the flight law (1) of the
    /// sample's command (1 without `[ground]`).
    pub blend: f64,
}

/// The ground metrics of a flight, from the truth (the on-board decisions'
/// times besides).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct GroundMetrics {
    /// The operator's arming (the engine start, s; `None` when the flight
    /// started in the air).
    pub arm_time_s: Option<f64>,
    /// When the on-board ground logic began the take-off: ready, in auto,
    /// a climb asked for (s).
    pub takeoff_start_s: Option<f64>,
    /// Time from the start to lift-off, the first sample with no skid
    /// loaded after the on-board take-off began (s).
    pub liftoff_time_s: Option<f64>,
    /// From arming to lift-off (s): the run-up, the wait for a climb, the
    /// take-off ramp.
    pub arm_to_liftoff_s: Option<f64>,
    /// When the on-board ground logic detected the lift-off (s).
    pub liftoff_detected_s: Option<f64>,
    /// Horizontal displacement of the CM from its start to lift-off (m).
    pub liftoff_drift_m: Option<f64>,
    /// The rotor speed at lift-off (rad/s).
    pub liftoff_omega_rad_s: Option<f64>,
    /// Time of the landing's touchdown: the first sample with a skid loaded
    /// after lift-off and after `land_after_s` (s).
    pub touchdown_time_s: Option<f64>,
    /// Vertical speed (down, m/s) at touchdown: the last sample before the
    /// first skid touched.
    pub touchdown_vertical_speed_m_s: Option<f64>,
    /// Horizontal speed at touchdown (m/s).
    pub touchdown_horizontal_speed_m_s: Option<f64>,
    /// Horizontal distance of the touchdown from the lift-off point (m).
    pub touchdown_offset_m: Option<f64>,
    /// Horizontal displacement on the ground after touchdown until the end
    /// (m): the slide of the landing.
    pub touchdown_drift_m: Option<f64>,
    /// The largest total normal force in the landing (N).
    pub touchdown_peak_normal_n: Option<f64>,
    /// When the on-board land detector declared the helicopter landed,
    /// after the touchdown (s).
    pub landed_detected_s: Option<f64>,
    /// When the on-board ground logic disarmed after the landing (s).
    pub disarm_time_s: Option<f64>,
    /// The largest tilt of the airframe from the ground's normal (the angle
    /// between the body z axis and the ground's down normal, rad) over the
    /// samples with a skid loaded: on the ground before lift-off and after
    /// touchdown. 0 when the skids never carried load.
    pub max_tilt_on_ground_rad: f64,
    /// The rotor speed at the end (rad/s).
    pub final_omega_rad_s: f64,
}

/// The servo frame's throttle hold on the engine's spool: set, the engine
/// is cut; clear, the governor spools the rotor up from `omega_rad_s` (its
/// speed now) and holds it. The simulator's engine for the on-board
/// program's hold (here and in [`crate::closed_loop::Hardware`]).
pub fn apply_throttle_hold(spool: &mut Spool, hold: bool, omega_rad_s: f64) {
    if hold {
        spool.stop();
    } else {
        spool.start(omega_rad_s);
    }
}

/// The on-board ground logic flown by the simulator, with the operator's
/// inputs of the scenario and the truth's metrics; stepped once per
/// controller sample: [`GroundFlight::holds_law`] and
/// [`GroundFlight::servo`] around the flight software's step, then
/// [`GroundFlight::update`].
#[derive(Debug, Clone)]
pub struct GroundFlight {
    section: GroundSection,
    ts_s: f64,
    landing: Landing,
    /// The blend of the last command ([`GroundFlight::servo`]).
    sample_blend: f64,
    /// The on-board program disarmed after the landing: the operator does
    /// not arm again.
    disarmed: bool,
    /// The engine's spool ramp, when the drivetrain is on.
    spool: Option<Spool>,
    takeoff_begun: bool,
    start_xy: Vector3<f64>,
    liftoff_xy: Option<Vector3<f64>>,
    touchdown_xy: Option<Vector3<f64>>,
    last_xy: Vector3<f64>,
    prev_v: Vector3<f64>,
    /// The ground plane's down normal (NED), for the tilt on the ground.
    ground_down: Vector3<f64>,
    metrics: GroundMetrics,
}

fn horizontal(x: &State) -> Vector3<f64> {
    Vector3::new(x[ix::X], x[ix::Y], 0.0)
}

fn ned_velocity(x: &State) -> Vector3<f64> {
    helicon_model::frames::ned_from_body(x[ix::PHI], x[ix::THETA], x[ix::PSI])
        * Vector3::new(x[ix::U], x[ix::V], x[ix::W])
}

/// The angle between the body z axis and `down` (a unit vector, NED), rad.
fn tilt_rad(x: &State, down: &Vector3<f64>) -> f64 {
    let body_down = helicon_model::frames::ned_from_body(x[ix::PHI], x[ix::THETA], x[ix::PSI])
        * Vector3::new(0.0, 0.0, 1.0);
    body_down.dot(down).clamp(-1.0, 1.0).acos()
}

/// What the flight software knew of a sample, for the ground logic: the
/// navigation's position and velocity NED and the IMU's body rates (the
/// truth's with ideal navigation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OnBoardView {
    /// Position and velocity NED (m, m/s).
    pub position_velocity_ned: Option<(Vector3<f64>, Vector3<f64>)>,
    /// Body rates (rad/s).
    pub gyro_body_rad_s: Option<Vector3<f64>>,
}

/// The truth of a sample, for the metrics and the engine.
#[derive(Debug, Clone, Copy)]
pub struct TruthView<'a> {
    /// The plant's state at the sample.
    pub x: &'a State,
    /// Any skid carries load.
    pub on_ground: bool,
    /// The total normal force (N).
    pub total_normal_n: f64,
    /// The rotor speed (rad/s).
    pub omega_rad_s: f64,
}

impl GroundFlight {
    /// The ground logic of `section` for a flight starting at `x0`, with
    /// the hover trim `u_trim` (the on-board low-collective mark), control
    /// period `ts_s`, and the drivetrain's spool when the parameters have
    /// it (stopped on the ground, governed otherwise).
    pub fn new(
        section: &GroundSection,
        params: &Params,
        ts_s: f64,
        u_trim: &Input,
        x0: &State,
    ) -> GroundFlight {
        let spool = params.drivetrain.is_enabled().then(|| {
            if section.on_ground {
                Spool::stopped(params)
            } else {
                Spool::governed(params)
            }
        });
        let config = section.landing_config();
        let landing = if section.on_ground {
            Landing::new(config, ts_s, u_trim, 0.0)
        } else {
            Landing::in_flight(config, ts_s, u_trim, 0.0)
        };
        GroundFlight {
            section: *section,
            ts_s,
            sample_blend: landing.blend(),
            landing,
            disarmed: false,
            spool,
            takeoff_begun: !section.on_ground,
            start_xy: horizontal(x0),
            liftoff_xy: (!section.on_ground).then(|| horizontal(x0)),
            touchdown_xy: None,
            last_xy: horizontal(x0),
            prev_v: ned_velocity(x0),
            ground_down: -helicon_model::landing_gear::GroundPlane::new(&params.landing_gear)
                .up_ned,
            metrics: GroundMetrics::default(),
        }
    }

    /// The law's integrators are held at zero this sample (the on-board
    /// ground logic: on the ground, and taking off until the ramp has reached the law).
    pub fn holds_law(&self) -> bool {
        self.landing.holds_law()
    }

    /// The servos' command of this sample from the law's `law_command`:
    /// `None` when it is the law's (the blend at 1), else the blend from
    /// ground idle ([`Landing::servo`]).
    pub fn servo(&mut self, law_command: &Input) -> Option<Input> {
        self.sample_blend = self.landing.blend();
        let u = self.landing.servo(law_command, false);
        (u != *law_command).then_some(u)
    }

    /// The operator's arm switch at `t_s`.
    fn armed(&self, t_s: f64) -> bool {
        !self.disarmed && (!self.section.on_ground || t_s >= self.section.spool_up_s)
    }

    /// One sample after the flight software's: the operator's inputs at
    /// `t_s` and the on-board ground logic's update on what the flight
    /// software knew (`onboard`), the engine's throttle hold, the metrics
    /// from the `truth` at the sample's start.
    pub fn update(
        &mut self,
        t_s: f64,
        reference: &Reference,
        onboard: &OnBoardView,
        truth: &TruthView<'_>,
    ) -> LandingStep {
        let s = self.section;
        let x = truth.x;
        let armed = self.armed(t_s);
        if armed && self.metrics.arm_time_s.is_none() && s.on_ground {
            self.metrics.arm_time_s = Some(t_s);
        }
        if truth.on_ground {
            let tilt = tilt_rad(x, &self.ground_down);
            self.metrics.max_tilt_on_ground_rad = self.metrics.max_tilt_on_ground_rad.max(tilt);
        }
        let step = self.landing.update(&LandingInput {
            now_s: t_s,
            armed,
            auto: !s.on_ground || t_s >= s.takeoff_s,
            reference,
            position_velocity_ned: onboard.position_velocity_ned,
            gyro_body_rad_s: onboard.gyro_body_rad_s,
        });
        if step.disarm {
            // the supervisor disarms: from the next sample on
            self.disarmed = true;
            self.metrics.disarm_time_s.get_or_insert(t_s);
        }
        if let Some(spool) = self.spool.as_mut() {
            apply_throttle_hold(spool, step.throttle_hold, truth.omega_rad_s);
            spool.step(self.ts_s);
        }
        if let Some((_, to)) = step.change {
            match to {
                SpoolState::TakingOff => {
                    self.takeoff_begun = true;
                    self.metrics.takeoff_start_s.get_or_insert(t_s);
                }
                SpoolState::Flying => {
                    self.metrics.liftoff_detected_s.get_or_insert(t_s);
                }
                SpoolState::Landed if self.touchdown_xy.is_some() => {
                    self.metrics.landed_detected_s.get_or_insert(t_s);
                }
                _ => {}
            }
        }
        // the truth: lift-off after the take-off began, the landing's
        // touchdown after lift-off and land_after_s
        if self.takeoff_begun && self.liftoff_xy.is_none() && !truth.on_ground {
            let m = &mut self.metrics;
            self.liftoff_xy = Some(horizontal(x));
            m.liftoff_time_s = Some(t_s);
            m.arm_to_liftoff_s = m.arm_time_s.map(|a| t_s - a);
            m.liftoff_drift_m = Some((horizontal(x) - self.start_xy).norm());
            m.liftoff_omega_rad_s = Some(truth.omega_rad_s);
        }
        if self.liftoff_xy.is_some()
            && self.touchdown_xy.is_none()
            && truth.on_ground
            && t_s >= s.land_after_s
        {
            self.touchdown_xy = Some(horizontal(x));
            let m = &mut self.metrics;
            m.touchdown_time_s = Some(t_s);
            m.touchdown_vertical_speed_m_s = Some(self.prev_v.z);
            m.touchdown_horizontal_speed_m_s = Some(self.prev_v.xy().norm());
            m.touchdown_offset_m = self.liftoff_xy.map(|l| (horizontal(x) - l).norm());
        }
        if self.touchdown_xy.is_some() {
            let peak = self.metrics.touchdown_peak_normal_n.get_or_insert(0.0);
            *peak = peak.max(truth.total_normal_n);
        }
        self.prev_v = ned_velocity(x);
        self.last_xy = horizontal(x);
        step
    }

    /// The on-board spool state now.
    pub fn spool_state(&self) -> SpoolState {
        self.landing.state()
    }

    /// The on-board land detector's stage now.
    pub fn land_stage(&self) -> LandStage {
        self.landing.stage()
    }

    /// The on-board blend (0 idle … 1 law) of the last command.
    pub fn sample_blend(&self) -> f64 {
        self.sample_blend
    }

    /// The on-board ground logic.
    pub fn landing(&self) -> &Landing {
        &self.landing
    }

    /// The drive command of the present sample (governed when there is no
    /// drivetrain).
    pub fn drive(&self, params: &Params) -> helicon_model::drivetrain::DriveCommand {
        self.spool
            .unwrap_or_else(|| Spool::governed(params))
            .command
    }

    /// The metrics at the end of the flight, with the final rotor speed.
    pub fn metrics(&self, final_omega_rad_s: f64) -> GroundMetrics {
        let mut m = self.metrics;
        if let Some(td) = self.touchdown_xy {
            m.touchdown_drift_m = Some((self.last_xy - td).norm());
        }
        m.final_omega_rad_s = final_omega_rad_s;
        m
    }
}
