//! Is the random error the fit weighs every frequency point by the real
//! scatter of the estimates? Truth-a's hover identification flight (the
//! demo's: sensor noise, light turbulence, the whole on-board chain, the
//! LQI designed on the nominal model) flown with 12 turbulence and sensor
//! seeds; each flight's responses estimated as the demo does (instruments,
//! 12 and 6 s windows); their scatter over the flights compared with the ε
//! each claimed ([`helicon_paramid::calibration`]).
//!
//! Measured (12 seeds, the points with ε ≤ 0.2): the cyclic responses' ε is
//! right or conservative, magnitude ratio 0.77–0.88, phase 0.74–0.86 (31–35
//! points); heave 0.81 / 0.96 (16 points). The yaw response's magnitude is
//! optimistic, 1.60 (phase 1.04), and its error is mostly one gain per
//! flight (common offset 1.26 ε against 0.24–0.42 for the others): the turbulence moves the tail rotor's operating point, so the
//! yaw response's gain differs from flight to flight by a few per cent, a
//! model error the linearisation at still-air trim cannot hold and the fit
//! absorbs into the tail servo's bandwidth (docs/paramid.md, "How good are
//! the Cramér–Rao bounds").
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::Params;
use helicon_paramid::calibration::calibrate;
use helicon_paramid::config::IdentConfig;
use helicon_paramid::data::measure;
use helicon_paramid::demo::{DemoOptions, FLIGHTS, TRUTHS, fly_scenario, ident_toml};
use rayon::prelude::*;

#[test]
fn hover_random_errors_against_their_scatter_over_12_flights() {
    let (_, truth_text) = TRUTHS[0];
    let truth = Params::from_toml_str(truth_text, "truth-a").unwrap();
    let text = FLIGHTS.iter().find(|f| f.0 == "hover").unwrap().2;
    let opts = DemoOptions {
        flights: vec!["hover".into()],
        verify: false,
        ground: false,
        ..DemoOptions::default()
    };
    let runs: Vec<_> = (1..=12u64)
        .into_par_iter()
        .map(|seed| {
            let dir = std::env::temp_dir().join(format!(
                "helicon-random-error-{seed}-{}",
                std::process::id()
            ));
            std::fs::create_dir_all(&dir).unwrap();
            let log = dir.join("flights").join("hover").join("log.csv");
            fly_scenario("hover", text, &truth, Some(seed), &log).unwrap();
            std::fs::write(dir.join("start.toml"), truth_text).unwrap();
            let cfg = IdentConfig::from_toml_str(&ident_toml(&opts), "IDENT.toml", &dir).unwrap();
            let d = measure(&cfg, 0).unwrap();
            let _ = std::fs::remove_dir_all(&dir);
            vec![d]
        })
        .collect();
    let cal = calibrate(&runs, 0.2).unwrap();
    for c in &cal {
        println!(
            "{:14} {:2} points  magnitude {:.2}  phase {:.2}  common offset {:.2} ε",
            c.label, c.points, c.magnitude_ratio, c.phase_ratio, c.common_offset
        );
    }
    let get = |label: &str| cal.iter().find(|c| c.label == label).unwrap();
    // cyclic and heave: right or conservative. 12 flights give each ratio a
    // sampling error of ~1/√22 ≈ 21 % per point, ~5 % over 30+ points:
    // above 1.15 would be optimistic beyond that, below 0.5 twice
    // conservative (the weights would still be right relative to each other)
    for label in [
        "meas_p/S_lat",
        "meas_q/S_lat",
        "meas_p/S_lon",
        "meas_q/S_lon",
        "w/S_col",
    ] {
        let c = get(label);
        // heave keeps 16 (its low frequencies are noisier), cyclic 31–35
        assert!(c.points >= 12, "{c:?}");
        assert!(c.magnitude_ratio > 0.5 && c.magnitude_ratio < 1.15, "{c:?}");
        assert!(c.phase_ratio > 0.5 && c.phase_ratio < 1.15, "{c:?}");
        assert!(c.common_offset < 0.8, "{c:?}");
    }
    // yaw: the known optimism and its per-flight gain (measured 1.60 and
    // 1.26): a change in either direction is news this test reports
    let yaw = get("meas_r/S_tr");
    assert!(
        yaw.magnitude_ratio > 1.15 && yaw.magnitude_ratio < 2.0,
        "{yaw:?}"
    );
    assert!(yaw.common_offset > 0.8, "{yaw:?}");
}
