//! `helicon onboard`'s program against hostile devices on pseudo-terminals:
//! a scripted hardware (a level, still helicopter at home: IMU at 400 Hz,
//! GPS at 5 Hz, the receiver armed at 50 Hz) that, at a chosen instant,
//! hangs up a device's line (and plugs a new one in behind the same path,
//! as `/dev/serial/by-id` links do), or sends what no sensor can measure:
//! a GPS without a fix, a glitching fix 10 km away at 300 m/s, an IMU sample
//! of 3e38 m/s², a 3e38-gauss field, receiver channels at 65535 µs or a
//! toggling arm switch. Each time the program must keep running, refuse the
//! value, act by its failsafe rule and say so in the log.
//!
//! The device paths in `onboard.toml` are symbolic links into the test's
//! folder pointing at the pty slaves; a re-plug points the link at a new
//! pseudo-terminal. The hardware runs on the wall clock, so the checks are
//! of outcomes and of the order of events; the times are printed.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;

use common::Ulog;
use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample};
use helicon_devices::avionics::RcInput as RcFrame;
use helicon_devices::{Geodetic, LocalNed, NavPvt, PtyPair, VnCommon};
use helicon_flight::config::OnboardConfig;
use helicon_sim::closed_loop::prepare;
use helicon_sim::scenario::Scenario;
use nalgebra::Vector3;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// What the scripted hardware does wrong, from `at_s` of its clock.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Fault {
    /// Nothing.
    None,
    /// Hang up the GPS line; plug a new one in at `replug_s`, if given.
    GpsHangup { replug_s: Option<f64> },
    /// Hang up the IMU line; plug a new one in at `replug_s`, if given.
    ImuHangup { replug_s: Option<f64> },
    /// Hang up the avionics line and plug a new one in at `replug_s`.
    AvionicsHangup { replug_s: f64 },
    /// NAV-PVT with fix type 0 (no fix), valid checksum.
    GpsNoFix,
    /// One NAV-PVT 10 km north, 5 km up, 300 m/s.
    GpsGlitch,
    /// One fix 200 m east at rest (a multipath jump: a plausible fix, but
    /// not where the helicopter can be).
    GpsJump,
    /// IMU samples of 3e38 m/s².
    ImuAbsurd,
    /// A 3e38-gauss field.
    MagAbsurd,
    /// Receiver channels at 65535 µs (and 0 µs every other frame).
    RcWild,
    /// The arm switch toggling every frame.
    ArmToggling,
    /// The arm switch moved to off and held there (no kill channel).
    ArmOff,
    /// The kill channel (channel 6, configured as `rc.kill_channel`) high
    /// and held.
    Kill,
    /// The pilot's switch in manual, the sticks at the receiver's range
    /// (800 and 2200 µs: in range, beyond the servos' limits).
    ManualOverLimit,
}

struct Run {
    report: helicon_flight::runtime::RunReport,
    ulog: Ulog,
    /// The servo commands of the servo frames the program sent on the
    /// avionics line during the fault (read only for
    /// [`Fault::ManualOverLimit`]).
    servo_sent: Vec<helicon_core::state::Input>,
}

/// The sticks of [`Fault::ManualOverLimit`] (channels 1–4: `S_col`, `S_lat`,
/// `S_lon`, `S_tr`): ±0.7 of servo command, beyond the collective's
/// (−0.10…0.30) and the tail's (−0.37…0.62) limits.
const OVER_LIMIT_STICKS_US: [u16; 4] = [2200, 2200, 800, 800];

/// Point `link` at `target`, replacing what it pointed at (atomically).
fn relink(target: &Path, link: &Path) {
    let tmp = link.with_extension("new");
    let _ = std::fs::remove_file(&tmp);
    std::os::unix::fs::symlink(target, &tmp).unwrap();
    std::fs::rename(&tmp, link).unwrap();
}

