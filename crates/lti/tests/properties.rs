//! Property tests (proptest) and named regression cases.

#![allow(clippy::unwrap_used)] // test helpers outside #[test] fns

mod common;

use helicon_lti::*;
use nalgebra::DMatrix;
use proptest::prelude::*;

/// A random system: A with entries in [−1, 1] scaled to spectral radius `rho` (some > 1,
/// i.e. open-loop unstable), B, Q = CᵀC (PSD, rank p ≤ n), R = DᵀD + 0.1 I (PD).
fn system() -> impl Strategy<Value = (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>)> {
    (1usize..12, 1usize..4, 1usize..12, 0.2f64..1.5).prop_flat_map(|(n, m, p, rho)| {
        let p = p.min(n);
        (
            proptest::collection::vec(-1.0f64..1.0, n * n),
            proptest::collection::vec(-1.0f64..1.0, n * m),
            proptest::collection::vec(-1.0f64..1.0, p * n),
            proptest::collection::vec(-1.0f64..1.0, m * m),
        )
            .prop_map(move |(a, b, c, d)| {
                let a = DMatrix::from_vec(n, n, a);
                let r0 = spectral_radius(&a).unwrap().max(1e-3);
                let a = a * (rho / r0);
                let b = DMatrix::from_vec(n, m, b);
                let c = DMatrix::from_vec(p, n, c);
                let d = DMatrix::from_vec(m, m, d);
                let q = c.transpose() * c;
                let r = d.transpose() * d + DMatrix::identity(m, m) * 0.1;
                (a, b, q, r)
            })
    })
}

