//! From the ground to the ground: the scenario's `[ground]` section, the
//! simulator's simple take-off and landing plan, and the flight's ground
//! metrics.
//!
//! ```toml
//! [ground]
//! on_ground = true      # start resting on the skids (needs landing_gear.enabled)
//! spool_up_s = 0.0      # engine start (drivetrain.enabled: the rotor starts at rest)
//! takeoff_s = 7.0       # the collective ramp from ground idle to the flight law starts
//! ramp_s = 2.0          # the ramp's length (both ways)
//! land_after_s = 20.0   # touching down after this time ends the flight: ramp back, engine cut
//! shutdown_delay_s = 2.0 # engine cut this long after touchdown
//! ```
//!
//! The plan (the on-board land detector is not in the loop): until
//! `takeoff_s` the servos get ground idle — zero collective, centred cyclic
//! and tail, the flight software running but its command unused; from
//! `takeoff_s` the command blends linearly from ground idle to the flight
//! law's over `ramp_s` (the law's references — e.g. a climb on `vd` — lift
//! it off); after `land_after_s` the first touchdown (any skid carrying
//! load) blends back to ground idle over `ramp_s` and cuts the engine
//! `shutdown_delay_s` later.

use crate::scenario::ScenarioError;
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
    /// the servos at ground idle; needs `landing_gear.enabled`.
    pub on_ground: bool,
    /// Engine start time (s); with the drivetrain on, the rotor spools up
    /// from rest in `drivetrain.spool_up_s`.
    pub spool_up_s: f64,
    /// Start of the take-off ramp (s).
    pub takeoff_s: f64,
    /// Length of the take-off and landing ramps (s).
    pub ramp_s: f64,
    /// The first touchdown after this time (s) is the landing.
    pub land_after_s: f64,
    /// Engine cut this long after the touchdown (s).
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

/// The plan's phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Phase {
    /// On the ground at idle.
    Ground,
    /// Blending into the flight law.
    TakingOff,
    /// Flying the law.
    Flying,
    /// Touched down: blending back to idle, engine cut after the delay.
    Landed,
}

impl Phase {
    /// The phase as a number for the ground log (0 … 3).
    pub fn code(self) -> f64 {
        match self {
            Phase::Ground => 0.0,
            Phase::TakingOff => 1.0,
            Phase::Flying => 2.0,
            Phase::Landed => 3.0,
        }
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
    /// The plan's phase code ([`Phase::code`]).
    pub phase: f64,
    /// The blend from ground idle (0) to the flight law (1).
    pub blend: f64,
}

/// The ground metrics of a flight.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct GroundMetrics {
    /// Time from the start to lift-off, the first sample with no skid
    /// loaded after the take-off ramp began (s).
    pub liftoff_time_s: Option<f64>,
    /// Horizontal displacement of the CM from its start to lift-off (m).
    pub liftoff_drift_m: Option<f64>,
    /// The rotor speed at lift-off (rad/s).
    pub liftoff_omega_rad_s: Option<f64>,
    /// Time of the landing's touchdown (s).
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
    /// The largest tilt of the airframe from the ground's normal (the angle
    /// between the body z axis and the ground's down normal, rad) over the
    /// samples with a skid loaded: on the ground before lift-off and after
    /// touchdown. 0 when the skids never carried load.
    pub max_tilt_on_ground_rad: f64,
    /// The rotor speed at the end (rad/s).
    pub final_omega_rad_s: f64,
}

