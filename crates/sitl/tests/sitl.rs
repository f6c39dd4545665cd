//! Software in the loop, lock-step: the on-board runtime reads the
//! simulator's devices over pseudo-terminals (VN-100 binary, UBX NAV-PVT,
//! the avionics framed protocol) and its servo frames drive the plant. The
//! on-board log is read back by `px4-ulog`, an independent reader.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers: a failed unwrap is a failed test

mod common;

use common::{Ulog, options, scenario};
use helicon_sim::closed_loop::{Termination, fly, prepare};
use helicon_sim::scenario::OUTPUTS;
use helicon_sitl as sitl;

/// Float32 rounding (round to nearest): relative error at most 2⁻²⁴.
fn f32_bound(x: f64) -> f64 {
    x.abs() * 2f64.powi(-24) + 1e-45
}

/// The transport's resolution: NAV-PVT latitude/longitude 1e-7° (half a
/// step: 5.6 mm north on the meridian radius, 3.0 mm east at 57° N; the
/// ECEF round trip adds < 1e-6 m), height 1 mm, velocity 1 mm/s.
const GPS_HORIZONTAL_M: f64 = 0.5e-7 * std::f64::consts::PI / 180.0 * 6.3925e6 + 1e-6;
const GPS_VERTICAL_M: f64 = 0.5e-3 + 1e-6;
const GPS_VELOCITY_M_S: f64 = 0.5e-3 + 1e-9;
/// The avionics protocol's servo resolution (counts of 1e-4): half a count.
const SERVO_M: f64 = 0.5e-4 + 1e-12;

#[test]
fn sim_and_sitl_agree_up_to_the_transport_quantisation() {
    let s = scenario("demo.toml", 8.0);
    let prepared = prepare(&s).unwrap();
    let opts = options("agree");
    let r = sitl::run(&s, &prepared, &opts).unwrap();
    let flown = fly(&s, &prepared, None).unwrap();
    assert_eq!(r.summary.termination, Termination::Completed);
    assert_eq!(flown.summary.termination, Termination::Completed);
    assert_eq!(r.samples, 3201);
    assert_eq!(r.onboard.steps, 3201);
    assert_eq!(r.onboard.servo_frames, 3201);
    assert_eq!(r.onboard.steps_without_imu, 0);

    // what the on-board software was given, against what the hardware sent
    let log = Ulog::read(&r.ulog);
    let imu_t = log.u64s("sensor_imu", "timestamp");
    assert_eq!(imu_t.len(), r.sent.len());
    let axis = ["[0]", "[1]", "[2]"];
    let mut worst_imu: f64 = 0.0;
    for (i, a) in axis.iter().enumerate() {
        let f = log.f64s("sensor_imu", &format!("specific_force_body_m_s2{a}"));
        let w = log.f64s("sensor_imu", &format!("gyro_body_rad_s{a}"));
        for (k, frame) in r.sent.iter().enumerate() {
            let (fs, ws) = (
                frame.imu.specific_force_body_m_s2[i],
                frame.imu.gyro_body_rad_s[i],
            );
            assert!((f[k] - fs).abs() <= f32_bound(fs), "accel {k}");
            assert!((w[k] - ws).abs() <= f32_bound(ws), "gyro {k}");
            worst_imu = worst_imu.max((f[k] - fs).abs());
        }
    }
    // times: the IMU's nanoseconds
    for (k, frame) in r.sent.iter().enumerate() {
        assert_eq!(imu_t[k], (frame.t_s * 1e6).round() as u64, "time {k}");
    }
    let mags: Vec<_> = r.sent.iter().filter_map(|f| f.mag_body).collect();
    assert_eq!(mags.len(), 801); // 100 Hz
    for (i, a) in axis.iter().enumerate() {
        let m = log.f64s("helicon_mag", &format!("field_body{a}"));
        assert_eq!(m.len(), mags.len());
        for (k, sent) in mags.iter().enumerate() {
            assert!((m[k] - sent[i]).abs() <= f32_bound(sent[i]), "mag {k}");
        }
    }
    let fixes: Vec<_> = r.sent.iter().filter_map(|f| f.gps).collect();
    assert!(fixes.len() >= 35, "{} fixes", fixes.len()); // 5 Hz, 2 % dropouts
    let mut worst = [0.0f64; 3];
    for (i, a) in axis.iter().enumerate() {
        let p = log.f64s("helicon_gps", &format!("position_ned_m{a}"));
        let v = log.f64s("helicon_gps", &format!("velocity_ned_m_s{a}"));
        assert_eq!(p.len(), fixes.len());
        for (k, fix) in fixes.iter().enumerate() {
            let dp = (p[k] - fix.position_ned_m[i]).abs();
            let bound = if i == 2 {
                GPS_VERTICAL_M
            } else {
                GPS_HORIZONTAL_M
            };
            assert!(dp <= bound, "fix {k} axis {i}: {dp} m > {bound} m");
            let vs = fix.velocity_ned_m_s.unwrap()[i];
            assert!((v[k] - vs).abs() <= GPS_VELOCITY_M_S, "velocity {k}");
            worst[i] = worst[i].max(dp);
        }
    }
    eprintln!("worst |Δ| accel {worst_imu:e} m/s², GPS NED {worst:?} m");

    // what the plant was given: the on-board commands at the protocol's resolution
    let control: Vec<Vec<f64>> = (0..4)
        .map(|i| log.f64s("control", &format!("command[{i}]")))
        .collect();
    for (k, u) in r.received.iter().enumerate() {
        for i in 0..4 {
            assert!((u[i] - control[i][k]).abs() <= SERVO_M, "servo {k} {i}");
        }
    }

    // tracking: within 1 % of helicon sim's RMS error (+1 mm/s, 1 mrad)
    for o in OUTPUTS {
        let (a, b) = (&r.summary.metrics[o], &flown.summary.metrics[o]);
        let tol = 0.01 * b.rms_error + 1e-3;
        eprintln!("{o}: rms sim {:.6} sitl {:.6}", b.rms_error, a.rms_error);
        assert!((a.rms_error - b.rms_error).abs() <= tol, "{o}");
        assert!((a.max_abs_error - b.max_abs_error).abs() <= 0.02 * b.max_abs_error + 1e-3);
    }
}