fn min_eig_sym(x: &DMatrix<f64>) -> f64 {
    nalgebra::SymmetricEigen::new(x.clone())
        .eigenvalues
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Residual < 1e-10, X symmetric PSD, closed loop stable. Random draws may be
    /// (numerically) non-stabilizable/non-detectable: then a typed error is the correct
    /// answer, never a panic or a wrong X.
    #[test]
    fn prop_dare_residual_psd_stable((a, b, q, r) in system()) {
        match dlqr(&a, &b, &q, &r, None) {
            Ok(l) => {
                let s = dare(&a, &b, &q, &r, None).unwrap();
                prop_assert!(s.residual < 1e-10, "residual {:e}", s.residual);
                prop_assert!((&s.x - s.x.transpose()).amax() <= 1e-14 * s.x.amax().max(1.0));
                // PSD to rounding: λ_min ≥ −1e-10 ‖X‖.
                prop_assert!(min_eig_sym(&s.x) >= -1e-10 * s.x.norm().max(1.0));
                prop_assert!(l.poles.iter().all(|z| z.norm() < 1.0));
            }
            Err(LtiError::NotStabilizable { .. } | LtiError::NotDetectable { .. }) => {}
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
    }

    /// Pincer: spectral radius of Φ − ΓK below 1/α.
    #[test]
    fn prop_pincer_radius((a, b, q, r) in system(), alpha in 1.0f64..1.3) {
        match dlqr_pincer(&a, &b, &q, &r, None, alpha) {
            Ok(l) => {
                prop_assert!(l.residual < 1e-10);
                let rho = l.poles.iter().map(|z| z.norm()).fold(0.0, f64::max);
                prop_assert!(rho < 1.0 / alpha, "rho {rho} alpha {alpha}");
            }
            Err(LtiError::NotStabilizable { .. } | LtiError::NotDetectable { .. }) => {}
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
    }

    /// Kalman duality: L = Φ M, P symmetric PSD, Φ − LC stable.
    #[test]
    fn prop_kalman((a, b, q, r) in system()) {
        // Use Bᵀ as C (p = m outputs) and Q as process noise (G = I).
        let c = b.transpose();
        match dlqe(&a, None, &c, &q, &r) {
            Ok(k) => {
                prop_assert!(k.residual < 1e-10);
                prop_assert!((&k.l - &a * &k.m).amax() <= 1e-12 * k.l.amax().max(1.0));
                prop_assert!(min_eig_sym(&k.p) >= -1e-10 * k.p.norm().max(1.0));
                prop_assert!(k.poles.iter().all(|z| z.norm() < 1.0));
            }
            Err(LtiError::NotStabilizable { .. } | LtiError::NotDetectable { .. }) => {}
            Err(e) => prop_assert!(false, "unexpected error {e}"),
        }
    }

    /// expm reconstruction: e^{A} e^{−A} = I, and c2d of a diagonal system is exact.
    #[test]
    fn prop_expm_inverse(v in proptest::collection::vec(-3.0f64..3.0, 25)) {
        let a = DMatrix::from_vec(5, 5, v);
        let e = expm(&a).unwrap();
        let ei = expm(&(-&a)).unwrap();
        let err = (&e * &ei - DMatrix::<f64>::identity(5, 5)).amax();
        // Conditioning of e^{±A} multiplies rounding by ‖e^A‖‖e^{−A}‖.
        let kappa = e.norm() * ei.norm();
        prop_assert!(err < 1e-13 * kappa, "err {err:e} kappa {kappa:e}");
    }
}

/// nalgebra's Schur stagnated on the integral-augmented thesis system [[Φ, 0], [−Hs, I]]
/// (exactly reducible, five eigenvalues at 1); `eigenvalues` must fall back and succeed.
#[test]
fn regress_schur_integral_augmented_thesis() {
    let (a, b) = common::thesis_ab();
    let (phi, gamma) = c2d(&a, &b, 1.0 / 400.0).unwrap();
    let hs = DMatrix::from_fn(4, 27, |i, j| if j == i + 2 { 1.0 } else { 0.0 });
    let aug = augment_integral(&phi, &gamma, &hs).unwrap();
    let ev = eigenvalues(&aug.phi).unwrap();
    assert_eq!(ev.len(), 31);
    // Four integrator poles plus the ψ integrator sit at z = 1. The ψ integrator and its
    // output integrator form a 2×2 Jordan block, so rounding moves them by ~√ε·‖Φ‖ ≈ 1e-8;
    // the nearest genuine plant pole (the slow pair) is 2.5e-4 away. Threshold 1e-6.
    let mut d: Vec<f64> = ev
        .iter()
        .map(|z| (*z - nalgebra::Complex::new(1.0, 0.0)).norm())
        .collect();
    d.sort_by(f64::total_cmp);
    println!("distances to 1: {:?}", &d[..7]);
    let near_one = d.iter().filter(|&&x| x < 1e-6).count();
    assert_eq!(near_one, 5);
}

/// Bad input gives typed errors, not panics.
#[test]
fn regress_dare_input_errors() {
    let a = common::mat(2, 2, &[1.0, 1.0, 0.0, 1.0]);
    let b = common::mat(2, 1, &[0.0, 1.0]);
    let q = DMatrix::identity(2, 2);
    let r = common::mat(1, 1, &[1.0]);
    assert!(matches!(
        dare(&a, &b, &q, &common::mat(1, 1, &[0.0]), None),
        Err(LtiError::NotPositiveDefinite { .. })
    ));
    assert!(matches!(
        dare(&a, &b, &common::mat(2, 2, &[1.0, 2.0, 0.0, 1.0]), &r, None),
        Err(LtiError::NotSymmetric { .. })
    ));
    assert!(matches!(
        dare(&a, &b, &(-&q), &r, None),
        Err(LtiError::NotPositiveSemidefinite { .. })
    ));
    assert!(matches!(
        dare(&a, &common::mat(3, 1, &[0.0, 1.0, 0.0]), &q, &r, None),
        Err(LtiError::Dimension { .. })
    ));
    let mut an = a.clone();
    an[(1, 1)] = f64::NAN;
    assert!(matches!(
        dare(&an, &b, &q, &r, None),
        Err(LtiError::NonFinite { .. })
    ));
    // Unstable mode (z = 2) not reachable from B: not stabilizable.
    let a2 = common::mat(2, 2, &[2.0, 0.0, 0.0, 0.5]);
    let b2 = common::mat(2, 1, &[0.0, 1.0]);
    assert!(matches!(
        dare(&a2, &b2, &q, &r, None),
        Err(LtiError::NotStabilizable { .. })
    ));
    // Unstable mode (z = 2) invisible in Q: not detectable. Strict mode rejects it up
    // front. Without strict mode, SDA (H₀ = Q, H_k = the 2^k-horizon cost, increasing)
    // converges to the minimal PSD solution, which leaves the mode unstable; the failed
    // stability check is then diagnosed as NotDetectable as well.
    let a3 = common::mat(2, 2, &[2.0, 0.0, 0.0, 0.5]);
    let b3 = DMatrix::identity(2, 2);
    let q3 = common::mat(2, 2, &[0.0, 0.0, 0.0, 1.0]);
    let strict = DareOptions {
        check_structure: true,
        ..DareOptions::default()
    };
    assert!(matches!(
        dare_with(&a3, &b3, &q3, &DMatrix::identity(2, 2), None, &strict),
        Err(LtiError::NotDetectable { .. })
    ));
    assert!(matches!(
        dare(&a3, &b3, &q3, &DMatrix::identity(2, 2), None),
        Err(LtiError::NotDetectable { .. })
    ));
    // Unobservable mode ON the unit circle: no stabilizing solution exists either.
    let a4 = common::mat(2, 2, &[1.0, 0.0, 0.0, 0.5]);
    assert!(matches!(
        dare(&a4, &b3, &q3, &DMatrix::identity(2, 2), None),
        Err(LtiError::NotDetectable { .. })
    ));
    // Same for strict mode on a non-stabilizable problem.
    assert!(matches!(
        dare_with(&a2, &b2, &q, &r, None, &strict),
        Err(LtiError::NotStabilizable { .. })
    ));
    // Joint weight [[Q, N], [Nᵀ, R]] indefinite.
    let n = common::mat(2, 1, &[5.0, 0.0]);
    assert!(matches!(
        dare(&a, &b, &q, &r, Some(&n)),
        Err(LtiError::NotPositiveSemidefinite { .. })
    ));
    assert!(matches!(
        dlqr_pincer(&a, &b, &q, &r, None, 0.5),
        Err(LtiError::Parameter { .. })
    ));
}

/// Thesis (14.25): α = 100^{0.0025/5} = 1.0023 (printed to 4 decimals), radius 0.9977.
#[test]
fn regress_alpha_from_settling_time_thesis() {
    let a = alpha_from_settling_time(1.0 / 400.0, 5.0).unwrap();
    assert!((a - 1.0023).abs() < 0.5e-4);
    assert!((1.0 / a - 0.9977).abs() < 0.5e-4);
}

/// Bryson's rule (14.15)/(14.16) and the (14.27) weights.
#[test]
fn regress_bryson_thesis_q2() {
    let q2 = bryson(&[0.1, 0.7, 0.7, 0.04]).unwrap();
    let expect = [100.0, 1.0 / 0.49, 1.0 / 0.49, 625.0];
    for i in 0..4 {
        assert!((q2[(i, i)] - expect[i]).abs() < 1e-12 * expect[i]);
    }
    assert!(bryson(&[0.0]).is_err());
}

/// The Newton (Hewer) refinement works: stop SDA early (relative change 0.3: a few doubling
/// steps short, residual ~1e-4) and let the automatic refinement (residual above
/// 1e-12) repair it; the result must match the fully converged solution.
#[test]
fn newton_refinement_repairs_early_stopped_sda() {
    let (a, b) = common::thesis_ab();
    let (phi, gamma) = c2d(&a, &b, 1.0 / 400.0).unwrap();
    let hs = DMatrix::from_fn(4, 27, |i, j| if j == i + 2 { 1.0 } else { 0.0 });
    let (q1, r) = bryson_weights(&hs, &[3.0; 4], &[0.1, 0.7, 0.7, 0.04], 10.0).unwrap();
    let full = dare(&phi, &gamma, &q1, &r, None).unwrap();
    let early = DareOptions {
        tol: 0.3,
        refine_above: f64::INFINITY,
        ..DareOptions::default()
    };
    let rough = dare_with(&phi, &gamma, &q1, &r, None, &early).unwrap();
    assert!(
        rough.residual > 1e-10,
        "early stop should leave a visible residual: {:e}",
        rough.residual
    );
    let fix = DareOptions {
        tol: 0.3,
        ..DareOptions::default()
    };
    let refined = dare_with(&phi, &gamma, &q1, &r, None, &fix).unwrap();
    println!(
        "early residual {:e} → refined {:e} with {} Newton steps",
        rough.residual, refined.residual, refined.newton_steps
    );
    assert!(refined.newton_steps >= 1);
    assert!(refined.residual < 1e-13, "{:e}", refined.residual);
    assert!(common::rel_err(&refined.x, &full.x) < 1e-11);
}