#[allow(clippy::too_many_lines)] // one scripted hardware: its devices and faults
fn fly(tag: &str, fault: Fault, at_s: f64, extra: &str, duration_s: f64) -> Run {
    // one flight at a time: the programs run on the wall clock, and nine
    // at once on two cores would starve each other's hardware threads
    static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _turn = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let dir = helicon_test_support::process_scratch().join(tag);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let s = Scenario::from_toml_str("name = \"hover\"\nduration_s = 1.0\n", "s.toml").unwrap();
    let prepared = prepare(&s).unwrap();
    prepared.gains.save(&dir.join("gains.json")).unwrap();
    let mut imu = PtyPair::open().unwrap();
    let mut gps = PtyPair::open().unwrap();
    let mut av = PtyPair::open().unwrap();
    let links: [PathBuf; 3] = ["imu", "gps", "avionics"].map(|n| dir.join(format!("{n}.tty")));
    relink(imu.slave_path(), &links[0]);
    relink(gps.slave_path(), &links[1]);
    relink(av.slave_path(), &links[2]);
    let cfg_text = format!(
        "gains = \"gains.json\"\n\
         [devices.imu]\npath = \"{}\"\nbaud = 921600\n\
         [devices.gps]\npath = \"{}\"\nbaud = 115200\n\
         [devices.avionics]\npath = \"{}\"\nbaud = 115200\n\
         [stale]\nimu_s = 0.05\ngps_s = 1.0\nmag_s = 0.5\nrc_s = 0.3\n\
         [failsafe]\nhold_s = 30.0\n\
         [rc]\narm_hold_s = 0.2\n{kill}\
         [landing]\nenabled = false\n\
         [log]\ndir = \"logs\"\n\
         [realtime]\nsched_fifo = false\nmlockall = false\n{extra}\n",
        links[0].display(),
        links[1].display(),
        links[2].display(),
        kill = if fault == Fault::Kill {
            "kill_channel = 6\n"
        } else {
            ""
        },
    );
    std::fs::write(dir.join("onboard.toml"), cfg_text).unwrap();
    let cfg = OnboardConfig::from_file(&dir.join("onboard.toml")).unwrap();
    let home = LocalNed::new(Geodetic::new(57.0146, 9.9869, 20.0).unwrap());
    let field = Vector3::from(cfg.sensors.mag.field_ned);
    let g = prepared.model.params().environment.g_m_s2;
    let done = Arc::new(AtomicBool::new(false));
    // the hardware's clock starts when the program has aligned (its first
    // receiver frame read): faults are timed from then
    let hw = {
        let done = done.clone();
        let links = links.clone();
        std::thread::spawn(move || {
            let t0 = Instant::now();
            let mut k = 0u64;
            let mut gps_up = true;
            let mut imu_up = true;
            let mut av_up = true;
            // faults count from 1 s of the hardware's clock: the program
            // has aligned and armed by then (its clock a few ms behind)
            let at = at_s + 1.0;
            let mut servo_sent = Vec::new();
            let mut decoder = helicon_devices::avionics::AvionicsDecoder::new();
            let mut buf = [0u8; 1024];
            while !done.load(Ordering::Relaxed) && k < 400 * 30 {
                let t = k as f64 * 0.0025;
                let faulty = t >= at && fault != Fault::None;
                // hang-ups and re-plugs
                match fault {
                    Fault::GpsHangup { replug_s } => {
                        if faulty && gps_up && replug_s.is_none_or(|r| t < r + 1.0) {
                            gps = PtyPair::open().unwrap(); // the old master closed
                            let _ = std::fs::remove_file(&links[1]);
                            gps_up = false;
                        }
                        if !gps_up && replug_s.is_some_and(|r| t >= r + 1.0) {
                            relink(gps.slave_path(), &links[1]);
                            gps_up = true;
                        }
                    }
                    Fault::ImuHangup { replug_s } => {
                        if faulty && imu_up && replug_s.is_none_or(|r| t < r + 1.0) {
                            imu = PtyPair::open().unwrap();
                            let _ = std::fs::remove_file(&links[0]);
                            imu_up = false;
                        }
                        if !imu_up && replug_s.is_some_and(|r| t >= r + 1.0) {
                            relink(imu.slave_path(), &links[0]);
                            imu_up = true;
                        }
                    }
                    Fault::AvionicsHangup { replug_s } => {
                        if faulty && av_up && t < replug_s + 1.0 {
                            av = PtyPair::open().unwrap();
                            let _ = std::fs::remove_file(&links[2]);
                            av_up = false;
                        }
                        if !av_up && t >= replug_s + 1.0 {
                            relink(av.slave_path(), &links[2]);
                            av_up = true;
                        }
                    }
                    _ => {}
                }
                if k % 8 == 0 && av_up {
                    let mut channels_us = [1500u16; 8];
                    channels_us[4] = 2000;
                    if faulty && fault == Fault::RcWild {
                        channels_us = [if k % 16 == 0 { 65535 } else { 0 }; 8];
                    }
                    if faulty && fault == Fault::ArmToggling && k % 16 == 8 {
                        channels_us[4] = 1000;
                    }
                    if faulty && fault == Fault::ArmOff {
                        channels_us[4] = 1000;
                    }
                    if faulty && fault == Fault::Kill {
                        channels_us[5] = 2000;
                    }
                    let manual = faulty && fault == Fault::ManualOverLimit;
                    if manual {
                        channels_us[..4].copy_from_slice(&OVER_LIMIT_STICKS_US);
                    }
                    let rc = RcFrame {
                        autonomous: !manual,
                        channels_us,
                        ..RcFrame::default()
                    };
                    let _ = av.write_all(rc.encode().as_bytes());
                }
                if k % 80 == 0 && gps_up {
                    let mut fix = GpsFix {
                        epoch_s: t,
                        fix: GpsFixType::Fix3d,
                        position_ned_m: Vector3::zeros(),
                        velocity_ned_m_s: Some(Vector3::zeros()),
                    };
                    let glitch = fault == Fault::GpsGlitch && faulty && t < at + 0.2;
                    if glitch {
                        fix.position_ned_m = Vector3::new(10_000.0, 0.0, -5_000.0);
                        fix.velocity_ned_m_s = Some(Vector3::new(300.0, 0.0, 0.0));
                    }
                    if fault == Fault::GpsJump && faulty && t < at + 0.2 {
                        fix.position_ned_m = Vector3::new(0.0, 200.0, 0.0);
                    }
                    let itow = 259_200_000 + (t * 1000.0) as u32;
                    let mut pvt = NavPvt::from_gps_fix(&fix, &home, itow, 0.0).unwrap();
                    if faulty && fault == Fault::GpsNoFix {
                        pvt.fix_type = 0;
                        pvt.flags = 0;
                    }
                    let _ = gps.write_all(pvt.encode().as_bytes());
                }
                let mut sample = ImuSample {
                    specific_force_body_m_s2: Vector3::new(0.0, 0.0, -g),
                    gyro_body_rad_s: Vector3::zeros(),
                };
                if faulty && fault == Fault::ImuAbsurd {
                    sample.specific_force_body_m_s2.x = 3e38;
                }
                let mut mag = (k % 4 == 0).then_some(field);
                if faulty && fault == Fault::MagAbsurd {
                    mag = mag.map(|_| Vector3::new(3e38, 0.0, 0.0));
                }
                if imu_up {
                    let vn = VnCommon::from_samples(t, &sample, mag.as_ref()).unwrap();
                    let _ = imu.write_all(vn.encode().unwrap().as_bytes());
                }
                if fault == Fault::ManualOverLimit {
                    // the servo frames the program sent (drained every
                    // sample: the line's buffer never fills)
                    while let Ok(n) = av.read_timeout(&mut buf, Duration::ZERO) {
                        if n == 0 {
                            break;
                        }
                        decoder.push_with(&buf[..n], |m| {
                            if let helicon_devices::avionics::AvionicsMessage::Servo(c) = m
                                && faulty
                            {
                                servo_sent.push(c.inputs());
                            }
                        });
                    }
                }
                k += 1;
                let next = Duration::from_secs_f64(k as f64 * 0.0025);
                if let Some(wait) = next.checked_sub(t0.elapsed()) {
                    std::thread::sleep(wait);
                }
            }
            servo_sent
        })
    };
    let (report, log) =
        helicon_flight::onboard::run(&cfg, Some(Duration::from_secs_f64(duration_s)), false)
            .unwrap();
    done.store(true, Ordering::Relaxed);
    let servo_sent = hw.join().unwrap();
    let ulog = Ulog::read(&log);
    for (t, text) in &ulog.texts {
        eprintln!("{tag}: {:.4} {text}", *t as f64 * 1e-6);
    }
    Run {
        report,
        ulog,
        servo_sent,
    }
}

