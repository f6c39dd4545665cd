//! The failsafes under lock-step SITL: GPS loss, a stuck IMU, the pilot's
//! manual override mid-flight. Each: the expected behaviour of the
//! helicopter (truth) and the on-board log's entries (read by `px4-ulog`).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;

use common::{Ulog, options, scenario};
use helicon_flight::ports::{stick_command, stick_us};
use helicon_sim::closed_loop::{Prepared, Termination, prepare};
use helicon_sim::log_csv::read_log_csv;
use helicon_sitl as sitl;

/// Codes of the log's message set (helicon-ulog): modes and failsafe reasons.
const AUTOMATIC: u8 = 2;
const MANUAL: u8 = 1;
const FAILSAFE: u8 = 3;
const SENSOR_TIMEOUT: u8 = 3;

#[test]
fn gps_loss_holds_then_descends() {
    // hover with a 2 m/s north step at 1 s; the GPS is lost at 2 s
    let s = scenario("demo.toml", 10.0);
    let prepared = prepare(&s).unwrap();
    let mut o = options("gps_loss");
    o.faults.gps_lost_from_s = Some(2.0);
    o.failsafe.hold_s = 4.0;
    let r = sitl::run(&s, &prepared, &o).unwrap();
    assert_eq!(r.summary.termination, Termination::Completed);
    let log = Ulog::read(&r.ulog);
    // hold when the last fix is older than stale.gps_s = 1 s (the last fix
    // was delivered before 2 s), descent hold_s later
    let hold = log.texts_with("gps_stale: auto -> hold");
    assert_eq!(hold.len(), 1, "{:?}", log.texts);
    assert!(hold[0].0 > 2.7 && hold[0].0 < 3.2, "hold at {}", hold[0].0);
    let descent = log.texts_with("hold_elapsed: hold -> descent");
    assert_eq!(descent.len(), 1);
    assert!((descent[0].0 - hold[0].0 - 4.0).abs() < 0.003);
    // each event is one text, the supervisor's (no generic "mode: …" or
    // "failsafe raised: …" beside it)
    assert_eq!(log.texts.len(), 3, "{:?}", log.texts);
    let mode_t = log.u64s("mode", "timestamp");
    let text_t: Vec<u64> = log.texts.iter().map(|(t, _)| *t).collect();
    assert_eq!(text_t, mode_t);
    assert_eq!(log.u8s("failsafe", "reason"), vec![SENSOR_TIMEOUT]);
    assert_eq!(log.bools("failsafe", "active"), vec![true]);
    // hold and descent are both the log's failsafe mode; the text names them
    assert_eq!(log.u8s("mode", "mode"), vec![AUTOMATIC, FAILSAFE, FAILSAFE]);
    assert_eq!(r.onboard.final_mode, "descent");
    // the references flown: zero velocity in hold, 0.5 m/s down in descent
    let t = log.f64s("control", "t_s");
    let vn_ref = log.f64s("control", "ref_vel_ned_m_s[0]");
    let vd_ref = log.f64s("control", "ref_vel_ned_m_s[2]");
    for k in 0..t.len() {
        if t[k] > hold[0].0 + 0.01 && t[k] < descent[0].0 {
            assert_eq!((vn_ref[k], vd_ref[k]), (0.0, 0.0), "t = {}", t[k]);
        }
        if t[k] > descent[0].0 + 0.01 {
            assert_eq!(vd_ref[k], 0.5);
        }
    }
    // the helicopter: slowed from 2 m/s north in the hold, sinking at the end
    let truth = read_log_csv(&r.log_csv).unwrap();
    let (ts, vn, vd) = (
        truth.time_s(),
        truth.column("vn").unwrap(),
        truth.column("vd").unwrap(),
    );
    let mean = |v: &[f64], a: f64, b: f64| {
        let sel: Vec<f64> = (0..ts.len())
            .filter(|&k| ts[k] >= a && ts[k] < b)
            .map(|k| v[k])
            .collect();
        sel.iter().sum::<f64>() / sel.len() as f64
    };
    let before = mean(vn, 2.5, 2.7);
    let held = mean(vn, hold[0].0 + 2.5, descent[0].0);
    eprintln!(
        "vn before {before:.3}, in hold {held:.3}, vd at end {:.3}",
        mean(vd, 9.0, 10.0)
    );
    // without GPS the velocity is dead-reckoned from the IMU: the hold
    // brings the estimate to zero, the truth keeps the drift (about
    // 1.3 m/s here, in the demo's turbulence)
    assert!(before > 1.5, "{before}");
    assert!(held < 0.6 * before, "{held}");
    assert!(mean(vd, 9.0, 10.0) > 0.2, "sinking");
}