#[test]
fn the_onboard_log_has_every_control_step_at_400_hz() {
    let s = scenario("demo.toml", 4.0);
    let prepared = prepare(&s).unwrap();
    let r = sitl::run(&s, &prepared, &options("ulog")).unwrap();
    let log = Ulog::read(&r.ulog);
    let samples = log.u64s("control", "sample");
    let ts = log.u64s("control", "timestamp");
    assert_eq!(samples.len() as u64, r.onboard.steps);
    assert!(samples.iter().enumerate().all(|(i, s)| *s == i as u64));
    assert!(ts.windows(2).all(|w| w[1] > w[0]), "monotonic");
    let rate = (ts.len() - 1) as f64 / ((ts[ts.len() - 1] - ts[0]) as f64 * 1e-6);
    assert!((rate / 400.0 - 1.0).abs() < 1e-3, "{rate} Hz");
    // one timing and one servo record per step
    assert_eq!(log.u64s("timing", "sample").len() as u64, r.onboard.steps);
    assert_eq!(
        log.u64s("servo_output", "timestamp").len() as u64,
        r.onboard.steps
    );
    assert_eq!(r.onboard.log_dropped, 0);
    // armed at the start: one mode change, standby -> automatic
    assert_eq!(log.u8s("mode", "mode"), vec![2]);
    assert_eq!(log.texts_with("armed: disarmed -> auto").len(), 1);
}

/// Real time exercises the threads of the on-board program (sensor server,
/// receiver, control task on the clock, avionics-out, logger and their
/// rings); no figure here depends on the wall clock: the run ends, every
/// control step sent its servo frame, the log is complete and in order.
#[test]
fn a_real_time_run_uses_every_thread_and_logs_in_order() {
    let s = scenario("demo.toml", 1.0);
    let prepared = prepare(&s).unwrap();
    let mut o = options("realtime");
    o.speed = sitl::Speed::Realtime;
    o.realtime.sched_fifo = false;
    o.realtime.mlockall = false;
    let r = sitl::run(&s, &prepared, &o).unwrap();
    assert!(r.onboard.error.is_none(), "{:?}", r.onboard.error);
    assert!(r.onboard.steps > 0);
    assert_eq!(
        r.onboard.servo_frames,
        r.onboard.steps + r.onboard.watchdog_trips
    );
    let log = Ulog::read(&r.ulog);
    let t = log.u64s("timing", "timestamp");
    assert_eq!(t.len() as u64, r.onboard.steps);
    assert!(t.windows(2).all(|w| w[1] > w[0]), "monotonic");
    let samples = log.u64s("control", "sample");
    assert!(samples.windows(2).all(|w| w[1] == w[0] + 1));
    // log.csv's estimate columns: from the first on-board report on, every
    // row carries one (a period whose report had not come yet the newest
    // the link had), never the nine zeros of no report
    use helicon_sim::log_csv::{LOG_SCHEMA, LogSource, read_log_csv};
    let table = read_log_csv(&r.log_csv).unwrap();
    let cols: Vec<&[f64]> = LOG_SCHEMA
        .iter()
        .filter(|c| matches!(c.source, LogSource::Estimate(_)))
        .map(|c| table.column(c.name).unwrap())
        .collect();
    assert_eq!(cols.len(), 9);
    let none = |k: usize| cols.iter().all(|c| c[k] == 0.0);
    let first = (0..table.rows())
        .find(|&k| !none(k))
        .expect("no estimate logged");
    let missing = (first..table.rows()).filter(|&k| none(k)).count();
    assert_eq!(
        missing, 0,
        "{missing} rows without an estimate after row {first}"
    );
}
