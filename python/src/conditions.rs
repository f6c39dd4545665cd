//! Trim and linearization at a flight condition, as `helicon trim --json`
//! and `helicon linearize` compute them: the same target, the same solver
//! options, the same validity report and the same refusals (with the same
//! messages) unless `allow_unphysical`.

use crate::error::{Error, Result};
use helicon_model::linearize::{EQUILIBRIUM_TOL, LinearModel, linearize};
use helicon_model::state::{INPUT_NAMES, REDUCED_STATE_NAMES};
use helicon_model::trim::{Allowed, Trim, TrimOptions, TrimTarget, Validity, Violation, trim};
use helicon_model::{InflowMode, Model};
use helicon_sim::scenario::{MAX_HEADING_RAD, MAX_SPEED_M_S};
use nalgebra::{DMatrix, Vector3};
use serde_json::{Map, Value, json};

/// A steady straight flight condition, checked as the CLI's flags are.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Condition {
    /// Inertial velocity NED (m/s).
    pub velocity_ned_m_s: [f64; 3],
    /// Heading ψ (rad).
    pub yaw_rad: f64,
    /// Air-mass velocity NED (m/s).
    pub wind_ned_m_s: [f64; 3],
}

impl Condition {
    /// The trim target, after the CLI's range checks (finite, |v| ≤ 100 m/s,
    /// |ψ| ≤ 100 rad).
    pub fn target(&self) -> Result<TrimTarget> {
        for (what, v) in [
            ("velocity_ned", &self.velocity_ned_m_s),
            ("wind_ned", &self.wind_ned_m_s),
        ] {
            for (i, c) in v.iter().enumerate() {
                if !c.is_finite() {
                    return Err(Error::new(format!("{what}[{i}] = {c} is not finite")));
                }
                if c.abs() > MAX_SPEED_M_S {
                    return Err(Error::new(format!(
                        "{what}[{i}] = {c} m/s is beyond +-100 m/s (a miniature helicopter flies far inside)"
                    )));
                }
            }
        }
        if !(self.yaw_rad.is_finite() && self.yaw_rad.abs() <= MAX_HEADING_RAD) {
            return Err(Error::new(format!(
                "yaw = {} rad must be finite and within +-100 rad",
                self.yaw_rad
            )));
        }
        Ok(TrimTarget {
            velocity_ned_m_s: Vector3::from(self.velocity_ned_m_s),
            yaw_rad: self.yaw_rad,
            wind_ned_m_s: Vector3::from(self.wind_ned_m_s),
        })
    }
}

/// Trim `model` at `cond` with the default solver options (the CLI's).
pub fn trim_at(model: &Model, cond: &Condition) -> Result<Trim> {
    Ok(trim(model, &cond.target()?, &TrimOptions::default())?)
}

fn violation_json(v: &Violation) -> Value {
    let (kind, min, max) = match v.allowed {
        Allowed::Within { min, max } => ("within", min, max),
        Allowed::Outside { min, max } => ("outside", min, max),
    };
    json!({
        "quantity": v.quantity,
        "value": v.value,
        "allowed": {"kind": kind, "min": min, "max": max},
        "reason": v.reason,
    })
}

/// The validity report: `{"physical": bool, "violations": [...]}`.
pub fn validity_json(v: &Validity) -> Value {
    json!({
        "physical": v.is_physical(),
        "violations": v.violations.iter().map(violation_json).collect::<Vec<_>>(),
    })
}

/// The trim as `helicon trim --json` prints it: `"state"` (27 by name),
/// `"input"` (4 by name), `lambda_mr`, `lambda_tr`, `residual_norm`,
/// `iterations`, the target, `beyond_saturation` and `"validity"`.
pub fn trim_json(t: &Trim, model: &Model) -> Value {
    let mut state = Map::new();
    for (i, n) in REDUCED_STATE_NAMES.iter().enumerate() {
        state.insert((*n).to_string(), json!(t.x[i]));
    }
    let mut input = Map::new();
    for (i, n) in INPUT_NAMES.iter().enumerate() {
        input.insert((*n).to_string(), json!(t.u[i]));
    }
    let v = t.target.velocity_ned_m_s;
    let w = t.target.wind_ned_m_s;
    json!({
        "state": state,
        "input": input,
        "lambda_mr": t.aux.lambda_mr,
        "lambda_tr": t.aux.lambda_tr,
        "residual_norm": t.residual_norm,
        "iterations": t.iterations,
        "velocity_ned_m_s": [v.x, v.y, v.z],
        "yaw_rad": t.target.yaw_rad,
        "wind_ned_m_s": [w.x, w.y, w.z],
        "beyond_saturation": t.beyond_saturation.iter().map(|v| v.input).collect::<Vec<_>>(),
        "validity": validity_json(&t.validity(model)),
    })
}