/// The time (s) from `cause` (the first logged text containing it) to
/// `failsafe` (the first containing it), printed as `what`, and checked to
/// be within `limit_s` (`stale_s`, the configured stale limit, plus 10 ms:
/// the stale limit counts from the device's last good sample, which came
/// before the fault's first sign, and the failsafe acts at the first
/// 2.5 ms step past it; the texts carry the steps' on-board times).
fn fault_to_failsafe(run: &Run, what: &str, cause: &str, failsafe: &str, stale_s: f64) -> f64 {
    let t_cause = first(run, cause);
    let t_failsafe = first(run, failsafe);
    let dt = t_failsafe - t_cause;
    eprintln!(
        "fault to failsafe: {what}: {:.1} ms (stale limit {:.0} ms)",
        dt * 1e3,
        stale_s * 1e3
    );
    assert!(
        dt > 0.0 && dt <= stale_s + 0.01,
        "{what}: {cause:?} at {t_cause:.4} s, {failsafe:?} at {t_failsafe:.4} s"
    );
    dt
}

/// The values of a logged field, which must have been logged.
fn values(run: &Run, topic: &str, field: &str) -> Vec<f64> {
    let v = run.ulog.f64s(topic, field);
    assert!(!v.is_empty(), "nothing logged as {topic}.{field}");
    v
}

