//! Rigid-body dynamics and kinematics, thesis (9.8), (9.14), (9.21), (9.22).

use crate::frames::{euler_rates, ned_from_body};
use nalgebra::Vector3;

/// Translational acceleration of the body velocity (9.21):
/// v̇ = F/M − ω × v (m/s², body axes), with `v` the inertial body velocity.
#[inline]
pub fn linear_accel(
    force_body_n: &Vector3<f64>,
    mass_kg: f64,
    v_body: &Vector3<f64>,
    omega_body: &Vector3<f64>,
) -> Vector3<f64> {
    force_body_n / mass_kg - omega_body.cross(v_body)
}

/// Angular acceleration (9.22) with a diagonal inertia:
/// ω̇ = I⁻¹(τ − ω × Iω) (rad/s²).
#[inline]
pub fn angular_accel(
    torque_body_nm: &Vector3<f64>,
    inertia_diag: &Vector3<f64>,
    omega_body: &Vector3<f64>,
) -> Vector3<f64> {
    let iw = inertia_diag.component_mul(omega_body);
    (torque_body_nm - omega_body.cross(&iw)).component_div(inertia_diag)
}

/// Position rate in NED (9.8): ṗ_ned = R_eb v_body.
#[inline]
pub fn position_rate(phi: f64, theta: f64, psi: f64, v_body: &Vector3<f64>) -> Vector3<f64> {
    ned_from_body(phi, theta, psi) * v_body
}

/// Euler-angle rates (9.14), re-exported for the block diagram.
#[inline]
pub fn attitude_rate(phi: f64, theta: f64, omega_body: &Vector3<f64>) -> Vector3<f64> {
    euler_rates(phi, theta, omega_body)
}
