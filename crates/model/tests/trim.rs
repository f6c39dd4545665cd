//! Trim (12.2)–(12.9) against the thesis hover trim (12.10)/(12.11), and
//! across the flight envelope.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::state::{REDUCED_OFFSET, expand, ix};
use helicon_model::trim::{TrimOptions, TrimTarget, sweep, trim};
use helicon_model::{Model, Preset};
use nalgebra::Vector3;

#[test]
fn thesis_hover_trim_reproduces_12_10_and_12_11() {
    let model = Model::bergen_twin(Preset::Thesis);
    let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
    println!("iterations {} history {:?}", t.iterations, t.history);
    assert!(t.residual_norm < 1e-10);
    assert!(t.beyond_saturation.is_empty());
    let o = REDUCED_OFFSET;
    // (value, printed) — printed to 3 significant digits, rounded or truncated.
    let checks = [
        ("S_col", t.u[0], 0.185_f64),
        ("S_lat", t.u[1], 2.94e-4),
        ("S_lon", t.u[2], -8.20e-4),
        ("S_tr", t.u[3], 0.159),
        ("phi", t.x[ix::PHI - o], 5.73e-2),
        ("theta", t.x[ix::THETA - o], -6.58e-4),
        ("a0", t.x[ix::A0 - o], 1.60e-2),
        ("a1", t.x[ix::A1 - o], 6.41e-4),
        ("a1sb", t.x[ix::A1SB - o], 5.74e-4),
        ("b1sb", t.x[ix::B1SB - o], -2.06e-4),
        ("theta0", t.x[ix::THETA0 - o], 0.129),
        ("A1", t.x[ix::A1_SWASH - o], 2.06e-4),
        ("B1", t.x[ix::B1_SWASH - o], -5.74e-4),
        ("theta_tr", t.x[ix::THETA_TR - o], 0.111),
        ("lambda_mr", t.aux.lambda_mr, -4.15e-2),
        ("lambda_tr", t.aux.lambda_tr, -4.68e-2),
    ];
    for (name, ours, printed) in checks {
        // within the printed 3 significant digits (rounded or truncated), or 0.3 %
        let mag = 10f64.powf(printed.abs().log10().floor() - 2.0);
        let rounded = (ours / mag).round() * mag;
        let truncated = (ours / mag).trunc() * mag;
        let ok = (rounded - printed).abs() < 0.5 * mag
            || (truncated - printed).abs() < 0.5 * mag
            || (ours - printed).abs() <= 0.003 * printed.abs();
        println!("{name:>10}: ours {ours:>12.6e} printed {printed:>10.3e}");
        assert!(ok, "{name}: ours {ours:e} printed {printed:e}");
    }
    // b1 is a near-cancellation quantity: printed 2.16e-6, independent reading
    // 2.32e-6 (MODEL.md §12). Its size is set by differences of ~1e-3 terms, so
    // we check only the order of magnitude and sign.
    let b1 = t.x[ix::B1 - o];
    assert!(b1 > 1e-6 && b1 < 4e-6, "b1 = {b1:e}");
}

#[test]
fn starting_at_a_trim_the_derivative_vanishes() {
    for preset in [Preset::Thesis, Preset::Physical] {
        let model = Model::bergen_twin(preset);
        let target = TrimTarget {
            velocity_ned_m_s: Vector3::new(3.0, -1.0, 0.5),
            yaw_rad: 0.7,
            wind_ned_m_s: Vector3::zeros(),
        };
        let t = trim(&model, &target, &TrimOptions::default()).unwrap();
        let (xd, _) = model
            .derivative(&expand(&t.x, [0.0; 3]), &t.u, &Vector3::zeros())
            .unwrap();
        // all 27 dynamic rows below 1e-9; position rates equal the target velocity
        for i in 3..30 {
            assert!(
                xd[i].abs() < 1e-9,
                "{preset:?} {}: {}",
                helicon_model::STATE_NAMES[i],
                xd[i]
            );
        }
        assert!((Vector3::new(xd[0], xd[1], xd[2]) - target.velocity_ned_m_s).norm() < 1e-9);
    }
}