/// A linearization: the continuous (A, B) of `A.csv`/`B.csv` (27 × 27,
/// 27 × 4, row-major), the ZOH (Φ, Γ) when a sample time was given, and
/// the trim it was taken at.
#[derive(Debug, Clone)]
pub struct Linearization {
    /// A (27 × 27).
    pub a: DMatrix<f64>,
    /// B (27 × 4).
    pub b: DMatrix<f64>,
    /// (Φ, Γ) at the sample time.
    pub discrete: Option<(DMatrix<f64>, DMatrix<f64>)>,
    /// The trim.
    pub trim: Trim,
    /// The linear model (affine residual, poles).
    pub model: LinearModel,
}

/// `helicon linearize`: trim at `cond`, refuse an unphysical trim or a
/// non-equilibrium operating point unless `allow_unphysical` (the CLI's
/// `--allow-unphysical`), linearize with converged or thesis-emulated
/// inflow, and discretize at `dt_s` when given (finite, > 0).
pub fn linearize_at(
    model: &Model,
    cond: &Condition,
    thesis_inflow: bool,
    dt_s: Option<f64>,
    allow_unphysical: bool,
) -> Result<Linearization> {
    if let Some(dt) = dt_s
        && !(dt.is_finite() && dt > 0.0)
    {
        return Err(Error::new(format!("dt = {dt} must be finite and > 0 s")));
    }
    let t = trim_at(model, cond)?;
    let validity = t.validity(model);
    if !validity.is_physical() && !allow_unphysical {
        let list: Vec<String> = validity.violations.iter().map(|v| v.to_string()).collect();
        return Err(Error::new(format!(
            "refusing to linearize: the trim is not physical ({} violation(s): {}); allow_unphysical=True linearizes anyway",
            validity.violations.len(),
            list.join("; ")
        )));
    }
    let inflow = if thesis_inflow {
        InflowMode::ThesisIteration {
            lambda_mr_in: t.aux.lambda_mr,
            lambda_tr_in: t.aux.lambda_tr,
            iterations: 7,
        }
    } else {
        InflowMode::Converged
    };
    let lm = linearize(model, &t.x, &t.u, &Vector3::from(cond.wind_ned_m_s), inflow)?;
    if !lm.is_equilibrium() && !allow_unphysical {
        let (name, value) = lm.worst_residual();
        return Err(Error::new(format!(
            "refusing to linearize: the operating point is not an equilibrium: affine residual |xdot0|_inf = {:.3e} (d{name}/dt = {value:.3e}) > {EQUILIBRIUM_TOL:e}; allow_unphysical=True linearizes anyway",
            lm.xdot0.amax()
        )));
    }
    let discrete = match dt_s {
        Some(dt) => Some(lm.discretize(dt)?),
        None => None,
    };
    Ok(Linearization {
        a: lm.a_dyn(),
        b: lm.b_dyn(),
        discrete,
        trim: t,
        model: lm,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use helicon_model::Preset;

    fn hover() -> Condition {
        Condition {
            velocity_ned_m_s: [0.0; 3],
            yaw_rad: 0.0,
            wind_ned_m_s: [0.0; 3],
        }
    }

    #[test]
    fn hover_trim_is_physical_and_named() {
        let m = Model::bergen_twin(Preset::Physical);
        let t = trim_at(&m, &hover()).unwrap();
        let j = trim_json(&t, &m);
        assert_eq!(j["validity"]["physical"], json!(true));
        assert_eq!(j["state"].as_object().map(Map::len), Some(27));
        assert!(j["input"]["S_col"].as_f64().is_some());
    }

    #[test]
    fn out_of_range_conditions_are_refused() {
        let mut c = hover();
        c.velocity_ned_m_s[0] = 150.0;
        assert!(c.target().unwrap_err().message().contains("100 m/s"));
        c.velocity_ned_m_s[0] = f64::NAN;
        assert!(c.target().unwrap_err().message().contains("not finite"));
        let mut c = hover();
        c.yaw_rad = f64::INFINITY;
        assert!(c.target().is_err());
        let m = Model::bergen_twin(Preset::Physical);
        let e = linearize_at(&m, &hover(), false, Some(0.0), false).unwrap_err();
        assert!(e.message().contains("dt = 0"), "{e}");
    }

    #[test]
    fn linearization_shapes() {
        let m = Model::bergen_twin(Preset::Physical);
        let l = linearize_at(&m, &hover(), false, Some(0.0025), false).unwrap();
        assert_eq!(l.a.shape(), (27, 27));
        assert_eq!(l.b.shape(), (27, 4));
        let (phi, gamma) = l.discrete.unwrap();
        assert_eq!((phi.shape(), gamma.shape()), ((27, 27), (27, 4)));
    }
}
