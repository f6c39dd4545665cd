//! The flight controller: state estimator + LQR with integral action, one
//! allocation-free [`FlightController::step`] per sample (thesis Figure 14.4,
//! (14.34), (15.8)).
//!
//! Per sample k, with x̂(k) the one-step prediction of the deviation from trim:
//! 1. outputs ŷ = [ψ̂, û, v̂, ŵ] from x̂(k) (or from the true state when the
//!    estimator is off);
//! 2. output errors e(k): ψ_ref − ψ̂ (wrapped to (−π, π]) and, for the
//!    velocities, r_ned − R_eb(Θ̂) v̂_body — the references are NED velocities
//!    and yaw, as the thesis plots them ((14.37), Figure 14.5);
//! 3. u(k) = u_trim − Ls,α x_fb − Li,α x_i,body (14.34), where x_fb is x̂ with
//!    the reference subtracted on the four output states (so a reference step
//!    acts through the proportional path too, not only through the slow
//!    integrators), and x_i,body is the integral state with its velocity part
//!    (kept in NED, so it survives heading changes) rotated into body axes;
//! 4. u saturated to the servo limits;
//! 5. x_i(k+1) = x_i(k) + e(k) (14.29), and the Kalman predictor (15.8)
//!    x̂(k+1) = Φ x̂(k) + Γ (u(k) − u_trim) + K (y_m(k) − Hm x̂(k)), with the
//!    yaw innovation wrapped.

use crate::design::{DesignError, Gains, NM, NUI, NXR, NY, from_rows};
use crate::fusion::wrap_pi;
use helicon_model::frames::EulerTrig;
use nalgebra::{SMatrix, SVector, Vector3};

/// Reference for the four controlled outputs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Reference {
    /// Velocity in NED (m/s).
    pub velocity_ned_m_s: Vector3<f64>,
    /// Heading ψ (rad).
    pub yaw_rad: f64,
}

/// The thesis's switches (Appendix E simulation environment).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerSwitches {
    /// Feedback on; off holds the trim inputs (open loop).
    pub feedback: bool,
    /// Estimator on; off feeds the true state back (analysis only).
    pub estimator: bool,
}

impl Default for ControllerSwitches {
    fn default() -> Self {
        ControllerSwitches {
            feedback: true,
            estimator: true,
        }
    }
}

/// What the controller is given each sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Feedback<'a> {
    /// The nine measured states (15.2) [φ θ ψ u v w p q r], absolute values.
    Measured(&'a SVector<f64, NM>),
    /// The full 27-state vector (absolute), e.g. truth; used directly when
    /// the estimator is off, and its first nine entries as the measurement
    /// when it is on.
    Full(&'a SVector<f64, NXR>),
}

/// The controller (fixed-size matrices; `step` does not allocate).
#[derive(Debug, Clone, PartialEq)]
pub struct FlightController {
    phi: SMatrix<f64, NXR, NXR>,
    gamma: SMatrix<f64, NXR, NUI>,
    ls: SMatrix<f64, NUI, NXR>,
    li: SMatrix<f64, NUI, NY>,
    k: SMatrix<f64, NXR, NM>,
    x_trim: SVector<f64, NXR>,
    u_trim: SVector<f64, NUI>,
    u_min: SVector<f64, NUI>,
    u_max: SVector<f64, NUI>,
    switches: ControllerSwitches,
    /// x̂(k): predicted deviation from trim.
    x_hat: SVector<f64, NXR>,
    /// Integral states [ψ, vn, ve, vd].
    x_i: SVector<f64, NY>,
    saturated: [bool; NUI],
    ts: f64,
    accel_body: Vector3<f64>,
    reference_in_proportional: bool,
    anti_windup: bool,
}

fn fixed<const R: usize, const C: usize>(
    what: &'static str,
    rows: &[Vec<f64>],
) -> Result<SMatrix<f64, R, C>, DesignError> {
    let d = from_rows(what, rows, R, C)?;
    Ok(SMatrix::<f64, R, C>::from_fn(|i, j| d[(i, j)]))
}

/// One sample's outputs, for logging.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerOutput {
    /// Servo command after saturation.
    pub u: SVector<f64, NUI>,
    /// The estimate used (absolute 27-state).
    pub x_estimate: SVector<f64, NXR>,
    /// Output errors [ψ, vn, ve, vd].
    pub error: SVector<f64, NY>,
    /// Which inputs saturated.
    pub saturated: [bool; NUI],
}

