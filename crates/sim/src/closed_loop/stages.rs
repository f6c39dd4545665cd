//! The stages of one controller sample: the plant ([`Plant`]), the on-board
//! software composed from the core ([`OnBoard`]) and the flight-envelope
//! checks ([`check_limits`]).

use super::*;
use helicon_core::SensorComputer;
use helicon_core::lqi::StateFeedback;
use helicon_core::schedule::{AnyPredictor, Law};
use helicon_model::drivetrain::{DriveCommand, RotorState, Spool, governed_state};
use helicon_model::landing_gear::{Anchors, ContactWrench, contact_wrench, resting_state};
use helicon_model::{PlantState, PlantVector};

/// The plant: the nonlinear model integrated with RK4 between controller
/// samples, inputs and wind held, inflow warm-started from the last solution.
pub(super) struct Plant<'a> {
    model: &'a Model,
    pub(super) x: State,
    /// Inflow ratios (main, tail) carried between evaluations.
    lambda: (f64, f64),
    /// The derivative at the start of the last step (for the accelerometer).
    xdot: State,
    inflow: PlantInflow,
    inflow_iterations: u32,
    substeps: u32,
    h_s: f64,
    /// The yaw-rate gyro between the tail input and the tail servo, when
    /// the parameters enable it (run once per controller sample).
    gyro: Option<YawGyroBlock>,
    /// The plant's states beyond the 30 (rotor speed, governor, friction
    /// anchors), when the parameters enable the landing gear or the
    /// drivetrain; `None` keeps the thesis's plant step unchanged.
    pub(super) ground: Option<PlantGround>,
}

/// The ground blocks' part of the plant.
pub(super) struct PlantGround {
    /// Rotor speed and governor integrator.
    pub(super) rotor: RotorState,
    /// Friction anchors.
    anchors: Anchors,
    /// The engine's command, held over a sample (set by the plan).
    pub(super) drive: DriveCommand,
    /// The contact at the end of the last step.
    pub(super) contact: ContactWrench,
}

/// What one plant step reports.
pub(super) struct PlantStep {
    /// Auxiliary outputs at the start of the step (default when the first
    /// evaluation failed).
    pub(super) aux: Aux,
    /// The model failure that cut the step short, if any.
    pub(super) error: Option<ModelError>,
}

impl<'a> Plant<'a> {
    pub(super) fn new(scenario: &Scenario, prepared: &'a Prepared, ts: f64) -> Self {
        let p = prepared.model.params();
        let on_ground = scenario.ground.is_some_and(|g| g.on_ground);
        let mut x = initial_state(scenario, &prepared.trim);
        if on_ground {
            // resting on the skids at the design point's north and east,
            // servos centred, blades still
            let mut rest = State::zeros();
            rest[ix::X] = x[ix::X];
            rest[ix::Y] = x[ix::Y];
            x = resting_state(&p.landing_gear, p.body.mass_kg, p.environment.g_m_s2, &rest);
        }
        let ground = (p.landing_gear.is_enabled() || p.drivetrain.is_enabled()).then(|| {
            let (rotor, drive) = if on_ground && p.drivetrain.is_enabled() {
                (
                    RotorState {
                        omega_rad_s: 0.0,
                        governor_integral: 0.0,
                    },
                    Spool::stopped(p).command,
                )
            } else {
                (
                    governed_state(p, prepared.trim.aux.rotor_load_n_m),
                    Spool::governed(p).command,
                )
            };
            let mut state = PlantState {
                x,
                rotor,
                anchors: Anchors::default(),
            };
            prepared.model.update_anchors(&mut state);
            let contact = if p.landing_gear.is_enabled() {
                contact_wrench(
                    &p.landing_gear,
                    prepared.model.ground_plane(),
                    prepared.model.contact_points_body_m(),
                    &x,
                    &state.anchors,
                )
            } else {
                ContactWrench::default()
            };
            PlantGround {
                rotor,
                anchors: state.anchors,
                drive,
                contact,
            }
        });
        Plant {
            model: &prepared.model,
            x,
            ground,
            lambda: (prepared.trim.aux.lambda_mr, prepared.trim.aux.lambda_tr),
            xdot: State::zeros(),
            inflow: scenario.plant.inflow,
            inflow_iterations: scenario.plant.inflow_iterations,
            substeps: scenario.plant.substeps,
            h_s: ts / f64::from(scenario.plant.substeps),
            gyro: YawGyroBlock::at_trim(prepared.model.params(), ts, prepared.trim.u[3]),
        }
    }

