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
//!
//! A converged trim is a solution of the model's equations, not necessarily a
//! state the helicopter (or the model's assumptions) can be in:
//! [`Trim::validity`] checks it against the physical ranges of [`LIMITS`] and
//! the servo ranges of the parameters, and [`Trim::require_physical`] turns a
//! violation into [`TrimError::Unphysical`]. [`discontinuities`] finds jumps
//! between neighbouring points of a [`sweep`] (a change of solution branch).

use crate::linearize::reduced_derivative;
use crate::model::{Aux, Model, ModelError, check_output};
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
    /// With the landing gear on, the trim point (the NED origin) is on or
    /// under the ground: a trim is a flight condition.
    #[error(
        "{field} = {ground_down_m} m puts the ground {height_m} m below the trim point (the NED \
         origin), at or above the skids' contact ({contact_m} m below the CM, \
         landing_gear.contact_z_m): a trim is a flight condition; put the ground more than \
         {contact_m} m below the origin"
    )]
    OnGround {
        /// The parameter that places the ground.
        field: &'static str,
        /// Its value (m).
        ground_down_m: f64,
        /// The trim point's height above the ground along its normal (m).
        height_m: f64,
        /// The skids' depth below the CM (m).
        contact_m: f64,
    },
    /// The trim converged but is outside the physical ranges of the model
    /// ([`Trim::validity`]).
    #[error(
        "trim is not physical: {}",
        violations.iter().map(ToString::to_string).collect::<Vec<_>>().join("; ")
    )]
    Unphysical {
        /// Every quantity out of range.
        violations: Vec<Violation>,
    },
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
    // A NaN would be ignored by the ∞-norm (`amax`) and could pass as converged.
    if let Some(i) = f.iter().position(|v| !v.is_finite()) {
        return Err(ModelError::NonFiniteOutput {
            what: "derivative of",
            name: REDUCED_STATE_NAMES[i],
            value: f[i],
        });
    }
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
    let gear = &model.params().landing_gear;
    if gear.is_enabled() {
        let height_m = model.ground_plane().height_m(&Vector3::zeros());
        if height_m <= gear.contact_z_m {
            return Err(TrimError::OnGround {
                field: "landing_gear.ground_down_m",
                ground_down_m: gear.ground_down_m,
                height_m,
                contact_m: gear.contact_z_m,
            });
        }
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
                Ok(_)
                | Err(
                    ModelError::GimbalLock { .. }
                    | ModelError::NonFinite { .. }
                    | ModelError::NonFiniteOutput { .. },
                ) if t >= 1e-3 => t *= 0.5,
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
    let (xdot, aux) = model.derivative(&expand(&x, [0.0; 3]), &u, &target.wind_ned_m_s)?;
    check_output(&xdot, &aux)?;
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

/// How a value must relate to its range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Allowed {
    /// min ≤ value ≤ max.
    Within {
        /// Lower limit.
        min: f64,
        /// Upper limit.
        max: f64,
    },
    /// value ≤ min or value ≥ max (the open interval between is excluded).
    Outside {
        /// Upper end of the lower allowed part.
        min: f64,
        /// Lower end of the upper allowed part.
        max: f64,
    },
}

impl Allowed {
    /// Whether `value` is allowed (NaN never is).
    pub fn admits(self, value: f64) -> bool {
        match self {
            Allowed::Within { min, max } => min <= value && value <= max,
            Allowed::Outside { min, max } => value <= min || value >= max,
        }
    }
}

impl std::fmt::Display for Allowed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Allowed::Within { min, max } => write!(f, "[{min}, {max}]"),
            Allowed::Outside { min, max } => write!(f, "<= {min} or >= {max}"),
        }
    }
}

/// One quantity of a trim outside its physical range.
#[derive(Debug, Clone, PartialEq)]
pub struct Violation {
    /// Quantity name: an input (`S_col`), a state (`a1sb`) or a derived
    /// quantity of [`LIMITS`] (`alpha75_mr`).
    pub quantity: &'static str,
    /// The value at the trim.
    pub value: f64,
    /// Its allowed range.
    pub allowed: Allowed,
    /// What the quantity is and why the range.
    pub reason: &'static str,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} = {:.4} not {} ({})",
            self.quantity, self.value, self.allowed, self.reason
        )
    }
}

