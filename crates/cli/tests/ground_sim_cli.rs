//! `helicon sim scenarios/ground-to-ground.toml` as a user runs it: the
//! ground files (`ground.csv` with the on-board spool state and land
//! detector's stage, `ground.png`/`.svg`) and the `ground` object of
//! `summary.json` with the time from arming to lift-off.
#![allow(clippy::unwrap_used)] // test helpers: a failed unwrap is a failed test

use helicon_flight::landing::{LandStage, SpoolState};
use helicon_sim::output::GROUND_COLUMNS;
use helicon_test_support::tmpdir;
use std::path::Path;
use std::process::Command;

#[test]
fn sim_of_the_ground_to_ground_scenario_writes_the_ground_files() {
    let d = tmpdir("ground-sim");
    let scenario =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/ground-to-ground.toml");
    let out = d.join("run");
    let o = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args([
            "sim",
            scenario.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && !err.contains("panicked"), "{err}");
    // ground.csv: the documented columns, a row per kept sample
    let csv = std::fs::read_to_string(out.join("ground.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next().unwrap(), GROUND_COLUMNS.join(","));
    let col = |name: &str| GROUND_COLUMNS.iter().position(|c| *c == name).unwrap();
    let (spool, stage) = (col("spool_state"), col("land_stage"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    // 45 s at 400 Hz, every 4th sample kept, and the last
    assert_eq!(rows.len(), 45 * 400 / 4 + 1);
    assert!(rows.iter().all(|r| r.len() == GROUND_COLUMNS.len()));
    // every on-board spool state and land-detector stage appears, each a
    // valid code
    for (c, n) in [
        (spool, SpoolState::ALL.len()),
        (stage, LandStage::ALL.len()),
    ] {
        for k in 0..n {
            assert!(
                rows.iter().any(|r| r[c] == k as f64),
                "{} never {k}",
                GROUND_COLUMNS[c]
            );
        }
        assert!(
            rows.iter()
                .all(|r| r[c] >= 0.0 && r[c] < n as f64 && r[c].fract() == 0.0)
        );
    }
    // the plots: a PNG (its signature) and an SVG
    let png = std::fs::read(out.join("ground.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let svg = std::fs::read_to_string(out.join("ground.svg")).unwrap();
    for name in [
        "spooling up",
        "taking off",
        "maybe landed",
        "ground contact",
    ] {
        assert!(svg.contains(name), "the state axis lacks {name}");
    }
    // summary.json: the time from arming to lift-off, its own metric
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let g = &summary["ground"];
    let arm = g["arm_time_s"].as_f64().unwrap();
    let lo = g["liftoff_time_s"].as_f64().unwrap();
    assert_eq!(g["arm_to_liftoff_s"].as_f64().unwrap(), lo - arm);
}
