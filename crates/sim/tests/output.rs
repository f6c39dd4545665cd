//! Run outputs: the files of a run folder, the `log.csv` layout and
//! decimation, the `summary.json` keys, and the gains round trip (flying the
//! saved gains reproduces the run bit for bit).
#![allow(clippy::unwrap_used, missing_docs)] // tests: a failed unwrap is a failed test

use helicon_core::frames::wrap_pi;
use helicon_gnc::design::Gains;
use helicon_model::state::{INPUT_NAMES, STATE_NAMES, ix};
use helicon_sim::closed_loop::{Outcome, fly, prepare};
use helicon_sim::output::{LOG_COLUMNS, MEASURED_NAMES, log_header, write_run};
use helicon_sim::scenario::Scenario;
use std::path::PathBuf;

fn tmpdir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("output_{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A short flight with a step, wind and a decimated log.
const SHORT: &str = r#"
name = "short"
preset = "physical"
duration_s = 1.0
[initial]
psi = 0.2
[[reference]]
t_s = 0.2
output = "vn"
value = 1.0
[wind]
seed = 3
[wind.steady]
wind_ned_m_s = [1.0, 0.5, 0.0]
[log]
decimation = 3
"#;

fn csv_rows(path: &std::path::Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn run_folder_files_csv_and_json() {
    let s = Scenario::from_toml_str(SHORT, "short.toml").unwrap();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    assert_eq!(f.summary.outcome, Outcome::Completed);
    let n = f.log.len();
    // 1 s at 400 Hz is 401 samples; the flight keeps every 3rd (k = 0, 3, …,
    // 399: 134) and the last one (k = 400): 135
    assert_eq!(n, 135, "decimated flight log");
    assert_eq!(f.log.last().unwrap().t_s, 1.0);
    assert!((f.log[1].t_s - 3.0 / 400.0).abs() < 1e-15);
    let dir = tmpdir("files");
    let files = write_run(&dir, &s, &p, &f).unwrap();
    for path in [
        &files.log,
        &files.summary,
        &files.gains,
        &files.scenario,
        &files.report,
    ] {
        assert!(std::fs::metadata(path).unwrap().len() > 0, "{path:?}");
    }
    // plots: each PNG has its SVG; the wind plot is there because there is wind
    let names: Vec<String> = files
        .plots
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for stem in [
        "output_vn",
        "output_ve",
        "output_vd",
        "output_psi",
        "servos",
        "wind",
        "estimator_error_attitude",
        "estimator_error_velocity",
        "estimator_error_rates",
        "inflow",
    ] {
        for ext in ["png", "svg"] {
            let name = format!("{stem}.{ext}");
            assert!(names.contains(&name), "{name} missing from {names:?}");
            assert!(dir.join(&name).exists());
        }
    }
    let png = std::fs::read(dir.join("output_vn.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let report = std::fs::read_to_string(&files.report).unwrap();
    assert!(report.contains("completed"));
    assert!(report.contains("(output_vn.png)"));
    assert!(report.contains("| vn |"));

    // log.csv: header, 76 columns, every 3rd sample from t = 0, exact values
    let (header, rows) = csv_rows(&files.log);
    assert_eq!(header, log_header());
    assert_eq!(header.len(), LOG_COLUMNS);
    assert_eq!(LOG_COLUMNS, 76);
    assert_eq!(header[0], "t_s");
    assert_eq!(&header[1..31], &STATE_NAMES.map(str::to_string)[..]);
    assert_eq!(&header[31..35], &INPUT_NAMES.map(str::to_string)[..]);
    for name in [
        "ref_vn",
        "ref_psi",
        "vn",
        "vd",
        "est_phi",
        "err_psi",
        "meas_r",
        "wind_n",
        "wind_d",
        "lambda_mr",
        "lambda_tr",
        "thrust_mr_n",
        "force_tr_y_n",
    ] {
        assert!(header.iter().any(|h| h == name), "{name}");
    }
    assert_eq!(rows.len(), n);
    assert_eq!(files.log_rows, rows.len());
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), LOG_COLUMNS);
        let r = &f.log[k];
        // the shortest round-trip text reads back to the same f64
        assert_eq!(row[0].to_bits(), r.t_s.to_bits());
        assert_eq!(row[col("psi")].to_bits(), r.x[ix::PSI].to_bits());
        assert_eq!(row[col("S_tr")].to_bits(), r.u[3].to_bits());
        assert_eq!(row[col("ref_vn")], r.reference[0]);
        assert_eq!(row[col("vn")], r.output[0]);
        assert_eq!(row[col("est_q")], r.estimate9[7]);
        assert_eq!(row[col("meas_theta")], r.measured9[1]);
        assert_eq!(row[col("wind_e")], 0.5);
        assert_eq!(row[col("lambda_mr")], r.lambda[0]);
        assert_eq!(row[col("force_tr_y_n")], r.thrust[1]);
        for (i, m) in MEASURED_NAMES.iter().enumerate() {
            let mut d = r.x[i + 3] - r.estimate9[i];
            if i == 2 {
                d = wrap_pi(d);
            }
            assert_eq!(row[col(&format!("err_{m}"))], d, "err_{m}");
        }
    }
    assert!((rows[1][0] - 3.0 * 0.0025).abs() < 1e-15);
    // the step at 0.2 s is in the reference column
    assert_eq!(rows[0][col("ref_vn")], 0.0);
    assert_eq!(rows.last().unwrap()[col("ref_vn")], 1.0);

    // summary.json
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&files.summary).unwrap()).unwrap();
    assert_eq!(v["outcome"], "completed");
    assert!(v["reason"].is_null());
    assert_eq!(v["t_end_s"].as_f64().unwrap(), f.summary.t_end_s);
    assert_eq!(v["scenario"], "short");
    for out in ["vn", "ve", "vd", "psi"] {
        let m = &v["metrics"][out];
        for key in [
            "settling_time_s",
            "overshoot_pct",
            "rms_error",
            "max_abs_error",
        ] {
            assert!(m.get(key).is_some(), "metrics.{out}.{key}");
        }
        assert!(m["rms_error"].as_f64().unwrap() >= 0.0);
    }
    // 1 s is too short for the 1 m/s step to settle to 1 %: null
    assert!(v["metrics"]["vn"]["settling_time_s"].is_null());
    let max_vn = v["metrics"]["vn"]["max_abs_error"].as_f64().unwrap();
    assert!(max_vn > 0.9 && max_vn <= 1.0, "{max_vn}");
    for key in [
        "control_effort_rms",
        "saturation_time_s",
        "estimator_error_rms",
    ] {
        assert!(v[key].is_array(), "{key}");
    }
    assert_eq!(v["estimator_error_rms"].as_array().unwrap().len(), 9);
    assert_eq!(v["wind_seed"], 3);
    assert!(v["sensor_seed"].is_u64());
    assert_eq!(v["parameter_hash"].as_str().unwrap().len(), 16);
    assert_eq!(v["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(v["preset"], "physical");

    // scenario.toml reads back to the scenario flown
    let back = Scenario::from_file(&files.scenario).unwrap();
    let mut expected = s.clone();
    expected.base_dir = back.base_dir.clone();
    assert_eq!(back, expected);
}

#[test]
fn flying_the_saved_gains_reproduces_the_run_bit_for_bit() {
    // thesis wind (random) and fusion off; the estimator in the loop
    let text = SHORT.replace(
        "[wind.steady]\nwind_ned_m_s = [1.0, 0.5, 0.0]",
        "[wind.thesis]",
    );
    let s = Scenario::from_toml_str(&text, "gains.toml").unwrap();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    let dir = tmpdir("gains");
    let files = write_run(&dir, &s, &p, &f).unwrap();
    let loaded = Gains::load(&files.gains).unwrap();
    assert_eq!(loaded, p.gains, "gains.json is an exact copy");

    // the run folder's scenario.toml with gains_file = "gains.json"
    let mut s2 = Scenario::from_file(&files.scenario).unwrap();
    assert!(s2.controller.gains_file.is_none());
    s2.controller.gains_file = Some(PathBuf::from("gains.json"));
    let p2 = prepare(&s2).unwrap();
    assert_eq!(p2.gains, p.gains);
    let f2 = fly(&s2, &p2, None).unwrap();
    assert_eq!(f2.summary, f.summary);
    assert_eq!(f2.log, f.log);
    let j1 = serde_json::to_string(&f.summary).unwrap();
    let j2 = serde_json::to_string(&f2.summary).unwrap();
    assert_eq!(j1, j2);

    // and the copy written for that run points at the absolute gains file
    let dir2 = tmpdir("gains2");
    let files2 = write_run(&dir2, &s2, &p2, &f2).unwrap();
    let s3 = Scenario::from_file(&files2.scenario).unwrap();
    let g = s3.controller.gains_file.unwrap();
    assert!(g.is_absolute(), "{g:?}");
    assert_eq!(
        std::fs::read_to_string(&files2.gains).unwrap(),
        std::fs::read_to_string(&files.gains).unwrap()
    );
}

#[test]
fn a_diverged_run_is_written_with_its_reason() {
    // open loop from a tilted start with a tight attitude limit
    let text = r#"
name = "falls"
duration_s = 2.0
[initial]
vn = 6.0
[controller]
feedback = false
[plant]
max_attitude_rad = 0.1
"#;
    let s = Scenario::from_toml_str(text, "falls.toml").unwrap();
    let p = prepare(&s).unwrap();
    let f = fly(&s, &p, None).unwrap();
    assert_eq!(f.summary.outcome, Outcome::Diverged);
    let dir = tmpdir("diverged");
    let files = write_run(&dir, &s, &p, &f).unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&files.summary).unwrap()).unwrap();
    assert_eq!(v["outcome"], "diverged");
    let reason = v["reason"].as_str().unwrap();
    assert!(reason.contains("attitude"), "{reason}");
    assert!(v["t_end_s"].as_f64().unwrap() < 2.0);
    let (_, rows) = csv_rows(&files.log);
    assert_eq!(rows.len(), f.log.len());
    assert!(rows.len() > 1);
    let report = std::fs::read_to_string(&files.report).unwrap();
    assert!(report.contains("diverged"), "{report}");
    // no wind: no wind plot
    assert!(!dir.join("wind.png").exists());
}
