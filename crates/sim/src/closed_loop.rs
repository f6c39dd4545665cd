//! The closed loop: the thesis's Simulink environment (Appendix E figure)
//! rebuilt as software. World (nonlinear model + wind [+ sensor models]) and
//! the on-board [`FlightController`] exchange servo commands and measurements
//! once per controller sample; the plant is integrated with RK4 in between
//! (inputs held, optional sub-steps).
//!
//! Preparation ([`prepare`]): trim at the scenario's design point, linearize,
//! ZOH-discretize, design (or load) the gains. Flight ([`fly`]): one loop per
//! sample; divergence (non-finite state, attitude beyond the limit, a model or
//! estimator failure) stops the run cleanly with the reason, time and state,
//! keeping the log so far.

use crate::metrics::{OutputMetrics, output_metrics};
use crate::navigation::{frame, navigation_filter_at, sensor_suite_at};
use crate::scenario::{DesignInflow, OUTPUTS, PlantInflow, Scenario};
use crate::sensors::SensorSuite;
use crate::trajectory::TruthSample;
use crate::wind::{Wind, WindModel};
use helicon_gnc::controller::{ControllerSwitches, Feedback, FlightController, Reference};
use helicon_gnc::design::{Gains, design};
use helicon_gnc::fusion::wrap_pi;
use helicon_gnc::navigation::FlightComputer;
use helicon_model::integrate::rk4;
use helicon_model::linearize::linearize;
use helicon_model::state::{NX, REDUCED_OFFSET, expand, ix, reduce};
use helicon_model::trim::{Trim, TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Input, Model, ModelError, Params, ReducedState, State};
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
    /// Wind configuration.
    #[error(transparent)]
    Wind(#[from] crate::wind::WindError),
    /// Sensor configuration.
    #[error(transparent)]
    Sensors(#[from] crate::sensors::SensorConfigError),
    /// Navigation (fusion) setup.
    #[error(transparent)]
    Fusion(#[from] helicon_gnc::fusion::FusionError),
    /// The log would not fit in memory.
    #[error("the flight log would need {rows} rows: raise [log] decimation or shorten duration_s")]
    LogTooLarge {
        /// Rows needed.
        rows: usize,
    },
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
    let t = trim(&model, &target, &TrimOptions::default())?;
    let gains = match &scenario.controller.gains_file {
        Some(f) => Gains::load(&scenario.resolve(f))?,
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
            let (phi, gamma) = lm.discretize(scenario.controller.design.sample_time_s)?;
            design(
                &phi,
                &gamma,
                t.x.as_slice(),
                t.u.as_slice(),
                &scenario.controller.design,
            )?
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
    /// Closed-loop poles of the design: largest |z|.
    pub design_spectral_radius: f64,
    /// Pincer α of the design.
    pub design_alpha: f64,
}

/// A finished flight: the log and the summary.
#[derive(Debug, Clone)]
pub struct Flight {
    /// Samples (every sample; decimate when writing).
    pub log: Vec<LogRow>,
    /// Summary and metrics.
    pub summary: Summary,
}

/// The on-board software flown in the loop.
enum OnBoard {
    /// The controller with ideal measurements (or truth).
    Controller(Box<FlightController>),
    /// Sensor models feeding the whole flight computer.
    Computer {
        /// The world's sensors.
        suite: Box<SensorSuite>,
        /// Navigation + controller.
        computer: Box<FlightComputer>,
    },
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
    let v = helicon_model::frames::EulerTrig::new(x[ix::PHI], x[ix::THETA], x[ix::PSI])
        .ned_from_body()
        * Vector3::new(x[ix::U], x[ix::V], x[ix::W]);
    [v.x, v.y, v.z, x[ix::PSI]]
}

/// Progress callback: fraction done in [0, 1].
pub type Progress<'a> = &'a mut dyn FnMut(f64);

/// Fly a prepared scenario.
pub fn fly(
    scenario: &Scenario,
    prepared: &Prepared,
    progress: Option<Progress<'_>>,
) -> Result<Flight, ClosedLoopError> {
    let mut progress = progress;
    let model = &prepared.model;
    let p = model.params();
    let servos = &p.servos;
    let u_min = [
        servos[0].s_min,
        servos[1].s_min,
        servos[2].s_min,
        servos[3].s_min,
    ];
    let u_max = [
        servos[0].s_max,
        servos[1].s_max,
        servos[2].s_max,
        servos[3].s_max,
    ];
    let sw = ControllerSwitches {
        feedback: scenario.controller.feedback,
        estimator: scenario.controller.estimator,
    };
    let mut ctrl = FlightController::new(&prepared.gains, u_min, u_max, sw)?;
    let mut x = initial_state(scenario, &prepared.trim);
    let x_trim27 = prepared.trim.x;
    // The estimator starts from the measured states and the trim for the rest.
    let mut x0_est = x_trim27;
    for i in 0..9 {
        x0_est[i] = x[i + REDUCED_OFFSET];
    }
    ctrl.reset(&x0_est);
    let mut wind = Wind::from_config(&scenario.wind)?;
    let ts = scenario.controller.design.sample_time_s;
    let n = (scenario.duration_s / ts).round() as usize;
    let h = ts / f64::from(scenario.plant.substeps);
    // The on-board software: the controller alone (ideal measurements), or the
    // whole flight computer (navigation + controller) fed by the sensor models.
    let mut onboard = if scenario.controller.fusion {
        OnBoard::Computer {
            suite: Box::new(sensor_suite_at(&scenario.sensors, ts)?),
            computer: Box::new(FlightComputer {
                navigation: navigation_filter_at(&scenario.sensors, &scenario.navigation, ts, &x)?,
                controller: ctrl,
            }),
        }
    } else {
        OnBoard::Controller(Box::new(ctrl))
    };
    let mut lam = (prepared.trim.aux.lambda_mr, prepared.trim.aux.lambda_tr);
    let schedule = scenario.reference_schedule();
    let decimation = scenario.log.decimation.max(1) as usize;
    let mut log = Vec::new();
    log.try_reserve(n / decimation + 2)
        .map_err(|_| ClosedLoopError::LogTooLarge {
            rows: n / decimation + 2,
        })?;
    let mut reason: Option<(Termination, String)> = None;
    let mut t = 0.0;
    let mut prev_xdot = State::zeros();
    for k in 0..=n {
        t = k as f64 * ts;
        let wind_ned = wind.step(t, ts);
        let r = schedule.at(t);
        let reference = Reference {
            velocity_ned_m_s: Vector3::new(r[0], r[1], r[2]),
            yaw_rad: r[3],
        };
        let xr: ReducedState = reduce(&x);
        let fb_full = !scenario.controller.estimator;
        let (out, measured9) = match &mut onboard {
            OnBoard::Controller(c) => {
                let y: SVector<f64, 9> = SVector::from_fn(|i, _| xr[i]);
                let fb = if fb_full {
                    Feedback::Full(&xr)
                } else {
                    Feedback::Measured(&y)
                };
                (c.step(fb, &reference), y)
            }
            OnBoard::Computer { suite, computer } => {
                let ned_from_body =
                    helicon_model::frames::EulerTrig::new(x[ix::PHI], x[ix::THETA], x[ix::PSI])
                        .ned_from_body();
                let v_body = Vector3::new(x[ix::U], x[ix::V], x[ix::W]);
                let omega = Vector3::new(x[ix::P], x[ix::Q], x[ix::R]);
                // inertial acceleration from the previous sample's derivative (one sample old)
                let acc_ned = ned_from_body
                    * (Vector3::new(prev_xdot[ix::U], prev_xdot[ix::V], prev_xdot[ix::W])
                        + omega.cross(&v_body));
                let truth = TruthSample {
                    t_s: t,
                    pos_ned_m: Vector3::new(x[ix::X], x[ix::Y], x[ix::Z]),
                    vel_ned_m_s: ned_from_body * v_body,
                    acc_ned_m_s2: acc_ned,
                    euler_rad: Vector3::new(x[ix::PHI], x[ix::THETA], x[ix::PSI]),
                    omega_body_rad_s: omega,
                };
                let sensor_frame = frame(&suite.sample(&truth));
                let res = if fb_full {
                    // analysis switch: navigation runs (and is logged) but the
                    // controller is fed the true state
                    computer
                        .navigation
                        .step(&sensor_frame, None)
                        .map(|y| (computer.controller.step(Feedback::Full(&xr), &reference), y))
                } else {
                    computer.step(&sensor_frame, &reference)
                };
                match res {
                    Ok(v) => v,
                    Err(e) => {
                        reason = Some((
                            Termination::NavigationFailure,
                            format!("navigation failed at t = {t:.3} s: {e}"),
                        ));
                        break;
                    }
                }
            }
        };
        let x_start = x;
        let est = out.x_estimate;
        let u = out.u;
        // plant: RK4 sub-steps with u and wind held
        let mut aux_first = None;
        let mut step_err: Option<ModelError> = None;
        for _ in 0..scenario.plant.substeps {
            let res = rk4(&x, h, |s| {
                let inflow = match scenario.plant.inflow {
                    PlantInflow::Converged => InflowMode::ConvergedFrom {
                        lambda_mr_hint: lam.0,
                        lambda_tr_hint: lam.1,
                    },
                    PlantInflow::ThesisIteration => InflowMode::ThesisIteration {
                        lambda_mr_in: lam.0,
                        lambda_tr_in: lam.1,
                        iterations: scenario.plant.inflow_iterations,
                    },
                };
                let (d, a) = model.derivative_with(s, &u, &wind_ned, inflow)?;
                // warm start (converged) or the thesis's recursion (iteration)
                lam = (a.lambda_mr, a.lambda_tr);
                if aux_first.is_none() {
                    aux_first = Some((a, d));
                }
                Ok::<_, ModelError>(d)
            });
            match res {
                Ok(next) => x = next,
                Err(e) => {
                    step_err = Some(e);
                    break;
                }
            }
        }
        let (aux, xdot) = aux_first.unwrap_or_default();
        prev_xdot = xdot;
        // the log keeps every `decimation`-th sample (and the last one)
        let keep = k % decimation == 0 || k == n;
        if keep {
            log.push(LogRow {
                t_s: t,
                x: x_start,
                u,
                reference: r,
                output: outputs(&x_start),
                estimate9: std::array::from_fn(|i| est[i]),
                measured9: std::array::from_fn(|i| measured9[i]),
                wind_ned: [wind_ned.x, wind_ned.y, wind_ned.z],
                lambda: [aux.lambda_mr, aux.lambda_tr],
                thrust: [-aux.force_mr_hub_n.z, aux.force_tr_y_n],
                inflow_residual: aux.inflow_residual,
            });
        }
        if let Some(e) = step_err {
            reason = Some((
                Termination::ModelFailure,
                format!("model failed at t = {t:.3} s: {e}"),
            ));
            break;
        }
        if !x.iter().all(|v| v.is_finite()) {
            reason = Some((
                Termination::NonFiniteState,
                format!("non-finite state at t = {:.3} s", t + ts),
            ));
            break;
        }
        let lim = scenario.plant.max_attitude_rad;
        if x[ix::PHI].abs() > lim || x[ix::THETA].abs() > lim {
            reason = Some((
                Termination::AttitudeLimit,
                format!(
                    "attitude beyond {lim} rad at t = {:.3} s (phi = {:.3}, theta = {:.3})",
                    t + ts,
                    x[ix::PHI],
                    x[ix::THETA]
                ),
            ));
            break;
        }
        let rate = x[ix::P].abs().max(x[ix::Q].abs()).max(x[ix::R].abs());
        if rate > scenario.plant.max_rate_rad_s {
            reason = Some((
                Termination::RateLimit,
                format!(
                    "body rate {rate:.2} rad/s beyond {} rad/s at t = {:.3} s",
                    scenario.plant.max_rate_rad_s,
                    t + ts
                ),
            ));
            break;
        }
        let r_next = schedule.at(t + ts);
        let yaw_err = x[ix::PSI] - r_next[3];
        if yaw_err.abs() > scenario.plant.max_yaw_error_rad {
            reason = Some((
                Termination::HeadingLost,
                format!(
                    "heading {:.2} rad is {yaw_err:.2} rad from its reference at t = {:.3} s: the helicopter spins away",
                    x[ix::PSI],
                    t + ts
                ),
            ));
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
    let summary = summarize(scenario, prepared, &log, reason, t);
    Ok(Flight { log, summary })
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

fn summarize(
    scenario: &Scenario,
    prepared: &Prepared,
    log: &[LogRow],
    reason: Option<(Termination, String)>,
    t_end: f64,
) -> Summary {
    let termination = reason.as_ref().map_or(Termination::Completed, |r| r.0);
    let reason = reason.map(|r| r.1);
    let t: Vec<f64> = log.iter().map(|r| r.t_s).collect();
    let mut metrics = std::collections::BTreeMap::new();
    let mut excitations = Vec::with_capacity(4);
    for (j, name) in OUTPUTS.iter().enumerate() {
        let mut e: Vec<f64> = log.iter().map(|r| r.reference[j] - r.output[j]).collect();
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
        let mut m = output_metrics(&t, &e, t_exc, size, band_scale);
        if let Some(w) = wrapped {
            let stats = output_metrics(&t, &w, t_exc, size, band_scale);
            m.rms_error = stats.rms_error;
            m.max_abs_error = stats.max_abs_error;
        }
        if reason.is_some() {
            // a run that stopped early never settled
            m.settling_time_s = None;
        }
        metrics.insert((*name).to_string(), m);
    }
    let u_trim = &prepared.gains.u_trim;
    let nrow = log.len().max(1) as f64;
    let ts = scenario.controller.design.sample_time_s;
    let servos = prepared.model.params().servos;
    let mut effort = [0.0; 4];
    let mut sat = [0.0; 4];
    for r in log {
        for i in 0..4 {
            effort[i] += (r.u[i] - u_trim[i]).powi(2);
            if r.u[i] <= servos[i].s_min + 1e-12 || r.u[i] >= servos[i].s_max - 1e-12 {
                sat[i] += ts * scenario.log.decimation.max(1) as f64;
            }
        }
    }
    let mut est = [0.0; 9];
    for r in log {
        for i in 0..9 {
            let mut d = r.x[i + REDUCED_OFFSET] - r.estimate9[i];
            if i == 2 {
                d = wrap_pi(d);
            }
            est[i] += d * d;
        }
    }
    let rho = prepared
        .gains
        .closed_loop_poles
        .iter()
        .map(|z| (z[0] * z[0] + z[1] * z[1]).sqrt())
        .fold(0.0, f64::max);
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
        design_spectral_radius: rho,
        design_alpha: prepared.gains.alpha,
    }
}

/// Number of state columns logged.
pub const LOG_STATES: usize = NX;
