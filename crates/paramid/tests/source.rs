//! `helicon_paramid::source`: a log is read as a flight log (ULog) or a
//! CSV by its first bytes, whatever its name; the flight log's column names
//! are `log.csv`'s.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests: a failed unwrap is a failed test

use helicon_paramid::source::{is_ulog, log_names, read_log};
use helicon_sim::log_csv::log_column;
use helicon_ulog::columns::ULOG_COLUMNS;
use helicon_ulog::synthetic::write_control_log;

fn dir() -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("helicon_paramid_source_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn flight_log_names_are_log_csv_names() {
    // every name a flight log gives is a log.csv column, but for the few
    // only a flight log has
    let extra = [
        "exc_active",
        "servo_source",
        "bias_gyro_x_rad_s",
        "bias_gyro_y_rad_s",
        "bias_gyro_z_rad_s",
    ];
    for c in &ULOG_COLUMNS {
        assert!(
            log_column(c.name).is_some() || extra.contains(&c.name),
            "{} is not a log.csv column",
            c.name
        );
    }
}

#[test]
fn the_file_not_its_name_decides() {
    let d = dir();
    // a flight log named .csv
    let ulg = d.join("flight.csv");
    write_control_log(
        &ulg,
        100,
        |k| Some(2500 * k),
        |k, c| c.command[1] = 0.01 * k as f64,
        |_, _| None,
    )
    .unwrap();
    assert!(is_ulog(&ulg));
    let c = read_log(&ulg, &["S_lat", "est_p"], 0.0025).unwrap();
    assert_eq!(c.names, ["t_s", "S_lat", "est_p"]);
    assert_eq!(c.column("S_lat")[7], 0.07);
    assert!((c.column("t_s")[99] - 0.2475).abs() < 1e-12);
    let names = log_names(&ulg).unwrap();
    assert!(
        names.iter().any(|n| n == "est_phi") && !names.iter().any(|n| n == "x" || n == "exc_lat")
    );
    // a CSV named .ulg
    let csv = d.join("log.ulg");
    let mut text = String::from("t_s,S_lat\n");
    for k in 0..100 {
        text.push_str(&format!("{},{}\n", k as f64 * 0.0025, k));
    }
    std::fs::write(&csv, text).unwrap();
    assert!(!is_ulog(&csv));
    let c = read_log(&csv, &["S_lat"], 0.0025).unwrap();
    assert_eq!(c.column("S_lat")[5], 5.0);
    assert_eq!(log_names(&csv).unwrap(), ["t_s", "S_lat"]);
    // a missing file is not ULog; the CSV reader names it
    let e = read_log(&d.join("none.ulg"), &["S_lat"], 0.0025)
        .unwrap_err()
        .to_string();
    assert!(e.contains("none.ulg"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}
