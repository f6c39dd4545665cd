//! Noise-free identification: the "measurements" are the truth's own
//! linearised responses (C(zI − Φ)⁻¹Γ at its trims) at two operating points,
//! 16 responses each; starting from the nominal Bergen Twin, bounded
//! Levenberg–Marquardt must return the truth's parameters.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::Params;
use helicon_paramid::config::{IdentConfig, Optimiser};
use helicon_paramid::cost::Cost;
use helicon_paramid::data::from_model;
use helicon_paramid::fit::{FitOptions, identify};
use helicon_paramid::keys;
use std::path::Path;

/// Two operating points (hover, 5 m/s forward), 4 servos × p, q, r, w,
/// 10 parameters.
pub const IDENT_2X16X10: &str = include_str!("../fixtures/noise_free.toml");

fn truth_a() -> Params {
    Params::from_file(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../params/truths/truth-a.toml"),
    )
    .unwrap()
}

fn check(optimiser: Optimiser, tol: f64) {
    check_text(IDENT_2X16X10, optimiser, tol);
}

fn check_text(text: &str, optimiser: Optimiser, tol: f64) {
    let cfg = IdentConfig::from_toml_str(text, "noise-free.toml", Path::new(".")).unwrap();
    assert_eq!(cfg.response_count(), 32);
    let truth = truth_a();
    let data = from_model(&cfg, &truth).unwrap();
    let cost = Cost::new(&cfg, &data).unwrap();
    let t0 = std::time::Instant::now();
    let fit = identify(
        &cost,
        &FitOptions {
            optimiser,
            max_iterations: 100,
            auto_fix: false,
        },
    )
    .unwrap();
    let elapsed = t0.elapsed().as_secs_f64();
    let evals: usize = fit.passes.iter().map(|p| p.evaluations).sum();
    println!(
        "{optimiser:?}: cost {:.3e} -> {:.3e}, {evals} cost evaluations, {elapsed:.2} s ({})",
        fit.cost_start, fit.cost_final, fit.passes[0].termination
    );
    let mut worst: f64 = 0.0;
    for p in &fit.parameters {
        let want = keys::get(&truth, keys::find(&p.key).unwrap());
        let rel = (p.identified - want).abs() / want.abs();
        println!(
            "  {:40} start {:10.5} identified {:12.7} truth {:10.5} rel {:.2e} CR {:?} %",
            p.key, p.start, p.identified, want, rel, p.cramer_rao_pct
        );
        worst = worst.max(rel);
    }
    assert!(worst < tol, "worst relative error {worst:e}");
    assert!(
        fit.cost_final < 1e-10 * fit.cost_start,
        "{} -> {}",
        fit.cost_start,
        fit.cost_final
    );
}

/// Tolerance 1e-6 relative (the issue's requirement). The floor is the
/// trim's residual tolerance (1e-10) and the linearisation's round-off
/// (~1e-11 relative), amplified by the conditioning of the fit.
#[test]
fn noise_free_lm_recovers_the_truth_to_1e_6() {
    check(Optimiser::Lm, 1e-6);
}

/// The simplex (MOSCA's optimiser) on the same problem: 20 times as many
/// cost evaluations as LM (2891 against 144, 10 s against 0.9 s on the shared
/// 2-core machine), the same answer (worst 1.4e-7 relative).
#[test]
fn noise_free_simplex_recovers_the_truth_to_1e_6() {
    check(Optimiser::Simplex, 1e-6);
}

/// CIFER's cost form on the same problem: the same answer (the weights
/// change the path, not the minimum of a noise-free fit).
#[test]
fn noise_free_cifer_cost_recovers_the_truth_to_1e_6() {
    check_text(
        &format!("cost = \"cifer\"\n{IDENT_2X16X10}"),
        Optimiser::Lm,
        1e-6,
    );
}

/// `auto_fix` on a parameter the responses cannot see: the tail servo's
/// bandwidth does not enter S_lat → p or S_lon → q (its state is driven by
/// S_tr alone), so it is flagged insensitive, fixed at its start with the
/// reason, and the others are still recovered.
#[test]
fn auto_fix_flags_a_parameter_the_data_cannot_see() {
    let text = r#"
auto_fix = true
points = 20
[[operating_point]]
name = "hover"
log = "unused.csv"
[[response]]
input = "S_lat"
output = "p"
omega_min_rad_s = 1.5
omega_max_rad_s = 25.0
[[response]]
input = "S_lon"
output = "q"
omega_min_rad_s = 1.5
omega_max_rad_s = 25.0
[[parameter]]
key = "main_rotor.spring_n_m_per_rad"
min = 100.0
max = 400.0
[[parameter]]
key = "servo.tail.omega_n_rad_s"
min = 50.0
max = 200.0
[[parameter]]
key = "body.iyy_kg_m2"
min = 0.31
max = 1.24
"#;
    let cfg = IdentConfig::from_toml_str(text, "fix.toml", Path::new(".")).unwrap();
    // the Bergen Twin with truth-a's hinge spring and pitch inertia
    let mut truth = Params::bergen_twin();
    for key in ["main_rotor.spring_n_m_per_rad", "body.iyy_kg_m2"] {
        let d = keys::find(key).unwrap();
        keys::set(&mut truth, d, keys::get(&truth_a(), d));
    }
    let data = from_model(&cfg, &truth).unwrap();
    let cost = Cost::new(&cfg, &data).unwrap();
    let fit = identify(
        &cost,
        &FitOptions {
            optimiser: Optimiser::Lm,
            max_iterations: 100,
            auto_fix: true,
        },
    )
    .unwrap();
    assert_eq!(fit.passes.len(), 2, "{:?}", fit.passes);
    let tail = &fit.parameters[1];
    assert!(
        !tail.identifiable && tail.identified == tail.start,
        "{tail:?}"
    );
    assert!(
        tail.reason.as_deref().unwrap().starts_with("insensitive"),
        "{tail:?}"
    );
    assert!(tail.cramer_rao_pct.is_none());
    for p in [&fit.parameters[0], &fit.parameters[2]] {
        let want = keys::get(&truth, keys::find(&p.key).unwrap());
        assert!(p.identifiable, "{p:?}");
        assert!((p.identified - want).abs() < 1e-6 * want, "{p:?} vs {want}");
    }
    assert_eq!(fit.correlation_keys.len(), 2);
}
