//! Position, velocity and attitude fusion of GPS + IMU + attitude measurement
//! as a standard discrete Kalman filter, thesis §13.3 (13.15)–(13.29).
//!
//! State (13.15), 9 elements: `Xf = [Ξ_ned (m), Ξ̇_ned (m/s), Θ = (φ, θ, ψ) (rad)]`.
//! Input (13.16): `Uf = [Ξ̈ (m/s², NED), Θ̇ (rad/s)]`, formed from the IMU:
//! the specific force measured in body axes is rotated to NED with the current
//! attitude estimate and gravity is removed, `Ξ̈ = R_eb(Θ) f_body + [0, 0, g]`
//! ((9.5); the accelerometer reads `f = a − g`), and the Euler rates come from
//! the gyro rates via (9.14), `Θ̇ = P_eb(φ, θ) ω_body`.
//! Measurement (13.18): `Zf = [Ξ_gps, Θ_pre]` with `Θ_pre` from the q-method
//! (§13.2); either part may be missing in a step.
//!
//! Discrete model, sample time `T_s`: `A_f` (13.27) and
//! `B_f = [[T_s²/2 I, 0], [T_s I, 0], [0, T_s I]]`. The printed (13.28) has
//! only the `T_s²/2` position block in its first three rows and shifts the
//! remaining blocks; the matrix above is the exact zero-order-hold
//! discretisation of (13.24)–(13.25) with the input held over the sample.
//!
//! Covariance prediction: `P⁻ = A P Aᵀ + Q` with `Q = B diag(σ_a² I, σ_Θ̇² I) Bᵀ`
//! (input noise mapped through B). **The thesis's (13.20) is misprinted** as
//! `P⁻(k) = A_f P_f(k−1) Q_f U_f(k−1)`, a product that is not even
//! dimensionally a covariance; the standard form is used here.
//! Gain and update (13.21)–(13.23): `K = P⁻Hᵀ(HP⁻Hᵀ + R)⁻¹`,
//! `X = X⁻ + K(Z − HX⁻)`, `P = (I − KH)P⁻` (then symmetrised), with `H` the
//! non-zero rows of `C_f` (13.29) present in this step. The GPS and attitude
//! updates are applied one after the other; with the block-diagonal R used
//! here this equals the joint update of (13.21)–(13.23).
//!
//! Angles: the ψ innovation is wrapped to (−π, π] and ψ is kept in (−π, π].

use crate::frames::{EulerTrig, wrap_pi};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// 9×9 matrix of the fusion filter.
pub type Matrix9 = SMatrix<f64, 9, 9>;
/// 9-vector of the fusion filter.
pub type Vector9 = SVector<f64, 9>;

/// Smallest |cos θ| accepted by the Euler-rate kinematics (9.14) before the
/// filter reports gimbal lock.
pub const MIN_COS_THETA: f64 = 1e-6;

/// Error of the fusion filter.
#[derive(Debug, Clone, PartialEq)]
pub enum FusionError {
    /// A configuration value is out of range.
    InvalidConfig {
        /// Field name.
        field: &'static str,
        /// Value given.
        value: f64,
        /// Allowed range.
        allowed: &'static str,
    },
    /// An input is NaN or infinite.
    NonFiniteInput {
        /// Which input.
        what: &'static str,
    },
    /// The attitude estimate reached θ = ±π/2 where (9.14) is singular.
    GimbalLock {
        /// Pitch estimate (rad).
        theta_rad: f64,
    },
    /// The innovation covariance was not invertible.
    SingularInnovation,
}

impl std::fmt::Display for FusionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FusionError::InvalidConfig {
                field,
                value,
                allowed,
            } => write!(
                f,
                "navigation setting `{field}` = {value} is invalid ({allowed})"
            ),
            FusionError::NonFiniteInput { what } => {
                write!(f, "navigation input: non-finite {what}")
            }
            FusionError::GimbalLock { theta_rad } => write!(
                f,
                "navigation: pitch estimate {theta_rad} rad is at the 3-2-1 gimbal lock"
            ),
            FusionError::SingularInnovation => {
                write!(f, "navigation: singular innovation covariance")
            }
        }
    }
}

