//! Runs `helicon ident frf` and `helicon ident tf` as a user would: a log of
//! a known second-order system driven by a sweep (written here, Tustin
//! discretisation), the response and the fit checked against the system;
//! bad logs refused with the file, column and line.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;
use common::{helicon, tmpdir};
use std::fmt::Write as _;
use std::path::Path;

/// ωn²/(s² + 2ζωn s + ωn²), ωn = 8, ζ = 0.3, RK4 at 1/10 of the step on the
/// linearly interpolated input; a log `t_s,servo,rate` at 200 Hz, with the
/// time column jittered by `jitter` (fraction of a step) when asked.
fn write_log(dir: &Path, jitter: f64) -> String {
    let dt = 0.005;
    let n = 24_000;
    let sweep = helicon_ident::inputs::Sweep::new(0.1, 0.5, 40.0, 115.0).unwrap();
    let u: Vec<f64> = (0..n).map(|i| sweep.value(i as f64 * dt)).collect();
    let (wn, z) = (8.0_f64, 0.3);
    let f = |x: [f64; 2], uu: f64| [x[1], wn * wn * (uu - x[0]) - 2.0 * z * wn * x[1]];
    let mut x = [0.0; 2];
    let mut text = String::from("# a comment line\nt_s,servo,rate\n");
    for i in 0..n {
        let tj = i as f64 * dt + if i % 2 == 1 { jitter * dt } else { 0.0 };
        writeln!(text, "{tj},{},{}", u[i], x[0]).unwrap();
        let h = dt / 10.0;
        for j in 0..10 {
            let ui = |s: f64| {
                let next = u.get(i + 1).copied().unwrap_or(0.0);
                u[i] + (next - u[i]) * s
            };
            let s0 = j as f64 / 10.0;
            let k1 = f(x, ui(s0));
            let k2 = f(
                [x[0] + h / 2.0 * k1[0], x[1] + h / 2.0 * k1[1]],
                ui(s0 + 0.05),
            );
            let k3 = f(
                [x[0] + h / 2.0 * k2[0], x[1] + h / 2.0 * k2[1]],
                ui(s0 + 0.05),
            );
            let k4 = f([x[0] + h * k3[0], x[1] + h * k3[1]], ui(s0 + 0.1));
            for c in 0..2 {
                x[c] += h / 6.0 * (k1[c] + 2.0 * k2[c] + 2.0 * k3[c] + k4[c]);
            }
        }
    }
    let p = dir.join("log.csv");
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

#[test]
fn frf_then_tf_recover_a_known_system() {
    let dir = tmpdir("known");
    let log = write_log(&dir, 0.0);
    let out = dir.join("out").display().to_string();
    let (ok, so, se) = helicon(&[
        "ident",
        "frf",
        &log,
        "--input",
        "servo",
        "--output",
        "rate",
        "--omega-min",
        "1",
        "--omega-max",
        "30",
        "--points",
        "120",
        "--out",
        &out,
    ]);
    assert!(ok, "{so}{se}");
    let frf = std::fs::read_to_string(dir.join("out/frf.csv")).unwrap();
    let mut lines = frf.lines();
    assert_eq!(
        lines.next().unwrap(),
        "output,omega_rad_s,mag_db,phase_deg,coherence,random_error"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').skip(1).map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 120);
    for r in &rows {
        let s = helicon_ident::Complex64::new(0.0, r[0]);
        let h = 64.0 / (s * s + 4.8 * s + 64.0);
        let dmag = r[1] - 20.0 * h.norm().log10();
        let dph = r[2] - h.arg().to_degrees();
        // Noise-free: Hann leakage of the sweep only (< 0.3 dB, 2°).
        assert!(
            dmag.abs() < 0.3 && dph.abs() < 2.0,
            "{r:?}: {dmag} dB {dph}°"
        );
        assert!(r[3] > 0.95 && r[3] <= 1.0);
    }
    assert!(dir.join("out/bode_rate.png").exists());
    let (ok, so, se) = helicon(&[
        "ident",
        "tf",
        &dir.join("out/frf.csv").display().to_string(),
        "--output",
        "rate",
        "--num",
        "0",
        "--den",
        "2",
        "--out",
        &out,
    ]);
    assert!(ok, "{so}{se}");
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/tf_rate.json")).unwrap())
            .unwrap();
    let den: Vec<f64> = fit["den"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let num = fit["num"][0].as_f64().unwrap();
    // Within 2 % (the leakage bias above; the fit of the analytic response is
    // exact, see the ident crate's tests).
    assert!(
        (den[1] - 4.8).abs() < 0.02 * 4.8 && (den[2] - 64.0).abs() < 0.02 * 64.0,
        "{den:?}"
    );
    assert!((num - 64.0).abs() < 0.02 * 64.0, "{num}");
    assert_eq!(fit["parameters"].as_array().unwrap().len(), 3);
    assert!(fit["verification"].is_null());
    // Verification on another log of the same system (here: the sweep log itself
    // with a jittered clock): Theil well below the 0.25 of a good fit.
    let other = dir.join("other");
    std::fs::create_dir_all(&other).unwrap();
    let vlog = write_log(&other, 0.2);
    let (ok, so, se) = helicon(&[
        "ident",
        "tf",
        &dir.join("out/frf.csv").display().to_string(),
        "--output",
        "rate",
        "--num",
        "0",
        "--den",
        "2",
        "--out",
        &out,
        "--verify",
        &vlog,
        "--verify-input",
        "servo",
        "--verify-output",
        "rate",
    ]);
    assert!(ok, "{so}{se}");
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/tf_rate.json")).unwrap())
            .unwrap();
    let tic = fit["verification"]["theil"].as_f64().unwrap();
    assert!(tic < 0.05, "{tic}");
    assert!(dir.join("out/verify_rate.png").exists());
    assert!(dir.join("out/tf_rate.png").exists());
    // Unknown output: the outputs available are named.
    let (ok, _, se) = helicon(&[
        "ident",
        "tf",
        &dir.join("out/frf.csv").display().to_string(),
        "--output",
        "nope",
        "--num",
        "0",
        "--den",
        "2",
        "--out",
        &out,
    ]);
    assert!(
        !ok && se.contains("no rows for output `nope`") && se.contains("rate"),
        "{se}"
    );
}

#[test]
fn irregular_time_is_resampled_and_stated() {
    let dir = tmpdir("jitter");
    let log = write_log(&dir, 0.2);
    let out = dir.join("out").display().to_string();
    let (ok, so, se) = helicon(&[
        "ident",
        "frf",
        &log,
        "--input",
        "servo",
        "--output",
        "rate",
        "--omega-max",
        "20",
        "--out",
        &out,
    ]);
    assert!(ok, "{so}{se}");
    assert!(se.contains("resampled by linear interpolation"), "{se}");
}

#[test]
fn bad_logs_are_refused_with_file_column_and_line() {
    let dir = tmpdir("bad");
    let mut text = String::from("t_s,servo,rate\n");
    for i in 0..100 {
        let r = if i == 50 {
            "abc".to_string()
        } else {
            format!("{}", i as f64 * 0.1)
        };
        writeln!(text, "{},{},{}", i as f64 * 0.01, (i as f64).sin(), r).unwrap();
    }
    let p = dir.join("bad.csv");
    std::fs::write(&p, &text).unwrap();
    let ps = p.display().to_string();
    let out = dir.join("out").display().to_string();
    let (ok, _, se) = helicon(&[
        "ident", "frf", &ps, "--input", "servo", "--output", "rate", "--out", &out,
    ]);
    assert!(
        !ok && se.contains("bad.csv") && se.contains("line 52") && se.contains("`rate`"),
        "{se}"
    );
    let (ok, _, se) = helicon(&[
        "ident", "frf", &ps, "--input", "servo", "--output", "pitch", "--out", &out,
    ]);
    assert!(!ok && se.contains("no column `pitch`"), "{se}");
    // a misspelt column: the nearest one suggested
    let (ok, _, se) = helicon(&[
        "ident", "frf", &ps, "--input", "servo", "--output", "rte", "--out", &out,
    ]);
    assert!(
        !ok && se.contains("no column `rte`") && se.contains("did you mean `rate`?"),
        "{se}"
    );
    // NaN and a time gap.
    let nan = text.replace("abc", "NaN");
    std::fs::write(&p, nan).unwrap();
    let (ok, _, se) = helicon(&[
        "ident", "frf", &ps, "--input", "servo", "--output", "rate", "--out", &out,
    ]);
    assert!(!ok && se.contains("not finite"), "{se}");
    let gap: String = text
        .replace("abc", "1")
        .lines()
        .enumerate()
        .filter(|(i, _)| !(30..40).contains(i))
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    std::fs::write(&p, gap).unwrap();
    let (ok, _, se) = helicon(&[
        "ident", "frf", &ps, "--input", "servo", "--output", "rate", "--out", &out,
    ]);
    assert!(!ok && se.contains("gap"), "{se}");
    let (ok, _, se) = helicon(&[
        "ident", "frf", &ps, "--input", "servo", "--output", "servo", "--out", &out,
    ]);
    assert!(!ok && se.contains("named twice"), "{se}");
}

#[test]
fn input_command_samples_a_toml_input() {
    let dir = tmpdir("input");
    let p = dir.join("d.toml");
    std::fs::write(&p, "kind = \"3211\"\namplitude = 0.05\npulse_s = 0.5\n").unwrap();
    let out = dir.join("d.csv").display().to_string();
    let (ok, so, se) = helicon(&[
        "ident",
        "input",
        &p.display().to_string(),
        "--dt",
        "0.01",
        "--out",
        &out,
    ]);
    assert!(ok, "{so}{se}");
    let text = std::fs::read_to_string(&out).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 351);
    let integral: f64 = rows.iter().map(|r| r[1]).sum::<f64>() * 0.01;
    // 3211: (3 − 2 + 1 − 1) × 0.5 s × 0.05 = 0.025.
    assert!((integral - 0.025).abs() < 1e-3, "{integral}");
    std::fs::write(&p, "kind = \"sweep\"\namplitude = 0.1\nomega_min_rad_s = 1\nomega_max_rad_s = 10\nduration_s = 10\n").unwrap();
    let (ok, _, se) = helicon(&["ident", "input", &p.display().to_string(), "--out", &out]);
    assert!(
        !ok && se.contains("d.toml") && se.contains("sweep.duration_s"),
        "{se}"
    );
}
