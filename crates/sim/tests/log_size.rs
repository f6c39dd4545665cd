//! The size of `log.csv` estimated before a flight against the file the
//! flight writes; a writer's stride (a lower log rate) keeps the summary of
//! every sample; a stop flag ends a flight early with its log whole.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

use helicon_sim::closed_loop::{
    Outcome, Termination, estimate_log_csv, fly, fly_to, fly_to_until, prepare,
};
use helicon_sim::log_csv::{LogWriter, read_log_csv, strided_rows};
use helicon_sim::scenario::Scenario;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

fn demo(duration_s: f64) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/demo.toml");
    let mut s = Scenario::from_file(&path).unwrap();
    s.duration_s = duration_s;
    s
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("helicon-logsize-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d.join("log.csv")
}

/// The estimate (a 2 s pilot flight) against the file a 12 s flight
/// writes, at the full rate and at a stride: rows exact, bytes within 2 %.
#[test]
fn the_estimate_is_within_two_percent_of_the_written_file() {
    let s = demo(12.0);
    let p = prepare(&s).unwrap();
    for stride in [1usize, 7] {
        let est = estimate_log_csv(&s, &p, stride as u64).unwrap();
        let path = tmp(&format!("est{stride}"));
        let mut w = LogWriter::create(&path).unwrap().with_stride(stride);
        fly_to(&s, &p, &mut w, None).unwrap();
        let rows = w.finish().unwrap();
        let bytes = std::fs::metadata(&path).unwrap().len();
        let err = (est.bytes as f64 - bytes as f64) / bytes as f64;
        eprintln!(
            "stride {stride}: {rows} rows, {bytes} bytes written, {} estimated ({:+.2} %), {:.1} bytes per row",
            est.bytes,
            100.0 * err,
            est.bytes_per_row
        );
        assert_eq!(est.rows, rows as u64);
        assert!(err.abs() < 0.02, "{err}");
    }
}

/// A stride writes every n-th row and the last; the summary is the same
/// as the full-rate flight's (its metrics use every kept sample).
#[test]
fn a_stride_thins_the_log_not_the_summary() {
    let s = demo(3.0);
    let p = prepare(&s).unwrap();
    let full = fly(&s, &p, None).unwrap();
    let path = tmp("stride");
    let mut w = LogWriter::create(&path).unwrap().with_stride(6);
    let thin = fly_to(&s, &p, &mut w, None).unwrap();
    let rows = w.finish().unwrap();
    assert_eq!(thin.summary, full.summary);
    assert_eq!(rows as u64, strided_rows(full.log.len() as u64, 6));
    let back = read_log_csv(&path).unwrap();
    let mut expect: Vec<f64> = full.log.iter().step_by(6).map(|r| r.t_s).collect();
    let last = full.log.last().unwrap().t_s;
    if expect.last() != Some(&last) {
        expect.push(last);
    }
    assert_eq!(back.time_s(), expect);
    assert_eq!(strided_rows(0, 6), 0);
    assert_eq!(strided_rows(1, 6), 1);
    assert_eq!(strided_rows(7, 6), 2);
    assert_eq!(strided_rows(8, 6), 3);
}

/// A stop flag set half-way ends the flight there: termination `stopped`,
/// the log whole up to that sample and ending on it.
#[test]
fn a_stop_flag_ends_the_flight_with_its_log_whole() {
    let s = demo(4.0);
    let p = prepare(&s).unwrap();
    let stop = AtomicBool::new(false);
    let path = tmp("stop");
    let mut w = LogWriter::create(&path).unwrap().with_stride(3);
    let mut cb = |f: f64| {
        if f >= 0.5 {
            stop.store(true, Ordering::Relaxed);
        }
    };
    let flight = fly_to_until(&s, &p, &mut w, Some(&mut cb), &stop).unwrap();
    let rows = w.finish().unwrap();
    let sum = &flight.summary;
    assert_eq!(sum.termination, Termination::Stopped);
    assert_eq!(sum.outcome, Outcome::Stopped);
    assert!(sum.t_end_s >= 2.0 && sum.t_end_s < 2.1, "{}", sum.t_end_s);
    let json = serde_json::to_value(sum).unwrap();
    assert_eq!(json["outcome"], "stopped");
    assert_eq!(json["termination"], "stopped");
    let back = read_log_csv(&path).unwrap();
    assert_eq!(back.rows(), rows);
    let t_last = *back.time_s().last().unwrap();
    assert!(
        (t_last - sum.t_end_s).abs() < 0.0101,
        "{t_last} {}",
        sum.t_end_s
    );
}
