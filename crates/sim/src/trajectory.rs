//! A scripted, smooth analytic trajectory to drive the sensor models.
//!
//! Until the closed loop (a later issue) drives the sensors from the nonlinear
//! model, this kinematically consistent trajectory supplies the truth:
//! a horizontal circle of radius `R` flown at angular rate `ω`, a slow
//! altitude oscillation, and small roll/pitch oscillations with the heading
//! turning at `ω`. Everything (acceleration, Euler rates, body rates) is the
//! exact derivative, so sensor errors come from the sensor models only.

use helicon_model::frames::EulerTrig;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// The true kinematic state at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthSample {
    /// Time (s).
    pub t_s: f64,
    /// Position NED (m).
    pub pos_ned_m: Vector3<f64>,
    /// Velocity NED (m/s).
    pub vel_ned_m_s: Vector3<f64>,
    /// Acceleration NED (m/s²).
    pub acc_ned_m_s2: Vector3<f64>,
    /// 3-2-1 Euler angles (φ, θ, ψ) (rad), thesis (9.5); ψ unwrapped.
    pub euler_rad: Vector3<f64>,
    /// Body rates (p, q, r) (rad/s).
    pub omega_body_rad_s: Vector3<f64>,
}

impl TruthSample {
    /// Specific force in body axes `f = R_be (a − g)` (m/s²): what an ideal
    /// accelerometer at the centre of mass reads.
    pub fn specific_force_body(&self, gravity_m_s2: f64) -> Vector3<f64> {
        self.body_from_ned() * (self.acc_ned_m_s2 - Vector3::new(0.0, 0.0, gravity_m_s2))
    }

    /// The rotation `body_from_ned` = R_be of this attitude (9.5).
    pub fn body_from_ned(&self) -> nalgebra::Matrix3<f64> {
        let e = &self.euler_rad;
        EulerTrig::new(e.x, e.y, e.z).ned_from_body().transpose()
    }

    /// A NED vector expressed in body axes, `R_be v` (9.5).
    pub fn to_body(&self, v_ned: &Vector3<f64>) -> Vector3<f64> {
        self.body_from_ned() * v_ned
    }
}

/// Parameters of the scripted trajectory.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScriptedTrajectory {
    /// Circle radius `R` (m).
    pub radius_m: f64,
    /// Angular rate on the circle `ω` (rad/s); heading turns at the same rate.
    pub omega_rad_s: f64,
    /// Mean altitude (m, positive up; NED down = −altitude).
    pub altitude_m: f64,
    /// Altitude oscillation amplitude (m) at angular frequency `ω_h`.
    pub altitude_amplitude_m: f64,
    /// Altitude oscillation angular frequency `ω_h` (rad/s).
    pub altitude_omega_rad_s: f64,
    /// Roll amplitude (rad) at angular frequency `ω_φ`.
    pub roll_amplitude_rad: f64,
    /// Roll angular frequency `ω_φ` (rad/s).
    pub roll_omega_rad_s: f64,
    /// Pitch amplitude (rad) at angular frequency `ω_θ`.
    pub pitch_amplitude_rad: f64,
    /// Pitch angular frequency `ω_θ` (rad/s).
    pub pitch_omega_rad_s: f64,
}

impl Default for ScriptedTrajectory {
    /// A 15 m circle in 63 s at 10 m altitude with ±2 m climbs, ±0.15 rad roll
    /// and ±0.1 rad pitch oscillations.
    fn default() -> Self {
        Self {
            radius_m: 15.0,
            omega_rad_s: 0.1,
            altitude_m: 10.0,
            altitude_amplitude_m: 2.0,
            altitude_omega_rad_s: 0.3,
            roll_amplitude_rad: 0.15,
            roll_omega_rad_s: 0.5,
            pitch_amplitude_rad: 0.1,
            pitch_omega_rad_s: 0.35,
        }
    }
}

impl ScriptedTrajectory {
    /// The truth at time `t_s`.
    pub fn truth(&self, t_s: f64) -> TruthSample {
        let (r, w) = (self.radius_m, self.omega_rad_s);
        let (s, c) = (w * t_s).sin_cos();
        let (ah, wh) = (self.altitude_amplitude_m, self.altitude_omega_rad_s);
        let (sh, ch) = (wh * t_s).sin_cos();
        let pos = Vector3::new(r * s, r * (1.0 - c), -self.altitude_m - ah * sh);
        let vel = Vector3::new(r * w * c, r * w * s, -ah * wh * ch);
        let acc = Vector3::new(-r * w * w * s, r * w * w * c, ah * wh * wh * sh);
        let (a_phi, w_phi) = (self.roll_amplitude_rad, self.roll_omega_rad_s);
        let (a_th, w_th) = (self.pitch_amplitude_rad, self.pitch_omega_rad_s);
        let phi = a_phi * (w_phi * t_s).sin();
        let theta = a_th * (w_th * t_s + 0.5).sin();
        let psi = w * t_s;
        let phi_dot = a_phi * w_phi * (w_phi * t_s).cos();
        let theta_dot = a_th * w_th * (w_th * t_s + 0.5).cos();
        let psi_dot = w;
        // Inverse of (9.14): ω_body = P_eb⁻¹ Θ̇.
        let (sf, cf) = phi.sin_cos();
        let (st, ct) = theta.sin_cos();
        let omega = Vector3::new(
            phi_dot - psi_dot * st,
            theta_dot * cf + psi_dot * sf * ct,
            -theta_dot * sf + psi_dot * cf * ct,
        );
        TruthSample {
            t_s,
            pos_ned_m: pos,
            vel_ned_m_s: vel,
            acc_ned_m_s2: acc,
            euler_rad: Vector3::new(phi, theta, psi),
            omega_body_rad_s: omega,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use helicon_model::frames::euler_rates;

    #[test]
    fn derivatives_are_consistent() {
        let tr = ScriptedTrajectory::default();
        let h = 1e-5;
        for t in [0.0, 3.3, 17.0] {
            let (a, b, m) = (tr.truth(t - h), tr.truth(t + h), tr.truth(t));
            assert_relative_eq!(
                (b.pos_ned_m - a.pos_ned_m) / (2.0 * h),
                m.vel_ned_m_s,
                epsilon = 1e-7
            );
            assert_relative_eq!(
                (b.vel_ned_m_s - a.vel_ned_m_s) / (2.0 * h),
                m.acc_ned_m_s2,
                epsilon = 1e-7
            );
            let rates = euler_rates(m.euler_rad.x, m.euler_rad.y, &m.omega_body_rad_s);
            assert_relative_eq!(
                (b.euler_rad - a.euler_rad) / (2.0 * h),
                rates,
                epsilon = 1e-7
            );
        }
    }
}