impl std::error::Error for FusionError {}

/// Tuning of the fusion filter: the weighting matrices Q_f and R_f of §13.3.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FusionConfig {
    /// Sample time `T_s` (s).
    pub dt_s: f64,
    /// Gravity (m/s²), thesis (13.13): 9.82.
    pub gravity_m_s2: f64,
    /// Standard deviation of the NED acceleration input per axis (m/s²).
    pub accel_sigma_m_s2: f64,
    /// Standard deviation of the Euler-rate input per axis (rad/s).
    pub euler_rate_sigma_rad_s: f64,
    /// Standard deviation of the GPS position (m), per NED axis.
    pub gps_sigma_m: Vector3<f64>,
    /// Standard deviation of the attitude measurement (rad), per angle.
    pub attitude_sigma_rad: Vector3<f64>,
    /// Standard deviation of the GPS (Doppler) velocity (m/s), per NED axis:
    /// an extension beyond the thesis, which fused GPS position only.
    pub gps_vel_sigma_m_s: Vector3<f64>,
}

impl Default for FusionConfig {
    /// 100 Hz, hobby IMU after attitude rotation (0.1 m/s²), gyro 0.01 rad/s,
    /// GPS 1.5 m horizontal / 3 m vertical, q-method attitude 0.02 rad.
    fn default() -> Self {
        Self {
            dt_s: 0.01,
            gravity_m_s2: 9.82,
            accel_sigma_m_s2: 0.1,
            euler_rate_sigma_rad_s: 0.01,
            gps_sigma_m: Vector3::new(1.5, 1.5, 3.0),
            gps_vel_sigma_m_s: Vector3::new(0.1, 0.1, 0.2),
            attitude_sigma_rad: Vector3::new(0.02, 0.02, 0.02),
        }
    }
}

impl FusionConfig {
    fn validate(&self) -> Result<(), FusionError> {
        let pos = |field: &'static str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(FusionError::InvalidConfig {
                    field,
                    value,
                    allowed: "finite and > 0",
                })
            }
        };
        pos("dt_s", self.dt_s)?;
        pos("gravity_m_s2", self.gravity_m_s2)?;
        pos("accel_sigma_m_s2", self.accel_sigma_m_s2)?;
        pos("euler_rate_sigma_rad_s", self.euler_rate_sigma_rad_s)?;
        for v in self.gps_sigma_m.iter() {
            pos("gps_sigma_m", *v)?;
        }
        for v in self.attitude_sigma_rad.iter() {
            pos("attitude_sigma_rad", *v)?;
        }
        for v in self.gps_vel_sigma_m_s.iter() {
            pos("gps_vel_sigma_m_s", *v)?;
        }
        Ok(())
    }
}

/// One step of inputs for [`FusionFilter::step`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FusionInput {
    /// Accelerometer specific force in body axes at k−1 (m/s²), `f = a − g`.
    pub specific_force_body_m_s2: Vector3<f64>,
    /// Gyro rates in body axes at k−1 (rad/s).
    pub gyro_body_rad_s: Vector3<f64>,
    /// GPS position in NED at k (m), `None` when no fix.
    pub gps_ned_m: Option<Vector3<f64>>,
    /// GPS velocity in NED at k (m/s), `None` when the receiver gives none.
    pub gps_vel_ned_m_s: Option<Vector3<f64>>,
    /// Attitude measurement (φ, θ, ψ) at k (rad) from the q-method, if any.
    pub attitude_rad: Option<Vector3<f64>>,
}

/// The fusion Kalman filter of §13.3; all matrices fixed-size, `step()` does
/// not allocate.
#[derive(Debug, Clone, PartialEq)]
pub struct FusionFilter {
    config: FusionConfig,
    a: Matrix9,
    b: SMatrix<f64, 9, 6>,
    q: Matrix9,
    x: Vector9,
    p: Matrix9,
    gate: GpsGate,
    /// Consecutive rejections of the GPS position and velocity updates.
    streak: [u32; 2],
    last: GateReport,
    rejected: u64,
}

