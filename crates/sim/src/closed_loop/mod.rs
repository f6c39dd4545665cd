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
use crate::vibration::RotorSpeeds;
use crate::wind::{Wind, WindModel};
use helicon_core::frames::{EulerTrig, wrap_pi};
use helicon_core::imu_health::ImuHealthMonitor;
use helicon_core::navigation::NavigationFilter;
use helicon_core::{
    CoreError, FlightComputer, Reference, StateMeasurement, Telemetry, TruthFeed, TruthMeasurement,
};
use helicon_gnc::design::{Gains, design};
use helicon_model::gyro::YawGyroBlock;
use helicon_model::integrate::rk4;
use helicon_model::linearize::linearize;
use helicon_model::state::{REDUCED_OFFSET, expand, ix, reduce};
use helicon_model::trim::{Trim, TrimOptions, TrimTarget, trim};
use helicon_model::{Aux, InflowMode, Input, Model, ModelError, Params, ReducedState, State};
use nalgebra::{SVector, Vector3};
use serde::Serialize;

mod hardware;
mod stages;
mod summary;

pub use hardware::{Hardware, HardwareSample, HardwareStep};
pub use helicon_setup::builder::{OnBoardSetup, flight_computer, imu_health_at};
use stages::{OnBoard, Plant, check_limits};
use summary::summarize;
pub use summary::{METRIC_TRACE_CAP, Outcome, Summary, SummaryAccumulator, Termination};

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
    /// Gain-schedule design or file.
    #[error(transparent)]
    Schedule(#[from] helicon_gnc::schedule::ScheduleError),
    /// Wind or sensor configuration (the one configuration error shape).
    #[error(transparent)]
    Config(#[from] helicon_model::ConfigError),
    /// The yaw-gyro augmentation of the design model.
    #[error(transparent)]
    Gyro(#[from] helicon_model::gyro::AugmentShapeError),
    /// Navigation (fusion) setup.
    #[error(transparent)]
    Fusion(#[from] helicon_core::fusion::FusionError),
    /// The flight software could not be built from the gains.
    #[error("flight software: {0}")]
    Core(#[from] CoreError),
    /// The flight computer could not be built (the one builder's error).
    #[error(transparent)]
    Build(#[from] helicon_setup::BuildError),
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
    /// The gains flown (with a schedule: its design point nearest the trim,
    /// for the sample time and the summary's design figures).
    pub gains: Gains,
    /// The gain schedule flown instead of `gains`, when the scenario names one.
    pub schedule: Option<std::sync::Arc<helicon_core::GainSchedule>>,
    /// The summaries' `parameter_hash` of `model`, remembered (start with
    /// `ParameterHash::default()`).
    pub parameter_hash: ParameterHash,
}

/// The FNV-1a hash of the parameters' TOML that each flight's summary
/// carries, computed once: writing the TOML costs about as much as a
/// thousand control steps, and every flight of a prepared scenario has the
/// same parameters.
#[derive(Debug, Clone, Default)]
pub struct ParameterHash(std::sync::OnceLock<(helicon_model::Params, String)>);

impl ParameterHash {
    /// The hash of `params`: remembered from the first call, for those
    /// parameters (others are hashed afresh each time).
    pub fn of(&self, params: &helicon_model::Params) -> String {
        if let Some((p, h)) = self.0.get()
            && p == params
        {
            return h.clone();
        }
        let h = fnv1a_hex(&params.to_toml());
        let _ = self.0.set((*params, h.clone()));
        h
    }
}

impl Prepared {
    /// What the on-board chain of `scenario` is built from, started at the
    /// aligned state `x0`: this design's gains (or schedule) and trim, the
    /// scenario's sensors, navigation, estimator and feedback switch.
    pub fn onboard_setup<'a>(&'a self, scenario: &'a Scenario, x0: &'a State) -> OnBoardSetup<'a> {
        let p = self.model.params();
        OnBoardSetup {
            servo_limits: p.servo_limits(),
            gravity_m_s2: p.environment.g_m_s2,
            gains: &self.gains.set,
            schedule: self.schedule.as_ref(),
            trim_x: &self.trim.x,
            sensors: &scenario.sensors,
            navigation: &scenario.navigation,
            estimator: &scenario.estimator,
            feedback: scenario.controller.feedback,
            x0,
        }
    }
}

/// The design for the helicopter as flown with the yaw-rate gyro: the tail
/// input is the yaw-rate command, its trim the mid-range (0 rad/s). The
/// design model is the gyro-augmented model (plant closed by the block) with
/// the block's integrator held at its trim value: the flight software's
/// 27-state layout has no room for it, and the LQI's ψ integral absorbs its
/// slow drift.
fn gyro_design(
    gyro: &YawGyroBlock,
    phi: &nalgebra::DMatrix<f64>,
    gamma: &nalgebra::DMatrix<f64>,
    t: &Trim,
    ts: f64,
    scenario: &Scenario,
) -> Result<Gains, ClosedLoopError> {
    let (phi_a, gamma_a) = gyro.augment_discrete(phi, gamma, ix::R - REDUCED_OFFSET)?;
    let n = phi.nrows();
    let phi_d = phi_a.view((0, 0), (n, n)).into_owned();
    let gamma_d = gamma_a.view((0, 0), (n, 4)).into_owned();
    let mut u = t.u;
    u[3] = gyro.mid_input();
    Ok(design(
        &phi_d,
        &gamma_d,
        &t.x,
        &u,
        ts,
        &gyro_design_config(gyro, &scenario.controller.design)?,
    )?)
}

/// The design settings for the helicopter flown with the gyro: the tail
/// input's Bryson maximum is a yaw-rate command
/// (`yaw_rate_command_max_rad_s`, by default the gyro's full range), not the
/// thesis's tail-pitch deflection `input_max[3]` (14.27). With 0.04 of input
/// (0.24 rad/s) the rate command was so dear that the LQR met the pincer's
/// heading decay with the cyclic instead (a ψ gain on S_lat six times the
/// gyro-less design's): the ψ = π step of Figure 14.5 then saturated the
/// lateral cyclic and rolled the helicopter over within 0.4 s.
pub fn gyro_design_config(
    gyro: &YawGyroBlock,
    config: &helicon_gnc::design::ControllerConfig,
) -> Result<helicon_gnc::design::ControllerConfig, ClosedLoopError> {
    config.validate()?;
    let rate = config
        .yaw_rate_command_max_rad_s
        .unwrap_or_else(|| gyro.max_rate_rad_s());
    let mut c = config.clone();
    c.input_max[3] = rate / gyro.rate_per_input_rad_s();
    Ok(c)
}

/// The parameters a scenario flies: its `params` file (relative to the
/// scenario), or the Bergen Twin.
pub fn scenario_params(scenario: &Scenario) -> Result<Params, ClosedLoopError> {
    Ok(match &scenario.params {
        Some(p) => Params::from_file(&scenario.resolve(p))?,
        None => Params::bergen_twin(),
    })
}

/// Trim, linearize, discretize and design (or load) the gains for a scenario.
pub fn prepare(scenario: &Scenario) -> Result<Prepared, ClosedLoopError> {
    prepare_with_params(scenario, scenario_params(scenario)?)
}

/// As [`prepare`] with explicit parameters (Monte Carlo dispersions).
pub fn prepare_with_params(
    scenario: &Scenario,
    params: Params,
) -> Result<Prepared, ClosedLoopError> {
    if let Some(g) = &scenario.ground {
        g.check_params(&params, &scenario.name)?;
    }
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
    let gyro = YawGyroBlock::at_trim(model.params(), ts, t.u[3]);
    let gyro_mismatch = |file: String, rule: &str| {
        ClosedLoopError::Config(helicon_model::ConfigError::invalid(
            &file,
            "yaw_gyro.enabled",
            1.0,
            rule,
        ))
    };
    if let Some(s) = crate::envelope::scenario_schedule(scenario)? {
        if gyro.is_some() {
            return Err(gyro_mismatch(
                "parameters".into(),
                "gain schedules are designed without the yaw-rate gyro: fly the gyro with a single design",
            ));
        }
        let (schedule, core) = &*s;
        if schedule.sample_time_s() != ts {
            return Err(ClosedLoopError::SampleTimeMismatch {
                file: format!("gain schedule `{}`", schedule.name),
                gains_s: schedule.sample_time_s(),
                params_s: ts,
            });
        }
        let sigma = helicon_core::schedule::heading_axes(target.yaw_rad, &target.velocity_ned_m_s);
        let nearest = (0..schedule.points.len())
            .min_by(|&a, &b| {
                let d = |i: usize| (Vector3::from(schedule.operating_point(i)) - sigma).norm();
                d(a).total_cmp(&d(b))
            })
            .unwrap_or(0);
        return Ok(Prepared {
            model,
            trim: t,
            gains: schedule.points[nearest].clone(),
            schedule: Some(std::sync::Arc::new(core.clone())),
            parameter_hash: ParameterHash::default(),
        });
    }
    let gains = match &scenario.controller.gains_file {
        Some(f) => {
            let path = scenario.resolve(f);
            let g = Gains::load(&path)?;
            if let Some(gyro) = &gyro {
                // a gyro design trims the tail input at mid-range (0 rad/s)
                if g.set.u_trim[3] != gyro.mid_input() {
                    return Err(gyro_mismatch(
                        path.display().to_string(),
                        "these gains were designed without the yaw-rate gyro (tail trim input is \
                         not the mid-range 0 rad/s command): redesign with the gyro on",
                    ));
                }
            }
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
            match gyro {
                None => design(&phi, &gamma, &t.x, &t.u, ts, &scenario.controller.design)?,
                Some(gyro) => gyro_design(&gyro, &phi, &gamma, &t, ts, scenario)?,
            }
        }
    };
    Ok(Prepared {
        model,
        trim: t,
        gains,
        schedule: None,
        parameter_hash: ParameterHash::default(),
    })
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
    /// The flight software's IMU health after this sample: in-band
    /// vibration RMS (m/s²), |mean f| − g (m/s²) and the flags
    /// (`helicon_core::ImuHealth`); zeros without sensor models.
    pub imu_health: [f64; 3],
    /// The servo excitation added to the law's command this sample
    /// [S_col, S_lat, S_lon, S_tr] (rad, before saturation; `[[excitation]]`).
    pub excitation: [f64; 4],
}

/// One sample of the ground blocks (kept with the log's decimation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundRow {
    /// Time (s).
    pub t_s: f64,
    /// The CM's height above the ground plane (m).
    pub height_m: f64,
    /// Rotor speed, contact forces, plan phase.
    pub sample: crate::ground::GroundSample,
}

/// A finished flight: the log and the summary.
#[derive(Debug, Clone)]
pub struct Flight {
    /// Samples (every `[log] decimation`-th).
    pub log: Vec<LogRow>,
    /// The ground blocks' samples, at the log's rows, kept in memory also
    /// when the log is streamed (empty unless the parameters enable the
    /// landing gear or the drivetrain).
    pub ground: Vec<GroundRow>,
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
    fly_with(scenario, prepared, None, progress, None)
}

/// As [`fly`] (the log in memory), checking `stop` once per controller
/// sample: once it is set the flight ends after the sample being flown, as
/// [`Termination::Stopped`]. For a caller that stops a flight from another
/// thread (the Python package's Ctrl-C).
pub fn fly_until(
    scenario: &Scenario,
    prepared: &Prepared,
    progress: Option<Progress<'_>>,
    stop: &std::sync::atomic::AtomicBool,
) -> Result<Flight, ClosedLoopError> {
    fly_with(scenario, prepared, None, progress, Some(stop))
}

/// As [`fly`], writing each kept log row to `log` as it is flown (memory
/// independent of the duration; [`Flight::log`] stays empty).
pub fn fly_to(
    scenario: &Scenario,
    prepared: &Prepared,
    log: &mut LogWriter,
    progress: Option<Progress<'_>>,
) -> Result<Flight, ClosedLoopError> {
    fly_with(scenario, prepared, Some(log), progress, None)
}

/// As [`fly_to`], checking `stop` once per controller sample: once it is
/// set the flight ends after the sample being flown (its row logged), as
/// [`Termination::Stopped`] (the summary covers what was flown). For a
/// signal handler's flag (`helicon sim` on SIGINT/SIGTERM).
pub fn fly_to_until(
    scenario: &Scenario,
    prepared: &Prepared,
    log: &mut LogWriter,
    progress: Option<Progress<'_>>,
    stop: &std::sync::atomic::AtomicBool,
) -> Result<Flight, ClosedLoopError> {
    fly_with(scenario, prepared, Some(log), progress, Some(stop))
}

/// Seconds flown (in memory) by [`estimate_log_csv`] to measure a row.
pub const PILOT_S: f64 = 2.0;

/// The `log.csv` that [`fly_to`] writes for `scenario` through a writer of
/// stride `stride` ([`LogWriter::with_stride`]): its rows (the flight
/// flown to its end) and estimated size, the bytes of a row measured on the
/// first [`PILOT_S`] seconds flown in memory (see
/// [`crate::log_csv::estimate_log_size`]). Cheap next to the flight: for a
/// limit on the log's size before flying.
pub fn estimate_log_csv(
    scenario: &Scenario,
    prepared: &Prepared,
    stride: u64,
) -> Result<crate::log_csv::LogSizeEstimate, ClosedLoopError> {
    let ts = prepared.gains.set.sample_time_s;
    let n = (scenario.duration_s / ts).round() as u64;
    let d = u64::from(scenario.log.decimation.max(1));
    let kept = n / d + 1 + u64::from(n % d != 0);
    let stride = stride.max(1);
    let rows = crate::log_csv::strided_rows(kept, stride);
    let mut pilot = scenario.clone();
    pilot.duration_s = scenario.duration_s.min(PILOT_S);
    let flight = fly(&pilot, prepared, None)?;
    let time_at = |j: u64| (j.saturating_mul(stride).saturating_mul(d)).min(n) as f64 * ts;
    Ok(
        crate::log_csv::estimate_log_size(&flight.log, rows, time_at).unwrap_or(
            crate::log_csv::LogSizeEstimate {
                rows,
                // no row flown: every cell at its widest (sign, 17 digits,
                // point, exponent) and a comma
                bytes_per_row: 25.0 * crate::log_csv::LOG_SCHEMA.len() as f64,
                bytes: crate::log_csv::header_bytes()
                    + rows * 25 * crate::log_csv::LOG_SCHEMA.len() as u64,
            },
        ),
    )
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

/// The flight software's IMU health monitor, when sensor models fly.
fn imu_health_monitor(
    scenario: &Scenario,
    prepared: &Prepared,
) -> Result<Option<ImuHealthMonitor>, ClosedLoopError> {
    if !scenario.controller.fusion {
        return Ok(None);
    }
    imu_health_at(
        prepared.model.params().environment.g_m_s2,
        prepared.gains.set.sample_time_s,
        &scenario.sensors,
        "<scenario>",
    )
    .map(Some)
    .map_err(Into::into)
}

#[allow(clippy::too_many_lines)] // one flight in order: set up, step (ground plan, stop flag), log, summarise
fn fly_with(
    scenario: &Scenario,
    prepared: &Prepared,
    mut stream: Option<&mut LogWriter>,
    progress: Option<Progress<'_>>,
    stop: Option<&std::sync::atomic::AtomicBool>,
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
    let params = prepared.model.params();
    let mut plan = scenario.ground.map(|g| {
        crate::ground::GroundFlight::new(&g, params, ts, &prepared.gains.set.u_trim, &plant.x)
    });
    let mut ground_rows = Vec::new();
    if plant.ground.is_some() {
        check_log_memory(rows, std::mem::size_of::<GroundRow>())?;
        ground_rows.reserve(rows);
    }
    let mut onboard = OnBoard::new(scenario, prepared, &plant.x)?;
    let mut wind = Wind::from_config(&scenario.wind)?;
    let mut health = imu_health_monitor(scenario, prepared)?;
    let schedule = scenario.reference_schedule();
    let excitations = crate::excitation::Excitations::new(&scenario.excitation, &scenario.name)?;
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
        let exc = excitations.at(t);
        // the on-board ground logic: the law held on the ground and until
        // lift-off, the servos' command blended from ground idle
        if plan
            .as_ref()
            .is_some_and(crate::ground::GroundFlight::holds_law)
        {
            onboard.reset_feedback();
        }
        let servo = |u: &Input| plan.as_mut().and_then(|p| p.servo(u));
        let stepped = onboard.step(t, &plant, &reference, &exc, record, health.as_mut(), servo);
        let (tel, gyro) = match stepped {
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
        let omega_start = plant.omega_rad_s();
        let contact_start = plant.ground.as_ref().map(|g| g.contact);
        let command = tel.command;
        if let Some(plan) = plan.as_mut() {
            let truth = plant.truth(t);
            let onboard_view = crate::ground::OnBoardView {
                // the navigation's solution; the truth with ideal navigation
                position_velocity_ned: Some(
                    tel.navigation
                        .map_or((truth.pos_ned_m, truth.vel_ned_m_s), |n| {
                            (n.position_ned_m, n.velocity_ned_m_s)
                        }),
                ),
                gyro_body_rad_s: Some(gyro.unwrap_or(truth.omega_body_rad_s)),
            };
            plan.update(
                t,
                &reference,
                &onboard_view,
                &crate::ground::TruthView {
                    x: &x_start,
                    on_ground: contact_start.is_some_and(|c| c.on_ground()),
                    total_normal_n: contact_start.map_or(0.0, |c| c.total_normal_n()),
                    omega_rad_s: omega_start,
                },
            );
            if let Some(g) = plant.ground.as_mut() {
                g.drive = plan.drive(params);
            }
        }
        let step = plant.advance(&command, &wind_ned);
        // the log keeps every `decimation`-th sample (and the last one)
        if k % decimation == 0 || k == n {
            let mut row = LogRow::new(t, &x_start, &tel, r, &wind_ned, &step.aux);
            row.u = command;
            row.excitation = exc.into();
            if let Some(c) = contact_start {
                ground_rows.push(ground_row(
                    prepared,
                    plan.as_ref(),
                    t,
                    &x_start,
                    omega_start,
                    &c,
                    &step.aux,
                ));
            }
            if let Some(h) = health.as_ref().map(ImuHealthMonitor::health) {
                row.imu_health = [
                    h.vibration_rms_m_s2,
                    h.gravity_residual_m_s2,
                    f64::from(h.flags),
                ];
            }
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
        if stop.is_some_and(|s| s.load(std::sync::atomic::Ordering::Relaxed)) && k < n {
            reason = Some((
                Termination::Stopped,
                format!("stopped on request at t = {t:.3} s"),
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
    let mut summary = summarize(scenario, prepared, &acc, reason, t);
    summary.ground = plan.map(|p| p.metrics(plant.omega_rad_s()));
    Ok(Flight {
        log,
        ground: ground_rows,
        sensors,
        summary,
    })
}

/// The ground row of one sample: the state at its start, the contact there,
/// the on-board ground logic after it, the plant's auxiliary outputs.
fn ground_row(
    prepared: &Prepared,
    plan: Option<&crate::ground::GroundFlight>,
    t_s: f64,
    x: &State,
    omega_rad_s: f64,
    contact: &helicon_model::landing_gear::ContactWrench,
    aux: &Aux,
) -> GroundRow {
    let plane = prepared.model.ground_plane();
    let gear = &prepared.model.params().landing_gear;
    GroundRow {
        t_s,
        height_m: plane.height_m(&Vector3::new(x[ix::X], x[ix::Y], x[ix::Z])),
        sample: crate::ground::GroundSample {
            clearance_m: if gear.is_enabled() {
                helicon_model::landing_gear::clearance_m(gear, x)
            } else {
                f64::NAN
            },
            omega_rad_s,
            throttle: aux.throttle,
            normal_n: contact.normal_n,
            friction_n: contact.friction_n.iter().sum(),
            ground_effect_factor: aux.ground_effect_factor,
            spool_state: plan.map_or(f64::NAN, |p| f64::from(p.spool_state().code())),
            land_stage: plan.map_or(f64::NAN, |p| f64::from(p.land_stage().code())),
            blend: plan.map_or(1.0, |p| p.sample_blend()),
        },
    }
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
            imu_health: [0.0; 3],
            excitation: [0.0; 4],
        }
    }
}
