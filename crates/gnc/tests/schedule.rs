//! The gain-schedule design: the frozen-point closed loop against the design
//! it interpolates, the interpolation against the design points, the file
//! round trip, and edited files refused.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests: a failed unwrap is a failed test

use helicon_gnc::design::output_matrix;
use helicon_gnc::schedule::{
    EnvelopeConfig, GridSection, Schedule, design_schedule, frozen_closed_loop, frozen_point_check,
    integrator_output_map,
};
use helicon_model::linearize::linearize;
use helicon_model::trim::{TrimOptions, TrimTarget, trim};
use helicon_model::{InflowMode, Model, Params, Preset};
use nalgebra::{Complex, DMatrix, Vector3};

fn model() -> Model {
    Model::new(Params::bergen_twin(), Preset::Physical.options())
}

fn small_config(forward: Vec<f64>, lateral: Vec<f64>) -> EnvelopeConfig {
    let mut cfg = EnvelopeConfig::from_toml_str("", "test.toml").unwrap();
    cfg.grid = GridSection {
        forward_m_s: forward,
        lateral_m_s: lateral,
        down_m_s: vec![0.0],
        accept_unphysical: false,
    };
    cfg
}

fn eig(a: &DMatrix<f64>) -> Vec<Complex<f64>> {
    helicon_lti::analysis::eigenvalues(a).unwrap()
}

/// Every expected eigenvalue has a distinct computed one within `tol`.
fn same_spectrum(expected: &[Complex<f64>], actual: &[Complex<f64>], tol: f64) {
    assert_eq!(expected.len(), actual.len());
    let mut used = vec![false; actual.len()];
    for e in expected {
        let (best, d) = actual
            .iter()
            .enumerate()
            .filter(|(i, _)| !used[*i])
            .map(|(i, a)| (i, (a - e).norm()))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        assert!(d < tol, "eigenvalue {e} unmatched (nearest at {d:e})");
        used[best] = true;
    }
}

/// At a design point the frozen closed loop separates: its eigenvalues are
/// the design's closed-loop poles and the estimator poles (separation
/// principle), at hover (where the integrated outputs are Hs) and at
/// 10 m/s (where they include the flight-path terms the design was given).
/// Tolerance 1e-7: both sides come from eigen-solvers of differently
/// conditioned 31- and 58-state matrices.
#[test]
fn frozen_loop_at_a_design_point_is_the_design() {
    let m = model();
    let s = design_schedule(
        &m,
        &small_config(vec![0.0, 10.0], vec![0.0]),
        &mut |_, _| {},
    )
    .unwrap();
    for (i, speed) in [(0usize, 0.0), (1, 10.0)] {
        let g = &s.points[i];
        let target = TrimTarget {
            velocity_ned_m_s: Vector3::new(speed, 0.0, 0.0),
            ..TrimTarget::hover()
        };
        let t = trim(&m, &target, &TrimOptions::default()).unwrap();
        if speed == 0.0 {
            let c = integrator_output_map(&t.x);
            assert!((c - output_matrix()).amax() < 1e-9, "hover C is Hs");
        }
        let ts = g.set.sample_time_s;
        let lm = linearize(&m, &t.x, &t.u, &Vector3::zeros(), InflowMode::Converged).unwrap();
        let (phi, gamma) = lm.discretize(ts).unwrap();
        let a = frozen_closed_loop(&phi, &gamma, &t.x, &g.set);
        let expected: Vec<Complex<f64>> = g
            .closed_loop_poles
            .iter()
            .chain(&g.estimator_poles)
            .map(|z| Complex::new(z[0], z[1]))
            .collect();
        same_spectrum(&expected, &eig(&a), 1e-7);
        assert!(g.spectral_radius() < 1.0 / g.set.alpha, "pincer");
    }
}

/// At speed the on-board integrator sees the attitude through R_eb v: the
/// pitch column of its vertical row is −V (a nose-down pitch δθ adds V δθ
/// of down velocity; sign: body w axis), checked against the closed form.
#[test]
fn integrator_map_at_speed_has_the_flight_path_terms() {
    let m = model();
    let target = TrimTarget {
        velocity_ned_m_s: Vector3::new(10.0, 0.0, 0.0),
        ..TrimTarget::hover()
    };
    let t = trim(&m, &target, &TrimOptions::default()).unwrap();
    let c = integrator_output_map(&t.x);
    // body velocity (u, w) at pitch θ; d(R v)/dθ rotated back = (−w, 0, u)·…
    let (u, w) = (t.x[3], t.x[5]);
    // R_be ∂R_eb/∂θ v = ω̂ × v with ω = (0, 1, 0) in the pitch-rotated frame:
    // for φ = 0 this is (w, 0, −u)
    assert!(t.x[0].abs() < 0.05, "near wings-level");
    assert!(
        (c[(1, 1)] - w).abs() < 0.05 * u.abs(),
        "{} vs {w}",
        c[(1, 1)]
    );
    assert!(
        (c[(3, 1)] + u).abs() < 0.05 * u.abs(),
        "{} vs {}",
        c[(3, 1)],
        -u
    );
}

