//! The closed loop: the thesis's Simulink environment (Appendix E figure)
//! rebuilt as software. World (nonlinear model + wind [+ sensor models]) and
//! the on-board flight software (`helicon_core::FlightComputer`) exchange servo commands and measurements
//! once per controller sample; the plant is integrated with RK4 in between
//! (inputs held, optional sub-steps).
//!
//! Preparation ([`prepare`]): trim at the scenario's design point, linearize,
//! ZOH-discretize, design (or load) the gains. Flight ([`fly`]): one loop per
//! sample; divergence (non-finite state, attitude beyond the limit, a model or
//! estimator failure) stops the run cleanly with the reason, time and state,
//! keeping the log so far.

use crate::log_csv::LogWriter;
use crate::metrics::{OutputMetrics, output_metrics};
use crate::navigation::{navigation_filter_at, sensor_suite_at};
use crate::scenario::{DesignInflow, OUTPUTS, PlantInflow, Scenario};
use crate::sensor_log::{LoggedTruth, SensorLogRow};
use crate::sensors::SensorSuite;
use crate::trajectory::TruthSample;
use crate::wind::{Wind, WindModel};
use helicon_core::frames::{EulerTrig, wrap_pi};
use helicon_core::navigation::NavigationFilter;
use helicon_core::{
    CoreError, FlightComputer, KalmanPredictor, Lqi, Reference, ServoLimits, StateMeasurement,
    Telemetry, ThesisEstimator, ThesisFlightComputer, TruthFeed, TruthMeasurement,
};
use helicon_gnc::design::{Gains, design};
use helicon_model::integrate::rk4;
use helicon_model::linearize::linearize;
use helicon_model::state::{NX, REDUCED_OFFSET, expand, ix, reduce};
use helicon_model::trim::{Trim, TrimOptions, TrimTarget, trim};
use helicon_model::{Aux, InflowMode, Input, Model, ModelError, Params, ReducedState, State};
use nalgebra::{SVector, Vector3};
use serde::Serialize;

