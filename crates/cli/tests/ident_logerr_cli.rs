//! The `helicon ident` commands on logs that cannot be used as they are: a
//! flight log's error under `ident fit` names the IDENT.toml, the field and
//! the log with the topic, field and time; a duplicated control stamp is
//! said to be one; a span the control law did not fly (`servo_source` ≠ 0)
//! is refused by `ident frf`, `ident servo` and `ident fit` naming its
//! times; the step read from a flight log prints as 0.0025 s. The logs are
//! written with the project's own ULog writer.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;
use common::{helicon, tmpdir};
use helicon_ulog::synthetic::{servo_record, write_control_log};
use std::path::Path;

/// A flight log of `n` control steps of 2500 µs from t = 1 s (step `k`
/// stamped `stamp(k)` µs), the servo commands and rates the synthetic
/// log's; `meas_q` of step 150 (t = 1.375 s) NaN when `nan`; a
/// `servo_output` record after each step with the source `source(k)` when
/// given.
fn write_ulog(
    path: &Path,
    n: u64,
    stamp: impl Fn(u64) -> u64,
    nan: bool,
    source: Option<&dyn Fn(u64) -> u8>,
) {
    write_control_log(
        path,
        n,
        |k| Some(stamp(k)),
        |k, c| {
            if nan && k == 150 {
                c.measured[7] = f64::NAN;
            }
        },
        |k, c| source.map(|s| servo_record(c, s(k))),
    )
    .unwrap();
}

fn steady(k: u64) -> u64 {
    1_000_000 + k * 2500
}

