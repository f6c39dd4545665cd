//! Bad inputs give errors naming the field or the device, never a panic;
//! the stale detector; the pseudo-terminal is 8-bit clean.
#![allow(clippy::unwrap_used)] // test helpers: a failed unwrap is a failed test

use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample};
use helicon_devices::*;
use nalgebra::{Vector3, Vector4};
use std::path::Path;
use std::time::{Duration, Instant};

#[test]
fn encoders_name_the_bad_field() {
    let imu = ImuSample {
        specific_force_body_m_s2: Vector3::new(0.0, f64::NAN, -9.8),
        gyro_body_rad_s: Vector3::zeros(),
    };
    let e = VnCommon::from_samples(0.0, &imu, None).unwrap_err();
    assert!(e.to_string().contains("acceleration"), "{e}");

    let e = ServoCommand::from_inputs(0, true, &Vector4::new(0.1, 0.2, 4.0, 0.0)).unwrap_err();
    assert!(e.to_string().contains("S_lon"), "{e}");
    let e = ServoCommand::from_inputs(0, true, &Vector4::new(0.1, f64::INFINITY, 0.0, 0.0))
        .unwrap_err();
    assert!(e.to_string().contains("S_lat"), "{e}");

    let home = LocalNed::new(Geodetic::new(57.0, 9.9, 30.0).unwrap());
    let fix = GpsFix {
        epoch_s: 0.0,
        fix: GpsFixType::Fix3d,
        position_ned_m: Vector3::zeros(),
        velocity_ned_m_s: Some(Vector3::new(0.0, f64::NAN, 0.0)),
    };
    let e = NavPvt::from_gps_fix(&fix, &home, 0, 40.0).unwrap_err();
    assert!(e.to_string().contains("GPS velocity"), "{e}");
    let e = Geodetic::new(91.0, 0.0, 0.0).unwrap_err();
    assert!(e.to_string().contains("latitude_deg"), "{e}");
    let e = Gga {
        utc_time_s: Some(90_000.0),
        latitude_deg: None,
        longitude_deg: None,
        quality: 0,
        satellites: None,
        hdop: None,
        altitude_msl_m: None,
        geoid_separation_m: None,
    }
    .encode()
    .unwrap_err();
    assert!(e.to_string().contains("utc_time_s"), "{e}");
    assert!(VnCommon::default().encode().is_err());
}

#[test]
fn a_missing_serial_port_is_an_error_naming_it() {
    let e = SerialLink::open(
        Path::new("/dev/helicon-no-such-port"),
        115_200,
        Duration::from_millis(10),
    )
    .unwrap_err();
    assert!(e.to_string().contains("/dev/helicon-no-such-port"), "{e}");
}

#[test]
fn stale_detector() {
    assert!(StaleDetector::new(0.0).is_err());
    assert!(StaleDetector::new(f64::NAN).is_err());
    let mut s = StaleDetector::new(0.05).unwrap();
    assert!(s.is_stale(0.0), "never seen is stale");
    s.seen(1.0);
    assert!(!s.is_stale(1.04));
    assert!(s.is_stale(1.0501));
    assert_eq!(s.age_s(0.5), Some(0.0), "a clock going backwards is age 0");
    s.seen(f64::NAN); // ignored
    assert_eq!(s.age_s(1.5), Some(0.5));
    assert!(s.is_stale(f64::INFINITY));
}

#[test]
fn the_pty_is_eight_bit_clean_and_raw() {
    let mut pty = PtyPair::open().unwrap();
    let mut link = SerialLink::open(pty.slave_path(), 921_600, Duration::from_millis(20)).unwrap();
    // every byte value, including ^C, ^S, ^Q, CR, LF, DEL and 0xFF
    let all: Vec<u8> = (0..=255u8).chain((0..=255u8).rev()).collect();
    pty.write_all(&all).unwrap();
    let mut got = Vec::new();
    let mut buf = [0u8; 128];
    let deadline = Instant::now() + Duration::from_secs(5);
    while got.len() < all.len() && Instant::now() < deadline {
        let n = link.read_chunk(&mut buf).unwrap();
        got.extend_from_slice(&buf[..n]);
    }
    assert_eq!(got, all);
    // and the other way, nothing echoed back to the writer
    link.write_all(&all).unwrap();
    let mut back = Vec::new();
    while back.len() < all.len() && Instant::now() < deadline {
        let n = pty
            .read_timeout(&mut buf, Duration::from_millis(20))
            .unwrap();
        back.extend_from_slice(&buf[..n]);
    }
    assert_eq!(back, all);
    assert_eq!(link.read_chunk(&mut buf).unwrap(), 0, "no echo");
}

#[test]
fn decoder_statistics_count_what_was_rejected() {
    let frame = ServoCommand {
        seq: 1,
        armed: true,
        throttle_hold: false,
        servo_counts: [1, 2, 3, 4],
    }
    .encode();
    let mut bad = frame.as_bytes().to_vec();
    bad[7] ^= 0x01;
    let mut d = AvionicsDecoder::new();
    let mut stream = b"noise".to_vec();
    stream.extend(&bad);
    stream.extend(frame.as_bytes());
    stream.extend([0xA5, 0x5A, 0xFF]); // a length beyond any frame
    stream.extend(frame.as_bytes());
    assert_eq!(d.push(&stream).count(), 2);
    let s = d.stats();
    assert_eq!(s.bytes, stream.len() as u64);
    assert_eq!((s.messages, s.checksum_failures, s.oversize), (2, 1, 1));
    assert_eq!(s.discarded_bytes, 5 + bad.len() as u64 + 3);
    // a partial frame is kept across pushes, an abandoned iterator counts unread
    let mut d = AvionicsDecoder::new();
    let mut two = frame.as_bytes().to_vec();
    two.extend(frame.as_bytes());
    drop(d.push(&two));
    assert_eq!((d.stats().messages, d.stats().unread), (2, 2));

    // a false start declaring the longest frame does not delay a real one:
    // it comes out as soon as its last byte is in
    let mut d = AvionicsDecoder::new();
    let mut stream = vec![0xA5, 0x5A, 26, 0x02, 0x00];
    stream.extend(frame.as_bytes());
    assert_eq!(d.push(&stream).count(), 1);
    assert_eq!((d.stats().discarded_bytes, d.pending_bytes()), (5, 0));
}