/// Errors before the flight starts (a divergence during flight is an outcome, not an error).
#[derive(Debug, thiserror::Error)]
pub enum ClosedLoopError {
    /// Parameters.
    #[error(transparent)]
    Params(#[from] helicon_model::ParamError),
    /// Trim failed.
    #[error("design point: {0}")]
    Trim(#[from] helicon_model::trim::TrimError),
    /// Model evaluation during linearization.
    #[error("linearization: {0}")]
    Model(#[from] ModelError),
    /// Discretization.
    #[error("discretization: {0}")]
    Lti(#[from] helicon_lti::LtiError),
    /// Controller design or gains file.
    #[error(transparent)]
    Design(#[from] helicon_gnc::design::DesignError),
    /// Wind or sensor configuration (the one configuration error shape).
    #[error(transparent)]
    Config(#[from] helicon_model::ConfigError),
    /// Navigation (fusion) setup.
    #[error(transparent)]
    Fusion(#[from] helicon_core::fusion::FusionError),
    /// The flight software could not be built from the gains.
    #[error("flight software: {0}")]
    Core(#[from] CoreError),
    /// A gains file designed for another sample time than the helicopter's.
    #[error(
        "{file}: the gains were designed for a sample time of {gains_s} s but the parameters' \
         `control.sample_time_s` is {params_s} s: redesign, or fly the parameters they were made for"
    )]
    SampleTimeMismatch {
        /// The gains file.
        file: String,
        /// Its sample time (s).
        gains_s: f64,
        /// The parameters' sample time (s).
        params_s: f64,
    },
    /// The log would not fit in the memory budget.
    #[error(
        "the flight log would need {rows} rows, {} MiB, beyond the {} MiB budget ({why}): \
         raise [log] decimation, shorten duration_s, or write it to a file (`helicon sim` does)",
        bytes >> 20,
        budget >> 20
    )]
    LogTooLarge {
        /// Rows needed.
        rows: usize,
        /// Bytes needed.
        bytes: u64,
        /// The budget (bytes).
        budget: u64,
        /// Where the budget comes from.
        why: String,
    },
    /// Writing the streamed log failed.
    #[error(transparent)]
    Log(#[from] crate::log_csv::LogCsvError),
}

/// Everything prepared for flying a scenario.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The plant model.
    pub model: Model,
    /// The design trim.
    pub trim: Trim,
    /// The gains flown.
    pub gains: Gains,
}

/// Trim, linearize, discretize and design (or load) the gains for a scenario.
pub fn prepare(scenario: &Scenario) -> Result<Prepared, ClosedLoopError> {
    let params = match &scenario.params {
        Some(p) => Params::from_file(&scenario.resolve(p))?,
        None => Params::bergen_twin(),
    };
    prepare_with_params(scenario, params)
}

/// As [`prepare`] with explicit parameters (Monte Carlo dispersions).
pub fn prepare_with_params(
    scenario: &Scenario,
    params: Params,
) -> Result<Prepared, ClosedLoopError> {
    let model = Model::new(params, scenario.preset.options());
    let target = TrimTarget {
        velocity_ned_m_s: Vector3::from(scenario.trim.velocity_ned_m_s),
        yaw_rad: scenario.trim.yaw_rad,
        wind_ned_m_s: Vector3::zeros(),
    };
    // the flight starts at this equilibrium: it must be one the helicopter
    // can hold (inputs within the servo range, blades unstalled, …)
    let t = trim(&model, &target, &TrimOptions::default())?.require_physical(&model)?;
    let ts = model.params().control.sample_time_s;
    let gains = match &scenario.controller.gains_file {
        Some(f) => {
            let path = scenario.resolve(f);
            let g = Gains::load(&path)?;
            if g.set.sample_time_s != ts {
                return Err(ClosedLoopError::SampleTimeMismatch {
                    file: path.display().to_string(),
                    gains_s: g.set.sample_time_s,
                    params_s: ts,
                });
            }
            g
        }
        None => {
            let inflow = match scenario.controller.design_inflow {
                DesignInflow::Converged => InflowMode::Converged,
                DesignInflow::ThesisIteration => InflowMode::ThesisIteration {
                    lambda_mr_in: t.aux.lambda_mr,
                    lambda_tr_in: t.aux.lambda_tr,
                    iterations: scenario.plant.inflow_iterations,
                },
            };
            let lm = linearize(&model, &t.x, &t.u, &Vector3::zeros(), inflow)?;
            let (phi, gamma) = lm.discretize(ts)?;
            design(&phi, &gamma, &t.x, &t.u, ts, &scenario.controller.design)?
        }
    };
    Ok(Prepared {
        model,
        trim: t,
        gains,
    })
}

/// How a flight ended, in one word.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Outcome {
    /// Flew the whole duration.
    Completed,
    /// Stopped early (see the termination and the reason).
    Diverged,
}

impl Outcome {
    /// The word written in `summary.json` and `runs.csv`.
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::Completed => "completed",
            Outcome::Diverged => "diverged",
        }
    }
}

/// Why a flight ended: the machine-readable kind (`"termination"` in
/// `summary.json`); the `reason` next to it is the sentence with times and values.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// Flew the whole duration.
    Completed,
    /// The true state became NaN or infinite.
    NonFiniteState,
    /// Roll or pitch beyond `[plant] max_attitude_rad`.
    AttitudeLimit,
    /// A body rate beyond `[plant] max_rate_rad_s`.
    RateLimit,
    /// The heading left its reference by more than `[plant] max_yaw_error_rad`.
    HeadingLost,
    /// The plant model failed to evaluate (e.g. the inflow did not converge).
    ModelFailure,
    /// The on-board navigation or estimator failed.
    NavigationFailure,
}

impl Termination {
    /// Every kind, in declaration order.
    pub const ALL: [Termination; 7] = [
        Termination::Completed,
        Termination::NonFiniteState,
        Termination::AttitudeLimit,
        Termination::RateLimit,
        Termination::HeadingLost,
        Termination::ModelFailure,
        Termination::NavigationFailure,
    ];

    /// The flight's outcome for this termination.
    pub fn outcome(self) -> Outcome {
        match self {
            Termination::Completed => Outcome::Completed,
            _ => Outcome::Diverged,
        }
    }

    /// The snake_case name written in files.
    pub fn as_str(self) -> &'static str {
        match self {
            Termination::Completed => "completed",
            Termination::NonFiniteState => "non_finite_state",
            Termination::AttitudeLimit => "attitude_limit",
            Termination::RateLimit => "rate_limit",
            Termination::HeadingLost => "heading_lost",
            Termination::ModelFailure => "model_failure",
            Termination::NavigationFailure => "navigation_failure",
        }
    }
}

