//! The 10 m/s identification flight completes for every shipped truth at
//! seeds 1, 3 and 7, in the light turbulence of the other flights (w20
//! 7.7 m/s), with the controller designed on the nominal model as the demo
//! flies it. Before the design integrated the on-board law's outputs at
//! speed, truth a diverged at ~72 s in this turbulence (a 1.6 rad/s
//! lateral–directional mode of the flown loop damped at −0.016 1/s grew
//! from ±0.1 to 1.2 rad of roll), with or without the sweeps.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_model::Params;
use helicon_paramid::demo::{FLIGHTS, TRUTHS, fly_scenario};

/// Largest |φ − mean φ| (rad) over a flight's log.csv.
fn roll_excursion_rad(log: &std::path::Path) -> f64 {
    let text = std::fs::read_to_string(log).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "phi").unwrap();
    let phi: Vec<f64> = lines
        .map(|l| l.split(',').nth(col).unwrap().parse().unwrap())
        .collect();
    let mean = phi.iter().sum::<f64>() / phi.len() as f64;
    phi.iter().map(|p| (p - mean).abs()).fold(0.0, f64::max)
}

#[test]
fn fwd10_flies_for_every_truth() {
    let (_, speed, text) = FLIGHTS.iter().find(|f| f.0 == "fwd10").unwrap();
    assert_eq!(*speed, 10.0);
    assert!(
        text.contains("w20_m_s = 7.7"),
        "fwd10 in the light turbulence"
    );
    let dir = std::env::temp_dir().join(format!("helicon-paramid-fwd10-{}", std::process::id()));
    let mut worst = 0.0_f64;
    for (name, truth) in TRUTHS {
        let p = Params::from_toml_str(truth, name).unwrap();
        for seed in [1, 3, 7] {
            let log = dir.join(format!("{name}-{seed}")).join("log.csv");
            fly_scenario("fwd10", text, &p, Some(seed), &log)
                .unwrap_or_else(|e| panic!("{name}, seed {seed}: {e}"));
            assert!(std::fs::metadata(&log).unwrap().len() > 1_000_000);
            let roll = roll_excursion_rad(&log);
            println!("{name} seed {seed}: largest roll excursion {roll:.3} rad");
            worst = worst.max(roll);
            let _ = std::fs::remove_file(&log);
        }
    }
    // no growing oscillation: the roll stays within a sixth of the 1.2 rad
    // divergence limit (measured worst 0.058 rad, truth b seed 1; the Hs
    // design had ±0.4 rad at 40-50 s)
    assert!(worst < 0.2, "largest roll excursion {worst} rad");
    let _ = std::fs::remove_dir_all(&dir);
}
