//! Trim at any steady straight flight condition, thesis (12.2)–(12.9),
//! extended from the thesis's hover to any earth-frame velocity and yaw.
//!
//! Unknowns: the 27 reduced states and the 4 inputs (31). Equations: f27 = 0
//! (27), R_eb·v_body = v_ned,ref (3) and ψ = ψ_ref (1). The inflow ratios are
//! solved inside f (converged), so they are not unknowns.
//!
//! Solver: Newton's method with a central-difference Jacobian and a
//! backtracking line search on the row-scaled residual ½‖D r‖² (D = inverse
//! row norms of the first Jacobian, so m/s², rad/s² and the large flapping
//! rows weigh alike). Newton's step itself does not depend on the scaling.
//! Converged when ‖r‖∞ < `tolerance` (SI units, default 1e-10).
//!
//! Input saturation is lifted while trimming (a saturated servo has no
//! sensitivity, which would make the Jacobian singular); the result lists the
//! inputs that lie beyond their limits, so a condition the helicopter cannot
//! hold is reported, never silently clipped.

use crate::linearize::reduced_derivative;
use crate::model::{Aux, Model, ModelError};
use crate::options::InflowMode;
use crate::state::{
    INPUT_NAMES, Input, NX_REDUCED, REDUCED_OFFSET, REDUCED_STATE_NAMES, ReducedState, expand, ix,
};
use nalgebra::{SMatrix, SVector, Vector3};

/// Number of trim unknowns and equations (27 states + 4 inputs).
pub const N_TRIM: usize = NX_REDUCED + 4;

/// Names of the trim equations: `d<state>/dt` for the 27 dynamic rows, then
/// the constraints `v_north`, `v_east`, `v_down`, `psi`.
pub fn equation_name(i: usize) -> String {
    if i < NX_REDUCED {
        format!("d{}/dt", REDUCED_STATE_NAMES[i])
    } else {
        ["v_north", "v_east", "v_down", "psi"][i - NX_REDUCED].to_string()
    }
}

/// A steady flight condition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrimTarget {
    /// Inertial velocity in NED (m/s).
    pub velocity_ned_m_s: Vector3<f64>,
    /// Heading ψ (rad).
    pub yaw_rad: f64,
    /// Air-mass velocity in NED (m/s); zero for still air.
    pub wind_ned_m_s: Vector3<f64>,
}

impl TrimTarget {
    /// Hover in still air at heading 0.
    pub fn hover() -> Self {
        TrimTarget {
            velocity_ned_m_s: Vector3::zeros(),
            yaw_rad: 0.0,
            wind_ned_m_s: Vector3::zeros(),
        }
    }
}

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrimOptions {
    /// Maximum Newton iterations.
    pub max_iterations: usize,
    /// Convergence threshold on ‖r‖∞ (SI units).
    pub tolerance: f64,
    /// Starting point; `None` for a cold start (level attitude, the target
    /// velocity in body axes, mid-range collectives).
    pub initial: Option<(ReducedState, Input)>,
}

impl Default for TrimOptions {
    fn default() -> Self {
        TrimOptions {
            max_iterations: 50,
            tolerance: 1e-10,
            initial: None,
        }
    }
}

/// An input that the trim needs beyond its saturation.
#[derive(Debug, Clone, PartialEq)]
pub struct InputViolation {
    /// Input name.
    pub input: &'static str,
    /// Trim value.
    pub value: f64,
    /// Lower limit.
    pub min: f64,
    /// Upper limit.
    pub max: f64,
}

/// A converged trim.
#[derive(Debug, Clone, PartialEq)]
pub struct Trim {
    /// Reduced state (27).
    pub x: ReducedState,
    /// Inputs.
    pub u: Input,
    /// Auxiliary outputs at the trim (inflow ratios, forces).
    pub aux: Aux,
    /// ‖r‖∞ of the 31 trim equations at the solution (SI units).
    pub residual_norm: f64,
    /// Newton iterations used.
    pub iterations: usize,
    /// ‖r‖∞ before each iteration and at the end.
    pub history: Vec<f64>,
    /// Inputs beyond their saturation limits (empty when flyable).
    pub beyond_saturation: Vec<InputViolation>,
    /// The target it was trimmed for.
    pub target: TrimTarget,
}

