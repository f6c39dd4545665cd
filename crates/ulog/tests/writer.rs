//! The writer: records round trip through helicon's reader, the flush
//! policy bounds what a crash can lose, no allocation per record, misuse
//! and bad times are typed errors.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use helicon_test_support::allocations;

#[global_allocator]
static ALLOC: helicon_test_support::Counting = helicon_test_support::Counting;

use helicon_core::computer::Telemetry;
use helicon_core::lqi::Reference;
use helicon_core::navigation::NavigationSolution;
use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample, SensorFrame};
use helicon_ulog::messages::{
    Control, Failsafe, FailsafeReason, FlightMode, HeliconGps, Mode, Navigation, SensorImu, Timing,
};
use helicon_ulog::reader::{Message, UlogReader};
use helicon_ulog::{
    FlightLog, FlushPolicy, LogInfo, LogLevel, LogRecord, Record, UlogWriter, WriteError,
    timestamp_us,
};
use nalgebra::{SVector, Vector3};

fn telemetry(k: u64) -> Telemetry {
    let t_s = k as f64 * 0.0025;
    Telemetry {
        sample: k,
        t_s,
        reference: Reference {
            velocity_ned_m_s: Vector3::new(1.0, 2.0, 3.0),
            yaw_rad: 0.5,
        },
        command: SVector::from([0.1, 0.2, 0.3, 0.4]),
        saturated: [true, false, true, false],
        tracking_error: SVector::from([1.0, 2.0, 3.0, 4.0]),
        integral: SVector::from([5.0, 6.0, 7.0, 8.0]),
        estimate: SVector::from_fn(|i, _| i as f64 + t_s),
        measured: SVector::from_fn(|i, _| -(i as f64)),
        navigation: Some(NavigationSolution {
            position_ned_m: Vector3::new(10.0, 20.0, -30.0),
            velocity_ned_m_s: Vector3::new(1.0, 0.5, 0.0),
            attitude_rad: Vector3::new(0.01, 0.02, 0.03),
            position_sigma_m: Vector3::new(0.4, 0.4, 0.9),
            attitude_fix: true,
            gps_fused: k % 80 == 0,
            imu_bias: None,
            rejected_updates: 0,
        }),
    }
}

fn frame(k: u64) -> SensorFrame {
    let t_s = k as f64 * 0.0025;
    SensorFrame {
        t_s,
        imu: ImuSample {
            specific_force_body_m_s2: Vector3::new(0.1, -0.2, -9.8),
            gyro_body_rad_s: Vector3::new(0.01, 0.02, -0.03),
        },
        mag_body: (k % 4 == 0).then(|| Vector3::new(0.15, 0.0, -0.44)),
        gps: (k % 80 == 0).then(|| GpsFix {
            epoch_s: t_s - 0.05,
            fix: GpsFixType::Fix3d,
            position_ned_m: Vector3::new(1.0, 2.0, -3.0),
            velocity_ned_m_s: (k % 160 == 0).then(|| Vector3::new(0.5, 0.0, 0.1)),
        }),
    }
}

/// Every record written, in order, decoded back from the bytes.
fn control_records(bytes: &[u8]) -> Vec<Control> {
    let mut r = UlogReader::new(bytes, "test").unwrap();
    let mut ids = std::collections::HashMap::new();
    let mut out = Vec::new();
    while let Ok(Some(m)) = r.next_message() {
        match m {
            Message::AddLogged { msg_id, name, .. } => {
                ids.insert(msg_id, name);
            }
            Message::Data { msg_id, payload } if ids[&msg_id] == "control" => {
                out.push(Control::decode(payload).unwrap());
            }
            _ => {}
        }
    }
    out
}

#[test]
fn telemetry_and_frames_round_trip() {
    let mut log = FlightLog::new(Vec::new(), &LogInfo::default(), FlushPolicy::default()).unwrap();
    for k in 0..400 {
        log.log_frame(&frame(k)).unwrap();
        log.log_telemetry(&telemetry(k)).unwrap();
    }
    let bytes = log.finish().unwrap();
    let controls = control_records(&bytes);
    assert_eq!(controls.len(), 400);
    for (k, c) in controls.iter().enumerate() {
        let t = telemetry(k as u64);
        assert_eq!(*c, Control::from_telemetry(&t).unwrap());
        assert_eq!(c.sample, k as u64);
        assert_eq!(c.timestamp, 2500 * k as u64);
        assert_eq!(c.t_s.to_bits(), t.t_s.to_bits());
        assert_eq!(c.ref_vel_ned_m_s, [1.0, 2.0, 3.0]);
        assert_eq!(c.ref_yaw_rad, 0.5);
        assert_eq!(c.command, [0.1, 0.2, 0.3, 0.4]);
        assert_eq!(c.saturated, [true, false, true, false]);
        assert_eq!(c.integral, [5.0, 6.0, 7.0, 8.0]);
        // the estimate's first nine reduced states are the measured ones
        assert_eq!(c.estimate[8], 8.0 + t.t_s);
        assert_eq!(c.measured[8], -8.0);
    }
    let n = Navigation::from_solution(1.0, &telemetry(0).navigation.unwrap()).unwrap();
    assert_eq!(n.position_ned_m, [10.0, 20.0, -30.0]);
    assert!(n.attitude_fix);
    // GPS records carry the fix back
    let f = frame(160);
    let g = HeliconGps::from_fix(f.t_s, f.gps.as_ref().unwrap()).unwrap();
    assert_eq!(g.to_fix(), f.gps);
    assert_eq!(g.fix_type, 3);
    let g2 = HeliconGps::from_fix(0.2, frame(80).gps.as_ref().unwrap()).unwrap();
    assert!(!g2.velocity_valid);
    assert_eq!(g2.to_fix(), frame(80).gps);
}

