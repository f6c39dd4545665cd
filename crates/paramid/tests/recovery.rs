//! Recovery on a known truth from flown, noisy data: the demo programme
//! (three identification flights with sensor noise and light turbulence,
//! the controller designed on the nominal model) on truth-a, fitted from
//! the nominal Bergen Twin.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::Params;
use helicon_paramid::demo::{DemoOptions, TRUTHS, run_demo};
use helicon_paramid::keys;
use helicon_paramid::linear::{linear_model, target};

/// For each pole of `truth`, the distance to the nearest pole of `other`
/// relative to its modulus; (median, max) over the poles of 0.5–40 rad/s
/// (near the fitted band 1.5–25 rad/s: the slow velocity and heading modes
/// depend on the drag and tail parameters the cyclic responses cannot
/// determine, and the servo poles at ~100 rad/s are beyond the band).
fn pole_mismatch(truth: &Params, other: &Params) -> (f64, f64) {
    let hover = target([0.0; 3], 0.0);
    let poles = |p: &Params| {
        let (_, lm) = linear_model(p, helicon_model::Preset::Physical, &hover, "hover").unwrap();
        lm.poles()
            .unwrap()
            .into_iter()
            .map(|p| p.value)
            .collect::<Vec<_>>()
    };
    let (pt, po) = (poles(truth), poles(other));
    let mut d: Vec<f64> = pt
        .iter()
        .filter(|z| z.norm() < 40.0 && z.norm() > 0.5)
        .map(|z| {
            po.iter()
                .map(|w| (z - w).norm())
                .fold(f64::INFINITY, f64::min)
                / z.norm()
        })
        .collect();
    d.sort_by(f64::total_cmp);
    (d[d.len() / 2], d[d.len() - 1])
}

fn truth(name: &str) -> Params {
    let text = TRUTHS.iter().find(|t| t.0 == name).unwrap().1;
    Params::from_toml_str(text, name).unwrap()
}

/// Returns (worst error % of the identifiable parameters, worst error in
/// CR bounds, cost ratio final/start, final cost / cost at the truth).
/// Fly the shipped `scenarios/demo.toml` (steps on vn, ψ, vd, turbulence,
/// sensors in the loop) on the true helicopter with the LQI designed on
/// `design`, for wind and sensor seeds 1..=n; the mean over the seeds of each
/// output's RMS tracking error (vn, ve, vd in m/s, psi in rad).
fn monte_carlo(truth: &Params, design: &Params, n: u64) -> Vec<(String, f64)> {
    use helicon_sim::closed_loop::{Outcome, fly, prepare_with_params};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/demo.toml");
    let mut sums: std::collections::BTreeMap<String, f64> = Default::default();
    for seed in 1..=n {
        let mut s = helicon_sim::scenario::Scenario::from_file(&path).unwrap();
        s.wind.seed = seed;
        s.sensors.seed = seed;
        let mut p = prepare_with_params(&s, *truth).unwrap();
        p.gains = prepare_with_params(&s, *design).unwrap().gains;
        let f = fly(&s, &p, None).unwrap();
        assert_eq!(
            f.summary.outcome,
            Outcome::Completed,
            "{:?}",
            f.summary.reason
        );
        for (k, m) in &f.summary.metrics {
            *sums.entry(k.clone()).or_default() += m.rms_error / n as f64;
        }
    }
    sums.into_iter().collect()
}

