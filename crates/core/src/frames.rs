//! Frames and rotations (thesis chapter 9).
//!
//! Earth frame: NED. Body frame: FRD (x nose, y right, z down along the shaft).
//! Attitude: 3-2-1 (yaw ψ, pitch θ, roll φ) Euler angles, thesis (9.5).
//! Rotations are named by what they map: `ned_from_body` takes body-frame
//! components to NED components (the thesis's R_eb, (9.5)/(9.8)), and
//! `body_from_ned` is its transpose (R_be).

use nalgebra::{Matrix3, Vector3};

/// Wrap an angle to (−π, π].
pub fn wrap_pi(a: f64) -> f64 {
    let two_pi = 2.0 * std::f64::consts::PI;
    let mut w = a % two_pi;
    if w > std::f64::consts::PI {
        w -= two_pi;
    } else if w <= -std::f64::consts::PI {
        w += two_pi;
    }
    w
}

/// Sines and cosines of a 3-2-1 Euler attitude, computed once and shared by
/// the rotations, the gravity vector and the Euler-rate kinematics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EulerTrig {
    /// sin φ, cos φ.
    pub sf: f64,
    /// cos φ.
    pub cf: f64,
    /// sin θ.
    pub st: f64,
    /// cos θ.
    pub ct: f64,
    /// sin ψ.
    pub sp: f64,
    /// cos ψ.
    pub cp: f64,
}

impl EulerTrig {
    /// From roll φ, pitch θ, yaw ψ (rad).
    #[inline]
    pub fn new(phi: f64, theta: f64, psi: f64) -> Self {
        let (sf, cf) = phi.sin_cos();
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = psi.sin_cos();
        EulerTrig {
            sf,
            cf,
            st,
            ct,
            sp,
            cp,
        }
    }

    /// `ned_from_body` = R_eb(φ, θ, ψ), thesis (9.5): v_ned = R_eb · v_body.
    #[inline]
    pub fn ned_from_body(&self) -> Matrix3<f64> {
        let EulerTrig {
            sf,
            cf,
            st,
            ct,
            sp,
            cp,
        } = *self;
        Matrix3::new(
            ct * cp,
            sf * st * cp - cf * sp,
            cf * st * cp + sf * sp,
            ct * sp,
            sf * st * sp + cf * cp,
            cf * st * sp - sf * cp,
            -st,
            sf * ct,
            cf * ct,
        )
    }

    /// Euler-angle rates (9.14): Θ̇ = P_eb · ω_body (singular at cos θ = 0).
    #[inline]
    pub fn euler_rates(&self, omega_body: &Vector3<f64>) -> Vector3<f64> {
        let EulerTrig { sf, cf, st, ct, .. } = *self;
        let tt = st / ct;
        let (p, q, r) = (omega_body.x, omega_body.y, omega_body.z);
        Vector3::new(
            p + sf * tt * q + cf * tt * r,
            cf * q - sf * r,
            (sf * q + cf * r) / ct,
        )
    }

    /// Gravity in body axes (8.3): g · [−sin θ, sin φ cos θ, cos φ cos θ].
    #[inline]
    pub fn gravity_body(&self, g_m_s2: f64) -> Vector3<f64> {
        Vector3::new(
            -g_m_s2 * self.st,
            g_m_s2 * self.sf * self.ct,
            g_m_s2 * self.cf * self.ct,
        )
    }
}

/// `ned_from_body` = R_eb(φ, θ, ψ), thesis (9.5): v_ned = R_eb · v_body.
pub fn ned_from_body(phi: f64, theta: f64, psi: f64) -> Matrix3<f64> {
    EulerTrig::new(phi, theta, psi).ned_from_body()
}

/// `body_from_ned` = R_be = R_ebᵀ, thesis (9.5): v_body = R_be · v_ned.
pub fn body_from_ned(phi: f64, theta: f64, psi: f64) -> Matrix3<f64> {
    ned_from_body(phi, theta, psi).transpose()
}

/// Euler-angle rates from body rates, thesis (9.14): Θ̇ = P_eb · ω_body.
///
/// Singular at θ = ±π/2 (the 3-2-1 gimbal lock); callers that may reach it
/// must check `cos θ` themselves.
pub fn euler_rates(phi: f64, theta: f64, omega_body: &Vector3<f64>) -> Vector3<f64> {
    EulerTrig::new(phi, 0.0, 0.0)
        .with_theta(theta)
        .euler_rates(omega_body)
}

/// Gravity in body axes, thesis (8.3): g_body = R_be · [0, 0, g] =
/// g · [−sin θ, sin φ cos θ, cos φ cos θ] (m/s²).
pub fn gravity_body(phi: f64, theta: f64, g_m_s2: f64) -> Vector3<f64> {
    EulerTrig::new(phi, 0.0, 0.0)
        .with_theta(theta)
        .gravity_body(g_m_s2)
}

impl EulerTrig {
    fn with_theta(mut self, theta: f64) -> Self {
        let (st, ct) = theta.sin_cos();
        self.st = st;
        self.ct = ct;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn rotation_is_orthonormal_and_matches_elementary_product() {
        let (phi, theta, psi) = (0.3, -0.4, 2.1);
        let r = ned_from_body(phi, theta, psi);
        assert_relative_eq!(r * r.transpose(), Matrix3::identity(), epsilon = 1e-15);
        assert_relative_eq!(r.determinant(), 1.0, epsilon = 1e-15);
        // R_eb = Rz(psi) Ry(theta) Rx(phi) with active rotations.
        let rz = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), psi);
        let ry = nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), theta);
        let rx = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), phi);
        let expected = (rz * ry * rx).into_inner();
        assert_relative_eq!(r, expected, epsilon = 1e-15);
    }

    #[test]
    fn gravity_body_is_rotated_ned_gravity() {
        let (phi, theta, psi) = (0.2, 0.5, -1.0);
        let g = body_from_ned(phi, theta, psi) * Vector3::new(0.0, 0.0, 9.82);
        assert_relative_eq!(g, gravity_body(phi, theta, 9.82), epsilon = 1e-14);
    }

    #[test]
    fn euler_rates_match_finite_difference_of_rotation() {
        // d/dt R_eb = R_eb [ω]x ; check Θ̇ from (9.14) reproduces it.
        let (phi, theta, psi) = (0.3, 0.2, 0.7);
        let w = Vector3::new(0.4, -0.3, 0.9);
        let rates = euler_rates(phi, theta, &w);
        let h = 1e-6;
        let rp = ned_from_body(phi + h * rates.x, theta + h * rates.y, psi + h * rates.z);
        let rm = ned_from_body(phi - h * rates.x, theta - h * rates.y, psi - h * rates.z);
        let rdot = (rp - rm) / (2.0 * h);
        let r = ned_from_body(phi, theta, psi);
        let expected = r * w.cross_matrix();
        assert_relative_eq!(rdot, expected, epsilon = 1e-8);
    }
}