/// Interpolation returns each design point's gains bit for bit at the node
/// and the average halfway between two nodes (multilinear, one axis).
#[test]
fn interpolation_hits_the_nodes_and_averages_between() {
    let m = model();
    let s = design_schedule(&m, &small_config(vec![0.0, 5.0], vec![0.0]), &mut |_, _| {}).unwrap();
    let gs = s.gain_schedule("test").unwrap();
    let at0 = gs.at(&Vector3::zeros());
    let at5 = gs.at(&Vector3::new(5.0, 0.0, 0.0));
    assert_eq!(at0, s.points[0].set);
    assert_eq!(at5, s.points[1].set);
    let mid = gs.at(&Vector3::new(2.5, 0.0, 0.0));
    let avg = (s.points[0].set.ls + s.points[1].set.ls) * 0.5;
    assert!((mid.ls - avg).amax() <= 1e-12 * avg.amax());
    // clamped beyond the grid
    assert_eq!(gs.at(&Vector3::new(40.0, 3.0, -2.0)), s.points[1].set);
}

/// The file reads back bit for bit; an edited operating point, a wrong
/// version and an edited α are refused naming the field.
#[test]
fn schedule_file_round_trip_and_edits_refused() {
    let m = model();
    let s = design_schedule(&m, &small_config(vec![0.0, 5.0], vec![0.0]), &mut |_, _| {}).unwrap();
    let text = s.to_json().unwrap();
    let back = Schedule::from_json(&text, "s.json").unwrap();
    assert_eq!(back, s);
    let edited = text.replacen(
        "\"operating_point_m_s\":[5.0",
        "\"operating_point_m_s\":[6.0",
        1,
    );
    let e = Schedule::from_json(&edited, "s.json")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("s.json") && e.contains("points[1].operating_point_m_s"),
        "{e}"
    );
    let edited = text.replacen("\"version\":1", "\"version\":7", 1);
    let e = Schedule::from_json(&edited, "s.json")
        .unwrap_err()
        .to_string();
    assert!(e.contains("`version` = 7"), "{e}");
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let alpha = v["points"][0]["gains"]["alpha"].as_f64().unwrap();
    let edited = text.replacen(&format!("\"alpha\":{alpha}"), "\"alpha\":1.5", 1);
    assert_ne!(edited, text);
    let e = Schedule::from_json(&edited, "s.json")
        .unwrap_err()
        .to_string();
    assert!(e.contains("points[0].gains") && e.contains("alpha"), "{e}");
}

/// The frozen-point check of a forward-speed schedule: every point between
/// 0 and 15 m/s (design points and two between each pair) is stable, and
/// the design points are among them.
#[test]
fn frozen_points_between_design_points_are_stable() {
    let m = model();
    let s = design_schedule(
        &m,
        &small_config(vec![0.0, 5.0, 10.0, 15.0], vec![0.0]),
        &mut |_, _| {},
    )
    .unwrap();
    let gs = s.gain_schedule("test").unwrap();
    let check = frozen_point_check(&m, &gs, 2, false, &mut |_, _| {}).unwrap();
    assert_eq!(check.points.len(), 10);
    assert_eq!(check.points.iter().filter(|p| p.design_point).count(), 4);
    assert!(check.stable(), "worst {:?}", check.worst);
}

/// Envelope files: an unknown key, a bad preset and a non-increasing axis
/// are errors naming the file and the field.
#[test]
fn envelope_file_errors_name_the_field() {
    let e = EnvelopeConfig::from_toml_str("presett = 1", "env.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("env.toml") && e.contains("presett"), "{e}");
    let e = EnvelopeConfig::from_toml_str("preset = \"nope\"", "env.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("env.toml") && e.contains("preset"), "{e}");
    let e = EnvelopeConfig::from_toml_str("[grid]\nforward_m_s = [0.0, 5.0, 5.0]", "env.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("env.toml") && e.contains("forward_m_s") && e.contains("increasing"),
        "{e}"
    );
    let e = EnvelopeConfig::from_toml_str("[grid]\ndown_m_s = [nan]", "env.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("grid.down_m_s"), "{e}");
    // the frozen check's work is bounded: 32 x 32 x 2 points with 8 subdivisions
    let axis = |n: usize| {
        format!(
            "[{}]",
            (0..n)
                .map(|i| format!("{i}.0"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    let text = format!(
        "[grid]\nforward_m_s = {}\nlateral_m_s = {}\ndown_m_s = [0.0, 1.0]\n[check]\nsubdivisions = 8\n",
        axis(32),
        axis(16)
    );
    let e = EnvelopeConfig::from_toml_str(&text, "env.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("check.subdivisions") && e.contains("MAX_FROZEN_POINTS"),
        "{e}"
    );
}