/// The innovation gate of the GPS updates ([`FusionFilter::with_gps_gate`]):
/// a position or velocity fix whose normalised innovation squared
/// `NIS = yᵀ S⁻¹ y` (χ² with 3 degrees of freedom for a consistent filter)
/// exceeds `nis` is not fused — a receiver's glitch cannot drag the
/// estimate — unless `reset_after` consecutive fixes were refused (then the
/// filter, not the receiver, is presumed wrong and the next fix is fused).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsGate {
    /// Largest accepted NIS of a 3-vector GPS update (`f64::INFINITY`: no gate).
    pub nis: f64,
    /// Refusals in a row after which the next fix is fused ungated (0: never).
    pub reset_after: u32,
}

impl GpsGate {
    /// No gate: every fix fused (the thesis's filter).
    pub const OFF: GpsGate = GpsGate {
        nis: f64::INFINITY,
        reset_after: 0,
    };
}

/// What the gate did with the last step's GPS fix.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GateReport {
    /// The position fix was refused by the gate.
    pub position_rejected: bool,
    /// The velocity fix was refused by the gate.
    pub velocity_rejected: bool,
    /// NIS of the last position update (gated or not; 0 without one).
    pub position_nis: f64,
    /// NIS of the last velocity update (gated or not; 0 without one).
    pub velocity_nis: f64,
}

impl FusionFilter {
    /// A filter with initial state `x0 = [Ξ, Ξ̇, Θ]` and covariance `p0`.
    pub fn new(config: FusionConfig, x0: Vector9, p0: Matrix9) -> Result<Self, FusionError> {
        config.validate()?;
        if !x0.iter().chain(p0.iter()).all(|v| v.is_finite()) {
            return Err(FusionError::NonFiniteInput {
                what: "initial state or covariance",
            });
        }
        let ts = config.dt_s;
        // (13.27)
        let mut a = Matrix9::identity();
        for i in 0..3 {
            a[(i, i + 3)] = ts;
        }
        // B_f: exact ZOH discretisation of (13.24)–(13.25), see module docs.
        let mut b = SMatrix::<f64, 9, 6>::zeros();
        for i in 0..3 {
            b[(i, i)] = 0.5 * ts * ts;
            b[(i + 3, i)] = ts;
            b[(i + 6, i + 3)] = ts;
        }
        let mut qu = SMatrix::<f64, 6, 6>::zeros();
        for i in 0..3 {
            qu[(i, i)] = config.accel_sigma_m_s2.powi(2);
            qu[(i + 3, i + 3)] = config.euler_rate_sigma_rad_s.powi(2);
        }
        let q = b * qu * b.transpose();
        Ok(Self {
            config,
            a,
            b,
            q,
            x: x0,
            p: p0,
            gate: GpsGate::OFF,
            streak: [0; 2],
            last: GateReport::default(),
            rejected: 0,
        })
    }

    /// The same filter with the GPS updates gated by `gate` (a NaN or
    /// non-positive bound is refused).
    pub fn with_gps_gate(mut self, gate: GpsGate) -> Result<Self, FusionError> {
        if gate.nis.is_nan() || gate.nis <= 0.0 {
            return Err(FusionError::InvalidConfig {
                field: "gps_gate_nis",
                value: gate.nis,
                allowed: "> 0 (infinite: no gate)",
            });
        }
        self.gate = gate;
        Ok(self)
    }

    /// What the gate did with the last step's GPS fix.
    pub fn last_gate(&self) -> &GateReport {
        &self.last
    }

    /// GPS updates refused by the gate since the start.
    pub fn rejected_updates(&self) -> u64 {
        self.rejected
    }

    /// Current state estimate `[Ξ_ned, Ξ̇_ned, Θ]`.
    pub fn state(&self) -> &Vector9 {
        &self.x
    }

    /// Current covariance.
    pub fn covariance(&self) -> &Matrix9 {
        &self.p
    }

    /// The configuration.
    pub fn config(&self) -> &FusionConfig {
        &self.config
    }

    /// Discrete `A_f` (13.27).
    pub fn a(&self) -> &Matrix9 {
        &self.a
    }