#[test]
fn logging_records_allocates_nothing() {
    // with a home and a control period: the PX4 view's geodetic topics and
    // dropouts are written too
    let info = LogInfo {
        home: Some(helicon_devices::Geodetic::new(57.0146, 9.9869, 20.0).unwrap()),
        control_period_us: Some(2500),
        ..LogInfo::default()
    };
    let mut log = FlightLog::new(std::io::sink(), &info, FlushPolicy::default()).unwrap();
    // warm-up: the first flush
    log.log_frame(&frame(0)).unwrap();
    log.log_telemetry(&telemetry(0)).unwrap();
    let before = allocations();
    for k in 1..4000 {
        log.log_frame(&frame(k)).unwrap();
        log.log_telemetry(&telemetry(k)).unwrap();
        let ts = 2500 * k;
        log.write(&LogRecord::Timing(Timing {
            timestamp: ts,
            sample: k,
            ..Default::default()
        }))
        .unwrap();
        if k % 500 == 0 {
            log.write(&LogRecord::Failsafe(Failsafe {
                timestamp: ts,
                reason: FailsafeReason::DeadlineMiss as u8,
                active: true,
            }))
            .unwrap();
            log.write(&LogRecord::Mode(Mode {
                timestamp: ts,
                mode: FlightMode::Manual as u8,
                previous: FlightMode::Automatic as u8,
            }))
            .unwrap();
            log.writer_mut()
                .log(LogLevel::Info, ts, "a text message")
                .unwrap();
            log.writer_mut().dropout(3, ts).unwrap();
        }
    }
    assert_eq!(allocations() - before, 0, "allocations while logging");
    let stats = log.writer_mut().stats();
    assert!(stats.flushes >= 100, "{stats:?}"); // 10 s of log at ≤ 0.1 s per flush
}

/// After every record, the output holds every control step older than the
/// flush interval: a process killed at any point loses at most 0.1 s.
#[test]
fn flush_policy_bounds_the_loss_to_a_tenth_of_a_second() {
    let mut log = FlightLog::new(Vec::new(), &LogInfo::default(), FlushPolicy::default()).unwrap();
    let mut max_unflushed = 0;
    for k in 0..1200u64 {
        log.log_frame(&frame(k)).unwrap();
        log.log_telemetry(&telemetry(k)).unwrap();
        let w = log.writer_mut();
        let on_disk = w.get_ref().len();
        if k % 10 == 0 || k > 1100 {
            let flushed = control_records(&w.get_ref()[..on_disk]).len() as u64;
            max_unflushed = max_unflushed.max(k + 1 - flushed);
        }
    }
    eprintln!("largest backlog: {max_unflushed} control steps");
    // 0.1 s at 400 Hz = 40 steps; at ~490 bytes a step the 16 KiB bound
    // comes first, after 33 steps
    assert!(max_unflushed <= 40, "{max_unflushed} steps buffered");
    assert!(
        max_unflushed >= 30,
        "{max_unflushed}: flushing more often than the policy says"
    );

    // the byte bound: records all at one time stamp
    let policy = FlushPolicy {
        interval_us: u64::MAX,
        max_bytes: 4096,
        sync_each_flush: false,
    };
    let mut w = UlogWriter::new(Vec::new(), 0, policy).unwrap();
    w.add_format::<Control>().unwrap();
    let topic = w.add_logged::<Control>(0).unwrap();
    for k in 0..200 {
        w.write(
            topic,
            &Control {
                sample: k,
                ..Default::default()
            },
        )
        .unwrap();
        assert!(
            w.buffered_bytes() < 4096,
            "{} bytes buffered",
            w.buffered_bytes()
        );
        assert_eq!(w.get_ref().len() as u64, w.stats().bytes_flushed);
    }
    let n = control_records(w.get_ref()).len();
    assert!(
        (180..200).contains(&n),
        "{n} of 200 flushed by the 4 KiB bound"
    );
}