#[test]
fn a_stuck_imu_hands_the_servos_to_the_trim_until_it_recovers() {
    let s = scenario("demo.toml", 4.0);
    let prepared = prepare(&s).unwrap();
    let mut o = options("imu_stale");
    o.faults.imu_frozen_s = Some((2.0, 2.25));
    let r = sitl::run(&s, &prepared, &o).unwrap();
    assert_eq!(r.summary.termination, Termination::Completed);
    assert_eq!(r.onboard.steps_without_imu, 100); // 0.25 s at 400 Hz
    let log = Ulog::read(&r.ulog);
    // the last fresh sample at 1.9975 s; lost once older than stale.imu_s = 0.02 s
    let lost = log.texts_with("imu_stale: auto -> imu_lost");
    assert_eq!(lost.len(), 1, "{:?}", log.texts);
    assert!((lost[0].0 - 2.02).abs() < 1e-6, "{}", lost[0].0);
    let back = log.texts_with("imu_recovered: imu_lost -> auto");
    assert_eq!(back.len(), 1, "{:?}", log.texts);
    assert!((back[0].0 - 2.25).abs() < 1e-6);
    assert_eq!(
        log.u8s("failsafe", "reason"),
        vec![SENSOR_TIMEOUT, SENSOR_TIMEOUT]
    );
    assert_eq!(log.bools("failsafe", "active"), vec![true, false]);
    // no control records while the IMU is stuck; the servos at the trim while lost
    assert_eq!(
        log.u64s("control", "sample").len() as u64,
        r.onboard.steps - 100
    );
    let trim = prepared.gains.set.u_trim;
    for k in 809..900 {
        for i in 0..4 {
            assert!(
                (r.received[k][i] - trim[i]).abs() <= 0.5e-4 + 1e-12,
                "k {k}"
            );
        }
    }
    assert!((0..4).any(|i| (r.received[905][i] - trim[i]).abs() > 1e-4));
}

#[test]
fn the_pilots_switch_takes_the_servos_at_once() {
    let s = scenario("demo.toml", 3.0);
    let prepared = prepare(&s).unwrap();
    let mut o = options("manual");
    o.pilot.manual_from_s = Some(2.0);
    let r = sitl::run(&s, &prepared, &o).unwrap();
    assert_eq!(r.summary.termination, Termination::Completed);
    let trim = prepared.gains.set.u_trim;
    // the receiver frame of 2.0 s precedes the IMU message of sample 800:
    // the servos are the pilot's from that very sample
    let first = (790..900)
        .find(|&k| {
            (0..4).all(|i| (r.received[k][i] - stick_command(stick_us(trim[i]))).abs() < 1e-9)
        })
        .unwrap();
    assert_eq!(first, 800);
    for k in first..r.received.len() {
        for i in 0..4 {
            let stick = stick_command(stick_us(trim[i]));
            assert!((r.received[k][i] - stick).abs() < 1e-9, "k {k}");
        }
    }
    let log = Ulog::read(&r.ulog);
    let manual = log.texts_with("pilot_manual: auto -> manual");
    assert_eq!(manual.len(), 1, "{:?}", log.texts);
    assert_eq!(log.u8s("mode", "mode"), vec![AUTOMATIC, MANUAL]);
    // the receiver's frames are logged, the switch at manual from 2 s on
    let rc_t = log.u64s("rc_input", "timestamp");
    let rc_manual = log.bools("rc_input", "manual_switch");
    assert!(rc_t.len() >= 30);
    for (t, m) in rc_t.iter().zip(&rc_manual) {
        assert_eq!(*m, *t as f64 * 1e-6 >= 2.0, "rc at {t} µs");
    }
    // servo records name the pilot as their source
    let src = log.u8s("servo_output", "source");
    assert!(src[800..].iter().all(|s| *s == 1));
    assert!(src[..800].iter().all(|s| *s == 0));
}

const RC_LOSS: u8 = 5;
const PILOT: u8 = 6;

