//! `helicon onboard`'s program end to end on pseudo-terminals: a scripted
//! hardware (a level, still helicopter at home: IMU at 400 Hz, GPS at 5 Hz,
//! the receiver armed at 50 Hz) feeds the devices; the program aligns from
//! the sensors, is armed by the receiver, flies on the clock for 1 s and
//! writes its log. No figure depends on the wall clock.
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
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// The program on pseudo-terminals for 1 s of control steps against the
/// scripted hardware, whose receiver sends frames until `rc_until_s` of its
/// own clock (always when `None`); `stale` is the `[stale]` section.
fn fly(
    tag: &str,
    rc_until_s: Option<f64>,
    stale: &str,
    duration_s: f64,
) -> (
    helicon_flight::runtime::RunReport,
    std::path::PathBuf,
    std::path::PathBuf,
) {
    let dir = helicon_test_support::process_scratch().join(tag);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // gains designed at hover for the Bergen Twin
    let s = Scenario::from_toml_str("name = \"hover\"\nduration_s = 1.0\n", "s.toml").unwrap();
    let prepared = prepare(&s).unwrap();
    prepared.gains.save(&dir.join("gains.json")).unwrap();
    let mut imu = PtyPair::open().unwrap();
    let mut gps = PtyPair::open().unwrap();
    let mut av = PtyPair::open().unwrap();
    let cfg_text = format!(
        "gains = \"gains.json\"\n\
         [devices.imu]\npath = \"{}\"\nbaud = 921600\n\
         [devices.gps]\npath = \"{}\"\nbaud = 115200\n\
         [devices.avionics]\npath = \"{}\"\nbaud = 115200\n\
         [stale]\nimu_s = 0.5\ngps_s = 5.0\nmag_s = 5.0\n{stale}\n\
         [landing]\nenabled = false\n\
         [log]\ndir = \"logs\"\n\
         [realtime]\nsched_fifo = false\nmlockall = false\n",
        imu.slave_path().display(),
        gps.slave_path().display(),
        av.slave_path().display(),
    );
    std::fs::write(dir.join("onboard.toml"), cfg_text).unwrap();
    let cfg = OnboardConfig::from_file(&dir.join("onboard.toml")).unwrap();

    // the scripted hardware, on the wall clock
    let home = LocalNed::new(Geodetic::new(57.0146, 9.9869, 20.0).unwrap());
    let field = Vector3::from(cfg.sensors.mag.field_ned);
    let g = prepared.model.params().environment.g_m_s2;
    let done = Arc::new(AtomicBool::new(false));
    let hw = {
        let done = done.clone();
        std::thread::spawn(move || {
            let t0 = Instant::now();
            let mut k = 0u64;
            while !done.load(Ordering::Relaxed) && k < 400 * 20 {
                let t = k as f64 * 0.0025;
                if k % 8 == 0 && rc_until_s.is_none_or(|u| t < u) {
                    let mut channels_us = [1500u16; 8];
                    channels_us[4] = 2000;
                    let rc = RcFrame {
                        autonomous: true,
                        channels_us,
                        ..RcFrame::default()
                    };
                    av.write_all(rc.encode().as_bytes()).unwrap();
                }
                if k % 80 == 0 {
                    let fix = GpsFix {
                        epoch_s: t,
                        fix: GpsFixType::Fix3d,
                        position_ned_m: Vector3::zeros(),
                        velocity_ned_m_s: Some(Vector3::zeros()),
                    };
                    let itow = 259_200_000 + (t * 1000.0) as u32;
                    let pvt = NavPvt::from_gps_fix(&fix, &home, itow, 0.0).unwrap();
                    gps.write_all(pvt.encode().as_bytes()).unwrap();
                }
                let sample = ImuSample {
                    specific_force_body_m_s2: Vector3::new(0.0, 0.0, -g),
                    gyro_body_rad_s: Vector3::zeros(),
                };
                let mag = (k % 4 == 0).then_some(field);
                let vn = VnCommon::from_samples(t, &sample, mag.as_ref()).unwrap();
                imu.write_all(vn.encode().unwrap().as_bytes()).unwrap();
                k += 1;
                let next = Duration::from_secs_f64(k as f64 * 0.0025);
                if let Some(wait) = next.checked_sub(t0.elapsed()) {
                    std::thread::sleep(wait);
                }
            }
        })
    };
    let (report, log) =
        helicon_flight::onboard::run(&cfg, Some(Duration::from_secs_f64(duration_s)), false)
            .unwrap();
    done.store(true, Ordering::Relaxed);
    hw.join().unwrap();
    (report, log, dir)
}