/// The first logged text containing `needle`, its time (s).
fn first(run: &Run, needle: &str) -> f64 {
    run.ulog.first_text(needle)
}

/// The GPS line hung up in flight: the program runs on (it ended the
/// whole program before), the loss is logged, the GPS failsafe acts after
/// `stale.gps_s`; a new receiver behind the same path is reopened and its
/// fixes are fused again (the failsafe stays latched, as for any loss).
#[test]
fn a_gps_hung_up_in_flight_is_a_gps_loss_and_is_reopened() {
    let run = fly(
        "gps_hangup",
        Fault::GpsHangup {
            replug_s: Some(2.0),
        },
        0.5,
        "",
        3.5,
    );
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    assert_eq!(run.report.steps, 1400);
    let lost = first(&run, "device: GPS port lost");
    let hold = first(&run, "gps_stale: auto -> hold");
    let back = first(&run, "device: GPS port reopened");
    eprintln!(
        "GPS: lost at {lost:.4} s, hold {:.4} s later, reopened at {back:.4} s",
        hold - lost
    );
    assert!(hold > lost && hold - lost <= 1.0 + 0.01, "{lost} {hold}");
    assert!(back > hold);
    assert_eq!(run.report.final_mode, "hold");
    // fixes fused again after the reopening
    let fused = run.ulog.bools("navigation", "gps_fused");
    let t = run.ulog.u64s("navigation", "timestamp");
    assert!(
        t.iter()
            .zip(&fused)
            .any(|(t, f)| *f && *t as f64 * 1e-6 > back),
        "no fix fused after the reopening"
    );
}

/// The IMU line hung up: the IMU is lost (`imu_lost`, servos at the trim),
/// the program runs on, and the re-plugged IMU flies the law again — in
/// the hold: the magnetometer, which comes in the IMU's messages, was
/// silent longer than `stale.mag_s` (a latched failsafe, as any loss).
#[test]
fn an_imu_hung_up_in_flight_is_an_imu_loss_and_is_reopened() {
    let run = fly(
        "imu_hangup",
        Fault::ImuHangup {
            replug_s: Some(1.0),
        },
        0.5,
        "",
        3.0,
    );
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    assert_eq!(run.report.steps, 1200);
    let lost = first(&run, "device: IMU port lost");
    let imu_lost = first(&run, "imu_stale: auto -> imu_lost");
    let back = first(&run, "device: IMU port reopened");
    let recovered = first(&run, "mag_stale: imu_lost -> hold");
    eprintln!(
        "IMU: lost at {lost:.4} s, imu_lost {:.4} s later, reopened at {back:.4}, recovered at {recovered:.4}",
        imu_lost - lost
    );
    assert!(imu_lost >= lost - 0.06 && imu_lost - lost <= 0.06);
    assert!(recovered >= back);
    assert_eq!(run.report.final_mode, "hold");
}

/// The avionics line hung up: the loss is logged (the receiver side's
/// event, as the sensors'), the receiver is silent (the pilot's link lost,
/// logged) within `stale.rc_s` of the loss, the servo frames meanwhile are
/// dropped and counted, and both come back on the re-plugged line.
#[test]
fn an_avionics_line_hung_up_is_reopened() {
    let run = fly(
        "av_hangup",
        Fault::AvionicsHangup { replug_s: 1.0 },
        0.5,
        "",
        3.0,
    );
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    assert_eq!(run.report.steps, 1200);
    fault_to_failsafe(
        &run,
        "avionics hang-up -> receiver silent",
        "device: avionics port lost",
        "rc_link: receiver silent",
        0.3,
    );
    first(&run, "device: avionics port reopened");
    first(&run, "rc_link: the pilot's link back");
    assert!(run.report.servo_frames_dropped > 0);
    assert_eq!(run.report.final_mode, "auto");
}

