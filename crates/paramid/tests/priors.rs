//! Prior measurements in the cost (`prior`, `prior_std` in IDENT.toml, the
//! demo's ground values): the fit weighs them against the flight data by
//! their errors.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::print_stdout)]

use helicon_model::Params;
use helicon_paramid::demo::{DemoOptions, TRUTHS, run_demo};
use helicon_paramid::report::run;

const KEY: &str = "main_rotor.spring_n_m_per_rad";

/// (identified value, its Cramér–Rao bound in SI) of KEY.
fn of_key(id: &helicon_paramid::report::Identification) -> (f64, f64) {
    let p = id.fit.parameters.iter().find(|p| p.key == KEY).unwrap();
    assert!(p.identifiable, "{KEY} flagged: {:?}", p.reason);
    (
        p.identified,
        p.cramer_rao_pct.unwrap() / 100.0 * p.identified.abs(),
    )
}

/// One flight (hover, truth b, the demo's responses, 20 points) fitted
/// three ways. A prior of a tiny standard error holds the parameter at
/// the prior. A prior as precise as the flight (σ = the flight's own bound)
/// placed four bounds away moves the estimate about half-way and narrows
/// the bound by about √2 — the inverse-variance combination of two
/// independent measurements, which the prior residual s·(θ − θ_prior)/σ
/// gives when s, the data residuals' standard deviation from their random
/// errors, equals the residual scale of the Cramér–Rao bound
/// (√(J/(n − p))). The two scales are estimated differently, so the
/// check allows 0.3–0.7 of the way and 0.55–0.85 of the bound (exactly
/// ½ and 1/√2 = 0.71 if they were equal; measured 0.564 and 0.683).
#[test]
fn a_prior_is_weighed_against_the_flight_by_its_error() {
    let truth = Params::from_toml_str(
        TRUTHS.iter().find(|t| t.0 == "truth-b").unwrap().1,
        "truth-b",
    )
    .unwrap();
    let dir = std::env::temp_dir().join("helicon-paramid-priors");
    let _ = std::fs::remove_dir_all(&dir);
    let opts = DemoOptions {
        flights: vec!["hover".into()],
        verify: false,
        ground: false,
        points: 20,
        ..DemoOptions::default()
    };
    let id = run_demo(&truth, &dir, &opts).unwrap();
    let (v_f, cr_f) = of_key(&id);
    let i = id
        .config
        .parameters
        .iter()
        .position(|p| p.key() == KEY)
        .unwrap();

    let mut cfg = id.config.clone();
    let tight = 1e-6 * v_f;
    cfg.parameters[i].prior = Some((v_f + 4.0 * cr_f, tight));
    let held = run(&cfg).unwrap();
    let (v_h, cr_h) = of_key(&held);
    println!(
        "tight prior: {v_h} (prior {}), bound {cr_h}",
        v_f + 4.0 * cr_f
    );
    assert!(
        (v_h - (v_f + 4.0 * cr_f)).abs() < 0.02 * cr_f,
        "held at {v_h}, prior {}",
        v_f + 4.0 * cr_f
    );
    assert!(
        cr_h < 0.05 * cr_f,
        "bound {cr_h} against the flight's {cr_f}"
    );

    let mut cfg = id.config.clone();
    let prior = v_f + 4.0 * cr_f;
    cfg.parameters[i].prior = Some((prior, cr_f));
    let both = run(&cfg).unwrap();
    let (v_b, cr_b) = of_key(&both);
    let way = (v_b - v_f) / (prior - v_f);
    println!(
        "flight {v_f} ± {cr_f}, prior {prior} ± {cr_f}: combined {v_b} ± {cr_b} ({way:.3} of the way, bound ratio {:.3})",
        cr_b / cr_f
    );
    assert!((0.3..0.7).contains(&way), "{way} of the way");
    assert!(
        (0.55..0.85).contains(&(cr_b / cr_f)),
        "bound ratio {}",
        cr_b / cr_f
    );
    let _ = std::fs::remove_dir_all(&dir);
}