    /// The true motion the sensor models sample; the inertial acceleration
    /// comes from the previous step's derivative (one sample old).
    pub(super) fn truth(&self, t_s: f64) -> TruthSample {
        let x = &self.x;
        let ned_from_body = EulerTrig::new(x[ix::PHI], x[ix::THETA], x[ix::PSI]).ned_from_body();
        let v_body = Vector3::new(x[ix::U], x[ix::V], x[ix::W]);
        let omega = Vector3::new(x[ix::P], x[ix::Q], x[ix::R]);
        let dv = Vector3::new(self.xdot[ix::U], self.xdot[ix::V], self.xdot[ix::W]);
        TruthSample {
            t_s,
            pos_ned_m: Vector3::new(x[ix::X], x[ix::Y], x[ix::Z]),
            vel_ned_m_s: ned_from_body * v_body,
            acc_ned_m_s2: ned_from_body * (dv + omega.cross(&v_body)),
            euler_rad: Vector3::new(x[ix::PHI], x[ix::THETA], x[ix::PSI]),
            omega_body_rad_s: omega,
        }
    }

    /// Integrate one controller sample with `u` and the wind held.
    pub(super) fn advance(&mut self, u: &Input, wind_ned: &Vector3<f64>) -> PlantStep {
        let mut u_servo = *u;
        if let Some(gyro) = self.gyro.as_mut() {
            // the tail input is a yaw-rate command; the gyro senses the true rate
            u_servo[3] = gyro.step(u[3], self.x[ix::R]);
        }
        let u = &u_servo;
        if self.ground.is_some() {
            return self.advance_ground(u, wind_ned);
        }
        // the first evaluation's ẋ and aux (the step's start), the others'
        // aux written over one scratch: no copy of the large Aux per stage
        let mut first: Option<State> = None;
        let mut aux_first = Aux::default();
        let mut aux_stage = Aux::default();
        let mut error = None;
        let (inflow, iterations, model) = (self.inflow, self.inflow_iterations, self.model);
        let lam = &mut self.lambda;
        for _ in 0..self.substeps {
            let res = rk4(&self.x, self.h_s, |s| {
                let mode = match inflow {
                    PlantInflow::Converged => InflowMode::ConvergedFrom {
                        lambda_mr_hint: lam.0,
                        lambda_tr_hint: lam.1,
                    },
                    PlantInflow::ThesisIteration => InflowMode::ThesisIteration {
                        lambda_mr_in: lam.0,
                        lambda_tr_in: lam.1,
                        iterations,
                    },
                };
                let a = if first.is_none() {
                    &mut aux_first
                } else {
                    &mut aux_stage
                };
                let d = model.derivative_into(s, u, wind_ned, mode, a)?;
                // warm start (converged) or the thesis's recursion (iteration)
                *lam = (a.lambda_mr, a.lambda_tr);
                if first.is_none() {
                    first = Some(d);
                }
                Ok::<_, ModelError>(d)
            });
            match res {
                Ok(next) => self.x = next,
                Err(e) => {
                    error = Some(e);
                    break;
                }
            }
        }
        let (aux, xdot) = match first {
            Some(d) => (aux_first, d),
            None => (Aux::default(), State::zeros()),
        };
        self.xdot = xdot;
        PlantStep { aux, error }
    }
}

