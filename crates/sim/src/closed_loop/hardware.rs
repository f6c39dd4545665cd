//! The simulator as the helicopter's hardware, one control period at a time,
//! for software-in-the-loop runs: [`Hardware::sense`] samples the sensor
//! models at the start of a period, [`Hardware::actuate`] takes the servo
//! commands the on-board software sent and integrates the plant and the wind
//! over the period. The order is [`fly`]'s, sample for sample: wind at t_k,
//! sensors at t_k, the flight software, the plant from t_k to t_k+1, the
//! envelope checks.

use super::*;
use crate::scenario::ReferenceSchedule;

/// What the hardware offers the on-board software at the start of a period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HardwareSample {
    /// Sample index k (t = k·Ts).
    pub k: usize,
    /// Time of the sample (s).
    pub t_s: f64,
    /// The sensor readings of the sample.
    pub frame: helicon_core::SensorFrame,
    /// The truth they were sampled from.
    pub truth: TruthSample,
    /// The scenario's reference at this time (the ground station's uplink).
    pub reference: Reference,
}

/// What one period of plant and wind reports.
#[derive(Debug, Clone, PartialEq)]
pub struct HardwareStep {
    /// The truth row of the period's start (the `log.csv` row; the estimate
    /// columns from the downlinked telemetry, zeros without it).
    pub row: LogRow,
    /// Whether the row is one `[log] decimation` keeps.
    pub kept: bool,
    /// The flight ended: the plant failed, left the envelope, or the
    /// scenario's duration was flown.
    pub end: Option<(Termination, Option<String>)>,
}

/// The plant, wind and sensor models of a scenario, stepped by servo
/// commands from outside (the sensor models are always in the loop: they are
/// what the on-board software reads).
pub struct Hardware<'a> {
    scenario: &'a Scenario,
    prepared: &'a Prepared,
    plant: Plant<'a>,
    wind: Wind,
    suite: SensorSuite,
    schedule: ReferenceSchedule,
    acc: SummaryAccumulator,
    ts: f64,
    n: usize,
    k: usize,
    /// The wind and reference of the sample sensed and not yet actuated.
    pending: Option<(Vector3<f64>, [f64; 4])>,
    reason: Option<(Termination, String)>,
    t_end_s: f64,
    /// The engine's spool ramp, with the drivetrain (started or stopped by
    /// the servo frame's throttle hold: [`Hardware::set_throttle_hold`]).
    spool: Option<helicon_model::drivetrain::Spool>,
    /// The heading is checked against the scenario's references (off when
    /// the references come from elsewhere: a ground station's navigator).
    heading_check: bool,
}

impl<'a> Hardware<'a> {
    /// The hardware of a prepared scenario, at its initial state, stepped at
    /// the flight software's control period (the gains' sample time).
    pub fn new(scenario: &'a Scenario, prepared: &'a Prepared) -> Result<Self, ClosedLoopError> {
        Self::new_at(scenario, prepared, prepared.gains.set.sample_time_s)
    }

    /// The same hardware stepped at the period `ts` (s) of an outside
    /// autopilot (ArduPilot's frame rate, say) instead of the gains' one: the
    /// plant's step, the sensor models and the wind are all sampled at `ts`.
    pub fn new_at(
        scenario: &'a Scenario,
        prepared: &'a Prepared,
        ts: f64,
    ) -> Result<Self, ClosedLoopError> {
        let (n, _) = sample_counts(scenario, ts);
        let p = prepared.model.params();
        let g = p.environment.g_m_s2;
        let on_ground = scenario.ground.is_some_and(|g| g.on_ground);
        let spool = p.drivetrain.is_enabled().then(|| {
            if on_ground {
                helicon_model::drivetrain::Spool::stopped(p)
            } else {
                helicon_model::drivetrain::Spool::governed(p)
            }
        });
        Ok(Hardware {
            scenario,
            prepared,
            plant: Plant::new(scenario, prepared, ts),
            wind: Wind::from_config(&scenario.wind)?,
            suite: sensor_suite_at(&scenario.sensors, ts, g)?,
            schedule: scenario.reference_schedule(),
            acc: SummaryAccumulator::new(prepared),
            ts,
            n,
            k: 0,
            pending: None,
            reason: None,
            t_end_s: 0.0,
            spool,
            heading_check: true,
        })
    }

    /// The same hardware without the heading check against the scenario's
    /// references (a ground station's navigator gives them instead).
    #[must_use]
    pub fn without_heading_check(mut self) -> Self {
        self.heading_check = false;
        self
    }

