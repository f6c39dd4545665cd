//! `helicon design --schedule`: the files it writes, the check it prints,
//! and errors naming the envelope file and field.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests: a failed unwrap is a failed test

use helicon_test_support::tmpdir;
use std::process::Command;

#[test]
fn design_schedule_writes_the_schedule_the_map_and_the_check() {
    let d = tmpdir("ok");
    std::fs::write(
        d.join("env.toml"),
        "name = \"small\"\n[grid]\nforward_m_s = [0.0, 5.0]\nlateral_m_s = [0.0]\ndown_m_s = [0.0]\n[check]\nsubdivisions = 1\n",
    )
    .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .current_dir(&d)
        .args(["design", "--schedule", "env.toml", "--out", "gains"])
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        out.contains("2 design points") && out.contains("frozen-point check: 3 points"),
        "{out}"
    );
    for f in [
        "schedule.json",
        "envelope.csv",
        "frozen_check.csv",
        "envelope.png",
    ] {
        assert!(d.join("gains").join(f).exists(), "{f} missing");
    }
    let csv = std::fs::read_to_string(d.join("gains/envelope.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3);
    // the schedule reads back
    let s = helicon_gnc::schedule::Schedule::load(&d.join("gains/schedule.json")).unwrap();
    assert_eq!(s.points.len(), 2);
}

#[test]
fn design_schedule_errors_name_the_file_and_field() {
    let d = tmpdir("bad");
    std::fs::write(d.join("env.toml"), "[grid]\nforward_m_s = [5.0, 0.0]\n").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_helicon"))
        .current_dir(&d)
        .args(["design", "--schedule", "env.toml"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("env.toml") && err.contains("forward_m_s") && err.contains("increasing"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}
