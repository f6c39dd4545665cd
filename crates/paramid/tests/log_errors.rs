//! A log named in an IDENT.toml that cannot be used: its errors name the
//! IDENT.toml, the field (`operating_point[1].log`, `verification[0].log`)
//! and the log, whichever the log's format (a `log.csv` or a flight
//! computer's ULog, whose own errors add the topic, the field and the
//! time); a span in which the control law did not drive the servos
//! (`servo_source` ≠ 0: the pilot or a failsafe) is refused naming its
//! first and last time. The logs are written with the project's own
//! writers.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests: a failed unwrap is a failed test

use helicon_paramid::config::IdentConfig;
use helicon_paramid::data::{measure, read_record};
use helicon_ulog::synthetic::{servo_record, write_control_log};
use std::path::{Path, PathBuf};

/// The control period of the Bergen Twin's parameters (the IDENT.toml's
/// default start), s.
const T_S: f64 = 0.0025;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "helicon_paramid_log_errors_{}_{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A flight log of `n` control steps of 2500 µs from t = 1 s (the
/// synthetic log's values); step `k`'s `measured[7]` (meas_q) is
/// `meas_q(k)`; a `servo_output` record after each `control` record when
/// `source` is given, with the source of step `k`.
fn write_ulog(
    path: &Path,
    n: u64,
    meas_q: impl Fn(u64) -> f64,
    source: Option<&dyn Fn(u64) -> u8>,
) {
    write_control_log(
        path,
        n,
        |k| Some(1_000_000 + k * 2500),
        |k, c| c.measured[7] = meas_q(k),
        |k, c| source.map(|s| servo_record(c, s(k))),
    )
    .unwrap();
}

