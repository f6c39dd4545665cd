//! `helicon_ulog::columns`: a flight log read onto the control grid under
//! log.csv's names. Each branch of the rule (docs/ulog.md, "Reading a
//! flight log as columns"): exact values on a uniform log; jittered steps
//! accepted and placed on the grid; jitter beyond the tolerance refused;
//! up to four dropped samples filled by linear interpolation, five refused;
//! other topics held (stamped after their step, starting late, stopping);
//! non-finite values, missing topics, unknown names, a cut log. And the
//! columns fixture against pyulog with the rule applied independently
//! (tools/gen_ulog_fixtures.py).
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests: a failed unwrap is a failed test

use helicon_ulog::LogRecord;
use helicon_ulog::columns::{
    ColumnsError, ULOG_COLUMNS, available_columns, read_ulog_columns, read_ulog_columns_with,
};
use helicon_ulog::messages::Excitation;
use helicon_ulog::synthetic::{synthetic_value as value, write_control_log};
use std::path::{Path, PathBuf};

const T_US: i64 = 2500;
const T_S: f64 = 0.0025;

/// A log of `n` control steps; `stamp(k)` gives step k's control timestamp
/// offset from k·T (µs) or `None` to drop it; `exc(k)` the excitation's
/// offset from the control timestamp or `None` for none. Step k's values
/// are `value(k, i)`: commands i = 0…3, estimate 10…18, measured 20…28,
/// excitation offsets 30…33.
fn write_log(
    name: &str,
    n: u64,
    stamp: impl Fn(u64) -> Option<i64>,
    exc: impl Fn(u64) -> Option<i64>,
) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("helicon_ulog_columns_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.ulg"));
    let stamp_us = |k: u64| {
        let j = stamp(k)?;
        Some(u64::try_from(1_000_000 + i64::try_from(k).unwrap() * T_US + j).unwrap())
    };
    write_control_log(
        &path,
        n,
        stamp_us,
        |_, _| {},
        |k, c| {
            let e = exc(k)?;
            Some(LogRecord::Excitation(Excitation {
                timestamp: c.timestamp.checked_add_signed(e).unwrap(),
                offset: std::array::from_fn(|i| value(k, i + 30)),
                active: true,
            }))
        },
    )
    .unwrap();
    path
}

const NAMES: [&str; 5] = ["S_lat", "meas_p", "est_q", "exc_lat", "exc_col"];

fn read(path: &Path) -> Result<helicon_ulog::columns::UlogColumns, ColumnsError> {
    read_ulog_columns(path, &NAMES, Some(T_S))
}

#[test]
fn uniform_log_gives_the_logged_values_exactly() {
    let p = write_log("uniform", 200, |_| Some(0), |_| Some(0));
    let c = read(&p).unwrap();
    assert_eq!(
        c.names,
        ["t_s", "S_lat", "meas_p", "est_q", "exc_lat", "exc_col"]
    );
    assert_eq!(c.columns[0].len(), 200);
    assert!(c.filled.is_empty() && c.skipped_start == 0 && c.truncated_at.is_none());
    for k in 0..200u64 {
        let kk = k as usize;
        assert!((c.columns[0][kk] - (1.0 + k as f64 * T_S)).abs() < 1e-12);
        assert_eq!(c.columns[1][kk], value(k, 1)); // command[1] = S_lat
        assert_eq!(c.columns[2][kk], value(k, 26)); // measured[6] = p
        assert_eq!(c.columns[3][kk], value(k, 17)); // estimate[7] = q
        assert_eq!(c.columns[4][kk], value(k, 31)); // offset[1] = S_lat
        assert_eq!(c.columns[5][kk], value(k, 30)); // offset[0] = S_col
    }
    assert_eq!(c.get("meas_p").unwrap(), c.columns[2].as_slice());
    // the median step when no period is given
    let m = read_ulog_columns(&p, &NAMES, None).unwrap();
    assert!((m.period_s - T_S).abs() < 1e-12);
}

#[test]
fn jittered_steps_are_placed_on_the_grid() {
    // up to ±120 µs: steps within ±230 µs (±10 % of 2500 µs); excitation stamped 400 µs late
    let jit = |k: u64| Some([0, 120, -110, 100, -60][(k % 5) as usize]);
    let p = write_log("jitter", 200, jit, |_| Some(400));
    let c = read(&p).unwrap();
    assert_eq!(c.columns[0].len(), 200);
    assert!((c.max_jitter_s - 120e-6).abs() < 1e-9, "{}", c.max_jitter_s);
    let steps: Vec<f64> = c.columns[0].windows(2).map(|w| w[1] - w[0]).collect();
    assert!(steps.iter().all(|d| (d - T_S).abs() < 1e-12));
    // values are the records', in order; the late excitation is its own step's
    for k in 0..200u64 {
        assert_eq!(c.columns[1][k as usize], value(k, 1));
        assert_eq!(c.columns[4][k as usize], value(k, 31));
    }
}

