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

#[test]
fn the_onboard_program_aligns_arms_flies_and_logs() {
    let dir = std::env::temp_dir().join(format!("helicon_onboard_prog_{}", std::process::id()));
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
         [stale]\nimu_s = 0.5\ngps_s = 5.0\nmag_s = 5.0\n\
         [log]\ndir = \"logs\"\n\
         [realtime]\nsched_fifo = false\nmlockall = false\n",
        imu.slave_path().display(),
        gps.slave_path().display(),
        av.slave_path().display()
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
                if k % 8 == 0 {
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
        helicon_flight::onboard::run(&cfg, Some(Duration::from_secs(1)), false).unwrap();
    done.store(true, Ordering::Relaxed);
    hw.join().unwrap();
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
