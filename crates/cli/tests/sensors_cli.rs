//! End-to-end tests of `helicon attitude`, `helicon sensors simulate` and
//! `helicon fuse`, including bad inputs (errors, never panics).
#![allow(clippy::too_many_lines, clippy::panic, clippy::cast_possible_wrap)] // tests: long scenarios, panics are failures
#![allow(clippy::unwrap_used)] // test helpers: a failed unwrap is a failed test

use helicon_test_support::tmpdir;
use std::process::{Command, Output};

fn helicon(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_helicon"))
        .args(args)
        .output()
        .unwrap()
}

fn no_panic(o: &Output) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "panic: {err}");
}

#[test]
fn attitude_batch_thesis_example_and_degenerate_row() {
    let d = tmpdir("att");
    let input = d.join("obs.csv");
    std::fs::write(
        &input,
        "w1,b1x,b1y,b1z,r1x,r1y,r1z,w2,b2x,b2y,b2z,r2x,r2y,r2z,w3,b3x,b3y,b3z,r3x,r3y,r3z\n\
         1,0.8273,0.5541,-0.0920,-0.1517,-0.9669,0.2050,1,-0.8285,0.5522,-0.0955,-0.8393,0.4494,-0.3044,,,,,,,\n\
         1,0,0,1,0,0,1,1,1,0,0,0,1,0,1,0,1,0,-1,0,0\n",
    )
    .unwrap();
    let o = helicon(&["attitude", "--input", input.to_str().unwrap()]);
    no_panic(&o);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8(o.stdout).unwrap();
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "qw,qx,qy,qz,phi,theta,psi,loss");
    let v: Vec<f64> = lines[1].split(',').map(|s| s.parse().unwrap()).collect();
    // SciPy fixture value for the thesis example (tools/gen_attitude_fixtures.py).
    assert!((v[0] - 0.026405421263470022).abs() < 1e-9, "{v:?}");
    assert!((v[1] - 0.8409940198104663).abs() < 1e-9);
    assert!((v[2] + 0.5019804444851943).abs() < 1e-9);
    // Row 2: body = ned rotated 90° about down (psi = +90°).
    let v: Vec<f64> = lines[2].split(',').map(|s| s.parse().unwrap()).collect();
    assert!((v[6] - std::f64::consts::FRAC_PI_2).abs() < 1e-12, "{v:?}");

    // Degenerate row: two parallel observations → error naming the row.
    std::fs::write(&input, "w1,b1x,b1y,b1z,r1x,r1y,r1z,w2,b2x,b2y,b2z,r2x,r2y,r2z\n1,1,0,0,0,1,0,1,0,0,1,0,0,1\n1,1,0,0,1,0,0,2,2,0,0,3,0,0\n").unwrap();
    let out_file = d.join("out.csv");
    let o = helicon(&[
        "attitude",
        "--input",
        input.to_str().unwrap(),
        "--out",
        out_file.to_str().unwrap(),
    ]);
    no_panic(&o);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("row 2") && err.contains("degenerate"), "{err}");
    // Non-numeric cell.
    std::fs::write(&input, "w1,b1x,b1y,b1z,r1x,r1y,r1z\n1,x,0,0,0,1,0\n").unwrap();
    let o = helicon(&["attitude", "--input", input.to_str().unwrap()]);
    no_panic(&o);
    assert!(String::from_utf8_lossy(&o.stderr).contains("row 1"));
}