#[test]
fn step_clock_records_stay_with_their_control_record() {
    // excitation stamped 4.7 ms after its control record (nearly two
    // periods: the step's wake-up clock under real time, as measured in a
    // real-time SITL flight): it belongs to the control record before it in
    // the file, not to the one its timestamp is nearest
    let p = write_log("stepclock", 100, |_| Some(0), |_| Some(4700));
    let c = read(&p).unwrap();
    assert_eq!(c.columns[0].len(), 100);
    for k in 0..100u64 {
        assert_eq!(c.columns[4][k as usize], value(k, 31));
    }
}

#[test]
fn jitter_beyond_the_tolerance_is_refused_naming_the_time() {
    // step 50 stamped 300 µs late: 12 % of the period
    let p = write_log(
        "badjitter",
        100,
        |k| Some(if k == 50 { 300 } else { 0 }),
        |_| Some(0),
    );
    let e = read(&p).unwrap_err();
    assert!(matches!(e, ColumnsError::Jitter { .. }), "{e}");
    let s = e.to_string();
    assert!(
        s.contains("badjitter.ulg") && s.contains("t = 1.1253 s"),
        "{s}"
    );
}

#[test]
fn four_dropped_samples_are_interpolated_five_refused() {
    let p = write_log(
        "drop4",
        120,
        |k| (!(60..64).contains(&k)).then_some(0),
        |_| Some(0),
    );
    let c = read(&p).unwrap();
    assert_eq!(c.columns[0].len(), 120);
    assert_eq!(c.filled, vec![(1.0 + 60.0 * T_S, 4)]);
    assert!(
        c.notes()
            .iter()
            .any(|n| n.contains("4 control sample(s) missing from t = 1.15 s"))
    );
    for i in 1..5 {
        let f = i as f64 / 5.0;
        let want = value(59, 26) + f * (value(64, 26) - value(59, 26));
        assert!((c.columns[2][59 + i] - want).abs() < 1e-15);
        let want = value(59, 31) + f * (value(64, 31) - value(59, 31));
        assert!((c.columns[4][59 + i] - want).abs() < 1e-15);
    }
    assert_eq!(c.columns[2][64], value(64, 26));
    let p = write_log(
        "drop5",
        120,
        |k| (!(60..65).contains(&k)).then_some(0),
        |_| Some(0),
    );
    let e = read(&p).unwrap_err();
    assert!(matches!(e, ColumnsError::Gap { missing: 5, .. }), "{e}");
    assert!(e.to_string().contains("before t = 1.1625 s"), "{e}");
}

#[test]
fn other_topics_are_held_start_late_and_must_not_stop() {
    // excitation from step 10 on: the record starts there
    let p = write_log("late", 100, |_| Some(0), |k| (k >= 10).then_some(0));
    let c = read(&p).unwrap();
    assert_eq!(c.skipped_start, 10);
    assert_eq!(c.columns[0].len(), 90);
    assert!((c.columns[0][0] - (1.0 + 10.0 * T_S)).abs() < 1e-12);
    assert_eq!(c.columns[1][0], value(10, 1));
    // excitation missing for steps 40..43 (4 samples): held from step 39
    let p = write_log(
        "hold",
        100,
        |_| Some(0),
        |k| (!(40..44).contains(&k)).then_some(0),
    );
    let c = read(&p).unwrap();
    for k in 40..44 {
        assert_eq!(c.columns[4][k], value(39, 31));
    }
    // ... for 5 samples: stopped
    let p = write_log(
        "stale",
        100,
        |_| Some(0),
        |k| (!(40..46).contains(&k)).then_some(0),
    );
    let e = read(&p).unwrap_err();
    assert!(matches!(e, ColumnsError::Stale { .. }), "{e}");
    assert!(
        e.to_string().contains("`excitation`") && e.to_string().contains("t = 1.1125 s"),
        "{e}"
    );
    // the age and the limit to the µs, not with a difference's round-off
    assert!(
        e.to_string().contains("in the 0.015 s before")
            && e.to_string().contains("(at most 0.0125 s)"),
        "{e}"
    );
}