impl std::fmt::Display for Termination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for Termination {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Termination::ALL
            .into_iter()
            .find(|t| t.as_str() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Termination::ALL.iter().map(|t| t.as_str()).collect();
                format!("unknown termination `{s}` (one of {})", names.join(", "))
            })
    }
}

/// One logged sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogRow {
    /// Time (s).
    pub t_s: f64,
    /// True state (30).
    pub x: State,
    /// Servo command (after saturation).
    pub u: Input,
    /// Reference [vn, ve, vd, psi].
    pub reference: [f64; 4],
    /// True outputs [vn, ve, vd, psi].
    pub output: [f64; 4],
    /// Estimated 9 measured states (absolute).
    pub estimate9: [f64; 9],
    /// Measurement given to the controller (9).
    pub measured9: [f64; 9],
    /// Wind NED (m/s).
    pub wind_ned: [f64; 3],
    /// Inflow ratios [main, tail].
    pub lambda: [f64; 2],
    /// Main-rotor thrust −hFz (N) and tail-rotor force tFy (N).
    pub thrust: [f64; 2],
    /// |g(λ)| of the momentum equations (7.33)/(7.56) at the λ used [main,
    /// tail]: ~1e-13 when converged; large when the thesis iteration is off its root.
    pub inflow_residual: [f64; 2],
}

/// Summary of a flight.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// "completed" or "diverged".
    pub outcome: Outcome,
    /// Why it ended, machine-readable (`completed`, `attitude_limit`, …).
    pub termination: Termination,
    /// Why it stopped early, as a sentence (None when completed).
    pub reason: Option<String>,
    /// Time reached (s).
    pub t_end_s: f64,
    /// Metrics per output `vn`, `ve`, `vd`, `psi`.
    pub metrics: std::collections::BTreeMap<String, OutputMetrics>,
    /// RMS of u − u_trim per input.
    pub control_effort_rms: [f64; 4],
    /// Time each input spent saturated (s).
    pub saturation_time_s: [f64; 4],
    /// RMS estimation error of the nine measured states (truth − estimate).
    pub estimator_error_rms: [f64; 9],
    /// Model preset.
    pub preset: String,
    /// Wind seed.
    pub wind_seed: u64,
    /// Sensor seed.
    pub sensor_seed: u64,
    /// FNV-1a hash of the effective parameter TOML.
    pub parameter_hash: String,
    /// helicon version.
    pub version: String,
    /// The flight software's sample time (s): the helicopter's `control.sample_time_s`.
    pub sample_time_s: f64,
    /// The settling metrics used every `metrics_stride`-th kept log row (1
    /// unless the flight outgrew [`METRIC_TRACE_CAP`] rows).
    pub metrics_stride: usize,
    /// Closed-loop poles of the design: largest |z|.
    pub design_spectral_radius: f64,
    /// Pincer α of the design.
    pub design_alpha: f64,
}

/// A finished flight: the log and the summary.
#[derive(Debug, Clone)]
pub struct Flight {
    /// Samples (every `[log] decimation`-th).
    pub log: Vec<LogRow>,
    /// Every sensor frame given to the flight software, with its truth
    /// (`[log] sensors = true` with sensor models in the loop; else empty).
    pub sensors: Vec<SensorLogRow>,
    /// Summary and metrics.
    pub summary: Summary,
}

