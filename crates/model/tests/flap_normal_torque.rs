//! The body normal torque (6.37)–(6.40) in the `thesis` preset, off hover.
//!
//! MODEL.md §11 item 3: the thesis implementation dropped the body
//! angular-acceleration torques (6.36) and the hub normal acceleration hz̈ of
//! (6.40) from the flapping; the velocity-product part mb·(−hẋ·q + hẏ·p) of
//! (6.40) needs no acceleration and stays. At hover p = q = hẋ = hẏ = 0, so
//! Appendix E and the hover trim (12.10)/(12.11) cannot show it; off hover it
//! is a torque like any other.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::state::{State, ix};
use helicon_model::{Input, Model, Params, Preset};
use nalgebra::Vector3;

/// ä0 of the `thesis` preset at a state with p, q, r and hub velocities all
/// non-zero, against row 0 of ä + Dȧ + Ka = JΥ + Eλ + G (MODEL.md §6.3,
/// K1 = θt = 0 for the Bergen Twin) written out here by hand, with
/// G0 = −(Ω𝒜RQ/2)(μx p + μy q) + (mb/Ib)(−hẋ q + hẏ p).
///
/// Tolerance 1e-12 relative to the largest term of the sum (K00·a0 ≈ 2e2
/// rad/s²): the model's exact quadrature equals the closed form to round-off
/// (`flapping_quadrature_matches_closed_forms_at_random_states`). The (6.40)
/// velocity term here is 0.1·(−6.03·(−0.3) + (−2.96)·0.4) = 0.0625 rad/s², 2e8
/// times the tolerance, so the test fails with the term dropped.
#[test]
fn thesis_preset_a0_ddot_off_hover_keeps_the_6_40_velocity_products() {
    let params = Params::bergen_twin();
    let model = Model::new(params, Preset::Thesis.options());
    let mr = params.main_rotor;
    let g = params.geometry;
    assert_eq!(mr.pitch_flap_coupling, 0.0);
    assert_eq!(mr.twist_rad, 0.0);

    let mut x = State::zeros();
    x[ix::PHI] = 0.05;
    x[ix::THETA] = -0.04;
    x[ix::U] = 6.0;
    x[ix::V] = -3.0;
    x[ix::W] = 1.0;
    x[ix::P] = 0.4;
    x[ix::Q] = -0.3;
    x[ix::R] = 0.2;
    x[ix::A0] = 0.02;
    x[ix::A1] = 0.01;
    x[ix::B1] = -0.005;
    x[ix::A0_DOT] = 0.3;
    x[ix::A1_DOT] = -0.2;
    x[ix::B1_DOT] = 0.1;
    x[ix::A1SB] = 0.004;
    x[ix::B1SB] = -0.006;
    x[ix::THETA0] = 0.12;
    x[ix::A1_SWASH] = 0.01;
    x[ix::B1_SWASH] = -0.02;
    x[ix::THETA_TR] = 0.1;
    let (xd, aux) = model
        .derivative(&x, &Input::zeros(), &Vector3::zeros())
        .unwrap();

    // Constants of MODEL.md §6.3.
    let (om, r, e) = (mr.omega_rad_s, mr.radius_m, mr.hinge_offset_m);
    let (ib, mb, ks) = (
        mr.blade_inertia_kg_m2,
        mr.blade_mass_moment_kg_m,
        mr.spring_n_m_per_rad,
    );
    let a_cal = params.environment.rho_kg_m3 * mr.lift_slope_per_rad * mr.chord_m / (2.0 * ib);
    let l = r - e;
    let m1 = l.powi(2) / 2.0;
    let m2 = l.powi(3) / 3.0;
    let m3 = l.powi(4) / 4.0;
    let pp = e * m2 + m3;
    let qq = e * m1 + m2;
    let ss = e * e * m1 + 2.0 * e * m2 + m3;

    // Hub velocities (D.4)–(D.5) (no wind: aerodynamic = inertial) and μ.
    let (p, q, rr) = (x[ix::P], x[ix::Q], x[ix::R]);
    let hx = x[ix::U] - q * g.kappa_v_m;
    let hy = x[ix::V] + p * g.kappa_v_m - rr * g.kappa_h_m;
    let (mx, my) = (hx / (om * r), hy / (om * r));
    // Υmr by Bell-Hiller mixing (4.3).
    let ups0 = x[ix::THETA0];
    let ups1 = mr.bell_factor * x[ix::A1_SWASH] - mr.hiller_factor * x[ix::B1SB];
    let ups2 = mr.bell_factor * x[ix::B1_SWASH] - mr.hiller_factor * x[ix::A1SB];
    let lambda = aux.lambda_mr_flap;

    let o2a = om * om * a_cal;
    let terms = [
        -om * a_cal * pp * x[ix::A0_DOT],
        -om * a_cal * r * m2 * my / 2.0 * x[ix::A1_DOT],
        -om * a_cal * r * m2 * mx / 2.0 * x[ix::B1_DOT],
        -(om * om * (1.0 + e * mb / ib) + ks / ib) * x[ix::A0],
        o2a * r * e * m1 * mx / 2.0 * x[ix::A1],
        -o2a * r * e * m1 * my / 2.0 * x[ix::B1],
        o2a * (r * r * m1 * (mx * mx + my * my) / 2.0 + ss) * ups0,
        o2a * r * qq * my * ups1,
        -o2a * r * qq * mx * ups2,
        o2a * r * qq * lambda,
        -(om * a_cal * r * qq / 2.0) * (mx * p + my * q),
        (mb / ib) * (-hx * q + hy * p),
    ];
    let expected: f64 = terms.iter().sum();
    let scale = terms.iter().fold(0.0_f64, |m, t| m.max(t.abs()));
    let got = xd[ix::A0_DOT];
    assert!(
        (got - expected).abs() <= 1e-12 * scale,
        "a0_ddot {got} vs closed form {expected} (scale {scale})"
    );
    // The (6.40) velocity term is far above the tolerance.
    assert!(terms[11].abs() > 1e6 * 1e-12 * scale, "{}", terms[11]);
}