/// The physical-validity report of a trim: empty when every quantity is in
/// range.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Validity {
    /// The quantities out of range, inputs first, then [`LIMITS`] order.
    pub violations: Vec<Violation>,
}

impl Validity {
    /// No violations.
    pub fn is_physical(&self) -> bool {
        self.violations.is_empty()
    }
}

/// A physical limit of a trim quantity (besides the servo ranges, which come
/// from the parameters).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limit {
    /// Quantity name.
    pub quantity: &'static str,
    /// Allowed range.
    pub allowed: Allowed,
    /// Definition and justification.
    pub reason: &'static str,
}

/// Largest blade angle of attack (rad): 12°. The blade-element lift is
/// linear, Cls·α, with no stall (7.7); static stall of the symmetric sections
/// of rotor blades at rotor Reynolds numbers (1e5–1e6) is 10°–15°.
pub const ALPHA_MAX_RAD: f64 = 0.21;
/// Largest flapping angle (rad): the flapping equations use sin β ≈ β and
/// cos β ≈ 1 ((6.42)–(6.46)); at 0.2 rad the cosine is off by 2 %.
pub const FLAP_MAX_RAD: f64 = 0.2;
/// Largest in-plane advance ratio: the blade-element integrals (6.14)–(6.21)
/// assume the air reaches every blade section from the leading edge; on the
/// retreating side the reverse-flow region reaches r = μR, 30 % of the
/// radius at μ = 0.3.
pub const MU_MAX: f64 = 0.3;
/// The descent ratio d = (descent speed along the shaft) / (induced
/// velocity) outside the momentum theory's valid states: for 0 < d < 2 the
/// air meets the disc against the induced flow but the far wake still flows
/// with it, so there is no single streamtube and (7.33)/(7.56) do not hold
/// (turbulent-wake and vortex-ring states; d ≥ 2 is the windmill-brake
/// state, d ≤ 0 the normal working state). Descents slower than a quarter of
/// the induced velocity are accepted as near-hover (our tolerance, not a
/// published boundary), and the check applies only while the edgewise speed
/// is below the induced velocity (faster edgewise flight sweeps the wake
/// away from the disc).
pub const VRS_DESCENT_RATIO: (f64, f64) = (0.25, 2.0);

/// The physical limits checked by [`Trim::validity`], with their reasons.
pub const LIMITS: [Limit; 11] = [
    Limit {
        quantity: "alpha75_mr",
        allowed: Allowed::Within {
            min: -ALPHA_MAX_RAD,
            max: ALPHA_MAX_RAD,
        },
        reason: "main-rotor blade angle of attack at 0.75 R, theta0 + twist - K1 a0 + lambda_mr/0.75 (rad); linear lift, stall near 12 deg",
    },
    Limit {
        quantity: "alpha75_tr",
        allowed: Allowed::Within {
            min: -ALPHA_MAX_RAD,
            max: ALPHA_MAX_RAD,
        },
        reason: "tail-rotor blade angle of attack at 0.75 R, theta_tr + lambda_tr/0.75 (rad); linear lift, stall near 12 deg",
    },
    Limit {
        quantity: "a0",
        allowed: Allowed::Within {
            min: -FLAP_MAX_RAD,
            max: FLAP_MAX_RAD,
        },
        reason: "main-rotor coning (rad); small-angle flapping model",
    },
    Limit {
        quantity: "a1",
        allowed: Allowed::Within {
            min: -FLAP_MAX_RAD,
            max: FLAP_MAX_RAD,
        },
        reason: "main-rotor longitudinal flapping (rad); small-angle flapping model",
    },
    Limit {
        quantity: "b1",
        allowed: Allowed::Within {
            min: -FLAP_MAX_RAD,
            max: FLAP_MAX_RAD,
        },
        reason: "main-rotor lateral flapping (rad); small-angle flapping model",
    },
    Limit {
        quantity: "a1sb",
        allowed: Allowed::Within {
            min: -FLAP_MAX_RAD,
            max: FLAP_MAX_RAD,
        },
        reason: "stabilizer-bar longitudinal flapping (rad); small-angle flapping model",
    },
    Limit {
        quantity: "b1sb",
        allowed: Allowed::Within {
            min: -FLAP_MAX_RAD,
            max: FLAP_MAX_RAD,
        },
        reason: "stabilizer-bar lateral flapping (rad); small-angle flapping model",
    },
    Limit {
        quantity: "mu_mr",
        allowed: Allowed::Within {
            min: 0.0,
            max: MU_MAX,
        },
        reason: "main-rotor in-plane advance ratio; reverse flow not modelled",
    },
    Limit {
        quantity: "mu_tr",
        allowed: Allowed::Within {
            min: 0.0,
            max: MU_MAX,
        },
        reason: "tail-rotor in-plane advance ratio; reverse flow not modelled",
    },
    Limit {
        quantity: "descent_ratio_mr",
        allowed: Allowed::Outside {
            min: VRS_DESCENT_RATIO.0,
            max: VRS_DESCENT_RATIO.1,
        },
        reason: "main-rotor descent along the shaft / induced velocity with edgewise speed below it: vortex-ring/turbulent-wake state, momentum theory (7.33) invalid",
    },
    Limit {
        quantity: "descent_ratio_tr",
        allowed: Allowed::Outside {
            min: VRS_DESCENT_RATIO.0,
            max: VRS_DESCENT_RATIO.1,
        },
        reason: "tail-rotor flow against its thrust / induced velocity with edgewise speed below it: vortex-ring/turbulent-wake state, momentum theory (7.56) invalid",
    },
];

