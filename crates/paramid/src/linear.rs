//! The model side: for candidate parameters, trim the nonlinear model at an
//! operating point, linearise it there (thesis (12.12)–(12.18)) and evaluate
//! its frequency responses.
//!
//! The responses are those of the sampled system, C(zI − Φ)⁻¹Γ with (Φ, Γ)
//! the zero-order-hold discretisation at the log's sample time (the control
//! period), z = e^{jωT}: the servo commands in the log are held over each
//! control period and the outputs are sampled at its start, so the measured
//! response of the linearised plant is exactly this one (the continuous
//! C(jωI − A)⁻¹B differs from it by the hold's half-sample delay and
//! sinc, 1.1° of phase at 15 rad/s at 400 Hz, which a noise-free fit
//! would have to absorb in the parameters).

use crate::error::{ParamIdError, Result};
use helicon_ident::Complex64;
use helicon_model::linearize::{LinearModel, linearize};
use helicon_model::trim::{Trim, TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Model, Params, Preset};
use nalgebra::{DMatrix, Vector3};

/// The trim target of an operating point (still air).
pub fn target(velocity_ned_m_s: [f64; 3], yaw_rad: f64) -> TrimTarget {
    TrimTarget {
        velocity_ned_m_s: Vector3::from(velocity_ned_m_s),
        yaw_rad,
        wind_ned_m_s: Vector3::zeros(),
    }
}

/// Trim and linearise `params` at `target` (converged inflow).
pub fn linear_model(
    params: &Params,
    preset: Preset,
    target: &TrimTarget,
    point: &str,
) -> Result<(Trim, LinearModel)> {
    let err = |reason: String| ParamIdError::Model {
        point: point.to_string(),
        reason,
    };
    params
        .validate("candidate parameters")
        .map_err(|e| err(e.to_string()))?;
    let model = Model::new(*params, preset.options());
    let t = trim(&model, target, &TrimOptions::default()).map_err(|e| err(e.to_string()))?;
    let lm = linearize(&model, &t.x, &t.u, &Vector3::zeros(), InflowMode::Converged)
        .map_err(|e| err(e.to_string()))?;
    Ok((t, lm))
}

/// The responses of a discretised model: for each ω of `omegas`, the 27×4
/// matrix (zI − Φ)⁻¹Γ, z = e^{jωT} (row = reduced state, column = servo).
pub fn sampled_responses(
    phi: &DMatrix<f64>,
    gamma: &DMatrix<f64>,
    ts_s: f64,
    omegas: &[f64],
) -> Option<Vec<DMatrix<Complex64>>> {
    let n = phi.nrows();
    let g = gamma.map(|v| Complex64::new(v, 0.0));
    omegas
        .iter()
        .map(|&w| {
            let z = Complex64::from_polar(1.0, w * ts_s);
            let m = DMatrix::from_fn(n, n, |i, j| {
                let d = if i == j { z } else { Complex64::new(0.0, 0.0) };
                d - Complex64::new(phi[(i, j)], 0.0)
            });
            let x = m.lu().solve(&g)?;
            x.iter()
                .all(|v| v.re.is_finite() && v.im.is_finite())
                .then_some(x)
        })
        .collect()
}

/// The model's responses at one operating point: for each `(input, state,
/// ω list)` of `wanted`, H(e^{jωT}) at those ω. Also returns the linear model.
pub fn point_responses(
    params: &Params,
    preset: Preset,
    target: &TrimTarget,
    point: &str,
    ts_s: f64,
    wanted: &[(usize, usize, &[f64])],
) -> Result<(Vec<Vec<Complex64>>, LinearModel)> {
    let (_, lm) = linear_model(params, preset, target, point)?;
    let (phi, gamma) = lm.discretize(ts_s).map_err(|e| ParamIdError::Model {
        point: point.to_string(),
        reason: e.to_string(),
    })?;
    let mut all: Vec<f64> = wanted.iter().flat_map(|w| w.2.iter().copied()).collect();
    all.sort_by(f64::total_cmp);
    all.dedup();
    let x = sampled_responses(&phi, &gamma, ts_s, &all).ok_or_else(|| ParamIdError::Model {
        point: point.to_string(),
        reason: "the linearised model has a pole on the unit circle at a fitted frequency".into(),
    })?;
    let out = wanted
        .iter()
        .map(|(input, state, om)| {
            om.iter()
                .map(|w| {
                    let k = all.partition_point(|v| v < w);
                    x[k.min(x.len() - 1)][(*state, *input)]
                })
                .collect()
        })
        .collect();
    Ok((out, lm))
}