/// A receiver that reports no fix (fix type 0, valid checksums) is a GPS
/// loss: its messages are refused, and the failsafe acts as
/// `gps_rejected` after `stale.gps_s` (before, any message counted as a
/// fresh fix and the failsafe never acted).
#[test]
fn a_gps_without_a_fix_triggers_the_gps_failsafe() {
    let run = fly("gps_nofix", Fault::GpsNoFix, 0.5, "", 2.5);
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    let refused = first(&run, "GPS: no 3-D fix, refused (1 so far)");
    let hold = first(&run, "gps_rejected: auto -> hold");
    eprintln!(
        "no fix: first refused at {refused:.4}, hold {:.4} s later",
        hold - refused
    );
    assert!(hold > refused && hold - refused <= 1.0 + 0.01);
    assert_eq!(run.report.final_mode, "hold");
}

/// One valid-checksum NAV-PVT 10 km away, 5 km up, at 300 m/s: refused (an
/// impossible speed); the estimate never leaves the still helicopter and
/// the servos never saturate.
#[test]
fn a_glitching_fix_is_refused_and_never_flown() {
    let run = fly("gps_glitch", Fault::GpsGlitch, 0.5, "", 2.0);
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    first(&run, "GPS: impossible speed, refused");
    assert_eq!(run.report.final_mode, "auto");
    for axis in 0..3 {
        let v = values(&run, "navigation", &format!("velocity_ned_m_s[{axis}]"));
        let max = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(max < 1.0, "velocity[{axis}] reached {max} m/s");
    }
    let sat = run.ulog.bools("control", "saturated[0]");
    assert!(!sat.is_empty());
    assert!(!sat.iter().any(|s| *s), "a servo saturated");
}

/// A fix 200 m away, plausible in itself: the navigation's innovation gate
/// refuses it; the position estimate stays at home, and the next fixes
/// come within `stale.gps_s`.
#[test]
fn a_jumping_fix_is_refused_by_the_innovation_gate() {
    let run = fly("gps_jump", Fault::GpsJump, 0.5, "", 2.0);
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    first(&run, "GPS: jump refused by the innovation gate (1 so far)");
    assert_eq!(run.report.final_mode, "auto");
    let east = values(&run, "navigation", "position_ned_m[1]");
    let max = east.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(max < 1.0, "the east position estimate reached {max} m");
}

/// An IMU reporting 3e38 m/s² (finite, impossible): every such sample is
/// refused, the IMU is lost as `imu_rejected` after `stale.imu_s` (servos at
/// the trim), and the attitude estimate never takes the value.
#[test]
fn impossible_imu_samples_are_refused_and_the_imu_is_lost() {
    let run = fly("imu_absurd", Fault::ImuAbsurd, 0.5, "", 2.0);
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    fault_to_failsafe(
        &run,
        "IMU refused -> imu_rejected",
        "IMU: acceleration beyond range, refused (1 so far)",
        "imu_rejected: auto -> imu_lost",
        0.05,
    );
    assert_eq!(run.report.final_mode, "imu_lost");
    let att = values(&run, "control", "estimate[0]");
    assert!(
        att.iter().all(|a| a.abs() < 0.1),
        "attitude estimate left the level"
    );
    // the servos at the trim once lost, never beyond the servo range
    let s = values(&run, "servo_output", "command[0]");
    assert!(s.iter().all(|x| x.abs() <= 1.0));
}

/// A 3e38-gauss field: refused, the magnetometer failsafe acts as
/// `mag_rejected` after `stale.mag_s`; the heading estimate stays.
#[test]
fn an_impossible_field_is_refused_and_the_mag_failsafe_acts() {
    let run = fly("mag_absurd", Fault::MagAbsurd, 0.5, "", 2.0);
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    fault_to_failsafe(
        &run,
        "field refused -> mag_rejected",
        "mag: field magnitude implausible, refused (1 so far)",
        "mag_rejected: auto -> hold",
        0.5,
    );
    let psi = values(&run, "control", "estimate[2]");
    assert!(psi.iter().all(|p| p.abs() < 0.1));
}

