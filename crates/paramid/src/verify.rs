//! Time-domain verification: the identified nonlinear model flown on the
//! servo commands of a flight that was not used in the fit (doublets), as
//! flight-test practice checks a frequency-domain model.
//!
//! The model starts at its own trim at the verification's operating point
//! and is driven open loop by u(t) = u_trim + (S(t) − S(t0)), the logged
//! servo commands as perturbations from their first sample (RK4 at the
//! log's step, commands held over each step, still air). Each output is
//! compared as a perturbation from its first sample with Theil's inequality
//! coefficient (`helicon_ident::fit::theil`): 0 for a perfect match, below
//! ~0.25–0.3 good. The log's turbulence and the helicopter's state at t0
//! are not known to the model, so the window should be short (a few
//! seconds around a doublet): an unstable helicopter flown open loop drifts
//! away from any log given time.

use crate::config::{IdentConfig, Response, Verification};
use crate::data::read_record;
use crate::error::{ParamIdError, Result};
use crate::linear::{linear_model, target};
use helicon_model::state::{REDUCED_OFFSET, expand};
use helicon_model::{INPUT_NAMES, Input, Model, Params};
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
    /// Per output.
    pub outputs: Vec<VerifiedOutput>,
    /// Time, s (from the window's start).
    #[serde(skip)]
    pub t_s: Vec<f64>,
    /// Per output: measured, start model, identified model (perturbations).
    #[serde(skip)]
    pub traces: Vec<[Vec<f64>; 3]>,
}

/// Fly `params` open loop on `u` (perturbations added to its trim at the
/// point); returns the perturbation of each state row in `rows`.
fn replay(
    params: &Params,
    cfg: &IdentConfig,
    v: &Verification,
    du: &[[f64; 4]],
    dt: f64,
    rows: &[usize],
) -> Result<Vec<Vec<f64>>> {
    let op = cfg
        .operating_points
        .iter()
        .find(|o| o.name == v.operating_point)
        .ok_or_else(|| ParamIdError::Fit(format!("no operating point `{}`", v.operating_point)))?;
    let (t, _) = linear_model(
        params,
        cfg.preset,
        &target(op.velocity_ned_m_s, op.yaw_rad),
        &op.name,
    )?;
    let model = Model::new(*params, cfg.preset.options());
    let mut x = expand(&t.x, [0.0; 3]);
    let mut out = vec![Vec::with_capacity(du.len()); rows.len()];
    for d in du {
        for (o, &r) in out.iter_mut().zip(rows) {
            o.push(x[r + REDUCED_OFFSET] - t.x[r]);
        }
        let u = t.u + Input::from(*d);
        x = model
            .step(&x, &u, &Vector3::zeros(), dt)
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

/// Verify the start and the identified parameters on verification `index`.
pub fn verify(
    cfg: &IdentConfig,
    index: usize,
    start: &Params,
    identified: &Params,
) -> Result<VerificationResult> {
    let v = &cfg.verification[index];
    let mut names: Vec<&str> = INPUT_NAMES.to_vec();
    names.extend(v.outputs.iter().map(String::as_str));
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
    let du: Vec<[f64; 4]> = (0..n)
        .map(|k| std::array::from_fn(|i| rec.columns[i][k] - rec.columns[i][0]))
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
    let ys = replay(start, cfg, v, &du, rec.dt_s, &rows)?;
    let yi = replay(identified, cfg, v, &du, rec.dt_s, &rows)?;
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
        outputs,
        t_s: rec.t_s.iter().map(|t| t - rec.t_s[0]).collect(),
        traces,
    })
}