#[test]
fn optional_columns_are_given_when_their_topic_was_logged() {
    // excitation logged: the optional column comes after those asked for,
    // with the logged values; servo_output not logged: left out, no error
    let p = write_log("optional", 50, |_| Some(0), |_| Some(0));
    let c =
        read_ulog_columns_with(&p, &["meas_p"], &["servo_source", "exc_lat"], Some(T_S)).unwrap();
    assert_eq!(c.names, ["t_s", "meas_p", "exc_lat"]);
    for k in 0..50u64 {
        assert_eq!(c.columns[1][k as usize], value(k, 26)); // measured[6]
        assert_eq!(c.columns[2][k as usize], value(k, 31)); // offset[1]
    }
    // no excitation at all: the optional column left out, the record whole
    let p = write_log("optional_none", 50, |_| Some(0), |_| None);
    let c = read_ulog_columns_with(&p, &["meas_p"], &["exc_lat"], Some(T_S)).unwrap();
    assert_eq!(c.names, ["t_s", "meas_p"]);
    assert_eq!((c.columns[0].len(), c.skipped_start), (50, 0));
    // asked for, not optional: refused as before
    let e = read_ulog_columns_with(&p, &["exc_lat"], &["meas_p"], Some(T_S)).unwrap_err();
    assert!(matches!(e, ColumnsError::MissingTopic { .. }), "{e}");
}

/// The log `name`: 50 control steps, the first also with a record of every
/// other topic a column comes from (`estimator_bias` only `with_bias`), then a subscription of a
/// format the log does not define (a fault the reader refuses).
fn all_topics_then_a_fault(name: &str, with_bias: bool) -> PathBuf {
    use helicon_ulog::messages::{EstimatorBias, ImuHealth};
    use helicon_ulog::synthetic::servo_record;
    let dir = std::env::temp_dir().join(format!("helicon_ulog_columns_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.ulg"));
    let mut log = helicon_ulog::FlightLog::create(
        &path,
        &helicon_ulog::LogInfo::default(),
        helicon_ulog::FlushPolicy::default(),
    )
    .unwrap();
    let c = helicon_ulog::messages::Control {
        timestamp: 1_000_000,
        ..Default::default()
    };
    let ts = c.timestamp;
    let mut records = vec![
        LogRecord::Control(c),
        LogRecord::Excitation(Excitation {
            timestamp: ts,
            ..Default::default()
        }),
        servo_record(&c, 0),
        LogRecord::ImuHealth(ImuHealth {
            timestamp: ts,
            ..Default::default()
        }),
        LogRecord::EstimatorBias(EstimatorBias {
            timestamp: ts,
            ..Default::default()
        }),
    ];
    if !with_bias {
        records.pop();
    }
    for r in &records {
        log.write(r).unwrap();
    }
    for k in 1..50u64 {
        let mut c = c;
        c.timestamp = 1_000_000 + 2500 * k;
        log.write(&LogRecord::Control(c)).unwrap();
    }
    log.finish().unwrap();
    // 'A': multi_id 0, msg_id 999, a format name never defined
    let name = b"nosuch";
    let mut bytes = std::fs::read(&path).unwrap();
    bytes.extend_from_slice(&u16::try_from(3 + name.len()).unwrap().to_le_bytes());
    bytes.push(b'A');
    bytes.push(0);
    bytes.extend_from_slice(&999u16.to_le_bytes());
    bytes.extend_from_slice(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn available_columns_stops_once_every_topic_was_seen() {
    // every topic in the first step: the names come before the fault
    let p = all_topics_then_a_fault("all_then_fault", true);
    let names = available_columns(&p).unwrap();
    assert_eq!(names.len(), 1 + ULOG_COLUMNS.len(), "{names:?}");
    // the columns themselves read to the end and meet it
    let e = read_ulog_columns(&p, &["S_lat"], Some(T_S)).unwrap_err();
    assert!(matches!(e, ColumnsError::Read(_)), "{e}");
    // a topic never logged: read to the end, the fault reported
    let p = all_topics_then_a_fault("bias_missing_then_fault", false);
    let e = available_columns(&p).unwrap_err().to_string();
    assert!(
        e.contains("bias_missing_then_fault.ulg") && e.contains("'A'"),
        "{e}"
    );
}

#[test]
fn bad_logs_are_refused_naming_file_topic_field() {
    // no excitation topic at all
    let p = write_log("noexc", 50, |_| Some(0), |_| None);
    let e = read(&p).unwrap_err().to_string();
    assert!(
        e.contains("noexc.ulg")
            && e.contains("`excitation`")
            && e.contains("offset[1]")
            && e.contains("[[excitation]]"),
        "{e}"
    );
    // an unknown name
    let e = read_ulog_columns(&p, &["x"], Some(T_S))
        .unwrap_err()
        .to_string();
    assert!(e.contains("no column `x`") && e.contains("meas_p"), "{e}");
    // a NaN in the measured rates
    let dir = p.parent().unwrap();
    let path = dir.join("nan.ulg");
    write_control_log(
        &path,
        50,
        |k| Some(1_000_000 + k * 2500),
        |k, c| {
            if k == 30 {
                c.measured[6] = f64::NAN;
            }
        },
        |_, _| None,
    )
    .unwrap();
    let e = read_ulog_columns(&path, &["meas_p"], Some(T_S))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("nan.ulg")
            && e.contains("`control.measured[6]`")
            && e.contains("t = 1.075 s")
            && e.contains("NaN"),
        "{e}"
    );
    // a log at another rate than the control period given
    let e = read_ulog_columns(&path, &["S_lat"], Some(0.00125))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("median step is 0.0025 s, not the control period 0.00125 s"),
        "{e}"
    );
    // a period that is not a time
    let e = read_ulog_columns(&path, &["S_lat"], Some(f64::NAN))
        .unwrap_err()
        .to_string();
    assert!(e.contains("period"), "{e}");
    // a file that is not ULog
    let txt = dir.join("not.ulg");
    std::fs::write(&txt, "t_s,S_lat\n0,0\n").unwrap();
    let e = read_ulog_columns(&txt, &["S_lat"], Some(T_S))
        .unwrap_err()
        .to_string();
    assert!(e.contains("not.ulg") && e.contains("not a ULog"), "{e}");
}

