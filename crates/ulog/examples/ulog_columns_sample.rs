//! Writes the flight log of the columns fixture
//! (`crates/ulog/tests/fixtures/columns_sample.ulg`): 240 control steps at
//! 400 Hz whose timestamps jitter (up to ±120 µs, steps within ±230 µs of the period, inside the 250 µs
//! tolerance), three control samples dropped after step 100, the
//! `excitation` and `servo_output` records stamped 4.7 ms after their control step (on the step's clock, as under real time), the
//! `imu_health` records starting at step 7, the `servo_output` records
//! (source 0). `tools/gen_ulog_fixtures.py --columns` reads it with pyulog
//! and applies the rule of `helicon_ulog::columns` independently.
//! Deterministic: values from arithmetic only.
//!
//! `cargo run -p helicon-ulog --example ulog_columns_sample -- OUT.ulg`

use helicon_ulog::messages::{Control, Excitation, ImuHealth, ServoOutput};
use helicon_ulog::{FlightLog, FlushPolicy, LogInfo, LogRecord};

/// Control steps in the sample.
const STEPS: u64 = 240;

fn f(k: u64, i: usize) -> f64 {
    let k = k as f64;
    let i = i as f64;
    ((k * 0.37 + i).sin() * 0.1) / (i + 1.0)
}

/// Jitter of step k, µs: a fixed pattern within ±120 µs.
fn jitter_us(k: u64) -> i64 {
    [0, 120, -100, 110, -120, 60, -30, 100][(k % 8) as usize]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .ok_or("usage: ulog_columns_sample OUT.ulg")?;
    let info = LogInfo {
        start_us: 900_000,
        ..LogInfo::default()
    };
    let mut log = FlightLog::create(std::path::Path::new(&out), &info, FlushPolicy::default())?;
    for k in 0..STEPS {
        if (101..104).contains(&k) {
            continue; // dropped
        }
        let ts = u64::try_from(1_000_000 + 2500 * i64::try_from(k)? + jitter_us(k))?;
        if k >= 7 {
            log.write(&LogRecord::ImuHealth(ImuHealth {
                timestamp: ts,
                vibration_rms_m_s2: 0.5 + f(k, 40),
                gravity_residual_m_s2: f(k, 41),
                peak_fraction: 0.1,
                flags: u8::from(k % 50 == 0),
            }))?;
        }
        log.write(&LogRecord::Control(Control {
            timestamp: ts,
            sample: k,
            t_s: ts as f64 * 1e-6,
            ref_yaw_rad: 0.25,
            ref_vel_ned_m_s: [2.0, -0.5, f(k, 3)],
            command: std::array::from_fn(|i| f(k, i)),
            tracking_error: [0.0; 4],
            integral: [0.0; 4],
            estimate: std::array::from_fn(|i| f(k, i + 12)),
            measured: std::array::from_fn(|i| f(k, i + 21)),
            saturated: [false; 4],
        }))?;
        log.write(&LogRecord::Excitation(Excitation {
            timestamp: ts + 4700,
            offset: std::array::from_fn(|i| f(k, i + 30)),
            active: k >= 20,
        }))?;
        log.write(&LogRecord::Servo(ServoOutput {
            timestamp: ts + 4700,
            command: std::array::from_fn(|i| f(k, i)),
            source: 0,
        }))?;
    }
    log.finish()?;
    Ok(())
}