/// The take-off and landing plan, stepped once per controller sample.
#[derive(Debug, Clone)]
pub struct GroundPlan {
    section: GroundSection,
    ts_s: f64,
    idle: Input,
    phase: Phase,
    blend: f64,
    /// The engine's spool ramp, when the drivetrain is on.
    pub spool: Option<Spool>,
    touchdown_at: Option<f64>,
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

impl GroundPlan {
    /// The plan of `section` for a flight starting at `x0`, with the
    /// drivetrain's spool when the parameters have it (started stopped
    /// when on the ground, governed otherwise).
    pub fn new(section: &GroundSection, params: &Params, ts_s: f64, x0: &State) -> GroundPlan {
        let spool = params.drivetrain.is_enabled().then(|| {
            if section.on_ground {
                Spool::stopped(params)
            } else {
                Spool::governed(params)
            }
        });
        let idle = Input::zeros();
        GroundPlan {
            section: *section,
            ts_s,
            idle,
            phase: if section.on_ground {
                Phase::Ground
            } else {
                Phase::Flying
            },
            blend: if section.on_ground { 0.0 } else { 1.0 },
            spool,
            touchdown_at: None,
            start_xy: horizontal(x0),
            liftoff_xy: None,
            touchdown_xy: None,
            last_xy: horizontal(x0),
            prev_v: ned_velocity(x0),
            ground_down: -helicon_model::landing_gear::GroundPlane::new(&params.landing_gear)
                .up_ned,
            metrics: GroundMetrics::default(),
        }
    }

    /// The command to the servos at `t_s` from the law's `law_command`,
    /// the plan advancing one sample; `on_ground`: any skid carries load,
    /// `x`: the plant's true state at the sample, `omega_rad_s` its rotor
    /// speed.
    pub fn command(
        &mut self,
        t_s: f64,
        law_command: &Input,
        on_ground: bool,
        x: &State,
        omega_rad_s: f64,
    ) -> Input {
        let s = self.section;
        if on_ground {
            let tilt = tilt_rad(x, &self.ground_down);
            self.metrics.max_tilt_on_ground_rad = self.metrics.max_tilt_on_ground_rad.max(tilt);
        }
        if let Some(spool) = self.spool.as_mut() {
            if t_s >= s.spool_up_s && self.touchdown_at.is_none() {
                spool.start(omega_rad_s);
            }
            spool.step(self.ts_s);
        }
        let ramp = self.ts_s / s.ramp_s;
        match self.phase {
            Phase::Ground => {
                if t_s >= s.takeoff_s {
                    self.phase = Phase::TakingOff;
                }
            }
            Phase::TakingOff | Phase::Flying => {
                self.blend = (self.blend + ramp).min(1.0);
                if self.phase == Phase::TakingOff && !on_ground {
                    self.phase = Phase::Flying;
                    self.liftoff_xy = Some(horizontal(x));
                    self.metrics.liftoff_time_s = Some(t_s);
                    self.metrics.liftoff_drift_m = Some((horizontal(x) - self.start_xy).norm());
                    self.metrics.liftoff_omega_rad_s = Some(omega_rad_s);
                }
                if self.phase == Phase::Flying && on_ground && t_s >= s.land_after_s {
                    self.phase = Phase::Landed;
                    self.touchdown_at = Some(t_s);
                    self.touchdown_xy = Some(horizontal(x));
                    let m = &mut self.metrics;
                    m.touchdown_time_s = Some(t_s);
                    m.touchdown_vertical_speed_m_s = Some(self.prev_v.z);
                    m.touchdown_horizontal_speed_m_s = Some(self.prev_v.xy().norm());
                    m.touchdown_offset_m = self.liftoff_xy.map(|l| (horizontal(x) - l).norm());
                }
            }
            Phase::Landed => {
                self.blend = (self.blend - ramp).max(0.0);
                if let (Some(t0), Some(spool)) = (self.touchdown_at, self.spool.as_mut())
                    && t_s >= t0 + s.shutdown_delay_s
                {
                    spool.stop();
                }
            }
        }
        self.prev_v = ned_velocity(x);
        self.last_xy = horizontal(x);
        let a = self.blend;
        if a >= 1.0 {
            *law_command
        } else {
            self.idle + (law_command - self.idle) * a
        }
    }

    /// Fold the sample's contact into the landing metrics.
    pub fn observe_contact(&mut self, total_normal_n: f64) {
        if self.phase == Phase::Landed {
            let peak = self.metrics.touchdown_peak_normal_n.get_or_insert(0.0);
            *peak = peak.max(total_normal_n);
        }
    }

    /// The current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The blend (0 idle … 1 law).
    pub fn blend(&self) -> f64 {
        self.blend
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