impl Plant<'_> {
    /// The rotor speed (rad/s): the drivetrain's state, or the constant Ω.
    pub(super) fn omega_rad_s(&self) -> f64 {
        match &self.ground {
            Some(g) => g.rotor.omega_rad_s,
            None => self.model.params().main_rotor.omega_rad_s,
        }
    }

    /// [`Plant::advance`] with the ground blocks: the 30 states and the
    /// drivetrain's integrated together ([`Model::plant_derivative`]), the
    /// friction anchors following after each step.
    fn advance_ground(&mut self, u: &Input, wind_ned: &Vector3<f64>) -> PlantStep {
        let mut first: Option<(Aux, State)> = None;
        let mut error = None;
        let (inflow, iterations, model) = (self.inflow, self.inflow_iterations, self.model);
        let lam = &mut self.lambda;
        let Some(g) = self.ground.as_mut() else {
            return PlantStep {
                aux: Aux::default(),
                error: None,
            };
        };
        let mut state = PlantState {
            x: self.x,
            rotor: g.rotor,
            anchors: g.anchors,
        };
        let drive = g.drive;
        for _ in 0..self.substeps {
            let anchors = state.anchors;
            let res = rk4(&state.vector(), self.h_s, |v| {
                let mut s = PlantState {
                    x: State::zeros(),
                    rotor: state.rotor,
                    anchors,
                };
                s.set_vector(v);
                let mode = match inflow {
                    PlantInflow::Converged => InflowMode::ConvergedFrom {
                        lambda_mr_hint: lam.0,
                        lambda_tr_hint: lam.1,
                    },
                    PlantInflow::ThesisIteration => InflowMode::ThesisIteration {
                        lambda_mr_in: lam.0,
                        lambda_tr_in: lam.1,
                        iterations,
                    },
                };
                let (d, rd, a) = model.plant_derivative(&s, u, wind_ned, mode, &drive)?;
                *lam = (a.lambda_mr, a.lambda_tr);
                if first.is_none() {
                    first = Some((a, d));
                }
                let mut dv = PlantVector::zeros();
                dv.fixed_rows_mut::<{ helicon_model::NX }>(0).copy_from(&d);
                dv[helicon_model::NX] = rd.omega_rad_s;
                dv[helicon_model::NX + 1] = rd.governor_integral;
                Ok::<_, ModelError>(dv)
            });
            match res {
                Ok(next) => {
                    state.set_vector(&next);
                    model.update_anchors(&mut state);
                }
                Err(e) => {
                    error = Some(e);
                    break;
                }
            }
        }
        self.x = state.x;
        g.rotor = state.rotor;
        g.anchors = state.anchors;
        let p = model.params();
        if p.landing_gear.is_enabled() {
            g.contact = contact_wrench(
                &p.landing_gear,
                model.ground_plane(),
                model.contact_points_body_m(),
                &state.x,
                &state.anchors,
            );
        }
        let (aux, xdot) = first.unwrap_or_default();
        self.xdot = xdot;
        PlantStep { aux, error }
    }
}

/// The on-board software flown in the loop, as the scenario's switches
/// compose it from the core's parts.
pub(super) enum OnBoard {
    /// Sensor models feeding the navigation chosen in `[estimator]`, the
    /// predictor and the law (`fusion = true`).
    Sensed {
        /// The world's sensors.
        suite: Box<SensorSuite>,
        /// Navigation + predictor + LQI (fixed or scheduled).
        computer: Box<SensorComputer>,
    },
    /// Ideal navigation: the predictor is given the nine measured states.
    IdealNavigation(Box<FlightComputer<AnyPredictor, Law>>),
    /// The thesis's "estimator off" switch: the law is fed the true state;
    /// with `fusion = true` the navigation still runs and is logged.
    Truth {
        /// Truth feed + LQI.
        computer: Box<FlightComputer<TruthFeed, Law>>,
        /// Sensors and navigation run alongside, for the log.
        navigation: Option<(Box<SensorSuite>, Box<NavigationFilter>)>,
    },
}

impl OnBoard {
    pub(super) fn new(
        scenario: &Scenario,
        prepared: &Prepared,
        x0: &State,
    ) -> Result<Self, ClosedLoopError> {
        let p = prepared.model.params();
        let set = &prepared.gains.set;
        let ts = set.sample_time_s;
        let g = p.environment.g_m_s2;
        let c = &scenario.controller;
        let setup = prepared.onboard_setup(scenario, x0);
        let sensed = || -> Result<_, ClosedLoopError> {
            Ok((
                Box::new(
                    sensor_suite_at(&scenario.sensors, ts, g)?
                        .with_rotor(RotorSpeeds::from_params(p))?,
                ),
                Box::new(navigation_filter_at(
                    &scenario.sensors,
                    &scenario.navigation,
                    ts,
                    g,
                    x0,
                )?),
            ))
        };
        Ok(match (c.estimator, c.fusion) {
            (true, true) => OnBoard::Sensed {
                suite: Box::new(sensor_suite_at(&scenario.sensors, ts, g)?),
                computer: Box::new(flight_computer(&setup)?),
            },
            (true, false) => OnBoard::IdealNavigation(Box::new(FlightComputer::new(
                setup.predictor()?,
                setup.law()?,
            ))),
            (false, fusion) => OnBoard::Truth {
                computer: Box::new(FlightComputer::new(TruthFeed, setup.law()?)),
                navigation: if fusion { Some(sensed()?) } else { None },
            },
        })
    }