/// The descent ratio d of [`VRS_DESCENT_RATIO`] for one rotor, or `None`
/// when the check does not apply (no induced flow, or edgewise speed at or
/// above the induced velocity). Inflow ratios in the convention of
/// [`crate::inflow`]: λ = μ_axial − ν, the induced ratio ν positive along
/// the induced flow for positive thrust; a rotor with reversed thrust is
/// mirrored.
fn descent_ratio(mu_axial: f64, mu_inplane: f64, lambda: f64) -> Option<f64> {
    let nu = mu_axial - lambda;
    if nu == 0.0 || mu_inplane >= nu.abs() {
        return None;
    }
    Some(mu_axial * nu.signum() / nu.abs())
}

impl Trim {
    /// The physical-validity report: every servo command within
    /// [S_min, S_max] of the model's parameters, and every quantity of
    /// [`LIMITS`] within its range.
    pub fn validity(&self, model: &Model) -> Validity {
        let p = model.params();
        let mr = &p.main_rotor;
        let o = REDUCED_OFFSET;
        let mut violations: Vec<Violation> = p
            .servos
            .iter()
            .enumerate()
            .filter_map(|(k, s)| {
                let allowed = Allowed::Within {
                    min: s.s_min,
                    max: s.s_max,
                };
                (!allowed.admits(self.u[k])).then_some(Violation {
                    quantity: INPUT_NAMES[k],
                    value: self.u[k],
                    allowed,
                    reason: "servo command range S_min..S_max of the parameters",
                })
            })
            .collect();
        let a = &self.aux;
        let r75_from_hinge = 0.75 * mr.radius_m - mr.hinge_offset_m;
        let theta75 = self.x[ix::THETA0 - o] + mr.twist_rad / mr.radius_m * r75_from_hinge
            - mr.pitch_flap_coupling * self.x[ix::A0 - o];
        let mu_mr = a.mu_mr.x.hypot(a.mu_mr.y);
        let mu_tr = a.mu_tr.x.hypot(a.mu_tr.z);
        let values = [
            Some(theta75 + a.lambda_mr / 0.75),
            Some(self.x[ix::THETA_TR - o] + a.lambda_tr / 0.75),
            Some(self.x[ix::A0 - o]),
            Some(self.x[ix::A1 - o]),
            Some(self.x[ix::B1 - o]),
            Some(self.x[ix::A1SB - o]),
            Some(self.x[ix::B1SB - o]),
            Some(mu_mr),
            Some(mu_tr),
            descent_ratio(a.mu_mr.z, mu_mr, a.lambda_mr),
            descent_ratio(a.mu_tr.y, mu_tr, a.lambda_tr),
        ];
        for (limit, value) in LIMITS.iter().zip(values) {
            if let Some(v) = value {
                if !limit.allowed.admits(v) {
                    violations.push(Violation {
                        quantity: limit.quantity,
                        value: v,
                        allowed: limit.allowed,
                        reason: limit.reason,
                    });
                }
            }
        }
        Validity { violations }
    }