#[test]
fn forward_sweep_0_to_15_converges_continuously() {
    let model = Model::bergen_twin(Preset::Physical);
    let targets: Vec<TrimTarget> = (0..=30)
        .map(|k| TrimTarget {
            velocity_ned_m_s: Vector3::new(0.5 * k as f64, 0.0, 0.0),
            yaw_rad: 0.0,
            wind_ned_m_s: Vector3::zeros(),
        })
        .collect();
    let res = sweep(&model, &targets, &TrimOptions::default());
    let mut prev: Option<helicon_model::trim::Trim> = None;
    for (k, r) in res.into_iter().enumerate() {
        let t = r.unwrap_or_else(|e| panic!("{} m/s: {e}", 0.5 * k as f64));
        assert!(t.residual_norm < 1e-9);
        if let Some(p) = &prev {
            // continuity: no input or attitude jumps between 0.5 m/s neighbours
            assert!(
                (t.u - p.u).amax() < 0.02,
                "jump in inputs at {} m/s",
                0.5 * k as f64
            );
            assert!(
                (t.x[1] - p.x[1]).abs() < 0.02,
                "jump in pitch at {} m/s",
                0.5 * k as f64
            );
        }
        prev = Some(t);
    }
}

#[test]
fn open_loop_drift_follows_the_unstable_modes() {
    // Issue 3: an open-loop run from (near) the trim drifts only through the
    // unstable modes. Start 1e-6 off the trim along a generic direction; after
    // 30 s the stable modes have decayed and the deviation must equal the
    // linear prediction exp(A t)·δx0 (dominated by the unstable modes) to a
    // few %, and grow at the rate of the largest unstable real part.
    use helicon_model::InflowMode;
    use helicon_model::linearize::linearize;
    for preset in [Preset::Thesis, Preset::Physical] {
        let model = Model::bergen_twin(preset);
        let t = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
        let lm = linearize(&model, &t.x, &t.u, &Vector3::zeros(), InflowMode::Converged).unwrap();
        let dx0 =
            helicon_model::ReducedState::from_fn(|i, _| 1e-6 * ((i as f64 * 0.7).sin() + 0.2));
        let mut x = expand(&(t.x + dx0), [0.0; 3]);
        let dt = 1.0 / 400.0;
        let t_end = 30.0;
        for _ in 0..(t_end / dt) as usize {
            x = model.step(&x, &t.u, &Vector3::zeros(), dt).unwrap().0;
        }
        let dx_nl = helicon_model::state::reduce(&x) - t.x;
        let phi = helicon_lti::expm(&(lm.a_dyn() * t_end)).unwrap();
        let dx_lin = phi * nalgebra::DVector::from_column_slice(dx0.as_slice());
        let err = (nalgebra::DVector::from_column_slice(dx_nl.as_slice()) - &dx_lin).norm()
            / dx_lin.norm();
        let growth = dx_lin.norm() / dx0.norm();
        let sigma = lm
            .poles()
            .unwrap()
            .iter()
            .map(|p| p.value.re)
            .fold(f64::MIN, f64::max);
        println!(
            "{preset:?}: |dx(30s)|/|dx0| = {growth:.1}, max Re(s) = {sigma:.4}, nonlinear vs linear {err:.2e}"
        );
        assert!(err < 0.02, "{preset:?}: {err}");
        // the growth is that of the unstable modes (between e^{σt}/50 and 50·e^{σt}:
        // the projection of δx0 onto them sets the constant)
        let g = (sigma * t_end).exp();
        assert!(
            growth > g / 50.0 && growth < 50.0 * g,
            "{preset:?}: {growth} vs {g}"
        );
    }
}

#[test]
fn conditions_beyond_saturation_are_reported_not_clipped() {
    // 30 m/s forward needs more collective than S_col,max = 0.30 allows: the
    // trim converges with saturation lifted and names the input.
    let model = Model::bergen_twin(Preset::Physical);
    let target = TrimTarget {
        velocity_ned_m_s: Vector3::new(30.0, 0.0, 0.0),
        ..TrimTarget::hover()
    };
    let t = trim(&model, &target, &TrimOptions::default()).unwrap();
    assert!(t.residual_norm < 1e-9);
    assert_eq!(t.beyond_saturation.len(), 1, "{:?}", t.beyond_saturation);
    let v = &t.beyond_saturation[0];
    assert_eq!(v.input, "S_col");
    assert!(v.value > v.max && t.u[0] == v.value);
    // and a hover is flyable
    let h = trim(&model, &TrimTarget::hover(), &TrimOptions::default()).unwrap();
    assert!(h.beyond_saturation.is_empty());
}

#[test]
fn failure_names_the_remaining_equations() {
    // One iteration cannot converge from a cold start: the error names the
    // equations with the largest residuals and the iterations used.
    let model = Model::bergen_twin(Preset::Physical);
    let opts = TrimOptions {
        max_iterations: 1,
        ..TrimOptions::default()
    };
    let e = trim(&model, &TrimTarget::hover(), &opts)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("after 1 iterations") && e.contains("d") && e.contains("/dt"),
        "{e}"
    );
    let bad = TrimTarget {
        yaw_rad: f64::NAN,
        ..TrimTarget::hover()
    };
    assert!(trim(&model, &bad, &TrimOptions::default()).is_err());
}
