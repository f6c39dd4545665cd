//! Hostile devices in lock-step SITL: the simulated hardware behind the
//! pseudo-terminals sends what no sensor can measure or hangs a line up, at
//! a chosen instant of the simulated clock (a GPS without a fix, a fix
//! 10 km away at 300 m/s, the GPS line hung up, IMU samples of 3e38 m/s²,
//! a 3e38-gauss field, receiver channels at 65535 and 0 µs). The on-board
//! program must refuse each value, act by its failsafe rule and say so in
//! its log. In lock-step the times are the simulated clock's: each fault's
//! time to its failsafe is exact and the same on every run (checked by
//! flying each twice), which the wall-clock attacks on the on-board
//! program itself (`device_faults`) cannot give.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;

use common::{Ulog, options, scenario};
use helicon_sim::closed_loop::{Termination, prepare};
use helicon_sitl::{Faults, SitlResult};

/// When every fault starts (s of the simulated clock): the demo's step
/// references are being flown.
const AT_S: f64 = 2.0;
/// The flight (s).
const DURATION_S: f64 = 4.5;
/// The sample time (s).
const TS: f64 = 0.0025;

struct Flown {
    result: SitlResult,
    log: Ulog,
}

fn fly(tag: &str, faults: Faults) -> Flown {
    let s = scenario("demo.toml", DURATION_S);
    let prepared = prepare(&s).unwrap();
    let mut o = options(tag);
    o.faults = faults;
    o.keep_frames = false;
    o.failsafe.hold_s = 30.0;
    let result = helicon_sitl::run(&s, &prepared, &o).unwrap();
    assert_eq!(result.summary.termination, Termination::Completed, "{tag}");
    assert!(
        result.onboard.error.is_none(),
        "{tag}: {:?}",
        result.onboard.error
    );
    let log = Ulog::read(&result.ulog);
    Flown { result, log }
}

/// Fly `faults` twice: the same texts at the same simulated times.
fn fly_twice(tag: &str, faults: Faults) -> Flown {
    let a = fly(tag, faults);
    let b = fly(&format!("{tag}_again"), faults);
    assert_eq!(a.log.texts, b.log.texts, "{tag}: lock-step runs differ");
    for (t, text) in &a.log.texts {
        eprintln!("{tag}: {:.4} {text}", *t as f64 * 1e-6);
    }
    a
}

/// The time (s) of the first text containing `needle`.
fn first(f: &Flown, needle: &str) -> f64 {
    f.log.first_text(needle)
}

/// The time from the fault (`AT_S`) to `failsafe`, printed and checked to
/// be exact: the device's last good sample at `last_good_s`, older than
/// `stale_s` at the next step after `last_good_s + stale_s` (the limit is
/// "older than", so the step at exactly the limit does not act).
fn fault_to(f: &Flown, what: &str, failsafe: &str, last_good_s: f64, stale_s: f64) -> f64 {
    let dt = first(f, failsafe) - AT_S;
    eprintln!("lock-step fault to failsafe: {what}: {:.1} ms", dt * 1e3);
    let want = last_good_s + stale_s + TS - AT_S;
    // the log's timestamps are whole microseconds
    assert!((dt - want).abs() < 2e-6, "{what}: {dt} s, not {want} s");
    dt
}

/// No fix from 2 s: refused at its first message, the GPS failsafe once
/// the last good fix is older than `stale.gps_s` (1 s; the last good fix
/// came at most one GPS period, 0.2 s, before the fault).
#[test]
fn a_gps_without_a_fix_is_refused_and_the_gps_failsafe_acts() {
    let f = fly_twice(
        "nofix",
        Faults {
            gps_no_fix_s: Some((AT_S, f64::INFINITY)),
            ..Faults::default()
        },
    );
    let refused = first(&f, "GPS: no 3-D fix, refused (1 so far)");
    assert!((AT_S..AT_S + 0.2 + 0.1).contains(&refused), "{refused}");
    // the fixes at 5 Hz: the last good one at 1.9 s
    fault_to(&f, "GPS no fix", "gps_rejected: auto -> hold", 1.9, 1.0);
    assert_eq!(f.result.onboard.final_mode, "hold");
}