    /// Discrete `B_f` (see module docs on (13.28)).
    pub fn b(&self) -> &SMatrix<f64, 9, 6> {
        &self.b
    }

    /// Process-noise covariance `Q_f = B diag(σ_a², σ_Θ̇²) Bᵀ`.
    pub fn q(&self) -> &Matrix9 {
        &self.q
    }

    /// The input (13.16) from IMU samples and the current attitude estimate:
    /// `[Ξ̈_ned, Θ̇]`.
    pub fn input_from_imu(
        &self,
        specific_force_body_m_s2: &Vector3<f64>,
        gyro_body_rad_s: &Vector3<f64>,
    ) -> Result<SVector<f64, 6>, FusionError> {
        let (phi, theta, psi) = (self.x[6], self.x[7], self.x[8]);
        if theta.cos().abs() < MIN_COS_THETA {
            return Err(FusionError::GimbalLock { theta_rad: theta });
        }
        let trig = EulerTrig::new(phi, theta, psi);
        let acc_ned = trig.ned_from_body() * specific_force_body_m_s2
            + Vector3::new(0.0, 0.0, self.config.gravity_m_s2);
        let rates = trig.euler_rates(gyro_body_rad_s); // (9.14)
        let mut u = SVector::<f64, 6>::zeros();
        u.fixed_rows_mut::<3>(0).copy_from(&acc_ned);
        u.fixed_rows_mut::<3>(3).copy_from(&rates);
        Ok(u)
    }

    /// Prediction (13.19) and `P⁻ = A P Aᵀ + Q` (the corrected (13.20)).
    ///
    /// Uses the block structure of `A_f` (identity plus `T_s` coupling of
    /// position to velocity) instead of dense 9×9 products; the result equals
    /// `A P Aᵀ + Q` (cross-checked against the dense NumPy reference).
    pub fn predict(&mut self, u: &SVector<f64, 6>) {
        let ts = self.config.dt_s;
        let h = 0.5 * ts * ts;
        for i in 0..3 {
            self.x[i] += ts * self.x[i + 3] + h * u[i];
            self.x[i + 3] += ts * u[i];
            self.x[i + 6] += ts * u[i + 3];
        }
        self.x[8] = wrap_pi(self.x[8]);
        // P ← A P: rows 0..3 += T_s · rows 3..6.
        for i in 0..3 {
            for j in 0..9 {
                let v = self.p[(i + 3, j)];
                self.p[(i, j)] += ts * v;
            }
        }
        // P ← P Aᵀ: columns 0..3 += T_s · columns 3..6.
        for j in 0..3 {
            for i in 0..9 {
                let v = self.p[(i, j + 3)];
                self.p[(i, j)] += ts * v;
            }
        }
        self.p += self.q;
    }

    /// Measurement update (13.21)–(13.23) with the three states starting at
    /// `offset` (0: position, 6: attitude) measured with per-axis σ `sigma`.
    fn update_block(
        &mut self,
        offset: usize,
        z: &Vector3<f64>,
        sigma: &Vector3<f64>,
        wrap_last: bool,
        gated: Option<usize>,
    ) -> Result<bool, FusionError> {
        let mut innov = z - self.x.fixed_rows::<3>(offset);
        if wrap_last {
            innov.z = wrap_pi(innov.z);
        }
        let p_xh: SMatrix<f64, 9, 3> = self.p.fixed_columns::<3>(offset).into_owned();
        let mut s: Matrix3<f64> = self.p.fixed_view::<3, 3>(offset, offset).into_owned();
        for i in 0..3 {
            s[(i, i)] += sigma[i] * sigma[i];
        }
        let s_inv = s.try_inverse().ok_or(FusionError::SingularInnovation)?;
        if let Some(g) = gated {
            let nis = (innov.transpose() * s_inv * innov)[(0, 0)];
            if g == 0 {
                self.last.position_nis = nis;
            } else {
                self.last.velocity_nis = nis;
            }
            let forced = self.gate.reset_after > 0 && self.streak[g] >= self.gate.reset_after;
            // a NaN NIS (an overflowing innovation) is refused too
            if (nis.is_nan() || nis > self.gate.nis) && !forced {
                self.streak[g] = self.streak[g].saturating_add(1);
                self.rejected += 1;
                return Ok(false);
            }
            self.streak[g] = 0;
        }
        let k = p_xh * s_inv; // (13.21)
        self.x += k * innov; // (13.23)
        // (13.22): P = (I − K H) P⁻ with H selecting rows offset..offset+3.
        // P ← P − K (H P); H P = P_xhᵀ (P symmetric). Only the lower
        // triangle is computed and mirrored, which keeps P exactly symmetric
        // (the dense form followed by (P + Pᵀ)/2 differs by round-off only).
        for i in 0..9 {
            for j in 0..=i {
                let mut acc = 0.0;
                for m in 0..3 {
                    acc += k[(i, m)] * p_xh[(j, m)];
                }
                let v = self.p[(i, j)] - acc;
                self.p[(i, j)] = v;
                self.p[(j, i)] = v;
            }
        }
        self.x[8] = wrap_pi(self.x[8]);
        Ok(true)
    }

