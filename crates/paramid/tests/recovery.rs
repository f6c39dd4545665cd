//! Recovery on a known truth from flown, noisy data: the demo programme
//! (the §11.1 ground experiments simulated on the truth, then three
//! identification flights with sensor noise and light turbulence, the
//! controller designed on the nominal model) on truths a and c, fitted from
//! the Bergen Twin with the ground-measured values.
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

/// What [`recover`] measured.
struct Recovered {
    /// Worst error of the identifiable parameters, % of the truth.
    worst_pct: f64,
    /// Worst error of the identifiable parameters in Cramér–Rao bounds.
    worst_cr: f64,
    /// Cost ratio identified / start.
    ratio: f64,
    /// Identified cost / the cost at the truth on the same data.
    vs_truth: f64,
    /// Against the truth's model responses: (before the ground experiments,
    /// start, identified).
    truth_model: (f64, f64, f64),
    /// Worst ground error in its standard errors.
    ground_worst_se: f64,
}

fn recover(name: &str, instruments: bool, controllers: bool) -> Recovered {
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
    let mut ground_worst_se = 0.0_f64;
    for g in &r.ground {
        let want = keys::get(&t, keys::find(&g.key).unwrap());
        let d = keys::find(&g.key).unwrap();
        // the measured value, not the truth, is the start
        assert_eq!(keys::get(&id.config.start, d), g.value, "{}", g.key);
        ground_worst_se = ground_worst_se.max((g.value - want).abs() / g.std_error);
        println!(
            "  ground {:38} {:.6} ± {:.2e} truth {want:.6} error {:+.2} % ({:.2} σ)",
            g.key,
            g.value,
            g.std_error,
            100.0 * (g.value - want) / want,
            (g.value - want) / g.std_error
        );
    }
    let tm = r.truth_model_cost.unwrap();
    // the truth against its own responses: zero (the same linearisations)
    let own = id.truth_model_cost(&t, Some(&t)).unwrap();
    assert!(
        own.before_ground.unwrap() < 1e-20,
        "the truth's cost against itself {own:?}"
    );
    println!(
        "  truth-model cost: before ground {:.4e}, start {:.4e}, identified {:.4e}",
        tm.before_ground.unwrap_or(f64::NAN),
        tm.start,
        tm.identified
    );
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
    // the parameters before the ground experiments: the Bergen Twin with the
    // weighed mass and inertias
    let mut weighed = Params::bergen_twin();
    for key in helicon_paramid::demo::GROUND_MEASURED {
        let d = keys::find(key).unwrap();
        keys::set(&mut weighed, d, keys::get(&t, d));
    }
    let (w_med, w_max) = pole_mismatch(&t, &weighed);
    let (s_med, s_max) = pole_mismatch(&t, &start);
    let (i_med, i_max) = pole_mismatch(&t, &id.identified);
    println!(
        "  hover poles 0.5-40 rad/s vs the truth's (relative distance, median / max): before the ground {w_med:.4} / {w_max:.4}, start {s_med:.4} / {s_max:.4}, identified {i_med:.4} / {i_max:.4}"
    );
    assert!(
        i_med < w_med && i_max < w_max,
        "identified poles no closer to the truth's than before the ground experiments"
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
    Recovered {
        worst_pct,
        worst_cr,
        ratio: r.cost_identified / r.cost_start,
        vs_truth: r.cost_identified / cost_truth,
        truth_model: (
            tm.before_ground.unwrap_or(f64::NAN),
            tm.start,
            tm.identified,
        ),
        ground_worst_se,
    }
}

/// Prints the figures and checks what the truth a and c tests share: the
/// bound on the identifiable errors (in Cramér–Rao bounds and in per cent),
/// the ground values within 3 standard errors of the truth, the fit about
/// as good as the truth on the same data, and the model nearer the
/// truth's own responses by `min_truth_model_fall` from the parameters
/// before the ground experiments.
fn check(name: &str, r: &Recovered, max_cr: f64, max_pct: f64, min_truth_model_fall: f64) {
    let (before, start, identified) = r.truth_model;
    println!(
        "{name}: worst {:.2} %, {:.2} CR bounds, cost ratio {:.3}, final/truth {:.3}, ground worst {:.2} σ, truth-model {before:.3e} -> {start:.3e} -> {identified:.3e} ({:.0}x, {:.1}x from the start)",
        r.worst_pct,
        r.worst_cr,
        r.ratio,
        r.vs_truth,
        r.ground_worst_se,
        before / identified,
        start / identified
    );
    assert!(
        r.worst_cr <= max_cr,
        "worst identifiable error {} Cramér–Rao bounds",
        r.worst_cr
    );
    assert!(
        r.worst_pct < max_pct,
        "worst identifiable error {} %",
        r.worst_pct
    );
    assert!(r.ratio < 1.0, "the cost did not fall: ratio {}", r.ratio);
    // at most 1 % above the truth's own cost: a parameter flagged and kept at
    // its (wrong) start value keeps the fit from the truth's minimum
    // (truth c: the collective servo, +25 %: 1.003)
    assert!(
        r.vs_truth <= 1.01,
        "the fit must do about as well as the truth: {}",
        r.vs_truth
    );
    assert!(
        r.ground_worst_se <= 3.0,
        "a ground value {} standard errors off",
        r.ground_worst_se
    );
    assert!(
        identified < start && before / identified >= min_truth_model_fall,
        "truth-model cost {before} (before the ground) -> {start} (start) -> {identified}"
    );
}

/// The demo's default programme (ground experiments as priors, the tail
/// lift slope kept at its ground value; the logged excitations as instruments,
/// H = G_eu⁻¹ G_ey, one flat window per sweep; hover, 5 and 10 m/s;
/// Cramér–Rao bounds of correlated frequency points) on truth-a at the
/// scenarios' seed (3). Measured: the eight identifiable parameters within
/// 1.48 Cramér–Rao bounds and 4.8 % (the tail servo's bandwidth), the
/// collective servo's flagged "insensitive"; the ground values within 1.0
/// standard errors; the cost 571 → 412, 0.99 of the truth's own cost on
/// the same data (the noise floor); against the truth's own model responses
/// 1.53e3 before the ground experiments → 178 at the start → 2.64
/// identified (577×). Over truths a, b, c at seeds 1, 3 and 7
/// (docs/paramid.md): 8 of the 9 runs within 2 bounds (the ninth 2.64),
/// errors ≤ 13.3 %, the error/bound ratio over 73 estimates RMS 1.05.
/// Asserted: the 2 bounds, < 8 %, ≥ 75×. The hover poles of
/// 0.5–40 rad/s move closer to the truth's (median 0.045 → 0.002); the LQI
/// designed on the identified model flies the truth through
/// `scenarios/demo.toml` (5 seeds) within 2 % of the one designed on the
/// truth (all three designs within 0.2 %: the scenario does not tell them
/// apart).
#[test]
fn truth_a_is_recovered_from_flown_noisy_data() {
    let r = recover("truth-a", true, true);
    check("truth-a", &r, 2.0, 8.0, 75.0);
}

/// The same programme on truth-c (issue 15: its lift slope was +7.6 % with
/// a 3.1 % bound before the ground experiments; the cause was the scatter of
/// the estimate, not the parameters fixed at wrong values — docs/paramid.md).
/// Measured at the scenarios' seed (3): within 1.66 bounds and 5.6 %, the
/// collective servo flagged; the ground values within 1.0 σ; the
/// truth-model cost 1.87e3 before the ground → 20.4 at the start → 4.19
/// identified (446×). Asserted as for truth a: 2 bounds, < 8 %, ≥ 50×.
#[test]
fn truth_c_is_recovered_from_flown_noisy_data() {
    let r = recover("truth-c", true, false);
    check("truth-c", &r, 2.0, 8.0, 50.0);
}

/// The same flights with the responses conditioned on the servos (CIFER's
/// way, no instruments; the overlapped Hann windows). Measured (three
/// points): identifiable parameters within 11.5 %, but up to 4.15
/// Cramér–Rao bounds off (before the flights rested between sweeps: 10.2 %,
/// 6.3 bounds): the LQI answers the turbulence and the gyro
/// noise, which correlates the servo commands with the disturbances and
/// biases the conditioned estimate (flown without turbulence and sensor
/// noise the lift-slope error falls from −4.2 % to −1.4 % for truth-c); the
/// cost falls 2.9× (0.34) to 0.89 of the truth's own cost on these data.
#[test]
fn conditioned_estimates_are_biased_by_the_feedback() {
    let r = recover("truth-a", false, false);
    println!(
        "worst {:.2} %, {:.2} CR bounds, cost ratio {:.2e}, final/truth {:.3}",
        r.worst_pct, r.worst_cr, r.ratio, r.vs_truth
    );
    assert!(
        r.worst_pct < 12.0,
        "worst identifiable error {} %",
        r.worst_pct
    );
    assert!(
        r.worst_cr > 2.0,
        "the conditioned estimate is no longer biased: {} CR bounds",
        r.worst_cr
    );
    assert!(r.ratio < 0.5, "cost ratio {}", r.ratio);
    assert!(r.vs_truth <= 1.0, "{}", r.vs_truth);
}