fn recover(name: &str, instruments: bool, controllers: bool) -> (f64, f64, f64, f64) {
    let t = truth(name);
    // one folder per test: the tests of this binary run in parallel in one process
    let dir = std::env::temp_dir().join(format!(
        "helicon-paramid-recovery-{name}-{}-{}",
        if instruments { "iv" } else { "conditioned" },
        std::process::id()
    ));
    let opts = DemoOptions {
        instruments,
        ..DemoOptions::default()
    };
    let id = run_demo(&t, &dir, &opts).unwrap();
    let r = id.report();
    println!(
        "{name}: cost {:.4e} -> {:.4e} (ratio {:.2e}), fit {:.1} s, passes {}",
        r.cost_start,
        r.cost_identified,
        r.cost_identified / r.cost_start,
        r.fit_time_s,
        r.passes.len()
    );
    let truth_values: Vec<f64> = id
        .cost
        .parameters
        .iter()
        .map(|p| keys::get(&t, p.descriptor))
        .collect();
    let cost_truth = id.cost.residuals(&truth_values).unwrap().norm_squared();
    println!("  cost at the truth {cost_truth:.4e}");
    let (mut worst_pct, mut worst_cr) = (0.0_f64, 0.0_f64);
    for p in &r.parameters {
        let want = keys::get(&t, keys::find(&p.key).unwrap());
        let err = 100.0 * (p.identified - want) / want;
        if p.identifiable {
            worst_pct = worst_pct.max(err.abs());
            worst_cr = worst_cr.max(err.abs() / p.cramer_rao_pct.unwrap());
        } else {
            assert!(p.reason.is_some(), "{}: flagged without a reason", p.key);
        }
        println!(
            "  {:38} start {:9.5} id {:10.6} truth {:9.5} err {:+7.3} % CR {:>8} ins {:>8} {} {}",
            p.key,
            p.start,
            p.identified,
            want,
            err,
            p.cramer_rao_pct.map_or("-".into(), |v| format!("{v:.3}")),
            p.insensitivity_pct
                .map_or("-".into(), |v| format!("{v:.3}")),
            p.identifiable,
            p.reason.as_deref().unwrap_or("")
        );
    }
    for v in &r.verification {
        for o in &v.outputs {
            println!(
                "  verify {} {:.3} -> {:.3}",
                o.output, o.theil_start, o.theil_identified
            );
        }
    }
    let start = id.config.start;
    let (s_med, s_max) = pole_mismatch(&t, &start);
    let (i_med, i_max) = pole_mismatch(&t, &id.identified);
    println!(
        "  hover poles 0.5-40 rad/s vs the truth's: start median {s_med:.4} max {s_max:.4}, identified median {i_med:.4} max {i_max:.4} (relative distance)"
    );
    assert!(
        i_med < s_med && i_max < s_max,
        "identified poles no closer to the truth's"
    );
    // the LQI designed on the identified, the true and the start model,
    // flown on the true helicopter (5 seeds). Measured: all within 0.6 % of
    // each other (identified/truth 0.999–1.005): demo.toml's steps under
    // turbulence do not tell these designs apart, the LQI is robust to the
    // start model's errors too.
    let n = if controllers { 5 } else { 0 };
    let on_id = monte_carlo(&t, &id.identified, n);
    let on_truth = monte_carlo(&t, &t, n);
    let on_start = monte_carlo(&t, &start, n);
    for ((k, a), ((_, b), (_, c))) in on_id.iter().zip(on_truth.iter().zip(&on_start)) {
        println!(
            "  demo.toml RMS error {k}: designed on identified {a:.5}, truth {b:.5}, start {c:.5}"
        );
        assert!(
            *a <= 1.02 * b,
            "{k}: designed on the identified model {a} vs on the truth {b}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    (
        worst_pct,
        worst_cr,
        r.cost_identified / r.cost_start,
        r.cost_identified / cost_truth,
    )
}

/// The demo's default estimate (the logged excitations as instruments,
/// H = G_eu⁻¹ G_ey) from the default flights (hover, 5 and 10 m/s).
/// Measured (seed 3): the six identifiable parameters within 1.04 of their
/// Cramér–Rao bounds (the "within 2×"; worst in per cent the
/// longitudinal servo bandwidth +4.0 % with a 4.9 % bound), four flagged
/// with reasons, the cost down 5× to the cost of the truth itself on the
/// same data (0.994 of it: the fit is at the noise floor; the issue's
/// "orders of magnitude" is not what a noisy flight allows). The hover
/// poles of 0.5–40 rad/s move closer to the truth's: median relative
/// distance 0.045 → 0.004, worst 0.078 → 0.013. The LQI designed on the
/// identified model flies the truth through `scenarios/demo.toml` (5 seeds)
/// within 2 % of the one designed on the truth (all three designs within
/// 0.6 %: the scenario does not tell them apart). With hover and 5 m/s only
/// the figures were 1.07 bounds, 9.3 %, poles 0.009 / 0.026.
#[test]
fn truth_a_is_recovered_from_flown_noisy_data() {
    let (worst_pct, worst_cr, ratio, vs_truth) = recover("truth-a", true, true);
    println!(
        "worst {worst_pct:.2} %, {worst_cr:.2} CR bounds, cost ratio {ratio:.2e}, final/truth {vs_truth:.3}"
    );
    assert!(
        worst_cr <= 2.0,
        "worst identifiable error {worst_cr} Cramér–Rao bounds"
    );
    assert!(worst_pct < 12.0, "worst identifiable error {worst_pct} %");
    assert!(ratio < 0.3, "cost ratio {ratio}");
    assert!(
        vs_truth <= 1.0,
        "the fit must do at least as well as the truth: {vs_truth}"
    );
}

/// The same flights with the responses conditioned on the servos (CIFER's
/// way, no instruments). Measured (three points): identifiable parameters
/// within 10.2 %, but up to 6.3 Cramér–Rao bounds off (two points: 7.6 %,
/// 5.5 bounds): the LQI answers the turbulence and the gyro
/// noise, which correlates the servo commands with the disturbances and
/// biases the conditioned estimate (flown without turbulence and sensor
/// noise the lift-slope error falls from −4.2 % to −1.4 % for truth-c); the
/// cost falls 16× to 0.87 of the truth's own cost on these data.
#[test]
fn conditioned_estimates_are_biased_by_the_feedback() {
    let (worst_pct, worst_cr, ratio, vs_truth) = recover("truth-a", false, false);
    println!(
        "worst {worst_pct:.2} %, {worst_cr:.2} CR bounds, cost ratio {ratio:.2e}, final/truth {vs_truth:.3}"
    );
    assert!(worst_pct < 12.0, "worst identifiable error {worst_pct} %");
    assert!(
        worst_cr > 2.0,
        "the conditioned estimate is no longer biased: {worst_cr} CR bounds"
    );
    assert!(ratio < 0.1, "cost ratio {ratio}");
    assert!(vs_truth <= 1.0, "{vs_truth}");
}