/// A log.csv of `n` rows every 2.5 ms from t = 1 s with the servo columns
/// and meas_q; `servo_source` a column when given; row `k`'s meas_q is
/// `meas_q(k)` as text.
fn write_csv(
    path: &Path,
    n: u64,
    meas_q: impl Fn(u64) -> String,
    source: Option<&dyn Fn(u64) -> u8>,
) {
    let mut text = String::from("t_s,S_col,S_lat,S_lon,S_tr,meas_q");
    if source.is_some() {
        text.push_str(",servo_source");
    }
    text.push('\n');
    for k in 0..n {
        let v = |i: u64| ((k as f64) * 0.37 + i as f64).sin();
        text.push_str(&format!(
            "{},{},{},{},{},{}",
            (1_000_000 + k * 2500) as f64 / 1e6,
            v(0),
            v(1),
            v(2),
            v(3),
            meas_q(k)
        ));
        if let Some(s) = source {
            text.push_str(&format!(",{}", s(k)));
        }
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

/// Two operating points (the second's log is `log`, its span
/// `[t_start_s, t_end_s]`) and a verification on `log`.
fn ident(d: &Path, log: &str, span: &str) -> IdentConfig {
    let text = format!(
        r#"
windows_s = [0.1]
[[operating_point]]
name = "hover"
log = "other.csv"
[[operating_point]]
name = "fwd"
velocity_ned_m_s = [2.0, 0.0, 0.0]
log = "{log}"
{span}
[[response]]
input = "S_lon"
output = "meas_q"
omega_min_rad_s = 1.5
omega_max_rad_s = 25.0
[[parameter]]
key = "body.iyy_kg_m2"
min = 0.3
max = 1.2
[[verification]]
operating_point = "hover"
log = "{log}"
outputs = ["meas_q"]
"#
    );
    IdentConfig::from_toml_str(&text, "bad.toml", d).unwrap()
}

fn all_in(e: &str, parts: &[&str]) {
    for p in parts {
        assert!(e.contains(p), "`{p}` missing from: {e}");
    }
}

/// Reads the log `log` both as operating point 1 and as verification 0 of
/// `cfg`: each error names the IDENT.toml, its own field, the log and the
/// given parts (`op` for the operating point, `verification` for the
/// verification flight).
fn both_refuse(cfg: &IdentConfig, log: &str, op: &[&str], verification: &[&str]) {
    let e = measure(cfg, 1).unwrap_err().to_string();
    all_in(&e, &["bad.toml", "operating_point[1].log", log]);
    all_in(&e, op);
    let start = cfg.start;
    let e = helicon_paramid::verify::verify(cfg, 0, &start, &start)
        .unwrap_err()
        .to_string();
    all_in(&e, &["bad.toml", "verification[0].log", log]);
    all_in(&e, verification);
}

#[test]
fn a_flight_log_error_names_the_ident_file_the_field_and_the_log() {
    let d = dir("ulog_nan");
    // meas_q not finite at step 150: t = 1 + 150 × 0.0025 = 1.375 s
    write_ulog(
        &d.join("flight.ulg"),
        400,
        |k| if k == 150 { f64::NAN } else { 0.0 },
        None,
    );
    let cfg = ident(&d, "flight.ulg", "");
    let at = ["control.measured[7]", "1.375"];
    both_refuse(&cfg, "flight.ulg", &at, &at);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_log_csv_error_names_the_ident_file_the_field_and_the_log() {
    let d = dir("csv_nan");
    write_csv(
        &d.join("log.csv"),
        400,
        |k| if k == 150 { "nan".into() } else { "0".into() },
        None,
    );
    let cfg = ident(&d, "log.csv", "");
    both_refuse(&cfg, "log.csv", &["meas_q"], &["meas_q"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_duplicated_control_stamp_is_a_sample_written_twice_not_time_going_back() {
    let d = dir("dup");
    let path = d.join("dup.ulg");
    // step 101 stamped as step 100 (t = 1.25 s): written twice
    write_control_log(
        &path,
        400,
        |k| Some(1_000_000 + (k - u64::from(k == 101)) * 2500),
        |_, _| {},
        |_, _| None,
    )
    .unwrap();
    let cfg = ident(&d, "dup.ulg", "");
    let e = measure(&cfg, 1).unwrap_err().to_string();
    all_in(
        &e,
        &[
            "bad.toml",
            "operating_point[1].log",
            "dup.ulg",
            "`control`",
            "1.25",
            "twice",
        ],
    );
    assert!(!e.contains("back in time"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// The pilot flew steps 200 … 279 (t = 1.5 … 1.6975 s), a failsafe 300 …
/// 309 (t = 1.75 … 1.7725 s); the law the rest.
fn source(k: u64) -> u8 {
    match k {
        200..=279 => 1,
        300..=309 => 2,
        _ => 0,
    }
}

#[test]
fn a_span_not_flown_by_the_law_is_refused_naming_its_times() {
    let d = dir("manual");
    write_ulog(&d.join("flight.ulg"), 400, |_| 0.0, Some(&source));
    write_csv(&d.join("log.csv"), 400, |_| "0".into(), Some(&source));
    let names = ["S_lon", "meas_q"];
    for log in ["flight.ulg", "log.csv"] {
        let path = d.join(log);
        let rec = |t0: Option<f64>, t1: Option<f64>| {
            read_record(
                &path,
                &names,
                t0,
                t1,
                T_S,
                "bad.toml",
                "operating_point[1].log",
            )
        };
        // the whole log: both spans named, first and last time each
        let e = rec(None, None).unwrap_err().to_string();
        all_in(
            &e,
            &[
                "bad.toml",
                "operating_point[1].log",
                log,
                "servo_source",
                "1.5 … 1.6975 s",
                "1.75 … 1.7725 s",
                "pilot",
                "failsafe",
                "t_start_s",
                "t_end_s",
            ],
        );
        // a span ending inside the manual part: named up to the span's end
        let e = rec(Some(1.2), Some(1.601)).unwrap_err().to_string();
        all_in(&e, &["1.5 … 1.6 s"]);
        assert!(!e.contains("1.75"), "{e}");
        // before and after: the law drove the servos
        let before = rec(None, Some(1.499)).unwrap();
        assert_eq!(before.t_s.len(), 200, "{log}");
        let after = rec(Some(1.774), None).unwrap();
        assert_eq!(after.t_s.len(), 90, "{log}");
        // between the two spans: 20 samples, too few, for that reason
        let e = rec(Some(1.699), Some(1.749)).unwrap_err().to_string();
        all_in(&e, &["at least 64 samples"]);
    }
    // through the IDENT.toml: operating point and verification
    let cfg = ident(&d, "flight.ulg", "");
    both_refuse(
        &cfg,
        "flight.ulg",
        &["1.5 … 1.6975 s"],
        &["1.75 … 1.7725 s"],
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_log_without_servo_source_is_taken_as_the_laws() {
    let d = dir("no_source");
    write_ulog(&d.join("flight.ulg"), 400, |_| 0.0, None);
    write_csv(&d.join("log.csv"), 400, |_| "0".into(), None);
    for log in ["flight.ulg", "log.csv"] {
        let r = read_record(
            &d.join(log),
            &["S_lon", "meas_q"],
            None,
            None,
            T_S,
            "bad.toml",
            "f",
        )
        .unwrap();
        assert_eq!(r.t_s.len(), 400, "{log}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_step_is_printed_to_the_nanosecond() {
    // a CSV whose step is not the control period: the step as the log's
    // text gives it, not 0.0049999999999998934
    let d = dir("step");
    let mut text = String::from("t_s,S_lon,meas_q\n");
    for k in 0..100 {
        text.push_str(&format!("{},0,0\n", 1.0 + k as f64 * 0.005));
    }
    std::fs::write(d.join("log.csv"), text).unwrap();
    let e = read_record(
        &d.join("log.csv"),
        &["S_lon", "meas_q"],
        None,
        None,
        T_S,
        "bad.toml",
        "f",
    )
    .unwrap_err()
    .to_string();
    all_in(&e, &["= 0.005:", "control period"]);
    let _ = std::fs::remove_dir_all(&d);
}
