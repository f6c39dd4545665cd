//! Hostile flight logs for `helicon_ulog::columns`: a small valid log cut at
//! every byte offset, every byte flipped, duplicated and backward control
//! timestamps, absurd control periods. Every case must give columns or an
//! error naming the file; never a panic, and no non-finite value in the
//! columns given.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests: a failed unwrap is a failed test

use helicon_ulog::LogRecord;
use helicon_ulog::columns::read_ulog_columns;
use helicon_ulog::messages::Excitation;
use helicon_ulog::synthetic::{synthetic_value, write_control_log};
use std::path::{Path, PathBuf};

const T_S: f64 = 0.0025;
const NAMES: [&str; 5] = ["S_lat", "meas_p", "est_q", "exc_lat", "exc_col"];

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("helicon_ulog_hostile_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A log of `n` control steps stamped by `stamp(k)` (µs), each followed by
/// an excitation record.
fn write_log(name: &str, n: u64, stamp: impl Fn(u64) -> u64) -> PathBuf {
    let path = dir().join(format!("{name}.ulg"));
    write_control_log(
        &path,
        n,
        |k| Some(stamp(k)),
        |_, _| {},
        |k, c| {
            Some(LogRecord::Excitation(Excitation {
                timestamp: c.timestamp,
                offset: std::array::from_fn(|i| synthetic_value(k, i + 30)),
                active: true,
            }))
        },
    )
    .unwrap();
    path
}

/// Read `path`; a panic fails with `what`; an error must name the file;
/// columns given must be finite.
fn read_checked(path: &Path, period_s: Option<f64>, what: &str) {
    let r = std::panic::catch_unwind(|| read_ulog_columns(path, &NAMES, period_s));
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    match r {
        Err(_) => panic!("{what}: the reader panicked"),
        Ok(Err(e)) => {
            let e = e.to_string();
            assert!(e.contains(&name), "{what}: error without the file: {e}");
        }
        Ok(Ok(c)) => {
            for (n, col) in c.names.iter().zip(&c.columns) {
                assert!(
                    col.iter().all(|x| x.is_finite()),
                    "{what}: column {n} has a non-finite value"
                );
                assert_eq!(col.len(), c.columns[0].len(), "{what}: column {n} length");
            }
        }
    }
}

#[test]
fn a_log_cut_at_every_offset_reads_or_is_refused_naming_the_file() {
    let p = write_log("whole", 40, |k| 1_000_000 + k * 2500);
    let bytes = std::fs::read(&p).unwrap();
    let cut = dir().join("cut.ulg");
    for at in 0..bytes.len() {
        std::fs::write(&cut, &bytes[..at]).unwrap();
        read_checked(&cut, Some(T_S), &format!("cut at {at}"));
    }
}

#[test]
fn a_log_with_any_byte_flipped_reads_or_is_refused_naming_the_file() {
    let p = write_log("flip_src", 40, |k| 1_000_000 + k * 2500);
    let bytes = std::fs::read(&p).unwrap();
    let flipped = dir().join("flipped.ulg");
    for at in 0..bytes.len() {
        // all bits of the even bytes, the lowest bit of the odd ones
        let mask = if at % 2 == 0 { 0xFFu8 } else { 0x01 };
        let mut b = bytes.clone();
        b[at] ^= mask;
        std::fs::write(&flipped, &b).unwrap();
        read_checked(&flipped, None, &format!("byte {at} ^ {mask:#x}"));
    }
}

#[test]
fn duplicated_or_backward_control_stamps_are_refused_naming_the_time() {
    // step 21 stamped as step 20
    let dup = write_log("dup", 40, |k| 1_000_000 + (k - u64::from(k > 20)) * 2500);
    let e = read_ulog_columns(&dup, &NAMES, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("dup.ulg") && e.contains("1.05") && e.contains("twice"),
        "{e}"
    );
    assert!(!e.contains("back in time"), "{e}");
    let back = write_log("back", 40, |k| {
        if k == 25 {
            1_000_000
        } else {
            1_000_000 + k * 2500
        }
    });
    let e = read_ulog_columns(&back, &NAMES, None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("back.ulg") && e.contains("back in time"), "{e}");
    // the largest stamps the format can hold
    let huge = write_log("huge", 40, |k| u64::MAX - 40 * 2500 + k * 2500);
    read_checked(&huge, None, "stamps near u64::MAX");
    read_checked(&huge, Some(T_S), "stamps near u64::MAX, period given");
}

#[test]
fn absurd_control_periods_are_refused_naming_the_period() {
    let p = write_log("period", 40, |k| 1_000_000 + k * 2500);
    for ts in [
        0.0,
        -T_S,
        f64::NAN,
        f64::INFINITY,
        1e-300,
        1e300,
        f64::MIN_POSITIVE,
    ] {
        let e = read_ulog_columns(&p, &NAMES, Some(ts))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("period.ulg") && e.contains("period"),
            "{ts}: {e}"
        );
    }
}