    /// `Ok(self)` when [`Trim::validity`] finds nothing, otherwise
    /// [`TrimError::Unphysical`] listing the violations: for callers that
    /// need an equilibrium the helicopter can hold.
    pub fn require_physical(self, model: &Model) -> Result<Trim, TrimError> {
        let v = self.validity(model);
        if v.is_physical() {
            Ok(self)
        } else {
            Err(TrimError::Unphysical {
                violations: v.violations,
            })
        }
    }

    /// The quantities compared by [`discontinuities`], named by
    /// [`TRIM_QUANTITY_NAMES`]: the 4 inputs, the 27 states, λmr and λtr.
    pub fn quantities(&self) -> [f64; N_TRIM_QUANTITIES] {
        let mut q = [0.0; N_TRIM_QUANTITIES];
        for (i, v) in self.u.iter().chain(self.x.iter()).enumerate() {
            q[i] = *v;
        }
        q[N_TRIM] = self.aux.lambda_mr;
        q[N_TRIM + 1] = self.aux.lambda_tr;
        q
    }
}

/// Number of trim quantities compared between sweep points.
pub const N_TRIM_QUANTITIES: usize = N_TRIM + 2;

/// Names of [`Trim::quantities`].
pub const TRIM_QUANTITY_NAMES: [&str; N_TRIM_QUANTITIES] = {
    let mut n = [""; N_TRIM_QUANTITIES];
    let mut i = 0;
    while i < 4 {
        n[i] = INPUT_NAMES[i];
        i += 1;
    }
    while i < N_TRIM {
        n[i] = REDUCED_STATE_NAMES[i - 4];
        i += 1;
    }
    n[N_TRIM] = "lambda_mr";
    n[N_TRIM + 1] = "lambda_tr";
    n
};

/// A jump factor: a step between neighbouring sweep points is a jump in a
/// quantity when its change exceeds this many times the larger change of the
/// steps on either side (see [`discontinuities`]).
pub const JUMP_FACTOR: f64 = 3.0;
/// ... and this fraction of the quantity's excursion (max − min) over the
/// converged points of the sweep: a curve flattening at an extremum at the
/// end of a sweep (one neighbour only) can have one step several times its
/// neighbour, but never a sizeable part of the whole excursion.
pub const JUMP_SHARE: f64 = 0.05;
/// Changes below this (SI units: rad, m/s, rad/s, servo units) are never
/// jumps: they are at the level of the trim tolerance's effect on the
/// solution, not a change of branch.
pub const JUMP_FLOOR: f64 = 1e-6;

/// A jump between two neighbouring points of a sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct Discontinuity {
    /// The step from point `index − 1` to point `index`.
    pub index: usize,
    /// The quantities that jump, with their change.
    pub quantities: Vec<(&'static str, f64)>,
}