    /// Clear the law's integrators (the on-board ground logic holds them).
    pub(super) fn reset_feedback(&mut self) {
        match self {
            OnBoard::Sensed { computer, .. } => computer.reset_feedback(),
            OnBoard::IdealNavigation(c) => c.feedback.reset(),
            OnBoard::Truth { computer, .. } => computer.feedback.reset(),
        }
    }

    /// One control sample against the plant's true state; the sensor frame
    /// and its truth are pushed to `record` when given. `servo` makes the
    /// servos' command of the law's (`None`: the law's; see
    /// [`FlightComputer::step_servo`]). Returns the telemetry and the IMU's
    /// body rates when sensor models ran.
    #[allow(clippy::too_many_arguments)] // one sample's inputs, each from its own stage
    pub(super) fn step(
        &mut self,
        t_s: f64,
        plant: &Plant<'_>,
        reference: &Reference,
        excitation: &Input,
        record: Option<&mut Vec<SensorLogRow>>,
        health: Option<&mut ImuHealthMonitor>,
        servo: impl FnOnce(&Input) -> Option<Input>,
    ) -> Result<(Telemetry, Option<Vector3<f64>>), CoreError> {
        let xr: ReducedState = reduce(&plant.x);
        let sense = |suite: &mut SensorSuite| {
            let truth = plant.truth(t_s);
            let frame = suite.sample(&truth);
            if let Some(h) = health {
                h.update(&frame.imu);
            }
            if let Some(rec) = record {
                rec.push(SensorLogRow {
                    frame,
                    truth: LoggedTruth::from(&truth),
                });
            }
            frame
        };
        match self {
            OnBoard::Sensed { suite, computer } => {
                let frame = sense(suite);
                let tel = computer.step_servo(&frame, reference, excitation, servo)?;
                Ok((tel, Some(frame.imu.gyro_body_rad_s)))
            }
            OnBoard::IdealNavigation(computer) => {
                let m = StateMeasurement {
                    t_s,
                    measured: SVector::from_fn(|i, _| xr[i]),
                };
                Ok((computer.step_servo(&m, reference, excitation, servo)?, None))
            }
            OnBoard::Truth {
                computer,
                navigation,
            } => {
                let nav = match navigation {
                    Some((suite, filter)) => {
                        let frame = sense(suite);
                        Some((
                            filter.step(&frame)?,
                            filter.solution(),
                            frame.imu.gyro_body_rad_s,
                        ))
                    }
                    None => None,
                };
                let mut tel = computer.step_servo(
                    &TruthMeasurement { t_s, state: xr },
                    reference,
                    excitation,
                    servo,
                )?;
                let mut gyro = None;
                if let Some((y, solution, g)) = nav {
                    tel.measured = y;
                    tel.navigation = Some(solution);
                    gyro = Some(g);
                }
                Ok((tel, gyro))
            }
        }
    }
}

/// The flight-envelope checks after a plant step at `t_next_s`: the first
/// limit crossed, as a termination kind and a sentence.
pub(super) fn check_limits(
    scenario: &Scenario,
    x: &State,
    t_next_s: f64,
    psi_ref_next: f64,
) -> Option<(Termination, String)> {
    let plant = &scenario.plant;
    // a slice walk: nalgebra's matrix iterator costs ~15 instructions an entry
    if !x.as_slice().iter().all(|v| v.is_finite()) {
        return Some((
            Termination::NonFiniteState,
            format!("non-finite state at t = {t_next_s:.3} s"),
        ));
    }
    let lim = plant.max_attitude_rad;
    if x[ix::PHI].abs() > lim || x[ix::THETA].abs() > lim {
        return Some((
            Termination::AttitudeLimit,
            format!(
                "attitude beyond {lim} rad at t = {t_next_s:.3} s (phi = {:.3}, theta = {:.3})",
                x[ix::PHI],
                x[ix::THETA]
            ),
        ));
    }
    let rate = x[ix::P].abs().max(x[ix::Q].abs()).max(x[ix::R].abs());
    if rate > plant.max_rate_rad_s {
        return Some((
            Termination::RateLimit,
            format!(
                "body rate {rate:.2} rad/s beyond {} rad/s at t = {t_next_s:.3} s",
                plant.max_rate_rad_s
            ),
        ));
    }
    let yaw_err = x[ix::PSI] - psi_ref_next;
    if yaw_err.abs() > plant.max_yaw_error_rad {
        return Some((
            Termination::HeadingLost,
            format!(
                "heading {:.2} rad is {yaw_err:.2} rad from its reference at t = {t_next_s:.3} s: \
                 the helicopter spins away",
                x[ix::PSI]
            ),
        ));
    }
    None
}