/// Trim failures.
#[derive(Debug, Clone, thiserror::Error)]
pub enum TrimError {
    /// Newton did not reach the tolerance.
    #[error(
        "trim did not converge after {iterations} iterations: residual {residual_norm:.3e}; largest remaining: {}",
        worst.iter().map(|(n, v)| format!("{n} = {v:.3e}")).collect::<Vec<_>>().join(", ")
    )]
    NoConvergence {
        /// Iterations used.
        iterations: usize,
        /// Final ‖r‖∞.
        residual_norm: f64,
        /// The equations with the largest remaining residuals.
        worst: Vec<(String, f64)>,
    },
    /// The Jacobian became singular.
    #[error("trim Jacobian singular at iteration {iteration} (residual {residual_norm:.3e})")]
    Singular {
        /// Iteration.
        iteration: usize,
        /// ‖r‖∞ at that point.
        residual_norm: f64,
    },
    /// The model could not be evaluated (non-finite values, gimbal lock).
    #[error("trim: model evaluation failed: {0}")]
    Model(#[from] ModelError),
    /// The target is not finite.
    #[error("trim target has a non-finite component")]
    BadTarget,
}

type Vec31 = SVector<f64, N_TRIM>;
type Mat31 = SMatrix<f64, N_TRIM, N_TRIM>;

fn pack(x: &ReducedState, u: &Input) -> Vec31 {
    Vec31::from_fn(|i, _| {
        if i < NX_REDUCED {
            x[i]
        } else {
            u[i - NX_REDUCED]
        }
    })
}

fn unpack(z: &Vec31) -> (ReducedState, Input) {
    (
        ReducedState::from_fn(|i, _| z[i]),
        Input::from_fn(|i, _| z[i + NX_REDUCED]),
    )
}

/// A copy of `model` with the input saturation lifted (for trimming only).
fn unbounded(model: &Model) -> Model {
    let mut p = *model.params();
    for s in &mut p.servos {
        s.s_min = -1e9;
        s.s_max = 1e9;
    }
    Model::new(p, *model.options())
}

fn residual(model: &Model, z: &Vec31, target: &TrimTarget) -> Result<Vec31, ModelError> {
    let (x, u) = unpack(z);
    let f = reduced_derivative(model, &x, &u, &target.wind_ned_m_s, InflowMode::Converged)?;
    let (phi, theta, psi) = (x[0], x[1], x[2]);
    let o = REDUCED_OFFSET;
    let v = Vector3::new(x[ix::U - o], x[ix::V - o], x[ix::W - o]);
    let v_ned = crate::frames::ned_from_body(phi, theta, psi) * v;
    let mut r = Vec31::zeros();
    for i in 0..NX_REDUCED {
        r[i] = f[i];
    }
    for i in 0..3 {
        r[NX_REDUCED + i] = v_ned[i] - target.velocity_ned_m_s[i];
    }
    r[NX_REDUCED + 3] = psi - target.yaw_rad;
    Ok(r)
}

fn jacobian(model: &Model, z: &Vec31, target: &TrimTarget) -> Result<Mat31, ModelError> {
    let mut j = Mat31::zeros();
    for k in 0..N_TRIM {
        let h = 1e-6 * z[k].abs().max(1.0);
        let mut zp = *z;
        zp[k] += h;
        let mut zm = *z;
        zm[k] -= h;
        let col = (residual(model, &zp, target)? - residual(model, &zm, target)?) / (2.0 * h);
        j.set_column(k, &col);
    }
    Ok(j)
}

/// A cold-start guess: level attitude at the target heading, the target
/// velocity in body axes, collectives at a typical hover setting.
pub fn cold_start(model: &Model, target: &TrimTarget) -> (ReducedState, Input) {
    let o = REDUCED_OFFSET;
    let mut x = ReducedState::zeros();
    x[ix::PSI - o] = target.yaw_rad;
    let v_body = crate::frames::body_from_ned(0.0, 0.0, target.yaw_rad) * target.velocity_ned_m_s;
    x[ix::U - o] = v_body.x;
    x[ix::V - o] = v_body.y;
    x[ix::W - o] = v_body.z;
    let s = &model.params().servos;
    let mid = |k: usize| 0.5 * (s[k].s_min + s[k].s_max);
    let u = Input::new(mid(0), 0.0, 0.0, mid(3));
    for (k, i) in [ix::THETA0, ix::A1_SWASH, ix::B1_SWASH, ix::THETA_TR]
        .iter()
        .enumerate()
    {
        x[i - o] = s[k].gain_rad * u[k];
    }
    (x, u)
}

