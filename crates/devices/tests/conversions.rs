//! The conversions to and from the flight software's types lose only what
//! each protocol's quantisation loses (figures printed with --nocapture).
#![allow(clippy::unwrap_used)] // test helpers: a failed unwrap is a failed test

use helicon_core::sensor::{GpsFix, GpsFixType, ImuSample};
use helicon_devices::*;
use nalgebra::Vector3;

/// A deterministic spread of points: an LCG, no RNG crate needed.
fn points(n: usize) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let mut s: u64 = 0x2545_F491_4F6C_DD1D;
    let mut u = || {
        s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    (0..n)
        .map(|_| {
            let p = Vector3::new(2000.0 * u(), 2000.0 * u(), -100.0 + 100.0 * u());
            let v = Vector3::new(15.0 * u(), 15.0 * u(), 3.0 * u());
            (p, v)
        })
        .collect()
}

#[test]
fn nav_pvt_fix_round_trip_within_its_quanta() {
    // Aalborg, the thesis's flying field region; and a high latitude
    for (lat, lon) in [(57.0147, 9.9859), (78.2, 15.6)] {
        let home = LocalNed::new(Geodetic::new(lat, lon, 30.0).unwrap());
        let (mut dp, mut dv) = (Vector3::<f64>::zeros(), 0.0f64);
        for (p, v) in points(2000) {
            let fix = GpsFix {
                epoch_s: 1.0,
                fix: GpsFixType::Fix3d,
                position_ned_m: p,
                velocity_ned_m_s: Some(v),
            };
            let f = NavPvt::from_gps_fix(&fix, &home, 0, 42.0).unwrap().encode();
            let got: Vec<NavPvt> = UbxDecoder::new().push(f.as_bytes()).collect();
            let back = got[0].to_gps_fix(&home, 1.0);
            assert_eq!(back.fix, GpsFixType::Fix3d);
            dp = dp.zip_map(&(back.position_ned_m - p), |a, b| a.max(b.abs()));
            dv = dv.max((back.velocity_ned_m_s.unwrap() - v).amax());
        }
        println!(
            "NAV-PVT at {lat}°: max |Δ| N {:.4} m, E {:.4} m, D {:.4} m, velocity {:.5} m/s",
            dp.x, dp.y, dp.z, dv
        );
        // half a quantum: 0.5e-7° of latitude is 5.6 mm, of longitude
        // 5.6 mm·cos(lat); 0.5 mm of height; 0.5 mm/s
        assert!(
            dp.x < 0.0056 && dp.y < 0.0056 * lat.to_radians().cos() + 1e-4 && dp.z < 0.00051,
            "{dp}"
        );
        assert!(dv <= 0.0005 + 1e-12);
    }
}

#[test]
fn nmea_fix_round_trip_within_its_quanta() {
    let home = LocalNed::new(Geodetic::new(57.0147, 9.9859, 30.0).unwrap());
    let mut dp = Vector3::<f64>::zeros();
    for (p, v) in points(2000) {
        let fix = GpsFix {
            epoch_s: 1.0,
            fix: GpsFixType::Fix3d,
            position_ned_m: p,
            velocity_ned_m_s: Some(v),
        };
        let mut d = NmeaDecoder::new();
        let mut gga = None;
        for m in nmea0183::sentences_from_fix(&fix, &home, 3600.0, 42.0).unwrap() {
            for got in d.push(m.encode().unwrap().as_bytes()) {
                if let NmeaMessage::Gga(g) = got {
                    gga = Some(g);
                }
            }
        }
        assert_eq!(d.stats().messages, 3);
        let back = gga.unwrap().to_gps_fix(&home, 1.0);
        assert!(back.velocity_ned_m_s.is_none());
        dp = dp.zip_map(&(back.position_ned_m - p), |a, b| a.max(b.abs()));
    }
    println!(
        "NMEA: max |Δ| N {:.4} m, E {:.4} m, D {:.4} m",
        dp.x, dp.y, dp.z
    );
    // half of 1e-5 arc-minute is 9.3 mm of latitude; 0.05 m of altitude
    // plus the f32 the nmea crate parses altitude and separation into
    assert!(dp.x < 0.0093 && dp.y < 0.0093 && dp.z < 0.0501, "{dp}");
}

#[test]
fn vn100_imu_round_trip_is_float32_rounding() {
    let imu = ImuSample {
        specific_force_body_m_s2: Vector3::new(0.123_456_789, -1.5, -9.82),
        gyro_body_rad_s: Vector3::new(1e-4, -0.3, 2.0),
    };
    let mag = Vector3::new(0.153, 0.008, -0.438);
    let f = VnCommon::from_samples(12.345_678_9, &imu, Some(&mag))
        .unwrap()
        .encode()
        .unwrap();
    let got: Vec<VnCommon> = VnBinaryDecoder::new().push(f.as_bytes()).collect();
    let m = got[0];
    let back = m.imu_sample().unwrap();
    let rel = |a: &Vector3<f64>, b: &Vector3<f64>| (a - b).component_div(b).amax();
    // float32 has a 24-bit significand: relative rounding ≤ 2^-24 ≈ 6e-8
    assert!(
        rel(
            &back.specific_force_body_m_s2,
            &imu.specific_force_body_m_s2
        ) <= 2f64.powi(-24)
    );
    assert!(rel(&back.gyro_body_rad_s, &imu.gyro_body_rad_s) <= 2f64.powi(-24));
    assert!(rel(&m.mag_body_gauss().unwrap(), &mag) <= 2f64.powi(-24));
    assert_eq!(m.time_startup_ns, Some(12_345_678_900));
    // without a magnetometer sample the packet carries no MagPres field
    let f = VnCommon::from_samples(0.01, &imu, None)
        .unwrap()
        .encode()
        .unwrap();
    let got: Vec<VnCommon> = VnBinaryDecoder::new().push(f.as_bytes()).collect();
    assert_eq!(got[0].mag_body_gauss(), None);
    assert_eq!(f.len(), 1 + 1 + 2 + 8 + 12 + 12 + 2);
}

#[test]
fn servo_commands_round_trip_within_1e_4() {
    let u = nalgebra::Vector4::new(0.184_975, -0.75, 0.75, 0.623_4);
    let c = ServoCommand::from_inputs(5, true, &u).unwrap();
    assert!((c.inputs() - u).amax() <= 0.5e-4 + 1e-15);
    let rc = RcInput::default().with_applied(&u).unwrap();
    assert_eq!(rc.applied(), c.inputs());
}