#[test]
fn the_onboard_program_aligns_arms_flies_and_logs() {
    let (report, log, dir) = fly("still", None, "", 1.0);
    assert!(report.error.is_none(), "{:?}", report.error);
    assert_eq!(report.steps, 400);
    assert_eq!(report.final_mode, "auto");
    assert!(log.starts_with(dir.join("logs")));
    let ulog = Ulog::read(&log);
    // armed by the receiver: standby -> automatic
    assert_eq!(ulog.u8s("mode", "mode"), vec![2]);
    assert_eq!(ulog.texts_with("armed: disarmed -> auto").len(), 1);
    // aligned level at home, heading from the magnetometer: a still hover
    let psi = ulog.f64s("control", "estimate[2]");
    assert!(!psi.is_empty());
    assert!(
        psi.iter().all(|p| p.abs() < 0.05),
        "heading {:?}",
        &psi[..3]
    );
    let t = ulog.u64s("timing", "timestamp");
    assert!(t.windows(2).all(|w| w[1] > w[0]));
}

/// The receiver goes silent on the clock-paced program (its own receiver
/// thread, the real avionics link on a pseudo-terminal): once its last
/// frame is older than `stale.rc_s` the loss is logged once; in auto the
/// flight goes on (no change of mode). The instant is the wall clock's
/// here, so only the outcome is checked; the lock-step SITL tests of
/// `failsafe.rs` check the timing.
#[test]
fn a_silent_receiver_on_the_clock_paced_program_is_logged_once() {
    let (report, log, _) = fly(
        "rc_silent",
        Some(0.4),
        "rc_s = 0.3\n[rc]\narm_hold_s = 0.1",
        1.0,
    );
    assert!(report.error.is_none(), "{:?}", report.error);
    assert_eq!(report.final_mode, "auto");
    let ulog = Ulog::read(&log);
    assert_eq!(ulog.u8s("mode", "mode"), vec![2]);
    let lost = ulog.texts_with("rc_link: receiver silent, the pilot's link lost");
    assert_eq!(lost.len(), 1, "{:?}", ulog.texts);
    assert!(ulog.texts_with("link back").is_empty(), "{:?}", ulog.texts);
    // the last receiver frame the control task logged, then the loss
    // after stale.rc_s (the control steps run on the clock, 2.5 ms apart)
    let rc_t = ulog.u64s("rc_input", "timestamp");
    let last = *rc_t.last().unwrap() as f64 * 1e-6;
    let after = lost[0].0 - last;
    eprintln!("loss {after:.4} s after the last frame logged");
    // (the log stamps in whole µs: the strict rule can read as equal)
    assert!(after >= 0.3 - 1e-6, "{after}");
}

/// Nobody reads the avionics port (the scripted hardware never does): once
/// the kernel's buffer is full the servo frames are dropped, never waited
/// for: every control step still runs, the drops are counted in the report
/// and logged as texts at the first and at each doubling.
#[test]
fn servo_frames_the_avionics_port_cannot_take_are_dropped_and_logged() {
    let (report, log, _) = fly("servo_full", None, "", 4.0);
    assert!(report.error.is_none(), "{:?}", report.error);
    assert_eq!(report.steps, 1600);
    assert_eq!(report.servo_frames, 1600);
    let dropped = report.servo_frames_dropped;
    eprintln!("{dropped} of 1600 servo frames dropped");
    assert!(dropped > 0 && dropped < 1600, "{dropped}");
    let ulog = Ulog::read(&log);
    let texts = ulog.texts_with("servo frame(s) dropped so far");
    assert!(
        texts[0].1.contains("avionics: 1 servo frame(s)"),
        "{texts:?}"
    );
    let expected = (0..).take_while(|k| 1u64 << k <= dropped).count();
    assert_eq!(texts.len(), expected, "{texts:?}");
}