/// FNV-1a 64-bit hash, as hex.
pub fn fnv1a_hex(text: &str) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.as_bytes() {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// The initial true state: the trim plus the scenario's deviations.
pub fn initial_state(scenario: &Scenario, trim: &Trim) -> State {
    let mut x = expand(&trim.x, [0.0; 3]);
    let o = REDUCED_OFFSET;
    let mut dv_ned = Vector3::zeros();
    for (k, v) in &scenario.initial {
        match k.as_str() {
            "vn" => dv_ned.x += v,
            "ve" => dv_ned.y += v,
            "vd" => dv_ned.z += v,
            name => {
                if let Some(i) = helicon_model::REDUCED_STATE_NAMES
                    .iter()
                    .position(|n| *n == name)
                {
                    x[i + o] += v;
                }
            }
        }
    }
    if dv_ned.norm() > 0.0 {
        let dv_body =
            helicon_model::frames::body_from_ned(x[ix::PHI], x[ix::THETA], x[ix::PSI]) * dv_ned;
        x[ix::U] += dv_body.x;
        x[ix::V] += dv_body.y;
        x[ix::W] += dv_body.z;
    }
    x
}

fn outputs(x: &State) -> [f64; 4] {
    let v = EulerTrig::new(x[ix::PHI], x[ix::THETA], x[ix::PSI]).ned_from_body()
        * Vector3::new(x[ix::U], x[ix::V], x[ix::W]);
    [v.x, v.y, v.z, x[ix::PSI]]
}

/// Progress callback: fraction done in [0, 1].
pub type Progress<'a> = &'a mut dyn FnMut(f64);

/// The plant: the nonlinear model integrated with RK4 between controller
/// samples, inputs and wind held, inflow warm-started from the last solution.
struct Plant<'a> {
    model: &'a Model,
    x: State,
    /// Inflow ratios (main, tail) carried between evaluations.
    lambda: (f64, f64),
    /// The derivative at the start of the last step (for the accelerometer).
    xdot: State,
    inflow: PlantInflow,
    inflow_iterations: u32,
    substeps: u32,
    h_s: f64,
}

/// What one plant step reports.
struct PlantStep {
    /// Auxiliary outputs at the start of the step (default when the first
    /// evaluation failed).
    aux: Aux,
    /// The model failure that cut the step short, if any.
    error: Option<ModelError>,
}

impl<'a> Plant<'a> {
    fn new(scenario: &Scenario, prepared: &'a Prepared, ts: f64) -> Self {
        Plant {
            model: &prepared.model,
            x: initial_state(scenario, &prepared.trim),
            lambda: (prepared.trim.aux.lambda_mr, prepared.trim.aux.lambda_tr),
            xdot: State::zeros(),
            inflow: scenario.plant.inflow,
            inflow_iterations: scenario.plant.inflow_iterations,
            substeps: scenario.plant.substeps,
            h_s: ts / f64::from(scenario.plant.substeps),
        }
    }