fn frf(log: &Path, out: &Path, extra: &[&str]) -> (bool, String, String) {
    let mut args = vec![
        "ident",
        "frf",
        log.to_str().unwrap(),
        "--input",
        "S_lat",
        "--output",
        "meas_p",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    helicon(&args)
}

#[test]
fn frf_on_a_flight_log_prints_its_step_rounded() {
    let d = tmpdir("step");
    let ulg = d.join("flight.ulg");
    write_ulog(&ulg, 2000, steady, false, Some(&|_| 0));
    let (ok, stdout, stderr) = frf(&ulg, &d.join("frf"), &[]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(stdout.contains("2000 samples every 0.0025 s"), "{stdout}");
    assert!(stderr.contains("every 0.0025 s"), "{stderr}");
    assert!(
        !format!("{stdout}{stderr}").contains("0.002499"),
        "{stdout}\n{stderr}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn frf_and_servo_refuse_a_span_the_law_did_not_fly() {
    let d = tmpdir("manual");
    // the pilot from step 400 to 599: t = 2 … 2.4975 s
    let ulg = d.join("flight.ulg");
    write_ulog(
        &ulg,
        2000,
        steady,
        false,
        Some(&|k| u8::from((400..600).contains(&k))),
    );
    let (ok, stdout, stderr) = frf(&ulg, &d.join("frf"), &[]);
    assert!(!ok, "{stdout}");
    for part in [
        "flight.ulg",
        "servo_source",
        "t = 2 … 2.4975 s (pilot, 200 samples)",
        "--t-start/--t-end",
    ] {
        assert!(stderr.contains(part), "`{part}`: {stderr}");
    }
    // the part after it: accepted, 1400 samples from t = 2.5 s
    let (ok, stdout, stderr) = frf(&ulg, &d.join("frf"), &["--t-start", "2.5"]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(stdout.contains("1400 samples every 0.0025 s"), "{stdout}");
    // ending inside it: named up to the end of the part used
    let (ok, _, stderr) = frf(
        &ulg,
        &d.join("frf"),
        &["--t-start", "1.5", "--t-end", "2.1"],
    );
    assert!(
        !ok && stderr.contains("t = 2 … 2.1 s (pilot, 41 samples)"),
        "{stderr}"
    );
    // a span that is not one
    let (ok, _, stderr) = frf(&ulg, &d.join("frf"), &["--t-start", "3", "--t-end", "2"]);
    assert!(
        !ok && stderr.contains("--t-start/--t-end 3 … 2"),
        "{stderr}"
    );
    let (ok, _, stderr) = frf(&ulg, &d.join("frf"), &["--t-start", "6.5"]);
    assert!(
        !ok && stderr.contains("0 data rows between --t-start/--t-end"),
        "{stderr}"
    );
    // a bench or flight CSV with the column: the same check
    let mut text = String::from("t_s,cmd,pos,servo_source\n");
    for k in 0..400 {
        let c = ((k as f64) * 0.1).sin() * 0.1;
        let s = if (100..110).contains(&k) { 2 } else { 0 };
        text.push_str(&format!("{},{c},{c},{s}\n", k as f64 / 400.0));
    }
    let csv = d.join("bench.csv");
    std::fs::write(&csv, &text).unwrap();
    let (ok, stdout, stderr) = helicon(&[
        "ident",
        "servo",
        csv.to_str().unwrap(),
        "--command",
        "cmd",
        "--position",
        "pos",
        "--out",
        d.join("servo").to_str().unwrap(),
    ]);
    assert!(!ok, "{stdout}");
    for part in [
        "bench.csv",
        "servo_source",
        "t = 0.25 … 0.2725 s (failsafe, 10 samples)",
    ] {
        assert!(stderr.contains(part), "`{part}`: {stderr}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// An IDENT.toml with one operating point on `log`.
fn ident_toml(d: &Path, log: &str) -> std::path::PathBuf {
    let p = d.join("IDENT.toml");
    std::fs::write(
        &p,
        format!(
            "windows_s = [0.5]\n[[operating_point]]\nname = \"hover\"\nlog = \"{log}\"\n\
             [[response]]\ninput = \"S_lon\"\noutput = \"meas_q\"\nomega_min_rad_s = 1.5\nomega_max_rad_s = 25.0\n\
             [[parameter]]\nkey = \"body.iyy_kg_m2\"\nmin = 0.3\nmax = 1.2\n"
        ),
    )
    .unwrap();
    p
}

#[test]
fn fit_names_the_ident_file_the_field_and_the_flight_logs_fault() {
    let d = tmpdir("fit");
    let fit = |log: &str| {
        let p = ident_toml(&d, log);
        helicon(&[
            "ident",
            "fit",
            p.to_str().unwrap(),
            "--out",
            d.join("out").to_str().unwrap(),
        ])
    };
    write_ulog(&d.join("nan.ulg"), 400, steady, true, None);
    let (ok, _, stderr) = fit("nan.ulg");
    assert!(!ok);
    // the reader's error is the cause, said once
    assert_eq!(stderr.matches("nan.ulg").count(), 1, "{stderr}");
    for part in [
        "IDENT.toml",
        "operating_point[0].log",
        "nan.ulg",
        "control.measured[7]",
        "1.375",
    ] {
        assert!(stderr.contains(part), "`{part}`: {stderr}");
    }
    // step 101 written twice with step 100's stamp (t = 1.25 s)
    write_ulog(
        &d.join("dup.ulg"),
        400,
        |k| steady(k - u64::from(k == 101)),
        false,
        None,
    );
    let (ok, _, stderr) = fit("dup.ulg");
    assert!(!ok);
    for part in [
        "IDENT.toml",
        "operating_point[0].log",
        "dup.ulg",
        "1.25",
        "twice",
    ] {
        assert!(stderr.contains(part), "`{part}`: {stderr}");
    }
    assert!(!stderr.contains("back in time"), "{stderr}");
    // a failsafe from step 300 (t = 1.75 s) to the end (t = 1.9975 s)
    write_ulog(
        &d.join("fs.ulg"),
        400,
        steady,
        false,
        Some(&|k| 2 * u8::from(k >= 300)),
    );
    let (ok, _, stderr) = fit("fs.ulg");
    assert!(!ok);
    for part in [
        "IDENT.toml",
        "operating_point[0].log",
        "fs.ulg",
        "t = 1.75 … 1.9975 s (failsafe, 100 samples)",
        "operating_point[0].t_start_s",
    ] {
        assert!(stderr.contains(part), "`{part}`: {stderr}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
