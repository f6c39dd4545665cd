//! Decoding and encoding allocate nothing in steady state: counted with the
//! workspace's wrapping global allocator (this test binary only).
#![allow(clippy::unwrap_used)] // test helpers: a failed unwrap is a failed test

use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample};
use helicon_devices::framing::Protocol;
use helicon_devices::*;
use nalgebra::{Vector3, Vector4};

use helicon_test_support::allocations;

#[global_allocator]
static ALLOC: helicon_test_support::Counting = helicon_test_support::Counting;

/// Decodes `stream` in 64-byte chunks; returns (messages, allocations).
fn decode_counting<P: Protocol>(stream: &[u8]) -> (usize, usize) {
    let mut d = StreamDecoder::<P>::new();
    let before = allocations();
    let mut n = 0;
    for chunk in stream.chunks(64) {
        n += d.push(chunk).count();
    }
    (n, allocations() - before)
}

#[test]
fn decoders_and_encoders_do_not_allocate() {
    let imu = ImuSample {
        specific_force_body_m_s2: Vector3::new(0.1, -0.2, -9.82),
        gyro_body_rad_s: Vector3::new(0.01, 0.02, -0.03),
    };
    let mag = Vector3::new(0.153, 0.008, -0.438);
    let home = LocalNed::new(Geodetic::new(57.0, 9.9, 30.0).unwrap());
    let fix = GpsFix {
        epoch_s: 1.0,
        fix: GpsFixType::Fix3d,
        position_ned_m: Vector3::new(10.0, 20.0, -30.0),
        velocity_ned_m_s: Some(Vector3::new(1.0, 2.0, 0.1)),
    };
    let u = Vector4::new(0.18, 0.0, 0.1, 0.3);

    // the counter counts
    let before = allocations();
    std::hint::black_box(Vec::<u8>::with_capacity(16));
    assert_eq!(allocations() - before, 1);

    // encoders
    let before = allocations();
    let vn = VnCommon::from_samples(1.0, &imu, Some(&mag))
        .unwrap()
        .encode()
        .unwrap();
    let ymr = VnYmr {
        yaw_pitch_roll_deg: [1.0, 2.0, 3.0],
        mag_gauss: [0.1, 0.2, 0.3],
        accel_m_s2: [0.0, 0.0, -9.8],
        angular_rate_rad_s: [0.0; 3],
    }
    .encode()
    .unwrap();
    let pvt = NavPvt::from_gps_fix(&fix, &home, 0, 40.0).unwrap().encode();
    let sentences = nmea0183::sentences_from_fix(&fix, &home, 3600.0, 40.0).unwrap();
    let nmea = sentences.map(|m| m.encode().unwrap());
    let servo = ServoCommand::from_inputs(1, true, &u).unwrap().encode();
    let rc = RcInput::default().with_applied(&u).unwrap().encode();
    assert_eq!(allocations() - before, 0, "encoders allocated");

    let repeat = |f: &[u8]| -> Vec<u8> { f.iter().copied().cycle().take(f.len() * 200).collect() };
    let mut nmea_stream = Vec::new();
    for _ in 0..200 {
        for s in &nmea {
            nmea_stream.extend_from_slice(s.as_bytes());
        }
    }
    let cases = [
        (
            "VN-100 binary",
            decode_counting::<vectornav::VnBinary>(&repeat(vn.as_bytes())),
        ),
        (
            "VNYMR",
            decode_counting::<vectornav::VnAscii>(&repeat(ymr.as_bytes())),
        ),
        (
            "NAV-PVT",
            decode_counting::<ubx::Ubx>(&repeat(pvt.as_bytes())),
        ),
        ("NMEA", decode_counting::<nmea0183::Nmea>(&nmea_stream)),
        (
            "servo",
            decode_counting::<avionics::Avionics>(&repeat(servo.as_bytes())),
        ),
        (
            "RC",
            decode_counting::<avionics::Avionics>(&repeat(rc.as_bytes())),
        ),
    ];
    for (name, (messages, allocs)) in cases {
        let want = if name == "NMEA" { 600 } else { 200 };
        assert_eq!(messages, want, "{name}");
        assert_eq!(allocs, 0, "{name} decoding allocated");
    }
    // the conversions
    let before = allocations();
    let p = NavPvt::from_gps_fix(&fix, &home, 0, 40.0).unwrap();
    let _ = black_box_fix(p.to_gps_fix(&home, 1.0));
    assert_eq!(allocations() - before, 0);

    // a serial link's try_write, queued or dropped (a pty nobody reads,
    // filled), allocates nothing
    let pty = PtyPair::open().unwrap();
    let mut link = SerialLink::open(
        pty.slave_path(),
        115_200,
        std::time::Duration::from_millis(1),
    )
    .unwrap();
    let frame = ServoCommand::from_inputs(1, true, &u).unwrap().encode();
    let before = allocations();
    let (mut queued, mut dropped) = (0, 0);
    for _ in 0..5000 {
        match link.try_write(frame.as_bytes()).unwrap() {
            Written::All => queued += 1,
            Written::Dropped { .. } => dropped += 1,
        }
    }
    assert_eq!(allocations() - before, 0, "try_write allocated");
    assert!(
        queued > 0 && dropped > 0,
        "{queued} queued, {dropped} dropped"
    );
}

fn black_box_fix(f: GpsFix) -> GpsFix {
    std::hint::black_box(f)
}

/// A serial link's look at an idle line, its read of a frame and its write
/// allocate nothing (a lock-step SITL polls its lines many times a sample;
/// the `serialport` crate's own read allocated a formatted error for each
/// look that found nothing).
#[test]
fn serial_link_looks_reads_and_writes_allocate_nothing() {
    use std::io::Write;
    use std::time::Duration;
    let mut pty = PtyPair::open().unwrap();
    let mut link = SerialLink::open(pty.slave_path(), 115_200, Duration::ZERO).unwrap();
    let mut buf = [0u8; 64];
    let frame = ServoCommand::from_inputs(1, true, &Vector4::new(0.1, 0.0, 0.0, 0.2))
        .unwrap()
        .encode();
    // warm up (the first calls may set up thread-local state)
    assert_eq!(link.read_chunk(&mut buf).unwrap(), 0);
    let before = allocations();
    for _ in 0..100 {
        assert_eq!(link.read_chunk(&mut buf).unwrap(), 0);
        assert_eq!(link.read_timeout(&mut buf, Duration::ZERO).unwrap(), 0);
    }
    assert_eq!(allocations() - before, 0, "looks at an idle line allocated");
    pty.master().write_all(frame.as_bytes()).unwrap();
    assert!(pty.wait_delivered(Duration::from_secs(1)).unwrap());
    let before = allocations();
    let n = link.read_timeout(&mut buf, Duration::from_secs(1)).unwrap();
    assert_eq!(link.try_write(frame.as_bytes()).unwrap(), Written::All);
    assert_eq!(allocations() - before, 0, "a read and a write allocated");
    assert_eq!(&buf[..n], frame.as_bytes());
}