    /// The servo frame's throttle hold: set, the engine is cut; clear, the
    /// governor spools the rotor up (from its speed now) and holds it. No
    /// effect without the drivetrain (the rotor then turns at its constant
    /// speed).
    pub fn set_throttle_hold(&mut self, hold: bool) {
        let omega = self.plant.omega_rad_s();
        if let Some(spool) = self.spool.as_mut() {
            crate::ground::apply_throttle_hold(spool, hold, omega);
        }
    }

    /// The rotor speed now (rad/s).
    pub fn rotor_speed_rad_s(&self) -> f64 {
        self.plant.omega_rad_s()
    }

    /// The true full state now (the start of the flight before any step:
    /// what the on-board software is aligned to on the ground).
    pub fn state(&self) -> &State {
        &self.plant.x
    }

    /// The control period (s).
    pub fn sample_time_s(&self) -> f64 {
        self.ts
    }

    /// The number of samples the scenario flies (k = 0..=n).
    pub fn samples(&self) -> usize {
        self.n + 1
    }

    /// Sample the wind and the sensors at the start of the current period.
    /// `None` once the flight has ended. Calling it twice without
    /// [`Hardware::actuate`] returns the same sample's time but draws new
    /// sensor noise: call it once per period.
    pub fn sense(&mut self) -> Option<HardwareSample> {
        if self.reason.is_some() || self.k > self.n {
            return None;
        }
        let t = self.k as f64 * self.ts;
        let wind_ned = self.wind.step(t, self.ts);
        let r = self.schedule.at(t);
        let truth = self.plant.truth(t);
        let frame = self.suite.sample(&truth);
        self.pending = Some((wind_ned, r));
        Some(HardwareSample {
            k: self.k,
            t_s: t,
            frame,
            truth,
            reference: Reference {
                velocity_ned_m_s: Vector3::new(r[0], r[1], r[2]),
                yaw_rad: r[3],
            },
        })
    }

    /// Hold `u` over the period sensed last and integrate the plant;
    /// `downlink` (the on-board telemetry of the sample, when available)
    /// fills the estimate columns of the truth row. `None` when nothing was
    /// sensed since the last call.
    pub fn actuate(&mut self, u: &Input, downlink: Option<&Telemetry>) -> Option<HardwareStep> {
        let (wind_ned, r) = self.pending.take()?;
        let t = self.k as f64 * self.ts;
        let x_start = self.plant.x;
        if let Some(spool) = self.spool.as_mut() {
            spool.step(self.ts);
            if let Some(g) = self.plant.ground.as_mut() {
                g.drive = spool.command;
            }
        }
        let step = self.plant.advance(u, &wind_ned);
        let decimation = self.scenario.log.decimation.max(1) as usize;
        let kept = self.k % decimation == 0 || self.k == self.n;
        let mut row = LogRow {
            t_s: t,
            x: x_start,
            u: *u,
            reference: r,
            output: outputs(&x_start),
            estimate9: [0.0; 9],
            measured9: [0.0; 9],
            wind_ned: [wind_ned.x, wind_ned.y, wind_ned.z],
            lambda: [step.aux.lambda_mr, step.aux.lambda_tr],
            thrust: [-step.aux.force_mr_hub_n.z, step.aux.force_tr_y_n],
            inflow_residual: step.aux.inflow_residual,
            // The IMU health monitor is flight software: the on-board side
            // does not report it through the hardware (zeros, as without sensors).
            imu_health: [0.0; 3],
            excitation: [0.0; 4],
        };
        if let Some(tel) = downlink {
            row = LogRow::new(t, &x_start, tel, r, &wind_ned, &step.aux);
            row.u = *u;
        }
        if kept {
            self.acc.push(&row);
        }
        self.t_end_s = t;
        if let Some(e) = step.error {
            self.reason = Some((
                Termination::ModelFailure,
                format!("model failed at t = {t:.3} s: {e}"),
            ));
        } else if let Some(stop) = check_limits(
            self.scenario,
            &self.plant.x,
            t + self.ts,
            if self.heading_check {
                self.schedule.at(t + self.ts)[3]
            } else {
                self.plant.x[ix::PSI]
            },
        ) {
            self.reason = Some(stop);
        }
        self.k += 1;
        let end = match &self.reason {
            Some((kind, why)) => Some((*kind, Some(why.clone()))),
            None if self.k > self.n => Some((Termination::Completed, None)),
            None => None,
        };
        Some(HardwareStep { row, kept, end })
    }

    /// End the flight early (the on-board side failed) with a reason.
    pub fn abort(&mut self, kind: Termination, reason: String) {
        if self.reason.is_none() {
            self.reason = Some((kind, reason));
        }
    }

    /// The flight's summary (metrics over the kept rows), as `helicon sim`
    /// writes it.
    pub fn summary(&self) -> Summary {
        summarize(
            self.scenario,
            self.prepared,
            &self.acc,
            self.reason.clone(),
            self.t_end_s,
        )
    }
}
