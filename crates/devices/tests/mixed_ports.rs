//! One port carrying two protocols, as real devices do: a u-blox receiver
//! with NMEA and UBX output enabled together, a VN-100 with its ASCII
//! asynchronous output and a binary output together. Each decoder reads the
//! same bytes and treats the other protocol as noise: every message of its
//! own is recovered, none invented.
#![allow(clippy::unwrap_used)] // test helpers: a failed unwrap is a failed test

use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample};
use helicon_devices::*;
use nalgebra::Vector3;

#[test]
fn a_ublox_port_with_nmea_and_ubx() {
    let home = LocalNed::new(Geodetic::new(57.0147, 9.9859, 30.0).unwrap());
    let mut bytes = Vec::new();
    let (mut pvts, mut sentences) = (Vec::new(), 0);
    for k in 0..500 {
        let t = f64::from(k) * 0.2;
        let fix = GpsFix {
            epoch_s: t,
            fix: GpsFixType::Fix3d,
            position_ned_m: Vector3::new(3.0 * t, -2.0 * t, -10.0 - 0.1 * t),
            velocity_ned_m_s: Some(Vector3::new(3.0, -2.0, -0.1)),
        };
        let pvt = NavPvt::from_gps_fix(&fix, &home, 200 * k, 42.0).unwrap();
        bytes.extend_from_slice(pvt.encode().as_bytes());
        pvts.push(pvt);
        for m in nmea0183::sentences_from_fix(&fix, &home, 3600.0 + t, 42.0).unwrap() {
            bytes.extend_from_slice(m.encode().unwrap().as_bytes());
            sentences += 1;
        }
    }
    let mut ubx = UbxDecoder::new();
    let mut nmea = NmeaDecoder::new();
    let mut got_pvt = Vec::new();
    let mut got_nmea = 0;
    for chunk in bytes.chunks(37) {
        got_pvt.extend(ubx.push(chunk));
        got_nmea += nmea.push(chunk).count();
    }
    assert_eq!(got_pvt, pvts);
    assert_eq!(got_nmea, sentences);
    assert_eq!(ubx.stats().checksum_failures, 0);
    println!(
        "UBX decoder {:?}\nNMEA decoder {:?}",
        ubx.stats(),
        nmea.stats()
    );
}

#[test]
fn a_vn100_port_with_ascii_and_binary() {
    let mut bytes = Vec::new();
    let (mut bins, mut ymrs) = (Vec::new(), Vec::new());
    for k in 0..1000u32 {
        let x = f64::from(k) * 1e-3;
        let imu = ImuSample {
            specific_force_body_m_s2: Vector3::new(x.sin(), x.cos(), -9.82 + x),
            gyro_body_rad_s: Vector3::new(0.1 * x, -0.2 * x, 0.3),
        };
        let mag = Vector3::new(0.153, 0.008 + x, -0.438);
        let bin = VnCommon::from_samples(x, &imu, Some(&mag)).unwrap();
        bytes.extend_from_slice(bin.encode().unwrap().as_bytes());
        bins.push(bin);
        if k % 4 == 0 {
            let ymr = VnYmr {
                yaw_pitch_roll_deg: [12.5, -3.25, f64::from(k % 360)],
                mag_gauss: [0.153, 0.008, -0.438],
                accel_m_s2: [0.1, -0.2, -9.81],
                angular_rate_rad_s: [0.001, -0.002, 0.003],
            };
            bytes.extend_from_slice(ymr.encode().unwrap().as_bytes());
            ymrs.push(ymr);
        }
    }
    let mut bin_dec = VnBinaryDecoder::new();
    let mut ascii_dec = VnAsciiDecoder::new();
    let (mut got_bin, mut got_ymr) = (Vec::new(), Vec::new());
    for chunk in bytes.chunks(50) {
        got_bin.extend(bin_dec.push(chunk));
        got_ymr.extend(ascii_dec.push(chunk));
    }
    assert_eq!(got_bin, bins);
    assert_eq!(got_ymr, ymrs);
    println!(
        "binary decoder {:?}\nASCII decoder {:?}",
        bin_dec.stats(),
        ascii_dec.stats()
    );
}