    /// The true motion the sensor models sample; the inertial acceleration
    /// comes from the previous step's derivative (one sample old).
    fn truth(&self, t_s: f64) -> TruthSample {
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
    fn advance(&mut self, u: &Input, wind_ned: &Vector3<f64>) -> PlantStep {
        let mut first: Option<(Aux, State)> = None;
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
                let (d, a) = model.derivative_with(s, u, wind_ned, mode)?;
                // warm start (converged) or the thesis's recursion (iteration)
                *lam = (a.lambda_mr, a.lambda_tr);
                if first.is_none() {
                    first = Some((a, d));
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
        let (aux, xdot) = first.unwrap_or_default();
        self.xdot = xdot;
        PlantStep { aux, error }
    }
}

/// The on-board software flown in the loop, as the scenario's switches
/// compose it from the core's parts.
enum OnBoard {
    /// Sensor models feeding the thesis's whole chain (`fusion = true`).
    Thesis {
        /// The world's sensors.
        suite: Box<SensorSuite>,
        /// Navigation + predictor + LQI.
        computer: Box<ThesisFlightComputer>,
    },
    /// Ideal navigation: the predictor is given the nine measured states.
    IdealNavigation(Box<FlightComputer<KalmanPredictor, Lqi>>),
    /// The thesis's "estimator off" switch: the law is fed the true state;
    /// with `fusion = true` the navigation still runs and is logged.
    Truth {
        /// Truth feed + LQI.
        computer: Box<FlightComputer<TruthFeed, Lqi>>,
        /// Sensors and navigation run alongside, for the log.
        navigation: Option<(Box<SensorSuite>, Box<NavigationFilter>)>,
    },
}

impl OnBoard {
    fn new(scenario: &Scenario, prepared: &Prepared, x0: &State) -> Result<Self, ClosedLoopError> {
        let p = prepared.model.params();
        let limits = ServoLimits {
            min: Input::from_fn(|i, _| p.servos[i].s_min),
            max: Input::from_fn(|i, _| p.servos[i].s_max),
        };
        let set = &prepared.gains.set;
        let ts = set.sample_time_s;
        let g = p.environment.g_m_s2;
        let law = Lqi::new(set, limits, scenario.controller.feedback)?;
        // The estimator starts from the measured states and the trim for the rest.
        let mut x0_est: ReducedState = prepared.trim.x;
        for i in 0..9 {
            x0_est[i] = x0[i + REDUCED_OFFSET];
        }
        let c = &scenario.controller;
        let sensed = || -> Result<_, ClosedLoopError> {
            Ok((
                Box::new(sensor_suite_at(&scenario.sensors, ts, g)?),
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
            (true, true) => {
                let (suite, navigation) = sensed()?;
                let estimator = ThesisEstimator {
                    navigation: *navigation,
                    predictor: KalmanPredictor::new(set, &x0_est)?,
                };
                OnBoard::Thesis {
                    suite,
                    computer: Box::new(FlightComputer::new(estimator, law)),
                }
            }
            (true, false) => OnBoard::IdealNavigation(Box::new(FlightComputer::new(
                KalmanPredictor::new(set, &x0_est)?,
                law,
            ))),
            (false, fusion) => OnBoard::Truth {
                computer: Box::new(FlightComputer::new(TruthFeed, law)),
                navigation: if fusion { Some(sensed()?) } else { None },
            },
        })
    }

    /// One control sample against the plant's true state; the sensor frame
    /// and its truth are pushed to `record` when given.
    fn step(
        &mut self,
        t_s: f64,
        plant: &Plant<'_>,
        reference: &Reference,
        record: Option<&mut Vec<SensorLogRow>>,
    ) -> Result<Telemetry, CoreError> {
        let xr: ReducedState = reduce(&plant.x);
        let sense = |suite: &mut SensorSuite| {
            let truth = plant.truth(t_s);
            let frame = suite.sample(&truth);
            if let Some(rec) = record {
                rec.push(SensorLogRow {
                    frame,
                    truth: LoggedTruth::from(&truth),
                });
            }
            frame
        };
        match self {
            OnBoard::Thesis { suite, computer } => {
                let frame = sense(suite);
                computer.step(&frame, reference)
            }
            OnBoard::IdealNavigation(computer) => {
                let m = StateMeasurement {
                    t_s,
                    measured: SVector::from_fn(|i, _| xr[i]),
                };
                computer.step(&m, reference)
            }
            OnBoard::Truth {
                computer,
                navigation,
            } => {
                let nav = match navigation {
                    Some((suite, filter)) => {
                        let frame = sense(suite);
                        Some((filter.step(&frame)?, filter.solution()))
                    }
                    None => None,
                };
                let mut tel = computer.step(&TruthMeasurement { t_s, state: xr }, reference)?;
                if let Some((y, solution)) = nav {
                    tel.measured = y;
                    tel.navigation = Some(solution);
                }
                Ok(tel)
            }
        }
    }
}

/// The flight-envelope checks after a plant step at `t_next_s`: the first
/// limit crossed, as a termination kind and a sentence.
fn check_limits(
    scenario: &Scenario,
    x: &State,
    t_next_s: f64,
    psi_ref_next: f64,
) -> Option<(Termination, String)> {
    let plant = &scenario.plant;
    if !x.iter().all(|v| v.is_finite()) {
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

/// Fly a prepared scenario, keeping the log in memory ([`Flight::log`]):
/// one loop per controller sample — sense, run the flight software,
/// integrate the plant, log, check the envelope. A log that would not fit in
/// the memory budget ([`crate::resources::memory_budget`]) is refused before
/// the flight; [`fly_to`] streams it to a file instead.
pub fn fly(
    scenario: &Scenario,
    prepared: &Prepared,
    progress: Option<Progress<'_>>,
) -> Result<Flight, ClosedLoopError> {
    fly_with(scenario, prepared, None, progress)
}

/// As [`fly`], writing each kept log row to `log` as it is flown (memory
/// independent of the duration; [`Flight::log`] stays empty).
pub fn fly_to(
    scenario: &Scenario,
    prepared: &Prepared,
    log: &mut LogWriter,
    progress: Option<Progress<'_>>,
) -> Result<Flight, ClosedLoopError> {
    fly_with(scenario, prepared, Some(log), progress)
}

/// The number of controller samples a flight of this scenario takes, and the
/// kept log rows.
fn sample_counts(scenario: &Scenario, ts: f64) -> (usize, usize) {
    let n = (scenario.duration_s / ts).round() as usize;
    let decimation = scenario.log.decimation.max(1) as usize;
    (n, n / decimation + 2)
}

/// Refuse a memory reservation beyond the budget before flying.
fn check_log_memory(rows: usize, row_bytes: usize) -> Result<(), ClosedLoopError> {
    let (budget, why) = crate::resources::memory_budget();
    let need = (rows as u64).saturating_mul(row_bytes as u64);
    if need > budget {
        return Err(ClosedLoopError::LogTooLarge {
            rows,
            bytes: need,
            budget,
            why,
        });
    }
    Ok(())
}

fn fly_with(
    scenario: &Scenario,
    prepared: &Prepared,
    mut stream: Option<&mut LogWriter>,
    progress: Option<Progress<'_>>,
) -> Result<Flight, ClosedLoopError> {
    let mut progress = progress;
    let ts = prepared.gains.set.sample_time_s;
    let (n, rows) = sample_counts(scenario, ts);
    let decimation = scenario.log.decimation.max(1) as usize;
    let mut log = Vec::new();
    if stream.is_none() {
        check_log_memory(rows, std::mem::size_of::<LogRow>())?;
        log.reserve(rows);
    }
    let record_sensors = scenario.log.sensors && scenario.controller.fusion;
    if record_sensors {
        check_log_memory(n + 1, std::mem::size_of::<SensorLogRow>())?;
    }
    let mut plant = Plant::new(scenario, prepared, ts);
    let mut onboard = OnBoard::new(scenario, prepared, &plant.x)?;
    let mut wind = Wind::from_config(&scenario.wind)?;
    let schedule = scenario.reference_schedule();
    let mut acc = SummaryAccumulator::new(prepared);
    let mut sensors = Vec::new();
    if record_sensors {
        sensors.reserve(n + 1);
    }
    let mut reason: Option<(Termination, String)> = None;
    let mut t = 0.0;
    for k in 0..=n {
        t = k as f64 * ts;
        let wind_ned = wind.step(t, ts);
        let r = schedule.at(t);
        let reference = Reference {
            velocity_ned_m_s: Vector3::new(r[0], r[1], r[2]),
            yaw_rad: r[3],
        };
        let record = record_sensors.then_some(&mut sensors);
        let tel = match onboard.step(t, &plant, &reference, record) {
            Ok(tel) => tel,
            Err(e) => {
                reason = Some((
                    Termination::NavigationFailure,
                    format!("navigation failed at t = {t:.3} s: {e}"),
                ));
                break;
            }
        };
        let x_start = plant.x;
        let step = plant.advance(&tel.command, &wind_ned);
        // the log keeps every `decimation`-th sample (and the last one)
        if k % decimation == 0 || k == n {
            let row = LogRow::new(t, &x_start, &tel, r, &wind_ned, &step.aux);
            acc.push(&row);
            match stream.as_deref_mut() {
                Some(w) => w.write(&row)?,
                None => log.push(row),
            }
        }
        if let Some(e) = step.error {
            reason = Some((
                Termination::ModelFailure,
                format!("model failed at t = {t:.3} s: {e}"),
            ));
            break;
        }
        if let Some(stop) = check_limits(scenario, &plant.x, t + ts, schedule.at(t + ts)[3]) {
            reason = Some(stop);
            break;
        }
        if let Some(cb) = progress.as_mut()
            && k % 400 == 0
        {
            cb(k as f64 / n.max(1) as f64);
        }
    }
    if let Some(cb) = progress.as_mut() {
        cb(1.0);
    }
    let summary = summarize(scenario, prepared, &acc, reason, t);
    Ok(Flight {
        log,
        sensors,
        summary,
    })
}

impl LogRow {
    /// The row of one sample: the true state at its start, the flight
    /// software's telemetry, the reference, the wind and the plant's
    /// auxiliary outputs.
    pub fn new(
        t_s: f64,
        x: &State,
        tel: &Telemetry,
        reference: [f64; 4],
        wind_ned: &Vector3<f64>,
        aux: &Aux,
    ) -> Self {
        LogRow {
            t_s,
            x: *x,
            u: tel.command,
            reference,
            output: outputs(x),
            estimate9: std::array::from_fn(|i| tel.estimate[i]),
            measured9: std::array::from_fn(|i| tel.measured[i]),
            wind_ned: [wind_ned.x, wind_ned.y, wind_ned.z],
            lambda: [aux.lambda_mr, aux.lambda_tr],
            thrust: [-aux.force_mr_hub_n.z, aux.force_tr_y_n],
            inflow_residual: aux.inflow_residual,
        }
    }
}

/// Make a heading-error sequence continuous (no 2π jumps) and shift it by the
/// multiple of 2π that brings its final value nearest zero, so a turn through
/// π in either direction is measured the way the helicopter actually went.
fn unwrap_heading_error(e: &mut [f64]) {
    let two_pi = 2.0 * std::f64::consts::PI;
    let mut prev: Option<f64> = None;
    for v in e.iter_mut() {
        let w = wrap_pi(*v);
        *v = match prev {
            None => w,
            Some(p) => p + wrap_pi(w - p),
        };
        prev = Some(*v);
    }
    if let Some(&last) = e.last() {
        let shift = two_pi * (last / two_pi).round();
        for v in e.iter_mut() {
            *v -= shift;
        }
    }
}

/// What the summary needs from the kept log rows, gathered as they are
/// flown so that its memory does not grow with the duration: sums for the
/// RMS figures (every row) and the output errors for the settling metrics,
/// kept for every row up to [`METRIC_TRACE_CAP`] rows and thinned evenly
/// beyond (every second row dropped, the stride doubled).
#[derive(Debug, Clone)]
pub struct SummaryAccumulator {
    rows: usize,
    effort: [f64; 4],
    saturated_rows: [usize; 4],
    estimator: [f64; 9],
    u_trim: Input,
    s_min: [f64; 4],
    s_max: [f64; 4],
    stride: usize,
    cap: usize,
    trace_t: Vec<f64>,
    trace_e: [Vec<f64>; 4],
}

/// The number of rows of output errors the summary keeps in memory (each
/// 40 bytes): 2¹⁹ rows, 21 MB, every row of a 1310 s flight at 400 Hz.
pub const METRIC_TRACE_CAP: usize = 1 << 19;

impl SummaryAccumulator {
    fn new(prepared: &Prepared) -> Self {
        let servos = prepared.model.params().servos;
        SummaryAccumulator {
            rows: 0,
            effort: [0.0; 4],
            saturated_rows: [0; 4],
            estimator: [0.0; 9],
            u_trim: prepared.gains.set.u_trim,
            s_min: servos.map(|s| s.s_min),
            s_max: servos.map(|s| s.s_max),
            stride: 1,
            cap: METRIC_TRACE_CAP,
            trace_t: Vec::new(),
            trace_e: Default::default(),
        }
    }

    fn push(&mut self, r: &LogRow) {
        for i in 0..4 {
            self.effort[i] += (r.u[i] - self.u_trim[i]).powi(2);
            if r.u[i] <= self.s_min[i] + 1e-12 || r.u[i] >= self.s_max[i] - 1e-12 {
                self.saturated_rows[i] += 1;
            }
        }
        for i in 0..9 {
            let mut d = r.x[i + REDUCED_OFFSET] - r.estimate9[i];
            if i == 2 {
                d = wrap_pi(d);
            }
            self.estimator[i] += d * d;
        }
        if self.rows % self.stride == 0 {
            if self.trace_t.len() == self.cap {
                self.thin();
            }
            if self.rows % self.stride == 0 {
                self.trace_t.push(r.t_s);
                for j in 0..4 {
                    self.trace_e[j].push(r.reference[j] - r.output[j]);
                }
            }
        }
        self.rows += 1;
    }

    /// Drop every second kept row and double the stride.
    fn thin(&mut self) {
        let keep = |v: &mut Vec<f64>| {
            let mut i = 0;
            v.retain(|_| {
                i += 1;
                (i - 1) % 2 == 0
            });
        };
        keep(&mut self.trace_t);
        for e in &mut self.trace_e {
            keep(e);
        }
        self.stride *= 2;
    }

    /// The output errors kept: one every `stride()` rows.
    pub fn stride(&self) -> usize {
        self.stride
    }
}

fn summarize(
    scenario: &Scenario,
    prepared: &Prepared,
    acc: &SummaryAccumulator,
    reason: Option<(Termination, String)>,
    t_end: f64,
) -> Summary {
    let termination = reason.as_ref().map_or(Termination::Completed, |r| r.0);
    let reason = reason.map(|r| r.1);
    let t = &acc.trace_t;
    let mut metrics = std::collections::BTreeMap::new();
    let mut excitations = Vec::with_capacity(4);
    for (j, name) in OUTPUTS.iter().enumerate() {
        let mut e: Vec<f64> = acc.trace_e[j].clone();
        if j == 3 {
            unwrap_heading_error(&mut e);
        }
        // heading statistics on the wrapped error (a half turn either way is the same heading)
        let wrapped: Option<Vec<f64>> = (j == 3).then(|| e.iter().map(|v| wrap_pi(*v)).collect());
        // excitation: the last reference change on this output, else the initial error
        let mut t_exc = 0.0;
        let mut size = e.first().map_or(0.0, |v| v.abs());
        let mut changes: Vec<_> = scenario
            .reference
            .iter()
            .filter(|c| c.output == *name && c.t_s <= t_end)
            .collect();
        changes.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
        if let Some(c) = changes.last() {
            let before = scenario.reference_at(c.t_s - 1e-9)[j];
            t_exc = c.t_s + c.ramp_s;
            size = (c.value - before).abs();
        }
        excitations.push((e, t_exc, size, wrapped));
    }
    let band_scale = excitations.iter().fold(0.0f64, |m, x| m.max(x.2));
    for (name, (e, t_exc, size, wrapped)) in OUTPUTS.iter().zip(excitations) {
        let mut m = output_metrics(t, &e, t_exc, size, band_scale);
        if let Some(w) = wrapped {
            let stats = output_metrics(t, &w, t_exc, size, band_scale);
            m.rms_error = stats.rms_error;
            m.max_abs_error = stats.max_abs_error;
        }
        if reason.is_some() {
            // a run that stopped early never settled
            m.settling_time_s = None;
        }
        metrics.insert((*name).to_string(), m);
    }
    let nrow = acc.rows.max(1) as f64;
    let ts = prepared.gains.set.sample_time_s;
    let row_s = ts * scenario.log.decimation.max(1) as f64;
    let sat = acc.saturated_rows.map(|n| n as f64 * row_s);
    let effort = acc.effort;
    let est = acc.estimator;
    let rho = prepared.gains.spectral_radius();
    Summary {
        scenario: scenario.name.clone(),
        outcome: termination.outcome(),
        termination,
        reason,
        t_end_s: t_end,
        metrics,
        control_effort_rms: effort.map(|v| (v / nrow).sqrt()),
        saturation_time_s: sat,
        estimator_error_rms: est.map(|v| (v / nrow).sqrt()),
        preset: scenario.preset.name().to_string(),
        wind_seed: scenario.wind.seed,
        sensor_seed: scenario.sensors.seed,
        parameter_hash: fnv1a_hex(&prepared.model.params().to_toml()),
        version: env!("CARGO_PKG_VERSION").to_string(),
        sample_time_s: ts,
        metrics_stride: acc.stride,
        design_spectral_radius: rho,
        design_alpha: prepared.gains.set.alpha,
    }
}

/// Number of state columns logged.
pub const LOG_STATES: usize = NX;

#[cfg(test)]
mod tests {
    use super::*;

    fn row(k: usize) -> LogRow {
        LogRow {
            t_s: k as f64,
            x: State::zeros(),
            u: Input::zeros(),
            reference: [k as f64, 0.0, 0.0, 0.0],
            output: [0.0; 4],
            estimate9: [0.0; 9],
            measured9: [0.0; 9],
            wind_ned: [0.0; 3],
            lambda: [0.0; 2],
            thrust: [0.0; 2],
            inflow_residual: [0.0; 2],
        }
    }

    #[test]
    fn metric_trace_is_bounded_and_evenly_thinned() {
        let mut acc = SummaryAccumulator {
            rows: 0,
            effort: [0.0; 4],
            saturated_rows: [0; 4],
            estimator: [0.0; 9],
            u_trim: Input::zeros(),
            s_min: [-1.0; 4],
            s_max: [1.0; 4],
            stride: 1,
            cap: 8,
            trace_t: Vec::new(),
            trace_e: Default::default(),
        };
        for k in 0..100 {
            acc.push(&row(k));
            assert!(acc.trace_t.len() <= 8);
        }
        // 100 rows into 8 slots: stride 16, rows 0, 16, …, 96 kept
        assert_eq!(acc.stride(), 16);
        assert_eq!(acc.trace_t, [0.0, 16.0, 32.0, 48.0, 64.0, 80.0, 96.0]);
        assert_eq!(acc.trace_e[0], acc.trace_t);
        // the RMS sums still see every row
        assert_eq!(acc.rows, 100);
    }
}