impl FlightController {
    /// A controller from designed gains and the servo command limits
    /// `[S_min; S_max]` per input.
    pub fn new(
        gains: &Gains,
        u_min: [f64; NUI],
        u_max: [f64; NUI],
        switches: ControllerSwitches,
    ) -> Result<Self, DesignError> {
        gains.check()?;
        Ok(FlightController {
            phi: fixed("phi", &gains.phi)?,
            gamma: fixed("gamma", &gains.gamma)?,
            ls: fixed("ls", &gains.ls)?,
            li: fixed("li", &gains.li)?,
            k: fixed("k", &gains.k)?,
            x_trim: SVector::from_column_slice(&gains.x_trim),
            u_trim: SVector::from_column_slice(&gains.u_trim),
            u_min: SVector::from(u_min),
            u_max: SVector::from(u_max),
            switches,
            x_hat: SVector::zeros(),
            x_i: SVector::zeros(),
            saturated: [false; NUI],
            ts: gains.config.sample_time_s,
            reference_in_proportional: gains.config.reference_in_proportional,
            anti_windup: gains.config.anti_windup,
            accel_body: Vector3::zeros(),
        })
    }

    /// Initialise the estimate (absolute 27-state), e.g. from the first
    /// measurement; the integrators are reset.
    pub fn reset(&mut self, x_abs: &SVector<f64, NXR>) {
        self.x_hat = x_abs - self.x_trim;
        self.x_i = SVector::zeros();
    }

    /// The current estimate (absolute).
    pub fn estimate(&self) -> SVector<f64, NXR> {
        self.x_hat + self.x_trim
    }

    /// The helicopter's own inertial acceleration in body axes (m/s²) as the
    /// estimator predicts it, v̇ + ω × v from the last predictor step: the
    /// acceleration the gravity observation (13.2) must subtract.
    pub fn predicted_accel_body(&self) -> Vector3<f64> {
        self.accel_body
    }

    /// The integral states [ψ, vn, ve, vd].
    pub fn integral_states(&self) -> &SVector<f64, NY> {
        &self.x_i
    }

    /// One controller sample.
    // `&self.phi * x`: by reference on purpose, the by-value `Mul` copies the
    // 27×27 matrix each call (measured: ~500 instructions per step).
    #[allow(clippy::op_ref)]
    pub fn step(&mut self, feedback: Feedback<'_>, reference: &Reference) -> ControllerOutput {
        let y_m: SVector<f64, NM> = match feedback {
            Feedback::Measured(y) => *y,
            Feedback::Full(x) => SVector::from_fn(|i, _| x[i]),
        };
        // The deviation used by the control law.
        let x_dev: SVector<f64, NXR> = match (self.switches.estimator, feedback) {
            (false, Feedback::Full(x)) => x - self.x_trim,
            _ => self.x_hat,
        };
        let x_abs = x_dev + self.x_trim;
        let trig = EulerTrig::new(x_abs[0], x_abs[1], x_abs[2]);
        let ned_from_body = trig.ned_from_body();
        let v_body = Vector3::new(x_abs[3], x_abs[4], x_abs[5]);
        let v_ned = ned_from_body * v_body;
        let e_psi = wrap_pi(reference.yaw_rad - x_abs[2]);
        let e_v = reference.velocity_ned_m_s - v_ned;
        let error = SVector::<f64, NY>::new(e_psi, e_v.x, e_v.y, e_v.z);

        let u = if self.switches.feedback {
            let mut x_fb = x_dev;
            if self.reference_in_proportional {
                // output states relative to the reference (ψ error, body velocity error)
                x_fb[2] = -e_psi;
                let r_body = ned_from_body.transpose() * reference.velocity_ned_m_s;
                for i in 0..3 {
                    x_fb[3 + i] = v_body[i] - r_body[i];
                }
            }
            let xi_v_body =
                ned_from_body.transpose() * Vector3::new(self.x_i[1], self.x_i[2], self.x_i[3]);
            let xi_body =
                SVector::<f64, NY>::new(self.x_i[0], xi_v_body.x, xi_v_body.y, xi_v_body.z);
            self.u_trim - &self.ls * x_fb - &self.li * xi_body
        } else {
            self.u_trim
        };
        let mut u_sat = u;
        for i in 0..NUI {
            u_sat[i] = u[i].clamp(self.u_min[i], self.u_max[i]);
            self.saturated[i] = u_sat[i] != u[i];
        }
        // integral action (14.29)
        if !(self.anti_windup && self.saturated.iter().any(|&b| b)) {
            self.x_i += error;
        }
        // Kalman predictor (15.8), yaw innovation wrapped
        if self.switches.estimator {
            let mut innov =
                SVector::<f64, NM>::from_fn(|i, _| y_m[i] - self.x_trim[i] - self.x_hat[i]);
            innov[2] = wrap_pi(innov[2]);
            self.x_hat =
                &self.phi * self.x_hat + &self.gamma * (u_sat - self.u_trim) + &self.k * innov;
        }
        ControllerOutput {
            u: u_sat,
            x_estimate: x_abs,
            error,
            saturated: self.saturated,
        }
    }
}