/// Receiver channels at 65535 and 0 µs: every frame refused (the sticks
/// never reach the servos, the servo frames keep going out), so the
/// receiver reads as silent: the pilot's link lost, the mission flies on.
/// An arm switch toggling every 20 ms never disarms.
#[test]
fn wild_channels_are_refused_and_a_toggling_arm_switch_does_nothing() {
    let run = fly("rc_wild", Fault::RcWild, 0.5, "", 2.0);
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    first(&run, "rc_link: receiver silent");
    assert_eq!(run.report.final_mode, "auto");
    assert!(run.report.servo_frames >= 799);
    // each refused frame counted (the fault from about 0.5 s of the 2 s
    // flight, 50 frames/s: some 50–75 frames), texted at the first and
    // each doubling only
    let refused = run.report.rc_frames_refused;
    let texts = run
        .ulog
        .texts_with("rc_input: RC: channel out of range, frame refused");
    eprintln!(
        "wild channels: {refused} frames refused, {} texts",
        texts.len()
    );
    assert!(refused >= 20, "{refused} frames refused");
    first(&run, "frame refused (1 so far)");
    assert_eq!(texts.len() as u32, refused.ilog2() + 1, "{texts:?}");
    let run = fly("arm_toggling", Fault::ArmToggling, 0.5, "", 2.0);
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    assert_eq!(run.report.final_mode, "auto");
    assert!(
        run.ulog.texts_with("disarmed at").is_empty()
            && run.ulog.texts_with("-> disarmed").is_empty()
    );
}

/// The arm switch moved to off in flight and held there: with no kill
/// channel configured (and no ground logic to say the helicopter is down)
/// it is refused and said once, the helicopter flying on in auto. With a
/// kill channel configured, the kill held `rc.kill_hold_s` (0.1 s)
/// disarms at once, reason `kill`.
#[test]
fn the_arm_switch_never_disarms_in_flight_only_the_kill_channel_does() {
    let run = fly("arm_off", Fault::ArmOff, 0.5, "", 2.0);
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    assert_eq!(run.report.final_mode, "auto");
    let refused = run.ulog.texts_with("disarm refused in flight");
    assert_eq!(refused.len(), 1, "{:?}", run.ulog.texts);
    assert!(
        run.ulog.texts_with("-> disarmed").is_empty(),
        "{:?}",
        run.ulog.texts
    );
    let run = fly("kill", Fault::Kill, 0.5, "", 2.0);
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    assert_eq!(run.report.final_mode, "disarmed");
    let t_kill = first(&run, "kill: auto -> disarmed");
    let t_armed = first(&run, "armed: disarmed -> auto");
    eprintln!(
        "kill channel: disarmed {:.3} s after arming",
        t_kill - t_armed
    );
    assert!(run.ulog.texts_with("disarm refused").is_empty());
}

/// The pilot flying manual with the sticks at the receiver's range (800
/// and 2200 µs, in range, so the frames are used): every servo frame sent
/// on the avionics line is within the servos' limits (the collective's
/// 0.30 and the tail's −0.37, not the sticks' ±0.7), the over-limit axes
/// held at their limits.
#[test]
fn sticks_beyond_the_servo_limits_are_clamped_in_manual() {
    let run = fly("manual_over_limit", Fault::ManualOverLimit, 0.5, "", 2.0);
    assert!(run.report.error.is_none(), "{:?}", run.report.error);
    assert_eq!(run.report.final_mode, "manual");
    assert_eq!(run.report.rc_frames_refused, 0);
    let limits = prepare(
        &Scenario::from_toml_str("name = \"hover\"\nduration_s = 1.0\n", "s.toml").unwrap(),
    )
    .unwrap()
    .model
    .params()
    .servo_limits();
    // the frames carry counts of 1e-4: half a count of rounding
    let tol = 0.5e-4 + 1e-12;
    let sent = &run.servo_sent;
    assert!(sent.len() > 100, "{} servo frames read", sent.len());
    for u in sent {
        for i in 0..4 {
            assert!(
                u[i] >= limits.min[i] - tol && u[i] <= limits.max[i] + tol,
                "servo {i}: {} beyond {}…{}",
                u[i],
                limits.min[i],
                limits.max[i]
            );
        }
    }
    // the pilot's sticks reached the servos, clamped
    let last = sent.last().unwrap();
    assert!((last[0] - limits.max[0]).abs() <= tol, "{last:?}");
    assert!((last[3] - limits.min[3]).abs() <= tol, "{last:?}");
    assert!(
        (last[1] - 0.7).abs() <= tol && (last[2] + 0.7).abs() <= tol,
        "{last:?}"
    );
}