    /// One filter step: predict with the IMU samples of k−1 ((13.16), (13.19),
    /// (13.20) corrected), then update with the GPS and/or attitude
    /// measurements of k if present. Without measurements it only predicts.
    pub fn step(&mut self, input: &FusionInput) -> Result<(), FusionError> {
        if !input
            .specific_force_body_m_s2
            .iter()
            .chain(input.gyro_body_rad_s.iter())
            .all(|v| v.is_finite())
        {
            return Err(FusionError::NonFiniteInput { what: "IMU sample" });
        }
        if let Some(g) = &input.gps_ned_m
            && !g.iter().all(|v| v.is_finite())
        {
            return Err(FusionError::NonFiniteInput { what: "GPS fix" });
        }
        if let Some(g) = &input.gps_vel_ned_m_s
            && !g.iter().all(|v| v.is_finite())
        {
            return Err(FusionError::NonFiniteInput {
                what: "GPS velocity",
            });
        }
        if let Some(a) = &input.attitude_rad
            && !a.iter().all(|v| v.is_finite())
        {
            return Err(FusionError::NonFiniteInput {
                what: "attitude measurement",
            });
        }
        let u = self.input_from_imu(&input.specific_force_body_m_s2, &input.gyro_body_rad_s)?;
        self.predict(&u);
        self.last = GateReport::default();
        if let Some(g) = &input.gps_ned_m {
            let sigma = self.config.gps_sigma_m;
            self.last.position_rejected = !self.update_block(0, g, &sigma, false, Some(0))?;
        }
        if let Some(v) = &input.gps_vel_ned_m_s {
            let sigma = self.config.gps_vel_sigma_m_s;
            self.last.velocity_rejected = !self.update_block(3, v, &sigma, false, Some(1))?;
        }
        if let Some(a) = &input.attitude_rad {
            let sigma = self.config.attitude_sigma_rad;
            self.update_block(6, a, &sigma, true, None)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn wrap_pi_range() {
        let pi = std::f64::consts::PI;
        assert_relative_eq!(wrap_pi(3.0 * pi / 2.0), -pi / 2.0, epsilon = 1e-15);
        assert_relative_eq!(wrap_pi(-pi), pi, epsilon = 1e-15);
        assert_relative_eq!(wrap_pi(0.3), 0.3, epsilon = 1e-15);
    }

    #[test]
    fn at_rest_level_prediction_stays_put() {
        let cfg = FusionConfig::default();
        let mut f = FusionFilter::new(cfg, Vector9::zeros(), Matrix9::identity()).unwrap();
        let input = FusionInput {
            specific_force_body_m_s2: Vector3::new(0.0, 0.0, -cfg.gravity_m_s2),
            gyro_body_rad_s: Vector3::zeros(),
            gps_ned_m: None,
            gps_vel_ned_m_s: None,
            attitude_rad: None,
        };
        for _ in 0..100 {
            f.step(&input).unwrap();
        }
        assert!(f.state().norm() < 1e-12);
        // Covariance only grows without measurements.
        assert!(f.covariance()[(0, 0)] > 1.0);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let cfg = FusionConfig::default();
        let mut f = FusionFilter::new(cfg, Vector9::zeros(), Matrix9::identity()).unwrap();
        let input = FusionInput {
            specific_force_body_m_s2: Vector3::new(f64::NAN, 0.0, 0.0),
            gyro_body_rad_s: Vector3::zeros(),
            gps_ned_m: None,
            gps_vel_ned_m_s: None,
            attitude_rad: None,
        };
        assert!(f.step(&input).is_err());
        let bad = FusionConfig { dt_s: 0.0, ..cfg };
        assert!(FusionFilter::new(bad, Vector9::zeros(), Matrix9::identity()).is_err());
        let mut x0 = Vector9::zeros();
        x0[7] = std::f64::consts::FRAC_PI_2;
        let mut f = FusionFilter::new(cfg, x0, Matrix9::identity()).unwrap();
        let input = FusionInput {
            specific_force_body_m_s2: Vector3::zeros(),
            gyro_body_rad_s: Vector3::zeros(),
            gps_ned_m: None,
            gps_vel_ned_m_s: None,
            attitude_rad: None,
        };
        assert!(matches!(
            f.step(&input),
            Err(FusionError::GimbalLock { .. })
        ));
    }

    /// The GPS gate: fixes at the estimate are fused; a fix 10 km away at
    /// 300 m/s (a receiver's glitch) is refused and leaves the estimate
    /// where prediction alone puts it; after `reset_after` refusals in a
    /// row the next fix is fused (the filter presumed wrong).
    #[test]
    fn the_gps_gate_refuses_a_glitch_and_resets_after_a_streak() {
        let cfg = FusionConfig::default();
        let gate = GpsGate {
            nis: 50.0,
            reset_after: 5,
        };
        let new = || {
            FusionFilter::new(cfg, Vector9::zeros(), Matrix9::identity())
                .unwrap()
                .with_gps_gate(gate)
                .unwrap()
        };
        let level = Vector3::new(0.0, 0.0, -cfg.gravity_m_s2);
        let at = |p: Vector3<f64>, v: Vector3<f64>| FusionInput {
            specific_force_body_m_s2: level,
            gyro_body_rad_s: Vector3::zeros(),
            gps_ned_m: Some(p),
            gps_vel_ned_m_s: Some(v),
            attitude_rad: None,
        };
        let mut f = new();
        for _ in 0..20 {
            f.step(&at(Vector3::new(0.5, -0.3, 0.2), Vector3::zeros()))
                .unwrap();
            assert!(!f.last_gate().position_rejected && !f.last_gate().velocity_rejected);
        }
        let mut predicted = f.clone();
        let glitch = at(
            Vector3::new(10_000.0, 0.0, -5_000.0),
            Vector3::new(300.0, 0.0, 0.0),
        );
        f.step(&glitch).unwrap();
        predicted
            .step(&FusionInput {
                gps_ned_m: None,
                gps_vel_ned_m_s: None,
                ..glitch
            })
            .unwrap();
        assert!(f.last_gate().position_rejected && f.last_gate().velocity_rejected);
        assert!(f.last_gate().position_nis > 1e6, "{:?}", f.last_gate());
        assert_eq!(f.state(), predicted.state());
        assert_eq!(f.rejected_updates(), 2);
        // four more refusals make a streak of five: the sixth is fused
        for _ in 0..4 {
            f.step(&glitch).unwrap();
            assert!(f.last_gate().position_rejected);
        }
        f.step(&glitch).unwrap();
        assert!(!f.last_gate().position_rejected);
        assert!(f.state()[0] > 100.0);
        // no gate: the thesis's filter fuses the glitch at once
        let mut off = FusionFilter::new(cfg, Vector9::zeros(), Matrix9::identity()).unwrap();
        off.step(&glitch).unwrap();
        assert!(!off.last_gate().position_rejected && off.state()[0] > 100.0);
        assert!(
            FusionFilter::new(cfg, Vector9::zeros(), Matrix9::identity())
                .unwrap()
                .with_gps_gate(GpsGate {
                    nis: f64::NAN,
                    reset_after: 0
                })
                .is_err()
        );
    }
}