/// After a lost link in manual (2 s, the hold) the link comes back and the
/// pilot's switch (still at manual) takes the servos at 3 s: one text each,
/// the modes auto → manual → failsafe → manual, the failsafe raised by the
/// loss and cleared by the pilot.
fn pilot_takes_back_at_3_s(log: &Ulog) {
    assert_eq!(log.texts_with("rc_link: the pilot's link back").len(), 1);
    let back = log.texts_with("pilot_manual: hold -> manual");
    assert_eq!(back.len(), 1, "{:?}", log.texts);
    assert!((back[0].0 - 3.0).abs() < 1e-6);
    assert_eq!(
        log.u8s("mode", "mode"),
        vec![AUTOMATIC, MANUAL, FAILSAFE, MANUAL]
    );
    assert_eq!(log.u8s("failsafe", "reason"), vec![RC_LOSS, PILOT]);
    assert_eq!(log.bools("failsafe", "active"), vec![true, false]);
}

/// The servos of such a flight: the pilot's sticks from 1 s until sample
/// `k_hold`, the law's command (not the receiver's failsafe sticks) from
/// then until 3 s, the pilot's again from 3 s.
fn servos_pilot_law_pilot(r: &sitl::SitlResult, prepared: &Prepared, log: &Ulog, k_hold: usize) {
    let trim = prepared.gains.set.u_trim;
    let pilot = |k: usize| {
        (0..4).all(|i| (r.received[k][i] - stick_command(stick_us(trim[i]))).abs() < 1e-9)
    };
    assert!((400..k_hold).all(pilot));
    assert!((k_hold + 1..1200).all(|k| !pilot(k)));
    assert!((1200..1601).all(pilot));
    let control = log.f64s("control", "command[0]");
    for k in k_hold..1200 {
        assert!(
            (r.received[k][0] - control[k]).abs() <= 0.5e-4 + 1e-12,
            "k {k}"
        );
    }
}

/// The receiver's failsafe while the pilot flies: the law's hold takes
/// over at the very sample (latched, reason `rc_lost`), the failsafe
/// frame's switches (manual, arm off) are ignored, and when the link is
/// back the pilot's switch (still at manual) takes the servos again.
#[test]
fn a_receiver_failsafe_in_manual_hands_over_to_the_hold() {
    let s = scenario("demo.toml", 4.0);
    let prepared = prepare(&s).unwrap();
    let mut o = options("rc_failsafe_manual");
    o.pilot.manual_from_s = Some(1.0);
    o.pilot.rc_failsafe_s = Some((2.0, 3.0));
    let r = sitl::run(&s, &prepared, &o).unwrap();
    assert_eq!(r.summary.termination, Termination::Completed);
    let log = Ulog::read(&r.ulog);
    let hold = log.texts_with("rc_lost: manual -> hold");
    assert_eq!(hold.len(), 1, "{:?}", log.texts);
    assert!((hold[0].0 - 2.0).abs() < 1e-6, "{}", hold[0].0);
    assert_eq!(log.texts_with("rc_link: receiver failsafe").len(), 1);
    pilot_takes_back_at_3_s(&log);
    // the servos: the pilot's until 2 s, the law's (not the receiver's
    // failsafe sticks) over the loss, the pilot's again from 3 s
    servos_pilot_law_pilot(&r, &prepared, &log, 800);
    // the receiver's frames logged with the loss
    let rc_t = log.u64s("rc_input", "timestamp");
    let lost = log.bools("rc_input", "signal_lost");
    for (t, l) in rc_t.iter().zip(&lost) {
        let t = *t as f64 * 1e-6;
        assert_eq!(*l, (2.0..3.0).contains(&t), "rc at {t} s");
    }
}

/// The receiver's failsafe in auto: the mission flies on (no change of
/// mode, never disarmed by the failsafe frame's arm switch), the loss
/// and the return logged.
#[test]
fn a_receiver_failsafe_in_auto_flies_the_mission_on() {
    let s = scenario("demo.toml", 3.0);
    let prepared = prepare(&s).unwrap();
    let mut o = options("rc_failsafe_auto");
    o.pilot.rc_failsafe_s = Some((1.0, 2.0));
    let r = sitl::run(&s, &prepared, &o).unwrap();
    assert_eq!(r.summary.termination, Termination::Completed);
    let log = Ulog::read(&r.ulog);
    assert_eq!(log.u8s("mode", "mode"), vec![AUTOMATIC]);
    assert_eq!(r.onboard.final_mode, "auto");
    let lost = log.texts_with("rc_link: receiver failsafe");
    assert_eq!(lost.len(), 1, "{:?}", log.texts);
    assert!((lost[0].0 - 1.0).abs() < 1e-6);
    assert_eq!(log.texts_with("rc_link: the pilot's link back").len(), 1);
    // the law flew every sample
    let source = log.u8s("servo_output", "source");
    assert!(source.iter().all(|s| *s == 0));
}

