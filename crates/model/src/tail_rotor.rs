//! Tail rotor, thesis (7.37)–(7.56) and (D.10)–(D.15), (D.39)–(D.43), with the
//! corrections of MODEL.md §9: the leading minus sign of (D.39), lost in the
//! extracted text, is restored from (7.47) (tFy = −7.85 N in hover), and the
//! torque factor is Rtr² as dimensions and (7.50) require.
//!
//! The tail-rotor frame is parallel to the body frame; its thrust points to
//! −y. The rotor-plane rates are the body rates p and r.

use crate::inflow::InflowProblem;
use crate::params::Params;
use nalgebra::Vector3;

/// Precomputed tail-rotor constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TailRotorConsts {
    /// Ωtr = G·Ω (rad/s).
    pub omega_tr: f64,
    /// Ωtr·Rtr (m/s).
    pub tip_speed: f64,
    /// (ρ/2) Cls,tr btr ctr Rtr (Ωtr Rtr)² (N).
    pub k_force: f64,
    /// ρ π Rtr² (Ωtr Rtr)² (N): C_T = −tFy / this, (7.53)/(D.40).
    pub ct_denominator: f64,
    /// Cd,tr / (4 Cls,tr).
    pub cd_ratio: f64,
    /// Rtr (m).
    pub radius: f64,
}

impl TailRotorConsts {
    /// From parameters.
    pub fn new(p: &Params) -> Self {
        let tr = &p.tail_rotor;
        let omega_tr = p.omega_tr_rad_s();
        let tip = omega_tr * tr.radius_m;
        let rho = p.environment.rho_kg_m3;
        TailRotorConsts {
            omega_tr,
            tip_speed: tip,
            k_force: 0.5
                * rho
                * tr.lift_slope_per_rad
                * tr.blades
                * tr.chord_m
                * tr.radius_m
                * tip
                * tip,
            ct_denominator: rho * std::f64::consts::PI * tr.radius_m * tr.radius_m * tip * tip,
            cd_ratio: tr.drag_coefficient / (4.0 * tr.lift_slope_per_rad),
            radius: tr.radius_m,
        }
    }
}

/// Tail-rotor advance ratios [μx,tr, μy,tr, μz,tr], (D.13)–(D.15), from the
/// tail-rotor-frame air velocity (m/s).
pub fn advance_ratios(c: &TailRotorConsts, v_tr_m_s: &Vector3<f64>) -> Vector3<f64> {
    v_tr_m_s / c.tip_speed
}

/// The λ-independent part of the bracket of (D.39):
/// θtr(1/3 + (μx,tr² + μz,tr²)/2) + (μx,tr p + μz,tr r)/(4Ωtr).
fn thrust_bracket0(c: &TailRotorConsts, mu: &Vector3<f64>, theta_tr: f64, p: f64, r: f64) -> f64 {
    let inplane2 = mu.x * mu.x + mu.z * mu.z;
    theta_tr * (1.0 / 3.0 + inplane2 / 2.0) + (mu.x * p + mu.z * r) / (4.0 * c.omega_tr)
}

/// The inflow problem (7.56)/(D.41) at collective θtr and body rates p, r:
/// C_T,tr(λ) from (D.39)/(D.40) is affine in λ.
pub fn inflow_problem(
    c: &TailRotorConsts,
    mu: &Vector3<f64>,
    theta_tr: f64,
    p: f64,
    r: f64,
) -> InflowProblem {
    let kk = c.k_force / c.ct_denominator;
    InflowProblem {
        mu_inplane2: mu.x * mu.x + mu.z * mu.z,
        mu_axial: mu.y,
        ct0: kk * thrust_bracket0(c, mu, theta_tr, p, r),
        ct1: kk * 0.5,
    }
}

/// Tail-rotor thrust tFy (N), (D.39) with the restored minus sign.
pub fn thrust_y(
    c: &TailRotorConsts,
    mu: &Vector3<f64>,
    theta_tr: f64,
    p: f64,
    r: f64,
    lambda: f64,
) -> f64 {
    -c.k_force * (lambda / 2.0 + thrust_bracket0(c, mu, theta_tr, p, r))
}