/// One fix 10 km away at 300 m/s: refused, never fused; the velocity
/// estimate is the one of the same flight without the glitch to within
/// what one missing fix changes (0.05 m/s), no failsafe.
#[test]
fn a_glitching_fix_is_refused_and_never_flown() {
    let clean = fly("clean", Faults::default());
    let f = fly_twice(
        "glitch",
        Faults {
            gps_glitch_at_s: Some(AT_S),
            ..Faults::default()
        },
    );
    first(&f, "GPS: impossible speed, refused (1 so far)");
    assert_eq!(f.result.onboard.final_mode, "auto");
    for axis in 0..3 {
        let field = format!("velocity_ned_m_s[{axis}]");
        let (a, b) = (
            clean.log.f64s("navigation", &field),
            f.log.f64s("navigation", &field),
        );
        assert_eq!(a.len(), b.len());
        assert!(!a.is_empty());
        let worst = a
            .iter()
            .zip(&b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        eprintln!("glitch: velocity estimate [{axis}] differs by at most {worst:.4} m/s");
        assert!(worst < 0.05, "velocity[{axis}] moved {worst} m/s");
    }
}

/// The GPS line hung up at 2 s: the device lost (said), the program flies
/// on, the GPS failsafe once the last fix is older than 1 s; the gone
/// device is never reopened.
#[test]
fn a_gps_line_hung_up_is_a_gps_loss() {
    let f = fly_twice(
        "gps_hangup",
        Faults {
            gps_hangup_at_s: Some(AT_S),
            ..Faults::default()
        },
    );
    let lost = first(&f, "device: GPS port lost");
    assert!((AT_S..AT_S + 0.25).contains(&lost), "{lost}");
    fault_to(&f, "GPS hang-up", "gps_stale: auto -> hold", 1.9, 1.0);
    assert!(f.log.texts_with("GPS port reopened").is_empty());
    assert_eq!(f.result.onboard.final_mode, "hold");
}

/// IMU samples of 3e38 m/s² from 2 s: refused at the first, the IMU taken
/// as lost once refused for `stale.imu_s` (20 ms); the attitude estimate
/// never leaves the flight's (no impossible sample fused).
#[test]
fn impossible_imu_samples_are_refused_and_the_imu_is_lost() {
    let f = fly_twice(
        "imu_absurd",
        Faults {
            imu_absurd_s: Some((AT_S, f64::INFINITY)),
            ..Faults::default()
        },
    );
    let refused = first(&f, "IMU: acceleration beyond range, refused (1 so far)");
    assert!((refused - AT_S).abs() <= TS + 1e-9, "{refused}");
    fault_to(
        &f,
        "IMU absurd",
        "imu_rejected: auto -> imu_lost",
        AT_S - TS,
        0.02,
    );
    assert_eq!(f.result.onboard.final_mode, "imu_lost");
    let att = f.log.f64s("control", "estimate[0]");
    assert!(!att.is_empty() && att.iter().all(|a| a.abs() < 0.5));
}

/// A 3e38-gauss field from 2 s: refused, the magnetometer failsafe once
/// its last good sample is older than `stale.mag_s` (0.5 s).
#[test]
fn an_impossible_field_is_refused_and_the_mag_failsafe_acts() {
    let f = fly_twice(
        "mag_absurd",
        Faults {
            mag_absurd_s: Some((AT_S, f64::INFINITY)),
            ..Faults::default()
        },
    );
    first(&f, "mag: field magnitude implausible, refused (1 so far)");
    // the field at 100 Hz: the last good one at 1.99 s
    fault_to(&f, "field absurd", "mag_rejected: auto -> hold", 1.99, 0.5);
    assert_eq!(f.result.onboard.final_mode, "hold");
}

/// Receiver channels at 65535 and 0 µs from 2 s: every frame refused and
/// counted, texted at the first and each doubling; the receiver reads as
/// silent after `stale.rc_s` (0.5 s) and the mission flies on in auto.
#[test]
fn wild_receiver_channels_are_refused_and_the_link_is_lost() {
    let f = fly_twice(
        "rc_wild",
        Faults {
            rc_wild_s: Some((AT_S, f64::INFINITY)),
            ..Faults::default()
        },
    );
    // the frames at 50 Hz: the last good one at 1.98 s
    fault_to(&f, "receiver wild", "rc_link: receiver silent", 1.98, 0.5);
    let refused = f.result.onboard.rc_frames_refused;
    // 50 frames/s from 2 s to 4.5 s
    assert!((120..=126).contains(&refused), "{refused} frames refused");
    let texts = f
        .log
        .texts_with("rc_input: RC: channel out of range, frame refused");
    assert_eq!(texts.len() as u32, refused.ilog2() + 1, "{texts:?}");
    assert_eq!(f.result.onboard.final_mode, "auto");
}