/// The jumps in a sweep: for each quantity of [`Trim::quantities`] and each
/// step k (from point k−1 to k, both converged), with changes d of the
/// neighbouring steps k−1 and k+1 (those with both points converged; at
/// least one is needed), the step is a jump when
/// |d_k| > [`JUMP_FACTOR`] · max(|d_k−1|, |d_k+1|),
/// |d_k| > [`JUMP_SHARE`] · (max − min of the quantity over the sweep) and
/// |d_k| > [`JUMP_FLOOR`].
///
/// On a smooth branch consecutive changes differ by O(h²·f''), so one step
/// three times larger than both neighbours needs a third derivative as large
/// as the first over one step: a branch switch (e.g. the inflow jumping from
/// the vortex-ring to the windmill-brake solution of (7.33)) or a sweep too
/// coarse to resolve the curve — both worth a look.
pub fn discontinuities(results: &[Result<Trim, TrimError>]) -> Vec<Discontinuity> {
    let q: Vec<Option<[f64; N_TRIM_QUANTITIES]>> = results
        .iter()
        .map(|r| r.as_ref().ok().map(Trim::quantities))
        .collect();
    // d[k] = change from point k−1 to k, for k ≥ 1 with both converged.
    let change = |k: usize, i: usize| -> Option<f64> {
        if k == 0 || k >= q.len() {
            return None;
        }
        match (&q[k - 1], &q[k]) {
            (Some(a), Some(b)) => Some(b[i] - a[i]),
            _ => None,
        }
    };
    let mut lo = [f64::INFINITY; N_TRIM_QUANTITIES];
    let mut hi = [f64::NEG_INFINITY; N_TRIM_QUANTITIES];
    for v in q.iter().flatten() {
        for i in 0..N_TRIM_QUANTITIES {
            lo[i] = lo[i].min(v[i]);
            hi[i] = hi[i].max(v[i]);
        }
    }
    let mut out = Vec::new();
    for k in 1..q.len() {
        let mut jumps = Vec::new();
        for (i, name) in TRIM_QUANTITY_NAMES.iter().enumerate() {
            let Some(d) = change(k, i) else { continue };
            let neighbours = [change(k - 1, i), change(k + 1, i)];
            let Some(nmax) = neighbours
                .iter()
                .flatten()
                .map(|v| v.abs())
                .reduce(f64::max)
            else {
                continue;
            };
            if d.abs() > JUMP_FLOOR
                && d.abs() > JUMP_FACTOR * nmax
                && d.abs() > JUMP_SHARE * (hi[i] - lo[i])
            {
                jumps.push((*name, d));
            }
        }
        if !jumps.is_empty() {
            out.push(Discontinuity {
                index: k,
                quantities: jumps,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inflow::InflowProblem;

    #[test]
    fn descent_ratio_classifies_the_axial_momentum_roots() {
        // Axial flow (μ_inplane = 0), constant C_T: the two roots of (7.33) in
        // descent (μa > 0) in closed form. λ < 0: λ = (μa − √(μa² + 2C_T))/2,
        // d = 2μa/(μa + √(μa² + 2C_T)) ∈ (0, 2): always the vortex-ring region.
        // λ > 0 (μa² > 2C_T): λ = (μa + √(μa² − 2C_T))/2,
        // d = 2μa/(μa − √(μa² − 2C_T)) ≥ 2: windmill brake. Climb: d < 0.
        let ct = 0.0034;
        for mu_a in [0.01, 0.05, 0.09, 0.2] {
            let p = InflowProblem {
                mu_inplane2: 0.0,
                mu_axial: mu_a,
                ct0: ct,
                ct1: 0.0,
            };
            let lam = (mu_a - (mu_a * mu_a + 2.0 * ct).sqrt()) / 2.0;
            assert!(lam < 0.0 && p.g(lam).abs() < 1e-15);
            let d = descent_ratio(mu_a, 0.0, lam).unwrap();
            let d_exact = 2.0 * mu_a / (mu_a + (mu_a * mu_a + 2.0 * ct).sqrt());
            assert!((d - d_exact).abs() < 1e-12 && d > 0.0 && d < 2.0);
            if mu_a * mu_a > 2.0 * ct {
                let wbs = (mu_a + (mu_a * mu_a - 2.0 * ct).sqrt()) / 2.0;
                assert!(p.g(wbs).abs() < 1e-15);
                assert!(descent_ratio(mu_a, 0.0, wbs).unwrap() >= 2.0);
            }
            // the solver returns one of the two roots
            let solved = p.solve().unwrap().lambda;
            assert!(p.g(solved).abs() < 1e-12);
        }
        let climb = InflowProblem {
            mu_inplane2: 0.0,
            mu_axial: -0.05,
            ct0: ct,
            ct1: 0.0,
        };
        assert!(descent_ratio(-0.05, 0.0, climb.solve().unwrap().lambda).unwrap() < 0.0);
        // a rotor with reversed thrust is mirrored
        assert_eq!(
            descent_ratio(-0.05, 0.0, -0.02),
            descent_ratio(0.05, 0.0, 0.02)
        );
        // edgewise speed above the induced velocity: not applicable
        assert_eq!(descent_ratio(0.05, 0.2, -0.01), None);
        assert_eq!(descent_ratio(0.0, 0.0, 0.0), None);
    }
}