/// Tail-rotor torque about its shaft tτy (N·m), (D.42) with the Rtr² factor.
pub fn torque_y(
    c: &TailRotorConsts,
    mu: &Vector3<f64>,
    theta_tr: f64,
    p: f64,
    r: f64,
    lambda: f64,
) -> f64 {
    let w = c.omega_tr;
    c.k_force
        * c.radius
        * (c.cd_ratio * (-mu.z * mu.z - mu.x * mu.x - 1.0)
            + theta_tr / 6.0 * (mu.x * p / w + mu.z * r / w + 2.0 * lambda)
            + lambda * lambda / 2.0
            + (r * r + p * p) / (8.0 * w * w))
}

/// Body-frame tail-rotor torque (7.51)/(7.52)/(D.43):
/// [tFy κv,tr, tτy, −tFy κh,tr].
pub fn body_torque(thrust_y: f64, torque_y: f64, kappa_v_tr: f64, kappa_h_tr: f64) -> Vector3<f64> {
    Vector3::new(thrust_y * kappa_v_tr, torque_y, -thrust_y * kappa_h_tr)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direct blade-element quadrature of the tail-rotor thrust (7.47)/(7.48):
    /// dL along the thrust axis, blades from 0 to Rtr (no hinge offset).
    #[test]
    fn closed_form_thrust_matches_blade_element_quadrature() {
        let p = Params::bergen_twin();
        let c = TailRotorConsts::new(&p);
        let mu = Vector3::new(0.03, -0.01, 0.02);
        let (theta, pr, rr, lam) = (0.12, 0.3, -0.5, -0.04);
        // Blade element: Ut = Ωr + ΩR(μx sinΨ − μz cosΨ), Up = ΩRλ + r(p sinΨ − r cosΨ)

        // (the azimuth origin of the tail rotor is not drawn in the thesis; this one makes
        // the rate cross term average to +(μx p + μz r)/4 as (D.39) prints).
        let n_psi = 64;
        let n_r = 400;
        let tr = &p.tail_rotor;
        let rho = p.environment.rho_kg_m3;
        let mut lift = 0.0;
        for j in 0..n_psi {
            let psi = 2.0 * std::f64::consts::PI * j as f64 / n_psi as f64;
            let (s, co) = psi.sin_cos();
            for i in 0..n_r {
                let r = tr.radius_m * (i as f64 + 0.5) / n_r as f64;
                let ut = c.omega_tr * r + c.tip_speed * (mu.x * s - mu.z * co);
                let up = c.tip_speed * lam + r * (pr * s - rr * co);
                let dl =
                    0.5 * rho * tr.chord_m * tr.lift_slope_per_rad * (ut * ut * theta + ut * up);
                lift += dl * tr.radius_m / n_r as f64 / n_psi as f64;
            }
        }
        let closed = thrust_y(&c, &mu, theta, pr, rr, lam);
        // midpoint rule, 400 panels on a quadratic: relative error ~ 1/(12·400²) = 5e-7
        assert!(
            (-lift * tr.blades - closed).abs() < 1e-5 * closed.abs(),
            "{} vs {closed}",
            -lift * tr.blades
        );
    }

    #[test]
    fn hover_thrust_balances_yaw_torque_order_of_magnitude() {
        // Thesis trim: θtr = 0.111, λtr = −0.0468 → tFy ≈ −7.85 N (MODEL.md §9).
        let p = Params::bergen_twin();
        let c = TailRotorConsts::new(&p);
        let mu = Vector3::zeros();
        let f = thrust_y(&c, &mu, 0.111, 0.0, 0.0, -0.0468);
        assert!((f + 7.85).abs() < 0.1, "{f}");
        // and the converged inflow at that collective is the printed λtr
        let sol = inflow_problem(&c, &mu, 0.111433, 0.0, 0.0).solve().unwrap();
        assert!((sol.lambda + 0.04678).abs() < 2e-4, "{}", sol.lambda);
    }
}