/// Trim `model` at `target`.
pub fn trim(model: &Model, target: &TrimTarget, options: &TrimOptions) -> Result<Trim, TrimError> {
    if !(target.velocity_ned_m_s.iter().all(|v| v.is_finite())
        && target.yaw_rad.is_finite()
        && target.wind_ned_m_s.iter().all(|v| v.is_finite()))
    {
        return Err(TrimError::BadTarget);
    }
    let m = unbounded(model);
    let (x0, u0) = options.initial.unwrap_or_else(|| cold_start(model, target));
    let mut z = pack(&x0, &u0);
    let mut r = residual(&m, &z, target)?;
    let mut history = vec![r.amax()];
    let mut scale: Option<Vec31> = None;
    let mut iterations = 0;
    while r.amax() >= options.tolerance && iterations < options.max_iterations {
        iterations += 1;
        let j = jacobian(&m, &z, target)?;
        let d = *scale.get_or_insert_with(|| {
            Vec31::from_fn(|i, _| {
                let n = j.row(i).norm();
                if n > 0.0 { 1.0 / n } else { 1.0 }
            })
        });
        let step = j.lu().solve(&(-r)).ok_or(TrimError::Singular {
            iteration: iterations,
            residual_norm: r.amax(),
        })?;
        if !step.iter().all(|v| v.is_finite()) {
            return Err(TrimError::Singular {
                iteration: iterations,
                residual_norm: r.amax(),
            });
        }
        let merit = |r: &Vec31| r.component_mul(&d).norm_squared();
        let m0 = merit(&r);
        let mut t = 1.0;
        loop {
            let zt = z + step * t;
            match residual(&m, &zt, target) {
                Ok(rt) if merit(&rt) <= (1.0 - 1e-4 * t) * m0 || t < 1e-3 => {
                    z = zt;
                    r = rt;
                    break;
                }
                Ok(_) | Err(ModelError::GimbalLock { .. }) if t >= 1e-3 => t *= 0.5,
                Ok(rt) => {
                    z = zt;
                    r = rt;
                    break;
                }
                Err(e) => return Err(e.into()),
            }
        }
        history.push(r.amax());
    }
    let residual_norm = r.amax();
    if residual_norm >= options.tolerance || !residual_norm.is_finite() {
        let mut worst: Vec<(String, f64)> = (0..N_TRIM).map(|i| (equation_name(i), r[i])).collect();
        worst.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        worst.truncate(4);
        return Err(TrimError::NoConvergence {
            iterations,
            residual_norm,
            worst,
        });
    }
    let (x, u) = unpack(&z);
    let (_, aux) = model.derivative(&expand(&x, [0.0; 3]), &u, &target.wind_ned_m_s)?;
    let beyond_saturation = model
        .params()
        .servos
        .iter()
        .enumerate()
        .filter(|(k, s)| u[*k] < s.s_min || u[*k] > s.s_max)
        .map(|(k, s)| InputViolation {
            input: INPUT_NAMES[k],
            value: u[k],
            min: s.s_min,
            max: s.s_max,
        })
        .collect();
    Ok(Trim {
        x,
        u,
        aux,
        residual_norm,
        iterations,
        history,
        beyond_saturation,
        target: *target,
    })
}

/// Trims along a path of targets with continuation: each trim starts from the
/// previous one. Returns one result per target (a failure does not stop the
/// sweep; the next point restarts from the last success).
pub fn sweep(
    model: &Model,
    targets: &[TrimTarget],
    options: &TrimOptions,
) -> Vec<Result<Trim, TrimError>> {
    let mut out = Vec::with_capacity(targets.len());
    let mut last: Option<(ReducedState, Input)> = options.initial;
    for t in targets {
        let mut o = *options;
        o.initial = last;
        let r = trim(model, t, &o).or_else(|_| {
            // fall back to a cold start once
            o.initial = None;
            trim(model, t, &o)
        });
        if let Ok(tr) = &r {
            last = Some((tr.x, tr.u));
        }
        out.push(r);
    }
    out
}
