//! The PX4 organisation's `px4-ulog` crate (an independent reader) reads
//! what this crate writes.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use helicon_ulog::messages::{Control, SensorImu, Timing};
use helicon_ulog::{FlightLog, FlushPolicy, LogInfo, LogRecord};
use px4_ulog::full_parser::{Completeness, SomeVec, read_file};

const RATE_HZ: f64 = 400.0;

fn control(k: u64) -> Control {
    let t_s = k as f64 / RATE_HZ;
    Control {
        timestamp: helicon_ulog::timestamp_us(t_s, "test").unwrap(),
        sample: k,
        t_s,
        ref_yaw_rad: 0.1,
        command: [0.5, -0.1, 0.2, k as f64 * 1e-3],
        saturated: [false, k % 7 == 0, false, true],
        estimate: [k as f64; 9],
        ..Default::default()
    }
}

#[test]
fn px4_ulog_reads_every_control_step_at_400_hz() {
    let dir = std::env::temp_dir().join(format!("helicon_ulog_px4_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("flight.ulg");
    let n = 4000u64; // 10 s at 400 Hz
    let mut log = FlightLog::create(&path, &LogInfo::default(), FlushPolicy::default()).unwrap();
    for k in 0..n {
        let c = control(k);
        log.write(&LogRecord::Imu(SensorImu {
            timestamp: c.timestamp,
            specific_force_body_m_s2: [0.0, 0.0, -9.81],
            ..Default::default()
        }))
        .unwrap();
        log.write(&LogRecord::Control(c)).unwrap();
        log.write(&LogRecord::Timing(Timing {
            timestamp: c.timestamp,
            sample: k,
            ..Default::default()
        }))
        .unwrap();
    }
    log.finish().unwrap();

    let parsed = read_file(path.to_str().unwrap()).unwrap();
    assert_eq!(parsed.completeness, Completeness::Complete);
    let control = &parsed.messages["control"][&px4_ulog::full_parser::MultiId::new(0)];
    let SomeVec::UInt64(ts) = &control["timestamp"] else {
        panic!("timestamp type")
    };
    let SomeVec::UInt64(samples) = &control["sample"] else {
        panic!("sample type")
    };
    // every control step present, in order
    assert_eq!(samples.len() as u64, n);
    assert!(samples.iter().enumerate().all(|(i, s)| *s == i as u64));
    // strictly monotonic timestamps
    assert!(ts.windows(2).all(|w| w[1] > w[0]));
    // 400 Hz ± 0.1 %
    let rate = (ts.len() - 1) as f64 / ((ts[ts.len() - 1] - ts[0]) as f64 * 1e-6);
    assert!((rate / RATE_HZ - 1.0).abs() < 1e-3, "rate {rate} Hz");
    // values bit for bit
    let SomeVec::Double(cmd3) = &control["command[3]"] else {
        panic!("command type")
    };
    assert!(cmd3.iter().enumerate().all(|(k, v)| *v == k as f64 * 1e-3));
    let SomeVec::Bool(sat1) = &control["saturated[1]"] else {
        panic!("saturated type")
    };
    assert!(sat1.iter().enumerate().all(|(k, v)| *v == (k % 7 == 0)));
    // trailing padding is not a field
    assert!(!control.keys().any(|k| k.starts_with("_padding")));
    std::fs::remove_dir_all(&dir).unwrap();
}