#[test]
fn simulate_then_fuse_beats_gps_and_rejects_bad_logs() {
    let d = tmpdir("fuse");
    let log = d.join("log.csv");
    let o = helicon(&[
        "sensors",
        "simulate",
        "--duration-s",
        "60",
        "--seed",
        "3",
        "--out",
        log.to_str().unwrap(),
    ]);
    no_panic(&o);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = d.join("run");
    let o = helicon(&[
        "fuse",
        log.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    no_panic(&o);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "fused.csv",
        "summary.json",
        "position.png",
        "position.svg",
        "attitude.png",
        "attitude.svg",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let fused = summary["rms_horizontal_position_error_m"].as_f64().unwrap();
    let gps = summary["rms_gps_horizontal_error_m"].as_f64().unwrap();
    let att = summary["rms_attitude_error_rad"].as_f64().unwrap();
    println!(
        "fuse: horizontal RMS fused {fused:.3} m vs GPS {gps:.3} m; attitude RMS {att:.4} rad"
    );
    assert!(fused < gps, "fused {fused} vs gps {gps}");
    assert!(att < 0.05);
    // the same log through the ESKF
    let out_eskf = d.join("run_eskf");
    let o = helicon(&[
        "fuse",
        log.to_str().unwrap(),
        "--out",
        out_eskf.to_str().unwrap(),
        "--estimator",
        "eskf",
    ]);
    no_panic(&o);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_eskf.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(s["estimator"], "eskf");
    assert!(s["rejected_updates"].as_u64().is_some());
    assert_eq!(s["gyro_bias_rad_s"].as_array().unwrap().len(), 3);
    let fused_eskf = s["rms_horizontal_position_error_m"].as_f64().unwrap();
    let att_eskf = s["rms_attitude_error_rad"].as_f64().unwrap();
    println!(
        "fuse --estimator eskf: horizontal RMS {fused_eskf:.3} m; attitude RMS {att_eskf:.4} rad"
    );
    assert!(fused_eskf < gps, "ESKF {fused_eskf} vs gps {gps}");
    assert!(att_eskf < att, "ESKF attitude {att_eskf} vs thesis {att}");

    let text = std::fs::read_to_string(&log).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    // Hostile cells: each an error naming the file, the line and the column.
    // (line numbers: 1 comment + 1 header, so data row i is line i + 1)
    for (name, col, cell, expect) in [
        ("nan", 1, "NaN", "fx_m_s2"),
        ("text", 2, "abc", "fy_m_s2"),
        ("trunc", 3, "0.", "truncated"),
        ("huge", 3, "1e308", "physical bound"),
        ("inf", 4, "inf", "p_rad_s"),
    ] {
        let mut bad = lines.clone();
        let mut cells: Vec<String> = bad[100].split(',').map(str::to_string).collect();
        cells[col] = cell.into();
        bad[100] = cells.join(",");
        let f = d.join(format!("{name}.csv"));
        std::fs::write(&f, bad.join("\n")).unwrap();
        let o = helicon(&[
            "fuse",
            f.to_str().unwrap(),
            "--out",
            d.join(format!("{name}_out")).to_str().unwrap(),
        ]);
        no_panic(&o);
        assert!(!o.status.success(), "{name} accepted");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(&format!("{name}.csv:101:")) && err.contains(expect),
            "{name}: {err}"
        );
    }
    // A duplicated column → error naming it.
    let mut dup = lines.clone();
    dup[1] = dup[1].replacen("fy_m_s2", "fx_m_s2", 1);
    std::fs::write(d.join("dup.csv"), dup.join("\n")).unwrap();
    let o = helicon(&[
        "fuse",
        d.join("dup.csv").to_str().unwrap(),
        "--out",
        d.join("dup_out").to_str().unwrap(),
    ]);
    no_panic(&o);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("fx_m_s2") && err.contains("twice"), "{err}");
    // A non-finite magnetic field on the command line.
    let o = helicon(&[
        "fuse",
        log.to_str().unwrap(),
        "--out",
        d.join("mag_out").to_str().unwrap(),
        "--mag-field-ned",
        "nan",
        "0",
        "0",
    ]);
    no_panic(&o);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--mag-field-ned"));
    // Time going backwards → error naming the row.
    let mut back = lines.clone();
    let mut cells: Vec<String> = back[50].split(',').map(str::to_string).collect();
    cells[0] = "0.001".into();
    back[50] = cells.join(",");
    std::fs::write(d.join("back.csv"), back.join("\n")).unwrap();
    let o = helicon(&[
        "fuse",
        d.join("back.csv").to_str().unwrap(),
        "--out",
        d.join("back_out").to_str().unwrap(),
    ]);
    no_panic(&o);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("backwards") && err.contains("back.csv:51:"),
        "{err}"
    );
    // Missing column → error naming it.
    lines[1] = lines[1].replace("gps_d_m", "gps_x");
    std::fs::write(d.join("miss.csv"), lines.join("\n")).unwrap();
    let o = helicon(&[
        "fuse",
        d.join("miss.csv").to_str().unwrap(),
        "--out",
        d.join("miss_out").to_str().unwrap(),
    ]);
    no_panic(&o);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("gps_d_m"));
    // Bad sensor config → error naming file and field.
    std::fs::write(d.join("s.toml"), "[gps]\nrate_hz = 50.0\n").unwrap();
    let o = helicon(&[
        "sensors",
        "simulate",
        "--config",
        d.join("s.toml").to_str().unwrap(),
        "--duration-s",
        "1",
    ]);
    no_panic(&o);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("s.toml") && err.contains("gps.rate_hz"),
        "{err}"
    );
}
