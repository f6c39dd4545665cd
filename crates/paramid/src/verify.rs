//! Time-domain verification: the identified nonlinear model flown on the
//! servo commands of a flight that was not used in the fit (doublets), as
//! flight-test practice checks a frequency-domain model.
//!
//! The replay starts from the best state the log holds (`initial_state`):
//! the logged true 30-state at the window's first sample (a simulator's log),
//! else the model's trim with the nine estimated states `est_*` of that
//! sample (a real flight), and is driven open loop by the logged servo
//! commands as they are; or (`"trim"`) the model's own trim at the
//! operating point driven by u(t) = u_trim + (S(t) − S(t0)). The logged wind
//! (`wind_n`, `wind_e`, `wind_d`) is flown when the log has it (`wind`), else
//! still air. RK4 at the log's step, commands and wind held over each step.
//! Each output is compared as a perturbation from its first sample with
//! Theil's inequality coefficient (`helicon_ident::fit::theil`): 0 for a
//! perfect match, below ~0.25–0.3 good. An unstable helicopter flown open
//! loop drifts away from any log given time, so windows stay short.

use crate::config::{IdentConfig, InitialState, Response, Verification, WindSource};
use crate::data::read_record;
use crate::error::{ParamIdError, Result};
use crate::linear::{linear_model, target};
use helicon_model::state::{REDUCED_OFFSET, STATE_NAMES, State, expand, ix};
use helicon_model::{ConfigError, INPUT_NAMES, Input, Model, Params};
use nalgebra::Vector3;
use serde::Serialize;

/// One output of one verification flight.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VerifiedOutput {
    /// Log column.
    pub output: String,
    /// Theil coefficient of the start model.
    pub theil_start: f64,
    /// Theil coefficient of the identified model.
    pub theil_identified: f64,
}

/// One verification flight's outcome, with the traces for plots.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VerificationResult {
    /// The log.
    pub log: String,
    /// Operating point.
    pub operating_point: String,
    /// Where the replay started.
    pub initial_state: InitialState,
    /// The wind flown.
    pub wind: WindSource,
    /// Per output.
    pub outputs: Vec<VerifiedOutput>,
    /// Time, s (from the window's start).
    #[serde(skip)]
    pub t_s: Vec<f64>,
    /// Per output: measured, start model, identified model (perturbations).
    #[serde(skip)]
    pub traces: Vec<[Vec<f64>; 3]>,
}

/// The estimate columns, in state order from `phi` (rows 3–11).
const ESTIMATE_NAMES: [&str; 9] = [
    "est_phi",
    "est_theta",
    "est_psi",
    "est_u",
    "est_v",
    "est_w",
    "est_p",
    "est_q",
    "est_r",
];
/// The wind columns, NED.
const WIND_NAMES: [&str; 3] = ["wind_n", "wind_e", "wind_d"];

/// What drives one replay: the logged commands (absolute), the logged start
/// state (30 or 9 values by `start`) and the wind per step.
struct Drive<'a> {
    start: InitialState,
    s: &'a [[f64; 4]],
    x0_logged: &'a [f64],
    wind: &'a [Vector3<f64>],
    dt: f64,
}

/// Fly `params` open loop from the start `d.start` chooses; returns the
/// perturbation from its first sample of each state row in `rows`.
fn replay(
    params: &Params,
    cfg: &IdentConfig,
    v: &Verification,
    d: &Drive<'_>,
    rows: &[usize],
) -> Result<Vec<Vec<f64>>> {
    let op = cfg
        .operating_points
        .iter()
        .find(|o| o.name == v.operating_point)
        .ok_or_else(|| ParamIdError::Fit(format!("no operating point `{}`", v.operating_point)))?;
    let model = Model::new(*params, cfg.preset.options());
    // trim only where it is used (a logged start needs none)
    let trim = match d.start {
        InitialState::Logged => None,
        InitialState::Estimate | InitialState::Trim => Some(
            linear_model(
                params,
                cfg.preset,
                &target(op.velocity_ned_m_s, op.yaw_rad),
                &op.name,
            )?
            .0,
        ),
    };
    let (mut x, u_offset): (State, Input) = match (&trim, d.start) {
        (Some(t), InitialState::Trim) => (expand(&t.x, [0.0; 3]), t.u - Input::from(d.s[0])),
        (Some(t), _) => {
            let mut x = expand(&t.x, [0.0; 3]);
            for (k, e) in d.x0_logged.iter().enumerate() {
                x[ix::PHI + k] = *e;
            }
            (x, Input::zeros())
        }
        (None, _) => (
            State::from_iterator(d.x0_logged.iter().copied()),
            Input::zeros(),
        ),
    };
    let x0 = x;
    let mut out = vec![Vec::with_capacity(d.s.len()); rows.len()];
    for (s, w) in d.s.iter().zip(d.wind) {
        for (o, &r) in out.iter_mut().zip(rows) {
            o.push(x[r + REDUCED_OFFSET] - x0[r + REDUCED_OFFSET]);
        }
        let u = u_offset + Input::from(*s);
        x = model
            .step(&x, &u, w, d.dt)
            .map_err(|e| ParamIdError::Model {
                point: op.name.clone(),
                reason: format!("verification replay of {}: {e}", v.log.display()),
            })?
            .0;
        if !x.iter().all(|v| v.is_finite()) {
            return Err(ParamIdError::Model {
                point: op.name.clone(),
                reason: format!("verification replay of {} diverged", v.log.display()),
            });
        }
    }
    Ok(out)
}