#[test]
fn a_log_cut_short_gives_what_is_before_the_cut() {
    let p = write_log("cut", 200, |_| Some(0), |_| Some(0));
    let bytes = std::fs::read(&p).unwrap();
    let cut = p.with_file_name("cut_short.ulg");
    std::fs::write(&cut, &bytes[..bytes.len() - 100]).unwrap();
    let c = read(&cut).unwrap();
    assert!(c.truncated_at.is_some());
    assert!(
        c.columns[0].len() >= 190 && c.columns[0].len() < 200,
        "{}",
        c.columns[0].len()
    );
    assert!(c.notes().iter().any(|n| n.contains("cut short")));
}

#[test]
fn columns_fixture_matches_pyulog_and_the_rule_applied_in_python() {
    let fix = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let want: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(fix.join("columns_sample.columns.json")).unwrap(),
    )
    .unwrap();
    let cols = want["columns"].as_object().unwrap();
    let names: Vec<&str> = cols.keys().map(String::as_str).collect();
    let c = read_ulog_columns(&fix.join("columns_sample.ulg"), &names, Some(T_S)).unwrap();
    assert_eq!(
        c.skipped_start as u64,
        want["skipped_start"].as_u64().unwrap()
    );
    let filled: Vec<(f64, usize)> = want["filled"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| (f[0].as_f64().unwrap(), f[1].as_u64().unwrap() as usize))
        .collect();
    assert!(!filled.is_empty(), "the fixture has dropped samples");
    assert_eq!(c.filled.len(), filled.len());
    for (got, want) in c.filled.iter().zip(&filled) {
        assert_eq!(got.1, want.1);
        // times of order 1 s to the µs, rounded by the reader: 1e-12 is
        // far below the µs and far above f64 round-off (2e-16 s)
        assert!((got.0 - want.0).abs() < 1e-12, "{got:?} vs {want:?}");
    }
    let t = want["t_s"].as_array().unwrap();
    assert_eq!(c.columns[0].len(), t.len());
    let mut worst: f64 = 0.0;
    for (a, b) in c.columns[0].iter().zip(t) {
        worst = worst.max((a - b.as_f64().unwrap()).abs());
    }
    for n in &names {
        let got = c.get(n).unwrap();
        let exp = cols[*n].as_array().unwrap();
        assert_eq!(got.len(), exp.len(), "{n}");
        for (a, b) in got.iter().zip(exp) {
            worst = worst.max((a - b.as_f64().unwrap()).abs());
        }
    }
    // the same arithmetic, possibly in another order (numpy's interp forms
    // the fraction differently): a few ulp of values and times of order 1,
    // ~1e-15; 1e-12 leaves that a margin of 1000 and is far below the
    // 3e-7 (median 1e-3) by which neighbouring samples of the fixture's
    // varying columns differ, so a sample taken from the wrong record fails
    assert!(worst < 1e-12, "{worst}");
}
