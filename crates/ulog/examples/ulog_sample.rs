//! Writes the sample flight log the pyulog fixture is made from
//! (`crates/ulog/tests/fixtures/helicon_sample.ulg`): every topic of the
//! message set, information, parameters (and a change), text messages,
//! failsafe and mode events, a dropout. Deterministic: values from
//! arithmetic only (exactly rounded on every platform).
//!
//! `cargo run -p helicon-ulog --example ulog_sample -- OUT.ulg`

use helicon_ulog::messages::{
    Control, EstimatorBias, Excitation, FailsafeReason, FlightMode, HeliconGps, HeliconMag,
    ImuHealth, Mode, Navigation, RcInput, SensorImu, ServoOutput, Timing,
};
use helicon_ulog::{FlightLog, FlushPolicy, LogInfo, LogLevel, LogRecord, UlogWriter, WriteError};

/// Control steps in the sample (400 Hz: 0.15 s, more than one flush period).
pub const STEPS: u64 = 60;

fn f(k: u64, i: usize) -> f64 {
    let k = k as f64;
    let i = i as f64;
    (k * 0.37 - i * 1.9) / (i + 3.0)
}

/// The records of step `k` (timestamps 2500 µs apart, starting at 1 s).
pub fn step_records(k: u64) -> Vec<LogRecord> {
    let ts = 1_000_000 + 2500 * k;
    let t_s = ts as f64 * 1e-6;
    let mut v = vec![
        LogRecord::Imu(SensorImu {
            timestamp: ts,
            specific_force_body_m_s2: [f(k, 0), f(k, 1), -9.81 + f(k, 2) * 1e-3],
            gyro_body_rad_s: [f(k, 3) * 1e-2, -1e-300, 2.5e10],
        }),
        LogRecord::Control(Control {
            timestamp: ts,
            sample: k,
            t_s,
            ref_yaw_rad: 0.25,
            ref_vel_ned_m_s: [2.0, -0.5, 0.1],
            command: [f(k, 0), f(k, 1), f(k, 2), f(k, 3)],
            tracking_error: [f(k, 4), f(k, 5), f(k, 6), f(k, 7)],
            integral: [f(k, 8), f(k, 9), f(k, 10), f(k, 11)],
            estimate: std::array::from_fn(|i| f(k, i + 12)),
            measured: std::array::from_fn(|i| f(k, i + 21)),
            saturated: [k % 5 == 0, false, k % 3 == 0, true],
        }),
        LogRecord::Navigation(Navigation {
            timestamp: ts,
            position_ned_m: [f(k, 30), f(k, 31), -10.0],
            velocity_ned_m_s: [1.0, 0.0, f(k, 32)],
            attitude_rad: [0.01, -0.02, 1.5],
            position_sigma_m: [0.5, 0.5, 1.25],
            attitude_fix: k % 2 == 0,
            gps_fused: k % 80 == 0,
        }),
        LogRecord::Servo(ServoOutput {
            timestamp: ts,
            command: [f(k, 0), f(k, 1), f(k, 2), f(k, 3)],
            source: u8::from(k >= 50) * 2,
        }),
        LogRecord::Timing(Timing {
            timestamp: ts,
            sample: k,
            wakeup_jitter_us: 7 - (k % 15) as i32,
            compute_time_us: 180 + (k % 11) as u32,
            deadline_misses: (k / 40) as u32,
            log_dropped: 0,
        }),
    ];
    if k % 10 == 3 {
        v.push(LogRecord::Excitation(Excitation {
            timestamp: ts,
            offset: [f(k, 0) * 1e-2, 0.0, -f(k, 2) * 1e-2, 0.0],
            active: k < 40,
        }));
        v.push(LogRecord::ImuHealth(ImuHealth {
            timestamp: ts,
            vibration_rms_m_s2: f(k, 5),
            gravity_residual_m_s2: -f(k, 6) * 1e-2,
            peak_fraction: 0.125,
            flags: (k % 16) as u8,
        }));
        v.push(LogRecord::EstimatorBias(EstimatorBias {
            timestamp: ts,
            gyro_rad_s: [f(k, 1) * 1e-3, -2e-3, 1e-4],
            accel_m_s2: [0.05, f(k, 2) * 1e-2, -0.1],
            gyro_sigma_rad_s: [1e-3; 3],
            accel_sigma_m_s2: [0.02, 0.02, f(k, 3).abs()],
        }));
    }
    if k % 4 == 0 {
        v.push(LogRecord::Mag(HeliconMag {
            timestamp: ts,
            field_body: [0.153, 0.008, -0.438],
        }));
    }
    if k % 8 == 0 {
        let mut channels_us = [0u16; 16];
        for (i, c) in channels_us.iter_mut().take(8).enumerate() {
            *c = 1000 + (k as u16) * 3 + i as u16 * 100;
        }
        v.push(LogRecord::Rc(RcInput {
            timestamp: ts,
            channels_us,
            channel_count: 8,
            manual_switch: k >= 48,
            signal_lost: false,
        }));
    }
    if k % 20 == 10 {
        v.push(LogRecord::Gps(HeliconGps {
            timestamp: ts,
            epoch_s: t_s - 0.05,
            position_ned_m: [f(k, 40), f(k, 41), -10.0],
            velocity_ned_m_s: if k == 30 { [0.0; 3] } else { [1.0, 0.0, 0.0] },
            fix_type: 3,
            velocity_valid: k != 30,
        }));
    }
    if k == 50 {
        v.push(LogRecord::Failsafe(helicon_ulog::messages::Failsafe {
            timestamp: ts,
            reason: FailsafeReason::RcLoss as u8,
            active: true,
        }));
        v.push(LogRecord::Mode(Mode {
            timestamp: ts,
            mode: FlightMode::Failsafe as u8,
            previous: FlightMode::Automatic as u8,
        }));
    }
    v
}

/// The sample log's bytes.
pub fn build() -> Result<Vec<u8>, WriteError> {
    let info = LogInfo {
        sys_name: "helicon".to_string(),
        ver_sw: "fixture".to_string(),
        time_ref_utc_s: Some(3600),
        start_us: 1_000_000,
        ..LogInfo::default()
    };
    let mut w = UlogWriter::new(Vec::new(), info.start_us, FlushPolicy::default())?;
    w.info_str("sys_name", &info.sys_name)?;
    w.info_str("ver_sw", &info.ver_sw)?;
    w.info_i32("time_ref_utc", 3600)?;
    w.info_u32("ver_hw_subtype", 7)?;
    w.parameter_f32("CTRL_DT", 0.0025)?;
    w.parameter_i32("LOG_RATE", 400)?;
    let mut log = FlightLog::from_writer(w)?;
    for k in 0..STEPS {
        for r in step_records(k) {
            log.write(&r)?;
        }
        if k == 20 {
            let w = log.writer_mut();
            w.log(LogLevel::Warning, 1_050_000, "gps: 5 satellites")?;
            w.parameter_f32("CTRL_DT", 0.005)?;
            w.dropout(12, 1_050_000)?;
        }
    }
    log.finish()
}

#[allow(dead_code)] // also compiled into the tests as a module
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .ok_or("usage: ulog_sample OUT.ulg")?;
    std::fs::write(&out, build()?)?;
    Ok(())
}