/// The start and wind of verification `v`: as configured, else the best the
/// log's header offers.
/// A start or wind configured that the log cannot give (a flight log has
/// neither the true state nor the wind) is refused naming the field.
fn choose(cfg: &IdentConfig, index: usize) -> Result<(InitialState, WindSource)> {
    let v = &cfg.verification[index];
    let header = crate::source::log_names(&v.log).map_err(|source| ParamIdError::LogOf {
        file: cfg.file.clone(),
        field: format!("verification[{index}].log"),
        source: Box::new(source),
    })?;
    let has = |names: &[&str]| names.iter().all(|n| header.iter().any(|c| c == n));
    let start = v.initial_state.unwrap_or(if has(&STATE_NAMES) {
        InitialState::Logged
    } else if has(&ESTIMATE_NAMES) {
        InitialState::Estimate
    } else {
        InitialState::Trim
    });
    let wind = v.wind.unwrap_or(if has(&WIND_NAMES) {
        WindSource::Logged
    } else {
        WindSource::Still
    });
    let needs = |field: &str, value: &str, names: &[&str]| -> Result<()> {
        let missing: Vec<&str> = names
            .iter()
            .filter(|n| !header.iter().any(|c| c == *n))
            .copied()
            .collect();
        if missing.is_empty() {
            return Ok(());
        }
        Err(ConfigError::Invalid {
            file: cfg.file.clone(),
            field: format!("verification[{index}].{field}"),
            value: format!("\"{value}\""),
            rule: format!(
                "{} has no column {} (a flight log has neither the true state nor the wind: use \"estimate\" and \"still\")",
                v.log.display(),
                missing.join(", ")
            ),
        }
        .into())
    };
    match start {
        InitialState::Logged => needs("initial_state", "logged", &STATE_NAMES)?,
        InitialState::Estimate => needs("initial_state", "estimate", &ESTIMATE_NAMES)?,
        InitialState::Trim => {}
    }
    if wind == WindSource::Logged {
        needs("wind", "logged", &WIND_NAMES)?;
    }
    Ok((start, wind))
}

/// Verify the start and the identified parameters on verification `index`.
pub fn verify(
    cfg: &IdentConfig,
    index: usize,
    start: &Params,
    identified: &Params,
) -> Result<VerificationResult> {
    let v = &cfg.verification[index];
    let (initial_state, wind) = choose(cfg, index)?;
    let mut names: Vec<&str> = INPUT_NAMES.to_vec();
    names.extend(v.outputs.iter().map(String::as_str));
    let n_fixed = names.len();
    match initial_state {
        InitialState::Logged => names.extend(STATE_NAMES),
        InitialState::Estimate => names.extend(ESTIMATE_NAMES),
        InitialState::Trim => {}
    }
    let n_state = names.len() - n_fixed;
    if wind == WindSource::Logged {
        names.extend(WIND_NAMES);
    }
    let rec = read_record(
        &v.log,
        &names,
        v.t_start_s,
        v.t_end_s,
        cfg.start.control.sample_time_s,
        &cfg.file,
        &format!("verification[{index}].log"),
    )?;
    let n = rec.t_s.len();
    let s: Vec<[f64; 4]> = (0..n)
        .map(|k| std::array::from_fn(|i| rec.columns[i][k]))
        .collect();
    let x0_logged: Vec<f64> = (0..n_state).map(|i| rec.columns[n_fixed + i][0]).collect();
    let wind_ned: Vec<Vector3<f64>> = (0..n)
        .map(|k| match wind {
            WindSource::Logged => Vector3::from_fn(|i, _| rec.columns[n_fixed + n_state + i][k]),
            WindSource::Still => Vector3::zeros(),
        })
        .collect();
    let rows: Vec<usize> = v
        .outputs
        .iter()
        .map(|o| {
            Response {
                input: String::new(),
                output: o.clone(),
                omega_min_rad_s: 1.0,
                omega_max_rad_s: 2.0,
            }
            .state_index()
            .unwrap_or(0)
        })
        .collect();
    let drive = Drive {
        start: initial_state,
        s: &s,
        x0_logged: &x0_logged,
        wind: &wind_ned,
        dt: rec.dt_s,
    };
    let ys = replay(start, cfg, v, &drive, &rows)?;
    let yi = replay(identified, cfg, v, &drive, &rows)?;
    let mut outputs = Vec::new();
    let mut traces = Vec::new();
    for (j, o) in v.outputs.iter().enumerate() {
        let c = &rec.columns[4 + j];
        let meas: Vec<f64> = c.iter().map(|y| y - c[0]).collect();
        let th = |sim: &[f64]| {
            helicon_ident::fit::theil(&meas, sim).map_err(|e| ParamIdError::Frf {
                file: v.log.display().to_string(),
                what: format!("verification of {o}"),
                source: Box::new(e),
            })
        };
        outputs.push(VerifiedOutput {
            output: o.clone(),
            theil_start: th(&ys[j])?,
            theil_identified: th(&yi[j])?,
        });
        traces.push([meas, ys[j].clone(), yi[j].clone()]);
    }
    Ok(VerificationResult {
        log: v.log.display().to_string(),
        operating_point: v.operating_point.clone(),
        initial_state,
        wind,
        outputs,
        t_s: rec.t_s.iter().map(|t| t - rec.t_s[0]).collect(),
        traces,
    })
}