#[test]
fn misuse_is_a_typed_error() {
    let mut w = UlogWriter::new(Vec::new(), 0, FlushPolicy::default()).unwrap();
    assert!(matches!(
        w.add_logged::<Control>(0),
        Err(WriteError::UnknownFormat { .. })
    ));
    w.add_format::<Control>().unwrap();
    w.add_format::<Control>().unwrap(); // the same type again: no-op
    assert!(matches!(
        w.info_str("bad key", "x"),
        Err(WriteError::Invalid { .. })
    ));
    assert!(matches!(
        w.parameter_f32("", 1.0),
        Err(WriteError::Invalid { .. })
    ));
    let c = w.add_logged::<Control>(0).unwrap();
    assert!(matches!(
        w.add_logged::<Control>(0),
        Err(WriteError::Duplicate { .. })
    ));
    let c1 = w.add_logged::<Control>(1).unwrap();
    assert_eq!((c.msg_id(), c1.msg_id(), c1.multi_id()), (0, 1, 1));
    let e = w.add_format::<SensorImu>().unwrap_err();
    assert!(matches!(e, WriteError::DefinitionsClosed { .. }));
    assert!(e.to_string().contains("sensor_imu"), "{e}");
    // parameters and information may change in the data section
    w.parameter_i32("LOG_RATE", 200).unwrap();
    w.info_str("note", "in flight").unwrap();
    // a handle of another writer
    let mut other = UlogWriter::new(Vec::new(), 0, FlushPolicy::default()).unwrap();
    other.add_format::<Timing>().unwrap();
    let t = other.add_logged::<Timing>(0).unwrap();
    assert!(matches!(
        w.write(t, &Timing::default()),
        Err(WriteError::UnknownTopic { .. })
    ));
    // a text longer than a message holds is cut, not refused
    let long = "é".repeat(40_000);
    w.log(LogLevel::Debug, 0, &long).unwrap();
    let bytes = w.finish().unwrap();
    let mut r = UlogReader::new(&bytes[..], "t").unwrap();
    let mut text_len = 0;
    while let Some(m) = r.next_message().unwrap() {
        if let Message::Logging { text, .. } = m {
            text_len = text.len();
        }
    }
    assert!(text_len > 65_000 && text_len <= 65_535 - 9, "{text_len}");
}

#[test]
fn an_oversized_buffer_is_refused() {
    let policy = FlushPolicy {
        max_bytes: usize::MAX,
        ..FlushPolicy::default()
    };
    let e = UlogWriter::new(Vec::new(), 0, policy).unwrap_err();
    assert!(e.to_string().contains("max_bytes"), "{e}");
    let ok = FlushPolicy {
        max_bytes: helicon_ulog::writer::MAX_FLUSH_BYTES,
        ..FlushPolicy::default()
    };
    assert!(UlogWriter::new(Vec::new(), 0, ok).is_ok());
}

#[test]
fn bad_times_are_refused() {
    for t in [f64::NAN, f64::INFINITY, -1e-3, 1e20] {
        let e = timestamp_us(t, "control").unwrap_err();
        assert!(matches!(e, WriteError::BadTime { .. }), "{t}");
        assert!(e.to_string().contains("control"));
    }
    assert_eq!(timestamp_us(0.0025 * 3.0, "x").unwrap(), 7500);
    assert_eq!(timestamp_us(0.0, "x").unwrap(), 0);
    let mut t = telemetry(1);
    t.t_s = f64::NAN;
    assert!(Control::from_telemetry(&t).is_err());
    let f = SensorFrame {
        t_s: -1.0,
        ..frame(0)
    };
    assert!(helicon_ulog::messages::frame_records(&f).is_err());
}

#[test]
fn io_errors_name_the_file() {
    let e = UlogWriter::create(
        std::path::Path::new("/nonexistent-dir/x.ulg"),
        0,
        FlushPolicy::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("/nonexistent-dir/x.ulg"), "{e}");
    assert!(e.to_string().contains("create"), "{e}");
}

/// `write` adds a text message for failsafe and mode events, `write_data`
/// does not.
#[test]
fn events_as_text_or_data_only() {
    let texts = |data_only: bool| {
        let mut log =
            FlightLog::new(Vec::new(), &LogInfo::default(), FlushPolicy::default()).unwrap();
        let ev = [
            LogRecord::Failsafe(Failsafe {
                timestamp: 10,
                reason: FailsafeReason::RcLoss as u8,
                active: true,
            }),
            LogRecord::Mode(Mode {
                timestamp: 10,
                mode: FlightMode::Failsafe as u8,
                previous: 99, // an unknown code is named `unknown`
            }),
        ];
        for e in &ev {
            if data_only {
                log.write_data(e).unwrap();
            } else {
                log.write(e).unwrap();
            }
        }
        let bytes = log.finish().unwrap();
        let mut r = UlogReader::new(&bytes[..], "t").unwrap();
        let (mut texts, mut data) = (Vec::new(), 0);
        while let Some(m) = r.next_message().unwrap() {
            match m {
                Message::Logging { text, level, .. } => texts.push((level.unwrap(), text)),
                Message::Data { .. } => data += 1,
                _ => {}
            }
        }
        // failsafe, mode, and the mode's PX4 vehicle_status
        assert_eq!(data, 3);
        texts
    };
    assert_eq!(
        texts(false),
        vec![
            (
                LogLevel::Critical,
                "failsafe raised: RC signal lost".to_string()
            ),
            (LogLevel::Info, "mode: unknown -> failsafe".to_string()),
        ]
    );
    assert!(texts(true).is_empty());
}