/// A receiver that goes silent while the pilot flies (no frames at all
/// over 2–3 s: a cut cable) is its failsafe flag: the law's hold once the
/// last frame is older than `stale.rc_s` (within one control period),
/// latched, one text; when the frames come back the pilot's switch (still
/// at manual) takes the servos at once.
#[test]
fn a_silent_receiver_in_manual_hands_over_to_the_hold() {
    let s = scenario("demo.toml", 4.0);
    let prepared = prepare(&s).unwrap();
    let mut o = options("rc_silent_manual");
    o.pilot.manual_from_s = Some(1.0);
    o.pilot.rc_silent_s = Some((2.0, 3.0));
    let ts = 0.0025;
    let rc_s = o.stale.rc_s;
    assert_eq!(rc_s, 0.5, "the default");
    let r = sitl::run(&s, &prepared, &o).unwrap();
    assert_eq!(r.summary.termination, Termination::Completed);
    let log = Ulog::read(&r.ulog);
    // the receiver's last frame before the silence, read from the log
    let rc_t: Vec<f64> = log
        .u64s("rc_input", "timestamp")
        .iter()
        .map(|t| *t as f64 * 1e-6)
        .collect();
    let last = rc_t
        .iter()
        .copied()
        .filter(|t| *t < 2.0)
        .fold(0.0, f64::max);
    assert!((last - 1.98).abs() < 1e-6, "{last}");
    assert!(rc_t.iter().all(|t| !(2.0..3.0).contains(t)), "silent");
    let hold = log.texts_with("rc_lost: manual -> hold");
    assert_eq!(hold.len(), 1, "{:?}", log.texts);
    let after = hold[0].0 - last;
    eprintln!("hold {after:.4} s after the last frame (stale.rc_s {rc_s} s)");
    assert!((after - rc_s).abs() <= ts + 1e-6, "{after}");
    let lost = log.texts_with("rc_link: receiver silent, the pilot's link lost");
    assert_eq!(lost.len(), 1, "{:?}", log.texts);
    assert_eq!(lost[0].0, hold[0].0);
    assert!(log.texts_with("rc_link: receiver failsafe").is_empty());
    pilot_takes_back_at_3_s(&log);
    // the servos: the pilot's (his last sticks) until the hold, the law's
    // over the rest of the silence, the pilot's again from 3 s
    let k_hold = (hold[0].0 / ts).round() as usize;
    servos_pilot_law_pilot(&r, &prepared, &log, k_hold);
}

/// A receiver silent in auto: the mission flies on, the loss and the
/// return logged once each; a shorter silence than `stale.rc_s` is nothing.
#[test]
fn a_silent_receiver_in_auto_flies_the_mission_on() {
    let s = scenario("demo.toml", 3.0);
    let prepared = prepare(&s).unwrap();
    let mut o = options("rc_silent_auto");
    o.pilot.rc_silent_s = Some((1.0, 2.0));
    o.stale.rc_s = 0.3;
    let r = sitl::run(&s, &prepared, &o).unwrap();
    assert_eq!(r.summary.termination, Termination::Completed);
    let log = Ulog::read(&r.ulog);
    assert_eq!(log.u8s("mode", "mode"), vec![AUTOMATIC]);
    assert_eq!(r.onboard.final_mode, "auto");
    let lost = log.texts_with("rc_link: receiver silent");
    assert_eq!(lost.len(), 1, "{:?}", log.texts);
    // last frame at 0.98 s, lost 0.3 s later (+ at most one period)
    assert!((lost[0].0 - 1.28).abs() <= 0.0025 + 1e-6, "{}", lost[0].0);
    let back = log.texts_with("rc_link: the pilot's link back");
    assert_eq!(back.len(), 1);
    assert!((back[0].0 - 2.0).abs() < 1e-6);
    assert!(log.u8s("servo_output", "source").iter().all(|s| *s == 0));

    // 0.25 s of silence with a 0.3 s limit: no loss
    let mut o = options("rc_silent_short");
    o.pilot.rc_silent_s = Some((1.0, 1.25));
    o.stale.rc_s = 0.3;
    let r = sitl::run(&s, &prepared, &o).unwrap();
    let log = Ulog::read(&r.ulog);
    assert!(log.texts_with("rc_link").is_empty(), "{:?}", log.texts);
}
